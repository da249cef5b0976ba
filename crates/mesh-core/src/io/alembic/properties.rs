//! Stored samples of scalar and array properties, checked against their headers, and the
//! little-endian values they hold.

use super::archive::Archive;
use super::headers::PropertyHeader;
use crate::io::ogawa::Group;

/// The values of a scalar property's stored sample `stored` (after the 16-byte key), `size`
/// bytes per value.
pub(super) fn scalar_sample<'a>(h: &PropertyHeader, g: &Group<'a>, stored: u64, size: usize) -> std::result::Result<&'a [u8], String> {
    let data = g.data(stored).map_err(|e| format!("{} sample {stored}: {e}", h.name))?;
    let want = size * h.extent as usize;
    if data.len() != 16 + want {
        return Err(format!("{} sample {stored}: {} bytes, expected a 16-byte key and {want} bytes", h.name, data.len()));
    }
    Ok(&data[16..])
}

pub(super) fn f64s(values: &[u8]) -> Vec<f64> {
    values
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
        .collect()
}

/// The sub-property `name` of a compound group, with its group.
pub(super) fn property<'a>(
    archive: &mut Archive<'a>,
    compound: &Group<'a>,
    name: &str,
) -> std::result::Result<Option<(PropertyHeader, Group<'a>)>, String> {
    let headers = archive.property_headers(compound)?;
    let Some(i) = headers.iter().position(|h| h.name == name) else {
        return Ok(None);
    };
    let group = compound.group(i as u64)?;
    Ok(Some((headers[i].clone(), group)))
}

/// The values of stored sample `stored` of an array property: the bytes after the 16-byte key,
/// checked against the element size and the recorded dimensions.
pub(super) fn array_sample<'a>(h: &PropertyHeader, g: &Group<'a>, stored: u64) -> std::result::Result<&'a [u8], String> {
    let elem = h.pod.size().ok_or_else(|| format!("{} values are {}, not read", h.name, h.pod.name()))? * h.extent as usize;
    let data = g.data(2 * stored).map_err(|e| format!("{} sample {stored}: {e}", h.name))?;
    if data.is_empty() {
        return Ok(data);
    }
    if data.len() < 16 || elem == 0 {
        return Err(format!("{} sample {stored}: {} bytes, not a key and values", h.name, data.len()));
    }
    let values = &data[16..];
    if values.len() % elem != 0 {
        return Err(format!("{} sample {stored}: {} bytes of values, not whole {elem}-byte elements", h.name, values.len()));
    }
    let dims = g.data(2 * stored + 1).map_err(|e| format!("{} sample {stored} dimensions: {e}", h.name))?;
    if !dims.is_empty() {
        if dims.len() % 8 != 0 {
            return Err(format!("{} sample {stored}: dimensions of {} bytes", h.name, dims.len()));
        }
        let count = dims.chunks_exact(8).try_fold(1u64, |acc, d| {
            acc.checked_mul(u64::from_le_bytes(d.try_into().unwrap_or([0xff; 8])))
        });
        if count != Some((values.len() / elem) as u64) {
            return Err(format!(
                "{} sample {stored}: dimensions do not match its {} elements",
                h.name,
                values.len() / elem
            ));
        }
    }
    Ok(values)
}

pub(super) fn int32s(values: &[u8]) -> impl Iterator<Item = i32> + '_ {
    values.chunks_exact(4).map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

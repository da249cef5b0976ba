//! The archive: the root group's versions, time samplings and indexed metadata, and the headers
//! of objects (name, schema) and of compound properties, with every header byte charged against
//! the file's length.

use super::headers::{Cursor, Kind, Pod, PropertyHeader};
use super::time::TimeSampling;
use crate::io::ogawa::{Group, Ogawa};

/// The Alembic library version the newest Ogawa files carry at least (Alembic 0.9.9).
pub(super) const MIN_LIBRARY_VERSION: i32 = 9999;
pub(super) const POLYMESH_SCHEMA: &str = "AbcGeom_PolyMesh_v1";
pub(super) const XFORM_SCHEMA: &str = "AbcGeom_Xform_v3";

/// The schemas of objects this reader tells apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Schema {
    PolyMesh,
    Xform,
    Other,
}

impl Schema {
    /// The schema named in object metadata.
    pub(super) fn of(meta: &str) -> Schema {
        match meta_value(meta, "schema") {
            Some(POLYMESH_SCHEMA) => Schema::PolyMesh,
            Some(XFORM_SCHEMA) => Schema::Xform,
            _ => Schema::Other,
        }
    }
}

/// The value of `key` in Alembic metadata (`key=value;key=value`).
pub(super) fn meta_value<'m>(meta: &'m str, key: &str) -> Option<&'m str> {
    meta.split(';').find_map(|kv| kv.split_once('=').filter(|(k, _)| *k == key).map(|(_, v)| v))
}

/// The archive: its time samplings, indexed metadata and top object.
pub(super) struct Archive<'a> {
    pub(super) time_samplings: Vec<TimeSampling>,
    pub(super) metadata: Vec<String>,
    pub(super) top: Group<'a>,
    /// Header bytes parsed so far, and the most allowed (the file's length: each header block
    /// once; a crafted file sharing one block between many groups stops here).
    pub(super) parsed: u64,
    pub(super) budget: u64,
}

pub(super) fn i32_data(d: &[u8], what: &str) -> std::result::Result<i32, String> {
    let b: [u8; 4] = d
        .try_into()
        .map_err(|_| format!("{what} is {} bytes, expected 4", d.len()))?;
    Ok(i32::from_le_bytes(b))
}

impl<'a> Archive<'a> {
    pub(super) fn open(file: &Ogawa<'a>) -> std::result::Result<Self, String> {
        let root = file.root()?;
        let layout_ok = root.len() >= 6
            && root.is_data(0)
            && root.is_data(1)
            && root.is_group(2)
            && root.is_data(3)
            && root.is_data(4)
            && root.is_data(5);
        if !layout_ok {
            return Err(format!(
                "not an Alembic archive: the root group ({} children) lacks the version, \
                 top object, time samplings and metadata Alembic puts there",
                root.len()
            ));
        }
        let version = i32_data(root.data(0)?, "the archive version")?;
        if !(0..=1).contains(&version) {
            return Err(format!("unsupported Alembic archive version {version} (expected 0 or 1)"));
        }
        let library = i32_data(root.data(1)?, "the library version")?;
        if library < MIN_LIBRARY_VERSION {
            return Err(format!("unsupported Alembic library version {library} (expected {MIN_LIBRARY_VERSION} or later)"));
        }
        let time_samplings = parse_time_samplings(root.data(4)?)?;
        let metadata = parse_indexed_metadata(root.data(5)?)?;
        Ok(Archive {
            time_samplings,
            metadata,
            top: root.group(2)?,
            parsed: 0,
            budget: file.len(),
        })
    }

    pub(super) fn charge(&mut self, bytes: usize) -> std::result::Result<(), String> {
        self.parsed += bytes as u64;
        if self.parsed > self.budget {
            return Err("the object tree refers to the same headers again and again (more header bytes than the file holds)".into());
        }
        Ok(())
    }

    /// The indexed metadata entry `index`.
    pub(super) fn indexed(&self, index: u32, what: &str) -> std::result::Result<&str, String> {
        self.metadata
            .get(index as usize)
            .map(String::as_str)
            .ok_or_else(|| format!("{what}: metadata index {index} but the archive indexes {}", self.metadata.len()))
    }

    /// The headers of `group`'s child objects: name and schema.
    pub(super) fn object_headers(&mut self, group: &Group<'a>) -> std::result::Result<Vec<(String, Schema)>, String> {
        let n = group.len();
        if n == 0 || !group.is_data(n - 1) {
            return Ok(Vec::new());
        }
        let data = group.data(n - 1)?;
        self.charge(data.len())?;
        if data.len() <= 32 {
            return Ok(Vec::new());
        }
        let mut c = Cursor::new(&data[..data.len() - 32], "object headers");
        let mut out = Vec::new();
        while !c.done() {
            let size = c.u32()? as usize;
            if size == 0 {
                return Err("object headers: an object without a name".into());
            }
            let name = c.text(size)?;
            let index = c.u8()?;
            let schema = if index == 0xff {
                let size = c.u32()? as usize;
                Schema::of(&String::from_utf8_lossy(c.take(size)?))
            } else {
                Schema::of(self.indexed(u32::from(index), "object headers")?)
            };
            out.push((name, schema));
        }
        Ok(out)
    }

    /// The property headers of a compound property group.
    pub(super) fn property_headers(&mut self, group: &Group<'a>) -> std::result::Result<Vec<PropertyHeader>, String> {
        let n = group.len();
        if n == 0 || !group.is_data(n - 1) {
            return Ok(Vec::new());
        }
        let data = group.data(n - 1)?;
        self.charge(data.len())?;
        let mut c = Cursor::new(data, "property headers");
        let mut out = Vec::new();
        while !c.done() {
            let info = c.u32()?;
            let kind = match info & 3 {
                0 => Kind::Compound,
                1 => Kind::Scalar,
                _ => Kind::Array,
            };
            let hint = (info >> 2) & 3;
            let mut h = PropertyHeader {
                name: String::new(),
                kind,
                pod: Pod::Other(0xff),
                extent: 0,
                samples: 0,
                first_changed: 0,
                last_changed: 0,
                time_sampling: 0,
            };
            if kind != Kind::Compound {
                let pod = ((info >> 4) & 0xf) as u8;
                if pod > 13 {
                    return Err(format!("property headers: unknown data type {pod}"));
                }
                h.pod = Pod::of(pod);
                h.extent = ((info >> 12) & 0xff) as u8;
                h.samples = c.hinted(hint)?;
                if info & 0x200 != 0 {
                    h.first_changed = c.hinted(hint)?;
                    h.last_changed = c.hinted(hint)?;
                } else if info & 0x800 != 0 {
                    (h.first_changed, h.last_changed) = (0, 0);
                } else {
                    h.first_changed = 1;
                    h.last_changed = h.samples.saturating_sub(1);
                }
                if info & 0x100 != 0 {
                    h.time_sampling = c.hinted(hint)?;
                }
            }
            let size = c.hinted(hint)? as usize;
            if size == 0 {
                return Err("property headers: a property without a name".into());
            }
            h.name = c.text(size)?;
            let meta_index = (info >> 20) & 0xff;
            if meta_index == 0xff {
                let size = c.hinted(hint)? as usize;
                c.take(size)?;
            } else {
                self.indexed(meta_index, "property headers")?;
            }
            out.push(h);
        }
        Ok(out)
    }
}

pub(super) fn parse_time_samplings(data: &[u8]) -> std::result::Result<Vec<TimeSampling>, String> {
    let mut c = Cursor::new(data, "time samplings");
    let mut out = Vec::new();
    while !c.done() {
        let _max_sample = c.u32()?;
        let time_per_cycle = c.f64()?;
        let n = c.u32()? as usize;
        if n == 0 {
            return Err("time samplings: a sampling with no sample times".into());
        }
        // Checked against the buffer before allocating.
        let raw = c.take(n.checked_mul(8).ok_or("time samplings: count overflows")?)?;
        let times = raw
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
            .collect();
        out.push(TimeSampling { time_per_cycle, times });
    }
    Ok(out)
}

pub(super) fn parse_indexed_metadata(data: &[u8]) -> std::result::Result<Vec<String>, String> {
    // Entry 0 is the empty metadata; the archive indexes at most 255 more, each under 256 bytes.
    let mut out = vec![String::new()];
    let mut c = Cursor::new(data, "indexed metadata");
    while !c.done() {
        let n = c.u8()? as usize;
        out.push(c.text(n)?);
        if out.len() > 256 {
            return Err("indexed metadata: more than 255 entries".into());
        }
    }
    Ok(out)
}

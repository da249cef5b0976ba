//! The Xforms above a PolyMesh: their operations and channel values per stored sample, and
//! their matrix at a time ([`crate::io::alembic_xform`]).

use super::archive::Archive;
use super::headers::{Kind, Pod, PropertyHeader};
use super::properties::{array_sample, f64s, property, scalar_sample};
use super::time::{sample_near, TimeSampling};
use crate::input::escape_control;
use crate::io::ogawa::Group;

/// An Xform's operations and its channel values per stored sample.
pub(super) struct Xform {
    pub(super) path: String,
    pub(super) ops: Vec<u8>,
    pub(super) header: Option<PropertyHeader>,
    pub(super) values: Vec<Vec<f64>>,
    pub(super) inherits: bool,
}

impl Xform {
    /// The matrix at time `t`.
    pub(super) fn matrix_at(&self, samplings: &[TimeSampling], t: f64) -> std::result::Result<nalgebra::Matrix4<f64>, String> {
        let vals = match &self.header {
            Some(h) if h.samples > 1 => {
                let ts = samplings.get(h.time_sampling as usize).ok_or_else(|| {
                    format!("Xform {}: time sampling {} is not in the archive", escape_control(&self.path), h.time_sampling)
                })?;
                let k = sample_near(ts, h.samples, t);
                let stored = h.stored_index(k).unwrap_or(0) as usize;
                self.values.get(stored).or(self.values.last())
            }
            _ => self.values.first(),
        };
        let defaults;
        let vals = match vals {
            Some(v) => v,
            None => {
                defaults = crate::io::alembic_xform::default_values(&self.ops);
                &defaults
            }
        };
        crate::io::alembic_xform::matrix(&self.ops, vals).map_err(|e| format!("Xform {}: {e}", escape_control(&self.path)))
    }
}

/// Reads the Xform object `group` (`.xform`: `.ops`, `.vals`, `.inherits`).
pub(super) fn read_xform<'a>(archive: &mut Archive<'a>, path: String, group: &Group<'a>) -> std::result::Result<Xform, String> {
    let mut x = Xform { path, ops: Vec::new(), header: None, values: Vec::new(), inherits: true };
    let at = |e: String| format!("Xform {}: {e}", escape_control(&x.path));
    if group.is_empty() || !group.is_group(0) {
        return Ok(x);
    }
    let props = group.group(0).map_err(at)?;
    let Some((xh, xg)) = property(archive, &props, ".xform").map_err(at)? else {
        return Ok(x);
    };
    if xh.kind != Kind::Compound {
        return Err(at(".xform is not a compound property".into()));
    }
    let headers = archive.property_headers(&xg).map_err(at)?;
    for (i, h) in headers.iter().enumerate() {
        let g = || xg.group(i as u64);
        match h.name.as_str() {
            ".ops" if h.samples > 0 => {
                if h.kind != Kind::Scalar || h.pod != Pod::Uint8 {
                    return Err(at(format!(".ops is {} {:?}, expected uint8 scalar", h.pod.name(), h.kind)));
                }
                x.ops = scalar_sample(h, &g().map_err(at)?, 0, 1).map_err(at)?.to_vec();
            }
            ".inherits" if h.samples > 0 => {
                if h.kind != Kind::Scalar || !matches!(h.pod, Pod::Bool | Pod::Uint8) || h.extent != 1 {
                    return Err(at(format!(".inherits is {} x{}, expected bool", h.pod.name(), h.extent)));
                }
                x.inherits = scalar_sample(h, &g().map_err(at)?, 0, 1).map_err(at)?[0] != 0;
            }
            ".vals" if h.samples > 0 => {
                if h.pod != Pod::Float64 || h.kind == Kind::Compound {
                    return Err(at(format!(".vals is {} {:?}, expected float64", h.pod.name(), h.kind)));
                }
                let vg = g().map_err(at)?;
                let last = h.stored_index(h.samples - 1).ok_or_else(|| at(".vals: inconsistent sample indices".into()))?;
                for k in 0..=last {
                    let bytes = if h.kind == Kind::Scalar {
                        scalar_sample(h, &vg, k, 8)
                    } else {
                        array_sample(h, &vg, k)
                    }
                    .map_err(at)?;
                    x.values.push(f64s(bytes));
                }
                x.header = Some(h.clone());
            }
            _ => {}
        }
    }
    let need = crate::io::alembic_xform::channel_count(&x.ops).map_err(at)?;
    if let Some(bad) = x.values.iter().position(|v| v.len() != need) {
        return Err(at(format!(
            ".vals sample {bad} has {} values, the operations take {need}",
            x.values[bad].len()
        )));
    }
    Ok(x)
}

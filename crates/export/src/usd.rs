//! USD export (`.usda`, the ASCII form of Pixar's Universal Scene Description) of a mesh
//! sequence as one `Mesh` prim whose `points` are time-sampled, one sample per exported frame.
//!
//! Layout:
//! ```text
//! #usda 1.0
//! ( defaultPrim = "walk"  startTimeCode = 0  endTimeCode = N-1
//!   timeCodesPerSecond = FPS  framesPerSecond = FPS  upAxis = "Y"  metersPerUnit = 1 )
//! def Mesh "walk" {
//!     uniform token subdivisionScheme = "none"
//!     int[] faceVertexCounts = [3, 3, ...]
//!     int[] faceVertexIndices = [...]
//!     point3f[] points.timeSamples = { 0: [(x, y, z), ...], 1: [...], ... }
//!     float3[] extent.timeSamples = { 0: [(min), (max)], ... }
//! }
//! ```
//! Frame `i` of the sequence is time code `i` (with a stride, the kept frames keep their own
//! numbers), so `timeCodesPerSecond` is the sequence's frame rate and time code / rate is the
//! frame's time in seconds. Points are float32 (`point3f`), printed as the shortest decimal that
//! reads back as the same float, so a USD reader gets exactly the f32-rounded positions.
//! `subdivisionScheme = "none"`: the mesh is the surface (USD's default is Catmull-Clark).
//! Orientation is USD's default, right-handed, as surfcap's faces are counter-clockwise.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use mesh_core::atomic::write_atomic;
use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};

/// USD's two up axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum UpAxis {
    #[default]
    Y,
    Z,
}

/// Options of [`encode_usda`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UsdOptions {
    /// Keep frames 0, stride, 2*stride, ... (>= 1).
    pub stride: usize,
    /// Frames per second of the sequence: `timeCodesPerSecond`.
    pub fps: f64,
    pub up_axis: UpAxis,
    /// Metres per unit of the coordinates (1 for metres).
    pub meters_per_unit: f64,
}

impl Default for UsdOptions {
    fn default() -> Self {
        UsdOptions { stride: 1, fps: 30.0, up_axis: UpAxis::Y, meters_per_unit: 1.0 }
    }
}

/// A valid USD prim name from `name`: letters, digits and `_`, not starting with a digit.
pub fn prim_name(name: &str) -> String {
    let mut s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

/// Writes `seq` as USDA text into `w` under the prim name `name` (see the module doc).
pub fn encode_usda(w: &mut dyn Write, seq: &MeshSequence, name: &str, opts: &UsdOptions) -> std::io::Result<()> {
    let kept: Vec<usize> = (0..seq.n_frames()).step_by(opts.stride.max(1)).collect();
    let last = kept.last().copied().unwrap_or(0);
    let up = match opts.up_axis {
        UpAxis::Y => "Y",
        UpAxis::Z => "Z",
    };
    let name = prim_name(name);
    writeln!(w, "#usda 1.0")?;
    writeln!(w, "(")?;
    writeln!(w, "    defaultPrim = \"{name}\"")?;
    writeln!(w, "    doc = \"surfcap mesh-export\"")?;
    writeln!(w, "    endTimeCode = {last}")?;
    writeln!(w, "    framesPerSecond = {}", opts.fps)?;
    writeln!(w, "    metersPerUnit = {}", opts.meters_per_unit)?;
    writeln!(w, "    startTimeCode = 0")?;
    writeln!(w, "    timeCodesPerSecond = {}", opts.fps)?;
    writeln!(w, "    upAxis = \"{up}\"")?;
    writeln!(w, ")")?;
    writeln!(w)?;
    writeln!(w, "def Mesh \"{name}\"")?;
    writeln!(w, "{{")?;
    writeln!(w, "    uniform token subdivisionScheme = \"none\"")?;
    let mut line = String::new();
    line.push_str("    int[] faceVertexCounts = [");
    for k in 0..seq.n_faces() {
        line.push_str(if k == 0 { "3" } else { ", 3" });
    }
    line.push_str("]\n    int[] faceVertexIndices = [");
    for (k, f) in seq.faces.iter().enumerate() {
        let sep = if k == 0 { "" } else { ", " };
        let _ = write!(line, "{sep}{}, {}, {}", f[0], f[1], f[2]);
    }
    line.push_str("]\n");
    w.write_all(line.as_bytes())?;
    writeln!(w, "    point3f[] points.timeSamples = {{")?;
    let mut extents = Vec::with_capacity(kept.len());
    for &i in &kept {
        line.clear();
        let _ = write!(line, "        {i}: [");
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for (k, p) in seq.frames[i].iter().enumerate() {
            let c = [p.x as f32, p.y as f32, p.z as f32];
            for a in 0..3 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
            let sep = if k == 0 { "" } else { ", " };
            let _ = write!(line, "{sep}({:?}, {:?}, {:?})", c[0], c[1], c[2]);
        }
        line.push_str("],\n");
        w.write_all(line.as_bytes())?;
        extents.push((i, lo, hi));
    }
    writeln!(w, "    }}")?;
    writeln!(w, "    float3[] extent.timeSamples = {{")?;
    for (i, lo, hi) in extents {
        writeln!(w, "        {i}: [({:?}, {:?}, {:?}), ({:?}, {:?}, {:?})],", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2])?;
    }
    writeln!(w, "    }}")?;
    writeln!(w, "}}")
}

/// Writes `seq` as the `.usda` file `path`, atomically; the prim is named after the file stem.
pub fn write_usda(path: &Path, seq: &MeshSequence, opts: &UsdOptions) -> Result<()> {
    if seq.n_frames() == 0 || seq.n_vertices() == 0 {
        return Err(Error::file(path, "cannot export an empty sequence to USD"));
    }
    if opts.stride == 0 {
        return Err(Error::file(path, "USD export needs stride >= 1"));
    }
    mesh_core::frame_rate::check_fps(opts.fps).map_err(|e| Error::file(path, e))?;
    if !(opts.meters_per_unit.is_finite() && opts.meters_per_unit > 0.0) {
        return Err(Error::file(path, format!("metres per unit {} is not a positive number", opts.meters_per_unit)));
    }
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "sequence".into());
    write_atomic(path, |w| encode_usda(w, seq, &name, opts))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A one-triangle, two-frame sequence, written out by hand.
    #[test]
    fn a_triangle_over_two_frames_is_the_text_written_by_hand() {
        let seq = MeshSequence::new(
            vec![[0, 1, 2]],
            vec![
                vec![Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 0.1, 0.0)],
                vec![Vector3::new(0.0, 0.0, 1.0), Vector3::new(1.0, 0.0, 1.0), Vector3::new(0.0, -2.5, 1.0)],
            ],
        );
        let mut out = Vec::new();
        let opts = UsdOptions { fps: 25.0, ..UsdOptions::default() };
        encode_usda(&mut out, &seq, "1 walk", &opts).unwrap();
        let want = "#usda 1.0\n(\n    defaultPrim = \"_1_walk\"\n    doc = \"surfcap mesh-export\"\n    endTimeCode = 1\n    \
            framesPerSecond = 25\n    metersPerUnit = 1\n    startTimeCode = 0\n    timeCodesPerSecond = 25\n    upAxis = \"Y\"\n)\n\n\
            def Mesh \"_1_walk\"\n{\n    uniform token subdivisionScheme = \"none\"\n    int[] faceVertexCounts = [3]\n    \
            int[] faceVertexIndices = [0, 1, 2]\n    point3f[] points.timeSamples = {\n        \
            0: [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.1, 0.0)],\n        1: [(0.0, 0.0, 1.0), (1.0, 0.0, 1.0), (0.0, -2.5, 1.0)],\n    }\n    \
            float3[] extent.timeSamples = {\n        0: [(0.0, 0.0, 0.0), (1.0, 0.1, 0.0)],\n        1: [(0.0, -2.5, 1.0), (1.0, 0.0, 1.0)],\n    }\n}\n";
        assert_eq!(String::from_utf8(out).unwrap(), want);
    }

    #[test]
    fn prim_names_are_usd_identifiers() {
        assert_eq!(prim_name("walk"), "walk");
        assert_eq!(prim_name("var-3.b"), "var_3_b");
        assert_eq!(prim_name("0"), "_0");
        assert_eq!(prim_name(""), "_");
    }
}

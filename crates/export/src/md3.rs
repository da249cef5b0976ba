//! Quake 3 MD3 models: vertex-animated meshes in several surfaces, with
//! per-frame tags (named coordinate frames) where other models attach.
//!
//! Layout (little-endian, offsets in bytes):
//! - header (108): `"IDP3"`, `i32` version (15), name (64), `i32` flags,
//!   `i32` numFrames, numTags, numSurfaces, numSkins, ofsFrames, ofsTags,
//!   ofsSurfaces, ofsEnd (offsets from the start of the file);
//! - frames (56 each): bounds min and max, local origin (3 x `f32` each),
//!   `f32` radius, name (16);
//! - tags (112 each, numFrames x numTags, frame by frame): name (64),
//!   origin (3 x `f32`), axis (3 x 3 `f32`, the tag's x, y and z axes);
//! - surfaces, one after the other from ofsSurfaces: a 108-byte header
//!   (`"IDP3"`, name (64), `i32` flags, numFrames, numShaders, numVerts,
//!   numTriangles, ofsTriangles, ofsShaders, ofsSt, ofsXyzNormal, ofsEnd,
//!   offsets from the surface's start), triangles (3 x `i32` vertex indices),
//!   and numFrames x numVerts vertices (8 each, frame by frame): 3 x `i16`
//!   position in 1/64 units, 2 bytes of packed normal.
//!
//! Positions are returned in the file's units and axes (Quake: +z up, about
//! an inch a unit); shaders, texture coordinates and normals are not read.
//! Every count and offset is checked against the file's length before
//! anything is allocated, so a crafted header cannot make the reader
//! allocate more than the file justifies.

use std::path::Path;

use mesh_core::{Error, Result};
use nalgebra::{Matrix3, Vector3};

/// The magic bytes of an MD3 file and of each of its surfaces.
pub const MAGIC: &[u8; 4] = b"IDP3";
/// The MD3 version this reader reads.
pub const VERSION: i32 = 15;
/// Bytes of the file header, a frame, a tag, a surface header, a triangle, a vertex.
pub const HEADER_LEN: usize = 108;
pub const FRAME_LEN: usize = 56;
pub const TAG_LEN: usize = 112;
pub const SURFACE_HEADER_LEN: usize = 108;
pub const TRIANGLE_LEN: usize = 12;
pub const VERTEX_LEN: usize = 8;
/// Stored positions are integers in units of 1/64.
pub const POSITION_SCALE: f64 = 1.0 / 64.0;

/// A whole MD3 model.
#[derive(Clone, Debug, PartialEq)]
pub struct Md3 {
    pub name: String,
    pub frames: Vec<Md3Frame>,
    /// `tags[frame][k]`: tag `k` in `frame` (every frame names the same tags).
    pub tags: Vec<Vec<Tag>>,
    pub surfaces: Vec<Surface>,
}

/// A frame's bounding box, local origin and radius, as stored.
#[derive(Clone, Debug, PartialEq)]
pub struct Md3Frame {
    pub name: String,
    pub min: Vector3<f64>,
    pub max: Vector3<f64>,
    pub origin: Vector3<f64>,
    pub radius: f64,
}

/// A named coordinate frame of one animation frame: a point of the model
/// maps to `origin + axis * p` in the model carrying the tag (the columns of
/// `axis` are the tag's x, y and z axes).
#[derive(Clone, Debug, PartialEq)]
pub struct Tag {
    pub name: String,
    pub origin: Vector3<f64>,
    pub axis: Matrix3<f64>,
}

/// One surface: triangles over its own vertices, and the vertices' positions
/// in every frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    pub name: String,
    pub triangles: Vec<[u32; 3]>,
    /// `frames[f][v]`: vertex `v` in frame `f`, in file units (1/64 steps).
    pub frames: Vec<Vec<Vector3<f64>>>,
}

impl Md3 {
    /// The index of the tag named `name` (tags are named alike in every frame).
    pub fn tag_index(&self, name: &str) -> Option<usize> {
        self.tags.first()?.iter().position(|t| t.name == name)
    }
    /// Total vertex count over the surfaces.
    pub fn n_vertices(&self) -> usize {
        self.surfaces.iter().map(|s| s.frames.first().map_or(0, Vec::len)).sum()
    }
}

fn i32_at(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
fn i16_at(b: &[u8], at: usize) -> i16 {
    i16::from_le_bytes(b[at..at + 2].try_into().expect("2 bytes"))
}
fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
fn vec3_at(b: &[u8], at: usize) -> Vector3<f64> {
    Vector3::new(f32_at(b, at), f32_at(b, at + 4), f32_at(b, at + 8)).cast::<f64>()
}
/// A fixed-length, NUL-padded name.
fn name_at(b: &[u8], at: usize, len: usize) -> String {
    let field = &b[at..at + len];
    let end = field.iter().position(|&c| c == 0).unwrap_or(len);
    String::from_utf8_lossy(&field[..end]).into_owned()
}

/// A non-negative count or offset from the header, or an error naming it.
fn non_negative(value: i32, what: &str) -> std::result::Result<usize, String> {
    usize::try_from(value).map_err(|_| format!("negative {what} ({value})"))
}

/// Checks that `count` records of `size` bytes starting at `start` lie
/// within `0..end`.
fn check_span(
    start: usize,
    count: usize,
    size: usize,
    end: usize,
    what: &str,
) -> std::result::Result<(), String> {
    let bytes = (count as u128) * (size as u128);
    if (start as u128) + bytes > end as u128 {
        return Err(format!(
            "{count} {what} of {size} bytes at offset {start} run past the end ({end} bytes)"
        ));
    }
    Ok(())
}

fn finite(v: &Vector3<f64>, what: impl FnOnce() -> String) -> std::result::Result<(), String> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(format!("{}: coordinate is not finite", what()))
    }
}

/// Parses an MD3 file held in memory; the error is the problem without the file name.
pub fn parse_md3(b: &[u8]) -> std::result::Result<Md3, String> {
    let len = b.len();
    if len < HEADER_LEN {
        return Err(format!(
            "not an MD3 file: {len} bytes, shorter than the 108-byte header"
        ));
    }
    if &b[..4] != MAGIC {
        return Err("not an MD3 file: it does not start with \"IDP3\"".into());
    }
    let version = i32_at(b, 4);
    if version != VERSION {
        return Err(format!("unsupported MD3 version {version} (expected 15)"));
    }
    let name = name_at(b, 8, 64);
    let n_frames = non_negative(i32_at(b, 76), "frame count")?;
    let n_tags = non_negative(i32_at(b, 80), "tag count")?;
    let n_surfaces = non_negative(i32_at(b, 84), "surface count")?;
    let ofs_frames = non_negative(i32_at(b, 92), "frame offset")?;
    let ofs_tags = non_negative(i32_at(b, 96), "tag offset")?;
    let ofs_surfaces = non_negative(i32_at(b, 100), "surface offset")?;
    if n_frames == 0 {
        return Err("no frames (the header's frame count is 0)".into());
    }
    check_span(ofs_frames, n_frames, FRAME_LEN, len, "frames")?;
    check_span(ofs_tags, n_frames.saturating_mul(n_tags), TAG_LEN, len, "tags")?;
    // Each surface takes at least its header.
    check_span(ofs_surfaces, n_surfaces, SURFACE_HEADER_LEN, len, "surfaces")?;

    let mut frames = Vec::with_capacity(n_frames);
    for f in 0..n_frames {
        let at = ofs_frames + f * FRAME_LEN;
        let frame = Md3Frame {
            min: vec3_at(b, at),
            max: vec3_at(b, at + 12),
            origin: vec3_at(b, at + 24),
            radius: f32_at(b, at + 36) as f64,
            name: name_at(b, at + 40, 16),
        };
        for v in [&frame.min, &frame.max, &frame.origin] {
            finite(v, || format!("frame {f} bounds"))?;
        }
        frames.push(frame);
    }

    let mut tags = Vec::with_capacity(n_frames);
    for f in 0..n_frames {
        let mut frame_tags = Vec::with_capacity(n_tags);
        for k in 0..n_tags {
            let at = ofs_tags + (f * n_tags + k) * TAG_LEN;
            let name = name_at(b, at, 64);
            let origin = vec3_at(b, at + 64);
            let axis = Matrix3::from_columns(&[
                vec3_at(b, at + 76),
                vec3_at(b, at + 88),
                vec3_at(b, at + 100),
            ]);
            if !origin.iter().chain(axis.iter()).all(|c| c.is_finite()) {
                return Err(format!("frame {f}, tag '{name}': not a finite number"));
            }
            if f > 0 && tags.first().map(|t: &Vec<Tag>| &t[k].name) != Some(&name) {
                return Err(format!(
                    "frame {f}, tag {k} is named '{name}', not as in frame 0"
                ));
            }
            frame_tags.push(Tag { name, origin, axis });
        }
        tags.push(frame_tags);
    }

    let mut surfaces = Vec::with_capacity(n_surfaces);
    let mut start = ofs_surfaces;
    for s in 0..n_surfaces {
        let surface = parse_surface(b, start, n_frames).map_err(|e| format!("surface {s}: {e}"))?;
        start = surface.1;
        surfaces.push(surface.0);
    }
    Ok(Md3 { name, frames, tags, surfaces })
}

/// Parses the surface whose header starts at `start`; returns it and the
/// offset just past it (where the next surface starts).
fn parse_surface(
    b: &[u8],
    start: usize,
    n_frames: usize,
) -> std::result::Result<(Surface, usize), String> {
    let len = b.len();
    check_span(start, 1, SURFACE_HEADER_LEN, len, "surface header")?;
    if &b[start..start + 4] != MAGIC {
        return Err(format!("at offset {start}: no \"IDP3\" surface header"));
    }
    let name = name_at(b, start + 4, 64);
    let at = |k: usize| i32_at(b, start + 72 + 4 * k);
    let surface_frames = non_negative(at(0), "frame count")?;
    let n_verts = non_negative(at(2), "vertex count")?;
    let n_triangles = non_negative(at(3), "triangle count")?;
    let ofs_triangles = non_negative(at(4), "triangle offset")?;
    let ofs_xyz = non_negative(at(7), "vertex offset")?;
    let ofs_end = non_negative(at(8), "end offset")?;
    if surface_frames != n_frames {
        return Err(format!(
            "'{name}' has {surface_frames} frames, the model {n_frames}"
        ));
    }
    if ofs_end < SURFACE_HEADER_LEN || ofs_end > len - start {
        return Err(format!(
            "'{name}': end offset {ofs_end} outside the surface header..end of file ({} bytes)",
            len - start
        ));
    }
    let end = start + ofs_end;
    let tri_start = start.saturating_add(ofs_triangles);
    let xyz_start = start.saturating_add(ofs_xyz);
    check_span(tri_start, n_triangles, TRIANGLE_LEN, end, "triangles")
        .map_err(|e| format!("'{name}': {e}"))?;
    check_span(xyz_start, n_frames.saturating_mul(n_verts), VERTEX_LEN, end, "vertices")
        .map_err(|e| format!("'{name}': {e}"))?;

    let mut triangles = Vec::with_capacity(n_triangles);
    for t in 0..n_triangles {
        let at = tri_start + t * TRIANGLE_LEN;
        let mut tri = [0u32; 3];
        for (c, corner) in tri.iter_mut().enumerate() {
            let i = i32_at(b, at + 4 * c);
            match usize::try_from(i) {
                Ok(i) if i < n_verts => *corner = i as u32,
                _ => {
                    return Err(format!(
                        "'{name}': triangle {t} has vertex index {i}, not below the vertex count {n_verts}"
                    ))
                }
            }
        }
        triangles.push(tri);
    }
    let mut frames = Vec::with_capacity(n_frames);
    for f in 0..n_frames {
        let mut positions = Vec::with_capacity(n_verts);
        for v in 0..n_verts {
            let at = xyz_start + (f * n_verts + v) * VERTEX_LEN;
            positions.push(
                Vector3::new(
                    i16_at(b, at) as f64,
                    i16_at(b, at + 2) as f64,
                    i16_at(b, at + 4) as f64,
                ) * POSITION_SCALE,
            );
        }
        frames.push(positions);
    }
    Ok((Surface { name, triangles, frames }, end))
}

/// Reads an MD3 file; errors are one line naming the file.
pub fn read_md3(path: impl AsRef<Path>) -> Result<Md3> {
    let path = path.as_ref();
    let bytes = mesh_core::input::read_regular_file(path)?;
    parse_md3(&bytes).map_err(|m| Error::file(path, m))
}

/// Serialises `model` as MD3 (no skins, shaders or texture coordinates;
/// normals zero). Positions are rounded to the nearest 1/64 and must fit an
/// `i16` after scaling; every surface must have the model's frame count.
pub fn encode_md3(model: &Md3) -> std::result::Result<Vec<u8>, String> {
    let n_frames = model.frames.len();
    if model.tags.len() != n_frames {
        return Err(format!("{} tag frames for {n_frames} frames", model.tags.len()));
    }
    let n_tags = model.tags.first().map_or(0, Vec::len);
    let as_i32 = |n: usize, what: &str| i32::try_from(n).map_err(|_| format!("too many {what} for MD3"));
    let mut b = Vec::new();
    let push_name = |b: &mut Vec<u8>, name: &str, len: usize| {
        let mut field = vec![0u8; len];
        let bytes = name.as_bytes();
        let n = bytes.len().min(len - 1);
        field[..n].copy_from_slice(&bytes[..n]);
        b.extend_from_slice(&field);
    };
    let push_i32 = |b: &mut Vec<u8>, v: i32| b.extend_from_slice(&v.to_le_bytes());
    let push_vec3 = |b: &mut Vec<u8>, v: &Vector3<f64>| {
        for c in v.iter() {
            b.extend_from_slice(&(*c as f32).to_le_bytes());
        }
    };
    let ofs_frames = HEADER_LEN;
    let ofs_tags = ofs_frames + n_frames * FRAME_LEN;
    let ofs_surfaces = ofs_tags + n_frames * n_tags * TAG_LEN;
    b.extend_from_slice(MAGIC);
    push_i32(&mut b, VERSION);
    push_name(&mut b, &model.name, 64);
    push_i32(&mut b, 0);
    push_i32(&mut b, as_i32(n_frames, "frames")?);
    push_i32(&mut b, as_i32(n_tags, "tags")?);
    push_i32(&mut b, as_i32(model.surfaces.len(), "surfaces")?);
    push_i32(&mut b, 0);
    push_i32(&mut b, as_i32(ofs_frames, "bytes")?);
    push_i32(&mut b, as_i32(ofs_tags, "bytes")?);
    push_i32(&mut b, as_i32(ofs_surfaces, "bytes")?);
    let end_at = b.len();
    push_i32(&mut b, 0);
    for frame in &model.frames {
        push_vec3(&mut b, &frame.min);
        push_vec3(&mut b, &frame.max);
        push_vec3(&mut b, &frame.origin);
        b.extend_from_slice(&(frame.radius as f32).to_le_bytes());
        push_name(&mut b, &frame.name, 16);
    }
    for frame_tags in &model.tags {
        if frame_tags.len() != n_tags {
            return Err("frames have different tag counts".into());
        }
        for tag in frame_tags {
            push_name(&mut b, &tag.name, 64);
            push_vec3(&mut b, &tag.origin);
            for c in 0..3 {
                push_vec3(&mut b, &tag.axis.column(c).into_owned());
            }
        }
    }
    for s in &model.surfaces {
        if s.frames.len() != n_frames {
            return Err(format!("surface '{}' has {} frames, the model {n_frames}", s.name, s.frames.len()));
        }
        let n_verts = s.frames.first().map_or(0, Vec::len);
        let ofs_triangles = SURFACE_HEADER_LEN;
        let ofs_xyz = ofs_triangles + s.triangles.len() * TRIANGLE_LEN;
        let ofs_end = ofs_xyz + n_frames * n_verts * VERTEX_LEN;
        b.extend_from_slice(MAGIC);
        push_name(&mut b, &s.name, 64);
        push_i32(&mut b, 0);
        push_i32(&mut b, as_i32(n_frames, "frames")?);
        push_i32(&mut b, 0);
        push_i32(&mut b, as_i32(n_verts, "vertices")?);
        push_i32(&mut b, as_i32(s.triangles.len(), "triangles")?);
        push_i32(&mut b, as_i32(ofs_triangles, "bytes")?);
        push_i32(&mut b, as_i32(ofs_xyz, "bytes")?);
        push_i32(&mut b, as_i32(ofs_xyz, "bytes")?);
        push_i32(&mut b, as_i32(ofs_xyz, "bytes")?);
        push_i32(&mut b, as_i32(ofs_end, "bytes")?);
        for t in &s.triangles {
            for &i in t {
                push_i32(&mut b, as_i32(i as usize, "vertices")?);
            }
        }
        for positions in &s.frames {
            if positions.len() != n_verts {
                return Err(format!("surface '{}': frames have different vertex counts", s.name));
            }
            for p in positions {
                for c in p.iter() {
                    let q = (c / POSITION_SCALE).round();
                    if !(q >= i16::MIN as f64 && q <= i16::MAX as f64) {
                        return Err(format!("surface '{}': coordinate {c} does not fit MD3's int16", s.name));
                    }
                    b.extend_from_slice(&(q as i16).to_le_bytes());
                }
                b.extend_from_slice(&[0, 0]);
            }
        }
    }
    let total = as_i32(b.len(), "bytes")?;
    b[end_at..end_at + 4].copy_from_slice(&total.to_le_bytes());
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-triangle, two-frame model with one tag, written byte by byte
    /// from the format description (not by [`encode_md3`]).
    fn hand_built() -> Vec<u8> {
        let name = |s: &str, len: usize| {
            let mut f = s.as_bytes().to_vec();
            f.resize(len, 0);
            f
        };
        let i = |v: i32| v.to_le_bytes().to_vec();
        let f = |v: f32| v.to_le_bytes().to_vec();
        let mut b = Vec::new();
        b.extend(b"IDP3");
        b.extend(i(15));
        b.extend(name("models/test.md3", 64));
        b.extend(i(0)); // flags
        b.extend(i(2)); // frames
        b.extend(i(1)); // tags
        b.extend(i(1)); // surfaces
        b.extend(i(0)); // skins
        let ofs_frames = 108;
        let ofs_tags = ofs_frames + 2 * 56;
        let ofs_surfaces = ofs_tags + 2 * 112;
        b.extend(i(ofs_frames));
        b.extend(i(ofs_tags));
        b.extend(i(ofs_surfaces));
        let surface_len = 108 + 12 + 2 * 3 * 8;
        b.extend(i(ofs_surfaces + surface_len));
        assert_eq!(b.len(), 108);
        for k in 0..2 {
            for c in [-1.0f32, -2.0, -3.0, 1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 4.0] {
                b.extend(f(c + k as f32));
            }
            b.extend(name(&format!("frame{k}"), 16));
        }
        for k in 0..2 {
            b.extend(name("tag_torso", 64));
            for c in [0.5f32, 0.0, 20.0 + k as f32] {
                b.extend(f(c));
            }
            // axis: x -> y, y -> -x, z -> z (a quarter turn about z)
            for c in [0.0f32, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
                b.extend(f(c));
            }
        }
        assert_eq!(b.len(), ofs_surfaces as usize);
        b.extend(b"IDP3");
        b.extend(name("body", 64));
        b.extend(i(0)); // flags
        b.extend(i(2)); // frames
        b.extend(i(0)); // shaders
        b.extend(i(3)); // vertices
        b.extend(i(1)); // triangles
        b.extend(i(108)); // ofsTriangles
        b.extend(i(120)); // ofsShaders
        b.extend(i(120)); // ofsSt
        b.extend(i(120)); // ofsXyzNormal
        b.extend(i(surface_len)); // ofsEnd
        b.extend(i(0));
        b.extend(i(2));
        b.extend(i(1));
        // frame 0: (64, 0, 0), (0, 128, 0), (0, 0, -32) in 1/64 units; frame 1: + (1, 1, 1) steps
        for k in 0..2i16 {
            for p in [[64i16, 0, 0], [0, 128, 0], [0, 0, -32]] {
                for c in p {
                    b.extend((c + k).to_le_bytes());
                }
                b.extend([0u8, 0]);
            }
        }
        assert_eq!(b.len(), (ofs_surfaces + surface_len) as usize);
        b
    }

    #[test]
    fn a_hand_built_model_reads_back_to_the_float() {
        let m = parse_md3(&hand_built()).unwrap();
        assert_eq!(m.name, "models/test.md3");
        assert_eq!(m.frames.len(), 2);
        assert_eq!(m.frames[1].name, "frame1");
        assert_eq!(m.frames[1].min, Vector3::new(0.0, -1.0, -2.0));
        assert_eq!(m.frames[0].radius, 4.0);
        assert_eq!(m.tag_index("tag_torso"), Some(0));
        let tag = &m.tags[1][0];
        assert_eq!(tag.origin, Vector3::new(0.5, 0.0, 21.0));
        // The tag's x axis (first column) is the model's y.
        assert_eq!(tag.axis * Vector3::x(), Vector3::y());
        assert_eq!(tag.axis * Vector3::y(), -Vector3::x());
        let s = &m.surfaces[0];
        assert_eq!(s.name, "body");
        assert_eq!(s.triangles, vec![[0, 2, 1]]);
        assert_eq!(
            s.frames[0],
            vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 2.0, 0.0), Vector3::new(0.0, 0.0, -0.5)]
        );
        let step = 1.0 / 64.0;
        assert_eq!(s.frames[1][2], Vector3::new(step, step, -0.5 + step));
        assert_eq!(m.n_vertices(), 3);
    }

    #[test]
    fn encoding_then_parsing_gives_the_same_model() {
        let m = parse_md3(&hand_built()).unwrap();
        let again = parse_md3(&encode_md3(&m).unwrap()).unwrap();
        assert_eq!(again, m);
    }

    fn set_i32(b: &mut [u8], at: usize, v: i32) {
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }

    #[test]
    fn bad_headers_are_refused_with_one_line() {
        let good = hand_built();
        let cases: Vec<(Box<dyn Fn(&mut Vec<u8>)>, &str)> = vec![
            (Box::new(|b: &mut Vec<u8>| b.truncate(50)), "shorter than the 108-byte header"),
            (Box::new(|b: &mut Vec<u8>| b[0] = b'X'), "does not start with \"IDP3\""),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 4, 16)), "unsupported MD3 version 16"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 76, -1)), "negative frame count"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 76, 0)), "no frames"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 76, i32::MAX)), "run past the end"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 80, 1 << 30)), "tags of 112 bytes"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 84, 1 << 20)), "surfaces of 108 bytes"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 100, 1 << 30)), "run past the end"),
            // The surface's vertex count (surface header at 444, counts from 516).
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 444 + 72 + 8, 1 << 28)), "vertices of 8 bytes"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 444 + 72 + 12, 1 << 28)), "triangles of 12 bytes"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 444 + 72, 3)), "has 3 frames, the model 2"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 444 + 108 + 4, 3)), "vertex index 3"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 444 + 108 + 4, -7)), "vertex index -7"),
            (Box::new(|b: &mut Vec<u8>| set_i32(b, 444 + 72 + 32, 1 << 30)), "end offset"),
            (Box::new(|b: &mut Vec<u8>| b.truncate(b.len() - 1)), "end offset"),
            (Box::new(|b: &mut Vec<u8>| b[220 + 112 + 64..220 + 112 + 68].copy_from_slice(&f32::NAN.to_le_bytes())), "not a finite number"),
        ];
        for (k, (corrupt, expected)) in cases.iter().enumerate() {
            let mut b = good.clone();
            corrupt(&mut b);
            let err = parse_md3(&b).expect_err(&format!("case {k} ({expected}) was accepted"));
            assert!(err.contains(expected), "case {k}: '{err}' does not say '{expected}'");
            assert!(!err.contains('\n'), "case {k}: '{err}' is not one line");
        }
    }

    #[test]
    fn reading_a_missing_file_names_it() {
        let err = read_md3("/nonexistent/lower.md3").unwrap_err().to_string();
        assert!(err.contains("/nonexistent/lower.md3"), "{err}");
    }
}

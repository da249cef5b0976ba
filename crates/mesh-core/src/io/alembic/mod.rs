//! Alembic (`.abc`) mesh caches: one animated PolyMesh read into a [`MeshSequence`] and its
//! frame rate. The container is Ogawa ([`super::ogawa`]); this module walks Alembic's schema on
//! top of it, only as far as a PolyMesh's points and faces:
//!
//! - The root group: child 0 the archive version (`i32`), 1 the library version (`i32`), 2 the
//!   top object, 3 the archive's metadata, 4 the time samplings, 5 the indexed metadata.
//! - An object group: child 0 its properties (a compound), children `1..=n` its `n` child
//!   objects, the last child the headers of those children (name, metadata; 32 bytes of hashes
//!   at the end). A PolyMesh's metadata holds `schema=AbcGeom_PolyMesh_v1`.
//! - A compound property group: one child per property, the last child the packed property
//!   headers (kind, plain-old-data type and extent, sample counts, time sampling, name, metadata).
//! - An array property: two children per stored sample, the data (a 16-byte key, then the
//!   values) and its dimensions. Samples equal to the one before are not stored: the header's
//!   first and last changed indices map a sample to the one stored.
//! - A time sampling: time per cycle and the sample times of a cycle; one time per cycle is
//!   uniform sampling, `1 / time per cycle` frames per second.
//!
//! Read: the PolyMesh's `.geom` compound: `P` (float32 or float64 3-vectors, one sample per
//! frame, a constant vertex count), `.faceCounts` and `.faceIndices` (int32), constant over the
//! samples. Faces are stored clockwise (Alembic's convention, which Blender's and Maya's
//! exporters follow by reversing their polygons): each polygon is reversed back to
//! counter-clockwise and fan-triangulated. Positions are the mesh's own coordinates (Alembic is
//! +Y up like surfcap's capture sets: Blender's exporter turns its +Z up into +Y up); parent
//! transforms are not applied. Not read: normals, UVs, velocities, face sets, subdivision
//! surfaces, changing topology, other schemas.
//!
//! Hardening: every count and offset is checked against the file's length before anything is
//! allocated, the object tree is walked without recursion and each object group at most once,
//! and the frames written out (samples repeated from a stored one included) may not need more
//! than [`EXPANSION_LIMIT`] times the file's size.
//!
//! Files: [`headers`] (plain-old-data types, property headers, the little-endian cursor),
//! [`archive`] (the root group, object and property headers, time samplings, metadata),
//! [`tree`] (the object tree walked to the PolyMesh), [`properties`] (stored samples of
//! scalar and array properties), [`time`] (time samplings: sample times, frame rates),
//! [`xform`] (the Xforms above the mesh).

#![forbid(unsafe_code)]

use std::path::Path;

use nalgebra::Vector3;

use super::ogawa::{Group, Ogawa};
use crate::error::{Error, Result};
use crate::input::escape_control;
use crate::sequence::MeshSequence;

mod archive;
mod headers;
mod properties;
mod time;
mod tree;
mod xform;

use archive::Archive;
use headers::{Kind, Pod, PropertyHeader};
use properties::{array_sample, int32s, property};
use time::{sample_near, sample_time, sampling_fps, TimeSampling};
use tree::find_polymesh;
use xform::read_xform;

/// The frames read (as f64 vertices) may need at most this many times the file's bytes:
/// samples that repeat the one before are stored once, so a few bytes could otherwise ask for
/// any number of frames.
pub const EXPANSION_LIMIT: u64 = 32;

/// A PolyMesh read from an Alembic file.
#[derive(Clone, Debug)]
pub struct AlembicMesh {
    /// The object's full path in the file (`/Cube/CubeShape`).
    pub path: String,
    /// The frames, counter-clockwise triangles.
    pub sequence: MeshSequence,
    /// Frames per second of `P`'s time sampling.
    pub fps: f64,
    /// Time of the first sample, seconds.
    pub start_time: f64,
    /// Polygons left out as degenerate (fewer than 3 distinct corners).
    pub skipped_faces: usize,
}

/// Refuses `n_frames` frames of `n_vertices` vertices (f64) when they need more than
/// [`EXPANSION_LIMIT`] times a file of `file_len` bytes.
fn check_expansion(n_frames: usize, n_vertices: usize, file_len: usize) -> std::result::Result<(), String> {
    let needed = (n_frames as u128) * (n_vertices as u128) * 24;
    if needed > u128::from(EXPANSION_LIMIT) * file_len as u128 {
        return Err(format!(
            "P has {n_frames} samples of {n_vertices} points: {needed} bytes of frames, more than \
             {EXPANSION_LIMIT} times the file's {file_len} bytes (samples stored once and repeated)"
        ));
    }
    Ok(())
}

/// Reads a PolyMesh from an Alembic file held in memory: the one named `object` (its name or
/// full path), else the first. The error is the problem without the file name.
pub fn parse_alembic(bytes: &[u8], object: Option<&str>) -> std::result::Result<AlembicMesh, String> {
    let file = Ogawa::parse(bytes)?;
    let mut archive = Archive::open(&file)?;
    let (tree, found, others) = find_polymesh(&mut archive, object)?;
    let Some(mesh_node) = found else {
        return Err(match object {
            Some(w) if !others.is_empty() => format!(
                "no PolyMesh at or below '{}' (the file has {})",
                escape_control(w),
                escape_control(&others.join(", "))
            ),
            Some(w) => format!("no PolyMesh at or below '{}' (the file has none)", escape_control(w)),
            None => "holds no PolyMesh (only PolyMesh objects are read)".into(),
        });
    };
    let path = tree.path(mesh_node);
    let group = tree.nodes[mesh_node].group;
    let at = |e: String| format!("PolyMesh {}: {e}", escape_control(&path));
    if !group.is_group(0) {
        return Err(at("has no properties".into()));
    }
    let props = group.group(0).map_err(at)?;
    let (geom_h, geom) = property(&mut archive, &props, ".geom")
        .map_err(at)?
        .ok_or_else(|| at("has no .geom properties".into()))?;
    if geom_h.kind != Kind::Compound {
        return Err(at(".geom is not a compound property".into()));
    }
    // The .geom headers parsed once, each property looked up in them.
    let geom_headers = archive.property_headers(&geom).map_err(at)?;
    let array = |name: &str| -> std::result::Result<(PropertyHeader, Group), String> {
        let i = geom_headers.iter().position(|h| h.name == name).ok_or_else(|| format!("has no {name}"))?;
        let (h, g) = (geom_headers[i].clone(), geom.group(i as u64)?);
        if h.kind != Kind::Array {
            return Err(format!("{name} is not an array property"));
        }
        Ok((h, g))
    };
    let (p_h, p_g) = array("P").map_err(at)?;
    let (counts_h, counts_g) = array(".faceCounts").map_err(at)?;
    let (indices_h, indices_g) = array(".faceIndices").map_err(at)?;

    // Topology: every stored sample equal to the first.
    let mut topology = Vec::with_capacity(2);
    for (h, g) in [(&counts_h, &counts_g), (&indices_h, &indices_g)] {
        if h.pod != Pod::Int32 || h.extent != 1 {
            return Err(at(format!("{} is {} x{}, expected int32", h.name, h.pod.name(), h.extent)));
        }
        if h.samples == 0 {
            return Err(at(format!("{} has no samples", h.name)));
        }
        let last = h.stored_index(h.samples - 1).ok_or_else(|| at(format!("{}: inconsistent sample indices", h.name)))?;
        let first = array_sample(h, g, 0).map_err(at)?;
        for k in 1..=last {
            if array_sample(h, g, k).map_err(at)? != first {
                return Err(at(format!(
                    "{} changes at stored sample {k}: only constant topology is read",
                    h.name
                )));
            }
        }
        topology.push(first);
    }
    let (counts, indices) = (topology[0], topology[1]);

    // Points.
    if !matches!(p_h.pod, Pod::Float32 | Pod::Float64) || p_h.extent != 3 {
        return Err(at(format!("P is {} x{}, expected float32 or float64 x3", p_h.pod.name(), p_h.extent)));
    }
    if p_h.samples == 0 {
        return Err(at("P has no samples".into()));
    }
    let first = array_sample(&p_h, &p_g, 0).map_err(at)?;
    let elem = p_h.pod.size().unwrap_or(4) * 3;
    let n_vertices = first.len() / elem;
    if n_vertices == 0 {
        return Err(at("P has no points".into()));
    }
    let decode = |values: &[u8], k: u32| -> std::result::Result<Vec<Vector3<f64>>, String> {
        let mut v = Vec::with_capacity(values.len() / elem);
        for (j, e) in values.chunks_exact(elem).enumerate() {
            let p = if p_h.pod == Pod::Float32 {
                let f = |i: usize| f64::from(f32::from_le_bytes([e[i], e[i + 1], e[i + 2], e[i + 3]]));
                Vector3::new(f(0), f(4), f(8))
            } else {
                let f = |i: usize| {
                    let mut a = [0u8; 8];
                    a.copy_from_slice(&e[i..i + 8]);
                    f64::from_le_bytes(a)
                };
                Vector3::new(f(0), f(8), f(16))
            };
            if !p.iter().all(|c| c.is_finite()) {
                return Err(format!("P sample {k}, point {j}: coordinate is not finite"));
            }
            v.push(p);
        }
        Ok(v)
    };
    let samplings = std::mem::take(&mut archive.time_samplings);
    let sampling = |index: u32, what: &str| -> std::result::Result<TimeSampling, String> {
        samplings.get(index as usize).cloned().ok_or_else(|| {
            at(format!("{what}'s time sampling {index} is not in the archive's {}", samplings.len()))
        })
    };
    let p_ts = sampling(p_h.time_sampling, "P")?;
    // The Xforms above the mesh, outermost first: frame k is placed by their matrices at its
    // time (each Xform's sample nearest that time).
    let mut xforms = Vec::new();
    for n in tree.xforms(mesh_node) {
        let node_path = tree.path(n);
        xforms.push(read_xform(&mut archive, node_path, &tree.nodes[n].group)?);
    }
    // The frames are P's samples; points that never change under an animated Xform (a rigid
    // object's motion: Blender writes P once) follow the Xform with the most samples instead.
    let animated = xforms.iter().filter_map(|x| x.header.as_ref()).filter(|h| h.samples > 1).max_by_key(|h| h.samples);
    let (ts, n_frames, follows_p) = match animated {
        Some(h) if p_h.samples == 1 => (sampling(h.time_sampling, "its Xform")?, h.samples, false),
        _ => (p_ts.clone(), p_h.samples, true),
    };
    let fps = sampling_fps(&ts, if follows_p { "P" } else { "its Xform" }).map_err(at)?;
    let start_time = ts.times.first().copied().unwrap_or(0.0);
    check_expansion(n_frames as usize, n_vertices, bytes.len()).map_err(at)?;
    let mut frames: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(n_frames as usize);
    let mut local: Vec<Vector3<f64>> = Vec::new();
    let mut last_stored = None;
    for k in 0..n_frames {
        let t = sample_time(&ts, k);
        let pk = if follows_p { k } else { sample_near(&p_ts, p_h.samples, t) };
        let stored = p_h.stored_index(pk).ok_or_else(|| at("P: inconsistent sample indices".into()))?;
        if last_stored != Some(stored) {
            let values = array_sample(&p_h, &p_g, stored).map_err(at)?;
            if values.len() / elem != n_vertices {
                return Err(at(format!(
                    "P sample {pk} has {} points, sample 0 has {n_vertices}: only constant topology is read",
                    values.len() / elem
                )));
            }
            local = decode(values, pk).map_err(at)?;
            last_stored = Some(stored);
        }
        let mut world = nalgebra::Matrix4::identity();
        for x in &xforms {
            let m = x.matrix_at(&samplings, t)?;
            world = if x.inherits { world * m } else { m };
        }
        if world == nalgebra::Matrix4::identity() {
            frames.push(local.clone());
        } else {
            let placed: Vec<Vector3<f64>> = local.iter().map(|p| (world * p.push(1.0)).xyz()).collect();
            if let Some(j) = placed.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
                return Err(at(format!("P sample {k}, point {j}: not finite once placed by its Xforms")));
            }
            frames.push(placed);
        }
    }

    // Faces: clockwise polygons reversed and fan-triangulated.
    let mut faces = Vec::with_capacity(indices.len() / 4);
    let mut all = int32s(indices);
    let mut poly = Vec::new();
    let mut skipped = 0;
    let mut used = 0usize;
    for (f, count) in int32s(counts).enumerate() {
        let count = usize::try_from(count).map_err(|_| at(format!("face {f} has {count} corners")))?;
        if count > indices.len() / 4 - used {
            return Err(at(format!(
                ".faceCounts asks for more corners than the {} of .faceIndices",
                indices.len() / 4
            )));
        }
        used += count;
        poly.clear();
        for _ in 0..count {
            let i = all.next().unwrap_or(-1);
            if i < 0 || i as usize >= n_vertices {
                return Err(at(format!("face {f}: vertex index {i} out of range (0..{n_vertices})")));
            }
            poly.push(i as u32);
        }
        poly.reverse();
        skipped += super::push_fan(&mut faces, &poly);
    }
    if used != indices.len() / 4 {
        return Err(at(format!(
            ".faceCounts covers {used} corners but .faceIndices has {}",
            indices.len() / 4
        )));
    }

    Ok(AlembicMesh {
        path,
        sequence: MeshSequence::new(faces, frames),
        fps,
        start_time,
        skipped_faces: skipped,
    })
}

/// Reads a PolyMesh from the Alembic file `path` (see [`parse_alembic`]); errors are one line
/// naming the file.
pub fn read_alembic(path: impl AsRef<Path>, object: Option<&str>) -> Result<AlembicMesh> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    let mesh = parse_alembic(&bytes, object).map_err(|m| Error::file(path, m))?;
    super::warn_skipped_faces(path, mesh.skipped_faces);
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Vec<u8> {
        std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/alembic/cube.abc")).unwrap()
    }

    /// `fixtures/alembic/cube.abc`, written by Blender 5.0.1 (`fixtures/alembic/cube.py`): a cube
    /// with a shape key, turned, scaled and moving (an animated Xform above the mesh), read back
    /// as the world-space values Blender printed (7 decimals), turned +Z up -> +Y up.
    #[test]
    fn blenders_cube_reads_as_blender_had_it() {
        let m = parse_alembic(&cube(), None).unwrap();
        assert_eq!(m.path, "/Cube/CubeShape");
        assert_eq!(m.fps, 25.0);
        assert!((m.start_time - 0.04).abs() < 1e-12, "{}", m.start_time);
        assert_eq!(m.skipped_faces, 0);
        let blender: [[[f64; 3]; 8]; 3] = [
            [[0.2554128, -2.2618861, 1.2268115], [0.4457921, -2.4879124, 2.182148],
             [-0.9754766, -0.8005229, 1.817852], [-0.7850972, -1.0265492, 2.7731886],
             [1.7850972, -0.9734508, 1.2268115], [1.9754765, -1.1994772, 2.182148],
             [0.5542079, 0.4879125, 1.817852], [0.7445872, 0.2618862, 2.7731886]],
            [[0.5935379, -1.9577692, 1.2010374], [0.8697543, -2.2080913, 2.3952079],
             [-0.8685894, -0.0666433, 1.9398379], [-0.5923732, -0.3169653, 3.1340086],
             [2.658612, -0.2183814, 1.2010374], [2.9348283, -0.4687035, 2.3952079],
             [1.1964844, 1.6727444, 1.9398379], [1.4727008, 1.4224224, 3.1340086]],
            [[0.9316632, -1.6536522, 1.1752632], [1.2937164, -1.92827, 2.608268],
             [-0.7617023, 0.6672363, 2.0618238], [-0.3996491, 0.3926186, 3.4948287],
             [3.5321267, 0.5366879, 1.1752632], [3.8941798, 0.2620701, 2.608268],
             [1.8387611, 2.8575764, 2.0618238], [2.2008145, 2.5829587, 3.4948287]],
        ];
        assert_eq!(m.sequence.n_frames(), 3);
        for (frame, want) in m.sequence.frames.iter().zip(&blender) {
            assert_eq!(frame.len(), 8);
            for (got, b) in frame.iter().zip(want) {
                let want = Vector3::new(b[0], b[2], -b[1]);
                assert!((got - want).amax() < 1e-6, "{got:?} vs {want:?}");
            }
        }
        // Blender's quads, counter-clockwise as Blender has them, fan-triangulated.
        let quads = [[0, 1, 3, 2], [2, 3, 7, 6], [6, 7, 5, 4], [4, 5, 1, 0], [2, 6, 4, 0], [7, 3, 1, 5]];
        let want: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        assert_eq!(m.sequence.faces, want);
        // Outward normals: the faces wind counter-clockwise seen from outside.
        let f0 = &m.sequence.frames[0];
        let middle = f0.iter().sum::<Vector3<f64>>() / 8.0;
        for t in &m.sequence.faces {
            let [a, b, c] = t.map(|i| f0[i as usize]);
            let centre = (a + b + c) / 3.0 - middle;
            assert!((b - a).cross(&(c - a)).dot(&centre) > 0.0, "{t:?} winds inwards");
        }
        // Picked by name or by path; a missing name lists the meshes there are.
        assert_eq!(parse_alembic(&cube(), Some("CubeShape")).unwrap().path, "/Cube/CubeShape");
        assert_eq!(parse_alembic(&cube(), Some("/Cube/CubeShape")).unwrap().path, "/Cube/CubeShape");
        // The Xform above it names it too.
        assert_eq!(parse_alembic(&cube(), Some("Cube")).unwrap().path, "/Cube/CubeShape");
        assert_eq!(parse_alembic(&cube(), Some("/Cube")).unwrap().path, "/Cube/CubeShape");
        let err = parse_alembic(&cube(), Some("Suzanne")).unwrap_err();
        assert_eq!(err, "no PolyMesh at or below 'Suzanne' (the file has /Cube/CubeShape)");
        for wrong in ["/CubeShape", "/X/CubeShape", "Cube/CubeShape", "//Cube/CubeShape", "/"] {
            assert!(parse_alembic(&cube(), Some(wrong)).unwrap_err().starts_with("no PolyMesh at or below"), "{wrong}");
        }
    }

    /// `fixtures/alembic/rigid.abc` (`rigid.py`): a mesh that does not deform under an animated
    /// parent, written by Blender as one sample of points below animated Xforms (/Rig, /Rig/Tet),
    /// reads as Blender's world-space frames, at the Xforms' 4 samples and 30 fps; the still
    /// `Ball` beside it by `--object`.
    #[test]
    fn a_rigid_motion_is_the_xforms_frames() {
        let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/alembic/rigid.abc")).unwrap();
        let m = parse_alembic(&bytes, None).unwrap();
        assert_eq!((m.path.as_str(), m.fps, m.sequence.n_frames()), ("/Rig/Tet/TetShape", 30.0, 4));
        let blender = [
            [[1.4794255, 2.0, 3.8775826], [2.357008, 2.0, 3.3981571], [1.4794255, 3.0, 3.8775826], [1.9588511, 2.0, 4.7551651]],
            [[1.9476438, 2.0, 3.7253461], [2.6729898, 2.0, 3.0369618], [1.9476438, 3.0, 3.7253461], [2.6360281, 2.0, 4.4506922]],
            [[2.6867652, 2.0, 3.3240955], [3.0108607, 2.0, 2.3780711], [2.6867652, 3.0, 3.3240955], [3.6327896, 2.0, 3.648191]],
            [[2.9974949, 2.0, 3.0707371], [3.0682321, 2.0, 2.0732422], [2.9974949, 3.0, 3.0707371], [3.9949899, 2.0, 3.1414742]],
        ];
        for (frame, want) in m.sequence.frames.iter().zip(&blender) {
            for (got, b) in frame.iter().zip(want) {
                let want = Vector3::new(b[0], b[2], -b[1]);
                assert!((got - want).amax() < 1e-6, "{got:?} vs {want:?}");
            }
        }
        assert_eq!(m.sequence.faces, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
        let ball = parse_alembic(&bytes, Some("Ball")).unwrap();
        assert_eq!((ball.path.as_str(), ball.sequence.n_frames(), ball.sequence.n_vertices()), ("/Ball/Icosphere", 1, 12));
        assert!(ball.sequence.frames[0].iter().all(|p| (p.x - 3.0).abs() <= 1.0 + 1e-6));
        for n in 0..bytes.len() {
            assert!(parse_alembic(&bytes[..n], None).is_err(), "prefix of {n} bytes read");
        }
    }

    /// Every proper prefix of the fixture is an error, never a panic.
    #[test]
    fn every_truncation_is_an_error() {
        let bytes = cube();
        for n in 0..bytes.len() {
            assert!(parse_alembic(&bytes[..n], None).is_err(), "prefix of {n} bytes read");
        }
    }

    /// Every single-bit flip of the fixture reads or fails, never panics, and a read keeps the
    /// sequence's shape consistent.
    #[test]
    fn bit_flips_never_panic() {
        let bytes = cube();
        for i in 0..bytes.len() {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                if let Ok(m) = parse_alembic(&b, None) {
                    let n = m.sequence.n_vertices();
                    assert!(m.sequence.frames.iter().all(|f| f.len() == n));
                    assert!(m.sequence.faces.iter().flatten().all(|&v| (v as usize) < n));
                    assert!(crate::frame_rate::check_fps(m.fps).is_ok());
                }
            }
        }
    }

    /// Errors read as one line naming the file.
    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.abc");
        std::fs::write(&path, &cube()[..1000]).unwrap();
        let err = read_alembic(&path, None).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}: ", path.display())) && err.lines().count() == 1, "{err}");
        std::fs::write(&path, b"POINTCACHE2\0 and more bytes").unwrap();
        let err = read_alembic(&path, None).unwrap_err().to_string();
        assert!(err.ends_with("not an Alembic (Ogawa) file: it does not start with \"Ogawa\""), "{err}");
    }

    /// A few bytes claiming 4 billion repeats of one stored sample are refused before allocating.
    #[test]
    fn repeats_beyond_the_files_size_are_refused() {
        assert!(check_expansion(3, 8, 3258).is_ok());
        assert!(check_expansion(1000, 100_000, 300_000_000).is_ok());
        let err = check_expansion(u32::MAX as usize, 8, 3258).unwrap_err();
        assert!(err.contains("more than 32 times the file's 3258 bytes"), "{err}");
    }

}

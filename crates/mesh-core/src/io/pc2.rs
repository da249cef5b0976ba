//! PC2 point caches: the vertex-animation format of 3ds Max that Blender's
//! Mesh Cache modifier reads, paired with a template OBJ holding the faces.
//!
//! Layout (little-endian): `"POINTCACHE2\0"` (12 bytes), `i32` version (1),
//! `i32` numPoints, `f32` startFrame, `f32` sampleRate, `i32` numSamples, then
//! `numSamples x numPoints x (f32 x, f32 y, f32 z)`. Positions are stored in
//! f32, so a round trip keeps them to float32 precision.
//!
//! Reading checks that the header's counts match the file's length exactly
//! before allocating, so a crafted header cannot make it allocate more than
//! the file justifies.
//!
//! A pair is written PC2 first, then OBJ, each atomically; the OBJ's first line names the
//! pair's identity ([`PAIR_TAG`], [`write_pair`]) and [`read_obj_pc2`] refuses a mismatched
//! pair, so a reader sees a whole pair or an error, never a new OBJ over an old cache.

use std::io::Write;
use std::path::Path;

use nalgebra::Vector3;

use crate::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::sequence::MeshSequence;

/// The 12 magic bytes of a PC2 file.
pub const MAGIC: &[u8; 12] = b"POINTCACHE2\0";
const HEADER_LEN: usize = 32;

/// A point cache: per-sample vertex positions plus timing.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCache {
    /// Frame number of the first sample.
    pub start_frame: f32,
    /// Frames between samples (1.0 = one sample per frame).
    pub sample_rate: f32,
    /// Positions of every vertex, per sample.
    pub samples: Vec<Vec<Vector3<f64>>>,
}

/// Serialises the frames as PC2 (start frame 0, one sample per frame).
pub fn encode_pc2(w: &mut dyn Write, frames: &[Vec<Vector3<f64>>]) -> std::io::Result<()> {
    let n_points = frames.first().map_or(0, Vec::len);
    let too_big = |what: &str| std::io::Error::other(format!("too many {what} for PC2 (i32)"));
    let n_points_i = i32::try_from(n_points).map_err(|_| too_big("points"))?;
    let n_samples_i = i32::try_from(frames.len()).map_err(|_| too_big("samples"))?;
    let mut buf = Vec::with_capacity(HEADER_LEN + frames.len() * n_points * 12);
    buf.extend_from_slice(MAGIC);
    buf.extend_from_slice(&1i32.to_le_bytes());
    buf.extend_from_slice(&n_points_i.to_le_bytes());
    buf.extend_from_slice(&0f32.to_le_bytes());
    buf.extend_from_slice(&1f32.to_le_bytes());
    buf.extend_from_slice(&n_samples_i.to_le_bytes());
    for frame in frames {
        if frame.len() != n_points {
            return Err(std::io::Error::other(format!(
                "frames have {} and {n_points} vertices: PC2 needs one vertex count",
                frame.len()
            )));
        }
        for v in frame {
            for c in [v.x, v.y, v.z] {
                buf.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
    }
    w.write_all(&buf)
}

/// Writes `frames` as a PC2 file, atomically.
pub fn write_pc2(path: impl AsRef<Path>, frames: &[Vec<Vector3<f64>>]) -> Result<()> {
    write_atomic(path.as_ref(), |w| encode_pc2(w, frames))
}

fn i32_at(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

/// Parses a PC2 file held in memory; the error is the problem without the file name.
pub fn parse_pc2(bytes: &[u8]) -> std::result::Result<PointCache, String> {
    if bytes.len() < HEADER_LEN {
        return Err(format!(
            "not a PC2 file: {} bytes, shorter than the 32-byte header",
            bytes.len()
        ));
    }
    if &bytes[..12] != MAGIC {
        return Err("not a PC2 file: it does not start with \"POINTCACHE2\"".into());
    }
    let version = i32_at(bytes, 12);
    if version != 1 {
        return Err(format!("unsupported PC2 version {version} (expected 1)"));
    }
    let (n_points, n_samples) = (i32_at(bytes, 16), i32_at(bytes, 28));
    let (start_frame, sample_rate) = (f32_at(bytes, 20), f32_at(bytes, 24));
    if n_points < 0 || n_samples < 0 {
        return Err(format!(
            "negative count in header ({n_points} points, {n_samples} samples)"
        ));
    }
    if !start_frame.is_finite() || !sample_rate.is_finite() {
        return Err("start frame or sample rate is not a finite number".into());
    }
    let (n_points, n_samples) = (n_points as usize, n_samples as usize);
    let payload = bytes.len() - HEADER_LEN;
    let expected = (n_points as u128) * (n_samples as u128) * 12;
    if expected != payload as u128 {
        return Err(format!(
            "header announces {n_samples} samples of {n_points} points ({expected} bytes) \
             but {payload} bytes follow it"
        ));
    }
    let mut samples = Vec::with_capacity(n_samples);
    let mut at = HEADER_LEN;
    for s in 0..n_samples {
        let mut frame = Vec::with_capacity(n_points);
        for p in 0..n_points {
            let v = Vector3::new(
                f32_at(bytes, at),
                f32_at(bytes, at + 4),
                f32_at(bytes, at + 8),
            );
            if !v.iter().all(|c| c.is_finite()) {
                return Err(format!("sample {s}, point {p}: coordinate is not finite"));
            }
            frame.push(v.cast::<f64>());
            at += 12;
        }
        samples.push(frame);
    }
    Ok(PointCache {
        start_frame,
        sample_rate,
        samples,
    })
}

/// Reads a PC2 file; errors are one line naming the file.
pub fn read_pc2(path: impl AsRef<Path>) -> Result<PointCache> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    parse_pc2(&bytes).map_err(|m| Error::file(path, m))
}

/// The first line of a pair's OBJ, followed by the pair's identity (64 hex digits).
pub const PAIR_TAG: &str = "# surfcap obj+pc2 pair sha256 ";

/// The identity of an OBJ + PC2 pair: the SHA-256 of the OBJ's bytes after its first line
/// (the vertices and faces) followed by the PC2's bytes, in lowercase hex.
fn pair_identity(obj_body: &[u8], pc2: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update(obj_body);
    h.update(pc2);
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// Writes `seq` as a template OBJ (frame 0 with the faces) plus a PC2 cache ([`write_pair`]).
pub fn write_obj_pc2(obj: &Path, pc2: &Path, seq: &MeshSequence) -> Result<()> {
    write_pair(obj, pc2, &seq.faces, &seq.frames)
}

/// Writes `frames` as the PC2 cache `pc2` and the template OBJ `obj` (the first frame with
/// `faces`), each atomically, the PC2 first. The OBJ's first line carries the pair's identity
/// (`PAIR_TAG` + the SHA-256 of the OBJ's geometry and the PC2's bytes), so a reader refuses
/// an OBJ beside a PC2 it was not written with: one of the two replaced by another pair's,
/// or a write killed between the two renames.
pub fn write_pair(obj: &Path, pc2: &Path, faces: &[[u32; 3]], frames: &[Vec<Vector3<f64>>]) -> Result<()> {
    let Some(first) = frames.first() else {
        return Err(Error::file(pc2, "cannot export an empty sequence"));
    };
    let mut cache = Vec::new();
    encode_pc2(&mut cache, frames).map_err(|e| Error::file(pc2, e.to_string()))?;
    let mut body = Vec::new();
    super::obj::encode_obj(&mut body, &crate::mesh::TriMesh::new(first.clone(), faces.to_vec()))
        .map_err(|e| Error::file(obj, e.to_string()))?;
    let id = pair_identity(&body, &cache);
    write_atomic(pc2, |w| w.write_all(&cache))?;
    write_atomic(obj, |w| {
        w.write_all(format!("{PAIR_TAG}{id}\n").as_bytes())?;
        w.write_all(&body)
    })
}

/// Reads a template OBJ/PLY (for the faces) plus a PC2 cache into a sequence; the cache's
/// point count must equal the template's vertex count. A template OBJ written by
/// [`write_pair`] must be the PC2's pair (its identity line matches); a template without that
/// line (another tool's, or an older surfcap's) is read unchecked.
pub fn read_obj_pc2(template: &Path, pc2: &Path) -> Result<MeshSequence> {
    let cache_bytes = crate::input::read_regular_file(pc2)?;
    // The cache's own problems first (a truncated PC2 is reported as such), then the pair's.
    let cache = parse_pc2(&cache_bytes).map_err(|m| Error::file(pc2, m))?;
    let is_obj = super::MeshFormat::from_path(template) == Some(super::MeshFormat::Obj);
    let mesh = if is_obj {
        let bytes = crate::input::read_regular_file(template)?;
        check_pair(template, pc2, &bytes, &cache_bytes)?;
        super::obj::read_obj_bytes(template, &bytes)?
    } else {
        super::read_mesh(template)?
    };
    if let Some(first) = cache.samples.first() {
        if first.len() != mesh.vertices.len() {
            return Err(Error::file(
                pc2,
                format!(
                    "has {} points but the template {} has {} vertices",
                    first.len(),
                    template.display(),
                    mesh.vertices.len()
                ),
            ));
        }
    }
    Ok(MeshSequence::new(mesh.faces, cache.samples))
}

/// Refuses an OBJ whose pair identity line does not match its geometry and `cache`.
fn check_pair(obj: &Path, pc2: &Path, obj_bytes: &[u8], cache: &[u8]) -> Result<()> {
    let Some(rest) = obj_bytes.strip_prefix(PAIR_TAG.as_bytes()) else {
        return Ok(());
    };
    let line_end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
    let recorded = String::from_utf8_lossy(&rest[..line_end]);
    let body = rest.get(line_end + 1..).unwrap_or(&[]);
    if recorded.trim() != pair_identity(body, cache) {
        return Err(Error::file(
            obj,
            format!(
                "is not the pair of {}: the pair identity in its first line does not match \
                 (one of the two was replaced, or a write was interrupted)",
                pc2.display()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(n_points: i32, n_samples: i32) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(&n_points.to_le_bytes());
        b.extend_from_slice(&0f32.to_le_bytes());
        b.extend_from_slice(&1f32.to_le_bytes());
        b.extend_from_slice(&n_samples.to_le_bytes());
        b
    }

    /// Byte layout checked by hand against the format description.
    #[test]
    fn known_bytes() {
        let frames = vec![
            vec![Vector3::new(1.0, 2.0, 3.0)],
            vec![Vector3::new(-0.5, 0.25, 4.0)],
        ];
        let mut out = Vec::new();
        encode_pc2(&mut out, &frames).unwrap();
        let mut expected = header(1, 2);
        for c in [1.0f32, 2.0, 3.0, -0.5, 0.25, 4.0] {
            expected.extend_from_slice(&c.to_le_bytes());
        }
        assert_eq!(out, expected);
        let back = parse_pc2(&out).unwrap();
        assert_eq!(back.samples, frames);
        assert_eq!((back.start_frame, back.sample_rate), (0.0, 1.0));
    }

    #[test]
    fn crafted_counts_are_rejected_before_allocating() {
        // Claims 2^31-1 x 2^31-1 points (~5e19 bytes) with no payload.
        let err = parse_pc2(&header(i32::MAX, i32::MAX)).unwrap_err();
        assert!(err.contains("but 0 bytes follow"), "{err}");
        let err = parse_pc2(&header(-1, 2)).unwrap_err();
        assert!(err.contains("negative"), "{err}");
        let mut short = header(2, 1);
        short.extend_from_slice(&[0u8; 12]);
        assert!(parse_pc2(&short).unwrap_err().contains("24 bytes"));
        assert!(parse_pc2(b"POINTCACHE").unwrap_err().contains("shorter"));
        let mut bad = header(0, 0);
        bad[0] = b'X';
        assert!(parse_pc2(&bad).unwrap_err().contains("not a PC2"));
    }

    fn walk(shift: f64) -> MeshSequence {
        let m = crate::shapes::icosphere(1);
        let frames = (0..4)
            .map(|t| m.vertices.iter().map(|p| p + Vector3::new(shift, 0.1 * t as f64, 0.0)).collect())
            .collect();
        MeshSequence::new(m.faces, frames)
    }

    /// Two pairs written side by side; one file of the first replaced by the second's (as a
    /// write killed between the two renames leaves it) makes the reader refuse, naming both.
    #[test]
    fn a_pair_with_a_file_of_another_pair_is_refused_naming_both_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = |n: &str| dir.path().join(n);
        write_obj_pc2(&p("a.obj"), &p("a.pc2"), &walk(0.0)).unwrap();
        write_obj_pc2(&p("b.obj"), &p("b.pc2"), &walk(1.0)).unwrap();
        assert_eq!(read_obj_pc2(&p("a.obj"), &p("a.pc2")).unwrap().n_frames(), 4);
        let first = std::fs::read_to_string(p("a.obj")).unwrap();
        assert!(first.starts_with(PAIR_TAG) && first.lines().next().unwrap().len() == PAIR_TAG.len() + 64, "{first:.100}");
        let (a_obj, a_pc2) = (std::fs::read(p("a.obj")).unwrap(), std::fs::read(p("a.pc2")).unwrap());
        for (replaced, by) in [("a.pc2", "b.pc2"), ("a.obj", "b.obj")] {
            std::fs::copy(p(by), p(replaced)).unwrap();
            let err = read_obj_pc2(&p("a.obj"), &p("a.pc2")).unwrap_err().to_string();
            assert!(err.contains("a.obj") && err.contains("a.pc2") && err.contains("not the pair"), "{err}");
            assert_eq!(err.lines().count(), 1);
            std::fs::write(p("a.obj"), &a_obj).unwrap();
            std::fs::write(p("a.pc2"), &a_pc2).unwrap();
        }
        // An edited vertex of the OBJ breaks the identity as well.
        let edited = String::from_utf8(a_obj.clone()).unwrap().replacen("\nv ", "\nv 9", 1);
        std::fs::write(p("a.obj"), edited).unwrap();
        assert!(read_obj_pc2(&p("a.obj"), &p("a.pc2")).unwrap_err().to_string().contains("not the pair"));
    }

    /// A pair without the identity line (another tool's, or an older export) is read unchecked.
    #[test]
    fn a_pair_without_the_identity_line_is_read_as_before() {
        let dir = tempfile::tempdir().unwrap();
        let (obj, pc2) = (dir.path().join("w.obj"), dir.path().join("w.pc2"));
        let seq = walk(0.5);
        super::super::write_obj(&obj, &seq.frame_mesh(0)).unwrap();
        write_pc2(&pc2, &seq.frames).unwrap();
        let back = read_obj_pc2(&obj, &pc2).unwrap();
        assert_eq!(back.faces, seq.faces);
        assert_eq!(back.n_frames(), 4);
        // The written pair's OBJ is that same file after its identity line.
        let (obj2, pc22) = (dir.path().join("v.obj"), dir.path().join("v.pc2"));
        write_obj_pc2(&obj2, &pc22, &seq).unwrap();
        let text = std::fs::read_to_string(&obj2).unwrap();
        assert_eq!(text.split_once('\n').unwrap().1, std::fs::read_to_string(&obj).unwrap());
        assert_eq!(std::fs::read(&pc22).unwrap(), std::fs::read(&pc2).unwrap());
    }
}

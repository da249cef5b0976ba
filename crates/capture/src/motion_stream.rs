//! Reading an aligned motion frame by frame: each frame goes to a sink as it is decoded, so a
//! motion of any length is read holding one frame (plus whatever the sink keeps), in one pass
//! that also hashes the file. `gpr-train` and `dtw-densify` encode the frames into PCA
//! coefficients this way ([`read_encoded`]) instead of holding whole motions, and `pca-fit` reads
//! its training motions pass by pass ([`MotionFiles`], [`crate::streamed_pca`]).
//!
//! The frames are checked as [`AlignedMotion::validate`] checks them, and the sink gets only
//! frames that passed: every frame has frame 0's vertex count and finite coordinates. The
//! errors are those of [`AlignedMotion::load`], in its order: the file's (a corrupt file is a
//! checksum mismatch), then the payload's checks, then the sink's.

use std::fmt;
use std::path::{Path, PathBuf};

use mesh_core::artifact::{read_artifact_seeded, Artifact};
use mesh_core::rigid::RigidMotion;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use serde::de::{DeserializeSeed, Deserializer, Error as _, SeqAccess, Visitor};

use crate::align::{check_besides_frames, AlignedMotion, CaptureInfo, FrameChecks};
use crate::part_pca::{check_same_template, EncodedFrames, FrameEncoder, PcaModel};
use crate::streamed_pca::TrainingFrames;

/// An aligned motion without its frames' vertices, as [`read_frames`] returns it.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionInfo {
    pub faces: Vec<[u32; 3]>,
    /// Number of frames (each handed to the sink).
    pub n_frames: usize,
    /// Vertices per frame.
    pub n_vertices: usize,
    pub poses: Vec<RigidMotion>,
    pub displacements: Vec<[f64; 6]>,
    pub anchor: Vec<u32>,
    pub capture: CaptureInfo,
}

/// Reads the aligned motion at `path` in one pass, handing each frame in order to `sink` once
/// it passed the checks of [`AlignedMotion::validate`]; returns the rest of the motion and the
/// file's SHA-256 (for an input record). After a frame fails a check or the sink returns an
/// error, the sink gets no more frames; the first such problem is the error, naming the file,
/// once the whole file was read and its checksum matched.
pub fn read_frames(
    path: impl AsRef<Path>,
    mut sink: impl FnMut(Vec<Vector3<f64>>) -> Result<()>,
) -> Result<(MotionInfo, String)> {
    let path = path.as_ref();
    let mut frames = StreamChecks::default();
    let seed = MotionSeed { frames: &mut frames, sink: &mut sink };
    let (_, rest, sha256) = read_artifact_seeded(path, AlignedMotion::KIND, AlignedMotion::VERSION, seed)?;
    let invalid = |msg: String| Error::file(path, format!("invalid '{}' payload: {msg}", AlignedMotion::KIND));
    let (faces, poses, displacements, anchor, capture) = rest;
    let n = frames.checks.verdict().map_err(invalid)?;
    let n_frames = frames.checks.n_frames;
    check_besides_frames(n, n_frames, &faces, &anchor, poses.len(), displacements.len(), &capture)
        .map_err(invalid)?;
    if let Some(e) = frames.sink_error {
        return Err(Error::file(path, e.to_string()));
    }
    Ok((MotionInfo { faces, n_frames, n_vertices: n, poses, displacements, anchor, capture }, sha256))
}

/// The aligned motion at `path` encoded with `pca` as it is read ([`read_frames`] into a
/// [`FrameEncoder`]): per part, the coefficients of every frame (`F x m_k`, those of
/// [`PcaModel::encode`] on the loaded motion, to the bit), the rest of the motion and the file's
/// SHA-256. Holds the coefficients and at most two encoder blocks of frames, never the motion.
/// Fails, naming the file, as [`PcaModel::check_motion`] fails on a motion of another vertex
/// count or template.
pub fn read_encoded(path: impl AsRef<Path>, pca: &PcaModel) -> Result<(Vec<DMatrix<f64>>, MotionInfo, String)> {
    let path = path.as_ref();
    let mut encoder = FrameEncoder::new(pca);
    let (info, sha256) = read_frames(path, |f| encoder.push(f))?;
    let coefficients = encoder.finish(&info.capture.template_sha256).map_err(|e| Error::file(path, e.to_string()))?;
    Ok((coefficients, info, sha256))
}

/// The aligned motion at `path` encoded with each of `models` in the one pass that reads it
/// ([`read_frames`] into a [`FrameEncoder::with_truncation`] per model): per model, the
/// coefficients of every frame (those of [`PcaModel::encode`], to the bit) and their truncation
/// residuals (those of [`PcaModel::truncation`]); the rest of the motion and the file's SHA-256.
/// Holds at most two encoder blocks of frames per model, never the motion. Fails, naming the
/// file, as [`read_encoded`] fails.
pub fn read_encoded_with_truncation(path: impl AsRef<Path>, models: &[&PcaModel]) -> Result<(Vec<EncodedFrames>, MotionInfo, String)> {
    let path = path.as_ref();
    let mut encoders: Vec<FrameEncoder> = models.iter().map(|m| FrameEncoder::with_truncation(m)).collect();
    let (info, sha256) = read_frames(path, |f| {
        if let Some((last, others)) = encoders.split_last_mut() {
            for e in others {
                e.push(f.clone())?;
            }
            last.push(f)?;
        }
        Ok(())
    })?;
    let encoded = encoders
        .into_iter()
        .map(|e| e.finish_with_truncation(&info.capture.template_sha256).map_err(|e| Error::file(path, e.to_string())))
        .collect::<Result<Vec<_>>>()?;
    Ok((encoded, info, sha256))
}

/// Aligned motion files as [`TrainingFrames`]: every pass reads them again with
/// [`read_frames`]. The first pass checks that each motion was aligned to `template_sha256`
/// (`pca-fit --template`) and records its hash and anchor; a later pass fails if a file's hash
/// changed.
pub struct MotionFiles<'a> {
    paths: &'a [PathBuf],
    template_sha256: String,
    /// The SHA-256 and anchor of every file read by the first pass.
    seen: Vec<(String, Vec<u32>)>,
}

impl<'a> MotionFiles<'a> {
    pub fn new(paths: &'a [PathBuf], template_sha256: &str) -> Self {
        MotionFiles { paths, template_sha256: template_sha256.to_string(), seen: Vec::new() }
    }
}

impl TrainingFrames for MotionFiles<'_> {
    fn pass(&mut self, sink: &mut dyn FnMut(usize, &[Vector3<f64>]) -> Result<()>) -> Result<()> {
        for (k, path) in self.paths.iter().enumerate() {
            // The sink's first error waits for the file's own checks: a motion aligned to another
            // template is reported as that, not as the frame size it then has.
            let mut sink_error: Option<Error> = None;
            let (info, sha256) = read_frames(path, |f| {
                if sink_error.is_none() {
                    sink_error = sink(k, &f).err();
                }
                Ok(())
            })?;
            if self.seen.get(k).is_none() {
                check_same_template(&info.capture.template_sha256, &self.template_sha256, "the motion was aligned to", "--template is")
                    .map_err(|e| Error::file(path, e.to_string()))?;
            }
            if let Some(e) = sink_error {
                return Err(Error::file(path, e.to_string()));
            }
            match self.seen.get(k) {
                None => {
                    self.seen.push((sha256, info.anchor));
                }
                Some((first, _)) if *first != sha256 => {
                    return Err(Error::file(path, "changed between two passes over the training frames"));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }

    fn anchors(&self) -> Vec<Vec<u32>> {
        self.seen.iter().map(|(_, a)| a.clone()).collect()
    }
}

/// The frames read so far: [`FrameChecks`], and the sink's first error.
#[derive(Default)]
struct StreamChecks {
    checks: FrameChecks,
    sink_error: Option<Error>,
}

impl StreamChecks {
    /// Checks the next frame and hands it to `sink` while every frame so far passed.
    fn take(&mut self, frame: Vec<Vector3<f64>>, sink: &mut dyn FnMut(Vec<Vector3<f64>>) -> Result<()>) {
        if self.checks.check(&frame) && self.sink_error.is_none() {
            if let Err(e) = sink(frame) {
                self.sink_error = Some(e);
            }
        }
    }
}

/// Everything of an [`AlignedMotion`] but its frames, in the order of its fields.
type Rest = (Vec<[u32; 3]>, Vec<RigidMotion>, Vec<[f64; 6]>, Vec<u32>, CaptureInfo);

/// Decodes an [`AlignedMotion`] as its derived `Deserialize` does, field by field, with the
/// frames going through [`StreamChecks::take`] instead of into a vector.
struct MotionSeed<'a> {
    frames: &'a mut StreamChecks,
    sink: &'a mut dyn FnMut(Vec<Vector3<f64>>) -> Result<()>,
}

/// The fields of [`AlignedMotion`] in declaration order (the order bincode stores them in).
const FIELDS: &[&str] = &["faces", "frames", "poses", "displacements", "anchor", "capture"];

impl<'de> DeserializeSeed<'de> for MotionSeed<'_> {
    type Value = Rest;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Rest, D::Error> {
        d.deserialize_struct("AlignedMotion", FIELDS, self)
    }
}

impl<'de> Visitor<'de> for MotionSeed<'_> {
    type Value = Rest;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("struct AlignedMotion")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Rest, A::Error> {
        let missing = |i: usize| A::Error::invalid_length(i, &"struct AlignedMotion with 6 elements");
        let faces = seq.next_element()?.ok_or_else(|| missing(0))?;
        seq.next_element_seed(FramesSeed { frames: self.frames, sink: self.sink })?.ok_or_else(|| missing(1))?;
        let poses = seq.next_element()?.ok_or_else(|| missing(2))?;
        let displacements = seq.next_element()?.ok_or_else(|| missing(3))?;
        let anchor = seq.next_element()?.ok_or_else(|| missing(4))?;
        let capture = seq.next_element()?.ok_or_else(|| missing(5))?;
        Ok((faces, poses, displacements, anchor, capture))
    }
}

/// The `frames` field: a sequence of frames, each decoded as a `Vec<Vector3<f64>>` (which
/// grows with the bytes actually read, whatever length the file claims) and handed on.
struct FramesSeed<'a> {
    frames: &'a mut StreamChecks,
    sink: &'a mut dyn FnMut(Vec<Vector3<f64>>) -> Result<()>,
}

impl<'de> DeserializeSeed<'de> for FramesSeed<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<(), D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for FramesSeed<'_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a sequence of frames")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<(), A::Error> {
        while let Some(frame) = seq.next_element::<Vec<Vector3<f64>>>()? {
            self.frames.take(frame, self.sink);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::artifact::{Header, InputRecord};

    fn motion(n_frames: usize, n: usize) -> AlignedMotion {
        let frames: Vec<Vec<Vector3<f64>>> = (0..n_frames)
            .map(|f| (0..n).map(|v| Vector3::new(v as f64, f as f64 * 0.5, (v * f) as f64 / 7.0)).collect())
            .collect();
        AlignedMotion {
            faces: vec![[0, 1, 2], [1, 2, 3]],
            poses: (0..n_frames).map(|_| RigidMotion::identity()).collect(),
            displacements: (0..n_frames).map(|f| [f as f64, 0.0, 0.0, 0.0, 0.1, 0.0]).collect(),
            anchor: vec![0, 3],
            capture: CaptureInfo { fps: 50.0, up: [0.0, 1.0, 0.0], template_sha256: "ab".repeat(32) },
            frames,
        }
    }

    fn save(dir: &Path, name: &str, m: &AlignedMotion) -> std::path::PathBuf {
        let path = dir.join(name);
        let header = Header { inputs: vec![InputRecord { path: "x".into(), sha256: "y".into() }], ..Header::new("align", "0") };
        m.save(&path, &header).unwrap();
        path
    }

    fn read_all(path: &Path) -> Result<(AlignedMotion, String)> {
        let mut frames = Vec::new();
        let (info, sha) = read_frames(path, |f| {
            frames.push(f);
            Ok(())
        })?;
        // Every field of the motion, so that a field added to it fails to compile here.
        let MotionInfo { faces, n_frames, n_vertices, poses, displacements, anchor, capture } = info;
        assert_eq!((n_frames, n_vertices), (frames.len(), frames[0].len()));
        Ok((AlignedMotion { faces, frames, poses, displacements, anchor, capture }, sha))
    }

    /// The frames and the rest read in one pass are the motion `load` reads, with the hash of
    /// the whole file.
    #[test]
    fn frames_and_rest_are_the_loaded_motion() {
        let dir = tempfile::tempdir().unwrap();
        let m = motion(9, 5);
        let path = save(dir.path(), "m.aligned", &m);
        let (back, sha) = read_all(&path).unwrap();
        assert_eq!(back, m);
        assert_eq!((back, sha), AlignedMotion::load_hashed(&path).unwrap());
    }

    /// A motion encoded as it is read has the coefficients `encode` gives on the loaded motion,
    /// bit for bit, and the file's hash.
    #[test]
    fn read_encoded_is_the_encoding_of_the_loaded_motion() {
        use crate::part_pca::{fit, whole_body, PartAlignment};
        let dir = tempfile::tempdir().unwrap();
        let mut m = motion(40, 6);
        m.faces = vec![[0, 1, 2], [2, 3, 4], [3, 4, 5]];
        for (f, frame) in m.frames.iter_mut().enumerate() {
            for (v, p) in frame.iter_mut().enumerate() {
                p.z += ((f * 7 + v * 3) as f64).sin();
            }
        }
        m.capture.template_sha256.clear();
        let path = save(dir.path(), "m.aligned", &m);
        let (model, _) = fit(&m.frames[0], &whole_body(6), &[&m], gp::pca::Components::Count(4), PartAlignment::Body).unwrap();
        let (coefficients, info, sha) = read_encoded(&path, &model).unwrap();
        let bits = |c: &[DMatrix<f64>]| c.iter().flat_map(|x| x.iter().map(|v| v.to_bits())).collect::<Vec<_>>();
        assert!(bits(&coefficients) == bits(&model.encode(&m).unwrap()), "coefficients differ");
        assert_eq!((info.n_frames, sha), (40, mesh_core::artifact::sha256_file(&path).unwrap()));
    }

    /// A motion encoded with two models as it is read has, per model, the coefficients of
    /// `encode` and the truncation residuals of `truncation` on the loaded motion, bit for bit,
    /// whether the motion is shorter than an encoder block or several blocks long.
    #[test]
    fn read_encoded_with_truncation_is_that_of_the_loaded_motion() {
        use crate::part_pca::{fit, whole_body, PartAlignment};
        let dir = tempfile::tempdir().unwrap();
        for frames in [9, 700] {
            let mut m = motion(frames, 6);
            m.faces = vec![[0, 1, 2], [2, 3, 4], [3, 4, 5]];
            for (f, frame) in m.frames.iter_mut().enumerate() {
                for (v, p) in frame.iter_mut().enumerate() {
                    p.z += ((f * 7 + v * 3) as f64).sin();
                    p.x += 0.3 * ((f * 5 + v) as f64).cos();
                }
            }
            m.capture.template_sha256.clear();
            let path = save(dir.path(), "m.aligned", &m);
            let fitted = |k: usize| fit(&m.frames[0], &whole_body(6), &[&m], gp::pca::Components::Count(k), PartAlignment::Body).unwrap().0;
            let (a, b) = (fitted(2), fitted(7));
            let (encoded, info, _) = read_encoded_with_truncation(&path, &[&a, &b]).unwrap();
            assert_eq!((encoded.len(), info.n_frames), (2, frames));
            let bits = |c: &[DMatrix<f64>]| c.iter().flat_map(|x| x.iter().map(|v| v.to_bits())).collect::<Vec<_>>();
            for (e, model) in encoded.iter().zip([&a, &b]) {
                let rows = model.part_rows(&m).unwrap();
                let coefficients = model.encode_rows(&rows).unwrap();
                let truncation = model.truncation(&rows, &coefficients).unwrap();
                assert!(bits(&e.coefficients) == bits(&coefficients), "coefficients differ at {frames} frames");
                let flat = |t: &[Vec<f64>]| t.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert!(flat(&e.truncation) == flat(&truncation), "truncation residuals differ at {frames} frames");
                assert_eq!(e.truncation[0].len(), frames);
            }
            // Two components of a noisy 6-vertex body leave a residual; seven represent it exactly.
            assert!(encoded[0].truncation[0].iter().all(|&r| r > 1e-6), "{:?}", &encoded[0].truncation[0][..3]);
        }
    }

    /// A motion `validate` refuses is refused with the same message, and its bad frames never
    /// reach the sink; a corrupt file is a checksum mismatch, a sink's error names the file.
    #[test]
    fn invalid_motions_fail_as_load_fails() {
        let dir = tempfile::tempdir().unwrap();
        let mut short = motion(6, 5);
        short.frames[3].pop();
        let mut nan = motion(6, 5);
        nan.frames[2][1].y = f64::NAN;
        let mut both = motion(6, 5);
        both.frames[1][0].x = f64::INFINITY;
        both.frames[4].push(Vector3::zeros());
        let mut poses = motion(6, 5);
        poses.poses.pop();
        let mut up = motion(6, 5);
        up.capture.up = [0.0, 2.0, 0.0];
        let mut face = motion(6, 5);
        face.faces.push([0, 1, 5]);
        let mut empty = motion(0, 5);
        empty.frames.clear();
        for (name, m) in [("short", short), ("nan", nan), ("both", both), ("poses", poses), ("up", up), ("face", face), ("empty", empty)] {
            let path = save(dir.path(), name, &m);
            let mut seen = 0;
            let err = read_frames(&path, |f| {
                assert!(f.len() == 5 && f.iter().all(|v| v.iter().all(|c| c.is_finite())), "{name}: a bad frame reached the sink");
                seen += 1;
                Ok(())
            })
            .unwrap_err()
            .to_string();
            assert_eq!(err, AlignedMotion::load(&path).unwrap_err().to_string(), "{name}");
        }
        let path = save(dir.path(), "good", &motion(6, 5));
        let mut bytes = std::fs::read(&path).unwrap();
        let mid = bytes.len() / 2;
        bytes[mid] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        let err = read_frames(&path, |_| Ok(())).unwrap_err().to_string();
        assert!(err.ends_with("checksum mismatch (file corrupt)"), "{err}");
        let path = save(dir.path(), "good", &motion(6, 5));
        let mut calls = 0;
        let err = read_frames(&path, |_| {
            calls += 1;
            Err(Error::invalid(format!("refused frame {}", calls - 1)))
        })
        .unwrap_err()
        .to_string();
        assert_eq!(err, format!("{}: refused frame 0", path.display()));
        assert_eq!(calls, 1, "no frame after the sink's error");
    }
}

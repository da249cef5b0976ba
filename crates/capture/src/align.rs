//! `align`: rigid alignment of every frame of a motion to the subject's
//! template, and the per-frame rigid displacement (transfer paper §4,
//! "Rigid Transformation").
//!
//! For frame `i` with vertices `V_i`, orthogonal Procrustes gives the pose
//! `P_i = (R_i, t_i)` minimising `Σ |R_i T + t_i - V_i|²` over the template
//! `T`. The aligned frame is `P_i⁻¹ V_i` (the body brought back to the
//! template's position and heading). The displacement of frame `i` is the
//! motion of the body's *root* from the previous frame, expressed in the
//! previous frame's body coordinates: with the root pose `Q_i = P_i ∘ T(c)`
//! (`c` the template's root point, [`root_point`]), `D_i = Q_{i-1}⁻¹ Q_i`. It
//! does not depend on heading nor on where the template stands (a turn on the
//! spot is a pure rotation); it is stored as the 6-vector
//! `(t_x, t_y, t_z, h_1, h_2, h_3)` with `h = log R`. `D_0` is the identity:
//! every motion starts where its first frame stands, and `P_0` records where
//! that is.
//!
//! Which vertices the Procrustes fit uses is the *alignment frame*
//! ([`AlignFrame`]): the paper's reading fits the whole body; `root` fits only
//! the root part's core (the torso without the overlap bands it shares with
//! the limbs), so a raised leg or a punch does not tilt the frame every part is
//! expressed in. In the paper's 5-part tree (a torso and four limbs) the root
//! frame is also the hierarchical one: each limb in its parent's frame.

use mesh_core::artifact::Artifact;
use mesh_core::rigid::{procrustes, relative_in_body_frame, RigidMotion};
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result, TriMesh};
use nalgebra::{Vector3, Vector6};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which vertices define a frame's rigid pose (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum AlignFrame {
    /// The root part's core: the root without the bands it shares with its children.
    #[default]
    Root,
    /// Every vertex (the paper's Procrustes analysis of the whole mesh).
    Body,
}

/// The root part's core: its vertices in no child part (the torso without the bands it shares
/// with the limbs), of a template of `n_vertices`.
pub fn root_core<'a>(root: &[u32], children: impl IntoIterator<Item = &'a [u32]>, n_vertices: usize) -> Vec<u32> {
    let mut in_child = vec![false; n_vertices];
    for &v in children.into_iter().flatten() {
        if let Some(c) = in_child.get_mut(v as usize) {
            *c = true;
        }
    }
    root.iter().copied().filter(|&v| !in_child.get(v as usize).copied().unwrap_or(true)).collect()
}

/// The template vertices `frame` aligns on (sorted; empty means every vertex).
/// `Root` needs the subject's segmentation.
pub fn anchor_vertices(frame: AlignFrame, parts: Option<&Segmentation>) -> Result<Vec<u32>> {
    match frame {
        AlignFrame::Body => Ok(Vec::new()),
        AlignFrame::Root => {
            let parts = parts.ok_or_else(|| {
                Error::invalid("the root alignment frame needs the subject's segmentation")
            })?;
            let root = parts
                .parts
                .iter()
                .find(|p| p.parent.is_none())
                .ok_or_else(|| Error::invalid("the segmentation has no root part"))?;
            let children = parts.parts.iter().filter(|p| p.parent.is_some()).map(|p| p.vertices.as_slice());
            let core = root_core(&root.vertices, children, parts.n_vertices);
            if core.len() < 3 {
                return Err(Error::invalid(format!(
                    "root part '{}' keeps {} vertices outside its children's bands (need 3 to align on)",
                    root.name,
                    core.len()
                )));
            }
            Ok(core)
        }
    }
}

/// The root point of a template: the centroid of its `anchor` vertices (of every
/// vertex when `anchor` is empty). Displacements are motions of this point.
pub fn root_point(template: &[Vector3<f64>], anchor: &[u32]) -> Vector3<f64> {
    let (sum, n) = if anchor.is_empty() {
        (template.iter().sum::<Vector3<f64>>(), template.len())
    } else {
        (
            anchor.iter().filter_map(|&v| template.get(v as usize)).sum(),
            anchor.len(),
        )
    };
    if n == 0 {
        Vector3::zeros()
    } else {
        sum / n as f64
    }
}

/// Root poses `Q_i = P_i ∘ T(c)` of template poses `P_i`: where the root point `c`
/// is and how the body is turned.
pub fn root_poses(poses: &[RigidMotion], root: &Vector3<f64>) -> Vec<RigidMotion> {
    let to_root = RigidMotion::new(nalgebra::Rotation3::identity(), *root);
    poses.iter().map(|p| p.compose(&to_root)).collect()
}

/// The rigid motion taking `src` onto `dst` fitted on the `anchor` vertices
/// only (every vertex when `anchor` is empty): Procrustes, as [`procrustes`].
pub fn fit_on(src: &[Vector3<f64>], dst: &[Vector3<f64>], anchor: &[u32]) -> RigidMotion {
    if anchor.is_empty() {
        return procrustes(src, dst, None);
    }
    let pick = |x: &[Vector3<f64>]| -> Vec<Vector3<f64>> {
        anchor.iter().map(|&v| x[v as usize]).collect()
    };
    procrustes(&pick(src), &pick(dst), None)
}

/// What the stages after `align` need to know about the capture a motion came from, so
/// that no frame rate or axis travels through their command lines.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaptureInfo {
    /// Frames per second of the subject's captures (`subject.json` `fps`); 0 when the motion
    /// was aligned in memory without one ([`align_motion_on`]).
    pub fps: f64,
    /// Unit up axis of the capture's world (`subject.json` `up`).
    pub up: [f64; 3],
    /// SHA-256 (hex) of the template file the frames were aligned to; empty when aligned in
    /// memory.
    pub template_sha256: String,
}

impl Default for CaptureInfo {
    /// Unknown frame rate and template, `+y` up.
    fn default() -> Self {
        CaptureInfo { fps: 0.0, up: [0.0, 1.0, 0.0], template_sha256: String::new() }
    }
}

impl CaptureInfo {
    /// The frame rate, or an error naming `align --subject` when the motion carries none.
    pub fn require_fps(&self) -> Result<f64> {
        if self.fps > 0.0 {
            Ok(self.fps)
        } else {
            Err(Error::invalid("the aligned motion has no frame rate (aligned without `align --subject`)"))
        }
    }
}

/// A motion after alignment: the aligned frames, each frame's world pose and
/// its displacement from the previous frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AlignedMotion {
    /// Faces shared by every frame (the subject's topology).
    pub faces: Vec<[u32; 3]>,
    /// Aligned vertex positions, one vector per frame.
    pub frames: Vec<Vec<Vector3<f64>>>,
    /// World pose `P_i` of each frame: `world = P_i(aligned)`.
    pub poses: Vec<RigidMotion>,
    /// Displacements `D_i = P_{i-1}⁻¹ P_i` as 6-vectors (`D_0 = 0`).
    pub displacements: Vec<[f64; 6]>,
    /// Template vertices the poses were fitted on ([`anchor_vertices`]; empty: all).
    pub anchor: Vec<u32>,
    /// Frame rate, up axis and template of the capture.
    pub capture: CaptureInfo,
}

impl Artifact for AlignedMotion {
    const KIND: &'static str = "aligned-motion";
    const VERSION: u32 = 3;

    /// At least one frame, every frame with the same vertex count and finite
    /// coordinates, faces and anchor below it, one pose and one displacement
    /// per frame, a finite non-negative frame rate and a unit up axis.
    fn validate(&self) -> std::result::Result<(), String> {
        let mut checks = FrameChecks::default();
        for frame in &self.frames {
            checks.check(frame);
        }
        let n = checks.verdict()?;
        check_besides_frames(n, self.frames.len(), &self.faces, &self.anchor, self.poses.len(), self.displacements.len(), &self.capture)
    }
}

/// The checks of [`AlignedMotion::validate`] on the frames' vertices, a frame at a time (so that
/// [`crate::motion_stream`] checks frames as it decodes them): every frame has frame 0's vertex
/// count and finite coordinates.
#[derive(Default)]
pub(crate) struct FrameChecks {
    pub(crate) n_frames: usize,
    /// Frame 0's vertex count.
    n_vertices: Option<usize>,
    /// The first frame with another vertex count than frame 0, and its count.
    wrong_count: Option<(usize, usize)>,
    /// The first frame with a non-finite coordinate.
    non_finite: Option<usize>,
}

impl FrameChecks {
    /// Checks the next frame; true while every frame so far passed.
    pub(crate) fn check(&mut self, frame: &[Vector3<f64>]) -> bool {
        let i = self.n_frames;
        self.n_frames += 1;
        let n = *self.n_vertices.get_or_insert(frame.len());
        if frame.len() != n {
            self.wrong_count.get_or_insert((i, frame.len()));
        }
        if !frame.iter().all(|v| v.iter().all(|c| c.is_finite())) {
            self.non_finite.get_or_insert(i);
        }
        self.wrong_count.is_none() && self.non_finite.is_none()
    }

    /// The vertex count of the frames checked, or their first problem (no frames; a vertex
    /// count other than frame 0's, before a non-finite coordinate).
    pub(crate) fn verdict(&self) -> std::result::Result<usize, String> {
        let Some(n) = self.n_vertices else {
            return Err("no frames".into());
        };
        if let Some((i, len)) = self.wrong_count {
            return Err(format!("frame {i} has {len} vertices, frame 0 has {n}"));
        }
        if let Some(i) = self.non_finite {
            return Err(format!("frame {i} has a non-finite coordinate"));
        }
        Ok(n)
    }
}

/// The checks of [`AlignedMotion::validate`] on everything but the frames' vertices, for a
/// motion of `n_frames` frames of `n` vertices each.
pub(crate) fn check_besides_frames(
    n: usize,
    n_frames: usize,
    faces: &[[u32; 3]],
    anchor: &[u32],
    n_poses: usize,
    n_displacements: usize,
    c: &CaptureInfo,
) -> std::result::Result<(), String> {
    mesh_core::artifact::check_indices(faces.iter().flatten().copied(), n, || "the face list".into())?;
    mesh_core::artifact::check_indices(anchor.iter().copied(), n, || "the anchor".into())?;
    if n_poses != n_frames || n_displacements != n_frames {
        return Err(format!("{n_frames} frames but {n_poses} poses and {n_displacements} displacements"));
    }
    if c.fps != 0.0 {
        mesh_core::frame_rate::check_fps(c.fps)?;
    }
    let up = Vector3::from(c.up);
    if !up.iter().all(|x| x.is_finite()) || (up.norm() - 1.0).abs() > 1e-9 {
        return Err(format!("up axis {:?} is not a unit vector", c.up));
    }
    Ok(())
}

impl AlignedMotion {
    pub fn n_frames(&self) -> usize {
        self.frames.len()
    }

    /// The frames back in world coordinates (inverse of alignment).
    pub fn world_frames(&self) -> Vec<Vec<Vector3<f64>>> {
        self.frames.iter().zip(&self.poses).map(|(f, p)| p.apply_all(f)).collect()
    }
}

/// Aligns every frame of `motion` to `template` on the whole body (same topology required).
pub fn align_motion(template: &TriMesh, motion: &MeshSequence) -> Result<AlignedMotion> {
    align_motion_on(template, motion, &[])
}

/// Aligns every frame of `motion` to `template`, fitting each pose on the
/// `anchor` vertices ([`anchor_vertices`]; empty: every vertex).
pub fn align_motion_on(
    template: &TriMesh,
    motion: &MeshSequence,
    anchor: &[u32],
) -> Result<AlignedMotion> {
    check_anchor(template, anchor)?;
    check_topology(template, motion.n_vertices(), &motion.faces)?;
    if motion.n_frames() == 0 {
        return Err(Error::invalid("motion has no frames"));
    }
    let (poses, frames): (Vec<RigidMotion>, Vec<Vec<Vector3<f64>>>) = motion
        .frames
        .par_iter()
        .map(|frame| align_frame(template, frame, anchor))
        .unzip();
    let displacements = displacements(template, anchor, &poses);
    Ok(AlignedMotion {
        faces: motion.faces.clone(),
        frames,
        poses,
        displacements,
        anchor: anchor.to_vec(),
        capture: CaptureInfo::default(),
    })
}

/// Fails unless every `anchor` vertex is a vertex of `template`.
pub fn check_anchor(template: &TriMesh, anchor: &[u32]) -> Result<()> {
    match anchor.iter().find(|&&v| v as usize >= template.n_vertices()) {
        Some(&v) => Err(Error::invalid(format!(
            "alignment vertex {v} is beyond the template's {} vertices",
            template.n_vertices()
        ))),
        None => Ok(()),
    }
}

/// Fails unless a motion of `n_vertices` vertices and `faces` has `template`'s topology.
pub fn check_topology(template: &TriMesh, n_vertices: usize, faces: &[[u32; 3]]) -> Result<()> {
    if n_vertices != template.n_vertices() || faces != template.faces.as_slice() {
        return Err(Error::invalid(format!(
            "motion has {} vertices and {} faces but the template has {} and {}: not the same topology",
            n_vertices,
            faces.len(),
            template.n_vertices(),
            template.n_faces()
        )));
    }
    Ok(())
}

/// One frame aligned: its world pose `P` fitted on the `anchor` vertices, and the frame
/// brought back to the template, `P⁻¹ V`. A frame's alignment depends on no other frame.
pub fn align_frame(template: &TriMesh, frame: &[Vector3<f64>], anchor: &[u32]) -> (RigidMotion, Vec<Vector3<f64>>) {
    let pose = fit_on(&template.vertices, frame, anchor);
    let aligned = pose.inverse().apply_all(frame);
    (pose, aligned)
}

/// The displacements `D_i` of frames with world poses `poses` (`D_0 = 0`; see the module
/// documentation): motions of the root point of `template`'s `anchor` vertices.
pub fn displacements(template: &TriMesh, anchor: &[u32], poses: &[RigidMotion]) -> Vec<[f64; 6]> {
    let roots = root_poses(poses, &root_point(&template.vertices, anchor));
    let mut displacements = vec![[0.0; 6]];
    for w in roots.windows(2) {
        let d: Vector6<f64> = relative_in_body_frame(&w[0], &w[1]).to_6vec();
        displacements.push(d.into());
    }
    displacements.truncate(poses.len());
    displacements
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::rigid::{integrate, so3_exp};
    use mesh_core::shapes;

    /// A rigidly moving, slightly bending cylinder: alignment must bring every
    /// frame back onto the template and the displacements must integrate back
    /// to the true poses.
    #[test]
    fn recovers_known_poses_and_displacements() {
        let template = shapes::cylinder(12, 16, 0.1, 1.0);
        let mut truth = Vec::new();
        let mut frames = Vec::new();
        for i in 0..8 {
            let s = i as f64;
            let pose = RigidMotion::new(
                so3_exp(&Vector3::new(0.05 * s, 0.3 * s, -0.02 * s)),
                Vector3::new(0.1 * s, 0.01 * s * s, -0.2 * s),
            );
            frames.push(pose.apply_all(&template.vertices));
            truth.push(pose);
        }
        let seq = MeshSequence::new(template.faces.clone(), frames);
        let aligned = align_motion(&template, &seq).unwrap();
        for f in &aligned.frames {
            for (a, b) in f.iter().zip(&template.vertices) {
                assert!((a - b).norm() < 1e-9);
            }
        }
        let steps: Vec<RigidMotion> = aligned.displacements[1..]
            .iter()
            .map(|d| RigidMotion::from_6vec(&Vector6::from_column_slice(d)))
            .collect();
        // Displacements move the root point: integrate root poses, then shift back.
        let root = root_point(&template.vertices, &[]);
        let q0 = root_poses(&aligned.poses[..1], &root)[0];
        let back = RigidMotion::new(nalgebra::Rotation3::identity(), -root);
        let integrated: Vec<RigidMotion> =
            integrate(&q0, &steps).iter().map(|q| q.compose(&back)).collect();
        for (a, b) in integrated.iter().zip(&truth) {
            assert!((a.translation - b.translation).norm() < 1e-9);
            assert!((a.rotation.matrix() - b.rotation.matrix()).norm() < 1e-9);
        }
        // A pure heading change applied to the whole motion leaves the
        // displacements unchanged (they are expressed in body coordinates).
        let heading = RigidMotion::new(so3_exp(&Vector3::new(0.0, 1.2, 0.0)), Vector3::new(3.0, 0.0, 1.0));
        let turned = MeshSequence::new(
            template.faces.clone(),
            seq.frames.iter().map(|f| heading.apply_all(f)).collect(),
        );
        let aligned2 = align_motion(&template, &turned).unwrap();
        for (a, b) in aligned.displacements.iter().zip(&aligned2.displacements) {
            for k in 0..6 {
                assert!((a[k] - b[k]).abs() < 1e-9, "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn rejects_other_topology() {
        let template = shapes::cylinder(12, 16, 0.1, 1.0);
        let other = shapes::cylinder(10, 16, 0.1, 1.0);
        let seq = MeshSequence::new(other.faces.clone(), vec![other.vertices.clone()]);
        let err = align_motion(&template, &seq).unwrap_err().to_string();
        assert!(err.contains("not the same topology"), "{err}");
    }
}

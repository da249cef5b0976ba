//! From decoded target part meshes to one target mesh (transfer paper §6):
//! [`Surface::Assemble`] (overlaps averaged, `capture::assemble`),
//! [`Surface::Correct`] (§6.1 body part correction with the `M` nearest
//! training part meshes, then the same assembly) and
//! [`Surface::CorrectStitch`] (§6.2: correction, then the `surface` crate's
//! optimal-loop Poisson stitching; children are re-aligned on their band only
//! for `PartAlignment::Part`). The result is rigidly aligned to the
//! template, as `assemble` does, so that the predicted world poses apply.
//!
//! The training part meshes of the correction are the target's training
//! frames cut into parts exactly as PCA sees them ([`PcaModel::part_rows`]),
//! so prediction and training meshes share one frame.

use mesh_core::cli::ProgressBar;
use mesh_core::segmentation::Segmentation;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use rayon::prelude::*;
use surface::correct::Corrector;
use surface::stitch::Stitcher;

use std::path::PathBuf;
use std::time::Instant;

use capture::align::AlignedMotion;
use capture::assemble::{assemble, plan, AssemblyPlan};
use capture::motion_stream::read_frames;
use capture::part_pca::{check_same_template, PartAlignment, PcaModel};

/// Which surface reconstruction follows the PCA decoding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Surface {
    /// Overlaps averaged (no §6).
    #[default]
    Assemble,
    /// §6.1 correction, then averaging.
    Correct,
    /// §6.1 correction, then §6.2 stitching.
    CorrectStitch,
    /// §6.2 stitching of the uncorrected parts (diagnostic).
    Stitch,
}

/// Rows `F x 3n` -> one vertex list per frame.
pub fn rows_to_meshes(rows: &DMatrix<f64>) -> Vec<Vec<Vector3<f64>>> {
    let n = rows.ncols() / 3;
    rows.row_iter()
        .map(|r| {
            (0..n)
                .map(|i| Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]))
                .collect()
        })
        .collect()
}

/// Everything needed to rebuild target meshes from decoded parts.
pub struct Reconstructor {
    plan: AssemblyPlan,
    /// Per PCA part (correction only).
    correctors: Vec<Corrector>,
    neighbours: usize,
    /// Stitcher and the PCA part index of each of its parts (tree order).
    stitcher: Option<(Stitcher, Vec<usize>)>,
    /// Further stitchers, one per extra thread ([`Stitcher::fork`]).
    forks: Vec<Stitcher>,
    /// Counts corrected parts and stitched frames (hidden unless set).
    progress: ProgressBar,
    unstitched_frames: usize,
    /// Also merge the corrected parts by averaging ([`Reconstructor::with_corrected_assembly`]).
    corrected_assembly: bool,
    timing: SurfaceTiming,
}

/// Wall-clock seconds of the surface steps of every [`Reconstructor::reconstruct`] so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SurfaceTiming {
    /// Frames reconstructed.
    pub frames: usize,
    /// §6.1: the nearest training meshes of every part of every frame.
    pub nearest_s: f64,
    /// §6.1: the corrections themselves (factorisations of the training meshes made on first
    /// use included).
    pub correct_s: f64,
    /// §6.2 stitching, or the averaging merge.
    pub merge_s: f64,
}

/// Every `stride`-th frame of the target's aligned training motions at `paths`, cut into `pca`'s
/// parts: `[part][mesh]`, the training part meshes [`Reconstructor::new`] cuts from loaded
/// motions, read a frame at a time so that no motion is held whole. With [`Stride::Within`] the
/// stride is the smallest power of two whose meshes fit in the given bytes (1 when all fit; at
/// least each motion's first frame is kept): the stride doubles, dropping every other mesh kept,
/// each time they would exceed it. Returns the
/// meshes and the stride. Fails, naming the file, as [`PcaModel::check_motion`] fails on a motion
/// of another vertex count or template.
pub fn training_part_meshes(
    pca: &PcaModel,
    paths: &[PathBuf],
    stride: Stride,
) -> Result<(Vec<Vec<Vec<Vector3<f64>>>>, usize)> {
    let (mut stride, budget) = match stride {
        Stride::Every(s) => (s.max(1), usize::MAX),
        Stride::Within(bytes) => (1, bytes),
    };
    let frame_bytes: usize = pca.parts.iter().map(|p| p.vertices.len() * 24).sum();
    // Each kept mesh's frame index within its motion, to thin them when the stride doubles.
    let mut index: Vec<usize> = Vec::new();
    let mut per_part: Vec<Vec<Vec<Vector3<f64>>>> = vec![Vec::new(); pca.parts.len()];
    for path in paths {
        let mut i = 0usize;
        let (info, _) = read_frames(path, |frame| {
            if frame.len() != pca.n_vertices {
                return Err(Error::invalid(format!(
                    "the motion's frame {i} has {} vertices but the PCA model was fitted on {}: \
                     the motion and the model belong to different subjects or templates",
                    frame.len(),
                    pca.n_vertices
                )));
            }
            if i % stride == 0 {
                for (meshes, part) in per_part.iter_mut().zip(pca.frame_parts(&frame)?) {
                    meshes.push(part);
                }
                index.push(i);
                while index.len().saturating_mul(frame_bytes) > budget
                    && index.iter().any(|&j| j % (2 * stride) != 0)
                {
                    stride *= 2;
                    let keep: Vec<bool> = index.iter().map(|&j| j % stride == 0).collect();
                    for meshes in per_part.iter_mut() {
                        let mut k = keep.iter();
                        meshes.retain(|_| *k.next().unwrap_or(&false));
                    }
                    index.retain(|&j| j % stride == 0);
                }
            }
            i += 1;
            Ok(())
        })?;
        check_same_template(&info.capture.template_sha256, &pca.template_sha256, "the motion was aligned to", "the PCA model was fitted on")
            .map_err(|e| Error::file(path, e.to_string()))?;
    }
    Ok((per_part, stride))
}

/// Which training frames the correction uses (`training_part_meshes`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stride {
    /// Every n-th frame of each motion.
    Every(usize),
    /// Every 2^k-th frame, k the smallest whose part meshes fit in this many bytes.
    Within(usize),
}

impl Reconstructor {
    /// `training`: the target's aligned training motions (used by the correction, every
    /// `stride`-th frame); `seg` and `faces`: the target's segmentation and template faces.
    pub fn new(
        pca: &PcaModel,
        seg: &Segmentation,
        faces: &[[u32; 3]],
        training: &[&AlignedMotion],
        surface: Surface,
        neighbours: usize,
        stride: usize,
    ) -> Result<Self> {
        let mut per_part: Vec<Vec<Vec<Vector3<f64>>>> = vec![Vec::new(); pca.parts.len()];
        if matches!(surface, Surface::Correct | Surface::CorrectStitch) {
            for m in training {
                for (k, rows) in pca.part_rows(m)?.iter().enumerate() {
                    per_part[k].extend(rows_to_meshes(rows).into_iter().step_by(stride.max(1)));
                }
            }
        }
        Self::with_training_meshes(pca, seg, faces, per_part, surface, neighbours)
    }

    /// [`Reconstructor::new`] with the correction's training part meshes given: `[part][mesh]`,
    /// as [`training_part_meshes`] reads them.
    pub fn with_training_meshes(
        pca: &PcaModel,
        seg: &Segmentation,
        faces: &[[u32; 3]],
        training: Vec<Vec<Vec<Vector3<f64>>>>,
        surface: Surface,
        neighbours: usize,
    ) -> Result<Self> {
        let plan = plan(pca)?;
        if seg.parts.len() != pca.parts.len()
            || seg
                .parts
                .iter()
                .zip(&pca.parts)
                .any(|(s, p)| s.name != p.name || s.vertices != p.vertices)
        {
            return Err(Error::invalid(
                "the segmentation's parts differ from the PCA model's",
            ));
        }
        let correct = matches!(surface, Surface::Correct | Surface::CorrectStitch);
        let correctors = if correct {
            if training.iter().all(Vec::is_empty) {
                return Err(Error::invalid(
                    "correction needs the target's training motions",
                ));
            }
            training
                .into_iter()
                .zip(&seg.parts)
                .map(|(t, p)| Corrector::new(p.faces.clone(), t))
                .collect::<Result<_>>()?
        } else {
            Vec::new()
        };
        let stitcher = if matches!(surface, Surface::CorrectStitch | Surface::Stitch) {
            let order = seg.tree_order()?;
            // Parts cut from whole-body-aligned frames are already in one frame: re-aligning
            // children on their narrow band would only add orientation error.
            let layout = surface::segmentation::part_layout(seg, faces.to_vec())?;
            Some((
                Stitcher::new(layout).with_band_alignment(pca.alignment == PartAlignment::Part),
                order,
            ))
        } else {
            None
        };
        Ok(Reconstructor {
            plan,
            correctors,
            neighbours,
            stitcher,
            forks: Vec::new(),
            progress: ProgressBar::hidden(),
            unstitched_frames: 0,
            corrected_assembly: false,
            timing: SurfaceTiming::default(),
        })
    }

    /// Shows the work of [`Reconstructor::reconstruct`] on `bar`: one step per corrected part
    /// of a frame and per stitched frame, the bar's length growing with each call (cleared by
    /// [`Reconstructor::finish`]).
    pub fn with_progress(mut self, bar: ProgressBar) -> Self {
        self.progress = bar;
        self
    }

    /// Bounds the bytes of the correction's cached factorisations (shared among the parts by
    /// their vertex counts); the results do not depend on it ([`Corrector::set_cache_limit`]).
    pub fn with_correction_cache(mut self, bytes: usize) -> Self {
        let total: usize = self.correctors.iter().map(Corrector::n_vertices).sum();
        for c in &mut self.correctors {
            let share = bytes as f64 * c.n_vertices() as f64 / total.max(1) as f64;
            c.set_cache_limit(share as usize);
        }
        self
    }

    /// How many training meshes the correction has factorised so far (rebuilds included).
    pub fn factorisations(&self) -> usize {
        self.correctors.iter().map(Corrector::factorisations).sum()
    }

    /// With `yes` and [`Surface::CorrectStitch`], [`Reconstructor::reconstruct_both`] also
    /// merges the corrected parts by averaging, which is what [`Surface::Correct`] gives: both
    /// outputs from one correction.
    pub fn with_corrected_assembly(mut self, yes: bool) -> Self {
        self.corrected_assembly = yes;
        self
    }

    /// §6.1 on every part of every frame: `decoded[part][frame]` in, same shape out. The
    /// nearest training meshes of a part's frames are found together
    /// ([`Corrector::nearest_all`]).
    pub fn correct(
        &self,
        decoded: &[Vec<Vec<Vector3<f64>>>],
    ) -> Result<Vec<Vec<Vec<Vector3<f64>>>>> {
        Ok(self.correct_timed(decoded)?.0)
    }

    /// [`Reconstructor::correct`] and the seconds its nearest-mesh searches took.
    fn correct_timed(
        &self,
        decoded: &[Vec<Vec<Vector3<f64>>>],
    ) -> Result<(Vec<Vec<Vec<Vector3<f64>>>>, f64)> {
        if self.correctors.is_empty() {
            return Ok((decoded.to_vec(), 0.0));
        }
        let mut nearest_s = 0.0;
        let corrected = decoded
            .iter()
            .zip(&self.correctors)
            .map(|(frames, c)| {
                for p in frames {
                    surface::check_vertices(p, c.n_vertices(), "correct: prediction")?;
                }
                let t = Instant::now();
                let near = c.nearest_all(frames, self.neighbours);
                nearest_s += t.elapsed().as_secs_f64();
                frames
                    .par_iter()
                    .zip(near.par_iter())
                    .map(|(p, near)| {
                        let r = c.correct_with(p, near);
                        self.progress.inc(1);
                        r
                    })
                    .collect()
            })
            .collect::<Result<_>>()?;
        Ok((corrected, nearest_s))
    }

    /// Seconds of the surface steps of every reconstruction so far.
    pub fn timing(&self) -> SurfaceTiming {
        self.timing
    }

    /// One mesh per frame from `decoded[part][frame]` (after [`Reconstructor::correct`]).
    pub fn merge(
        &mut self,
        pca: &PcaModel,
        parts: &[Vec<Vec<Vector3<f64>>>],
    ) -> Result<Vec<Vec<Vector3<f64>>>> {
        let Some((stitcher, order)) = &mut self.stitcher else {
            return Ok(assemble(&self.plan, pca, parts));
        };
        let n_frames = parts.first().map_or(0, |p| p.len());
        // Contiguous runs of frames stitched side by side, one stitcher (factorisation) per
        // thread: each frame's result does not depend on which stitcher made it.
        let workers = rayon::current_num_threads().clamp(1, n_frames.max(1));
        while self.forks.len() + 1 < workers {
            self.forks.push(stitcher.fork());
        }
        let run = n_frames.div_ceil(workers).max(1);
        let (plan, progress, order) = (&self.plan, &self.progress, &*order);
        let mut stitchers: Vec<&mut Stitcher> =
            std::iter::once(stitcher).chain(self.forks.iter_mut()).take(workers).collect();
        let stitched: Vec<Vec<Result<Vec<Vector3<f64>>>>> = stitchers
            .par_iter_mut()
            .enumerate()
            .map(|(w, stitcher)| {
                (w * run..((w + 1) * run).min(n_frames))
                    .map(|f| {
                        let frame: Vec<Vec<Vector3<f64>>> =
                            order.iter().map(|&k| parts[k][f].clone()).collect();
                        progress.inc(1);
                        stitcher.stitch(&frame).map(|s| plan.to_template_frame(&s.vertices))
                    })
                    .collect()
            })
            .collect();
        let (mut unstitched, before) = (0, self.timing.frames);
        let merged = stitched
            .into_iter()
            .flatten()
            .enumerate()
            .map(|(f, frame)| match frame {
                Ok(frame) => frame,
                Err(e) => {
                    if unstitched == 0 && self.unstitched_frames == 0 {
                        let f = before + f;
                        mesh_core::warn!("stitch: frame {f}: {e}: such frames are assembled (overlaps averaged)");
                    }
                    unstitched += 1;
                    let one: Vec<Vec<Vec<Vector3<f64>>>> = parts.iter().map(|p| vec![p[f].clone()]).collect();
                    assemble(plan, pca, &one).swap_remove(0)
                }
            })
            .collect();
        self.unstitched_frames += unstitched;
        Ok(merged)
    }

    /// Ends the work of the calls so far: clears the progress bar and says how many frames
    /// could not be stitched, if any.
    pub fn finish(&self) {
        self.progress.finish_and_clear();
        if self.unstitched_frames > 0 {
            mesh_core::warn!(
                "stitch: {} of {} frames assembled instead of stitched",
                self.unstitched_frames,
                self.timing.frames
            );
        }
    }

    /// Frames [`Reconstructor::merge`] could not stitch (a part's overlap band that is not one
    /// ring, as on meshes modelled as separate pieces) and assembled instead.
    pub fn unstitched_frames(&self) -> usize {
        self.unstitched_frames
    }

    /// [`Reconstructor::correct`] then [`Reconstructor::merge`].
    pub fn reconstruct(
        &mut self,
        pca: &PcaModel,
        decoded: &[Vec<Vec<Vector3<f64>>>],
    ) -> Result<Vec<Vec<Vector3<f64>>>> {
        Ok(self.reconstruct_both(pca, decoded)?.0)
    }

    /// [`Reconstructor::reconstruct`], and with [`Reconstructor::with_corrected_assembly`] on a
    /// corrected and stitched reconstruction also the corrected parts merged by averaging.
    #[allow(clippy::type_complexity)]
    pub fn reconstruct_both(
        &mut self,
        pca: &PcaModel,
        decoded: &[Vec<Vec<Vector3<f64>>>],
    ) -> Result<(Vec<Vec<Vector3<f64>>>, Option<Vec<Vec<Vector3<f64>>>>)> {
        let n_frames = decoded.first().map_or(0, |p| p.len());
        let corrections = if self.correctors.is_empty() { 0 } else { decoded.len() * n_frames };
        let stitches = if self.stitcher.is_some() { n_frames } else { 0 };
        self.progress.inc_length((corrections + stitches) as u64);
        let t = Instant::now();
        let (corrected, nearest_s) = self.correct_timed(decoded)?;
        let correct_s = t.elapsed().as_secs_f64() - nearest_s;
        let t = Instant::now();
        let assembled = (self.corrected_assembly
            && !self.correctors.is_empty()
            && self.stitcher.is_some())
        .then(|| assemble(&self.plan, pca, &corrected));
        let merged = self.merge(pca, &corrected);
        self.timing.frames += n_frames;
        self.timing.nearest_s += nearest_s;
        self.timing.correct_s += correct_s;
        self.timing.merge_s += t.elapsed().as_secs_f64();
        Ok((merged?, assembled))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_fixtures::bending_capsule;
    use capture::part_pca::{fit, PartAlignment};
    use crate::representation::rebuilt_error;
    use gp::pca::Components;

    /// Parts cut from whole-body-aligned frames and passed through a full-rank
    /// PCA give back every frame exactly by each method: averaging and
    /// stitching (the known mesh from its overlapping halves), and the
    /// correction (a prediction equal to a training mesh is its own nearest
    /// mesh, weight 1, identity rotations: the Poisson solve reproduces it).
    #[test]
    fn exact_parts_rebuild_the_frames_by_every_method() {
        let (mesh, seg, motion) = bending_capsule();
        for alignment in [PartAlignment::Body, PartAlignment::Part] {
            let (pca, _) = fit(
                &mesh.vertices,
                &seg,
                &[&motion],
                Components::Count(20),
                alignment,
            )
            .unwrap();
            for surface in [
                Surface::Assemble,
                Surface::Stitch,
                Surface::Correct,
                Surface::CorrectStitch,
            ] {
                let mut r =
                    Reconstructor::new(&pca, &seg, &mesh.faces, &[&motion], surface, 3, 1).unwrap();
                let e = rebuilt_error(&pca, &mut r, &motion, true).unwrap();
                assert!(e < 1e-8, "{alignment:?} {surface:?}: {e}");
            }
        }
    }

    /// One correction feeding both outputs: beside the stitched frames, the corrected parts
    /// averaged are what [`Surface::Correct`] gives, and the stitched frames what
    /// [`Surface::CorrectStitch`] alone gives, bit for bit (predictions shrunk by 5 %, so the
    /// correction has work to do).
    #[test]
    fn one_correction_gives_the_corrected_and_the_stitched_frames() {
        let (mesh, seg, motion) = bending_capsule();
        let (pca, _) = fit(&mesh.vertices, &seg, &[&motion], Components::Count(20), PartAlignment::Body).unwrap();
        let decoded: Vec<Vec<Vec<Vector3<f64>>>> = pca
            .part_rows(&motion)
            .unwrap()
            .iter()
            .map(|rows| {
                rows_to_meshes(rows)
                    .into_iter()
                    .map(|x| {
                        let c = surface::centroid(&x);
                        x.iter().map(|v| c + 0.95 * (v - c)).collect()
                    })
                    .collect()
            })
            .collect();
        let new = |surface| Reconstructor::new(&pca, &seg, &mesh.faces, &[&motion], surface, 3, 1).unwrap();
        let (stitched, corrected) = new(Surface::CorrectStitch)
            .with_corrected_assembly(true)
            .reconstruct_both(&pca, &decoded)
            .unwrap();
        assert!(corrected.unwrap() == new(Surface::Correct).reconstruct(&pca, &decoded).unwrap());
        assert!(stitched == new(Surface::CorrectStitch).reconstruct(&pca, &decoded).unwrap());
        assert!(new(Surface::CorrectStitch).reconstruct_both(&pca, &decoded).unwrap().1.is_none());
    }

    /// The training part meshes read a frame at a time are those `new` cuts from the loaded
    /// motions, bit for bit: every `stride`-th frame of each motion in turn, on both part
    /// alignments.
    #[test]
    fn training_part_meshes_read_a_frame_at_a_time_are_the_loaded_ones() {
        use mesh_core::artifact::Artifact;
        let (mesh, seg, motion) = bending_capsule();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.aligned");
        motion.save(&path, &mesh_core::artifact::Header::new("align", "0")).unwrap();
        for alignment in [PartAlignment::Body, PartAlignment::Part] {
            let (pca, _) = fit(&mesh.vertices, &seg, &[&motion], Components::Count(20), alignment).unwrap();
            let rows = pca.part_rows(&motion).unwrap();
            let every = |stride: usize| -> Vec<Vec<Vec<Vector3<f64>>>> {
                rows.iter()
                    .map(|r| {
                        let once: Vec<Vec<Vector3<f64>>> = rows_to_meshes(r).into_iter().step_by(stride).collect();
                        [once.clone(), once].concat()
                    })
                    .collect()
            };
            let paths = [path.clone(), path.clone()];
            for stride in [1, 2, 3] {
                let (read, used) = training_part_meshes(&pca, &paths, Stride::Every(stride)).unwrap();
                assert_eq!(used, stride);
                assert!(read == every(stride), "{alignment:?}, stride {stride}: part meshes differ");
            }
            // Within a budget: the smallest power of two whose meshes fit, the same meshes as
            // that stride read directly.
            let frame_bytes: usize = pca.parts.iter().map(|p| p.vertices.len() * 24).sum();
            let n = motion.n_frames();
            for fit_frames in [2 * n, 2 * n - 1, n, n - 1, 3, 1] {
                let want_stride = (0..)
                    .map(|k| 1usize << k)
                    .find(|&s| 2 * n.div_ceil(s) <= fit_frames || s >= n)
                    .unwrap();
                let (read, used) = training_part_meshes(&pca, &paths, Stride::Within(fit_frames * frame_bytes)).unwrap();
                assert_eq!(used, want_stride, "{fit_frames} of {n} frames fit");
                assert!(read == every(used), "{alignment:?}, {fit_frames} frames fit: part meshes differ");
            }
        }
    }

    /// The correction undoes a shrinkage of the limb (the PCA regression
    /// artefact §6.1 targets): mean edge length returns to the training value.
    #[test]
    fn correction_restores_edge_lengths_of_a_shrunken_part() {
        let (mesh, seg, motion) = bending_capsule();
        let (pca, _) = fit(
            &mesh.vertices,
            &seg,
            &[&motion],
            Components::Count(20),
            PartAlignment::Body,
        )
        .unwrap();
        let r = Reconstructor::new(&pca, &seg, &mesh.faces, &[&motion], Surface::Correct, 3, 1)
            .unwrap();
        let mut parts: Vec<Vec<Vec<Vector3<f64>>>> =
            pca.part_rows(&motion).unwrap().iter().map(rows_to_meshes).collect();
        let limb = &mut parts[1][5];
        let c = surface::centroid(limb);
        limb.iter_mut().for_each(|v| *v = c + 0.85 * (*v - c));
        let mean_edge = |x: &[Vector3<f64>]| {
            let f = &seg.parts[1].faces;
            f.iter()
                .map(|t| (x[t[0] as usize] - x[t[1] as usize]).norm())
                .sum::<f64>()
                / f.len() as f64
        };
        let want = mean_edge(&rows_to_meshes(&pca.part_rows(&motion).unwrap()[1])[5]);
        let before = mean_edge(&parts[1][5]) / want;
        let after = mean_edge(&r.correct(&parts).unwrap()[1][5]) / want;
        assert!((before - 0.85).abs() < 1e-9);
        assert!(
            (after - 1.0).abs() < 0.02,
            "edge ratio after correction {after}"
        );
    }
}

//! `gpr-predict`: source coefficients and displacements -> target coefficients
//! and displacements (CVPR eq. 13, the GP posterior mean `K_* α`, for all
//! frames at once), and the displacement GP's predictive variance (CVPR eq. 12)
//! used by the `blended` placement.

use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::gpr_model::{GprModel, Regressor};
use crate::placed_frames::PlacedFrames;

/// The model's output for a source sequence of `N` frames.
#[derive(Clone, Debug)]
pub struct TargetPrediction {
    /// Target coefficients per part (`N x m_k`).
    pub coeffs: Vec<DMatrix<f64>>,
    /// Target displacement 6-vectors, one per frame (`N x 6`).
    pub displacement: DMatrix<f64>,
    /// Per frame, the displacement GP's latent variance divided by its prior
    /// variance `k(x, x)`, in `[0, 1]`: 0 on the training data, 1 far from it.
    /// `None` unless asked for (it costs a Cholesky of the training Gram matrix).
    pub variance_ratio: Option<Vec<f64>>,
}

/// Source displacements as an `N x 6` matrix.
pub fn displacement_matrix(disp: &[[f64; 6]]) -> DMatrix<f64> {
    DMatrix::from_fn(disp.len(), 6, |r, c| disp[r][c])
}

/// Maps source coefficients (per part, `N x m_k`) and displacements through `model`.
pub fn predict(
    model: &GprModel,
    source_coeffs: &[DMatrix<f64>],
    source_disp: &DMatrix<f64>,
    with_variance: bool,
) -> Result<TargetPrediction> {
    if source_coeffs.len() != model.parts.len() {
        return Err(Error::invalid(format!(
            "the source PCA has {} parts but the model was trained with {} ({:?})",
            source_coeffs.len(),
            model.parts.len(),
            model.part_names
        )));
    }
    let coeffs = model
        .parts
        .par_iter()
        .zip(source_coeffs)
        .zip(&model.part_names)
        .map(|((reg, x), name)| {
            reg.predict(x)
                .map_err(|e| Error::invalid(format!("part '{name}': {e}")))
        })
        .collect::<Result<Vec<_>>>()?;
    let (displacement, variance_ratio) = match (&model.displacement, with_variance) {
        (Regressor::Gp { gpr, y_scale, mean }, true) => {
            let mut notes = Vec::new();
            let (mean_gp, var) = gpr
                .predict_with_variance(source_disp, &mut notes)
                .map_err(|e| Error::invalid(format!("displacement: {e}")))?;
            for n in notes {
                mesh_core::warn!("displacement GP: {n}");
            }
            let ratio = crate::confidence::ratio_to_prior(&var, &gpr.kernel.diag(source_disp));
            let mut disp = mean_gp * *y_scale;
            if let Some(m) = mean {
                disp += m.predict(source_disp).map_err(|e| Error::invalid(format!("displacement: {e}")))?;
            }
            (disp, Some(ratio))
        }
        (reg, _) => (reg.predict(source_disp)?, None),
    };
    Ok(TargetPrediction {
        coeffs,
        displacement,
        variance_ratio,
    })
}

/// Wall-clock seconds of the steps of [`transfer_motion`] (the source's encoding is
/// [`SourceMotion::read`]'s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// GP prediction (CVPR eq. 13) of all parts and of the displacement.
    pub gp_s: f64,
    /// Target PCA decoding, assembly and placement.
    pub decode_s: f64,
}

/// A source motion as a transfer reads it: its coefficients, its poses, displacements and
/// capture record, and its soles' vertices in every frame; never its frames.
pub struct SourceMotion {
    /// Per part, the coefficients of every frame (`F x m_k`).
    pub coefficients: Vec<DMatrix<f64>>,
    pub info: capture::motion_stream::MotionInfo,
    /// The source's soles and their vertices in each frame (None: no two leg parts, or a sole
    /// vertex beyond the frames').
    soles: Option<(crate::feet::SourceSoles, Vec<Vec<nalgebra::Vector3<f64>>>)>,
}

impl SourceMotion {
    /// The aligned motion at `path` encoded with `source_pca`, a frame at a time. Which vertices
    /// are the soles depends on the up axis, which the file stores after the frames, so the file
    /// is read twice: once for its capture record, once to encode the frames and keep the soles'
    /// vertices (it must not change in between).
    pub fn read(path: &std::path::Path, source_pca: &capture::part_pca::PcaModel) -> Result<SourceMotion> {
        let (first, first_sha256) = capture::motion_stream::read_frames(path, |_| Ok(()))?;
        let soles = crate::feet::SourceSoles::of(source_pca, &first.capture.up.into());
        let mut picked = Vec::new();
        let mut encoder = capture::part_pca::FrameEncoder::new(source_pca);
        let (info, sha256) = capture::motion_stream::read_frames(path, |f| {
            if let Some(s) = &soles {
                picked.push(s.pick(&f));
            }
            encoder.push(f)
        })?;
        if sha256 != first_sha256 || info != first {
            return Err(Error::file(path, "changed while it was read"));
        }
        let coefficients = encoder.finish(&info.capture.template_sha256).map_err(|e| Error::file(path, e.to_string()))?;
        let soles = soles.and_then(|s| match picked.into_iter().collect::<Option<Vec<_>>>() {
            Some(frames) => Some((s, frames)),
            None => {
                mesh_core::info!("a sole vertex is beyond the source motion's vertices: no contacts");
                None
            }
        });
        Ok(SourceMotion { coefficients, info, soles })
    }

    pub fn n_frames(&self) -> usize {
        self.info.n_frames
    }

    /// The source's contacts ([`crate::feet::SourceSoles::contacts`]).
    pub fn contacts(&self) -> Option<crate::feet::SourceContacts> {
        let (soles, frames) = self.soles.as_ref()?;
        soles.contacts(frames, &self.info.poses, &self.info.capture)
    }
}

/// A transferred sequence: the target's frames in world coordinates, placed and cleaned up, on
/// disk until they are written ([`PlacedFrames::for_each`]).
pub struct Transferred {
    pub frames: PlacedFrames,
    /// The corrected parts merged by averaging, placed and cleaned up as `frames` are, when
    /// the reconstructor was asked for them too (`Reconstructor::with_corrected_assembly`).
    pub corrected_frames: Option<PlacedFrames>,
    /// Per-frame weight of the scaled source in the `blended` placement.
    pub blend_weights: Option<Vec<f64>>,
    /// What the feet clean-ups did (None: not asked for, or no two leg parts).
    pub planted: Option<crate::feet::Planted>,
    pub timing: Timing,
}

/// How [`transfer_motion`] makes and keeps a transfer's frames.
pub struct Streaming<'a> {
    /// The output folder of the frames (and of the corrected frames, when the reconstructor
    /// makes them): the kept frames' scratch files go beside them.
    pub output: &'a std::path::Path,
    pub corrected_output: Option<&'a std::path::Path>,
    /// Frames made at a time ([`capture::part_pca::blocks_of`]: every frame is the same
    /// whatever the block).
    pub block: usize,
    /// Bytes of placed frames held in memory per output; beyond it they are kept on disk
    /// ([`PlacedFrames`]).
    pub memory_budget: usize,
}

/// The whole of `gpr-predict` but the file writing: source coefficients -> target coefficients
/// (and displacements) -> target parts (limbs turned by the model's limb orientation,
/// `crate::limb_orientation`) -> assembled target mesh (or `reconstructor`'s §6 correction and
/// stitching) -> placed from the source's first world pose -> planted feet cleaned up as `feet`
/// asks ([`crate::feet`]). The frames are made a block at a time and kept as [`Streaming`] says,
/// so a motion of any length holds a block of frames and the kept frames' budget.
#[allow(clippy::too_many_arguments)]
pub fn transfer_motion(
    model: &GprModel,
    source_pca: &capture::part_pca::PcaModel,
    target_pca: &capture::part_pca::PcaModel,
    source: &SourceMotion,
    placement: crate::placement::Placement,
    mut reconstructor: Option<&mut crate::reconstruct::Reconstructor>,
    feet: &crate::feet::CleanUp,
    streaming: &Streaming,
) -> Result<Transferred> {
    use capture::align::root_poses;
    use crate::placement::{blend, root_point, scaled_source, scaled_start, template_height, Placement};
    use capture::root_placement::{integrate, place_in_place, world_poses};
    use std::time::Instant;
    let motion = &source.info;
    let xs = &source.coefficients;
    let xd = displacement_matrix(&motion.displacements);
    let t1 = Instant::now();
    let pred = predict(model, xs, &xd, placement == Placement::Blended)?;
    let gp_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let (source_root, target_root) = (root_point(source_pca), root_point(target_pca));
    let regressed: Vec<[f64; 6]> = pred
        .displacement
        .row_iter()
        .map(|r| std::array::from_fn(|c| r[c]))
        .collect();
    let hs = template_height(source_pca);
    let ratio = if hs > 0.0 {
        template_height(target_pca) / hs
    } else {
        1.0
    };
    let scaled = scaled_source(&motion.displacements, ratio);
    let steps = match placement {
        Placement::Regressed => regressed,
        Placement::ScaledSource => scaled,
        Placement::Blended => {
            let w = pred
                .variance_ratio
                .clone()
                .unwrap_or_else(|| vec![0.0; regressed.len()]);
            blend(&regressed, &scaled, &w)
        }
    };
    let source_start = root_poses(&motion.poses[..motion.poses.len().min(1)], &source_root);
    let start = scaled_start(&source_start.first().copied().unwrap_or_default(), ratio);
    let world_poses = world_poses(&integrate(&start, &steps, steps.len(), None), &target_root);

    // The clean-ups need the target's feet and the source's contacts; without either, the
    // frames are left as placed.
    let up = nalgebra::Vector3::from(motion.capture.up);
    let cleaned = feet.footskate || feet.foot_height;
    if cleaned {
        mesh_core::feet::check_smoothness(feet.smoothness)?;
    }
    let clean = cleaned
        .then(|| crate::feet::TargetFeet::of(target_pca, &up))
        .flatten()
        .and_then(|target| Some((target, source.contacts()?)));
    let recorded = clean.as_ref().map(|(target, _)| target);
    let plan = capture::assemble::plan(target_pca)?;
    let keep = |path: &std::path::Path| PlacedFrames::new(path, target_pca.n_vertices, streaming.memory_budget);
    let mut frames = keep(streaming.output);
    let mut corrected_frames: Option<PlacedFrames> = None;
    for range in capture::part_pca::blocks_of(source.n_frames(), streaming.block) {
        let rows = |m: &[DMatrix<f64>]| -> Vec<DMatrix<f64>> { m.iter().map(|c| c.rows(range.start, range.len()).into_owned()).collect() };
        // The decoded parts are dropped once assembled, and the assembled frames are placed
        // where they are.
        let (mut made, mut corrected) = {
            let mut decoded = target_pca.decode(&rows(&pred.coeffs))?;
            if let Some(o) = &model.orientation {
                crate::limb_orientation::apply(o, source_pca, target_pca, &rows(xs), &mut decoded)?;
            }
            match reconstructor.as_deref_mut() {
                Some(r) => r.reconstruct_both(target_pca, &decoded)?,
                None => (capture::assemble::assemble(&plan, target_pca, &decoded), None),
            }
        };
        place_in_place(&world_poses[range.clone()], &mut made);
        frames.push(&made, recorded, &up)?;
        if let Some(c) = corrected.as_mut() {
            place_in_place(&world_poses[range.clone()], c);
            let out = match (&mut corrected_frames, streaming.corrected_output) {
                (Some(out), _) => out,
                (None, Some(path)) => corrected_frames.insert(keep(path)),
                (None, None) => return Err(Error::invalid("corrected frames made with no output for them")),
            };
            out.push(c, recorded, &up)?;
        }
    }
    let planted = match &clean {
        Some((target, contacts)) => {
            let (moves, planted) = crate::feet::solve(frames.feet(), contacts, target, target_pca, ratio, &up, feet, placement)?;
            frames.set_moves(moves);
            if let Some(c) = corrected_frames.as_mut() {
                c.set_moves(crate::feet::solve(c.feet(), contacts, target, target_pca, ratio, &up, feet, placement)?.0);
            }
            Some(planted)
        }
        None => None,
    };
    let decode_s = t2.elapsed().as_secs_f64();
    Ok(Transferred {
        frames,
        corrected_frames,
        blend_weights: pred.variance_ratio,
        planted,
        timing: Timing {
            gp_s,
            decode_s,
        },
    })
}

//! `gpr-predict`: source coefficients and displacements -> target coefficients
//! and displacements (CVPR eq. 13, the GP posterior mean `K_* α`, for all
//! frames at once), and the displacement GP's predictive variance (CVPR eq. 12)
//! used by the `blended` placement.

use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::gpr_model::{GprModel, Regressor};

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

/// Wall-clock seconds of the steps of [`transfer_motion`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Source PCA encoding of the aligned frames.
    pub encode_s: f64,
    /// GP prediction (CVPR eq. 13) of all parts and of the displacement.
    pub gp_s: f64,
    /// Target PCA decoding, assembly and placement.
    pub decode_s: f64,
}

/// A transferred sequence: target frames in world coordinates and the poses used.
#[derive(Clone, Debug)]
pub struct Transferred {
    pub frames: Vec<Vec<nalgebra::Vector3<f64>>>,
    /// The corrected parts merged by averaging, placed and cleaned up as `frames` are, when
    /// the reconstructor was asked for them too (`Reconstructor::with_corrected_assembly`).
    pub corrected_frames: Option<Vec<Vec<nalgebra::Vector3<f64>>>>,
    pub poses: Vec<mesh_core::rigid::RigidMotion>,
    /// Per-frame weight of the scaled source in the `blended` placement.
    pub blend_weights: Option<Vec<f64>>,
    /// What the feet clean-ups did (None: not asked for, or no two leg parts).
    pub planted: Option<crate::feet::Planted>,
    pub timing: Timing,
}

/// The whole of `gpr-predict` but the file writing: source aligned motion ->
/// source coefficients -> target coefficients (and displacements) -> target
/// parts (limbs turned by the model's limb orientation, `crate::limb_orientation`) ->
/// assembled target mesh (or `reconstructor`'s §6 correction and
/// stitching) -> placed from the source's first world pose -> planted feet cleaned up as
/// `feet` asks ([`crate::feet`]).
pub fn transfer_motion(
    model: &GprModel,
    source_pca: &capture::part_pca::PcaModel,
    target_pca: &capture::part_pca::PcaModel,
    motion: &capture::align::AlignedMotion,
    placement: crate::placement::Placement,
    reconstructor: Option<&mut crate::reconstruct::Reconstructor>,
    feet: &crate::feet::CleanUp,
) -> Result<Transferred> {
    use capture::align::root_poses;
    use crate::placement::{
        blend, place_in_place, poses, root_point, scaled_source, scaled_start, template_height,
        world_poses, Placement,
    };
    use std::time::Instant;
    let t0 = Instant::now();
    let xs = source_pca.encode(motion)?;
    let xd = displacement_matrix(&motion.displacements);
    let encode_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let pred = predict(model, &xs, &xd, placement == Placement::Blended)?;
    let gp_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    // The decoded parts are dropped once assembled, and the assembled frames are placed where
    // they are: one copy of the target motion is held, besides the source (two when the
    // reconstructor also gives the corrected parts averaged).
    let (mut frames, mut corrected_frames) = {
        let mut decoded = target_pca.decode(&pred.coeffs)?;
        if let Some(o) = &model.orientation {
            crate::limb_orientation::apply(o, source_pca, target_pca, &xs, &mut decoded)?;
        }
        match reconstructor {
            Some(r) => r.reconstruct_both(target_pca, &decoded)?,
            None => {
                let plan = capture::assemble::plan(target_pca)?;
                (capture::assemble::assemble(&plan, target_pca, &decoded), None)
            }
        }
    };
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
    let world_poses = world_poses(&poses(&start, &steps), &target_root);
    place_in_place(&world_poses, &mut frames);
    let planted = crate::feet::plant(&mut frames, source_pca, target_pca, motion, ratio, feet)?;
    if let Some(c) = corrected_frames.as_mut() {
        place_in_place(&world_poses, c);
        crate::feet::plant(c, source_pca, target_pca, motion, ratio, feet)?;
    }
    let decode_s = t2.elapsed().as_secs_f64();
    Ok(Transferred {
        frames,
        corrected_frames,
        poses: world_poses,
        blend_weights: pred.variance_ratio,
        planted,
        timing: Timing {
            encode_s,
            gp_s,
            decode_s,
        },
    })
}

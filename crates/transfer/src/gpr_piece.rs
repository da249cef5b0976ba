//! One regressor of a transfer model trained alone (`gpr-train --part NAME`, one cluster task
//! per part) and the join of such pieces into the whole model (`merge-parts`).

use mesh_core::part_merge::Partitioned;
use mesh_core::{Error, Result};
use serde::{Deserialize, Serialize};

use crate::gpr_model::{
    check_inputs, train_displacement, train_parts, GprModel, MeanFunction, MeanPriors, Method, Regression, Regressor,
    RegressorReport, Templates,
};
use crate::limb_orientation::{LimbMap, LimbOrientation};
use crate::training_rows::TrainingRows;

/// The name of the displacement regressor among a model's pieces: `gpr-train --part
/// displacement` trains it alone.
pub const DISPLACEMENT: &str = "displacement";

/// One regressor of a [`GprModel`] (a part's, or the displacement's) with the model's shared
/// fields: what `gpr-train --part NAME` writes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GprPiece {
    pub method: Method,
    pub regressor: Regressor,
    pub report: RegressorReport,
    pub n_train: usize,
    pub frame_ratio: f64,
    pub keyposes_only: bool,
    pub nn_bias: bool,
    pub mean: MeanFunction,
    /// The model's limb orientation weight (0: none) and this part's map (`None` for the
    /// root and the displacement).
    pub orientation_weight: f64,
    pub orientation: Option<LimbMap>,
    pub templates: Templates,
}

impl GprPiece {
    /// The fields every regressor of one model shares.
    fn shared(&self) -> (Method, usize, u64, bool, bool, MeanFunction, u64, &Templates) {
        (
            self.method,
            self.n_train,
            self.frame_ratio.to_bits(),
            self.keyposes_only,
            self.nn_bias,
            self.mean,
            self.orientation_weight.to_bits(),
            &self.templates,
        )
    }
}

/// The pieces of a model are its parts' regressors, then the displacement's ([`DISPLACEMENT`]).
impl Partitioned for GprModel {
    const PIECE_KIND: &'static str = "gpr-model-part";
    type Body = GprPiece;

    fn validate_body(body: &GprPiece) -> std::result::Result<(), String> {
        body.regressor.validate(None)?;
        if !(body.frame_ratio.is_finite() && body.frame_ratio > 0.0) {
            return Err(format!("frame ratio {} is not a finite positive number", body.frame_ratio));
        }
        if !(0.0..=1.0).contains(&body.orientation_weight) {
            return Err(format!("limb orientation weight {} is not in [0, 1]", body.orientation_weight));
        }
        if let Some(m) = &body.orientation {
            m.validate()?;
        }
        Ok(())
    }

    fn join(parts: &[String], mut bodies: Vec<GprPiece>) -> std::result::Result<GprModel, String> {
        let (last, names) = parts.split_last().ok_or("no parts")?;
        if last != DISPLACEMENT || names.is_empty() || bodies.len() != parts.len() {
            return Err(format!("the pieces of a model are its parts then '{DISPLACEMENT}', not {}", parts.join(", ")));
        }
        if let Some((b, name)) = bodies.iter().zip(parts).find(|(b, _)| b.shared() != bodies[0].shared()) {
            return Err(format!(
                "part '{name}' was trained with another method, frame ratio, mean or training set ({:?}, not {:?})",
                b.shared(),
                bodies[0].shared()
            ));
        }
        let disp = bodies.pop().expect("one body per part");
        let mut reports: Vec<RegressorReport> = bodies.iter().map(|b| b.report.clone()).collect();
        reports.push(disp.report);
        let orientation = (disp.orientation_weight > 0.0).then(|| LimbOrientation {
            weight: disp.orientation_weight,
            maps: bodies.iter().map(|b| b.orientation.clone()).collect(),
        });
        Ok(GprModel {
            method: disp.method,
            part_names: names.to_vec(),
            parts: bodies.into_iter().map(|b| b.regressor).collect(),
            displacement: disp.regressor,
            n_train: disp.n_train,
            frame_ratio: disp.frame_ratio,
            keyposes_only: disp.keyposes_only,
            nn_bias: disp.nn_bias,
            mean: disp.mean,
            reports,
            orientation,
            templates: disp.templates,
        })
    }
}

/// [`train`] of one regressor: part `unit` (an index into `part_names`), or the displacement
/// when `unit == part_names.len()`; the regressor is trained exactly as in the whole model.
pub fn train_piece(regression: &Regression, part_names: &[String], rows: &TrainingRows, unit: usize) -> Result<GprPiece> {
    let Regression { method, nn_bias, mean: mean_fn, mean_ridge, mean_priors, opts, fixed } = *regression;
    check_inputs(regression, part_names, rows)?;
    let (data, keys) = (&rows.data, rows.keys());
    let (regressor, report) = if unit < part_names.len() {
        let priors = mean_priors.map(|p| MeanPriors { maps: &p.maps[unit..=unit], ..p });
        let (mut regs, mut reports) = train_parts(
            method,
            nn_bias,
            mean_fn,
            mean_ridge,
            priors,
            &part_names[unit..=unit],
            &data.part(unit),
            &keys.part(unit),
            opts,
            fixed.map(|f| &f.parts[unit..=unit]),
        )?;
        (regs.remove(0), reports.remove(0))
    } else if unit == part_names.len() {
        train_displacement(regression, rows, fixed.and_then(|f| f.displacement))?
    } else {
        return Err(Error::invalid(format!("regressor {unit} of {} parts and the displacement", part_names.len())));
    };
    Ok(GprPiece {
        method,
        regressor,
        report,
        n_train: rows.len(method),
        frame_ratio: rows.frame_ratio,
        keyposes_only: rows.keyposes_only,
        nn_bias,
        mean: mean_fn,
        orientation_weight: 0.0,
        orientation: None,
        templates: Templates::default(),
    })
}

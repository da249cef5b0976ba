//! The stages of surface motion transfer (Boukhayma, Franco, Boyer, CVPR 2017).
//!
//! Each module is one stage's logic; `src/bin/<stage>.rs` parses arguments
//! and calls it. Data flows one way: capture set -> the front end of crate `capture`
//! (`segment`, `align`, PCA per part) -> dense correspondences -> GP models -> predicted
//! target sequences -> evaluation.

pub mod densify;
pub mod gpr_model;
pub mod gpr_piece;
pub mod training_rows;
pub mod geometric_prior;
pub mod limb_orientation;
pub mod predict;
pub mod confidence;
pub mod reconstruct;
pub mod representation;
pub mod quality;
pub mod placement;
pub mod feet;
pub mod placed_frames;
pub mod evaluate;
pub mod cross_validation;
pub mod model_config;
pub mod reference_score;
pub mod learning_curves;
pub mod stage;
#[cfg(test)]
mod test_fixtures;

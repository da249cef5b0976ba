//! The papers' figures and every plot of the project, in one font ([`plot`]): the transfer
//! paper's illustrations, drawn by the `render` crate, and the `paper-figure` stage that writes
//! them ([`paper_figure`]); the learning curves (CVPR figs. 7-9) and the `learning-curves` stage
//! that computes and draws them ([`learning_curves`]):
//!
//! - CVPR figure 3, [`CostFigure`]: the association cost matrix `-log P_ij`
//!   of one training pair (CVPR eqs. 1-6, `gp::blr::cost_matrix`, summed over
//!   parts) as an image, source frames along x and target frames along y,
//!   with the DTW path (CVPR eq. 7, `gp::dtw::dtw_path`, as `dtw-densify`), the
//!   key-poses and, when the set has them, the true correspondences overlaid.
//!   Colours are `ln(1 + cost)` on a viridis-like ramp, clipped to the 2nd-98th
//!   percentiles (the cost spans many orders of magnitude).
//! - CVPR figure 5, [`CorrectionFigure`]: one predicted part mesh before and
//!   after the §6.1 correction, and the `M` nearest training meshes it was
//!   corrected with (`surface::correct::Corrector`), drawn side by side with
//!   one camera by the `render` crate; optionally the true part, rigidly
//!   aligned onto the corrected one.
//! - The per-frame confidence figure, [`ConfidenceFigure`] (not in the
//!   paper): for one transferred motion, the normalised nearest distance and
//!   the GP variance ratio of every part (`transfer::confidence`) and, with an
//!   `transfer-eval` record, the pose error, frame by frame; frames where a body
//!   part is at least [`DEFAULT_EXTRAPOLATION_THRESHOLD`] from its training
//!   inputs are shaded, and the Pearson correlation of the per-frame maximum
//!   distance with the error is reported.

mod confidence;
mod correction;
mod cost_matrix;
mod learning_curve_plots;
pub mod learning_curves;
pub mod paper_figure;
pub mod plot;
pub mod variation_eval;
mod variation_plots;

pub use confidence::*;
pub use correction::*;
pub use cost_matrix::*;

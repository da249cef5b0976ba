//! Where a latent trajectory leaves the learned data (3DV eq. 13's variance against the
//! prior's), and the HMC start that avoids a mean prediction that does.

mod common;

use gpdm::hmc::{leaves_the_data, sample_trajectories_scaled, HmcOptions, OFF_DATA_VARIANCE};
use gpdm::predict::Predictor;

/// On the learned latent points the pose variance is the noise's share of the prior; far from
/// every point the training poses say nothing and it is the whole prior.
#[test]
fn variance_ratio_is_small_on_the_data_and_one_far_away() {
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let on = pred.pose_variance_ratio(&m.x).unwrap();
    let largest = on.iter().copied().fold(0.0, f64::max);
    assert!(largest < 0.05, "largest ratio on the learned points {largest}");
    let far = m.x.map(|v| v + 50.0);
    let off = pred.pose_variance_ratio(&far).unwrap();
    assert!(off.iter().all(|&r| r > 0.99 && r <= 1.0 + 1e-12), "{off:?}");
    assert!(!leaves_the_data(&pred, &m.x).unwrap());
    assert!(leaves_the_data(&pred, &far).unwrap());
    assert!(OFF_DATA_VARIANCE > largest && OFF_DATA_VARIANCE < 0.99);
}

/// A chain from a learned first point starts at the mean prediction (it stays on the data of
/// this stable rotation); one whose mean prediction is off the data starts at the given
/// trajectory, and says so.
#[test]
fn chains_start_at_the_template_only_where_the_mean_prediction_leaves_the_data() {
    let (m, _, _) = common::rotation_model();
    let pred = Predictor::new(&m).unwrap();
    let opts = HmcOptions { n_samples: 2, burn_in: 10, thin: 1, leapfrog_steps: 5, seed: 3, ..Default::default() };
    let learned = m.sequence_latent(0).unwrap();
    let mean = pred.mean_trajectory(&learned.row(0).iter().copied().collect::<Vec<_>>(), learned.nrows()).unwrap();
    assert!(!leaves_the_data(&pred, &mean).unwrap());
    let (_, res) = sample_trajectories_scaled(&pred, &learned, &opts, 0.3).unwrap();
    assert!(!res.started_at_template);
    let far = learned.map(|v| v + 50.0);
    let (trajs, res) = sample_trajectories_scaled(&pred, &far, &opts, 0.3).unwrap();
    assert!(res.started_at_template);
    assert!(trajs.iter().all(|t| t.row(0) == far.row(0)), "the first point stays fixed");
}

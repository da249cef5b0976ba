//! How often ancestral draws leave a trained model's learned data, free and with the redraws of
//! `gpdm::ancestral::sample_trajectories_on_data` (the `--sampler ancestral` of `hmc-sample`).
//!
//! Per training sequence and part, 20 draws from the sequence's first latent point at the learned
//! length and at twice it: how many have a point whose pose variance (3DV eq. 13) passes
//! `gpdm::hmc::OFF_DATA_VARIANCE` of the prior's, free and redrawn, the largest share of the
//! prior's variance on any free draw, and the points the redraws left off the data. Lines whose
//! free draws all stay below 0.1 of the prior's variance are not printed.
//!
//! Usage: off_data_draws MODEL [κ] (default κ 0.3)
//! e.g.: target/release/off_data_draws out/work/variation/jump.model 0.3

use clap::Parser;
use gpdm::ancestral::{sample_trajectories_ancestral, sample_trajectories_on_data};
use gpdm::hmc::{leaves_the_data, OFF_DATA_VARIANCE};
use gpdm::predict::Predictor;
use mesh_core::artifact::Artifact;
use variation::train::VariationModel;

/// How often ancestral draws leave a trained model's learned data, free and with the redraws.
#[derive(Parser)]
struct Cli {
    /// The variation model (gpdm-train's output).
    model: String,
    /// The variance scale κ.
    #[arg(default_value_t = 0.3)]
    kappa: f64,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let model = VariationModel::load(&cli.model)?;
    let kappa = cli.kappa;
    let n = 20;
    for (k, pm) in model.parts.iter().enumerate() {
        let pr = Predictor::new(&pm.gpdm)?;
        for (s, info) in model.sequences.iter().enumerate() {
            let x = pm.gpdm.sequence_latent(s).expect("every sequence has latents");
            let x1: Vec<f64> = x.row(0).iter().copied().collect();
            let seed = 7 + 100 * s as u64 + k as u64;
            for len in [x.nrows(), 2 * x.nrows()] {
                let free = sample_trajectories_ancestral(&pr, &x1, len, n, seed, kappa)?;
                let off = free.iter().filter(|t| leaves_the_data(&pr, t).unwrap_or(true)).count();
                let worst = free
                    .iter()
                    .flat_map(|t| pr.pose_variance_ratio(t).unwrap_or_default())
                    .fold(0.0, f64::max);
                let (kept, points) = sample_trajectories_on_data(&pr, &x1, len, n, seed, kappa, OFF_DATA_VARIANCE)?;
                let kept_off = kept.iter().filter(|t| leaves_the_data(&pr, t).unwrap_or(true)).count();
                if off > 0 || worst > 0.1 {
                    println!(
                        "{} {} len {len}: free {off} of {n} off, worst ratio {worst:.2}; redrawn {kept_off} of {n} off, {} points",
                        info.name,
                        pm.part.name,
                        points.iter().sum::<usize>()
                    );
                }
            }
        }
    }
    Ok(())
}

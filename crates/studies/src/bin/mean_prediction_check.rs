//! Whether a trained model's mean predictions (3DV eq. 8, where HMC chains start) stay on the
//! learned data, per training sequence and part, and how smooth the pose decoder (3DV eq. 12)
//! is near the learned latents.
//!
//! Printed: (1) per sequence and part, the RMS vertex displacement (mm) between the decoding
//! of the learned latent trajectory and of that trajectory plus `ε` times a standard normal
//! draw per coordinate (`ε` relative to the RMS spread of the part's latent points); (2) per
//! sequence, the torso's edge distortion (mean |log edge-length ratio| to the part's reference)
//! decoded at the learned latents and along the mean prediction from the first latent point,
//! and per part the mean prediction's largest distance to a learned latent point (in median
//! training steps) and its largest pose variance over the prior's
//! (`Predictor::pose_variance_ratio`; above `gpdm::hmc::OFF_DATA_VARIANCE` the chain starts
//! at the learned trajectory instead).
//!
//! Usage: mean_prediction_check <model> [ε...]
//! e.g.: target/release/mean_prediction_check out/work/variation/locomotion.model 0.01 0.05

use clap::Parser;
use mesh_core::artifact::Artifact;
use nalgebra::DMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use variation::reconstruct::Decoder;
use variation::train::VariationModel;

/// A standard normal draw (Box-Muller).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let (u, v): (f64, f64) = (rng.random(), rng.random());
    (-2.0 * (1.0 - u).ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// Whether a trained model's mean predictions stay on the learned data, and how smooth the pose
/// decoder is near the learned latents.
#[derive(Parser)]
struct Cli {
    /// The variation model (gpdm-train's output).
    model: String,
    /// Latent perturbations ε, relative to the RMS spread of each part's latent points
    /// [default: 0.01 0.05].
    eps: Vec<f64>,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let cli = Cli::parse();
    let path = &cli.model;
    let eps: Vec<f64> = if cli.eps.is_empty() { vec![0.01, 0.05] } else { cli.eps.clone() };
    let model = VariationModel::load(path)?;
    let mut notes = Vec::new();
    let dec = Decoder::new(&model, &mut notes)?;
    let names: Vec<&str> = model.parts.iter().map(|p| p.part.name.as_str()).collect();
    println!("sequence\teps\t{}", names.join("\t"));
    for (s, info) in model.sequences.iter().enumerate() {
        let learned: Vec<DMatrix<f64>> =
            model.parts.iter().map(|p| p.gpdm.sequence_latent(s).expect("sequence in every part")).collect();
        let base = dec.part_poses(&learned, None::<&mut ChaCha8Rng>)?;
        for &e in &eps {
            let mut rng = ChaCha8Rng::seed_from_u64(0);
            let moved: Vec<DMatrix<f64>> = learned
                .iter()
                .zip(&model.parts)
                .map(|(x, p)| {
                    let all = &p.gpdm.x;
                    let spread = (all.row_variance().sum()).sqrt();
                    x.map(|v| v + e * spread * normal(&mut rng))
                })
                .collect();
            let out = dec.part_poses(&moved, None::<&mut ChaCha8Rng>)?;
            let rms: Vec<String> = base
                .parts
                .iter()
                .zip(&out.parts)
                .map(|(a, b)| {
                    let (mut sum, mut n) = (0.0, 0usize);
                    for (fa, fb) in a.iter().zip(b) {
                        for (va, vb) in fa.iter().zip(fb) {
                            sum += (va - vb).norm_squared();
                            n += 1;
                        }
                    }
                    format!("{:.1}", 1e3 * (sum / n.max(1) as f64).sqrt())
                })
                .collect();
            println!("{}\t{e}\t{}", info.name, rms.join("\t"));
        }
    }
    // Torso edges (template indices mapped to the torso's own vertex order), and their lengths
    // in the part's reference.
    let torso = &model.parts[0];
    let mut at = vec![usize::MAX; model.template.len()];
    for (i, &v) in torso.part.vertices.iter().enumerate() {
        at[v as usize] = i;
    }
    let mut edges = Vec::new();
    for f in &model.faces {
        for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
            let (a, b) = (at[a as usize], at[b as usize]);
            if a != usize::MAX && b != usize::MAX && a < b {
                edges.push((a, b));
            }
        }
    }
    let distortion = |frame: &[nalgebra::Vector3<f64>]| {
        edges
            .iter()
            .map(|&(a, b)| ((frame[a] - frame[b]).norm() / (torso.reference[a] - torso.reference[b]).norm()).ln().abs())
            .sum::<f64>()
            / edges.len() as f64
    };
    println!("\ntorso edge distortion (mean |log edge ratio| to the reference), mean over frames:");
    println!("sequence\tlearned latents\tmean dynamics from the first latent point");
    for (s, info) in model.sequences.iter().enumerate() {
        let learned: Vec<DMatrix<f64>> = model.parts.iter().map(|p| p.gpdm.sequence_latent(s).unwrap()).collect();
        let mean: Vec<DMatrix<f64>> = learned
            .iter()
            .zip(&dec.predictors)
            .map(|(x, pr)| pr.mean_trajectory(&x.row(0).iter().copied().collect::<Vec<_>>(), x.nrows()))
            .collect::<Result<_, _>>()?;
        let at_learned = dec.part_poses(&learned, None::<&mut ChaCha8Rng>)?;
        let at_mean = dec.part_poses(&mean, None::<&mut ChaCha8Rng>)?;
        let avg = |d: &variation::reconstruct::DecodedParts| d.parts[0].iter().map(|f| distortion(f)).sum::<f64>() / d.parts[0].len() as f64;
        let drift: f64 = learned[0].row_iter().zip(mean[0].row_iter()).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        println!("{}\t{:.3}\t{:.3} (largest torso latent distance {:.3})", info.name, avg(&at_learned), avg(&at_mean), drift);
        // Per part: the mean prediction's largest distance to the nearest learned latent point
        // (any sequence), in median training steps.
        let off: Vec<String> = model
            .parts
            .iter()
            .zip(&mean)
            .map(|(p, m)| {
                let x = &p.gpdm.x;
                let mut steps: Vec<f64> = Vec::new();
                let mut start = 0;
                for &len in &p.gpdm.seq_lens {
                    for t in start + 1..start + len {
                        steps.push((x.row(t) - x.row(t - 1)).norm());
                    }
                    start += len;
                }
                steps.sort_by(f64::total_cmp);
                let step = steps[steps.len() / 2];
                let far = m
                    .row_iter()
                    .map(|r| x.row_iter().map(|q| (r - q).norm()).fold(f64::INFINITY, f64::min))
                    .fold(0.0, f64::max);
                format!("{:.1}", far / step)
            })
            .collect();
        println!("  mean prediction's largest distance to the learned latents, in median steps, per part: {}", off.join(" "));
        let var: Vec<String> = dec
            .predictors
            .iter()
            .zip(&model.parts)
            .zip(&mean)
            .map(|((pr, p), m)| {
                let v = pr.pose_variance(m).expect("pose variance");
                let prior = p.gpdm.alpha[0] + 1.0 / p.gpdm.alpha[2];
                format!("{:.3}", v.iter().copied().fold(0.0, f64::max) / prior)
            })
            .collect();
        println!("  mean prediction's largest pose variance over the prior's, per part: {}", var.join(" "));
    }
    Ok(())
}

//! Cost of the stitched assembly (`Assembly::Stitch`, the pipeline's default) on a trained
//! model, per frame, for each factorisation of the Poisson merge, and how far the results are
//! from faer's default (simplicial) factorisation. Trajectories: exact ancestral draws of the
//! first training sequence (κ = 0.3, as `make variation`), decoded exactly.
//!
//! Usage: stitch_budget [model] [--variations N]
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/stitch_budget out/work/variation/locomotion.model

use std::time::Instant;

use gpdm::hmc::HmcOptions;
use mesh_core::artifact::Artifact;
use rand_chacha::ChaCha8Rng;
use surface::poisson::Factorisation;
use variation::reconstruct::{Assembly, DecodedParts, Decoder};
use variation::sample::{default_hmc, sequence_variations_len, Sampler};
use variation::train::VariationModel;

/// CPU seconds of this thread (clock_gettime(CLOCK_THREAD_CPUTIME_ID) through /proc would be
/// per process; the program runs on one thread, so the process figure is the thread's).
fn cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit(") ").next().unwrap_or("");
    let f: Vec<f64> = rest.split(' ').filter_map(|x| x.parse().ok()).collect();
    f.get(10).copied().unwrap_or(0.0) / 100.0 + f.get(11).copied().unwrap_or(0.0) / 100.0
}

/// Cost of the stitched assembly per frame for each factorisation of the Poisson merge.
#[derive(clap::Parser)]
struct Cli {
    /// A trained variation model.
    #[arg(default_value = "out/work/variation/locomotion.model")]
    model: String,
    /// Variations sampled.
    #[arg(long, default_value_t = 2)]
    variations: usize,
}

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    let model = VariationModel::load(&cli.model).expect("a trained variation model");
    let dec = Decoder::new(&model, &mut Vec::new()).expect("decoder");
    let decoded = decoded_variations(&model, &dec, cli.variations);
    let frames: usize = decoded.iter().map(|d| d.displacements.len()).sum();
    println!(
        "{}: {} variations, {frames} frames, {} vertices",
        cli.model,
        decoded.len(),
        model.template.len()
    );
    time_factorisations(&dec, &decoded, frames);
}

/// `n` exact ancestral draws of the first training sequence (up to 100 frames, κ = 0.3),
/// decoded exactly to part poses.
fn decoded_variations(model: &VariationModel, dec: &Decoder, n: usize) -> Vec<DecodedParts> {
    let opts = HmcOptions {
        n_samples: n,
        ..default_hmc(n, 0)
    };
    let (vars, _) = sequence_variations_len(
        dec,
        0,
        model.n_frames().min(100),
        Sampler::Ancestral,
        0.3,
        &opts,
        1,
    )
    .expect("samples");
    vars.iter()
        .map(|x| dec.part_poses::<ChaCha8Rng>(x, None).expect("decoded"))
        .collect()
}

/// Prints the stitched assembly's time per frame (of `frames` in `decoded`) for each
/// factorisation, twice each, and the largest distance of its vertices from the first's.
fn time_factorisations(dec: &Decoder, decoded: &[DecodedParts], frames: usize) {
    let mut reference: Option<Vec<Vec<Vec<nalgebra::Vector3<f64>>>>> = None;
    for how in [Factorisation::Auto, Factorisation::Supernodal] {
        for round in 0..2 {
            let (t, c) = (Instant::now(), cpu());
            let out: Vec<_> = decoded
                .iter()
                .map(|d| dec.assemble_with(d, Assembly::Stitch, how).expect("stitched"))
                .collect();
            let (wall, cpu_s) = (t.elapsed().as_secs_f64(), cpu() - c);
            let dev = reference.as_ref().map(|r| {
                r.iter()
                    .flatten()
                    .flatten()
                    .zip(out.iter().flatten().flatten())
                    .map(|(a, b)| (a - b).norm())
                    .fold(0.0, f64::max)
            });
            println!(
                "{how:?} (round {round}): {:.2} ms per frame wall, {:.2} ms CPU; max distance to Auto {}",
                wall * 1e3 / frames as f64,
                cpu_s * 1e3 / frames as f64,
                dev.map_or("-".into(), |d| format!("{d:.3e} m"))
            );
            if reference.is_none() {
                reference = Some(out);
            }
        }
    }
}

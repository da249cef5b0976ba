//! The GPDM speed goal end to end (docs/PERFORMANCE.md): 100 variations of a 100-frame motion, decoded to whole-body
//! meshes, on 2 cores. Loads a trained variation model (default: the demo's
//! `out/work/variation/locomotion.model`), samples 100 latent trajectories of 100 frames for
//! every body part (HMC, burn-in and step-size adaptation included), decodes every frame of
//! every part (3DV eq. 12) and assembles the body (`Assembly::Average`), in memory, no file writing.
//! Prints the time of each step for the old path (one chain per part, exact decoding,
//! per-variation `Decoder::decode`) and the fast path, measured back to back.
//!
//! Options: `--help`.
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/body_budget out/work/variation/locomotion.model

use std::time::Instant;

use gpdm::hmc::HmcOptions;
use mesh_core::artifact::Artifact;
use mesh_core::rigid::RigidMotion;
use nalgebra::DMatrix;
use rayon::prelude::*;
use variation::reconstruct::{Assembly, Decoder};
use variation::sample::{default_hmc, sequence_variations_len, Sampler};
use variation::train::VariationModel;

/// CPU seconds of this process so far (user + system, /proc/self/stat, 100 ticks/s): with
/// other jobs on the machine, CPU time is the load-independent figure ("on 2 cores" = wall
/// ≈ CPU / 2 when the two threads are busy).
fn cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit(") ").next().unwrap_or("");
    let f: Vec<f64> = rest.split(' ').filter_map(|x| x.parse().ok()).collect();
    // Fields after the name: state(skipped, not numeric), ppid..., utime = 14th, stime = 15th.
    f.get(10).copied().unwrap_or(0.0) / 100.0 + f.get(11).copied().unwrap_or(0.0) / 100.0
}

/// Fast-path decoding check: max |fast − old| (m) over the first variation's frames.
fn max_dev(a: &[nalgebra::Vector3<f64>], b: &[Vec<nalgebra::Vector3<f64>>]) -> f64 {
    b.iter()
        .flatten()
        .zip(a)
        .map(|(x, y)| (x - y).abs().max())
        .fold(0.0, f64::max)
}

/// 100 variations of a 100-frame motion on a trained model, decoded to whole-body meshes.
#[derive(clap::Parser)]
struct Cli {
    /// A trained variation model.
    #[arg(default_value = "out/work/variation/locomotion.model")]
    model: String,
    /// HMC samples the old path times (scaled to 100).
    #[arg(long, default_value_t = 10)]
    old_samples: usize,
    /// Do not time the old path.
    #[arg(long)]
    skip_old: bool,
    /// The fast path samples by `Sampler::Ancestral` instead of HMC.
    #[arg(long)]
    ancestral: bool,
    /// The fast path's HMC: burn-in, thin, leapfrog steps, chains per part.
    #[arg(long, value_parser = parse_hmc, default_value = "30,1,5,2")]
    fast: [usize; 4],
    /// Kernel-basis bound at the training points (m).
    #[arg(long, default_value_t = 2e-7)]
    tol: f64,
    /// HMC settings to sweep (burn-in, thin, leapfrog steps, chains per part), repeatable.
    #[arg(long, value_parser = parse_hmc)]
    hmc: Vec<[usize; 4]>,
    /// Variations per fused GEMM.
    #[arg(long, default_value_t = 1)]
    batch: usize,
    /// Vertices per fused block.
    #[arg(long, default_value_t = variation::reconstruct::FUSED_BLOCK_VERTICES)]
    block: usize,
    /// After sampling, only the fused decoding, this many times (a profiling aid).
    #[arg(long)]
    fused_only: Option<usize>,
}

/// `B,T,L,C`: burn-in, thin, leapfrog steps, chains.
fn parse_hmc(s: &str) -> Result<[usize; 4], String> {
    let v: Vec<usize> = s.split(',').map(|x| x.parse().map_err(|_| format!("{x:?} is not a count"))).collect::<Result<_, _>>()?;
    v.try_into().map_err(|_| "expected four counts B,T,L,C".to_string())
}

/// Frames of each variation.
const LEN: usize = 100;
/// Variations sampled.
const N: usize = 100;
/// The training sequence whose variations are sampled.
const SEQUENCE: usize = 0;

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let model = load(&cli.model);
    let start = model.sequences[SEQUENCE].start_pose;
    time_energy(&model);
    if !cli.hmc.is_empty() {
        sweep_hmc(&model, &pool, &cli.hmc);
    }
    fast_path(&model, &pool, &cli, &start);
    // `--fused-only` is a profiling aid: it stops after the fast path's fused decoding.
    if cli.fused_only.is_none() && !cli.skip_old {
        old_path(&model, &pool, cli.old_samples, &start);
    }
}

/// The variation model at `path`, its parts and load time printed; exits 1 when it cannot be
/// read.
fn load(path: &str) -> VariationModel {
    let t = Instant::now();
    let model = match VariationModel::load(path) {
        Ok(m) => m,
        Err(e) => {
            // NOTE(next): fall back to a synthetic multi-part model when no demo model exists.
            eprintln!("body_budget: {e} (train one with `make variation` first)");
            std::process::exit(1);
        }
    };
    println!(
        "model {path}: {} parts (D = {:?}), N = {:?}; loaded in {:.2} s",
        model.parts.len(),
        model
            .parts
            .iter()
            .map(|p| p.gpdm.y.ncols())
            .collect::<Vec<_>>(),
        model.parts[0].gpdm.seq_lens,
        t.elapsed().as_secs_f64()
    );
    model
}

/// Prints the cost of one HMC energy + gradient ([`LEN`]-frame trajectory) per part, one thread.
fn time_energy(model: &VariationModel) {
    use gpdm::hmc::{Energy, TrajectoryEnergy};
    let len = LEN;
    let dec = Decoder::new(model, &mut Vec::new()).unwrap();
    for (k, pr) in dec.predictors.iter().enumerate() {
        let x1: Vec<f64> = model.parts[k].gpdm.x.row(0).iter().copied().collect();
        let e = TrajectoryEnergy::new(pr, &x1, len).unwrap();
        let q = e.free_coords(&pr.mean_trajectory(&x1, len).unwrap());
        let mut g = vec![0.0; q.len()];
        let reps = 300;
        let t = Instant::now();
        for _ in 0..reps {
            std::hint::black_box(e.energy_grad(&q, &mut g));
        }
        let ms = t.elapsed().as_secs_f64() * 1e3 / reps as f64;
        let m = pr.dynamics_inputs().nrows();
        println!("part {k}: energy+gradient {ms:.3} ms (M = {m}, T = {len})");
    }
}

/// Prints, for each HMC setting (burn-in, thin, leapfrog steps, chains per part), the time of
/// [`N`] samples, the acceptance and the diversity of the samples.
fn sweep_hmc(model: &VariationModel, pool: &rayon::ThreadPool, settings: &[[usize; 4]]) {
    let (len, n, s) = (LEN, N, SEQUENCE);
    let dec = Decoder::new(model, &mut Vec::new()).unwrap();
    let starts: Vec<DMatrix<f64>> = dec
        .predictors
        .iter()
        .enumerate()
        .map(|(k, pr)| {
            let x1: Vec<f64> = model.parts[k].gpdm.x.row(0).iter().copied().collect();
            pr.mean_trajectory(&x1, len).unwrap()
        })
        .collect();
    for &[burn_in, thin, leapfrog, chains] in settings {
        let opts = hmc_options(n, burn_in, thin, leapfrog);
        let t = Instant::now();
        let (vars, stats) = pool
            .install(|| sequence_variations_len(&dec, s, len, Sampler::Hmc, 1.0, &opts, chains))
            .unwrap();
        let secs = t.elapsed().as_secs_f64();
        let (pair, to_mean) = diversity(&vars, &starts);
        let acc: Vec<f64> = stats.iter().map(|c| c.accept_rate).collect();
        let burn_acc: Vec<f64> = stats.iter().map(|c| c.burn_in_accept_rate).collect();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        println!(
            "HMC burn-in {burn_in}, thin {thin}, {leapfrog} leapfrog, {chains} chain(s)/part: {secs:.3} s for {} samples; acceptance {:.2} (burn-in {:.2}); latent RMS distance pairwise {pair:.4}, to mean prediction {to_mean:.4}",
            vars.len(),
            mean(&acc),
            mean(&burn_acc)
        );
    }
}

/// The default HMC settings for `n` samples with the burn-in, thinning and leapfrog steps given.
fn hmc_options(n: usize, burn_in: usize, thin: usize, leapfrog: usize) -> HmcOptions {
    HmcOptions { n_samples: n, burn_in, thin, leapfrog_steps: leapfrog, ..default_hmc(n, 0) }
}

/// The fast path: kernel-basis decoder, sampling by `--fast` HMC (or ancestral), then decoding
/// and assembling every variation, bulk and fused, checked against exact decoding; prints each
/// step's time; with `--fused-only`, only the fused decoding after the sampling.
fn fast_path(model: &VariationModel, pool: &rayon::ThreadPool, cli: &Cli, start: &RigidMotion) {
    let (len, n, s) = (LEN, N, SEQUENCE);
    let (fast, batch, block, tol) = (cli.fast, cli.batch, cli.block, cli.tol);
    let t = Instant::now();
    let (dec, info) = pool
        .install(|| Decoder::with_pose_basis(model, tol, &mut Vec::new()))
        .unwrap();
    let setup = t.elapsed().as_secs_f64();
    let [burn_in, thin, leapfrog, chains] = fast;
    let opts = hmc_options(n, burn_in, thin, leapfrog);
    let sampler = if cli.ancestral {
        Sampler::Ancestral
    } else {
        Sampler::Hmc
    };
    println!("fast path sampler: {sampler:?}");
    let (t, c) = (Instant::now(), cpu());
    let (vars, _) = pool
        .install(|| sequence_variations_len(&dec, s, len, sampler, 1.0, &opts, chains))
        .unwrap();
    let (hmc, hmc_cpu) = (t.elapsed().as_secs_f64(), cpu() - c);
    time_one_variation(model, &dec, &vars, start);
    if let Some(reps) = cli.fused_only {
        time_fused_only(pool, &dec, &vars, start, batch, block, reps);
        return;
    }
    let (first, decode, decode_cpu) = compare_fused(model, pool, &dec, &vars, start, batch, block, hmc, hmc_cpu);
    let exact = Decoder::new(model, &mut Vec::new()).unwrap();
    let old0 = exact
        .decode::<rand_chacha::ChaCha8Rng>(&vars[0], start, Assembly::Average, None)
        .unwrap();
    let dev = max_dev(&first, &old0);
    let nv = model.template.len();
    let dev0 = max_dev(&first[..nv], &old0[..1]);
    let bounds: Vec<f64> = dec
        .predictors
        .iter()
        .zip(&vars[0])
        .map(|(p, x)| p.basis_error_bound(x).unwrap_or(0.0) * 1e3)
        .collect();
    println!("variation 0: max deviation frame 0 {:.4} mm, all frames {:.4} mm; certified part bounds (mm) {bounds:?}", dev0 * 1e3, dev * 1e3);
    println!(
        "fast: setup {setup:.2} s (kernel bases: rank, bound at training points mm {:?}); sampling {sampler:?} (HMC settings: burn-in {burn_in}, thin {thin}, {leapfrog} leapfrog, {chains} chains/part) {hmc:.3} s (CPU {hmc_cpu:.2} s); decode+assemble {} variations x {len} frames x {} vertices {decode:.3} s (CPU {decode_cpu:.2} s; max deviation from exact decoding {:.4} mm); total {:.3} s (CPU {:.2} s)",
        info.iter().map(|(r, e)| (*r, (e * 1e4).round() / 10.0)).collect::<Vec<_>>(),
        vars.len(),
        model.template.len(),
        dev * 1e3,
        hmc + decode,
        hmc_cpu + decode_cpu
    );
}

/// Prints the time of one variation on this thread: the part GEMMs alone, then the whole decode
/// (a first call, then a second).
fn time_one_variation(model: &VariationModel, dec: &Decoder, vars: &[Vec<DMatrix<f64>>], start: &RigidMotion) {
    let len = LEN;
    let t = Instant::now();
    for (k, pr) in dec.predictors.iter().enumerate() {
        let mut buf = vec![0.0; pr.pose_dim() * len];
        pr.pose_mean_cols(&vars[0][k], &mut buf).unwrap();
        std::hint::black_box(&buf);
    }
    let gemm = t.elapsed().as_secs_f64();
    let mut scratch = variation::reconstruct::DecodeScratch::default();
    let mut out = vec![nalgebra::Vector3::zeros(); len * model.template.len()];
    let t = Instant::now();
    dec.decode_average_into(&vars[0], start, &mut scratch, &mut out)
        .unwrap();
    let first = t.elapsed().as_secs_f64();
    let t = Instant::now();
    dec.decode_average_into(&vars[1], start, &mut scratch, &mut out)
        .unwrap();
    println!(
        "one variation, one thread: part poses {:.1} ms; decode_average_into {:.1} ms (first call {:.1} ms)",
        gemm * 1e3,
        t.elapsed().as_secs_f64() * 1e3,
        first * 1e3
    );
}

/// Profiling aid (perf): only the fused decoding of `vars`, repeated `reps` times.
fn time_fused_only(pool: &rayon::ThreadPool, dec: &Decoder, vars: &[Vec<DMatrix<f64>>], start: &RigidMotion, batch: usize, block: usize, reps: usize) {
    let fused = pool
        .install(|| dec.fused(Assembly::Average))
        .unwrap()
        .with_block_vertices(block);
    let t = Instant::now();
    for _ in 0..reps {
        pool.install(|| {
            fused.decode_average_many(vars, start, batch, |_, f| {
                std::hint::black_box(f);
            })
        })
        .unwrap();
    }
    println!(
        "fused only: {:.3} s per 100 variations",
        t.elapsed().as_secs_f64() / reps as f64
    );
}

/// Decodes and assembles every variation in bulk, then fused and vertex-blocked (no D × T
/// intermediate), and prints both times and how far they differ (`hmc`, `hmc_cpu`: the
/// sampling's seconds, for the total). Returns variation 0's frames from the bulk decoding and
/// the bulk decoding's wall and CPU seconds.
#[allow(clippy::too_many_arguments)]
fn compare_fused(
    model: &VariationModel,
    pool: &rayon::ThreadPool,
    dec: &Decoder,
    vars: &[Vec<DMatrix<f64>>],
    start: &RigidMotion,
    batch: usize,
    block: usize,
    hmc: f64,
    hmc_cpu: f64,
) -> (Vec<nalgebra::Vector3<f64>>, f64, f64) {
    let len = LEN;
    let sum = std::sync::Mutex::new(0.0);
    let first = std::sync::Mutex::new(Vec::new());
    let (t, c) = (Instant::now(), cpu());
    pool.install(|| {
        dec.decode_average_many(vars, start, |k, frames| {
            let s: f64 = frames.iter().map(|v| v.x + v.y + v.z).sum();
            *sum.lock().unwrap() += s;
            if k == 0 {
                *first.lock().unwrap() = frames.to_vec();
            }
        })
    })
    .unwrap();
    let (decode, decode_cpu) = (t.elapsed().as_secs_f64(), cpu() - c);
    let t = Instant::now();
    let fused = pool
        .install(|| dec.fused(Assembly::Average))
        .unwrap()
        .with_block_vertices(block);
    let fsetup = t.elapsed().as_secs_f64();
    {
        let mut scratch = variation::reconstruct::FusedScratch::default();
        let mut out = vec![nalgebra::Vector3::zeros(); len * model.template.len()];
        fused
            .decode_average_into(&vars[0], start, &mut scratch, &mut out)
            .unwrap();
        let t = Instant::now();
        fused
            .decode_average_into(&vars[1], start, &mut scratch, &mut out)
            .unwrap();
        println!(
            "fused: one variation, one thread: {:.1} ms",
            t.elapsed().as_secs_f64() * 1e3
        );
    }
    let fsum = std::sync::Mutex::new(0.0);
    let ffirst = std::sync::Mutex::new(Vec::new());
    let (t, c) = (Instant::now(), cpu());
    pool.install(|| {
        fused.decode_average_many(vars, start, batch, |k, frames| {
            let s: f64 = frames.iter().map(|v| v.x + v.y + v.z).sum();
            *fsum.lock().unwrap() += s;
            if k == 0 {
                *ffirst.lock().unwrap() = frames.to_vec();
            }
        })
    })
    .unwrap();
    let (fdecode, fdecode_cpu) = (t.elapsed().as_secs_f64(), cpu() - c);
    let fdev = first
        .lock()
        .unwrap()
        .iter()
        .zip(ffirst.lock().unwrap().iter())
        .map(|(a, b)| (a - b).abs().max())
        .fold(0.0, f64::max);
    println!(
        "fused (batch {batch}): setup {fsetup:.2} s; decode+assemble {} variations {fdecode:.3} s (CPU {fdecode_cpu:.2} s) vs bulk {decode:.3} s (CPU {decode_cpu:.2} s): {:.2}x wall; max |fused - bulk| variation 0: {fdev:.2e} m; checksum difference {:.2e}; total with sampling {:.3} s (CPU {:.2} s)",
        vars.len(),
        decode / fdecode,
        (*fsum.lock().unwrap() - *sum.lock().unwrap()).abs(),
        hmc + fdecode,
        hmc_cpu + fdecode_cpu
    );
    (first.into_inner().unwrap(), decode, decode_cpu)
}

/// The old path: the stage's defaults (one chain per part, burn-in 200, thin 10, 20 leapfrog
/// steps), `old_n` samples timed and scaled to [`N`]; exact decoding of `old_n` variations,
/// scaled likewise.
fn old_path(model: &VariationModel, pool: &rayon::ThreadPool, old_n: usize, start: &RigidMotion) {
    let (len, n, s) = (LEN, N, SEQUENCE);
    let t = Instant::now();
    let dec = Decoder::new(model, &mut Vec::new()).unwrap();
    let setup = t.elapsed().as_secs_f64();
    let opts = default_hmc(old_n, 0);
    let (t, c) = (Instant::now(), cpu());
    let (vars, _) = pool
        .install(|| sequence_variations_len(&dec, s, len, Sampler::Hmc, 1.0, &opts, 1))
        .unwrap();
    let (hmc, hmc_cpu) = (t.elapsed().as_secs_f64(), cpu() - c);
    let burn = opts.burn_in as f64;
    let scale = (burn + (n * opts.thin) as f64) / (burn + (old_n * opts.thin) as f64);
    let hmc100 = hmc * scale;
    let (t, c) = (Instant::now(), cpu());
    let out: Vec<usize> = pool.install(|| {
        vars.par_iter()
            .map(|v| {
                dec.decode::<rand_chacha::ChaCha8Rng>(v, start, Assembly::Average, None)
                    .unwrap()
                    .len()
            })
            .collect()
    });
    let dscale = n as f64 / out.len() as f64;
    let (decode, decode_cpu) = (t.elapsed().as_secs_f64() * dscale, (cpu() - c) * dscale);
    println!(
        "old: setup {setup:.2} s; HMC {old_n} samples {hmc:.2} s -> 100 samples {hmc100:.2} s (CPU {:.1} s; scaled); decode+assemble 100 variations {decode:.2} s (CPU {decode_cpu:.1} s; scaled from {}); total {:.2} s (CPU {:.1} s)",
        hmc_cpu * scale,
        out.len(),
        hmc100 + decode,
        hmc_cpu * scale + decode_cpu
    );
}

/// Mean over parts of (mean pairwise RMS latent distance between samples, mean RMS distance of
/// a sample to the mean prediction); RMS over frames and coordinates.
fn diversity(vars: &[Vec<DMatrix<f64>>], starts: &[DMatrix<f64>]) -> (f64, f64) {
    let rms = |a: &DMatrix<f64>, b: &DMatrix<f64>| (a - b).norm() / (a.len() as f64).sqrt();
    let parts = starts.len();
    let (mut pair, mut to_mean) = (0.0, 0.0);
    for k in 0..parts {
        let mut sum = 0.0;
        let mut cnt = 0;
        for i in 0..vars.len() {
            for j in i + 1..vars.len() {
                sum += rms(&vars[i][k], &vars[j][k]);
                cnt += 1;
            }
        }
        pair += sum / cnt.max(1) as f64;
        to_mean += vars.iter().map(|v| rms(&v[k], &starts[k])).sum::<f64>() / vars.len() as f64;
    }
    (pair / parts as f64, to_mean / parts as f64)
}

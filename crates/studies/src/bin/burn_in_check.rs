//! Stationarity of the HMC chains of `hmc-sample` for a given burn-in and chain start.
//!
//! For every (training sequence, part) chain of a trained model, at the settings of `make
//! variation` (κ = 0.3, 5 samples, thin 10, 20 leapfrog steps), the energy (negative log
//! density, `gpdm::hmc::TrajectoryEnergy`) of the kept samples is compared with that of exact
//! draws of the same density (`gpdm::ancestral`, the stationary distribution itself). A chain
//! that has not reached stationarity keeps a lower energy than the exact draws (it starts at
//! the mean prediction, the centre of the density). Per setting the table gives, over all
//! chains, the mean of `z = (mean kept energy − mean exact energy) / sd of exact energy`, and
//! the mean latent RMS distance of the kept samples from the mean prediction relative to that
//! of the exact draws (the spread of the variations, 1 when it matches). Starts: `mean` (the
//! paper's), `ancestral` (an exact draw), `training` (the sequence's learned latent trajectory).
//!
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/burn_in_check out/work/variation/locomotion.model --seeds 8 --settings mean:200,mean:1000,ancestral:50

use gpdm::ancestral::sample_trajectories_ancestral;
use gpdm::hmc::{sample, sample_trajectories_scaled, ChainStart, Energy, TrajectoryEnergy};
use mesh_core::artifact::Artifact;
use nalgebra::DMatrix;
use rayon::prelude::*;
use variation::reconstruct::Decoder;
use variation::sample::{default_hmc, mix};
use variation::train::VariationModel;

const KAPPA: f64 = 0.3;

fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, v.sqrt())
}

fn rms(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    ((a - b).norm_squared() / a.nrows() as f64).sqrt()
}

/// Stationarity of the HMC chains for a given burn-in and chain start: kept samples against
/// exact draws of the same density.
#[derive(clap::Parser)]
struct Cli {
    /// A trained variation model.
    #[arg(default_value = "out/work/variation/locomotion.model")]
    model: String,
    /// Seeds per chain.
    #[arg(long, default_value_t = 8)]
    seeds: u64,
    /// START:BURN settings, START one of mean, ancestral, learned or training (the sequence's
    /// learned trajectory).
    #[arg(long, value_delimiter = ',', value_parser = parse_setting,
          default_value = "mean:200,mean:1000,ancestral:20,ancestral:50")]
    settings: Vec<(Option<ChainStart>, usize)>,
}

/// `START:BURN`; a start of None: the training trajectory.
fn parse_setting(s: &str) -> Result<(Option<ChainStart>, usize), String> {
    let (a, b) = s.split_once(':').ok_or("expected START:BURN")?;
    let start = match a {
        "mean" => Some(ChainStart::MeanPrediction),
        "ancestral" => Some(ChainStart::Ancestral),
        "learned" => Some(ChainStart::Learned),
        "training" => None,
        _ => return Err(format!("start {a:?} is not mean, ancestral, learned or training")),
    };
    Ok((start, b.parse().map_err(|_| format!("burn-in {b:?} is not a count"))?))
}

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    let model = VariationModel::load(&cli.model).expect("a trained variation model");
    let chains = Chains::new(&model);
    let reference = chains.references();
    println!(
        "{}: {} chains (sequences × parts), {} latent points, {} seeds, κ = {KAPPA}",
        cli.model,
        chains.chains.len(),
        chains.len,
        cli.seeds
    );
    println!("setting | mean z (sd over chains) | max |z| | chains |z|>2 | spread ratio | accept | energy evals");
    for &(start, burn_in) in &cli.settings {
        let runs = chains.run(start, burn_in, cli.seeds, &reference);
        report(start, burn_in, &runs);
    }
}

/// The chains `hmc-sample` runs on a trained model, one per training sequence and part.
struct Chains<'a> {
    model: &'a VariationModel,
    dec: Decoder<'a>,
    /// Latent points per chain (the model's frames at its stride).
    len: usize,
    /// `(sequence, part)` of each chain.
    chains: Vec<(usize, usize)>,
}

/// A chain's exact draws: mean and standard deviation of their energies, and their mean latent
/// RMS distance from the mean prediction.
struct Reference {
    e: (f64, f64),
    dist: f64,
}

/// One chain's kept samples at one setting over every seed: `z` of their mean energy against
/// the exact draws', their spread relative to the draws', the mean acceptance rate, and the
/// energy evaluations.
struct Run {
    z: f64,
    spread: f64,
    accept: f64,
    evaluations: usize,
}

impl<'a> Chains<'a> {
    fn new(model: &'a VariationModel) -> Self {
        let dec = Decoder::new(model, &mut Vec::new()).expect("decoder");
        let len = variation::frame_stride::covering_count(model.n_frames(), model.stride);
        let chains = (0..model.sequences.len()).flat_map(|s| (0..model.parts.len()).map(move |k| (s, k))).collect();
        Chains { model, dec, len, chains }
    }

    /// The first latent point of sequence `s` of part `k`, and the energy of its trajectories at
    /// [`KAPPA`].
    fn energy(&self, s: usize, k: usize) -> (DMatrix<f64>, Vec<f64>, TrajectoryEnergy<'_>) {
        let pr = &self.dec.predictors[k];
        let x = self.model.parts[k].gpdm.sequence_latent(s).expect("sequence");
        let x1: Vec<f64> = x.row(0).iter().copied().collect();
        let energy = TrajectoryEnergy::new(pr, &x1, self.len).and_then(|e| e.with_variance_scale(KAPPA)).expect("energy");
        (x, x1, energy)
    }

    /// Each chain's reference: 400 exact draws of its density.
    fn references(&self) -> Vec<Reference> {
        let len = self.len;
        self.chains
            .par_iter()
            .map(|&(s, k)| {
                let pr = &self.dec.predictors[k];
                let (_, x1, energy) = self.energy(s, k);
                let mean = pr.mean_trajectory(&x1, len).expect("mean");
                let draws = sample_trajectories_ancestral(pr, &x1, len, 400, 0xE4AC7, KAPPA).expect("draws");
                let mut g = vec![0.0; energy.dim()];
                let es: Vec<f64> = draws.iter().map(|d| energy.energy_grad(&energy.free_coords(d), &mut g).expect("finite")).collect();
                let dist = draws.iter().map(|d| rms(d, &mean)).sum::<f64>() / draws.len() as f64;
                Reference { e: mean_sd(&es), dist }
            })
            .collect()
    }

    /// Every chain run `seeds` times at `make variation`'s settings from `start` (None: the
    /// sequence's training trajectory) with `burn_in` iterations, against its `reference`.
    fn run(&self, start: Option<ChainStart>, burn_in: usize, seeds: u64, reference: &[Reference]) -> Vec<Run> {
        let len = self.len;
        self.chains
            .par_iter()
            .enumerate()
            .map(|(c, &(s, k))| {
                let pr = &self.dec.predictors[k];
                let (x, x1, energy) = self.energy(s, k);
                let template = DMatrix::from_fn(len, x.ncols(), |t, j| x[(t.min(x.nrows() - 1), j)]);
                let mean = pr.mean_trajectory(&x1, len).expect("mean");
                let mut g = vec![0.0; energy.dim()];
                let (mut es, mut dists, mut acc, mut evals) = (Vec::new(), Vec::new(), 0.0, 0);
                for seed in 0..seeds {
                    let mut o = default_hmc(5, mix(seed, s as u64 + 1, k as u64 + 1));
                    o.burn_in = burn_in;
                    let (trajs, res) = match start {
                        Some(start) => {
                            o.start = start;
                            sample_trajectories_scaled(pr, &template, &o, KAPPA).expect("chain")
                        }
                        None => {
                            let res = sample(&energy, &energy.free_coords(&template), &o).expect("chain");
                            (res.samples.iter().map(|q| energy.trajectory(q)).collect(), res)
                        }
                    };
                    for t in &trajs {
                        es.push(energy.energy_grad(&energy.free_coords(t), &mut g).expect("e"));
                        dists.push(rms(t, &mean));
                    }
                    acc += res.accept_rate;
                    evals += res.evaluations;
                }
                let r = &reference[c];
                Run {
                    z: (mean_sd(&es).0 - r.e.0) / r.e.1,
                    spread: dists.iter().sum::<f64>() / dists.len() as f64 / r.dist,
                    accept: acc / seeds as f64,
                    evaluations: evals,
                }
            })
            .collect()
    }
}

/// Prints the table's row of one setting.
fn report(start: Option<ChainStart>, burn_in: usize, runs: &[Run]) {
    let zs: Vec<f64> = runs.iter().map(|r| r.z).collect();
    let (zm, zsd) = mean_sd(&zs);
    let zmax = zs.iter().fold(0.0f64, |m, z| m.max(z.abs()));
    let over = zs.iter().filter(|z| z.abs() > 2.0).count();
    let spread = runs.iter().map(|r| r.spread).sum::<f64>() / runs.len() as f64;
    let acc = runs.iter().map(|r| r.accept).sum::<f64>() / runs.len() as f64;
    let evals: usize = runs.iter().map(|r| r.evaluations).sum();
    let name = match start {
        Some(ChainStart::MeanPrediction) => "mean",
        Some(ChainStart::Ancestral) => "ancestral",
        Some(ChainStart::Learned) => "learned",
        None => "training",
    };
    println!(
        "{name}:{burn_in} | {zm:+.2} ({zsd:.2}) | {zmax:.2} | {over}/{} | {spread:.3} | {acc:.2} | {evals}",
        zs.len()
    );
}

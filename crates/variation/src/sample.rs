//! `hmc-sample`: variations of latent trajectories (paper §6) and of blends (§7).
//!
//! For a training sequence, every part's chain starts from the mean prediction (3DV eqs. 8-10) from
//! the sequence's first learned latent point and draws whole trajectories by Hybrid Monte Carlo
//! with the first point fixed (`gpdm::hmc::sample_trajectories`: burn-in with step-size
//! adaptation toward the target acceptance, then thinning). Parts are sampled independently
//! (one of the paper's sources of variation); variation `k` takes sample `k` of every part.
//! For a blend weight `w*`, `X̃_{w*}` is made from random variants of the bounding trajectories
//! of `W ∪ {0, 1}` blended in proportion (`gpdm::blend::blend_pair`): only the two bounding
//! sequences are sampled ([`blend_bounding`]).
//! Every chain has its own seed derived from `(seed, sequence, part)`: same seed, same samples.
//! A training-free baseline to both GPDM samplers, `Sampler::MotionMatching`, recombines the
//! learned latent points of all parts jointly instead ([`matched_variations`],
//! [`matched_blend_variations`]; the algorithm in [`crate::motion_matching`]).

use gpdm::ancestral::sample_trajectories_on_data;
use gpdm::hmc::{sample_trajectories_scaled, ChainStart, HmcOptions};
use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::frame_stride;
use crate::motion_matching::{self, Examples, MatchOptions, Normaliser, Start};
use crate::reconstruct::Decoder;
use crate::train::VariationModel;

/// Statistics of one chain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChainStats {
    pub sequence: String,
    pub part: String,
    pub accept_rate: f64,
    pub burn_in_accept_rate: f64,
    pub step_size: f64,
    /// The chain started at the sequence's learned latent trajectory because the mean
    /// prediction left the learned data (`gpdm::hmc::leaves_the_data`).
    #[serde(default)]
    pub started_at_learned: bool,
    /// Points of the chain's kept trajectories off the learned data (3DV eq. 13's variance
    /// above `gpdm::hmc::OFF_DATA_VARIANCE` of the prior's): with `Sampler::Ancestral` those
    /// left after `gpdm::ancestral::MAX_REDRAWS` redraws.
    #[serde(default)]
    pub off_data_points: usize,
    /// The largest share of the pose prior's variance (3DV eq. 13) at any point of the kept
    /// trajectories: near 0 on the learned data, 1 where the training poses say nothing.
    #[serde(default)]
    pub max_pose_variance_ratio: f64,
    /// With `Sampler::Ancestral`: the draws left the learned data, so this part's variants are
    /// the paper's HMC chains.
    #[serde(default)]
    pub hmc_instead: bool,
}

/// How trajectories are drawn from the density of a part's GPDM dynamics given the first point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// Hybrid Monte Carlo (the paper's sampler): burn-in with step-size adaptation, thinning.
    #[default]
    Hmc,
    /// Independent draws of the same density restricted to the learned data, one forward pass
    /// each (`gpdm::ancestral::sample_trajectories_on_data`: a point off the data is redrawn);
    /// burn-in, thinning and chains do not apply. A part whose draws still leave the data
    /// (where the dynamics lead them off) takes the paper's chains instead, as with `Hmc`.
    Ancestral,
    /// A training-free baseline, not the GPDM's density: generative motion matching (GenMM)
    /// over the learned latent points of all parts jointly ([`crate::motion_matching`]);
    /// variance scale, burn-in, thinning and chains do not apply.
    #[value(name = "motion-matching")]
    #[serde(rename = "motion-matching")]
    MotionMatching,
}

impl Sampler {
    /// From its command-line name (`hmc`, `ancestral`, `motion-matching`).
    pub fn from_name(name: &str) -> Option<Sampler> {
        match name {
            "hmc" => Some(Sampler::Hmc),
            "ancestral" => Some(Sampler::Ancestral),
            "motion-matching" => Some(Sampler::MotionMatching),
            _ => None,
        }
    }
}

/// Where every HMC chain starts (`hmc-sample --hmc-start`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum HmcStart {
    /// The mean prediction from the first point (3DV eq. 8, the paper's), burn-in 200.
    #[default]
    Mean,
    /// An exact draw of the sampled density (`gpdm::ancestral`): the chain is stationary from
    /// its first iteration, and a burn-in of 50 only adapts the step size.
    Ancestral,
    /// The sequence's learned latent trajectory.
    Learned,
}

impl HmcStart {
    /// The chain start of `gpdm::hmc`.
    pub fn chain_start(self) -> ChainStart {
        match self {
            HmcStart::Mean => ChainStart::MeanPrediction,
            HmcStart::Ancestral => ChainStart::Ancestral,
            HmcStart::Learned => ChainStart::Learned,
        }
    }

    /// Burn-in iterations by default: 200 from the mean prediction (the chain has to move away
    /// from the centre of the density; `burn_in_check` in crates/studies measures how far it gets), 50
    /// from an exact draw (step-size adaptation only).
    pub fn default_burn_in(self) -> usize {
        match self {
            HmcStart::Mean => 200,
            HmcStart::Ancestral | HmcStart::Learned => 50,
        }
    }
}

/// Default scale κ of every one-step variance of the sampled dynamics (`hmc-sample
/// --variance-scale`; 1 is the paper's density). At 1 the learned dynamics noise makes every frame
/// jitter: foot sliding 10-20x the captures' and variations scattered 0.7-1.5 m apart; at 0.3
/// sliding 2-8x, and the variations still differ from their source
/// (docs/studies/14-variance-scale.md).
pub const VARIANCE_SCALE: f64 = 0.3;

/// `variations[k][part]`: latent trajectory (T × d) of part `part` in variation `k`.
pub type Variations = Vec<Vec<DMatrix<f64>>>;

/// Sampler defaults for variations: decorrelated draws (thin 10) after 200 burn-in iterations.
pub fn default_hmc(n: usize, seed: u64) -> HmcOptions {
    HmcOptions {
        n_samples: n,
        burn_in: 200,
        thin: 10,
        leapfrog_steps: 20,
        initial_step: 0.01,
        target_accept: 0.7,
        seed,
        start: ChainStart::MeanPrediction,
    }
}

/// The learned latent trajectory `x` (T × d) cut or extended to `len` points. Past its end it
/// is replayed: from the learned point nearest the end's next step extrapolated
/// (`2 x_T − x_{T−1}`), among those at least a quarter of the trajectory (and 2 points) before
/// the end, then on to the end again. A learned gait cycle thus continues into its next cycle,
/// and every point stays a learned one (a chain started here where the mean prediction leaves
/// the data stays on the data past the capture's length, instead of holding the last pose).
pub fn learned_template(x: &DMatrix<f64>, len: usize) -> DMatrix<f64> {
    let t_len = x.nrows();
    if t_len == 0 {
        return DMatrix::zeros(len, x.ncols());
    }
    let gap = (t_len / 4).max(2);
    let mut rows = Vec::with_capacity(len);
    let mut cur = 0usize;
    while rows.len() < len {
        rows.push(cur);
        cur = if cur + 1 < t_len {
            cur + 1
        } else if t_len > gap {
            let next = x.row(cur) * 2.0 - x.row(cur - 1);
            (0..t_len - gap)
                .min_by(|&a, &b| {
                    (x.row(a) - &next).norm_squared().total_cmp(&(x.row(b) - &next).norm_squared())
                })
                .expect("t_len > gap")
        } else {
            cur
        };
    }
    DMatrix::from_fn(len, x.ncols(), |t, c| x[(rows[t], c)])
}

/// A seed for stream `(a, b)` of run `seed` (SplitMix64 finaliser).
pub fn mix(seed: u64, a: u64, b: u64) -> u64 {
    let mut z =
        seed ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// `opts.n_samples` variations of training sequence `s` at its capture length (chains seeded
/// from `opts.seed`).
pub fn sequence_variations(
    dec: &Decoder,
    s: usize,
    sampler: Sampler,
    variance_scale: f64,
    opts: &HmcOptions,
) -> Result<(Variations, Vec<ChainStats>)> {
    if s >= dec.model.sequences.len() {
        return Err(Error::invalid(format!("no training sequence {s}")));
    }
    sequence_variations_len(
        dec,
        s,
        dec.model.n_frames(),
        sampler,
        variance_scale,
        opts,
        1,
    )
}

/// `opts.n_samples` variations of `len` capture frames of training sequence `s` (started at its
/// first latent point; `len` may exceed the sequence's length), every part
/// sampled by `chains` independent chains (each `ceil(n / chains)` samples, its own burn-in).
/// The chains run at the model's training steps (`frame_stride::covering_count(len, stride)`
/// points) and the draws are brought to the capture's rate ([`crate::frame_stride::upsample`]).
/// All (part, chain) pairs run as parallel tasks; chain `c` of part `k` is seeded with
/// `mix(opts.seed, s + 1, k + 1 + c·2³²)` (chain 0: the single-chain seed) and the samples are
/// concatenated by chain, so the result is the same for any number of threads. With
/// [`Sampler::Ancestral`] every part is one task of `opts.n_samples` independent draws (seeded
/// the same way; `chains` and the HMC settings other than the seed are not used), and its
/// statistics report acceptance 1 and step size 0. `variance_scale` κ scales every one-step
/// variance of the dynamics (1: the model's density; `hmc-sample --variance-scale`). With
/// [`Sampler::MotionMatching`] the variations are [`matched_variations`] with the default
/// [`MatchOptions`] (seeded from `opts.seed`; the other settings do not apply).
pub fn sequence_variations_len(
    dec: &Decoder,
    s: usize,
    len: usize,
    sampler: Sampler,
    variance_scale: f64,
    opts: &HmcOptions,
    chains: usize,
) -> Result<(Variations, Vec<ChainStats>)> {
    let model = dec.model;
    let info = model
        .sequences
        .get(s)
        .ok_or_else(|| Error::invalid(format!("no training sequence {s}")))?;
    if chains == 0 {
        return Err(Error::invalid("at least one chain per part is needed"));
    }
    let (chains, per) = match sampler {
        Sampler::Hmc => (chains, opts.n_samples.div_ceil(chains)),
        Sampler::Ancestral => (1, opts.n_samples),
        Sampler::MotionMatching => {
            return matched_variations(dec, s, len, opts.n_samples, opts.seed, &MatchOptions::default())
        }
    };
    let tasks: Vec<(usize, usize)> = (0..model.parts.len())
        .flat_map(|k| (0..chains).map(move |c| (k, c)))
        .collect();
    let frames = len;
    let len = frame_stride::covering_count(frames, model.stride);
    let runs: Vec<Result<(Vec<DMatrix<f64>>, ChainStats)>> = tasks
        .par_iter()
        .map(|&(k, c)| {
            let (pr, pm) = (&dec.predictors[k], &model.parts[k]);
            let x = pm.gpdm.sequence_latent(s).expect("index checked");
            if frames < 2 {
                return Err(Error::invalid(format!(
                    "{}: {frames} frames requested, at least 2 are needed",
                    info.name
                )));
            }
            // The learned trajectory, replayed past its end ([`learned_template`]): its first
            // point and length set the chain, which starts from the mean prediction (3DV eq. 8),
            // or from this trajectory where the mean prediction leaves the learned data.
            let template = learned_template(&x, len);
            let o = HmcOptions {
                n_samples: per,
                seed: mix(opts.seed, s as u64 + 1, k as u64 + 1 + ((c as u64) << 32)),
                ..opts.clone()
            };
            let fail = |e: gpdm::GpdmError| {
                Error::invalid(format!("{} part '{}': {e}", info.name, pm.part.name))
            };
            let (trajs, accept_rate, burn_in_accept_rate, step_size, started_at_learned, hmc_instead) = match sampler {
                Sampler::Hmc => {
                    let (trajs, res) =
                        sample_trajectories_scaled(pr, &template, &o, variance_scale)
                            .map_err(fail)?;
                    if res.started_at_template && c == 0 {
                        mesh_core::warn!(
                            "{} part '{}': the mean prediction leaves the learned data (3DV eq. 13's variance above {} of the prior's); its chains start at the learned trajectory",
                            info.name,
                            pm.part.name,
                            gpdm::hmc::OFF_DATA_VARIANCE
                        );
                    }
                    (
                        trajs,
                        res.accept_rate,
                        res.burn_in_accept_rate,
                        res.step_size,
                        res.started_at_template,
                        false,
                    )
                }
                Sampler::MotionMatching => unreachable!("motion matching returned above"),
                Sampler::Ancestral => {
                    let x1: Vec<f64> = template.row(0).iter().copied().collect();
                    let (drawn, off) = sample_trajectories_on_data(
                        pr,
                        &x1,
                        len,
                        per,
                        o.seed,
                        variance_scale,
                        gpdm::ancestral::REDRAW_VARIANCE,
                    )
                    .map_err(fail)?;
                    if off.iter().all(|&n| n == 0) {
                        (drawn, 1.0, 1.0, 0.0, false, false)
                    } else {
                        // Where the dynamics lead every draw off the data (their mean, or the
                        // noise accumulated along them), this part's variants are the paper's
                        // chains instead: from the mean prediction, or from the learned
                        // trajectory where the mean prediction leaves the data.
                        let o = HmcOptions { start: ChainStart::MeanPrediction, ..o.clone() };
                        let (trajs, res) =
                            sample_trajectories_scaled(pr, &template, &o, variance_scale)
                                .map_err(fail)?;
                        if c == 0 {
                            mesh_core::info!(
                                "{} part '{}': ancestral draws leave the learned data; its variants are HMC chains",
                                info.name,
                                pm.part.name
                            );
                        }
                        (
                            trajs,
                            res.accept_rate,
                            res.burn_in_accept_rate,
                            res.step_size,
                            res.started_at_template,
                            true,
                        )
                    }
                }
            };
            let (mut off_data_points, mut max_pose_variance_ratio) = (0, 0.0f64);
            for x in &trajs {
                let ratios = pr.pose_variance_ratio(x).map_err(fail)?;
                off_data_points += ratios.iter().filter(|&&r| r > gpdm::hmc::OFF_DATA_VARIANCE).count();
                max_pose_variance_ratio = ratios.iter().copied().fold(max_pose_variance_ratio, f64::max);
            }
            let stats = ChainStats {
                sequence: info.name.clone(),
                part: pm.part.name.clone(),
                accept_rate,
                burn_in_accept_rate,
                step_size,
                started_at_learned,
                off_data_points,
                max_pose_variance_ratio,
                hmc_instead,
            };
            Ok((trajs, stats))
        })
        .collect();
    let mut by_part: Vec<Vec<DMatrix<f64>>> = vec![Vec::new(); model.parts.len()];
    let mut stats = Vec::new();
    for (r, &(k, _)) in runs.into_iter().zip(&tasks) {
        let (t, st) = r?;
        by_part[k].extend(
            t.iter()
                .map(|x| frame_stride::upsample(x, model.stride, frames)),
        );
        stats.push(st);
    }
    let n = by_part
        .iter()
        .map(|t| t.len())
        .min()
        .unwrap_or(0)
        .min(opts.n_samples);
    Ok((
        (0..n)
            .map(|k| by_part.iter().map(|t| t[k].clone()).collect())
            .collect(),
        stats,
    ))
}

/// `n` variations of `len` capture frames of training sequence `s` by generative motion
/// matching ([`motion_matching::synthesize`]) over every part's learned latent points side by
/// side, at the model's training steps (`frame_stride::covering_count(len, stride)` rows), then
/// brought to the capture's rate ([`crate::frame_stride::upsample`]) and split into the parts.
/// The examples are sequence `s` alone or every training sequence (`o.examples`); each
/// variation starts (`o.start`) from `s`'s learned trajectory ([`learned_template`] of the joint
/// points, so past its end the parts replay together; with `Start::Phase` from a random point
/// of its first half) or from random crops of the examples, with noise. Variation `k` is seeded with
/// `mix(seed, s + 1, 0x4D4D_0000_0000 + k)`; the variations run as parallel tasks, the result
/// is the same for any number of threads. The per-part statistics report acceptance 1, step
/// size 0 and the points off the learned data as the samplers' do.
pub fn matched_variations(
    dec: &Decoder,
    s: usize,
    len: usize,
    n: usize,
    seed: u64,
    o: &MatchOptions,
) -> Result<(Variations, Vec<ChainStats>)> {
    let m = Matched::new(dec, s, len, n, seed, o)?;
    let parts: Vec<Vec<DMatrix<f64>>> = m.syntheses.iter().map(|y| m.split(&y.rows)).collect();
    let model = dec.model;
    let name = &model.sequences[s].name;
    let mut stats = Vec::with_capacity(model.parts.len());
    for (k, pm) in model.parts.iter().enumerate() {
        let (mut off_data_points, mut max_pose_variance_ratio) = (0, 0.0f64);
        for v in &parts {
            let ratios = dec.predictors[k]
                .pose_variance_ratio(&v[k])
                .map_err(|e| Error::invalid(format!("{name} part '{}': {e}", pm.part.name)))?;
            off_data_points += ratios.iter().filter(|&&r| r > gpdm::hmc::OFF_DATA_VARIANCE).count();
            max_pose_variance_ratio = ratios.iter().copied().fold(max_pose_variance_ratio, f64::max);
        }
        stats.push(ChainStats {
            sequence: name.clone(),
            part: pm.part.name.clone(),
            accept_rate: 1.0,
            burn_in_accept_rate: 1.0,
            step_size: 0.0,
            started_at_learned: true,
            off_data_points,
            max_pose_variance_ratio,
            hmc_instead: false,
        });
    }
    let vars = parts.into_iter().map(|v| m.to_capture_rate(&v)).collect();
    Ok((vars, stats))
}

/// `n` variations of the blend at `w` of training sequences `a` and `b` by motion matching:
/// the variations of the nearest learned weight below `w` ([`blend_entries`]) matched against
/// that sequence alone ([`matched_variations`] with `Examples::Own`), and their matched windows
/// ([`motion_matching::Synthesis`]) applied to the nearest learned weight above `w` too (the
/// sequences are time-aligned, so the same rows are the same moments); the two blended in
/// proportion (§7, `gpdm::blend::blend_pair`). Variation `k` is seeded as variation `k` of the
/// lower sequence.
pub fn matched_blend_variations(
    dec: &Decoder,
    (a, b): (usize, usize),
    w: f64,
    len: usize,
    n: usize,
    seed: u64,
    o: &MatchOptions,
) -> Result<Variations> {
    let entries = blend_entries(dec.model, a, b);
    let lo = entries.iter().rev().find(|e| e.0 <= w);
    let hi = entries.iter().find(|e| e.0 >= w);
    let (Some(&(w1, i1)), Some(&(w2, i2))) = (lo, hi) else {
        return Err(Error::invalid(format!("blend weight {w} outside [0, 1]")));
    };
    let own = MatchOptions { examples: Examples::Own, ..o.clone() };
    let m = Matched::new(dec, i1, len, n, seed, &own)?;
    // The chosen windows name training sequence i1 (the only example): read them from i2.
    let mut upper = vec![DMatrix::zeros(0, 0); dec.model.sequences.len()];
    upper[i1] = m.joint(i2);
    Ok(m.syntheses
        .iter()
        .map(|y| {
            let x = if i1 == i2 {
                y.rows.clone()
            } else {
                let u = motion_matching::blend_patches(&y.chosen, y.patch, y.rows.nrows(), &upper);
                gpdm::blend::blend_pair(&y.rows, w1, &u, w2, w)
            };
            m.to_capture_rate(&m.split(&x))
        })
        .collect())
}

/// Motion-matching syntheses of one sequence, in the joint coordinates (every part's latent
/// points side by side, at the training steps), before they are split into parts.
struct Matched<'a> {
    dec: &'a Decoder<'a>,
    dims: Vec<usize>,
    frames: usize,
    syntheses: Vec<motion_matching::Synthesis>,
}

impl<'a> Matched<'a> {
    fn new(dec: &'a Decoder<'a>, s: usize, len: usize, n: usize, seed: u64, o: &MatchOptions) -> Result<Self> {
        let model = dec.model;
        let info = model
            .sequences
            .get(s)
            .ok_or_else(|| Error::invalid(format!("no training sequence {s}")))?;
        if len < 2 {
            return Err(Error::invalid(format!(
                "{}: {len} frames requested, at least 2 are needed",
                info.name
            )));
        }
        o.check()?;
        let steps = frame_stride::covering_count(len, model.stride);
        let dims: Vec<usize> = model.model_latents(s).iter().map(|x| x.ncols()).collect();
        let mut m = Matched { dec, dims, frames: len, syntheses: Vec::new() };
        let used: Vec<usize> = match o.examples {
            Examples::Own => vec![s],
            Examples::Group => (0..model.sequences.len()).collect(),
        };
        // The examples are matched with every part's block at a unit RMS radius (the
        // synthesis is an average of example rows, so it comes back to the latent coordinates
        // through the inverse map, and the chosen windows apply to the raw points alike).
        let raw: Vec<DMatrix<f64>> = used.iter().map(|&i| m.joint(i)).collect();
        let norm = Normaliser::new(&raw, &m.dims);
        let examples: Vec<DMatrix<f64>> = raw.iter().map(|x| norm.forward(x)).collect();
        let source = m.joint(s);
        // A random phase only where the learned trajectories close into cycles: their replay
        // seams (from the end's extrapolated next step to the nearest point a quarter back or
        // more) no longer than twice their median step. Elsewhere (a jump, a clip not cut to
        // whole cycles) a replay from mid-way jumps, and every variation starts at the source's
        // first point. Every sequence of the group has to close, so that variation `k` of every
        // sequence starts at the same phase (the sequences are time-aligned).
        let closes = (0..model.sequences.len()).all(|i| {
            let x = m.joint(i);
            cycle_closes(&Normaliser::new(std::slice::from_ref(&x), &m.dims).forward(&x))
        });
        m.syntheses = (0..n)
            .into_par_iter()
            .map(|k| {
                let mut rng = ChaCha8Rng::seed_from_u64(mix(seed, s as u64 + 1, 0x4D4D_0000_0000 + k as u64));
                // The phase of variation `k` is drawn from its own stream, the same for every
                // sequence; the learned trajectory from there on, replayed past its end
                // ([`learned_template`]).
                let phase = match o.start {
                    Start::Phase if closes => ChaCha8Rng::seed_from_u64(mix(seed, 0x9A5E, k as u64))
                        .random_range(0..source.nrows().div_ceil(2)),
                    _ => 0,
                };
                let start = norm.forward(&learned_template(&source, steps + phase).rows(phase, steps).into_owned());
                motion_matching::synthesize(&examples, &start, steps, norm.noise_scale(), o, &mut rng)
                    .map(|mut y| {
                        y.rows = norm.inverse(&y.rows);
                        // Example `e` of the synthesis is training sequence `used[e]`.
                        y.chosen.iter_mut().for_each(|c| c.0 = used[c.0]);
                        y
                    })
                    .map_err(|e| Error::invalid(format!("{}: {e}", info.name)))
            })
            .collect::<Result<_>>()?;
        Ok(m)
    }

    /// Training sequence `i`'s learned points of every part side by side, one row per training
    /// step.
    fn joint(&self, i: usize) -> DMatrix<f64> {
        let xs = self.dec.model.model_latents(i);
        let rows = xs.first().map_or(0, |x| x.nrows());
        let mut m = DMatrix::zeros(rows, self.dims.iter().sum());
        let mut c0 = 0;
        for x in &xs {
            m.view_mut((0, c0), (rows, x.ncols())).copy_from(x);
            c0 += x.ncols();
        }
        m
    }

    /// A joint trajectory split into the parts' trajectories.
    fn split(&self, y: &DMatrix<f64>) -> Vec<DMatrix<f64>> {
        let mut c0 = 0;
        self.dims
            .iter()
            .map(|&d| {
                let x = y.columns(c0, d).into_owned();
                c0 += d;
                x
            })
            .collect()
    }

    /// Parts' trajectories at the training steps brought to the capture's rate.
    fn to_capture_rate(&self, parts: &[DMatrix<f64>]) -> Vec<DMatrix<f64>> {
        parts.iter().map(|x| frame_stride::upsample(x, self.dec.model.stride, self.frames)).collect()
    }
}

/// Whether the trajectory `x` closes into a cycle: the gap between its end's extrapolated next
/// step (`2 x_T − x_{T−1}`) and the nearest point at least a quarter of it (and 2 points) before
/// the end, which [`learned_template`] replays from, is at most twice its median step.
pub fn cycle_closes(x: &DMatrix<f64>) -> bool {
    let t_len = x.nrows();
    let gap = (t_len / 4).max(2);
    if t_len <= gap + 1 {
        return false;
    }
    let mut steps: Vec<f64> = (1..t_len).map(|t| (x.row(t) - x.row(t - 1)).norm()).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    let next = x.row(t_len - 1) * 2.0 - x.row(t_len - 2);
    let seam = (0..t_len - gap).map(|a| (x.row(a) - &next).norm()).fold(f64::INFINITY, f64::min);
    seam <= 2.0 * median
}

/// The learned trajectories that guide a blend of training sequences `a` (w = 0) and `b`
/// (w = 1), as `(w, sequence index)` sorted by `w`: the endpoints, plus every pre-blended
/// sequence of §7 between `a` and `b` (made in either order; weights flipped to `a`'s side).
/// A weight between two of them blends the variants of the nearest learned weight on each side
/// ([`blend_bounding`]); a pair without pre-blends blends the endpoints' variants directly
/// (the paper's unguided interpolation).
pub fn blend_entries(model: &VariationModel, a: usize, b: usize) -> Vec<(f64, usize)> {
    let mut entries = vec![(0.0, a), (1.0, b)];
    for (i, s) in model.sequences.iter().enumerate() {
        match (s.blend, s.blend_of) {
            (Some(v), Some(of)) if of == (a, b) => entries.push((v, i)),
            (Some(v), Some(of)) if of == (b, a) => entries.push((1.0 - v, i)),
            _ => {}
        }
    }
    entries.sort_by(|x, y| x.0.total_cmp(&y.0));
    entries
}

/// `n` variations of the blend at `w` of training sequences `a` and `b` from the sampled
/// variants `pools[s]` of the training sequences (index `s` as in the model; only those of
/// [`blend_entries`] are read).
pub fn blend_variations(
    dec: &Decoder,
    pools: &[Variations],
    (a, b): (usize, usize),
    w: f64,
    n: usize,
    seed: u64,
) -> Result<Variations> {
    let model = dec.model;
    if !(0.0..=1.0).contains(&w) {
        return Err(Error::invalid(format!("blend: blend weight {w} outside [0, 1]")));
    }
    let [(w1, i1), (w2, i2)] = blend_bounding(model, a, b, w);
    let (p1, p2) = (&pools[i1], &pools[i2]);
    if p1.is_empty() || p2.is_empty() {
        return Err(Error::invalid(format!("blend: no trajectory for blend weight {}", if p1.is_empty() { w1 } else { w2 })));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(mix(seed, 0xB1E4D, (w * 1e6).round() as u64));
    // Per variation and part: a variant of each bounding weight drawn uniformly, blended
    // linearly in w* (3DV §7, `gpdm::blend::blend_pair`); a learned weight draws its own.
    Ok((0..n)
        .map(|_| {
            (0..model.parts.len())
                .map(|k| {
                    let x = &p1[rng.random_range(0..p1.len())][k];
                    if i1 == i2 {
                        return x.clone();
                    }
                    let y = &p2[rng.random_range(0..p2.len())][k];
                    gpdm::blend::blend_pair(x, w1, y, w2, w)
                })
                .collect()
        })
        .collect())
}

/// The learned weights of [`blend_entries`] nearest to `w` ∈ [0, 1] on each side, as
/// `(w, sequence index)` (the same twice when `w` is learned): the only sequences a blend at
/// `w` draws variants of.
pub fn blend_bounding(model: &VariationModel, a: usize, b: usize, w: f64) -> [(f64, usize); 2] {
    let entries = blend_entries(model, a, b);
    if let Some(&e) = entries.iter().find(|e| e.0 == w) {
        return [e, e];
    }
    let lo = *entries.iter().rev().find(|e| e.0 <= w).unwrap_or(&entries[0]);
    let hi = *entries.iter().find(|e| e.0 >= w).unwrap_or(&entries[entries.len() - 1]);
    [lo, hi]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points of one turn of a circle, the last one step before the first.
    fn circle(n: usize) -> DMatrix<f64> {
        DMatrix::from_fn(n, 2, |t, c| {
            let a = std::f64::consts::TAU * t as f64 / n as f64;
            if c == 0 { a.cos() } else { a.sin() }
        })
    }

    #[test]
    fn a_circle_closes_into_a_cycle_and_a_stroke_does_not() {
        assert!(cycle_closes(&circle(40)));
        assert!(!cycle_closes(&DMatrix::from_fn(12, 1, |t, _| t as f64)));
        assert!(!cycle_closes(&circle(2)));
    }

    #[test]
    fn a_learned_cycle_continues_into_its_next_cycle() {
        let x = circle(40);
        let t = learned_template(&x, 100);
        // Every point a learned one, in order: 0..40, then 0..40 again, then 0..20.
        for r in 0..100 {
            assert_eq!(t.row(r), x.row(r % 40), "row {r}");
        }
        assert_eq!(learned_template(&x, 25), x.rows(0, 25).into_owned());
    }

    #[test]
    fn a_learned_stroke_replays_from_a_quarter_back_at_the_latest() {
        // A straight stroke along x: the extrapolated next step is past the end; the nearest
        // allowed point is the last one a quarter (3 of 12) before the end.
        let x = DMatrix::from_fn(12, 1, |t, _| t as f64);
        let t = learned_template(&x, 20);
        let got: Vec<f64> = t.iter().copied().collect();
        let want: Vec<f64> = (0..12).chain(8..12).chain(8..12).map(|v| v as f64).collect();
        assert_eq!(got, want);
        // Too short to replay: the last point is held.
        let two = DMatrix::from_fn(2, 1, |t, _| t as f64);
        assert_eq!(learned_template(&two, 4).iter().copied().collect::<Vec<_>>(), vec![0.0, 1.0, 1.0, 1.0]);
    }
}

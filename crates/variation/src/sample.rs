//! `hmc-sample`: variations of latent trajectories (paper §6) and of blends (§7).
//!
//! For a training sequence, every part's chain starts from the mean prediction (3DV eqs. 8-10) from
//! the sequence's first learned latent point and draws whole trajectories by Hybrid Monte Carlo
//! with the first point fixed (`gpdm::hmc::sample_trajectories`: burn-in with step-size
//! adaptation toward the target acceptance, then thinning). Parts are sampled independently
//! (one of the paper's sources of variation); variation `k` takes sample `k` of every part.
//! For a blend weight `w*`, each part's `gpdm::blend::BlendSet` of sampled variants at
//! `W ∪ {0, 1}` gives `X̃_{w*}` from random variants of the bounding trajectories.
//! Every chain has its own seed derived from `(seed, sequence, part)`: same seed, same samples.

use gpdm::ancestral::sample_trajectories_on_data;
use gpdm::blend::BlendSet;
use gpdm::hmc::{sample_trajectories_scaled, ChainStart, HmcOptions};
use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::frame_stride;
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
}

impl Sampler {
    /// From its command-line name (`hmc`, `ancestral`).
    pub fn from_name(name: &str) -> Option<Sampler> {
        match name {
            "hmc" => Some(Sampler::Hmc),
            "ancestral" => Some(Sampler::Ancestral),
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
    /// from the centre of the density; `examples/burn_in_check` measures how far it gets), 50
    /// from an exact draw (step-size adaptation only).
    pub fn default_burn_in(self) -> usize {
        match self {
            HmcStart::Mean => 200,
            HmcStart::Ancestral | HmcStart::Learned => 50,
        }
    }
}

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
/// variance of the dynamics (1: the model's density; `hmc-sample --variance-scale`).
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
                Sampler::Ancestral => {
                    let x1: Vec<f64> = template.row(0).iter().copied().collect();
                    let (drawn, off) = sample_trajectories_on_data(
                        pr,
                        &x1,
                        len,
                        per,
                        o.seed,
                        variance_scale,
                        gpdm::hmc::OFF_DATA_VARIANCE,
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

/// The learned trajectories that guide a blend of training sequences `a` (w = 0) and `b`
/// (w = 1), as `(w, sequence index)` sorted by `w`: the endpoints, plus every pre-blended
/// sequence of §7 between `a` and `b` (made in either order; weights flipped to `a`'s side).
/// A weight between two of them blends the variants of the nearest learned weight on each side
/// (`gpdm::blend::BlendSet`); a pair without pre-blends blends the endpoints' variants directly
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
    let entries_idx = blend_entries(model, a, b);
    let sets = (0..model.parts.len())
        .map(|k| {
            let entries = entries_idx
                .iter()
                .map(|&(v, i)| (v, pools[i].iter().map(|var| var[k].clone()).collect()))
                .collect();
            BlendSet::new(entries).map_err(|e| Error::invalid(format!("blend: {e}")))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut rng = ChaCha8Rng::seed_from_u64(mix(seed, 0xB1E4D, (w * 1e6).round() as u64));
    (0..n)
        .map(|_| {
            sets.iter()
                .map(|set| {
                    set.sample(w, &mut rng)
                        .map_err(|e| Error::invalid(format!("blend: {e}")))
                })
                .collect()
        })
        .collect()
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

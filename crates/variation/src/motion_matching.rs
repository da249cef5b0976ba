//! A training-free baseline to the GPDM samplers: generative motion matching (GenMM, Li et al.,
//! SIGGRAPH 2023, "Example-based Motion Synthesis via Generative Motion Matching") over the
//! learned latent coordinates of all body parts jointly (`hmc-sample --sampler motion-matching`).
//!
//! GenMM synthesises a skeleton's joint rotations by multi-scale patch nearest neighbours: a
//! coarse-to-fine pyramid of the examples, a coarsest synthesis started from the example with
//! noise, and at every level a few iterations of (1) every overlapping temporal patch of the
//! synthesis replaced by its nearest example patch, distances normalised by how well each example
//! patch is already matched (its "completeness" term), and (2) the overlapping patches averaged
//! frame by frame; then the synthesis is upsampled to the next level. Here a frame is the
//! concatenation of every part's learned latent point (each part's block centred and divided by
//! its RMS radius, so every part weighs alike whatever its scale): matching whole-body frames keeps
//! the legs, arms and torso of one output frame from one moment of the examples (per-part matching
//! would desynchronise the legs). The torso's latent coordinates carry the root's per-frame
//! displacements (3DV §4), so the matched patches bring their travel with them. The output is an
//! average of example frames, so every coordinate stays within the examples' range; decoded by the
//! pose GPs it stays near the learned poses.

use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which training sequences a variation of one sequence matches against.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Examples {
    /// The queried sequence only: a walk variation is made of walk patches.
    #[default]
    Own,
    /// Every sequence of the group (its motions and pre-blends), started from the queried one.
    Group,
}

/// How the coarsest level of a synthesis starts. `Phase` is a start the caller makes
/// (`crate::sample::matched_variations` passes the re-phased trajectory as `start`);
/// [`synthesize`] uses it as it uses `Source`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Start {
    /// The queried sequence's trajectory with noise (GenMM's start). On short examples the
    /// matching finds the source's own patches again: the variations are its copies.
    Source,
    /// Random crops of the examples' coarsest level, one patch long each, laid end to end, with
    /// noise: the matching then recombines the examples' pieces in a new order.
    Shuffle,
    /// The queried trajectory from a random point of its first half on, replayed past its end
    /// from its nearest point, with noise: the source's motion at another phase (where the
    /// group's learned trajectories close into cycles; else from its first point).
    #[default]
    Phase,
}

/// Settings of [`synthesize`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MatchOptions {
    /// Patch length in frames (model training steps), the same at every level as in GenMM: a
    /// coarse level's patch spans more time. Cut to the shortest of the longest example and the
    /// output.
    pub patch: usize,
    /// Most pyramid levels; fewer when a coarser level would be shorter than one patch.
    pub levels: usize,
    /// Length ratio between consecutive levels.
    pub ratio: f64,
    /// Matching iterations per level.
    pub iterations: usize,
    /// α of the completeness normalisation: the distance of a synthesis patch to example patch
    /// `j` is divided by `α + min_i d(i, j)` (GenMM's eq. 2), so example patches no synthesis
    /// patch is near yet are preferred. None: plain nearest neighbours.
    pub alpha: Option<f64>,
    /// Standard deviation of the Gaussian noise added to the coarsest start, in units of each
    /// part's RMS radius (per coordinate `noise / √d`).
    pub noise: f64,
    /// Which sequences are matched against.
    #[serde(default)]
    pub examples: Examples,
    /// How the coarsest level starts.
    #[serde(default)]
    pub start: Start,
}

impl Default for MatchOptions {
    fn default() -> Self {
        MatchOptions {
            patch: 11,
            levels: 4,
            ratio: 2.0,
            iterations: 3,
            alpha: None,
            noise: 1.0,
            examples: Examples::Own,
            start: Start::Phase,
        }
    }
}

impl MatchOptions {
    /// The settings' sanity: one line naming the first bad one.
    pub fn check(&self) -> Result<()> {
        if self.patch == 0 {
            return Err(Error::invalid("motion matching: the patch needs at least 1 frame"));
        }
        if self.levels == 0 || self.iterations == 0 {
            return Err(Error::invalid("motion matching: at least one level and one iteration are needed"));
        }
        if !(self.ratio > 1.0 && self.ratio.is_finite()) {
            return Err(Error::invalid(format!("motion matching: level ratio {} must be a finite number > 1", self.ratio)));
        }
        if !(self.noise >= 0.0 && self.noise.is_finite()) {
            return Err(Error::invalid(format!("motion matching: noise {} must be a finite number >= 0", self.noise)));
        }
        if let Some(a) = self.alpha {
            if !(a > 0.0 && a.is_finite()) {
                return Err(Error::invalid(format!("motion matching: α = {a} must be a finite number > 0")));
            }
        }
        Ok(())
    }
}

/// Every part's block of columns centred and divided by its RMS radius over the examples, and
/// back: `x' = (x − mean) / scale[block]`.
#[derive(Clone, Debug)]
pub struct Normaliser {
    mean: Vec<f64>,
    /// Per column, its block's RMS radius (1 for a block without spread).
    scale: Vec<f64>,
    /// Per column, `1/√d` of its block (the per-coordinate noise of a unit RMS radius).
    noise: Vec<f64>,
}

impl Normaliser {
    /// From the examples' rows; `dims[k]`: columns of block `k`, in order.
    pub fn new(examples: &[DMatrix<f64>], dims: &[usize]) -> Normaliser {
        let cols: usize = dims.iter().sum();
        let n: usize = examples.iter().map(|e| e.nrows()).sum();
        let mut mean = vec![0.0; cols];
        for e in examples {
            for r in e.row_iter() {
                for (m, v) in mean.iter_mut().zip(r.iter()) {
                    *m += v / n.max(1) as f64;
                }
            }
        }
        let (mut scale, mut noise) = (vec![1.0; cols], vec![1.0; cols]);
        let mut c0 = 0;
        for &d in dims {
            let mut ss = 0.0;
            for e in examples {
                for r in e.row_iter() {
                    ss += (c0..c0 + d).map(|c| (r[c] - mean[c]).powi(2)).sum::<f64>();
                }
            }
            let rms = (ss / n.max(1) as f64).sqrt();
            for c in c0..c0 + d {
                scale[c] = if rms > 1e-12 { rms } else { 1.0 };
                noise[c] = 1.0 / (d.max(1) as f64).sqrt();
            }
            c0 += d;
        }
        Normaliser { mean, scale, noise }
    }

    pub fn forward(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(x.nrows(), x.ncols(), |t, c| (x[(t, c)] - self.mean[c]) / self.scale[c])
    }

    pub fn inverse(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(x.nrows(), x.ncols(), |t, c| x[(t, c)] * self.scale[c] + self.mean[c])
    }

    /// Per-column noise standard deviation for a unit noise level.
    pub fn noise_scale(&self) -> &[f64] {
        &self.noise
    }
}

/// `x` (T × D) resampled to `n` rows by linear interpolation in time, the first and last rows
/// kept (one row: the middle one). Every output row is a convex combination of two input rows.
pub fn resample(x: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    let (t, d) = x.shape();
    if t == 0 || n == 0 {
        return DMatrix::zeros(n, d);
    }
    if n == 1 || t == 1 {
        let mid = (t - 1) / 2;
        return DMatrix::from_fn(n, d, |_, c| x[(mid, c)]);
    }
    DMatrix::from_fn(n, d, |j, c| {
        let u = j as f64 * (t - 1) as f64 / (n - 1) as f64;
        let i = (u.floor() as usize).min(t - 2);
        let f = u - i as f64;
        (1.0 - f) * x[(i, c)] + f * x[(i + 1, c)]
    })
}

/// Length of a sequence of `len` rows at pyramid level `l` (ratio `r`): `round(len / r^l)`, at
/// least 1.
fn level_len(len: usize, r: f64, l: usize) -> usize {
    ((len as f64 / r.powi(l as i32)).round() as usize).max(1)
}

/// One standard normal draw (Box-Muller; `rand` alone has no normal distribution).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The patch length and number of levels [`synthesize`] uses for examples of lengths `lens`
/// and an output of `len` rows: the patch cut to the longest example and the output, and the
/// levels while the coarser level still holds one patch in the longest example and the output.
pub fn pyramid(lens: &[usize], len: usize, o: &MatchOptions) -> (usize, usize) {
    let longest = lens.iter().copied().max().unwrap_or(0);
    let patch = o.patch.min(longest).min(len).max(1);
    let mut levels = 1;
    while levels < o.levels
        && level_len(longest, o.ratio, levels) >= patch
        && level_len(len, o.ratio, levels) >= patch
    {
        levels += 1;
    }
    (patch, levels)
}

/// Every window of `patch` rows of every example, flattened row by row: `(keys, owner)` with
/// `owner[j] = (example, first row)`.
fn patches(examples: &[DMatrix<f64>], patch: usize) -> (Vec<Vec<f64>>, Vec<(usize, usize)>) {
    let mut keys = Vec::new();
    let mut owner = Vec::new();
    for (e, x) in examples.iter().enumerate() {
        if x.nrows() < patch {
            continue;
        }
        for s in 0..=x.nrows() - patch {
            keys.push((s..s + patch).flat_map(|t| x.row(t).iter().copied().collect::<Vec<_>>()).collect());
            owner.push((e, s));
        }
    }
    (keys, owner)
}

/// One matching iteration at one level: every window of `patch` rows of `syn` replaced by its
/// nearest example window (completeness-normalised with `alpha`), the overlapping windows
/// averaged frame by frame; with the chosen example windows. Ties go to the first example
/// window, so the result does not depend on the number of threads.
fn match_step(
    syn: &DMatrix<f64>,
    examples: &[DMatrix<f64>],
    keys: &[Vec<f64>],
    owner: &[(usize, usize)],
    patch: usize,
    alpha: Option<f64>,
) -> (DMatrix<f64>, Vec<(usize, usize)>) {
    let len = syn.nrows();
    let queries: Vec<Vec<f64>> = (0..=len - patch)
        .map(|s| (s..s + patch).flat_map(|t| syn.row(t).iter().copied().collect::<Vec<_>>()).collect())
        .collect();
    // dist[q][j]: squared L2 between synthesis window q and example window j.
    let dist: Vec<Vec<f64>> = queries
        .par_iter()
        .map(|q| {
            keys.iter()
                .map(|k| q.iter().zip(k).map(|(a, b)| (a - b) * (a - b)).sum::<f64>())
                .collect()
        })
        .collect();
    // GenMM's completeness: each example window's distances divided by α plus its smallest
    // distance to any synthesis window.
    let norm: Vec<f64> = match alpha {
        Some(a) => (0..keys.len())
            .map(|j| a + dist.iter().map(|row| row[j]).fold(f64::INFINITY, f64::min))
            .collect(),
        None => vec![1.0; keys.len()],
    };
    let chosen: Vec<(usize, usize)> = dist
        .iter()
        .map(|row| {
            let mut best = (f64::INFINITY, 0usize);
            for (j, (&v, &n)) in row.iter().zip(&norm).enumerate() {
                let v = v / n;
                if v < best.0 {
                    best = (v, j);
                }
            }
            owner[best.1]
        })
        .collect();
    let out = blend_patches(&chosen, patch, len, examples);
    (out, chosen)
}

/// The synthesis that matched window `q` (rows `q..q + patch`) to rows `s..s + patch` of
/// example `e` for every `(e, s) = chosen[q]`: every row the mean of the example rows its
/// windows matched. Applied to other sequences time-aligned with the examples (same rows), it
/// gives their frames at the same moments ([`Synthesis`]).
pub fn blend_patches(chosen: &[(usize, usize)], patch: usize, len: usize, examples: &[DMatrix<f64>]) -> DMatrix<f64> {
    let d = examples.iter().map(|e| e.ncols()).max().unwrap_or(0);
    let mut sum = DMatrix::<f64>::zeros(len, d);
    let mut count = vec![0usize; len];
    for (q, &(e, s)) in chosen.iter().enumerate() {
        for t in 0..patch.min(len.saturating_sub(q)) {
            let Some(src) = examples.get(e).filter(|x| s + t < x.nrows() && x.ncols() == d) else { continue };
            for c in 0..d {
                sum[(q + t, c)] += src[(s + t, c)];
            }
            count[q + t] += 1;
        }
    }
    for (t, &n) in count.iter().enumerate() {
        for c in 0..d {
            sum[(t, c)] /= n.max(1) as f64;
        }
    }
    sum
}

/// A synthesised trajectory and how it was made: at the finest level, window `q` (rows
/// `q..q + patch`) matched rows `s..s + patch` of example `e`, `(e, s) = chosen[q]`, and `rows`
/// is [`blend_patches`] of them.
#[derive(Clone, Debug, PartialEq)]
pub struct Synthesis {
    pub rows: DMatrix<f64>,
    pub chosen: Vec<(usize, usize)>,
    pub patch: usize,
}

/// A trajectory of `len` rows made of the `examples`' patches (all with the same columns),
/// started (`o.start`) from `start` (any number of rows, resampled to the coarsest level) or
/// from random crops of the examples, plus Gaussian noise `o.noise · noise[c]` per column,
/// drawn from `rng`. Every output coordinate lies within the
/// examples' range of that coordinate.
pub fn synthesize(
    examples: &[DMatrix<f64>],
    start: &DMatrix<f64>,
    len: usize,
    noise: &[f64],
    o: &MatchOptions,
    rng: &mut ChaCha8Rng,
) -> Result<Synthesis> {
    o.check()?;
    let d = start.ncols();
    if examples.is_empty() || examples.iter().all(|e| e.nrows() == 0) {
        return Err(Error::invalid("motion matching: no example frames"));
    }
    if examples.iter().any(|e| e.ncols() != d) || noise.len() != d || start.nrows() == 0 {
        return Err(Error::invalid("motion matching: the examples, start and noise differ in columns"));
    }
    if len == 0 {
        return Ok(Synthesis { rows: DMatrix::zeros(0, d), chosen: Vec::new(), patch: 0 });
    }
    let lens: Vec<usize> = examples.iter().map(|e| e.nrows()).collect();
    let (patch, levels) = pyramid(&lens, len, o);
    let coarsest = levels - 1;
    let n0 = level_len(len, o.ratio, coarsest);
    let mut syn = match o.start {
        Start::Source | Start::Phase => resample(start, n0),
        Start::Shuffle => {
            // Crops of `patch` rows (or of a whole shorter example) from random examples and
            // positions at the coarsest level, end to end until `n0` rows.
            let at: Vec<DMatrix<f64>> = examples
                .iter()
                .map(|e| resample(e, level_len(e.nrows(), o.ratio, coarsest).min(e.nrows())))
                .collect();
            // Only examples with rows are cropped (at least one has: checked above).
            let held: Vec<&DMatrix<f64>> = at.iter().filter(|e| e.nrows() > 0).collect();
            let mut m = DMatrix::zeros(n0, d);
            let mut t = 0;
            while t < n0 {
                let e = held[rng.random_range(0..held.len())];
                let w = patch.min(e.nrows()).min(n0 - t).max(1);
                let s0 = rng.random_range(0..=e.nrows() - w);
                m.rows_mut(t, w).copy_from(&e.rows(s0, w));
                t += w;
            }
            m
        }
    };
    for c in 0..d {
        for t in 0..syn.nrows() {
            syn[(t, c)] += o.noise * noise[c] * normal(rng);
        }
    }
    let (mut chosen, mut last_patch) = (Vec::new(), 0);
    for l in (0..levels).rev() {
        let at: Vec<DMatrix<f64>> =
            examples.iter().map(|e| resample(e, level_len(e.nrows(), o.ratio, l).min(e.nrows()))).collect();
        let n = if l == 0 { len } else { level_len(len, o.ratio, l) };
        syn = resample(&syn, n);
        let p = patch.min(n);
        let (keys, owner) = patches(&at, p);
        if keys.is_empty() {
            return Err(Error::invalid(format!("motion matching: no example holds a patch of {p} frames")));
        }
        for _ in 0..o.iterations {
            let (next, c) = match_step(&syn, &at, &keys, &owner, p, o.alpha);
            syn = next;
            if l == 0 {
                chosen = c;
                last_patch = p;
            }
        }
    }
    Ok(Synthesis { rows: syn, chosen, patch: last_patch })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// A 2-D example: a circle traversed `turns` times over `n` rows, radius growing with time.
    fn example(n: usize, turns: f64) -> DMatrix<f64> {
        DMatrix::from_fn(n, 2, |t, c| {
            let a = std::f64::consts::TAU * turns * t as f64 / n as f64;
            let r = 1.0 + t as f64 / n as f64;
            if c == 0 { r * a.cos() } else { r * a.sin() }
        })
    }

    fn rng(seed: u64) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(seed)
    }

    #[test]
    fn a_patch_as_long_as_the_only_example_copies_it() {
        let x = example(30, 2.0);
        let o = MatchOptions { patch: 30, ..Default::default() };
        let y = synthesize(&[x.clone()], &x, 30, &[1.0, 1.0], &o, &mut rng(3)).unwrap().rows;
        assert!((y - x).abs().max() < 1e-12);
    }

    #[test]
    fn the_same_seed_gives_the_same_trajectory_and_another_seed_another() {
        let ex = [example(200, 7.3), example(150, 4.1)];
        // Random crops recombined (a source start finds its own patches again: a copy).
        let o = MatchOptions { start: Start::Shuffle, levels: 2, ..Default::default() };
        let a = synthesize(&ex, &ex[0], 120, &[0.5, 0.5], &o, &mut rng(7)).unwrap().rows;
        let b = synthesize(&ex, &ex[0], 120, &[0.5, 0.5], &o, &mut rng(7)).unwrap().rows;
        let c = synthesize(&ex, &ex[0], 120, &[0.5, 0.5], &o, &mut rng(8)).unwrap().rows;
        assert_eq!(a, b);
        assert_ne!(a, c);
        // The same on one thread as on several.
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let d = one.install(|| synthesize(&ex, &ex[0], 120, &[0.5, 0.5], &o, &mut rng(7)).unwrap().rows);
        assert_eq!(a, d);
        // With GenMM's completeness term too.
        let o = MatchOptions { alpha: Some(0.01), ..o };
        let e = synthesize(&ex, &ex[0], 120, &[0.5, 0.5], &o, &mut rng(7)).unwrap().rows;
        assert_eq!(e, synthesize(&ex, &ex[0], 120, &[0.5, 0.5], &o, &mut rng(7)).unwrap().rows);
    }

    #[test]
    fn the_source_start_finds_its_own_patches_again() {
        // Started from the only example, the nearest patch of every window is its own: a copy
        // whatever the noise (the noise averages out over a patch's coordinates).
        let x = example(64, 2.0);
        let o = MatchOptions { start: Start::Source, noise: 0.3, ..Default::default() };
        let y = synthesize(&[x.clone()], &x, 64, &[1.0, 1.0], &o, &mut rng(5)).unwrap().rows;
        assert!((y - &x).abs().max() < 1e-12);
    }

    #[test]
    fn the_chosen_windows_rebuild_the_synthesis_and_carry_over_to_an_aligned_sequence() {
        let ex = [example(80, 3.0)];
        let o = MatchOptions { start: Start::Shuffle, levels: 2, ..Default::default() };
        let y = synthesize(&ex, &ex[0], 90, &[0.5, 0.5], &o, &mut rng(2)).unwrap();
        assert_eq!(blend_patches(&y.chosen, y.patch, 90, &ex), y.rows);
        // A sequence aligned with the example (here twice it) gets the same moments: twice y.
        let twice = [&ex[0] * 2.0];
        assert!((blend_patches(&y.chosen, y.patch, 90, &twice) - &y.rows * 2.0).abs().max() < 1e-12);
    }

    #[test]
    fn every_frame_stays_within_the_examples_range() {
        let ex = [example(50, 2.5), example(40, 1.5)];
        for (seed, start) in (0..6).zip([Start::Shuffle, Start::Source, Start::Phase].into_iter().cycle()) {
            let o = MatchOptions { noise: 3.0, start, alpha: (seed % 2 == 0).then_some(0.01), ..Default::default() };
            let y = synthesize(&ex, &ex[1], 70, &[1.0, 1.0], &o, &mut rng(seed)).unwrap().rows;
            for c in 0..2 {
                let lo = ex.iter().map(|e| e.column(c).min()).fold(f64::INFINITY, f64::min);
                let hi = ex.iter().map(|e| e.column(c).max()).fold(f64::NEG_INFINITY, f64::max);
                assert!(y.column(c).iter().all(|&v| v >= lo - 1e-12 && v <= hi + 1e-12), "seed {seed}");
            }
        }
    }

    #[test]
    fn an_output_longer_than_the_examples_is_made() {
        let ex = [example(20, 1.0)];
        for start in [Start::Shuffle, Start::Source] {
            let o = MatchOptions { start, ..Default::default() };
            let y = synthesize(&ex, &ex[0], 75, &[0.3, 0.3], &o, &mut rng(1)).unwrap().rows;
            assert_eq!(y.shape(), (75, 2));
            assert!(y.iter().all(|v| v.is_finite()));
        }
        let y = synthesize(&ex, &ex[0], 75, &[0.3, 0.3], &MatchOptions::default(), &mut rng(1)).unwrap().rows;
        assert!(y.iter().all(|v| v.is_finite()));
        // Shorter than a patch and one frame work too.
        assert_eq!(synthesize(&ex, &ex[0], 4, &[0.3, 0.3], &MatchOptions::default(), &mut rng(1)).unwrap().rows.nrows(), 4);
        assert_eq!(synthesize(&ex, &ex[0], 1, &[0.3, 0.3], &MatchOptions::default(), &mut rng(1)).unwrap().rows.nrows(), 1);
    }

    #[test]
    fn bad_settings_and_inputs_are_errors() {
        let ex = [example(20, 1.0)];
        let bad = |o: MatchOptions| synthesize(&ex, &ex[0], 20, &[1.0, 1.0], &o, &mut rng(0)).is_err();
        assert!(bad(MatchOptions { patch: 0, ..Default::default() }));
        assert!(bad(MatchOptions { ratio: 1.0, ..Default::default() }));
        assert!(bad(MatchOptions { noise: f64::NAN, ..Default::default() }));
        assert!(bad(MatchOptions { alpha: Some(0.0), ..Default::default() }));
        assert!(synthesize(&[], &ex[0], 20, &[1.0, 1.0], &MatchOptions::default(), &mut rng(0)).is_err());
        assert!(synthesize(&ex, &ex[0], 20, &[1.0], &MatchOptions::default(), &mut rng(0)).is_err());
        // An empty example beside one with rows is skipped.
        let with_empty = [DMatrix::zeros(0, 2), example(20, 1.0)];
        for start in [Start::Shuffle, Start::Source] {
            let o = MatchOptions { start, ..Default::default() };
            assert_eq!(synthesize(&with_empty, &ex[0], 30, &[1.0, 1.0], &o, &mut rng(0)).unwrap().rows.nrows(), 30);
        }
    }

    #[test]
    fn the_pyramid_keeps_a_patch_at_its_coarsest_level() {
        let o = MatchOptions::default();
        assert_eq!(pyramid(&[100], 100, &o), (11, 4)); // 100, 50, 25, 13
        assert_eq!(pyramid(&[40], 40, &o), (11, 2)); // 40, 20; 10 < 11
        assert_eq!(pyramid(&[8], 40, &o), (8, 1));
    }

    #[test]
    fn normalising_gives_every_block_a_unit_radius_and_inverts() {
        let x = DMatrix::from_fn(10, 3, |t, c| if c < 2 { 5.0 * t as f64 + c as f64 } else { 0.01 * t as f64 });
        let n = Normaliser::new(&[x.clone()], &[2, 1]);
        let y = n.forward(&x);
        for (c0, d) in [(0, 2), (2, 1)] {
            let ss: f64 = y.row_iter().map(|r| (c0..c0 + d).map(|c| r[c] * r[c]).sum::<f64>()).sum();
            assert!((ss / 10.0 - 1.0).abs() < 1e-12);
        }
        assert!((n.inverse(&y) - x).abs().max() < 1e-12);
    }
}

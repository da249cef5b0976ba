//! Foot-skating correction: the horizontal root shifts that keep planted feet from sliding, the
//! "traditional post-processing" the transfer paper names at the start of CVPR §6 ("foot-skating
//! correction to ensure foot contacts don't appear to be slipping"). The variation paper
//! describes no post-processing; its samples slide as transfers do and get the same clean-up.
//! It lives here, below `transfer` and `variation`, because `capture` is the lowest crate both
//! depend on that reaches `gp`'s banded solver, and it already detects the contacts.
//!
//! Over `T` frames the unknowns are one shift `d(t)` per frame, with `d(0) = 0` (the sequence
//! keeps its start), and one free anchor `a_I` per anchor term. Each axis is solved alone (the
//! same matrix for all of them):
//!
//! `min_{d, a}  Σ_{velocity (t, v)} ‖d(t) − d(t−1) − v‖²  +  Σ_{anchor I} Σ_{t ∈ I} ‖p_I(t) + d(t) − a_I‖²
//!            + λ Σ_{t=1}^{T−2} ‖d(t−1) − 2 d(t) + d(t+1)‖²  +  μ Σ_{t≥1} ‖d(t)‖²`
//!
//! * a **velocity** term asks the shift to move by `v` from frame `t − 1` to `t`: the transfer
//!   (`transfer::feet`) wants a target sole to travel between two contact frames as the
//!   source's sole does, scaled, so `v` is that travel minus the sole's own;
//! * an **anchor** term asks the sole positions `p_I(t)` of a contact interval `I`, once shifted,
//!   to stay at one point `a_I` that is itself free (it ends at the mean shifted position):
//!   the variation (`variation::footskate`) pins each planted foot wherever it is planted;
//! * `λ` (smoothness) spreads the correction smoothly over the frames between contacts;
//! * `μ` (ridge) makes the correction return to zero away from contacts (the transfer's
//!   `RETURN`) or only keeps the system definite (the variation's 1e-9).
//!
//! The normal equations without the fixed `d(0)` are bordered: a band of width 2 for the
//! `T − 1` shifts (every term couples frames at most two apart), and `K` anchor rows and columns
//! that couple an anchor only to the frames of its interval (`−1` each) and to itself (the
//! interval's length). The band is factorised once ([`gp::band::BandCholesky`], with its
//! jitter retry) and the anchors eliminated by their `K x K` Schur complement
//! `S = A_aa − A_ad A_dd⁻¹ A_da` ([`gp::linalg::Cholesky`]): with `A_dd⁻¹ [b_d | A_da]` from the
//! band solves, `S a = b_a − A_ad A_dd⁻¹ b_d` gives the anchors and `d = A_dd⁻¹ (b_d − A_da a)`
//! the shifts. No inverse is formed. The cost is `O(T (K + D) + K³)` for `D` axes, linear in
//! the frame count for the few anchors of a clip; without anchors it is the band solve alone.
//! Without any term the answer is `d = 0`.

use std::ops::Range;

use gp::band::{BandCholesky, SymmetricBand};
use gp::linalg::Cholesky;
use mesh_core::{Error, Result};
use nalgebra::DMatrix;

/// One anchor term: its frames and the sum of its sole positions (the anchor's right-hand side).
#[derive(Clone, Debug)]
struct Anchor<const D: usize> {
    frames: Range<usize>,
    sum: [f64; D],
}

/// A foot-skating problem over `frames` frames and `D` axes (module doc): terms are added,
/// their normal equations accumulated in the order they come, then [`Problem::solve`].
#[derive(Clone, Debug)]
pub struct Problem<const D: usize> {
    frames: usize,
    smoothness: f64,
    /// The band of the shifts `d(1..T)` (unknown `t − 1` is `d(t)`): ridge and data terms so far.
    band: SymmetricBand,
    /// Their right-hand sides, `T − 1` rows, one column per axis.
    rhs: DMatrix<f64>,
    anchors: Vec<Anchor<D>>,
    terms: usize,
}

impl<const D: usize> Problem<D> {
    /// A problem with no terms yet: smoothness `λ` and ridge `μ` must be finite numbers >= 0.
    pub fn new(frames: usize, smoothness: f64, ridge: f64) -> Result<Self> {
        mesh_core::feet::check_smoothness(smoothness)?;
        if !(ridge.is_finite() && ridge >= 0.0) {
            return Err(Error::invalid(format!("foot-skating ridge must be a finite number >= 0, got {ridge}")));
        }
        let dim = frames.saturating_sub(1);
        let mut band = SymmetricBand::zeros(dim, 2);
        (0..dim).for_each(|i| band.add(i, i, ridge));
        Ok(Problem { frames, smoothness, band, rhs: DMatrix::zeros(dim, D), anchors: Vec::new(), terms: 0 })
    }

    /// Frames `T`.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Adds the velocity term `‖d(t) − d(t−1) − wanted‖²`. Panics unless `1 <= t < T`: the
    /// caller's frames are its own.
    pub fn add_velocity(&mut self, t: usize, wanted: [f64; D]) {
        assert!(t >= 1 && t < self.frames, "velocity term at frame {t} of {}", self.frames);
        let (i, prev) = (t - 1, t.checked_sub(2));
        self.band.add(i, i, 1.0);
        for c in 0..D {
            self.rhs[(i, c)] += wanted[c];
        }
        if let Some(j) = prev {
            self.band.add(j, j, 1.0);
            self.band.add(i, j, -1.0);
            for c in 0..D {
                self.rhs[(j, c)] -= wanted[c];
            }
        }
        self.terms += 1;
    }

    /// Adds the anchor term `Σ_t ‖positions[t − start] + d(t) − a‖²` over the frames
    /// `start..start + positions.len()`, with its own free anchor `a`. Panics when the interval
    /// is empty or runs past the last frame.
    pub fn add_anchor(&mut self, start: usize, positions: &[[f64; D]]) {
        let frames = start..start + positions.len();
        assert!(!frames.is_empty() && frames.end <= self.frames, "anchor over frames {frames:?} of {}", self.frames);
        let mut sum = [0.0; D];
        for (t, p) in frames.clone().zip(positions) {
            if t >= 1 {
                self.band.add(t - 1, t - 1, 1.0);
                for c in 0..D {
                    self.rhs[(t - 1, c)] -= p[c];
                }
            }
            for c in 0..D {
                sum[c] += p[c];
            }
        }
        self.anchors.push(Anchor { frames, sum });
        self.terms += 1;
    }

    /// The shifts `d(t)`, `T` of them (`d(0) = 0`). Jitter retries of the factorisations go to
    /// `notes`.
    pub fn solve(&self, notes: &mut Vec<String>) -> Result<Vec<[f64; D]>> {
        let n = self.frames;
        if self.terms == 0 || n < 2 {
            return Ok(vec![[0.0; D]; n]);
        }
        let failed = |e: gp::GpError| Error::invalid(format!("foot-skating clean-up: {e}"));
        let mut a = self.band.clone();
        // Second differences d(t−1) − 2 d(t) + d(t+1), t = 1..T−2 (d(0) = 0 drops out), each
        // pair of the stencil once (the lower triangle).
        let w = [1.0, -2.0, 1.0];
        for t in 1..n.saturating_sub(1) {
            for (u, wu) in w.iter().enumerate() {
                for (v, wv) in w.iter().enumerate().take(u + 1) {
                    if let (Some(i), Some(j)) = ((t + u).checked_sub(2), (t + v).checked_sub(2)) {
                        a.add(i, j, self.smoothness * wu * wv);
                    }
                }
            }
        }
        let chol = BandCholesky::new(&a, "foot-skating normal equations", notes).map_err(failed)?;
        let x = if self.anchors.is_empty() {
            chol.solve(&self.rhs)
        } else {
            self.eliminate_anchors(&chol, notes).map_err(failed)?
        };
        Ok(std::iter::once([0.0; D]).chain((0..n - 1).map(|i| std::array::from_fn(|c| x[(i, c)]))).collect())
    }

    /// The shifts `d(1..T)` of the bordered system by the anchors' Schur complement (module doc).
    fn eliminate_anchors(&self, chol: &BandCholesky, notes: &mut Vec<String>) -> gp::Result<DMatrix<f64>> {
        let (dim, k) = (self.frames - 1, self.anchors.len());
        // Columns [b_d | A_da]: anchor j's column is −1 at the unknowns of its interval.
        let mut cols = DMatrix::<f64>::zeros(dim, D + k);
        cols.columns_mut(0, D).copy_from(&self.rhs);
        for (j, anchor) in self.anchors.iter().enumerate() {
            for t in anchor.frames.clone().filter(|&t| t >= 1) {
                cols[(t - 1, D + j)] = -1.0;
            }
        }
        let y = chol.solve(&cols);
        // Row j of A_ad (A_dd⁻¹ X) is minus the sum of (A_dd⁻¹ X)'s rows over interval j.
        let interval_sum = |j: usize, col: usize| -> f64 {
            self.anchors[j].frames.clone().filter(|&t| t >= 1).map(|t| y[(t - 1, col)]).sum()
        };
        let mut s = DMatrix::<f64>::zeros(k, k);
        let mut r = DMatrix::<f64>::zeros(k, D);
        for (j, anchor) in self.anchors.iter().enumerate() {
            // Lower triangle only (all Cholesky reads).
            for l in 0..=j {
                s[(j, l)] = interval_sum(j, D + l);
            }
            s[(j, j)] += anchor.frames.len() as f64;
            for c in 0..D {
                r[(j, c)] = anchor.sum[c] + interval_sum(j, c);
            }
        }
        let anchors = Cholesky::new(&s, "foot-skating anchors (Schur complement)", notes)?.solve(&r);
        // d = A_dd⁻¹ b_d − (A_dd⁻¹ A_da) a.
        let (z, y_a) = (y.columns(0, D), y.columns(D, k));
        Ok(z - y_a * anchors)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator of numbers in [0, 1) (no dependency for tests).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() * n as f64) as usize
        }
    }

    /// The same minimisation written as dense least squares `min ‖J x − r‖²` over
    /// `x = (d(1..T), anchors)`, one row per residual, solved from its normal equations
    /// `Jᵀ J x = Jᵀ r` by a dense factorisation; the shifts `d(0..T)` per axis.
    fn dense_reference(
        n: usize,
        smoothness: f64,
        ridge: f64,
        velocities: &[(usize, [f64; 2])],
        anchors: &[(usize, Vec<[f64; 2]>)],
    ) -> Vec<[f64; 2]> {
        let k = anchors.len();
        let dim = n - 1 + k;
        let mut rows: Vec<(Vec<(usize, f64)>, [f64; 2])> = Vec::new();
        let d = |t: usize| (t >= 1).then(|| t - 1);
        for &(t, v) in velocities {
            let mut row = vec![(d(t).unwrap(), 1.0)];
            row.extend(d(t - 1).map(|i| (i, -1.0)));
            rows.push((row, v));
        }
        for (j, (start, ps)) in anchors.iter().enumerate() {
            for (t, p) in (*start..).zip(ps) {
                let mut row = vec![(n - 1 + j, -1.0)];
                row.extend(d(t).map(|i| (i, 1.0)));
                rows.push((row, [-p[0], -p[1]]));
            }
        }
        for t in 1..n - 1 {
            let s = smoothness.sqrt();
            let row = [(t - 1, s), (t, -2.0 * s), (t + 1, s)].into_iter().filter_map(|(t, w)| d(t).map(|i| (i, w))).collect();
            rows.push((row, [0.0; 2]));
        }
        for t in 1..n {
            rows.push((vec![(t - 1, ridge.sqrt())], [0.0; 2]));
        }
        let mut j = DMatrix::<f64>::zeros(rows.len(), dim);
        let mut r = DMatrix::<f64>::zeros(rows.len(), 2);
        for (i, (row, rhs)) in rows.iter().enumerate() {
            for &(c, w) in row {
                j[(i, c)] += w;
            }
            r[(i, 0)] = rhs[0];
            r[(i, 1)] = rhs[1];
        }
        let x = (j.transpose() * &j).cholesky().expect("definite normal equations").solve(&(j.transpose() * r));
        std::iter::once([0.0; 2]).chain((0..n - 1).map(|i| [x[(i, 0)], x[(i, 1)]])).collect()
    }

    #[test]
    fn random_problems_of_both_terms_solve_as_the_dense_normal_equations_do() {
        let mut rng = Lcg(39);
        for case in 0..40 {
            let n = 2 + rng.below(60);
            let (smoothness, ridge) = (0.1 + rng.next() * 3.0, [0.0, 1e-9, 0.1][case % 3]);
            let velocities: Vec<(usize, [f64; 2])> = (0..rng.below(2 * n))
                .map(|_| (1 + rng.below(n - 1), [rng.next() - 0.5, 0.1 * rng.next()]))
                .collect();
            let anchors: Vec<(usize, Vec<[f64; 2]>)> = (0..1 + rng.below(6))
                .map(|_| {
                    let start = rng.below(n);
                    let len = 1 + rng.below(n - start);
                    (start, (0..len).map(|_| [rng.next() * 2.0 - 1.0, rng.next()]).collect())
                })
                .collect();
            // The ridge-free cases need a term that fixes the shifts' linear mode: a velocity
            // at frame 1 (d(1) alone).
            let mut problem = Problem::<2>::new(n, smoothness, ridge).unwrap();
            problem.add_velocity(1, [0.02, -0.01]);
            let mut velocities = velocities;
            velocities.insert(0, (1, [0.02, -0.01]));
            for &(t, v) in &velocities[1..] {
                problem.add_velocity(t, v);
            }
            for (start, ps) in &anchors {
                problem.add_anchor(*start, ps);
            }
            let mut notes = Vec::new();
            let got = problem.solve(&mut notes).unwrap();
            let want = dense_reference(n, smoothness, ridge, &velocities, &anchors);
            let scale = want.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-3);
            let err = got.iter().flatten().zip(want.iter().flatten()).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(err <= 1e-10 * scale, "case {case} (T {n}, K {}): error {err:e} of {scale:e}", anchors.len());
            assert_eq!(got[0], [0.0; 2]);
            assert!(notes.is_empty(), "{notes:?}");
        }
    }

    #[test]
    fn a_planted_foot_that_does_not_slide_needs_no_shift() {
        // Two feet planted in turn at fixed points (anchor terms) and a third track whose
        // contact travel is already what is wanted (velocity terms of zero): d = 0.
        let n = 50;
        let mut problem = Problem::<3>::new(n, 1.0, 1e-9).unwrap();
        problem.add_anchor(0, &vec![[0.3, 0.0, 0.1]; 20]);
        problem.add_anchor(15, &vec![[0.8, 0.0, -0.1]; 20]);
        problem.add_anchor(40, &vec![[1.3, 0.0, 0.1]; 10]);
        (20..30).for_each(|t| problem.add_velocity(t, [0.0; 3]));
        let d = problem.solve(&mut Vec::new()).unwrap();
        assert_eq!(d.len(), n);
        assert!(d.iter().flatten().all(|x| x.abs() < 1e-12), "{d:?}");
    }

    #[test]
    fn a_slide_under_an_anchor_comes_back_out() {
        // A foot planted over frames 10-29 slides 1 cm per frame along the first axis: the
        // shift takes the slide out within 2 mm through the middle of the contact.
        let n = 40;
        let mut problem = Problem::<2>::new(n, 1.0, 1e-9).unwrap();
        let slide: Vec<[f64; 2]> = (10..30).map(|t| [0.5 + 0.01 * (t - 10) as f64, 0.2]).collect();
        problem.add_anchor(10, &slide);
        let d = problem.solve(&mut Vec::new()).unwrap();
        let shifted: Vec<f64> = (12..28).map(|t| slide[t - 10][0] + d[t][0]).collect();
        let spread = shifted.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x)) - shifted.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        assert!(spread < 0.002, "{spread} {shifted:?}");
        assert!(d.iter().all(|d| d[1].abs() < 1e-9));
    }

    #[test]
    fn no_terms_no_shift_and_bad_weights_refused() {
        let p = Problem::<2>::new(10, 1.0, 0.1).unwrap();
        assert_eq!(p.solve(&mut Vec::new()).unwrap(), vec![[0.0; 2]; 10]);
        assert_eq!(Problem::<2>::new(0, 1.0, 0.1).unwrap().solve(&mut Vec::new()).unwrap(), Vec::<[f64; 2]>::new());
        let e = Problem::<2>::new(10, -1.0, 0.1).unwrap_err();
        assert!(e.to_string().contains("smoothness"), "{e}");
        assert!(Problem::<2>::new(10, 1.0, f64::NAN).is_err());
    }
}

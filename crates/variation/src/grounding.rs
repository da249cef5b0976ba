//! Grounding of synthesised variations: a post-process (transfer paper §6, "traditional
//! post-processing such as foot-contact clean-up") that is not part of the GPDM model.
//!
//! Sampled bodies inherit their height from the torso GP's gravity values, which drift over a
//! trajectory (feet through the floor or floating). Per frame `t` of a variation, its lowest
//! point `h_v(t)` (lowest of the given sole vertices along `up`, or of all vertices; `hmc-sample`
//! uses all, as sampled toes dip below the soles) is made to follow the source's at
//! the matching source frame `h_s(m(t))`, where `m` is the DTW correspondence of the two pose
//! sequences (the mean matched source frame; identity when the DTW fails). The offset
//! `o(t) = h_s(m(t)) − h_v(t)` is smoothed over time by a Gaussian-weighted local linear fit
//! (σ frames, default 1.5 = 60 ms at 25 fps; linear profiles pass unchanged, even at the ends) so that nothing pops, and the
//! whole frame is shifted by `o(t) · up`.

use gp::dtw::{dtw_path, DtwOptions};
use mesh_core::rigid::RigidMotion;
use nalgebra::{Matrix3, Vector3};


/// Default smoothing width of the offsets (frames).
pub const SIGMA_FRAMES: f64 = 1.5;

/// Per-frame height along `up` of the lowest of `vertices` (all vertices when empty).
pub fn lowest(frames: &[Vec<Vector3<f64>>], vertices: &[u32], up: &Vector3<f64>) -> Vec<f64> {
    frames
        .iter()
        .map(|f| {
            if vertices.is_empty() {
                f.iter().map(|p| p.dot(up)).fold(f64::INFINITY, f64::min)
            } else {
                vertices
                    .iter()
                    .map(|&v| f[v as usize].dot(up))
                    .fold(f64::INFINITY, f64::min)
            }
        })
        .collect()
}

/// Matching source frame (fractional) of every variation frame: the mean source index matched
/// by DTW on template-aligned poses; the (clamped) same index when the DTW fails.
pub fn correspondence(
    var: &[Vec<Vector3<f64>>],
    source: &[Vec<Vector3<f64>>],
    template: &[Vector3<f64>],
) -> Vec<f64> {
    MatchSource::new(source, template).matches(var)
}

/// Vertices of the pose cost of [`correspondence`] (evenly subsampled, as
/// `prealign::pose_cost` subsamples them).
const MATCH_VERTICES: usize = 400;

/// The vertices of a body of `n` vertices the pose cost of [`correspondence`] compares: every
/// `ceil(n / 400)`-th.
pub fn match_vertices(n: usize) -> Vec<usize> {
    let step = n.div_ceil(MATCH_VERTICES).max(1);
    (0..n).step_by(step).collect()
}

/// The source side of [`correspondence`], prepared once for any number of variations: the
/// subsampled vertices ([`match_vertices`]) of every source frame rigidly aligned to the
/// template (the alignment fitted on all vertices, as [`crate::metrics::normalise`] fits it;
/// [`TemplateFit`]).
pub struct MatchSource {
    fit: TemplateFit,
    len: usize,
    idx: Vec<usize>,
    poses: Vec<Vec<Vector3<f64>>>,
}

impl MatchSource {
    pub fn new(source: &[Vec<Vector3<f64>>], template: &[Vector3<f64>]) -> MatchSource {
        let idx = match_vertices(source.first().map_or(0, |f| f.len()));
        let fit = TemplateFit::new(template);
        MatchSource {
            len: source.len(),
            poses: fit.aligned_rows(source, &idx),
            fit,
            idx,
        }
    }

    /// The matcher of a source whose aligned rows (as [`MatchSource::new`] makes them from its
    /// frames, one per frame, [`match_vertices`] of the template's vertex count each) are
    /// `rows`.
    pub fn from_rows(template: &[Vector3<f64>], rows: Vec<Vec<Vector3<f64>>>) -> MatchSource {
        MatchSource {
            len: rows.len(),
            idx: match_vertices(template.len()),
            fit: TemplateFit::new(template),
            poses: rows,
        }
    }

    /// The source's aligned rows, one per frame.
    pub fn into_rows(self) -> Vec<Vec<Vector3<f64>>> {
        self.poses
    }

    /// [`correspondence`] of `var` to this source.
    pub fn matches(&self, var: &[Vec<Vector3<f64>>]) -> Vec<f64> {
        let identity = || {
            (0..var.len())
                .map(|t| t.min(self.len.saturating_sub(1)) as f64)
                .collect()
        };
        if var.is_empty() || self.len == 0 {
            return identity();
        }
        let a = self.fit.aligned_rows(var, &self.idx);
        // The rows are already subsampled: every one of them is used.
        let cost = crate::prealign::pose_cost(&a, &self.poses, usize::MAX);
        let Ok(path) = dtw_path(&cost, &[], &DtwOptions::default()) else {
            return identity();
        };
        let mut sum = vec![0.0; var.len()];
        let mut count = vec![0usize; var.len()];
        for (i, j) in path {
            if i < var.len() {
                sum[i] += j as f64;
                count[i] += 1;
            }
        }
        (0..var.len())
            .map(|i| {
                if count[i] > 0 {
                    sum[i] / count[i] as f64
                } else {
                    i.min(self.len - 1) as f64
                }
            })
            .collect()
    }
}

/// Rigid alignment of frames to one template (`mesh_core::rigid::procrustes(frame, template)`,
/// unweighted) with the template's side precomputed: its centroid `c_t` and centred points
/// `e_i = t_i − c_t`, so that a frame's cross-covariance is `H = Σ (s_i − c_s) e_iᵀ`, nine
/// products per vertex. The same motion as `procrustes` up to rounding.
pub struct TemplateFit {
    centroid: Vector3<f64>,
    /// Centred template, one array per coordinate.
    e: [Vec<f64>; 3],
}

impl TemplateFit {
    pub fn new(template: &[Vector3<f64>]) -> TemplateFit {
        let n = template.len().max(1) as f64;
        let centroid = template.iter().sum::<Vector3<f64>>() / n;
        let e = [0, 1, 2].map(|a| template.iter().map(|p| p[a] - centroid[a]).collect());
        TemplateFit { centroid, e }
    }

    /// The rigid motion taking `frame` (one point per template vertex) onto the template; the
    /// identity for an empty frame or one of another vertex count.
    pub fn fit(&self, frame: &[Vector3<f64>]) -> RigidMotion {
        let n = frame.len();
        if n == 0 || n != self.e[0].len() {
            return RigidMotion::identity();
        }
        let cs = frame.iter().sum::<Vector3<f64>>() / n as f64;
        let mut h = [0.0f64; 9];
        for (i, p) in frame.iter().enumerate() {
            let s = [p.x - cs.x, p.y - cs.y, p.z - cs.z];
            let e = [self.e[0][i], self.e[1][i], self.e[2][i]];
            for a in 0..3 {
                for b in 0..3 {
                    h[3 * a + b] += s[a] * e[b];
                }
            }
        }
        let h = Matrix3::from_row_slice(&h);
        mesh_core::rigid::rigid_from_moments(&cs, &self.centroid, &h)
    }

    /// Vertices `idx` of every frame after the frame's alignment ([`TemplateFit::fit`]).
    pub fn aligned_rows(&self, frames: &[Vec<Vector3<f64>>], idx: &[usize]) -> Vec<Vec<Vector3<f64>>> {
        frames
            .iter()
            .map(|f| {
                let r = self.fit(f);
                idx.iter().map(|&v| r.apply(&f[v])).collect()
            })
            .collect()
    }
}

/// Linear interpolation of `values` at fractional index `x` (clamped to the ends).
pub(crate) fn at(values: &[f64], x: f64) -> f64 {
    let x = x.clamp(0.0, (values.len() - 1) as f64);
    let i = (x.floor() as usize).min(values.len() - 1);
    let j = (i + 1).min(values.len() - 1);
    let f = x - i as f64;
    values[i] * (1.0 - f) + values[j] * f
}

/// Smoothed vertical offsets `o(t)` taking the variation's sole heights `var_low` to the
/// source's `source_low` at the matching frames `matches` (see the module doc).
pub fn offsets(var_low: &[f64], source_low: &[f64], matches: &[f64], sigma: f64) -> Vec<f64> {
    if source_low.is_empty() {
        return vec![0.0; var_low.len()];
    }
    let raw: Vec<f64> = var_low
        .iter()
        .zip(matches)
        .map(|(&h, &m)| at(source_low, m) - h)
        .collect();
    crate::local_linear::fit(&raw, sigma)
}

/// Grounds `var` on `source` in place (module doc); returns the applied offsets (m).
pub fn ground(
    var: &mut [Vec<Vector3<f64>>],
    source: &[Vec<Vector3<f64>>],
    soles: &[u32],
    template: &[Vector3<f64>],
    up: &Vector3<f64>,
    sigma: f64,
) -> Vec<f64> {
    let matches = correspondence(var, source, template);
    ground_matched(var, source, &matches, soles, up, sigma)
}

/// [`ground`] with the matching source frames already known (from [`correspondence`], which
/// vertical and horizontal shifts of the variation leave unchanged).
pub fn ground_matched(
    var: &mut [Vec<Vector3<f64>>],
    source: &[Vec<Vector3<f64>>],
    matches: &[f64],
    soles: &[u32],
    up: &Vector3<f64>,
    sigma: f64,
) -> Vec<f64> {
    let var_low = lowest(var, soles, up);
    ground_on(var, &var_low, &lowest(source, soles, up), matches, up, sigma)
}

/// [`ground_matched`] with the lowest heights ([`lowest`], of the same vertices) of the
/// variation, `var_low`, and of the source, `source_low`, already known.
pub fn ground_on(
    var: &mut [Vec<Vector3<f64>>],
    var_low: &[f64],
    source_low: &[f64],
    matches: &[f64],
    up: &Vector3<f64>,
    sigma: f64,
) -> Vec<f64> {
    let o = offsets(var_low, source_low, matches, sigma);
    for (f, &d) in var.iter_mut().zip(&o) {
        let shift = up * d;
        f.iter_mut().for_each(|p| *p += shift);
    }
    o
}

/// Floor contact of a variation against its source, in metres: `penetration` the largest depth
/// of the variation's lowest point below the floor (the source's lowest point over all frames),
/// `floating` the largest height of its lowest point above the floor over the frames whose
/// matching source frame is in contact (source lowest point within `contact_height` of the
/// floor). Both 0 when perfect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorContact {
    pub penetration: f64,
    pub floating: f64,
}

/// [`FloorContact`] of per-frame lowest heights `var_low`, `source_low` and the matches.
pub fn floor_contact(
    var_low: &[f64],
    source_low: &[f64],
    matches: &[f64],
    contact_height: f64,
) -> FloorContact {
    let floor = source_low.iter().copied().fold(f64::INFINITY, f64::min);
    if !floor.is_finite() {
        return FloorContact {
            penetration: 0.0,
            floating: 0.0,
        };
    }
    let penetration = var_low.iter().map(|h| floor - h).fold(0.0_f64, f64::max);
    let floating = var_low
        .iter()
        .zip(matches)
        .filter(|(_, &m)| source_low[m.round() as usize] - floor <= contact_height)
        .map(|(h, _)| h - floor)
        .fold(0.0_f64, f64::max);
    FloorContact {
        penetration,
        floating,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Unit};

    /// A rigidly moved, slightly deformed copy of `t`.
    fn moved(t: &[Vector3<f64>], angle: f64, shift: Vector3<f64>, wobble: f64) -> Vec<Vector3<f64>> {
        let r = Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::new(0.3, 1.0, -0.2)), angle);
        t.iter()
            .enumerate()
            .map(|(i, p)| r * (p + Vector3::new(wobble * (i as f64 * 0.7).sin(), 0.0, 0.0)) + shift)
            .collect()
    }

    #[test]
    fn template_fit_is_procrustes_onto_the_template() {
        let t = mesh_core::shapes::icosphere(2).vertices;
        let fit = TemplateFit::new(&t);
        for (angle, wobble) in [(0.0, 0.0), (0.4, 0.0), (2.9, 0.01), (-1.3, 0.05)] {
            let f = moved(&t, angle, Vector3::new(3.0, -0.5, 12.0), wobble);
            let (a, b) = (fit.fit(&f), mesh_core::rigid::procrustes(&f, &t, None));
            for p in &f {
                assert!((a.apply(p) - b.apply(p)).norm() < 1e-12, "angle {angle}");
            }
            if wobble == 0.0 {
                // An exact rigid copy goes back onto the template.
                for (p, q) in f.iter().zip(&t) {
                    assert!((a.apply(p) - q).norm() < 1e-12);
                }
            }
        }
        assert_eq!(fit.fit(&t[..5]), RigidMotion::identity(), "another vertex count");
    }

    #[test]
    fn a_delayed_copy_matches_its_source_frames() {
        // Source: a sphere whose x-scale oscillates, travelling and turning; the variation is
        // its frames 4.. placed elsewhere: frame i matches source frame i + 4.
        let t = mesh_core::shapes::icosphere(2).vertices;
        let source: Vec<Vec<Vector3<f64>>> = (0..40)
            .map(|k| {
                let s = 1.0 + 0.3 * (0.25 * k as f64).sin() + 0.01 * k as f64;
                let f: Vec<_> = t.iter().map(|p| Vector3::new(p.x * s, p.y, p.z)).collect();
                moved(&f, 0.05 * k as f64, Vector3::new(0.1 * k as f64, 0.0, 0.0), 0.0)
            })
            .collect();
        let var: Vec<_> = source[4..]
            .iter()
            .map(|f| moved(f, 1.0, Vector3::new(-2.0, 0.0, 5.0), 0.0))
            .collect();
        let m = MatchSource::new(&source, &t).matches(&var);
        assert_eq!(m, correspondence(&var, &source, &t));
        // The path starts at the corner (0, 0), then catches up within a few frames.
        for (i, &j) in m.iter().enumerate().skip(6) {
            assert!((j - (i + 4) as f64).abs() < 1e-9, "frame {i}: {m:?}");
        }
    }

    #[test]
    fn floor_contact_known_answer() {
        let src = [0.0, 0.0, 0.2, 0.0];
        let var = [-0.03, 0.05, 0.4, 0.01];
        let m = [0.0, 1.0, 2.0, 3.0];
        let c = floor_contact(&var, &src, &m, 0.02);
        assert!((c.penetration - 0.03).abs() < 1e-12);
        // Frame 2 is a source flight frame and does not count as floating.
        assert!((c.floating - 0.05).abs() < 1e-12);
    }

    /// A small articulated "body" (8 points) at frame `t`: a leg swinging by a growing angle
    /// (every pose distinct), travelling forward, with a jump (height profile) in frames 8-14.
    fn body(t: usize) -> Vec<Vector3<f64>> {
        let a = 0.06 * t as f64;
        let hop = if (8..=14).contains(&t) {
            0.3 * ((t - 8) as f64 * std::f64::consts::PI / 6.0).sin()
        } else {
            0.0
        };
        let base = Vector3::new(0.05 * t as f64, 0.0, hop);
        let mut pts = vec![
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(0.1, 0.2, 1.5),
            Vector3::new(-0.1, -0.2, 1.4),
            Vector3::new(0.0, 0.1, 0.0),
            Vector3::new(0.05, 0.1, 0.0),
        ];
        // Swinging leg: hip at height 1, foot below it.
        for k in 1..=3 {
            let r = 0.33 * k as f64;
            pts.push(Vector3::new(r * a.sin(), -0.1, 1.0 - r * a.cos()));
        }
        pts.iter().map(|p| p + base).collect()
    }

    #[test]
    fn grounding_recovers_the_source_height() {
        let up = Vector3::z();
        let source: Vec<Vec<Vector3<f64>>> = (0..24).map(body).collect();
        let template = source[0].clone();
        let soles = [3u32, 4, 7];
        // Linear drift: recovered exactly (the smoother keeps lines, DTW matches frame to frame).
        let drift = |t: usize| -0.14 + 0.011 * t as f64;
        let mut var: Vec<Vec<Vector3<f64>>> = source
            .iter()
            .enumerate()
            .map(|(t, f)| f.iter().map(|p| p + up * drift(t)).collect())
            .collect();
        let o = ground(&mut var, &source, &soles, &template, &up, 2.0);
        for t in 0..source.len() {
            assert!((o[t] + drift(t)).abs() < 1e-9, "frame {t}: {}", o[t]);
            for (p, q) in var[t].iter().zip(&source[t]) {
                assert!((p - q).norm() < 1e-9);
            }
        }
        // Smooth non-linear drift (period 24 frames, 5 cm): back within a few mm.
        let wave = |t: usize| 0.05 * (t as f64 * std::f64::consts::TAU / 24.0).sin();
        let mut var: Vec<Vec<Vector3<f64>>> = source
            .iter()
            .enumerate()
            .map(|(t, f)| f.iter().map(|p| p + up * wave(t)).collect())
            .collect();
        let before = floor_contact(
            &lowest(&var, &[], &up),
            &lowest(&source, &[], &up),
            &correspondence(&var, &source, &template),
            0.02,
        );
        assert!(
            before.penetration > 0.04 && before.floating > 0.04,
            "{before:?}"
        );
        ground(&mut var, &source, &soles, &template, &up, 1.5);
        let err = lowest(&var, &soles, &up)
            .iter()
            .zip(lowest(&source, &soles, &up))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 0.005, "height error {err}");
        let after = floor_contact(
            &lowest(&var, &[], &up),
            &lowest(&source, &[], &up),
            &correspondence(&var, &source, &template),
            0.02,
        );
        assert!(
            after.penetration < 0.005 && after.floating < 0.005,
            "{after:?}"
        );
    }
}

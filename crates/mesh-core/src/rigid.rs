//! Rigid motion: orthogonal Procrustes alignment, the SO(3) exponential map
//! and the 6-vector parametrisation of the transfer paper (§4, "Rigid
//! Transformation"): each pose's rigid displacement from the previous pose,
//! `(dT, dR) -> (t_x, t_y, t_z, h_1, h_2, h_3)`, with `h = log(dR)` the
//! exponential-map (axis times angle) coordinates of the rotation.

use nalgebra::{Matrix3, Rotation3, Vector3, Vector6};
use serde::{Deserialize, Serialize};

/// A rigid motion `x -> R x + t`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigidMotion {
    pub rotation: Rotation3<f64>,
    pub translation: Vector3<f64>,
}

impl Default for RigidMotion {
    fn default() -> Self {
        Self::identity()
    }
}

impl RigidMotion {
    pub fn new(rotation: Rotation3<f64>, translation: Vector3<f64>) -> Self {
        RigidMotion {
            rotation,
            translation,
        }
    }

    pub fn identity() -> Self {
        RigidMotion {
            rotation: Rotation3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// `R p + t`.
    pub fn apply(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }

    /// Applies the motion to every point.
    pub fn apply_all(&self, points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        points.iter().map(|p| self.apply(p)).collect()
    }

    /// `self ∘ other`: first `other`, then `self`
    /// (`R = R_self R_other`, `t = R_self t_other + t_self`).
    pub fn compose(&self, other: &RigidMotion) -> RigidMotion {
        RigidMotion {
            rotation: self.rotation * other.rotation,
            translation: self.rotation * other.translation + self.translation,
        }
    }

    /// The inverse motion `x -> R^T (x - t)`.
    pub fn inverse(&self) -> RigidMotion {
        let r_inv = self.rotation.inverse();
        RigidMotion {
            rotation: r_inv,
            translation: -(r_inv * self.translation),
        }
    }

    /// The paper's 6-vector `(t_x, t_y, t_z, h_1, h_2, h_3)` with `h = so3_log(R)`.
    pub fn to_6vec(&self) -> Vector6<f64> {
        let t = &self.translation;
        let h = so3_log(&self.rotation);
        Vector6::new(t.x, t.y, t.z, h.x, h.y, h.z)
    }

    /// Inverse of [`RigidMotion::to_6vec`]: `R = so3_exp(h)`.
    pub fn from_6vec(v: &Vector6<f64>) -> RigidMotion {
        RigidMotion {
            rotation: so3_exp(&Vector3::new(v[3], v[4], v[5])),
            translation: Vector3::new(v[0], v[1], v[2]),
        }
    }
}

/// The displacement from `prev` to `cur` expressed in `prev`'s body frame:
/// `prev^{-1} ∘ cur`, so that `cur = prev ∘ relative`. This is the paper's
/// elementary rigid motion `(dT_i, dR_i)` of pose `i` relative to pose `i-1`;
/// it does not depend on where the motion starts or which way it faces.
pub fn relative_in_body_frame(prev: &RigidMotion, cur: &RigidMotion) -> RigidMotion {
    prev.inverse().compose(cur)
}

/// The body-frame displacements between consecutive motions
/// (`n` motions give `n - 1` displacements).
pub fn relative_motions(motions: &[RigidMotion]) -> Vec<RigidMotion> {
    motions
        .windows(2)
        .map(|w| relative_in_body_frame(&w[0], &w[1]))
        .collect()
}

/// Integrates body-frame displacements from `start`: returns
/// `[start, start ∘ d_1, start ∘ d_1 ∘ d_2, ...]` (`n` displacements give
/// `n + 1` motions). Inverse of [`relative_motions`].
pub fn integrate(start: &RigidMotion, relative: &[RigidMotion]) -> Vec<RigidMotion> {
    let mut out = Vec::with_capacity(relative.len() + 1);
    let mut cur = *start;
    out.push(cur);
    for d in relative {
        cur = cur.compose(d);
        out.push(cur);
    }
    out
}

/// `[w]_x`, the cross-product matrix: `[w]_x v = w x v`.
pub fn hat(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

/// Exponential map so(3) -> SO(3) (Rodrigues):
/// `R = I + (sin θ / θ) [h]_x + ((1 - cos θ) / θ^2) [h]_x^2`, `θ = |h|`,
/// with Taylor series for the two coefficients when `θ` is small.
pub fn so3_exp(h: &Vector3<f64>) -> Rotation3<f64> {
    let theta2 = h.norm_squared();
    let theta = theta2.sqrt();
    let (a, b) = if theta < 1e-4 {
        // Truncation error below theta^6 / 5040 < 1e-24.
        (
            1.0 - theta2 / 6.0 + theta2 * theta2 / 120.0,
            0.5 - theta2 / 24.0 + theta2 * theta2 / 720.0,
        )
    } else {
        (theta.sin() / theta, (1.0 - theta.cos()) / theta2)
    };
    let k = hat(h);
    Rotation3::from_matrix_unchecked(Matrix3::identity() + k * a + k * k * b)
}

/// Logarithm map SO(3) -> so(3), the inverse of [`so3_exp`]; returns `h` with
/// `|h| = θ ∈ [0, π]`.
///
/// `θ = atan2(|v|, (tr R - 1) / 2)` with `v = vee(R - R^T) / 2 = sin θ · a`
/// (accurate at every angle). For `θ < π/2` the axis is `v / sin θ`
/// (Taylor series of `θ / sin θ` near 0). Near `π`, `sin θ` vanishes and the
/// axis is read from the symmetric part instead:
/// `(R + R^T) / 2 - cos θ I = (1 - cos θ) a a^T`, taking its largest column and
/// the sign that agrees with `v` (at exactly `π` both signs are the same rotation).
pub fn so3_log(r: &Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    let v = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5;
    let sin_t = v.norm();
    let cos_t = (m.trace() - 1.0) * 0.5;
    let theta = sin_t.atan2(cos_t);
    if cos_t >= 0.0 {
        let scale = if theta < 1e-4 {
            1.0 + theta * theta / 6.0 + 7.0 * theta.powi(4) / 360.0
        } else {
            theta / sin_t
        };
        return v * scale;
    }
    let s = (m + m.transpose()) * 0.5 - Matrix3::identity() * cos_t;
    let i = (0..3)
        .max_by(|&i, &j| s[(i, i)].total_cmp(&s[(j, j)]))
        .unwrap_or(0);
    let col: Vector3<f64> = s.column(i).into_owned();
    let mut axis = col / col.norm();
    if axis.dot(&v) < 0.0 {
        axis = -axis;
    }
    axis * theta
}

/// Orthogonal Procrustes without scale (Kabsch / Umeyama): the rigid motion
/// minimising `Σ_i w_i |R src_i + t - dst_i|^2` (all `w_i = 1` if `weights` is
/// `None`).
///
/// With weighted centroids `c_s`, `c_d` and cross-covariance
/// `H = Σ w_i (src_i - c_s)(dst_i - c_d)^T = U Σ V^T`:
/// `R = V diag(1, 1, d) U^T` with `d = sign det(V U^T)` (the reflection
/// guard: `det R = +1` even for mirrored data), and `t = c_d - R c_s`.
///
/// Empty input or a zero total weight gives the identity. Non-finite input
/// gives a motion full of NaN (validate meshes on load).
///
/// # Panics
/// If `src`, `dst` (and `weights`) differ in length: a programming error.
pub fn procrustes(
    src: &[Vector3<f64>],
    dst: &[Vector3<f64>],
    weights: Option<&[f64]>,
) -> RigidMotion {
    assert_eq!(
        src.len(),
        dst.len(),
        "procrustes: point sets differ in length"
    );
    if let Some(w) = weights {
        assert_eq!(
            w.len(),
            src.len(),
            "procrustes: weights differ in length from points"
        );
    }
    let w = |i: usize| weights.map_or(1.0, |w| w[i]);
    let total: f64 = (0..src.len()).map(w).sum();
    if src.is_empty() || total == 0.0 {
        return RigidMotion::identity();
    }
    let mut cs = Vector3::zeros();
    let mut cd = Vector3::zeros();
    for i in 0..src.len() {
        cs += src[i] * w(i);
        cd += dst[i] * w(i);
    }
    cs /= total;
    cd /= total;
    let mut h = Matrix3::zeros();
    for i in 0..src.len() {
        h += (src[i] - cs) * (dst[i] - cd).transpose() * w(i);
    }
    rigid_from_moments(&cs, &cd, &h)
}

/// The rotation and translation of [`procrustes`] from its moments: source centroid `cs`,
/// target centroid `cd`, cross-covariance `h = Σ w_i (s_i − cs)(d_i − cd)ᵀ` (Kabsch with the
/// reflection guard). Non-finite moments or a failed SVD give a NaN motion.
pub fn rigid_from_moments(cs: &Vector3<f64>, cd: &Vector3<f64>, h: &Matrix3<f64>) -> RigidMotion {
    let nan = || RigidMotion {
        rotation: Rotation3::from_matrix_unchecked(Matrix3::from_element(f64::NAN)),
        translation: Vector3::from_element(f64::NAN),
    };
    if !h
        .iter()
        .chain(cs.iter())
        .chain(cd.iter())
        .all(|x| x.is_finite())
    {
        return nan();
    }
    let Some(svd) = h.try_svd(true, true, f64::EPSILON, 10_000) else {
        return nan();
    };
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return nan();
    };
    let v = v_t.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    let rotation = Rotation3::from_matrix_unchecked(r);
    RigidMotion {
        rotation,
        translation: cd - rotation * cs,
    }
}

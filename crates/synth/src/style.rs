//! A subject's own motion style: a deterministic non-linear map of joint rotations and a
//! smooth monotonic time warp (its cadence).
//!
//! The map acts on canonical local rotations `q_b = Q_p^T Q_b`, where `Q_b = R_b C_b^T` and
//! `C_b` is the shortest arc from the body's rest bone direction to "straight down" for limb
//! bones (identity otherwise), i.e. rotations relative to an arms-down, legs-down stance,
//! whatever the source's rest pose. Maps (rotation vector `r`, angle `θ = |r|`):
//! - upper arm: swing (the rotation vector's component `r_x` about the lateral axis)
//!   `r_x' = θmax tanh(g r_x / θmax)` (saturated larger/smaller swing), then an abduction by
//!   `α` about the forward axis;
//! - forearm: `θ' = e θ`; knee: `θ' = θ + k θ² / π` (deeper bend at high flexion);
//! - upper leg: abduction by `β`; spine: forward lean `λ · v` with `v` the root speed (m/s).

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::retarget::{shortest_arc, LIMB_BONES};
use crate::skeleton::Skeleton;

/// Smooth monotonic time warp from subject time `t` to mocap time
/// `φ(t) = rate t + amp sin(2π t / period + phase) - amp sin(phase)`; monotonic while
/// `amp 2π / period < rate`.
#[derive(Clone, Copy, Debug)]
pub struct TimeWarp {
    pub rate: f64,
    pub amp: f64,
    pub period: f64,
    pub phase: f64,
}

impl TimeWarp {
    pub fn identity() -> Self {
        TimeWarp {
            rate: 1.0,
            amp: 0.0,
            period: 1.0,
            phase: 0.0,
        }
    }
    pub fn mocap_time(&self, t: f64) -> f64 {
        use std::f64::consts::TAU;
        self.rate * t + self.amp * ((TAU * t / self.period + self.phase).sin() - self.phase.sin())
    }
    /// Minimum of `φ'(t)`; positive means strictly monotonic.
    pub fn min_slope(&self) -> f64 {
        self.rate - self.amp.abs() * std::f64::consts::TAU / self.period
    }
}

/// Style parameters of one subject.
#[derive(Clone, Copy, Debug)]
pub struct Style {
    pub arm_gain: f64,
    pub arm_max: f64,
    pub arm_abduction: f64,
    pub elbow_gain: f64,
    pub knee_k: f64,
    pub hip_abduction: f64,
    pub lean_per_speed: f64,
    pub warp: TimeWarp,
}

impl Style {
    /// The identity style (no change to the mocap).
    pub fn neutral() -> Self {
        Style {
            arm_gain: 1.0,
            arm_max: 1e9,
            arm_abduction: 0.0,
            elbow_gain: 1.0,
            knee_k: 0.0,
            hip_abduction: 0.0,
            lean_per_speed: 0.0,
            warp: TimeWarp::identity(),
        }
    }
}

fn scale_angle(q: &UnitQuaternion<f64>, f: impl Fn(f64) -> f64) -> UnitQuaternion<f64> {
    let r = q.scaled_axis();
    let th = r.norm();
    if th < 1e-12 {
        return *q;
    }
    UnitQuaternion::from_scaled_axis(r * (f(th) / th))
}

/// Precomputed canonical frames of one skeleton.
#[derive(Clone, Debug)]
pub struct Stylist {
    canon: Vec<UnitQuaternion<f64>>,
    parent: Vec<Option<usize>>,
    role: Vec<Role>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    Other,
    UpperArm(f64),
    ForeArm,
    Knee,
    UpperLeg(f64),
    Spine,
}

impl Stylist {
    pub fn new(skel: &Skeleton) -> Self {
        let down = -Vector3::y();
        let canon = skel
            .bones
            .iter()
            .map(|b| {
                if LIMB_BONES.contains(&b.name.as_str()) {
                    shortest_arc(&b.direction(), &down)
                } else {
                    UnitQuaternion::identity()
                }
            })
            .collect();
        let role = skel
            .bones
            .iter()
            .map(|b| match b.name.as_str() {
                "LeftArm" => Role::UpperArm(1.0),
                "RightArm" => Role::UpperArm(-1.0),
                "LeftForeArm" | "RightForeArm" => Role::ForeArm,
                "LeftLeg" | "RightLeg" => Role::Knee,
                "LeftUpLeg" => Role::UpperLeg(1.0),
                "RightUpLeg" => Role::UpperLeg(-1.0),
                "Spine" => Role::Spine,
                _ => Role::Other,
            })
            .collect();
        Stylist {
            canon,
            parent: skel.bones.iter().map(|b| b.parent).collect(),
            role,
        }
    }

    /// Applies `style` to world rotations `rots` (in place); `speed` is the root speed in m/s.
    pub fn apply(&self, style: &Style, rots: &mut [Rotation3<f64>], speed: f64) {
        let n = rots.len();
        let q: Vec<UnitQuaternion<f64>> = (0..n)
            .map(|b| UnitQuaternion::from_rotation_matrix(&rots[b]) * self.canon[b].inverse())
            .collect();
        let mut out: Vec<UnitQuaternion<f64>> = Vec::with_capacity(n);
        let fwd = Vector3::z_axis();
        for b in 0..n {
            let local = match self.parent[b] {
                Some(p) => q[p].inverse() * q[b],
                None => q[b],
            };
            let local = match self.role[b] {
                Role::Other => local,
                Role::UpperArm(side) => {
                    let (g, m) = (style.arm_gain, style.arm_max);
                    // Swing = the rotation vector's component about the lateral (x) axis.
                    let mut r = local.scaled_axis();
                    r.x = m * (g * r.x / m).tanh();
                    let swung = UnitQuaternion::from_scaled_axis(r);
                    UnitQuaternion::from_axis_angle(&fwd, side * style.arm_abduction) * swung
                }
                Role::ForeArm => scale_angle(&local, |th| style.elbow_gain * th),
                Role::Knee => scale_angle(&local, |th| {
                    th + style.knee_k * th * th / std::f64::consts::PI
                }),
                Role::UpperLeg(side) => {
                    UnitQuaternion::from_axis_angle(&fwd, side * style.hip_abduction) * local
                }
                Role::Spine => {
                    UnitQuaternion::from_axis_angle(
                        &Vector3::x_axis(),
                        style.lean_per_speed * speed,
                    ) * local
                }
            };
            let world = match self.parent[b] {
                Some(p) => out[p] * local,
                None => local,
            };
            out.push(world);
        }
        for b in 0..n {
            rots[b] = (out[b] * self.canon[b]).to_rotation_matrix();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_warps_of_the_presets_are_monotonic() {
        for s in [
            crate::preset::subject_a(crate::subject::Topology::Body, 25.0),
            crate::preset::subject_b(crate::subject::Topology::Body, 50.0),
            crate::preset::subject_c(),
            crate::preset::subject_d(),
            crate::preset::subject_e(),
            crate::preset::subject_f(),
        ] {
            let w = s.style.warp;
            assert!(w.min_slope() > 0.0);
            assert_eq!(w.mocap_time(0.0), 0.0);
            let ts: Vec<f64> = (0..2000).map(|k| w.mocap_time(k as f64 * 0.005)).collect();
            assert!(ts.windows(2).all(|p| p[1] > p[0]));
        }
    }

    #[test]
    fn angle_maps_keep_the_axis_and_change_the_angle() {
        let q = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 1.0);
        let k = scale_angle(&q, |t| t + 0.35 * t * t / std::f64::consts::PI);
        assert!((k.angle() - (1.0 + 0.35 / std::f64::consts::PI)).abs() < 1e-12);
        assert!((k.axis().unwrap().into_inner() - Vector3::x()).norm() < 1e-12);
    }
}

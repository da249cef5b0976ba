//! Motion capture input: DeepMimic clips (JSON, retargeted CMU/SFU mocap) and CMU BVH, parsed
//! into one form: per frame the root position and the world rotation of each source segment,
//! expressed in the body's axes (+Y up, facing +Z, left +X), plus the segments' rest directions.
//!
//! Segments carry CMU names (`Hips`, `Spine1`, `Neck`, `LeftUpLeg`, `LeftLeg`, `LeftFoot`,
//! `LeftArm`, `LeftForeArm`, ...), so that the retargeting table is shared.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde_json::Value;

use mesh_core::{Error, Result};

/// A motion clip in body axes. `globals[f][s]` is the world rotation of segment `s` at frame
/// `f` relative to the source's rest pose; `rest_dirs[s]` the segment's rest direction.
#[derive(Clone, Debug)]
pub struct Clip {
    pub name: String,
    pub segments: Vec<String>,
    pub rest_dirs: Vec<Vector3<f64>>,
    pub times: Vec<f64>,
    pub root: Vec<Vector3<f64>>,
    pub globals: Vec<Vec<UnitQuaternion<f64>>>,
    /// Hip-to-ankle length of the source skeleton, in the clip's units.
    pub leg_length: f64,
}

/// A clip sampled at one instant.
#[derive(Clone, Debug)]
pub struct Sample {
    pub root: Vector3<f64>,
    pub globals: Vec<UnitQuaternion<f64>>,
}

impl Clip {
    pub fn duration(&self) -> f64 {
        *self.times.last().unwrap_or(&0.0)
    }
    pub fn n_frames(&self) -> usize {
        self.times.len()
    }
    pub fn segment(&self, name: &str) -> Option<usize> {
        self.segments.iter().position(|s| s == name)
    }

    /// The clip at time `t` (clamped): linear root, slerped rotations.
    pub fn sample(&self, t: f64) -> Sample {
        let n = self.times.len();
        let t = t.clamp(0.0, self.duration());
        let k = self
            .times
            .partition_point(|&x| x <= t)
            .clamp(1, n.max(2) - 1);
        if n < 2 {
            return Sample {
                root: self.root[0],
                globals: self.globals[0].clone(),
            };
        }
        let (t0, t1) = (self.times[k - 1], self.times[k]);
        let a = if t1 > t0 {
            ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let root = self.root[k - 1].lerp(&self.root[k], a);
        let globals = self.globals[k - 1]
            .iter()
            .zip(&self.globals[k])
            .map(|(q0, q1)| q0.try_slerp(q1, a, 1e-12).unwrap_or(*q0))
            .collect();
        Sample { root, globals }
    }

    /// Horizontal root speed at time `t` (central difference over +-50 ms), clip units/s.
    pub fn root_speed(&self, t: f64) -> f64 {
        let h = 0.05;
        let (a, b) = ((t - h).max(0.0), (t + h).min(self.duration()));
        if b <= a {
            return 0.0;
        }
        let d = self.sample(b).root - self.sample(a).root;
        (d.x * d.x + d.z * d.z).sqrt() / (b - a)
    }

    /// Repeats a cyclic clip `cycles` times, carrying the root's horizontal displacement.
    pub fn looped(mut self, cycles: usize) -> Self {
        let n = self.times.len();
        if cycles <= 1 || n < 2 {
            return self;
        }
        let period = self.duration();
        let mut shift = self.root[n - 1] - self.root[0];
        shift.y = 0.0;
        for c in 1..cycles {
            for f in 1..n {
                self.times.push(self.times[f] + c as f64 * period);
                self.root.push(self.root[f] + shift * c as f64);
                self.globals.push(self.globals[f].clone());
            }
        }
        self
    }

    /// The clip walked along a curve: its heading turned at `rate` radians per second about the
    /// vertical (+y; positive turns +z, the body's forward, toward +x, its left). Frame `f`'s
    /// segments are turned by `rate · t_f` about the root, and each frame's horizontal root step
    /// by the same angle, so a straight walk follows an arc of radius `speed / rate`. 0 leaves
    /// the clip as it is.
    pub fn turned(mut self, rate: f64) -> Self {
        if rate == 0.0 {
            return self;
        }
        let mut prev = self.root.first().copied().unwrap_or_default();
        for f in 1..self.times.len() {
            let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), rate * self.times[f]);
            let step = self.root[f] - prev;
            prev = self.root[f];
            self.root[f] = self.root[f - 1] + turn * step;
            for g in &mut self.globals[f] {
                *g = turn * *g;
            }
        }
        self
    }

    /// The part of the clip between `t0` and `t1` (seconds), times restarting at zero.
    pub fn window(mut self, t0: f64, t1: f64) -> Self {
        let keep: Vec<usize> = (0..self.times.len())
            .filter(|&i| self.times[i] >= t0 && self.times[i] <= t1)
            .collect();
        if keep.len() >= 2 {
            let start = self.times[keep[0]];
            self.times = keep.iter().map(|&i| self.times[i] - start).collect();
            self.root = keep.iter().map(|&i| self.root[i]).collect();
            self.globals = keep.iter().map(|&i| self.globals[i].clone()).collect();
        }
        self
    }
}

/// DeepMimic axes (x forward, y up, z right) into body axes: `M = [[0,0,-1],[0,1,0],[1,0,0]]`.
fn deepmimic_axes() -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(Matrix3::new(0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0))
}

/// DeepMimic's humanoid leg length (hip to ankle) from `humanoid.urdf`: the knee and ankle
/// joint origins, times the 0.25 global scaling DeepMimic loads the URDF with.
pub fn deepmimic_leg_length(urdf: &Path) -> Result<f64> {
    let text = std::fs::read(urdf).map_err(|e| Error::io(urdf, e))?;
    let text = String::from_utf8_lossy(&text);
    let origin_y = |joint: &str| -> Option<f64> {
        let start = text.find(&format!("<joint name=\"{joint}\""))?;
        let rest = &text[start..];
        let o = rest.find("<origin")?;
        let x = rest[o..].find("xyz")?;
        let q1 = rest[o + x..].find('"')? + o + x + 1;
        let q2 = rest[q1..].find('"')? + q1;
        let v: Vec<f64> = rest[q1..q2]
            .split_whitespace()
            .filter_map(|s| s.parse().ok())
            .collect();
        v.get(1).copied()
    };
    match (origin_y("right_knee"), origin_y("right_ankle")) {
        (Some(k), Some(a)) if k < 0.0 && a < 0.0 => Ok(0.25 * (k.abs() + a.abs())),
        _ => Err(Error::file(
            urdf,
            "right_knee / right_ankle joint origins not found",
        )),
    }
}

/// Parses a DeepMimic clip: per frame `dt, root xyz, root quat wxyz, chest q, neck q,
/// right hip q, right knee angle, right ankle q, right shoulder q, right elbow angle`, then
/// the same for the left side (44 floats). Revolute knee and elbow turn about the local z axis.
pub fn parse_deepmimic(path: &Path, name: &str, leg_length: f64) -> Result<Clip> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let v: Value =
        serde_json::from_str(&text).map_err(|e| Error::file(path, format!("bad JSON: {e}")))?;
    let frames = v
        .get("Frames")
        .and_then(Value::as_array)
        .ok_or_else(|| Error::file(path, "no \"Frames\" array"))?;
    if frames.len() < 2 {
        return Err(Error::file(path, "fewer than 2 frames"));
    }
    let m = deepmimic_axes();
    let mq = UnitQuaternion::from_rotation_matrix(&m);
    let segs = [
        "Hips",
        "Spine1",
        "Neck",
        "RightUpLeg",
        "RightLeg",
        "RightFoot",
        "RightArm",
        "RightForeArm",
        "LeftUpLeg",
        "LeftLeg",
        "LeftFoot",
        "LeftArm",
        "LeftForeArm",
    ];
    let up = Vector3::y();
    let down = -Vector3::y();
    let fwd = Vector3::z();
    let rest_dirs = vec![
        up, up, up, down, down, fwd, down, down, down, down, fwd, down, down,
    ];
    let mut times = Vec::with_capacity(frames.len());
    let mut root = Vec::with_capacity(frames.len());
    let mut globals = Vec::with_capacity(frames.len());
    let mut t = 0.0;
    for (i, fr) in frames.iter().enumerate() {
        let x: Vec<f64> = fr
            .as_array()
            .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
            .filter(|a| a.len() == 44 && a.iter().all(|x| x.is_finite()))
            .ok_or_else(|| Error::file(path, format!("frame {i}: expected 44 finite numbers")))?;
        let q = |k: usize| {
            UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                x[k],
                x[k + 1],
                x[k + 2],
                x[k + 3],
            ))
        };
        let rz = |a: f64| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a);
        let g_root = q(4);
        let g_chest = g_root * q(8);
        let g_neck = g_chest * q(12);
        let side = |o: usize| {
            let hip = g_root * q(o);
            let knee = hip * rz(x[o + 4]);
            let ankle = knee * q(o + 5);
            let shoulder = g_chest * q(o + 9);
            let elbow = shoulder * rz(x[o + 13]);
            [hip, knee, ankle, shoulder, elbow]
        };
        let r = side(16);
        let l = side(30);
        let g = [
            g_root, g_chest, g_neck, r[0], r[1], r[2], r[3], r[4], l[0], l[1], l[2], l[3], l[4],
        ];
        globals.push(g.iter().map(|q| mq * q * mq.inverse()).collect());
        root.push(m * Vector3::new(x[1], x[2], x[3]));
        times.push(t);
        if (i + 1 < frames.len() && x[0] <= 0.0) || !(0.0..=1.0).contains(&x[0]) {
            return Err(Error::file(
                path,
                format!("frame {i}: bad frame duration {}", x[0]),
            ));
        }
        t += x[0];
    }
    Ok(Clip {
        name: name.to_string(),
        segments: segs.iter().map(|s| s.to_string()).collect(),
        rest_dirs,
        times,
        root,
        globals,
        leg_length,
    })
}

struct BvhJoint {
    name: String,
    parent: Option<usize>,
    offset: Vector3<f64>,
    channels: Vec<String>,
    child_offset: Option<Vector3<f64>>,
}

/// Parses a BVH file (Y up; CMU's rest pose is a T-pose facing +Z, left +X, so its axes are
/// the body's). Rotation channels compose in the listed order, `R = R_1 R_2 R_3`, degrees.
/// Frames are read up to the header count; a header cannot make us allocate more than the file holds.
pub fn parse_bvh(path: &Path, name: &str) -> Result<Clip> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let bad = |msg: &str| Error::file(path, msg.to_string());
    let (head, motion) = text
        .split_once("MOTION")
        .ok_or_else(|| bad("no MOTION section"))?;
    let mut toks = head.split_whitespace().peekable();
    let mut joints: Vec<BvhJoint> = Vec::new();
    let mut stack: Vec<Option<usize>> = Vec::new();
    let mut last: Option<usize> = None;
    let mut in_end = false;
    while let Some(t) = toks.next() {
        match t {
            "ROOT" | "JOINT" => {
                let n = toks.next().ok_or_else(|| bad("joint without name"))?;
                joints.push(BvhJoint {
                    name: n.to_string(),
                    parent: stack.last().copied().flatten(),
                    offset: Vector3::zeros(),
                    channels: Vec::new(),
                    child_offset: None,
                });
                last = Some(joints.len() - 1);
            }
            "End" => {
                toks.next();
                in_end = true;
            }
            "{" => {
                stack.push(if in_end { None } else { last });
            }
            "}" => {
                if stack.pop().is_none() {
                    return Err(bad("unbalanced braces"));
                }
                if in_end {
                    in_end = false;
                }
            }
            "OFFSET" => {
                let mut o = [0.0; 3];
                for c in o.iter_mut() {
                    *c = toks
                        .next()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| bad("bad OFFSET"))?;
                }
                let o = Vector3::new(o[0], o[1], o[2]);
                if in_end {
                    // End Site: direction of the enclosing joint's bone.
                    if let Some(Some(j)) = stack.iter().rev().nth(1) {
                        joints[*j].child_offset.get_or_insert(o);
                    }
                } else if let Some(j) = last {
                    joints[j].offset = o;
                    if let Some(p) = joints[j].parent {
                        if o.norm() > 1e-9 {
                            joints[p].child_offset.get_or_insert(o);
                        }
                    }
                }
            }
            "CHANNELS" => {
                let n: usize = toks
                    .next()
                    .and_then(|s| s.parse().ok())
                    .filter(|&n| n <= 6)
                    .ok_or_else(|| bad("bad CHANNELS"))?;
                let j = last.ok_or_else(|| bad("CHANNELS outside a joint"))?;
                for _ in 0..n {
                    joints[j]
                        .channels
                        .push(toks.next().ok_or_else(|| bad("bad CHANNELS"))?.to_string());
                }
            }
            _ => {}
        }
    }
    if joints.is_empty() {
        return Err(bad("no joints"));
    }
    let n_channels: usize = joints.iter().map(|j| j.channels.len()).sum();
    let mut lines = motion.lines().map(str::trim).filter(|l| !l.is_empty());
    let n_frames: usize = lines
        .next()
        .and_then(|l| l.strip_prefix("Frames:"))
        .and_then(|s| s.trim().parse().ok())
        .ok_or_else(|| bad("bad Frames: line"))?;
    let dt: f64 = lines
        .next()
        .and_then(|l| l.strip_prefix("Frame Time:"))
        .and_then(|s| s.trim().parse().ok())
        .filter(|&d: &f64| d > 0.0 && d < 10.0)
        .ok_or_else(|| bad("bad Frame Time: line"))?;
    // Allocation bounded by the data actually present, not by the header's count.
    let mut times = Vec::new();
    let mut root = Vec::new();
    let mut globals = Vec::new();
    for (f, line) in lines.enumerate().take(n_frames) {
        let vals: Vec<f64> = line
            .split_whitespace()
            .map(|s| s.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad(&format!("frame {f}: bad number")))?;
        if vals.len() != n_channels || vals.iter().any(|v| !v.is_finite()) {
            return Err(bad(&format!(
                "frame {f}: expected {n_channels} finite values"
            )));
        }
        let mut k = 0;
        let mut g: Vec<UnitQuaternion<f64>> = Vec::with_capacity(joints.len());
        let mut pos = Vector3::zeros();
        for j in &joints {
            let mut local = UnitQuaternion::identity();
            for c in &j.channels {
                let v = vals[k];
                k += 1;
                match c.as_str() {
                    "Xposition" => pos.x = v,
                    "Yposition" => pos.y = v,
                    "Zposition" => pos.z = v,
                    "Xrotation" => {
                        local *= UnitQuaternion::from_axis_angle(&Vector3::x_axis(), v.to_radians())
                    }
                    "Yrotation" => {
                        local *= UnitQuaternion::from_axis_angle(&Vector3::y_axis(), v.to_radians())
                    }
                    "Zrotation" => {
                        local *= UnitQuaternion::from_axis_angle(&Vector3::z_axis(), v.to_radians())
                    }
                    other => return Err(bad(&format!("unknown channel {other}"))),
                }
            }
            g.push(match j.parent {
                Some(p) => g[p] * local,
                None => local,
            });
        }
        times.push(f as f64 * dt);
        root.push(pos + joints[0].offset);
        globals.push(g);
    }
    if n_frames == 0 {
        return Err(bad("no frames"));
    }
    if times.len() != n_frames {
        return Err(bad(&format!(
            "header says {n_frames} frames, file holds {}",
            times.len()
        )));
    }
    let idx: BTreeMap<&str, usize> = joints
        .iter()
        .enumerate()
        .map(|(i, j)| (j.name.as_str(), i))
        .collect();
    let leg = match (idx.get("LeftLeg"), idx.get("LeftFoot")) {
        (Some(&k), Some(&a)) => joints[k].offset.norm() + joints[a].offset.norm(),
        _ => return Err(bad("no LeftLeg/LeftFoot joints (not a CMU skeleton)")),
    };
    Ok(Clip {
        name: name.to_string(),
        segments: joints.iter().map(|j| j.name.clone()).collect(),
        rest_dirs: joints
            .iter()
            .map(|j| {
                j.child_offset
                    .map(|o| o.normalize())
                    .unwrap_or_else(Vector3::y)
            })
            .collect(),
        times,
        root,
        globals,
        leg_length: leg,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body walking straight ahead (+z) at 1 m/s for 2 s, turned at π/4 rad/s, follows the arc
    /// of radius 4/π: it ends heading +x (a quarter turn to the left), its last chord from the
    /// start is 2R sin(π/4), and its segments are turned by the heading.
    #[test]
    fn a_turned_straight_walk_follows_an_arc() {
        let times: Vec<f64> = (0..=200).map(|i| i as f64 * 0.01).collect();
        let clip = Clip {
            name: "walk".into(),
            segments: vec!["hips".into()],
            rest_dirs: vec![Vector3::y()],
            root: times.iter().map(|&t| Vector3::new(0.0, 0.9, t)).collect(),
            globals: times.iter().map(|_| vec![UnitQuaternion::identity()]).collect(),
            times,
            leg_length: 0.8,
        };
        let rate = std::f64::consts::FRAC_PI_4;
        let turned = clip.clone().turned(rate);
        let n = turned.n_frames();
        let last_step = turned.root[n - 1] - turned.root[n - 2];
        let heading = last_step.x.atan2(last_step.z);
        assert!((heading - std::f64::consts::FRAC_PI_2).abs() < 1e-9, "heading {heading}");
        let radius = 1.0 / rate;
        let chord = (turned.root[n - 1] - turned.root[0]).norm();
        // The discrete path turns each 0.01 s step by the angle at its end: within a step's
        // turn of the continuous arc.
        assert!((chord - 2.0 * radius * std::f64::consts::FRAC_PI_4.sin()).abs() < 0.01, "chord {chord}");
        assert!(turned.root.iter().all(|r| r.y == 0.9), "the height is kept");
        let angle = turned.globals[n - 1][0].angle();
        assert!((angle - std::f64::consts::FRAC_PI_2).abs() < 1e-9, "segment turned {angle}");
        assert_eq!(clip.clone().turned(0.0).root, clip.root, "0 leaves the clip as it is");
    }
}

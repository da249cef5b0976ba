//! Retargeting a mocap clip onto the body's rig.
//!
//! Per bone `b` driven by source segment `s`: world rotation `R_b(t) = G_s(t) S_b`, with `S_b`
//! the shortest-arc rotation from the body's rest bone direction to the source's rest
//! direction (limb bones only: the torso, clavicles and feet of both rest poses already agree).
//! Hands and fingers reuse the forearm's rotation. The root translation is scaled by the
//! leg-length ratio body/source.

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::mocap::Clip;
use crate::skeleton::Skeleton;
use mesh_core::{Error, Result};

/// Which kind of source skeleton a clip comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    /// DeepMimic humanoid: 13 segments, arms-down rest pose.
    DeepMimic,
    /// CMU BVH: same bone names as the rig, T-pose rest.
    Cmu,
}

/// How one body bone is driven.
#[derive(Clone, Debug)]
enum Drive {
    Segment { seg: usize, s: UnitQuaternion<f64> },
    CopyOf(usize),
}

/// Limb bones: the ones whose rest directions differ between rest poses.
pub const LIMB_BONES: [&str; 8] = [
    "LeftArm",
    "LeftForeArm",
    "RightArm",
    "RightForeArm",
    "LeftUpLeg",
    "LeftLeg",
    "RightUpLeg",
    "RightLeg",
];

/// Shortest-arc rotation taking unit `a` onto unit `b` (a half-turn about a perpendicular axis
/// if they are opposite).
pub fn shortest_arc(a: &Vector3<f64>, b: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(a, b).unwrap_or_else(|| {
        let p = if a.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let axis = nalgebra::Unit::new_normalize(a.cross(&p));
        UnitQuaternion::from_axis_angle(&axis, std::f64::consts::PI)
    })
}

fn deepmimic_segment(bone: &str) -> Option<&'static str> {
    Some(match bone {
        "Hips" | "LHipJoint" | "RHipJoint" | "LowerBack" => "Hips",
        "Spine" | "Spine1" | "LeftShoulder" | "RightShoulder" => "Spine1",
        "Neck" | "Neck1" | "Head" => "Neck",
        "LeftUpLeg" => "LeftUpLeg",
        "LeftLeg" => "LeftLeg",
        "LeftFoot" | "LeftToeBase" => "LeftFoot",
        "RightUpLeg" => "RightUpLeg",
        "RightLeg" => "RightLeg",
        "RightFoot" | "RightToeBase" => "RightFoot",
        "LeftArm" => "LeftArm",
        "LeftForeArm" => "LeftForeArm",
        "RightArm" => "RightArm",
        "RightForeArm" => "RightForeArm",
        _ => return None,
    })
}

fn is_hand(bone: &str) -> bool {
    ["Hand", "Finger", "Thumb"].iter().any(|k| bone.contains(k))
}

/// The retargeting of one clip onto one skeleton.
#[derive(Clone, Debug)]
pub struct Retarget {
    drives: Vec<Drive>,
    /// Leg-length ratio body / source.
    pub scale: f64,
    /// Horizontal centre of the clip's root path (clip units), subtracted so motions are centred.
    centre: Vector3<f64>,
}

impl Retarget {
    pub fn new(skel: &Skeleton, clip: &Clip, kind: SourceKind) -> Result<Self> {
        let mut drives = Vec::with_capacity(skel.bones.len());
        for (i, b) in skel.bones.iter().enumerate() {
            let name = b.name.as_str();
            if is_hand(name) {
                let fore = if name.starts_with('L') {
                    "LeftForeArm"
                } else {
                    "RightForeArm"
                };
                let f = skel
                    .index(fore)
                    .ok_or_else(|| Error::invalid(format!("rig has no {fore}")))?;
                drives.push(Drive::CopyOf(f));
                continue;
            }
            let seg_name = match kind {
                SourceKind::DeepMimic => deepmimic_segment(name),
                SourceKind::Cmu => Some(name),
            }
            .ok_or_else(|| Error::invalid(format!("no source segment for bone {name}")))?;
            let seg = clip.segment(seg_name).ok_or_else(|| {
                Error::invalid(format!("clip {}: no segment {seg_name}", clip.name))
            })?;
            let s = if LIMB_BONES.contains(&name) {
                shortest_arc(&b.direction(), &clip.rest_dirs[seg])
            } else {
                UnitQuaternion::identity()
            };
            debug_assert!(i == drives.len());
            drives.push(Drive::Segment { seg, s });
        }
        let leg_body = leg_length(skel)?;
        let n = clip.root.len() as f64;
        let mut centre = clip.root.iter().sum::<Vector3<f64>>() / n;
        centre.y = 0.0;
        Ok(Retarget {
            drives,
            scale: leg_body / clip.leg_length,
            centre,
        })
    }

    /// World rotations of all bones and the root head position at clip time `t`
    /// (vertical position not yet grounded).
    pub fn at(&self, clip: &Clip, t: f64) -> (Vec<Rotation3<f64>>, Vector3<f64>) {
        let sample = clip.sample(t);
        let mut rots: Vec<Rotation3<f64>> = Vec::with_capacity(self.drives.len());
        for d in &self.drives {
            rots.push(match d {
                Drive::Segment { seg, s } => (sample.globals[*seg] * s).to_rotation_matrix(),
                Drive::CopyOf(_) => Rotation3::identity(),
            });
        }
        self.fix_copies(&mut rots);
        (rots, (sample.root - self.centre) * self.scale)
    }

    /// Re-applies the hand = forearm rule (after a style changed the forearms).
    pub fn fix_copies(&self, rots: &mut [Rotation3<f64>]) {
        for (i, d) in self.drives.iter().enumerate() {
            if let Drive::CopyOf(f) = d {
                rots[i] = rots[*f];
            }
        }
    }
}

/// Hip-to-ankle length of the body's left leg (upper leg + lower leg bone lengths).
pub fn leg_length(skel: &Skeleton) -> Result<f64> {
    let len = |n: &str| {
        skel.index(n)
            .map(|i| (skel.bones[i].tail - skel.bones[i].head).norm())
            .ok_or_else(|| Error::invalid(format!("rig has no {n}")))
    };
    Ok(len("LeftUpLeg")? + len("LeftLeg")?)
}

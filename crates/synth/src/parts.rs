//! Part curves derived from the rig: five parts (torso as root; arm_l, arm_r, leg_l, leg_r),
//! each limb with two closed vertex loops around its upper bone, the first near the torso,
//! the second further down the limb; the band between them is the overlap with the torso.
//!
//! A loop is the plane cut perpendicular to the bone at a fraction of its length: for each
//! mesh edge crossing the plane whose endpoints are both mostly skinned to the limb and near
//! the bone axis, the endpoint closer to the plane; these are ordered by angle around the
//! axis (deterministic). Consecutive entries need not be adjacent (the format joins them by
//! shortest edge paths).

use std::collections::BTreeMap;

use nalgebra::Vector3;

use crate::subject::Subject;
use mesh_core::{Error, Result};

/// Part tree: part -> parent.
pub fn part_tree() -> BTreeMap<String, Option<String>> {
    let mut m = BTreeMap::new();
    m.insert("torso".to_string(), None);
    for p in ["arm_l", "arm_r", "leg_l", "leg_r"] {
        m.insert(p.to_string(), Some("torso".to_string()));
    }
    m
}

/// (part, upper bone, limb bones, loop fractions along the upper bone).
const LIMBS: [(&str, &str, &[&str], [f64; 2]); 4] = [
    (
        "arm_l",
        "LeftArm",
        &[
            "LeftArm",
            "LeftForeArm",
            "LeftHand",
            "LeftFingerBase",
            "LeftHandFinger1",
            "LThumb",
        ],
        [0.22, 0.45],
    ),
    (
        "arm_r",
        "RightArm",
        &[
            "RightArm",
            "RightForeArm",
            "RightHand",
            "RightFingerBase",
            "RightHandFinger1",
            "RThumb",
        ],
        [0.22, 0.45],
    ),
    (
        "leg_l",
        "LeftUpLeg",
        &["LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase"],
        [0.22, 0.42],
    ),
    (
        "leg_r",
        "RightUpLeg",
        &["RightUpLeg", "RightLeg", "RightFoot", "RightToeBase"],
        [0.22, 0.42],
    ),
];

/// The curves of every limb of `s`, on its rest mesh.
pub fn part_curves(s: &Subject) -> Result<BTreeMap<String, Vec<Vec<u32>>>> {
    let mut out = BTreeMap::new();
    for (part, upper, chain, fr) in LIMBS {
        let bi = s
            .skeleton
            .index(upper)
            .ok_or_else(|| Error::invalid(format!("rig has no {upper}")))?;
        let chain_idx: Vec<usize> = chain.iter().filter_map(|n| s.skeleton.index(n)).collect();
        let limb_w: Vec<f64> = s
            .weights
            .iter()
            .map(|row| {
                row.iter()
                    .filter(|(b, _)| chain_idx.contains(b))
                    .map(|&(_, w)| w)
                    .sum()
            })
            .collect();
        let bone = &s.skeleton.bones[bi];
        let loops = fr
            .iter()
            .map(|&f| {
                let c = bone.head + (bone.tail - bone.head) * f;
                ring(s, &c, &bone.direction(), &limb_w).ok_or_else(|| {
                    Error::invalid(format!(
                        "subject {}: no loop around {part} at {f}",
                        s.def.name
                    ))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        out.insert(part.to_string(), loops);
    }
    Ok(out)
}

fn ring(s: &Subject, c: &Vector3<f64>, axis: &Vector3<f64>, limb_w: &[f64]) -> Option<Vec<u32>> {
    let v = &s.rest;
    let sd: Vec<f64> = v.iter().map(|p| (p - c).dot(axis)).collect();
    let radial = |i: usize| {
        let d = v[i] - c;
        (d - axis * d.dot(axis)).norm()
    };
    let mut picked: Vec<usize> = Vec::new();
    for f in &s.faces {
        for k in 0..3 {
            let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
            if (sd[a] >= 0.0) == (sd[b] >= 0.0) || limb_w[a] < 0.5 || limb_w[b] < 0.5 {
                continue;
            }
            let p = if sd[a].abs() <= sd[b].abs() { a } else { b };
            picked.push(p);
        }
    }
    picked.sort_unstable();
    picked.dedup();
    if picked.is_empty() {
        return None;
    }
    // Keep the cut around this bone: radius within 1.6x the median.
    let mut radii: Vec<f64> = picked.iter().map(|&i| radial(i)).collect();
    radii.sort_by(f64::total_cmp);
    let med = radii[radii.len() / 2];
    picked.retain(|&i| radial(i) <= 1.6 * med);
    if picked.len() < 3 {
        return None;
    }
    let e1 = {
        let r = if axis.z.abs() < 0.9 {
            Vector3::z()
        } else {
            Vector3::x()
        };
        (r - axis * r.dot(axis)).normalize()
    };
    let e2 = axis.cross(&e1);
    let mut ang: Vec<(f64, usize)> = picked
        .iter()
        .map(|&i| {
            let d = v[i] - c;
            (d.dot(&e2).atan2(d.dot(&e1)), i)
        })
        .collect();
    ang.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    Some(ang.into_iter().map(|(_, i)| i as u32).collect())
}

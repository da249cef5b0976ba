//! Part curves derived from the rig: five parts (torso as root; arm_l, arm_r, leg_l, leg_r),
//! each limb with two closed vertex loops around its upper bone, the first near the torso,
//! the second further down the limb; the band between them is the overlap with the torso.
//!
//! A loop is a true edge cycle of the mesh: the region of the limb beyond a plane cut
//! perpendicular to the upper bone (at a fraction of its length): faces beyond the plane and
//! mostly skinned to the limb, connected to the limb's end; its boundary cycles are walked along
//! oriented half-edges, split into simple cycles, and the one winding once around the bone axis
//! and lying closest to the plane is kept. If the second loop would share vertices with the
//! first (coarse meshes), it moves further down the limb. Deterministic.

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
        let at = |f: f64| {
            let c = bone.head + (bone.tail - bone.head) * f;
            ring(s, &c, &bone.direction(), &limb_w)
        };
        let missing = |f: f64| {
            Error::invalid(format!(
                "subject {}: no loop around {part} at {f}",
                s.def.name
            ))
        };
        let near = at(fr[0]).ok_or_else(|| missing(fr[0]))?;
        let mut f = fr[1];
        let far = loop {
            let far = at(f).ok_or_else(|| missing(f))?;
            if !far.iter().any(|v| near.contains(v)) {
                break far;
            }
            f += 0.05;
            if f > 0.9 {
                return Err(Error::invalid(format!(
                    "subject {}: {part} loops overlap",
                    s.def.name
                )));
            }
        };
        out.insert(part.to_string(), vec![near, far]);
    }
    Ok(out)
}

fn ring(s: &Subject, c: &Vector3<f64>, axis: &Vector3<f64>, limb_w: &[f64]) -> Option<Vec<u32>> {
    let v = &s.rest;
    let rel = |i: usize| v[i] - c;
    let sd = |i: usize| rel(i).dot(axis);
    // Region: faces beyond the plane (by centroid) mostly skinned to the limb, then the
    // edge-connected component holding the most distal such face.
    let faces = &s.faces;
    let centre_sd = |f: usize| faces[f].iter().map(|&i| sd(i as usize)).sum::<f64>() / 3.0;
    let cand: Vec<bool> = (0..faces.len())
        .map(|f| {
            centre_sd(f) >= 0.0 && faces[f].iter().map(|&i| limb_w[i as usize]).sum::<f64>() >= 1.5
        })
        .collect();
    let mut owner: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for f in (0..faces.len()).filter(|&f| cand[f]) {
        let t = faces[f];
        for k in 0..3 {
            owner.insert((t[k], t[(k + 1) % 3]), f);
        }
    }
    let seed = (0..faces.len())
        .filter(|&f| cand[f])
        .max_by(|&a, &b| centre_sd(a).total_cmp(&centre_sd(b)))?;
    let mut in_region = vec![false; faces.len()];
    in_region[seed] = true;
    let mut stack = vec![seed];
    while let Some(f) = stack.pop() {
        let t = faces[f];
        for k in 0..3 {
            if let Some(&g) = owner.get(&(t[(k + 1) % 3], t[k])) {
                if !in_region[g] {
                    in_region[g] = true;
                    stack.push(g);
                }
            }
        }
    }
    let region: Vec<usize> = (0..faces.len()).filter(|&f| in_region[f]).collect();
    // Oriented half-edges of region faces; boundary ones have no region face on the twin.
    let mut half: BTreeMap<(u32, u32), ()> = BTreeMap::new();
    for &f in &region {
        let t = faces[f];
        for k in 0..3 {
            half.insert((t[k], t[(k + 1) % 3]), ());
        }
    }
    let mut next: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for &(a, b) in half.keys() {
        if !half.contains_key(&(b, a)) {
            next.entry(a).or_default().push(b);
        }
    }
    // Walk the boundary, splitting at repeated vertices into simple cycles.
    let mut cycles: Vec<Vec<u32>> = Vec::new();
    while let Some(start) = next.iter().find(|(_, o)| !o.is_empty()).map(|(&k, _)| k) {
        let mut path: Vec<u32> = vec![start];
        loop {
            let cur = *path.last().expect("walk path is never empty");
            let n = match next.get_mut(&cur) {
                Some(o) if !o.is_empty() => o.remove(0),
                _ => break, // open chain (non-manifold): dropped
            };
            if let Some(p) = path.iter().position(|&x| x == n) {
                cycles.push(path.split_off(p));
            }
            path.push(n);
        }
    }
    // Keep the cycle winding once around the axis, closest to the plane.
    let e1 = {
        let r = if axis.z.abs() < 0.9 {
            Vector3::z()
        } else {
            Vector3::x()
        };
        (r - axis * r.dot(axis)).normalize()
    };
    let e2 = axis.cross(&e1);
    let angle = |i: u32| {
        let d = rel(i as usize);
        d.dot(&e2).atan2(d.dot(&e1))
    };
    cycles
        .into_iter()
        .filter(|cy| cy.len() >= 3)
        .filter(|cy| {
            let mut w = 0.0;
            for k in 0..cy.len() {
                let mut d = angle(cy[(k + 1) % cy.len()]) - angle(cy[k]);
                if d > std::f64::consts::PI {
                    d -= std::f64::consts::TAU;
                } else if d < -std::f64::consts::PI {
                    d += std::f64::consts::TAU;
                }
                w += d;
            }
            (w.abs() / std::f64::consts::TAU - 1.0).abs() < 0.1
        })
        .map(|cy| {
            let mean = cy.iter().map(|&i| sd(i as usize).abs()).sum::<f64>() / cy.len() as f64;
            (mean, cy)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .map(|(_, cy)| cy)
}

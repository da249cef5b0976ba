//! Limb loops of a human template found without annotation.
//!
//! 1. **Extremities**: farthest-point sampling in geodesic distance, started
//!    from the vertex farthest from the one nearest the centroid, gives five
//!    points: head, hands and feet. Along the subject's up axis the highest is
//!    the head, the two lowest the feet, the other two the hands.
//! 2. **Left and right**: the body faces where its toes point (the horizontal
//!    offset from the lower shin to the toe tip, summed over both feet);
//!    left is `up × forward`.
//! 3. **The cut that separates a limb**: the level sets of the geodesic
//!    distance `d` from the extremity are swept outward in steps of `step`.
//!    Up the limb each level set is one loop around it whose length grows
//!    slowly (with noise of a few centimetres); where the front reaches the
//!    torso (armpit, crotch) its length jumps. The first level whose loop is
//!    `jump` times longer than every loop from `window` to `lookback` earlier
//!    ends the limb; the near loop (parent side) is taken
//!    `margin` before it and the far loop `band` further down the limb, as
//!    fractions of the limb length (the near loop's distance), so that the
//!    overlap band scales with the body.
//! 4. **Loops**: a level set's loop is the boundary of the faces whose three
//!    corners lie within the level (a closed vertex loop along mesh edges).

use std::collections::BTreeMap;

use anyhow::{bail, Context, Result};
use mesh_core::topology::Topology;
use mesh_core::TriMesh;
use nalgebra::Vector3;


/// The sweep's settings (defaults tuned on the demo bodies, docs/RESULTS.md).
#[derive(Clone, Debug)]
pub struct Settings {
    /// Sweep step, m.
    pub step: f64,
    /// A loop this many times longer than every loop from `window` to `lookback` earlier ends the limb.
    pub jump: f64,
    /// The jump test's window, m.
    pub window: f64,
    pub lookback: f64,
    /// Levels nearer the extremity than this fraction of the body height are
    /// not tested: the hand and wrist of an arm, the foot and calf of a leg.
    pub skip_arm: f64,
    pub skip_leg: f64,
    /// The near loop lies this fraction of the limb length before the jump.
    pub margin: f64,
    /// The far loop lies this fraction of the limb length below the near loop.
    pub band: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { step: 0.005, jump: 1.3, window: 0.15, lookback: 0.05, skip_arm: 0.25, skip_leg: 0.35, margin: 0.05, band: 0.09 }
    }
}

/// One limb: its part name, extremity and `[near the parent, down the limb]` loops.
#[derive(Clone, Debug)]
pub struct Limb {
    pub part: String,
    pub extremity: u32,
    pub loops: [Vec<u32>; 2],
    /// Geodesic distance of the two loops from the extremity, m.
    pub levels: [f64; 2],
}

/// Five extremities by geodesic farthest-point sampling.
fn extremities(topo: &Topology, pos: &[Vector3<f64>]) -> Vec<u32> {
    let centroid = pos.iter().sum::<Vector3<f64>>() / pos.len() as f64;
    let centre = (0..pos.len()).min_by(|&a, &b| (pos[a] - centroid).norm().total_cmp(&(pos[b] - centroid).norm())).unwrap_or(0) as u32;
    let d0 = topo.edge_distances(pos, &[centre]);
    let far = argmax(&d0);
    let mut chosen = vec![far];
    let mut dmin = topo.edge_distances(pos, &[far]);
    while chosen.len() < 5 {
        let next = argmax(&dmin);
        chosen.push(next);
        let d = topo.edge_distances(pos, &[next]);
        for (m, x) in dmin.iter_mut().zip(d) {
            *m = m.min(x);
        }
    }
    chosen
}

fn argmax(d: &[f64]) -> u32 {
    let mut best = 0;
    for (i, &x) in d.iter().enumerate() {
        if x.is_finite() && (!d[best].is_finite() || x > d[best]) {
            best = i;
        }
    }
    best as u32
}

/// The longest boundary loop of the faces whose corners all have `d <= t`, with its length.
fn level_loop(mesh: &TriMesh, d: &[f64], t: f64) -> Option<(Vec<u32>, f64)> {
    let faces: Vec<[u32; 3]> = mesh.faces.iter().copied().filter(|f| f.iter().all(|&v| d[v as usize] <= t)).collect();
    if faces.is_empty() {
        return None;
    }
    let topo = Topology::new(mesh.vertices.len(), &faces);
    let len = |lp: &[u32]| -> f64 {
        (0..lp.len()).map(|k| (mesh.vertices[lp[k] as usize] - mesh.vertices[lp[(k + 1) % lp.len()] as usize]).norm()).sum()
    };
    topo.boundary_loops().into_iter().map(|lp| { let l = len(&lp); (lp, l) }).max_by(|a, b| a.1.total_cmp(&b.1))
}

/// A loop is usable when it visits no vertex twice.
fn simple(lp: &[u32]) -> bool {
    let mut s = lp.to_vec();
    s.sort_unstable();
    s.windows(2).all(|w| w[0] != w[1]) && lp.len() >= 3
}

/// The near and far loops of the limb ending at `extremity` (step 3 of the module doc).
fn limb_loops(mesh: &TriMesh, topo: &Topology, extremity: u32, skip: f64, s: &Settings) -> Result<([Vec<u32>; 2], [f64; 2])> {
    let d = topo.edge_distances(&mesh.vertices, &[extremity]);
    let dmax = d.iter().copied().filter(|x| x.is_finite()).fold(0.0, f64::max);
    let mut lengths: Vec<(f64, f64)> = Vec::new();
    let mut t = s.step;
    let mut end = None;
    while t < dmax {
        if let Some((_, l)) = level_loop(mesh, &d, t) {
            // The longest loop between `window` and `lookback` back.
            let before = lengths
                .iter()
                .filter(|(u, _)| *u >= t - s.window && *u <= t - s.lookback)
                .map(|(_, l)| *l)
                .fold(0.0, f64::max);
            lengths.push((t, l));
            if t > skip && before > 0.0 && l > s.jump * before {
                end = Some(t);
                break;
            }
        }
        t += s.step;
    }
    let end = end.with_context(|| format!("no level set from vertex {extremity} separates a limb"))?;
    let near_t = end * (1.0 - s.margin);
    let far_t = near_t * (1.0 - s.band);
    // The nearest level to `target` whose loop is simple and shares no vertex with `avoid`
    // (on a coarse mesh two nearby levels can share their loop).
    let pick = |target: f64, avoid: &[u32]| -> Result<(Vec<u32>, f64)> {
        for k in 0..60 {
            for sign in [-1.0, 1.0] {
                let t = target + sign * k as f64 * s.step * 0.5;
                if let Some((lp, _)) = level_loop(mesh, &d, t) {
                    if simple(&lp) && !lp.iter().any(|v| avoid.contains(v)) {
                        return Ok((lp, t));
                    }
                }
            }
        }
        bail!("no simple loop near distance {target:.3} m from vertex {extremity}")
    };
    let (near, tn) = pick(near_t, &[])?;
    let (far, tf) = pick(far_t.min(tn - s.step), &near)?;
    Ok(([near, far], [tn, tf]))
}

/// Finds the four limbs of `mesh` (`up`: the subject's up axis), named
/// `arm_l`, `arm_r`, `leg_l`, `leg_r` (the body's own left).
pub fn propose(mesh: &TriMesh, up: &Vector3<f64>, s: &Settings) -> Result<Vec<Limb>> {
    if mesh.vertices.len() < 10 {
        bail!("the template has {} vertices: too few for a body", mesh.vertices.len());
    }
    let topo = Topology::new(mesh.vertices.len(), &mesh.faces);
    let pos = &mesh.vertices;
    let h = |v: u32| pos[v as usize].dot(up);
    let mut ext = extremities(&topo, pos);
    ext.sort_by(|&a, &b| h(a).total_cmp(&h(b)));
    let height = h(ext[4]) - h(ext[0]);
    let (feet, hands) = ([ext[0], ext[1]], [ext[2], ext[3]]);
    // Forward: from the lower shin (level set at 15% of the height) to the toe tip.
    let mut forward = Vector3::zeros();
    for &f in &feet {
        let d = topo.edge_distances(pos, &[f]);
        let band: Vec<usize> = (0..pos.len()).filter(|&v| (d[v] - 0.15 * height).abs() < 0.02 * height).collect();
        if band.is_empty() {
            continue;
        }
        let c = band.iter().map(|&v| pos[v]).sum::<Vector3<f64>>() / band.len() as f64;
        let off = pos[f as usize] - c;
        forward += off - up * off.dot(up);
    }
    if forward.norm() < 1e-9 {
        bail!("cannot tell which way the body faces (no toe offset)");
    }
    let left = up.cross(&forward.normalize());
    let side = |v: u32| pos[v as usize].dot(&left);
    let name = |pair: [u32; 2], limb: &str| -> [(String, u32); 2] {
        let (l, r) = if side(pair[0]) > side(pair[1]) { (pair[0], pair[1]) } else { (pair[1], pair[0]) };
        [(format!("{limb}_l"), l), (format!("{limb}_r"), r)]
    };
    let mut out = Vec::new();
    for (part, e) in name(hands, "arm").into_iter().chain(name(feet, "leg")) {
        let skip = height * if part.starts_with("arm") { s.skip_arm } else { s.skip_leg };
        let (loops, levels) = limb_loops(mesh, &topo, e, skip, s).with_context(|| format!("part '{part}'"))?;
        out.push(Limb { part, extremity: e, loops, levels });
    }
    Ok(out)
}

/// `subject` (the parsed `subject.json`) with the proposed curves, and the
/// part tree `torso` + four limbs when it has none.
pub fn with_curves(mut subject: serde_json::Value, limbs: &[Limb]) -> Result<serde_json::Value> {
    let obj = subject.as_object_mut().context("subject.json is not a JSON object")?;
    let mut parts = BTreeMap::new();
    parts.insert("torso".to_string(), serde_json::Value::Null);
    let mut curves = serde_json::Map::new();
    for l in limbs {
        parts.insert(l.part.clone(), serde_json::Value::String("torso".into()));
        curves.insert(l.part.clone(), serde_json::json!([l.loops[0], l.loops[1]]));
    }
    let tree_ok = obj.get("parts").and_then(|p| p.as_object()).is_some_and(|p| {
        p.len() == parts.len() && parts.iter().all(|(k, v)| p.get(k) == Some(v))
    });
    if !tree_ok && obj.get("parts").is_some_and(|p| p.as_object().is_some_and(|m| !m.is_empty())) {
        bail!("its part tree is not torso + arm_l, arm_r, leg_l, leg_r: propose-curves finds those four limbs only");
    }
    obj.insert("parts".into(), serde_json::to_value(parts)?);
    obj.insert("curves".into(), serde_json::Value::Object(curves));
    Ok(subject)
}

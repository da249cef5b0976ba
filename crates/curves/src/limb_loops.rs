//! Limb loops of a human template found without annotation.
//!
//! 1. **Extremities**: head, hands and feet, left and right ([`crate::extremities`]), on the
//!    body graph ([`crate::body_graph`]: mesh edges plus the joins between separate pieces).
//! 2. **The cut that separates a limb**: the level sets of the geodesic
//!    distance `d` from the extremity are swept outward in steps of `step`.
//!    Up the limb each level set is one loop around it whose length grows
//!    slowly (with noise of a few centimetres); where the front reaches the
//!    torso (armpit, crotch) its length jumps. The first level whose loop is
//!    `jump` times longer than every loop from `window` to `lookback` earlier
//!    ends the limb. The limb ends earlier
//!    - where its front meets another limb's ([`meeting_levels`]: the crotch, for a leg whose
//!      loop would otherwise go round both legs);
//!    - where the shortest path from the extremity to the body's centre enters the piece of
//!      the mesh the centre lies on (a limb modelled as a piece of its own is cut before its
//!      join to the body), or crossed into another piece within `window` before the jump.
//!
//!    The near loop (parent side) is taken `margin` before the end and the far loop `band`
//!    further down the limb, as fractions of the limb length, so that the overlap band scales
//!    with the body. Lengths (`step`, `window`, `lookback`) are in metres.
//! 3. **Loops**: a level set's loops are the boundary loops of the faces whose three corners
//!    lie within the level (closed vertex loops along mesh edges) that run at least partly along
//!    the front (the holes of an open mesh are no cut). The length test takes the longest; the
//!    near and far loops are taken on the piece the path from the extremity to the centre is on
//!    at their level, the longest there (one piece) or the nearest the path. On a coarse mesh
//!    one ring of vertices is the loop of a range of levels: the near and far loops are chosen
//!    among the distinct rings below the end ([`choose_loops`]), two different ones.

use std::collections::BTreeMap;

use anyhow::{bail, Context, Result};
use mesh_core::TriMesh;
use nalgebra::Vector3;

use crate::body_graph::{BodyGraph, Distances};
use crate::extremities::Extremities;


/// The sweep's settings (defaults tuned on the demo bodies, docs/studies/28-propose-curves.md).
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

/// The level sets `d <= t` of the distance `d` from one extremity: the faces in order of their
/// farthest corner, so that the faces within a level are a prefix.
struct LevelSets<'a> {
    graph: &'a BodyGraph<'a>,
    d: &'a [f64],
    /// Per face, the largest distance of its corners.
    face_level: Vec<f64>,
    /// Face indices by ascending `face_level`.
    order: Vec<u32>,
}

impl<'a> LevelSets<'a> {
    fn new(graph: &'a BodyGraph<'a>, d: &'a [f64]) -> Self {
        let face_level: Vec<f64> = graph.mesh.faces.iter().map(|f| f.iter().map(|&v| d[v as usize]).fold(0.0, f64::max)).collect();
        let mut order: Vec<u32> = (0..face_level.len() as u32).collect();
        order.sort_by(|&a, &b| face_level[a as usize].total_cmp(&face_level[b as usize]).then(a.cmp(&b)));
        LevelSets { graph, d, face_level, order }
    }

    /// The boundary loops of the faces whose three corners lie within `t` (an edge is on the
    /// boundary when exactly one of its faces is within), each following its faces' edges, that
    /// run at least partly along the front (a vertex with a neighbour beyond `t`), with their
    /// lengths.
    fn front_loops(&self, t: f64) -> Vec<(Vec<u32>, f64)> {
        let topo = &self.graph.topology;
        let faces = &self.graph.mesh.faces;
        let within = self.order.partition_point(|&f| self.face_level[f as usize] <= t);
        let inside = |f: u32| self.face_level[f as usize] <= t;
        let mut out: Vec<[u32; 2]> = Vec::new();
        for &f in &self.order[..within] {
            let face = faces[f as usize];
            for k in 0..3 {
                let (a, b) = (face[k], face[(k + 1) % 3]);
                let Some(e) = topo.edge_index(a, b) else { continue };
                if topo.edge_faces(e).iter().filter(|&&g| inside(g)).count() == 1 {
                    out.push([a, b]);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        // Chain the half-edges into loops, as `Topology::boundary_loops` does.
        let mut used = vec![false; out.len()];
        let mut loops = Vec::new();
        for start in 0..out.len() {
            if used[start] {
                continue;
            }
            used[start] = true;
            let first = out[start][0];
            let mut lp = vec![first];
            let mut cur = out[start][1];
            while cur != first {
                lp.push(cur);
                let lo = out.partition_point(|h| h[0] < cur);
                match (lo..out.len()).take_while(|&i| out[i][0] == cur).find(|&i| !used[i]) {
                    Some(i) => {
                        used[i] = true;
                        cur = out[i][1];
                    }
                    None => break,
                }
            }
            loops.push(lp);
        }
        let pos = &self.graph.mesh.vertices;
        let len = |lp: &[u32]| -> f64 { (0..lp.len()).map(|k| (pos[lp[k] as usize] - pos[lp[(k + 1) % lp.len()] as usize]).norm()).sum() };
        let on_front = |v: &u32| topo.vertex_neighbors(*v).iter().any(|&w| self.d[w as usize] > t);
        loops
            .into_iter()
            .filter(|lp| lp.iter().any(on_front))
            .map(|lp| {
                let l = len(&lp);
                (lp, l)
            })
            .collect()
    }
}

/// A loop is usable when it visits no vertex twice.
fn simple(lp: &[u32]) -> bool {
    let mut s = lp.to_vec();
    s.sort_unstable();
    s.windows(2).all(|w| w[0] != w[1]) && lp.len() >= 3
}

/// The near and far loops of the limb ending at `extremity` (step 2 of the module doc), with
/// the body's `centre` and the lengths of `s` multiplied by `scale`.
fn limb_loops(graph: &BodyGraph, from: &Distances, centre: u32, meet: f64, skip: f64, s: &Settings) -> Result<([Vec<u32>; 2], [f64; 2])> {
    let (step, window, lookback) = (s.step, s.window, s.lookback);
    let d = &from.d;
    let extremity = from.path_from(centre).last().copied().unwrap_or(centre);
    // The shortest path from the extremity to the centre, and where it crosses between pieces.
    let mut path = from.path_from(centre);
    path.reverse();
    let crossings: Vec<f64> = path
        .windows(2)
        .filter(|w| graph.component[w[0] as usize] != graph.component[w[1] as usize])
        .map(|w| d[w[0] as usize])
        .collect();
    // Where the path enters the piece the centre lies on: a limb modelled as its own piece is
    // cut before its join to the body, wherever that join is.
    let body = graph.component[centre as usize];
    let entry = path
        .windows(2)
        .find(|w| graph.component[w[0] as usize] != body && graph.component[w[1] as usize] == body)
        .map(|w| d[w[0] as usize]);
    let dmax = d.iter().copied().filter(|x| x.is_finite()).fold(0.0, f64::max);
    let levels = LevelSets::new(graph, d);
    let mut lengths: Vec<(f64, f64)> = Vec::new();
    let mut t = step;
    let mut end = None;
    while t < dmax.min(meet) {
        if let Some(l) = levels.front_loops(t).into_iter().map(|(_, l)| l).max_by(f64::total_cmp) {
            // The longest loop between `window` and `lookback` back.
            let before = lengths
                .iter()
                .filter(|(u, _)| *u >= t - window && *u <= t - lookback)
                .map(|(_, l)| *l)
                .fold(0.0, f64::max);
            lengths.push((t, l));
            if t > skip && before > 0.0 && l > s.jump * before {
                end = Some(t);
                break;
            }
        }
        t += step;
    }
    let mut end = match end {
        Some(t) => t,
        None if meet.is_finite() && meet > skip => meet,
        None => bail!("no level set from vertex {extremity} separates a limb"),
    };
    if let Some(&c) = crossings.iter().find(|&&c| c > skip && c <= end && c >= end - window) {
        end = c;
    }
    if let Some(c) = entry.filter(|&c| c > 2.0 * step && c < end) {
        end = c;
    }
    let near_t = end * (1.0 - s.margin);
    let far_t = near_t * (1.0 - s.band);
    let rings = rings(graph, &levels, &path, d, step, end, &[near_t, far_t]);
    choose_loops(&rings, near_t, far_t).with_context(|| format!("no two loops round the limb of vertex {extremity} below distance {end:.3}"))
}

/// The distinct simple loops round `path` (from the extremity, with distances `d`) at the levels
/// `step, 2 step, ...` and `also` below `end`, each with the first level it is the loop at: on a
/// coarse mesh one ring of vertices is the loop of a range of levels.
fn rings(graph: &BodyGraph, levels: &LevelSets, path: &[u32], d: &[f64], step: f64, end: f64, also: &[f64]) -> Vec<(Vec<u32>, f64)> {
    let mut ts: Vec<f64> = (1..).map(|k| k as f64 * step).take_while(|&t| t < end).chain(also.iter().copied().filter(|&t| t > 0.0 && t < end)).collect();
    ts.sort_by(f64::total_cmp);
    let mut rings: Vec<(Vec<u32>, f64)> = Vec::new();
    let mut seen: Vec<Vec<u32>> = Vec::new();
    for t in ts {
        if let Some(lp) = round_path(graph, levels, path, d, t).filter(|lp| simple(lp)) {
            let mut key = lp.clone();
            key.sort_unstable();
            if !seen.contains(&key) {
                seen.push(key);
                rings.push((lp, t));
            }
        }
    }
    rings
}

/// The loop at level `t` round the path: on the piece of the mesh the path is on at `t`, the
/// longest (one piece) or the nearest the path (the loops of other pieces' holes are no cut).
fn round_path(graph: &BodyGraph, levels: &LevelSets, path: &[u32], d: &[f64], t: f64) -> Option<Vec<u32>> {
    let at = path.iter().copied().find(|&v| d[v as usize] >= t).or(path.last().copied())?;
    let p = graph.position(at);
    let gap = |lp: &[u32]| lp.iter().map(|&v| (graph.position(v) - p).norm()).fold(f64::INFINITY, f64::min);
    let on_piece = levels.front_loops(t).into_iter().filter(|(lp, _)| graph.component[lp[0] as usize] == graph.component[at as usize]);
    let best = if graph.n_components == 1 {
        on_piece.max_by(|a, b| a.1.total_cmp(&b.1))
    } else {
        on_piece.min_by(|a, b| gap(&a.0).total_cmp(&gap(&b.0)))
    };
    best.map(|(lp, _)| lp)
}

/// The near loop: the last ring at or below `near_t` (else the first); the far loop: the ring
/// before it nearest `far_t` sharing no vertex with it, or when there is none, the near ring
/// with the next ring up as the near loop.
fn choose_loops(rings: &[(Vec<u32>, f64)], near_t: f64, far_t: f64) -> Result<([Vec<u32>; 2], [f64; 2])> {
    let disjoint = |a: &[u32], b: &[u32]| !a.iter().any(|v| b.contains(v));
    let near = rings.iter().rposition(|(_, t)| *t <= near_t).unwrap_or(0);
    let below = |near: usize| {
        rings[..near]
            .iter()
            .filter(|(lp, _)| disjoint(lp, &rings[near].0))
            .min_by(|a, b| (a.1 - far_t).abs().total_cmp(&(b.1 - far_t).abs()))
    };
    let (near, far) = match below(near) {
        Some(far) => (&rings[near], far),
        None => {
            let up = rings.get(near + 1).filter(|(lp, _)| disjoint(lp, &rings[near].0)).context("one ring only")?;
            (up, &rings[near])
        }
    };
    Ok(([near.0.clone(), far.0.clone()], [near.1, far.1]))
}


/// Per limb, the level of its distance at which its front meets another limb's: the least
/// distance from its extremity of a vertex at least as near another limb's extremity (the
/// crotch for a leg, whose front meets the other leg's there). A limb's cut lies below it.
fn meeting_levels(from: &[Distances]) -> Vec<f64> {
    (0..from.len())
        .map(|k| {
            let d = &from[k].d;
            (0..d.len())
                .filter(|&v| from.iter().enumerate().any(|(j, o)| j != k && o.d[v] <= d[v]))
                .map(|v| d[v])
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// What [`propose`] found: the extremities when it got that far, the limbs it could cut, and
/// why it stopped, if it did.
pub struct Proposal {
    pub extremities: Option<Extremities>,
    pub limbs: Vec<Limb>,
    pub error: Option<anyhow::Error>,
}

impl Proposal {
    /// The four limbs, or the error (naming the extremities chosen).
    pub fn into_result(self) -> Result<Vec<Limb>> {
        match self.error {
            None => Ok(self.limbs),
            Some(e) => Err(e),
        }
    }
}

/// Finds the four limbs of `mesh` (`up`: the subject's up axis), named
/// `arm_l`, `arm_r`, `leg_l`, `leg_r` (the body's own left), taking the extremities in
/// `hints` (name to vertex, [`crate::extremities::NAMES`]) as given.
pub fn propose(mesh: &TriMesh, up: &Vector3<f64>, s: &Settings, hints: &BTreeMap<String, u32>) -> Proposal {
    let mut proposal = Proposal { extremities: None, limbs: Vec::new(), error: None };
    if mesh.vertices.len() < 10 {
        proposal.error = Some(anyhow::anyhow!("the template has {} vertices: too few for a body", mesh.vertices.len()));
        return proposal;
    }
    let graph = BodyGraph::new(mesh);
    let up = up.normalize();
    let ext = match crate::extremities::find(&graph, &up, hints) {
        Ok(e) => e,
        Err(e) => {
            proposal.error = Some(e.context("cannot choose the extremities (give them with --extremity NAME=VERTEX)"));
            return proposal;
        }
    };
    mesh_core::info!("extremities: {}", ext.describe(mesh));
    if !ext.sided {
        proposal.error = Some(anyhow::anyhow!(
            "cannot tell the body's left from its right (the feet show no toes; extremities {}; give them with --extremity NAME=VERTEX)",
            ext.describe(mesh)
        ));
        proposal.extremities = Some(ext);
        return proposal;
    }
    let limbs = [("arm_l", "hand_l"), ("arm_r", "hand_r"), ("leg_l", "foot_l"), ("leg_r", "foot_r")];
    let from: Vec<Distances> = limbs.iter().map(|(_, name)| graph.distances(&[ext.vertex(name).unwrap_or(0)])).collect();
    let meet = meeting_levels(&from);
    for (k, (part, name)) in limbs.iter().enumerate() {
        let e = ext.vertex(name).unwrap_or(0);
        let skip = ext.height * if part.starts_with("arm") { s.skip_arm } else { s.skip_leg };
        match limb_loops(&graph, &from[k], ext.centre, meet[k], skip, s) {
            Ok((loops, levels)) => proposal.limbs.push(Limb { part: part.to_string(), extremity: e, loops, levels }),
            Err(err) => {
                proposal.error = Some(anyhow::anyhow!(
                    "part '{part}': {err} (extremities {}; give them with --extremity NAME=VERTEX)",
                    ext.describe(mesh)
                ));
                break;
            }
        }
    }
    proposal.extremities = Some(ext);
    proposal
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

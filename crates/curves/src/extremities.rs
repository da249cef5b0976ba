//! Head, hands and feet of a body found without annotation, in a body-aligned frame.
//!
//! 1. **Candidates**: farthest-point sampling in geodesic distance on the body graph
//!    ([`crate::body_graph`]), started from the vertex farthest from the one nearest the per-axis
//!    median of the positions, keeps up to [`MAX_CANDIDATES`] tips, each
//!    at least [`MIN_SEPARATION`] body heights from the others: hands, feet and head, but also
//!    hair, braids, props, wings, a tail. Each is then moved up the distance from the centre
//!    (below) to the tip it lies on, so that a point half-way down a limb becomes its end; of
//!    tips nearer each other than [`MIN_SEPARATION`] the one farther from the centre is kept.
//!    The body's **centre** is the vertex whose largest distance to the first five tips is
//!    least (between head, hands and feet, on the torso).
//! 2. **Head**: the candidate whose blob's top (its highest vertex within [`MIN_SEPARATION`])
//!    is highest along the subject's up axis less [`HEAD_OFFSET_WEIGHT`] times its horizontal
//!    distance from the centre: a hand raised above the head is higher but off to the side by
//!    at least the shoulder's half-width, a shoulder pad lower. The head is that top.
//! 3. **Hanging from the head**: a tip whose shortest path to the centre passes by the head
//!    (hair, a braid, a hat's ribbon) has a small excess `d(x, head) + d(head, centre) -
//!    d(x, centre)` (twice the way from the head to where the piece hangs from it, about 0.15
//!    body heights at most), a hand's path leaves the head aside (the excess is the detour
//!    over the neck and the head, about 0.4 heights whatever the pose), a foot's more. Tips whose
//!    excess is below [`HANGING_EXCESS`] times the head's distance to the centre are no limb.
//! 4. **Feet**: of the remaining tips, the pair lowest along the up axis whose two geodesic
//!    distances to the centre agree (left/right symmetry) and which lie far apart on the body
//!    (not two toes of one foot).
//! 5. **Hands**: every tip is the end of a branch off the **spine**, the shortest path from the
//!    head to the nearer foot ([`Branches`]). A hand's branch is an arm: its root (the point
//!    [`ROOT_FRACTION`] of the way from the tip to the spine, the shoulder) lies higher than
//!    [`UPPER_BODY`] of the height (a tail's lies at the hip), the hand lies above
//!    [`HAND_LOWEST`] of the height and is wider than [`HAND_WIDTH`] of it (a braid or a strap
//!    is thinner), and it lies at least [`LIMB_SEPARATION`] from the feet. A branch on a piece
//!    of its own counts up to where its path to the centre enters the body's piece (a limb
//!    pushed into the body is joined at its root, a prop anywhere along it). The hands are the
//!    two such branches longest together less [`ARM_ASYMMETRY`] times the difference of their
//!    lengths, whose ways to each other share nothing (two arms, not two ends of one) and
//!    whose roots lie on either side of the body (at least [`SIDE_OFFSET`] apart across it)
//!    when the toes tell the sides (6).
//! 6. **Left and right**: the body faces where its toes point (the horizontal offset from the
//!    lower shin to the toe tip, summed over both feet); left is `up × forward`. Feet are
//!    sided by their tips, hands by their roots: a hand held across the body lies on the
//!    other side, its shoulder does not.
//!
//! Hints (`--extremity hand_l=VERTEX`) replace any of the five choices; the others are then
//! chosen among the candidates not within [`MIN_SEPARATION`] of a hinted vertex.

use std::collections::BTreeMap;

use anyhow::{bail, Result};
use mesh_core::TriMesh;
use nalgebra::Vector3;

use crate::body_graph::{BodyGraph, Distances};

/// The names of the five extremities, as `--extremity` takes them.
pub const NAMES: [&str; 5] = ["head", "hand_l", "hand_r", "foot_l", "foot_r"];
/// Most candidate tips kept by the farthest-point sampling.
pub const MAX_CANDIDATES: usize = 24;
/// Least geodesic distance between two candidates, in body heights (the fingers of one hand
/// give one candidate).
pub const MIN_SEPARATION: f64 = 0.1;
/// Least geodesic distance of a hand from either foot, in body heights.
pub const LIMB_SEPARATION: f64 = 0.4;
/// Least distance of each hand from the plane half-way between the feet, in body heights.
pub const SIDE_OFFSET: f64 = 0.03;
/// The head is the candidate highest along the up axis less this many times its horizontal
/// distance from the centre.
pub const HEAD_OFFSET_WEIGHT: f64 = 2.0;
/// A tip whose head excess is below this fraction of the head's distance to the centre hangs
/// from the head.
pub const HANGING_EXCESS: f64 = 0.7;
/// The root of a hand's branch (its shoulder) lies higher than this fraction of the body's
/// height above the lower foot; a tail's lies at the hip.
pub const UPPER_BODY: f64 = 0.5;
/// The hands are the pair of branches longest together less this many times the difference of
/// their lengths (the two arms are about as long).
pub const ARM_ASYMMETRY: f64 = 1.5;
/// A hand is wider than this fraction of the body's height (a braid, a strap or a cord is not).
pub const HAND_WIDTH: f64 = 0.025;
/// A hand lies higher than this fraction of the body's height above the lower foot (above the
/// knees; a tail's tip lies lower).
pub const HAND_LOWEST: f64 = 0.25;
/// A hand's side is that of its branch this fraction of the way from the hand to the spine.
pub const ROOT_FRACTION: f64 = 0.85;

/// The five chosen extremities and the body frame.
#[derive(Clone, Debug)]
pub struct Extremities {
    /// Vertex of `head`, `hand_l`, `hand_r`, `foot_l`, `foot_r` (the order of [`NAMES`]).
    pub vertices: [u32; 5],
    /// Height of the body along the up axis, from the lower foot to the head.
    pub height: f64,
    /// Towards the body's left (`up × forward`), unit; zero when the toes give no direction.
    pub left: Vector3<f64>,
    /// Candidate tips rejected as hanging from the head (hair, braids).
    pub hanging: Vec<u32>,
    /// The body's centre: the vertex whose farthest distance to the first five candidates is least.
    pub centre: u32,
    /// Whether left and right are known (from the toes or from hints).
    pub sided: bool,
}

impl Extremities {
    pub fn vertex(&self, name: &str) -> Option<u32> {
        NAMES.iter().position(|n| *n == name).map(|k| self.vertices[k])
    }

    /// `head 12 (0.010, 1.710, 0.030), hand_l 811 (...), ...`, for messages.
    pub fn describe(&self, mesh: &TriMesh) -> String {
        NAMES
            .iter()
            .zip(self.vertices)
            .map(|(n, v)| {
                let p = mesh.vertices[v as usize];
                format!("{n} {v} ({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Checks the form of one `NAME=VERTEX` hint (clap's value parser for `--extremity`).
pub fn check_hint(h: &str) -> std::result::Result<String, String> {
    let (name, v) = h.split_once('=').ok_or_else(|| format!("expected NAME=VERTEX (NAME one of {})", NAMES.join(", ")))?;
    if !NAMES.contains(&name) {
        return Err(format!("unknown extremity '{name}' (one of {})", NAMES.join(", ")));
    }
    v.parse::<u32>().map_err(|_| format!("'{v}' is not a vertex index"))?;
    Ok(h.to_string())
}

/// Parses `NAME=VERTEX` hints, checking the name and that the vertex exists.
pub fn parse_hints(hints: &[String], n_vertices: usize) -> Result<BTreeMap<String, u32>> {
    let mut out = BTreeMap::new();
    for h in hints {
        let Some((name, v)) = h.split_once('=') else {
            bail!("--extremity {h}: expected NAME=VERTEX (NAME one of {})", NAMES.join(", "));
        };
        if !NAMES.contains(&name) {
            bail!("--extremity {h}: unknown extremity '{name}' (one of {})", NAMES.join(", "));
        }
        let v: u32 = v.parse().map_err(|_| anyhow::anyhow!("--extremity {h}: '{v}' is not a vertex index"))?;
        if v as usize >= n_vertices {
            bail!("--extremity {h}: the template has {n_vertices} vertices");
        }
        if out.insert(name.to_string(), v).is_some() {
            bail!("--extremity {name} is given twice");
        }
    }
    Ok(out)
}

/// One candidate tip and its distances to every vertex.
struct Tip {
    v: u32,
    d: Vec<f64>,
}

/// Chooses the five extremities of the body in `graph` (`up`: the subject's up axis, unit),
/// taking the `hints` (name to vertex) as given.
pub fn find(graph: &BodyGraph, up: &Vector3<f64>, hints: &BTreeMap<String, u32>) -> Result<Extremities> {
    let pos = &graph.mesh.vertices;
    let n = pos.len();
    let h = |v: u32| pos[v as usize].dot(up);
    let heights: Vec<f64> = pos.iter().map(|p| p.dot(up)).collect();
    let base = heights.iter().copied().fold(f64::INFINITY, f64::min);
    let extent = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max) - base;
    if !(extent > 0.0) {
        bail!("the template is flat along the up axis");
    }
    // A start for the sampling: the vertex nearest the per-axis median of the positions.
    let median = |k: usize| {
        let mut c: Vec<f64> = pos.iter().map(|p| p[k]).collect();
        c.sort_by(f64::total_cmp);
        c[c.len() / 2]
    };
    let m = Vector3::new(median(0), median(1), median(2));
    let start = (0..n as u32).min_by(|&a, &b| (pos[a as usize] - m).norm().total_cmp(&(pos[b as usize] - m).norm())).unwrap_or(0);
    let d_start = graph.distances(&[start]).d;

    // 1. Candidates: the hints, then farthest-point sampling.
    let mut tips: Vec<Tip> = Vec::new();
    let mut dmin = vec![f64::INFINITY; n];
    let add = |tips: &mut Vec<Tip>, dmin: &mut Vec<f64>, v: u32| {
        let d = graph.distances(&[v]).d;
        for (m, x) in dmin.iter_mut().zip(&d) {
            *m = m.min(*x);
        }
        tips.push(Tip { v, d });
    };
    for &v in hints.values() {
        add(&mut tips, &mut dmin, v);
    }
    let hinted = tips.len();
    if tips.is_empty() {
        add(&mut tips, &mut dmin, argmax(&d_start));
    }
    while tips.len() < MAX_CANDIDATES + hinted {
        let next = argmax(&dmin);
        if !(dmin[next as usize] > MIN_SEPARATION * extent) {
            break;
        }
        add(&mut tips, &mut dmin, next);
    }
    // The centre: the vertex whose farthest distance to the first five tips is least (the
    // middle of the body between head, hands and feet).
    let first = &tips[..tips.len().min(5)];
    let centre = (0..n as u32)
        .min_by(|&a, &b| {
            let far = |v: u32| first.iter().map(|t| t.d[v as usize]).fold(0.0, f64::max);
            far(a).total_cmp(&far(b)).then(a.cmp(&b))
        })
        .unwrap_or(start);
    let from_centre = graph.distances(&[centre]);
    let dc = &from_centre.d;
    // Each sampled candidate moved up the distance from the centre to the tip it lies on
    // (a point half-way down a leg becomes the toe); of tips nearer each other than
    // MIN_SEPARATION the one farthest from the centre is kept (the top of the head, not the end
    // of a braid hidden inside it).
    let mut snapped: Vec<u32> = Vec::new();
    for t in &tips[hinted..] {
        let mut v = t.v;
        while let Some(&w) = graph.neighbours(v).max_by(|&&a, &&b| dc[a as usize].total_cmp(&dc[b as usize])).filter(|&&w| dc[w as usize] > dc[v as usize]) {
            v = w;
        }
        if !snapped.contains(&v) && !tips[..hinted].iter().any(|t| t.v == v) {
            snapped.push(v);
        }
    }
    tips.truncate(hinted);
    snapped.sort_by(|&a, &b| dc[b as usize].total_cmp(&dc[a as usize]).then(a.cmp(&b)));
    for v in snapped {
        let d = graph.distances(&[v]).d;
        if tips.iter().all(|t| d[t.v as usize] > MIN_SEPARATION * extent) {
            tips.push(Tip { v, d });
        }
    }
    let free: Vec<usize> = (hinted..tips.len()).filter(|&k| (0..hinted).all(|j| tips[j].d[tips[k].v as usize] > MIN_SEPARATION * extent)).collect();

    // 2. Head: high and over the centre, at the top of the blob its tip lies on (the tip is
    // where the blob is farthest from the centre, which on a head modelled as a piece of its
    // own is opposite where it is joined, not its top).
    let top = |k: usize| {
        (0..n as u32).filter(|&v| tips[k].d[v as usize] < MIN_SEPARATION * extent).max_by(|&a, &b| h(a).total_cmp(&h(b))).unwrap_or(tips[k].v)
    };
    let over_centre = |k: usize| {
        let off = pos[top(k) as usize] - pos[centre as usize];
        h(top(k)) - HEAD_OFFSET_WEIGHT * (off - up * off.dot(up)).norm()
    };
    let hinted_head = hints.get("head").map(|&v| tips.iter().position(|t| t.v == v).unwrap_or(0));
    let head = match hinted_head {
        Some(k) => k,
        None => {
            let k = free
                .iter()
                .copied()
                .max_by(|&a, &b| over_centre(a).total_cmp(&over_centre(b)))
                .ok_or_else(|| anyhow::anyhow!("no candidate for the head"))?;
            let v = top(k);
            tips[k] = Tip { v, d: graph.distances(&[v]).d };
            k
        }
    };
    let hint = |name: &str| hints.get(name).map(|&v| tips.iter().position(|t| t.v == v).unwrap_or(0));
    let hv = tips[head].v;
    let dh = &tips[head].d;
    let to_head = dc[hv as usize];
    // 3. Tips hanging from the head.
    let excess = |k: usize| dh[tips[k].v as usize] + to_head - dc[tips[k].v as usize];
    let near_head = |k: usize| tips[k].d[hv as usize] <= MIN_SEPARATION * extent;
    let hanging: Vec<usize> = free.iter().copied().filter(|&k| k != head && !near_head(k) && excess(k) < HANGING_EXCESS * to_head).collect();
    let limbs: Vec<usize> = free.iter().copied().filter(|&k| k != head && !near_head(k) && !hanging.contains(&k)).collect();

    // 4. Feet, then hands: symmetric pairs far apart.
    let dck = |k: usize| dc[tips[k].v as usize];
    let apart = |a: usize, b: usize| tips[a].d[tips[b].v as usize] > 0.8 * dck(a).min(dck(b));
    let asymmetry = |a: usize, b: usize| (dck(a) - dck(b)).abs() / extent;
    let pair = |pool: &[usize], fixed: [Option<usize>; 2], cost: &dyn Fn(usize, usize) -> f64| -> Option<[usize; 2]> {
        let by_cost = |x: &(usize, usize), y: &(usize, usize)| cost(x.0, x.1).total_cmp(&cost(y.0, y.1));
        match fixed {
            [Some(a), Some(b)] => Some([a, b]),
            [Some(f), None] | [None, Some(f)] => {
                pool.iter().map(|&a| (f, a)).filter(|&(f, a)| a != f && apart(f, a)).min_by(by_cost).map(|(f, a)| [f, a])
            }
            [None, None] => pool
                .iter()
                .enumerate()
                .flat_map(|(i, &a)| pool[i + 1..].iter().map(move |&b| (a, b)))
                .filter(|&(a, b)| apart(a, b))
                .min_by(by_cost)
                .map(|(a, b)| [a, b]),
        }
    };
    let feet_cost = |a: usize, b: usize| (h(tips[a].v) + h(tips[b].v) - 2.0 * base) / extent + 2.0 * asymmetry(a, b);
    let feet = pair(&limbs, [hint("foot_l"), hint("foot_r")], &feet_cost)
        .ok_or_else(|| anyhow::anyhow!("no pair of tips for the feet"))?;
    // The hands lie far from the feet (not a heel or an ankle of a foot modelled in pieces) and,
    // when the toes tell left from right, one on each side of the plane half-way between the feet.
    let height = h(hv) - h(tips[feet[0]].v).min(h(tips[feet[1]].v));
    let left = body_left(graph, up, [tips[feet[0]].v, tips[feet[1]].v], height);
    let off_feet = |k: &usize| feet.iter().all(|&f| tips[f].d[tips[*k].v as usize] > LIMB_SEPARATION * extent);
    // Where each tip's branch leaves the path from the head to the nearer foot, and how long it is.
    let branch = Branches::new(graph, hv, [&tips[feet[0]].d, &tips[feet[1]].d]);
    // An arm leaves the body at the shoulder, high up; a tail at the hip.
    let root_height = |k: usize| (branch.root(tips[k].v, &tips[k].d).dot(up) - (h(hv) - height)) / height;
    let upper = |k: &usize| root_height(*k) > UPPER_BODY && (h(tips[*k].v) - (h(hv) - height)) / height > HAND_LOWEST;
    let thick = |k: &usize| tip_width(graph, tips[*k].v, &tips[*k].d, extent) > HAND_WIDTH * extent;
    let rest: Vec<usize> = limbs.iter().copied().filter(|k| !feet.contains(k)).filter(off_feet).filter(upper).filter(thick).collect();
    let o = SIDE_OFFSET * extent;
    let root_side = |k: usize| branch.root(tips[k].v, &tips[k].d).dot(&left);
    let sides = |a: usize, b: usize| left.norm() == 0.0 || (root_side(a) - root_side(b)).abs() > o;
    // A branch counts up to where it enters the body's piece: a limb modelled as a piece of its
    // own is joined where it is pushed into the body, at its root, a prop anywhere along it.
    let body = graph.component[centre as usize];
    let to_body = |k: usize| {
        let path = from_centre.path_from(tips[k].v);
        path.iter().find(|&&v| graph.component[v as usize] == body).map_or(0.0, |&v| tips[k].d[v as usize])
    };
    let length = |k: usize| branch.of(tips[k].v).0.min(if graph.component[tips[k].v as usize] == body { f64::INFINITY } else { to_body(k) });
    let hands_cost = |a: usize, b: usize| {
        // Two arms, not two ends of one: their branches share no way to each other.
        let own_branches = tips[a].d[tips[b].v as usize] > 0.9 * (length(a) + length(b));
        if sides(a, b) && own_branches { (ARM_ASYMMETRY * (length(a) - length(b)).abs() - length(a) - length(b)) / extent } else { f64::INFINITY }
    };
    if mesh_core::cli::verbosity() >= 2 {
        mesh_core::info!("the legs part {:.3} from the head along the spine", branch.crotch);
        for &k in &free {
            let p = pos[tips[k].v as usize];
            mesh_core::info!(
                "candidate {} ({:.3}, {:.3}, {:.3}): to the centre {:.3}, head excess {:.3}, branch {:.3} leaving the spine {:.3} from the head, root side {:.3} height {:.3} width {:.3}{}",
                tips[k].v, p.x, p.y, p.z, dc[tips[k].v as usize], excess(k), branch.of(tips[k].v).0, branch.of(tips[k].v).1, root_side(k), root_height(k), tip_width(graph, tips[k].v, &tips[k].d, extent) / extent,
                if k == head { " (head)" } else if hanging.contains(&k) { " (hangs from the head)" } else if near_head(k) { " (on the head)" } else { "" }
            );
        }
    }
    let hands = pair(&rest, [hint("hand_l"), hint("hand_r")], &hands_cost)
        .filter(|p| hands_cost(p[0], p[1]).is_finite() || (hint("hand_l").is_some() && hint("hand_r").is_some()))
        .ok_or_else(|| anyhow::anyhow!("no pair of tips for the hands (head at vertex {hv})"))?;

    // 5. Left and right.
    let side = |k: usize| pos[tips[k].v as usize].dot(&left);
    let order_by = |p: [usize; 2], l: Option<usize>, r: Option<usize>, side: &dyn Fn(usize) -> f64| -> [usize; 2] {
        match (l, r) {
            (Some(l), _) => [l, if p[0] == l { p[1] } else { p[0] }],
            (None, Some(r)) => [if p[0] == r { p[1] } else { p[0] }, r],
            _ if side(p[0]) >= side(p[1]) => p,
            _ => [p[1], p[0]],
        }
    };
    let order = |p: [usize; 2], l: Option<usize>, r: Option<usize>| order_by(p, l, r, &side);
    let hands = order_by(hands, hint("hand_l"), hint("hand_r"), &root_side);
    let feet = order(feet, hint("foot_l"), hint("foot_r"));
    let missing_side = left.norm() == 0.0 && (hint("hand_l").or(hint("hand_r")).is_none() || hint("foot_l").or(hint("foot_r")).is_none());
    let ext = Extremities {
        vertices: [hv, tips[hands[0]].v, tips[hands[1]].v, tips[feet[0]].v, tips[feet[1]].v],
        height,
        left,
        hanging: hanging.iter().map(|&k| tips[k].v).collect(),
        centre,
        sided: !missing_side,
    };
    Ok(ext)
}

/// The branches of the body off its spine, the shortest path from the head to the nearer foot:
/// a tip `x` leaves it at `along = (d(x, head) - d(x, foot) + d(head, foot)) / 2` from the head
/// (the Gromov product), by a branch `length = d(x, head) - along` long. An arm leaves it at the
/// shoulder, high up; hair at the head, a tail or the other leg at the hip.
struct Branches<'a> {
    graph: &'a BodyGraph<'a>,
    head: u32,
    /// Distances from the head, with its shortest paths.
    from_head: Distances,
    feet: [&'a [f64]; 2],
    /// Where the legs part (the other foot's branch leaves the spine), from the head.
    pub crotch: f64,
}

impl<'a> Branches<'a> {
    fn new(graph: &'a BodyGraph<'a>, head: u32, feet: [&'a [f64]; 2]) -> Self {
        let from_head = graph.distances(&[head]);
        // The other foot's branch off the path from the head to one foot.
        let foot = |k: usize| (0..feet[k].len()).find(|&v| feet[k][v] == 0.0).unwrap_or(0);
        let (f0, f1) = (foot(0), foot(1));
        let crotch = ((from_head.d[f1] - feet[0][f1] + from_head.d[f0]) / 2.0).max(0.0);
        Branches { graph, head, from_head, feet, crotch }
    }

    /// `(length, along)` of the branch ending at `x`.
    fn of(&self, x: u32) -> (f64, f64) {
        let (x, h) = (x as usize, self.head as usize);
        let foot = if self.feet[0][x] <= self.feet[1][x] { self.feet[0] } else { self.feet[1] };
        let dh = self.from_head.d[x];
        let along = ((dh - foot[x] + foot[h]) / 2.0).clamp(0.0, dh);
        (dh - along, along)
    }

    /// The root of the branch ending at `x`, just before it joins the spine: the vertex of its
    /// shortest path to the head [`ROOT_FRACTION`] of its length from `x` (`dx`: distances from
    /// `x`). Where the branches join the spine (at the neck, for arms whose way to the head
    /// passes over the shoulders) does not tell the sides; the shoulders do.
    fn root(&self, x: u32, dx: &[f64]) -> Vector3<f64> {
        let (length, _) = self.of(x);
        let path = self.from_head.path_from(x);
        let v = path.iter().copied().find(|&v| dx[v as usize] >= ROOT_FRACTION * length).unwrap_or(self.head);
        self.graph.position(v)
    }
}

/// The width of the body round a tip `x` (`dx`: distances from it): twice the largest distance
/// from the line from the tip through their centroid of the vertices between 0.05 and 0.1
/// `extent` from the tip (the palm of a hand, a braid's thickness).
fn tip_width(graph: &BodyGraph, x: u32, dx: &[f64], extent: f64) -> f64 {
    let band: Vec<Vector3<f64>> = (0..dx.len()).filter(|&v| dx[v] >= 0.05 * extent && dx[v] <= 0.1 * extent).map(|v| graph.position(v as u32)).collect();
    if band.is_empty() {
        return 0.0;
    }
    let tip = graph.position(x);
    let axis = (band.iter().sum::<Vector3<f64>>() / band.len() as f64 - tip).try_normalize(1e-12).unwrap_or_else(Vector3::zeros);
    2.0 * band.iter().map(|p| ((p - tip) - axis * (p - tip).dot(&axis)).norm()).fold(0.0, f64::max)
}

/// The body's left (`up × forward`), forward being where the toes point: the horizontal
/// offset from the lower shin (the level set at 15 % of the height from each foot) to the foot's
/// tip, summed over both feet. Zero when the feet show no direction.
fn body_left(graph: &BodyGraph, up: &Vector3<f64>, feet: [u32; 2], height: f64) -> Vector3<f64> {
    let pos = &graph.mesh.vertices;
    let mut forward = Vector3::zeros();
    for f in feet {
        let d = graph.distances(&[f]).d;
        let band: Vec<usize> = (0..pos.len()).filter(|&v| (d[v] - 0.15 * height).abs() < 0.02 * height).collect();
        if band.is_empty() {
            continue;
        }
        let c = band.iter().map(|&v| pos[v]).sum::<Vector3<f64>>() / band.len() as f64;
        let off = pos[f as usize] - c;
        forward += off - up * off.dot(up);
    }
    if forward.norm() < 1e-9 * height.max(1e-9) {
        return Vector3::zeros();
    }
    up.cross(&forward.normalize())
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

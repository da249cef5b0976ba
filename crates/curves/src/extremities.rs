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
    let body = Body::new(graph, up)?;
    let mut c = Candidates::find(&body, hints);
    let free = free_candidates(&body, &c);
    let head = choose_head(&body, &mut c, &free, hints)?;
    let hint = |name: &str| c.hinted(hints, name);
    let (hanging, limbs) = split_hanging(&body, &c, &free, head);
    let feet = choose_feet(&body, &c, &limbs, [hint("foot_l"), hint("foot_r")])?;
    let arms = Arms::new(&body, &c, head, feet);
    if mesh_core::cli::verbosity() >= 2 {
        arms.log(&free, &hanging);
    }
    let hands = choose_hands(&arms, &limbs, [hint("hand_l"), hint("hand_r")])?;
    let hands = left_first(hands, hint("hand_l"), hint("hand_r"), &|k: usize| arms.root_side(k));
    let feet = left_first(feet, hint("foot_l"), hint("foot_r"), &|k: usize| graph.position(c.v(k)).dot(&arms.left));
    let missing_side = arms.left.norm() == 0.0 && (hint("hand_l").or(hint("hand_r")).is_none() || hint("foot_l").or(hint("foot_r")).is_none());
    Ok(Extremities {
        vertices: [c.v(head), c.v(hands[0]), c.v(hands[1]), c.v(feet[0]), c.v(feet[1])],
        height: arms.height,
        left: arms.left,
        hanging: hanging.iter().map(|&k| c.v(k)).collect(),
        centre: c.centre,
        sided: !missing_side,
    })
}

/// The body's graph with its up axis and its span along it.
struct Body<'a> {
    graph: &'a BodyGraph<'a>,
    up: &'a Vector3<f64>,
    /// The lowest height of a vertex along `up`.
    base: f64,
    /// The highest height of a vertex along `up` less the lowest.
    extent: f64,
}

impl<'a> Body<'a> {
    /// The span of `graph`'s vertices along `up`; an error when it is none.
    fn new(graph: &'a BodyGraph<'a>, up: &'a Vector3<f64>) -> Result<Self> {
        let heights: Vec<f64> = graph.mesh.vertices.iter().map(|p| p.dot(up)).collect();
        let base = heights.iter().copied().fold(f64::INFINITY, f64::min);
        let extent = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max) - base;
        if !(extent > 0.0) {
            bail!("the template is flat along the up axis");
        }
        Ok(Body { graph, up, base, extent })
    }

    /// The height of vertex `v` along the up axis.
    fn h(&self, v: u32) -> f64 {
        self.graph.mesh.vertices[v as usize].dot(self.up)
    }

    /// The least distance between two candidates: [`MIN_SEPARATION`] body heights.
    fn separation(&self) -> f64 {
        MIN_SEPARATION * self.extent
    }
}

/// The candidate tips (step 1) and the body's centre.
struct Candidates {
    tips: Vec<Tip>,
    /// How many of `tips`, the first ones, are hinted vertices.
    hinted: usize,
    /// The vertex whose largest distance to the first five sampled tips is least.
    centre: u32,
    /// Distances from the centre, with their shortest paths.
    from_centre: Distances,
}

impl Candidates {
    /// The hinted vertices, then the sampled tips moved to the ends of their limbs, and the
    /// centre found from the sampled tips.
    fn find(body: &Body, hints: &BTreeMap<String, u32>) -> Candidates {
        let start = median_vertex(&body.graph.mesh.vertices);
        let (mut tips, hinted) = sample_tips(body, hints, start);
        let centre = body_centre(&tips, body.graph.n_vertices(), start);
        let from_centre = body.graph.distances(&[centre]);
        snap_to_tips(body, &mut tips, hinted, &from_centre.d);
        Candidates { tips, hinted, centre, from_centre }
    }

    /// The vertex of tip `k`.
    fn v(&self, k: usize) -> u32 {
        self.tips[k].v
    }

    /// The distance of tip `k` from the centre.
    fn to_centre(&self, k: usize) -> f64 {
        self.from_centre.d[self.tips[k].v as usize]
    }

    /// The distance between tips `a` and `b`.
    fn between(&self, a: usize, b: usize) -> f64 {
        self.tips[a].d[self.tips[b].v as usize]
    }

    /// The tip of the extremity `name` when it is hinted (the first tip when the hinted vertex
    /// is no tip).
    fn hinted(&self, hints: &BTreeMap<String, u32>, name: &str) -> Option<usize> {
        hints.get(name).map(|&v| self.tips.iter().position(|t| t.v == v).unwrap_or(0))
    }
}

/// The vertex nearest the per-axis median of the positions (the first when there are several,
/// 0 when there is none): where the sampling starts.
fn median_vertex(pos: &[Vector3<f64>]) -> u32 {
    let median = |k: usize| {
        let mut c: Vec<f64> = pos.iter().map(|p| p[k]).collect();
        c.sort_by(f64::total_cmp);
        c[c.len() / 2]
    };
    let m = Vector3::new(median(0), median(1), median(2));
    (0..pos.len() as u32).min_by(|&a, &b| (pos[a as usize] - m).norm().total_cmp(&(pos[b as usize] - m).norm())).unwrap_or(0)
}

/// Farthest-point sampling in geodesic distance: the hinted vertices first (their count is
/// returned with the tips), else the vertex farthest from `start`; then the vertex farthest from
/// every tip so far, while that distance exceeds the separation, until [`MAX_CANDIDATES`] are
/// sampled.
fn sample_tips(body: &Body, hints: &BTreeMap<String, u32>, start: u32) -> (Vec<Tip>, usize) {
    let graph = body.graph;
    let mut tips: Vec<Tip> = Vec::new();
    let mut dmin = vec![f64::INFINITY; graph.n_vertices()];
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
        add(&mut tips, &mut dmin, argmax(&graph.distances(&[start]).d));
    }
    while tips.len() < MAX_CANDIDATES + hinted {
        let next = argmax(&dmin);
        if !(dmin[next as usize] > body.separation()) {
            break;
        }
        add(&mut tips, &mut dmin, next);
    }
    (tips, hinted)
}

/// The body's centre: of the `n` vertices, the one whose farthest distance to the first five
/// tips is least (the middle of the body between head, hands and feet; the lowest index of
/// equals); `start` when there are no vertices.
fn body_centre(tips: &[Tip], n: usize, start: u32) -> u32 {
    let first = &tips[..tips.len().min(5)];
    (0..n as u32)
        .min_by(|&a, &b| {
            let far = |v: u32| first.iter().map(|t| t.d[v as usize]).fold(0.0, f64::max);
            far(a).total_cmp(&far(b)).then(a.cmp(&b))
        })
        .unwrap_or(start)
}

/// Replaces the sampled tips (those after the `hinted` ones) by the ends they lie on: each is
/// moved up the distance from the centre (`dc`) until no neighbour lies farther (a point
/// half-way down a leg becomes the toe). Ends that coincide or are a hinted vertex are dropped;
/// the others are kept farthest from the centre first, each unless it lies within the separation
/// of a tip already kept (the top of the head is kept, not the end of a braid hidden inside it).
fn snap_to_tips(body: &Body, tips: &mut Vec<Tip>, hinted: usize, dc: &[f64]) {
    let graph = body.graph;
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
        if tips.iter().all(|t| d[t.v as usize] > body.separation()) {
            tips.push(Tip { v, d });
        }
    }
}

/// The sampled tips farther than the separation from every hinted vertex: those the extremities
/// that are not hinted are chosen among.
fn free_candidates(body: &Body, c: &Candidates) -> Vec<usize> {
    (c.hinted..c.tips.len()).filter(|&k| (0..c.hinted).all(|j| c.between(j, k) > body.separation())).collect()
}

/// Step 2, the head's tip: the hinted one, else the free tip whose blob's top (its highest vertex
/// within the separation) is highest along the up axis less [`HEAD_OFFSET_WEIGHT`] times the
/// top's horizontal distance from the centre; that tip is then replaced by its top (the tip is
/// where the blob is farthest from the centre, which on a head modelled as a piece of its own is
/// opposite where it is joined, not its top).
fn choose_head(body: &Body, c: &mut Candidates, free: &[usize], hints: &BTreeMap<String, u32>) -> Result<usize> {
    if let Some(k) = c.hinted(hints, "head") {
        return Ok(k);
    }
    let (pos, up) = (&body.graph.mesh.vertices, body.up);
    let tips = &c.tips;
    let top = |k: usize| {
        (0..pos.len() as u32).filter(|&v| tips[k].d[v as usize] < body.separation()).max_by(|&a, &b| body.h(a).total_cmp(&body.h(b))).unwrap_or(tips[k].v)
    };
    let over_centre = |k: usize| {
        let off = pos[top(k) as usize] - pos[c.centre as usize];
        body.h(top(k)) - HEAD_OFFSET_WEIGHT * (off - up * off.dot(up)).norm()
    };
    let k = free
        .iter()
        .copied()
        .max_by(|&a, &b| over_centre(a).total_cmp(&over_centre(b)))
        .ok_or_else(|| anyhow::anyhow!("no candidate for the head"))?;
    let v = top(k);
    c.tips[k] = Tip { v, d: body.graph.distances(&[v]).d };
    Ok(k)
}

/// The head excess of tip `k`: `d(x, head) + d(head, centre) - d(x, centre)`, twice the way
/// from the head to where `x`'s path to the centre leaves it, or the detour over the head.
fn head_excess(c: &Candidates, head: usize, k: usize) -> f64 {
    c.between(head, k) + c.to_centre(head) - c.to_centre(k)
}

/// Whether tip `k` lies on the head: within the separation of its vertex.
fn on_head(body: &Body, c: &Candidates, head: usize, k: usize) -> bool {
    c.between(k, head) <= body.separation()
}

/// Step 3: of the free tips other than the head and not on it, those hanging from the head
/// (head excess below [`HANGING_EXCESS`] times the head's distance to the centre) and the
/// others, among which the limbs are chosen.
fn split_hanging(body: &Body, c: &Candidates, free: &[usize], head: usize) -> (Vec<usize>, Vec<usize>) {
    let to_head = c.to_centre(head);
    let off_head: Vec<usize> = free.iter().copied().filter(|&k| k != head && !on_head(body, c, head, k)).collect();
    off_head.iter().copied().partition(|&k| head_excess(c, head, k) < HANGING_EXCESS * to_head)
}

/// The pair of tips of `pool` of least `cost` (the first of equals) whose tips lie apart on the
/// body (farther from each other than 0.8 times the nearer one's distance to the centre: not two
/// toes of one foot), `fixed` (hinted) tips taken as they are.
fn best_pair(c: &Candidates, pool: &[usize], fixed: [Option<usize>; 2], cost: &dyn Fn(usize, usize) -> f64) -> Option<[usize; 2]> {
    let apart = |a: usize, b: usize| c.between(a, b) > 0.8 * c.to_centre(a).min(c.to_centre(b));
    let by_cost = |x: &(usize, usize), y: &(usize, usize)| cost(x.0, x.1).total_cmp(&cost(y.0, y.1));
    match fixed {
        [Some(a), Some(b)] => Some([a, b]),
        [Some(f), None] | [None, Some(f)] => pool.iter().map(|&a| (f, a)).filter(|&(f, a)| a != f && apart(f, a)).min_by(by_cost).map(|(f, a)| [f, a]),
        [None, None] => pool
            .iter()
            .enumerate()
            .flat_map(|(i, &a)| pool[i + 1..].iter().map(move |&b| (a, b)))
            .filter(|&(a, b)| apart(a, b))
            .min_by(by_cost)
            .map(|(a, b)| [a, b]),
    }
}

/// Step 4, the feet: the pair of `limbs` lowest along the up axis together plus twice the
/// difference of their distances to the centre (in extents), `hinted` feet taken as they are.
fn choose_feet(body: &Body, c: &Candidates, limbs: &[usize], hinted: [Option<usize>; 2]) -> Result<[usize; 2]> {
    let asymmetry = |a: usize, b: usize| (c.to_centre(a) - c.to_centre(b)).abs() / body.extent;
    let cost = |a: usize, b: usize| (body.h(c.v(a)) + body.h(c.v(b)) - 2.0 * body.base) / body.extent + 2.0 * asymmetry(a, b);
    best_pair(c, limbs, hinted, &cost).ok_or_else(|| anyhow::anyhow!("no pair of tips for the feet"))
}

/// What tells the arms once head and feet are known: the branches off the spine, the body's
/// height and its left.
struct Arms<'a> {
    body: &'a Body<'a>,
    c: &'a Candidates,
    /// The head's tip and the feet's.
    head: usize,
    feet: [usize; 2],
    branch: Branches<'a>,
    /// The head's height above the lower foot.
    height: f64,
    /// Towards the body's left ([`body_left`]).
    left: Vector3<f64>,
}

impl<'a> Arms<'a> {
    fn new(body: &'a Body<'a>, c: &'a Candidates, head: usize, feet: [usize; 2]) -> Self {
        let hv = c.v(head);
        let height = body.h(hv) - body.h(c.v(feet[0])).min(body.h(c.v(feet[1])));
        let left = body_left(body.graph, body.up, [c.v(feet[0]), c.v(feet[1])], height);
        let branch = Branches::new(body.graph, hv, [&c.tips[feet[0]].d, &c.tips[feet[1]].d]);
        Arms { body, c, head, feet, branch, height, left }
    }

    /// The height of tip `k`'s branch root above the lower foot, in body heights.
    fn root_height(&self, k: usize) -> f64 {
        let t = &self.c.tips[k];
        (self.branch.root(t.v, &t.d).dot(self.body.up) - (self.body.h(self.c.v(self.head)) - self.height)) / self.height
    }

    /// How far tip `k`'s branch root lies towards the left.
    fn root_side(&self, k: usize) -> f64 {
        let t = &self.c.tips[k];
        self.branch.root(t.v, &t.d).dot(&self.left)
    }

    /// The body's width round tip `k` ([`tip_width`]).
    fn width(&self, k: usize) -> f64 {
        tip_width(self.body.graph, self.c.v(k), &self.c.tips[k].d, self.body.extent)
    }

    /// Whether tip `k` can be a hand: at least [`LIMB_SEPARATION`] from both feet (not a heel or
    /// an ankle of a foot modelled in pieces), its branch's root higher than [`UPPER_BODY`] (an
    /// arm leaves the body at the shoulder, high up; a tail at the hip), itself higher than
    /// [`HAND_LOWEST`] and wider than [`HAND_WIDTH`].
    fn can_be_hand(&self, k: usize) -> bool {
        let (body, c, height) = (self.body, self.c, self.height);
        let off_feet = self.feet.iter().all(|&f| c.between(f, k) > LIMB_SEPARATION * body.extent);
        let upper = || self.root_height(k) > UPPER_BODY && (body.h(c.v(k)) - (body.h(c.v(self.head)) - height)) / height > HAND_LOWEST;
        let thick = || self.width(k) > HAND_WIDTH * body.extent;
        off_feet && upper() && thick()
    }

    /// The length of tip `k`'s branch, counted up to where it enters the body's piece (the
    /// centre's): a limb modelled as a piece of its own is joined where it is pushed into the
    /// body, at its root, a prop anywhere along it.
    fn length(&self, k: usize) -> f64 {
        let (graph, c) = (self.body.graph, self.c);
        let piece = graph.component[c.centre as usize];
        let to_body = || {
            let path = c.from_centre.path_from(c.v(k));
            path.iter().find(|&&v| graph.component[v as usize] == piece).map_or(0.0, |&v| c.tips[k].d[v as usize])
        };
        self.branch.of(c.v(k)).0.min(if graph.component[c.v(k) as usize] == piece { f64::INFINITY } else { to_body() })
    }

    /// The cost of tips `a` and `b` as the hands: [`ARM_ASYMMETRY`] times the difference of
    /// their branches' lengths less the two lengths (in extents); infinite unless their roots lie
    /// more than [`SIDE_OFFSET`] apart across the body (when it has a left) and their branches
    /// share no way to each other (two arms, not two ends of one).
    fn hands_cost(&self, a: usize, b: usize) -> f64 {
        let (la, lb) = (self.length(a), self.length(b));
        let sides = self.left.norm() == 0.0 || (self.root_side(a) - self.root_side(b)).abs() > SIDE_OFFSET * self.body.extent;
        let own_branches = self.c.between(a, b) > 0.9 * (la + lb);
        if sides && own_branches { (ARM_ASYMMETRY * (la - lb).abs() - la - lb) / self.body.extent } else { f64::INFINITY }
    }

    /// Logs where the legs part and, for each free tip, what the choices measure of it.
    fn log(&self, free: &[usize], hanging: &[usize]) {
        let (c, head) = (self.c, self.head);
        mesh_core::info!("the legs part {:.3} from the head along the spine", self.branch.crotch);
        for &k in free {
            let p = self.body.graph.position(c.v(k));
            mesh_core::info!(
                "candidate {} ({:.3}, {:.3}, {:.3}): to the centre {:.3}, head excess {:.3}, branch {:.3} leaving the spine {:.3} from the head, root side {:.3} height {:.3} width {:.3}{}",
                c.v(k), p.x, p.y, p.z, c.to_centre(k), head_excess(c, head, k), self.branch.of(c.v(k)).0, self.branch.of(c.v(k)).1, self.root_side(k), self.root_height(k), self.width(k) / self.body.extent,
                if k == head { " (head)" } else if hanging.contains(&k) { " (hangs from the head)" } else if on_head(self.body, c, head, k) { " (on the head)" } else { "" }
            );
        }
    }
}

/// Step 5, the hands: of the `limbs` other than the feet that can be hands, the pair of least
/// [`Arms::hands_cost`], `hinted` hands taken as they are; an error when no pair has a finite
/// cost and the two are not both hinted.
fn choose_hands(arms: &Arms, limbs: &[usize], hinted: [Option<usize>; 2]) -> Result<[usize; 2]> {
    let rest: Vec<usize> = limbs.iter().copied().filter(|k| !arms.feet.contains(k)).filter(|&k| arms.can_be_hand(k)).collect();
    let cost = |a: usize, b: usize| arms.hands_cost(a, b);
    best_pair(arms.c, &rest, hinted, &cost)
        .filter(|p| cost(p[0], p[1]).is_finite() || (hinted[0].is_some() && hinted[1].is_some()))
        .ok_or_else(|| anyhow::anyhow!("no pair of tips for the hands (head at vertex {})", arms.c.v(arms.head)))
}

/// Step 6: the pair `p` as `[left, right]`: a hinted left (`l`) or right (`r`) tip in its place,
/// else the one of greater `side` (towards the left) first.
fn left_first(p: [usize; 2], l: Option<usize>, r: Option<usize>, side: &dyn Fn(usize) -> f64) -> [usize; 2] {
    match (l, r) {
        (Some(l), _) => [l, if p[0] == l { p[1] } else { p[0] }],
        (None, Some(r)) => [if p[0] == r { p[1] } else { p[0] }, r],
        _ if side(p[0]) >= side(p[1]) => p,
        _ => [p[1], p[0]],
    }
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

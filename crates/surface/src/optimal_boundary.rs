//! Optimal merging boundary in an overlap band (transfer paper §6.2, after Huang et al. 2007
//! "Optimal boundaries for Poisson mesh merging").
//!
//! The band is a cylinder (two boundary loops) present in two geometries (root and aligned
//! child). We look for the closed edge loop going once around the cylinder that minimises
//! `Σ_edges |e| (½(c_u + c_v) + δ)`, where `c_v = |x_v^root - x_v^child|` is the per-vertex
//! discrepancy (the curve integral of the discrepancy) and `δ = 10⁻³ · mean(c)` (1 if all
//! `c = 0`) a small length term that breaks ties towards short loops.
//!
//! Search: a shortest (hop count) path `P` joins the two boundaries (the cut). A loop goes
//! around the cylinder iff it crosses `P` an odd number of times, so we run Dijkstra in the
//! two-sheeted cover of the band graph where stepping between a vertex of `P` and a neighbour
//! on its right side (from the ordered one-ring) switches sheet, from `(s, 0)` to `(s, 1)`
//! for every `s ∈ P`, and keep the cheapest. Every non-contractible loop meets `P`, so this is
//! exact for loops along mesh edges (Huang et al. approximate on a similar graph); loops that
//! wind an odd number `> 1` of times are never cheaper with positive weights.

use crate::topo::ordered_fan;
use crate::{Error, Result};
use mesh_core::topology::Topology;
use nalgebra::Vector3;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};

/// A closed loop of band vertices (first not repeated at the end) and its cost.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryLoop {
    pub vertices: Vec<usize>,
    pub cost: f64,
}

/// Per-vertex discrepancy `|a_v - b_v|` between two instantiations of the band.
pub fn discrepancy(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Vec<f64> {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).collect()
}

#[derive(Copy, Clone, PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// The cheapest loop around the band. `positions` give edge lengths, `faces` the band faces
/// (indices into `positions`), `cost` the per-vertex discrepancy.
pub fn optimal_loop(
    positions: &[Vector3<f64>],
    faces: &[[u32; 3]],
    cost: &[f64],
) -> Result<BoundaryLoop> {
    crate::check_faces(positions.len(), faces, "overlap band")?;
    optimal_loop_in(&Topology::new(positions.len(), faces), positions, cost)
}

/// [`optimal_loop`] on a band whose topology is already built (reused across frames).
pub fn optimal_loop_in(
    topo: &Topology,
    positions: &[Vector3<f64>],
    cost: &[f64],
) -> Result<BoundaryLoop> {
    let n = positions.len();
    let faces = topo.faces();
    if topo.n_vertices() != n || cost.len() != n || cost.iter().any(|c| !c.is_finite() || *c < 0.0)
    {
        return Err(Error::invalid(
            "overlap band: positions and discrepancy must be finite, one per vertex",
        ));
    }
    let loops = topo.boundary_loops();
    if loops.len() != 2 {
        return Err(Error::invalid(format!(
            "overlap band is not a cylinder: {} boundary loops instead of 2",
            loops.len()
        )));
    }
    let cut = cut_path(topo, &loops[0], &loops[1])?;
    let crossing = crossing_edges(&cut, topo, faces)?;
    let flips = |u: usize, v: usize| crossing[u].contains(&v) || crossing[v].contains(&u);

    let mean = cost.iter().sum::<f64>() / n as f64;
    let delta = if mean > 0.0 { 1e-3 * mean } else { 1.0 };
    let weight = |u: usize, v: usize| {
        (positions[u] - positions[v]).norm() * (0.5 * (cost[u] + cost[v]) + delta)
    };

    let mut best: Option<BoundaryLoop> = None;
    let mut dist = vec![f64::INFINITY; 2 * n];
    let mut prev = vec![usize::MAX; 2 * n];
    for &s in &cut {
        dist.iter_mut().for_each(|d| *d = f64::INFINITY);
        prev.iter_mut().for_each(|p| *p = usize::MAX);
        let bound = best.as_ref().map_or(f64::INFINITY, |b| b.cost);
        let (src, dst) = (2 * s, 2 * s + 1);
        dist[src] = 0.0;
        let mut heap = BinaryHeap::new();
        heap.push(Reverse((Key(0.0), src)));
        while let Some(Reverse((Key(d), node))) = heap.pop() {
            if d > dist[node] || d >= bound {
                continue;
            }
            if node == dst {
                break;
            }
            let (u, sheet) = (node / 2, node % 2);
            for &v in topo.vertex_neighbors(u as u32) {
                let v = v as usize;
                let flip = flips(u, v) as usize;
                let next = 2 * v + (sheet ^ flip);
                let nd = d + weight(u, v);
                if nd < dist[next] {
                    dist[next] = nd;
                    prev[next] = node;
                    heap.push(Reverse((Key(nd), next)));
                }
            }
        }
        if dist[dst] < bound {
            let mut vertices = Vec::new();
            let mut node = prev[dst];
            while node != src {
                vertices.push(node / 2);
                node = prev[node];
            }
            vertices.push(s);
            vertices.reverse();
            best = Some(BoundaryLoop {
                vertices,
                cost: dist[dst],
            });
        }
    }
    best.ok_or_else(|| Error::invalid("overlap band: no loop around the band found"))
}

/// Breadth-first shortest path from boundary `a` to boundary `b`.
fn cut_path(topo: &Topology, a: &[u32], b: &[u32]) -> Result<Vec<usize>> {
    let n = topo.n_vertices();
    let in_b: HashSet<usize> = b.iter().map(|&v| v as usize).collect();
    let mut prev = vec![usize::MAX; n];
    let mut seen = vec![false; n];
    let mut queue = std::collections::VecDeque::new();
    for &s in a {
        seen[s as usize] = true;
        queue.push_back(s as usize);
    }
    while let Some(u) = queue.pop_front() {
        if in_b.contains(&u) {
            let mut path = vec![u];
            let mut v = u;
            while prev[v] != usize::MAX {
                v = prev[v];
                path.push(v);
            }
            path.reverse();
            return Ok(path);
        }
        for &v in topo.vertex_neighbors(u as u32) {
            let v = v as usize;
            if !seen[v] {
                seen[v] = true;
                prev[v] = u;
                queue.push_back(v);
            }
        }
    }
    Err(Error::invalid(
        "overlap band: its two boundaries are not connected",
    ))
}

/// For each cut vertex, its neighbours on the cut's right side (the sheet-switching edges);
/// empty for the other vertices.
fn crossing_edges(cut: &[usize], topo: &Topology, faces: &[[u32; 3]]) -> Result<Vec<Vec<usize>>> {
    let on_cut: HashSet<usize> = cut.iter().copied().collect();
    let m = cut.len();
    let mut crossing = vec![Vec::new(); topo.n_vertices()];
    for (k, &p) in cut.iter().enumerate() {
        let fan = ordered_fan(p, topo.vertex_faces(p as u32), faces)?;
        let pos = |x: usize| fan.iter().position(|&y| y == x);
        // Right side in counter-clockwise order (module doc): from the previous cut vertex
        // round to the next one.
        let right: Vec<usize> = if m == 1 {
            return Err(Error::invalid("overlap band: the two boundaries touch"));
        } else if k == 0 {
            let i = pos(cut[1]).ok_or_else(|| Error::invalid("overlap band: broken cut"))?;
            fan[..i].to_vec()
        } else if k == m - 1 {
            let i = pos(cut[k - 1]).ok_or_else(|| Error::invalid("overlap band: broken cut"))?;
            fan[i + 1..].to_vec()
        } else {
            let (i_next, i_prev) = match (pos(cut[k + 1]), pos(cut[k - 1])) {
                (Some(a), Some(b)) => (a, b),
                _ => return Err(Error::invalid("overlap band: broken cut")),
            };
            let len = fan.len();
            let mut r = Vec::new();
            let mut i = (i_prev + 1) % len;
            while i != i_next {
                r.push(fan[i]);
                i = (i + 1) % len;
            }
            r
        };
        crossing[p] = right.into_iter().filter(|u| !on_cut.contains(u)).collect();
    }
    Ok(crossing)
}

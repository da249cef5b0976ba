//! Geodesic distance approximated along mesh edges: Dijkstra from a set of
//! sources with Euclidean edge lengths.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use mesh_core::topology::Topology;
use nalgebra::Vector3;

#[derive(PartialEq)]
struct Item(f64, u32);
impl Eq for Item {}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Item {
    // Smallest distance first; ties by vertex for determinism.
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

/// Edge-path distance from the nearest source to every vertex (`f64::INFINITY`
/// where unreachable).
pub fn distances(topology: &Topology, pos: &[Vector3<f64>], sources: &[u32]) -> Vec<f64> {
    let mut d = vec![f64::INFINITY; pos.len()];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        d[s as usize] = 0.0;
        heap.push(Item(0.0, s));
    }
    while let Some(Item(dist, v)) = heap.pop() {
        if dist > d[v as usize] {
            continue;
        }
        for &w in topology.vertex_neighbors(v) {
            let nd = dist + (pos[v as usize] - pos[w as usize]).norm();
            if nd < d[w as usize] {
                d[w as usize] = nd;
                heap.push(Item(nd, w));
            }
        }
    }
    d
}

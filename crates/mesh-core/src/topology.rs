//! Mesh connectivity: vertex/edge/face adjacency, boundary loops, connected
//! components and Dijkstra shortest edge paths.
//!
//! Built once per topology (all frames of a sequence share it) from the face
//! list alone; geometry enters only through the edge weights of the path
//! queries.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use nalgebra::Vector3;

/// Adjacency of a triangle mesh with `n_vertices` vertices.
///
/// Edges are undirected, stored as `[a, b]` with `a < b`, sorted; edge ids are
/// positions in [`Topology::edges`]. Faces are assumed valid (indices in range,
/// no repeated index: see [`crate::TriMesh::validate`]).
#[derive(Clone, Debug)]
pub struct Topology {
    n_vertices: usize,
    faces: Vec<[u32; 3]>,
    vertex_neighbors: Vec<Vec<u32>>,
    vertex_faces: Vec<Vec<u32>>,
    edges: Vec<[u32; 2]>,
    edge_faces: Vec<Vec<u32>>,
    face_neighbors: Vec<Vec<u32>>,
}

impl Topology {
    /// Builds the adjacency. Panics if a face index is `>= n_vertices`
    /// (validate untrusted meshes first).
    pub fn new(n_vertices: usize, faces: &[[u32; 3]]) -> Self {
        let mut vertex_neighbors = vec![Vec::new(); n_vertices];
        let mut vertex_faces = vec![Vec::new(); n_vertices];
        let mut half: Vec<([u32; 2], u32)> = Vec::with_capacity(3 * faces.len());
        for (f, face) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face[k], face[(k + 1) % 3]);
                vertex_neighbors[a as usize].push(b);
                vertex_neighbors[b as usize].push(a);
                vertex_faces[a as usize].push(f as u32);
                half.push(([a.min(b), a.max(b)], f as u32));
            }
        }
        for n in &mut vertex_neighbors {
            n.sort_unstable();
            n.dedup();
        }
        half.sort_unstable();
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut edge_faces: Vec<Vec<u32>> = Vec::new();
        for (e, f) in half {
            if edges.last() != Some(&e) {
                edges.push(e);
                edge_faces.push(Vec::with_capacity(2));
            }
            edge_faces.last_mut().unwrap().push(f);
        }
        let mut face_neighbors = vec![Vec::with_capacity(3); faces.len()];
        for ef in &edge_faces {
            for &f in ef {
                face_neighbors[f as usize].extend(ef.iter().copied().filter(|&g| g != f));
            }
        }
        for n in &mut face_neighbors {
            n.sort_unstable();
            n.dedup();
        }
        Topology {
            n_vertices,
            faces: faces.to_vec(),
            vertex_neighbors,
            vertex_faces,
            edges,
            edge_faces,
            face_neighbors,
        }
    }

    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    /// Vertices sharing an edge with `v`, sorted ascending.
    pub fn vertex_neighbors(&self, v: u32) -> &[u32] {
        &self.vertex_neighbors[v as usize]
    }
    /// Faces using vertex `v`, ascending.
    pub fn vertex_faces(&self, v: u32) -> &[u32] {
        &self.vertex_faces[v as usize]
    }
    /// All undirected edges `[a, b]`, `a < b`, sorted.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
    /// Faces containing edge `e` (one on a boundary, two inside a manifold).
    pub fn edge_faces(&self, e: usize) -> &[u32] {
        &self.edge_faces[e]
    }
    /// Faces sharing an edge with face `f`, sorted ascending.
    pub fn face_neighbors(&self, f: u32) -> &[u32] {
        &self.face_neighbors[f as usize]
    }
    /// Id of the edge between `a` and `b`, if they are adjacent.
    pub fn edge_index(&self, a: u32, b: u32) -> Option<usize> {
        self.edges.binary_search(&[a.min(b), a.max(b)]).ok()
    }
    pub fn are_adjacent(&self, a: u32, b: u32) -> bool {
        self.vertex_neighbors
            .get(a as usize)
            .is_some_and(|n| n.binary_search(&b).is_ok())
    }

    /// `V - E + F` (2 for a closed genus-0 surface, 0 for an open cylinder).
    pub fn euler_characteristic(&self) -> i64 {
        self.n_vertices as i64 - self.edges.len() as i64 + self.faces.len() as i64
    }

    /// True when no edge lies on a boundary (every edge has at least two faces).
    pub fn is_closed(&self) -> bool {
        self.edge_faces.iter().all(|f| f.len() >= 2)
    }

    /// True when every edge has at most two faces.
    pub fn is_edge_manifold(&self) -> bool {
        self.edge_faces.iter().all(|f| f.len() <= 2)
    }

    /// Boundary loops, each an ordered list of vertices (first vertex not
    /// repeated at the end). A boundary edge is an edge with exactly one face;
    /// each loop follows the direction of its faces' edges, so the surface lies
    /// to the left when walking it on the outside of a counter-clockwise mesh.
    /// Loops start at their smallest boundary half-edge and are listed in that
    /// order, so the result is deterministic. Where two loops touch at one
    /// vertex (non-manifold) the walk takes the smallest unused outgoing
    /// boundary edge, which may merge them into one figure-eight loop.
    pub fn boundary_loops(&self) -> Vec<Vec<u32>> {
        // Directed boundary half-edges as they appear in their face, sorted.
        let mut out: Vec<[u32; 2]> = Vec::new();
        for (e, ef) in self.edges.iter().zip(&self.edge_faces) {
            if ef.len() == 1 {
                let face = self.faces[ef[0] as usize];
                let forward = (0..3).any(|k| face[k] == e[0] && face[(k + 1) % 3] == e[1]);
                out.push(if forward { *e } else { [e[1], e[0]] });
            }
        }
        out.sort_unstable();
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
                // Next unused half-edge leaving `cur` (smallest, for determinism).
                let lo = out.partition_point(|h| h[0] < cur);
                let next = (lo..out.len())
                    .take_while(|&i| out[i][0] == cur)
                    .find(|&i| !used[i]);
                match next {
                    Some(i) => {
                        used[i] = true;
                        cur = out[i][1];
                    }
                    None => break, // inconsistent orientation: return the open chain
                }
            }
            loops.push(lp);
        }
        loops
    }

    /// Connected components (through edges) as sorted vertex lists, ordered by
    /// their smallest vertex. Isolated vertices form their own components.
    pub fn connected_components(&self) -> Vec<Vec<u32>> {
        let mut label = vec![u32::MAX; self.n_vertices];
        let mut comps = Vec::new();
        let mut stack = Vec::new();
        for s in 0..self.n_vertices {
            if label[s] != u32::MAX {
                continue;
            }
            let id = comps.len() as u32;
            let mut comp = Vec::new();
            label[s] = id;
            stack.push(s as u32);
            while let Some(v) = stack.pop() {
                comp.push(v);
                for &w in &self.vertex_neighbors[v as usize] {
                    if label[w as usize] == u32::MAX {
                        label[w as usize] = id;
                        stack.push(w);
                    }
                }
            }
            comp.sort_unstable();
            comps.push(comp);
        }
        comps
    }

    /// Shortest edge path from `from` to `to` with Euclidean edge lengths from
    /// `positions`. Returns the vertex path (both ends included) and its
    /// length, or `None` if `to` is unreachable.
    pub fn shortest_path(
        &self,
        positions: &[Vector3<f64>],
        from: u32,
        to: u32,
    ) -> Option<(Vec<u32>, f64)> {
        self.shortest_path_by(from, to, |a, b| {
            Some((positions[a as usize] - positions[b as usize]).norm())
        })
    }

    /// As [`Topology::shortest_path`], but only through vertices with
    /// `allowed[v] == true` (the end points must be allowed too).
    pub fn shortest_path_within(
        &self,
        positions: &[Vector3<f64>],
        allowed: &[bool],
        from: u32,
        to: u32,
    ) -> Option<(Vec<u32>, f64)> {
        self.shortest_path_by(from, to, |a, b| {
            (allowed[a as usize] && allowed[b as usize])
                .then(|| (positions[a as usize] - positions[b as usize]).norm())
        })
    }

    /// Dijkstra's algorithm with custom weights: `weight(a, b)` is the cost of
    /// the edge `a -> b`, or `None` if it may not be used. Negative, NaN or
    /// infinite weights are treated as `None`. Ties are broken by vertex id, so
    /// the result is deterministic.
    pub fn shortest_path_by<W>(&self, from: u32, to: u32, weight: W) -> Option<(Vec<u32>, f64)>
    where
        W: Fn(u32, u32) -> Option<f64>,
    {
        let n = self.n_vertices;
        if from as usize >= n || to as usize >= n {
            return None;
        }
        let mut dist = vec![f64::INFINITY; n];
        let mut prev = vec![u32::MAX; n];
        let mut heap = BinaryHeap::new();
        dist[from as usize] = 0.0;
        heap.push(Node { cost: 0.0, v: from });
        while let Some(Node { cost, v }) = heap.pop() {
            if v == to {
                break;
            }
            if cost > dist[v as usize] {
                continue;
            }
            for &w in &self.vertex_neighbors[v as usize] {
                let Some(c) = weight(v, w).filter(|c| c.is_finite() && *c >= 0.0) else {
                    continue;
                };
                let nd = cost + c;
                if nd < dist[w as usize] {
                    dist[w as usize] = nd;
                    prev[w as usize] = v;
                    heap.push(Node { cost: nd, v: w });
                }
            }
        }
        if !dist[to as usize].is_finite() {
            return None;
        }
        let mut path = vec![to];
        let mut cur = to;
        while cur != from {
            cur = prev[cur as usize];
            path.push(cur);
        }
        path.reverse();
        Some((path, dist[to as usize]))
    }
}

/// Min-heap entry (reversed ordering on cost, then vertex id).
#[derive(Clone, Copy, PartialEq)]
struct Node {
    cost: f64,
    v: u32,
}
impl Eq for Node {}
impl Ord for Node {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .cost
            .total_cmp(&self.cost)
            .then_with(|| other.v.cmp(&self.v))
    }
}
impl PartialOrd for Node {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

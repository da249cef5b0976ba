//! Mesh connectivity: vertex/edge/face adjacency, boundary loops, connected
//! components and Dijkstra shortest edge paths.
//!
//! Built once per topology (all frames of a sequence share it) from the face
//! list alone; geometry enters only through the edge weights of the path
//! queries.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use nalgebra::Vector3;

/// Rows of `u32` lists stored flat (compressed sparse rows): row `i` is
/// `items[offsets[i]..offsets[i + 1]]`. One allocation per table instead of
/// one per vertex, edge or face.
#[derive(Clone, Debug, Default)]
struct Rows {
    offsets: Vec<usize>,
    items: Vec<u32>,
}

impl Rows {
    /// Rows from their lengths; every row is then filled by [`Rows::fill`].
    fn with_lengths(lengths: impl Iterator<Item = usize>) -> (Self, Vec<usize>) {
        let mut offsets = vec![0];
        for n in lengths {
            offsets.push(offsets.last().unwrap() + n);
        }
        let cursor = offsets[..offsets.len() - 1].to_vec();
        let items = vec![0; *offsets.last().unwrap()];
        (Rows { offsets, items }, cursor)
    }
    fn fill(&mut self, cursor: &mut [usize], row: usize, value: u32) {
        self.items[cursor[row]] = value;
        cursor[row] += 1;
    }
    fn len(&self) -> usize {
        self.offsets.len() - 1
    }
    fn row(&self, i: usize) -> &[u32] {
        &self.items[self.offsets[i]..self.offsets[i + 1]]
    }
    fn iter(&self) -> impl Iterator<Item = &[u32]> {
        (0..self.len()).map(move |i| self.row(i))
    }
    /// Sorts and deduplicates every row in place, then releases the slack.
    fn sort_dedup_rows(&mut self) {
        let mut write = 0;
        let mut start = 0;
        for i in 0..self.len() {
            let end = self.offsets[i + 1];
            self.items[start..end].sort_unstable();
            let row_start = write;
            for k in start..end {
                let v = self.items[k];
                if write == row_start || self.items[write - 1] != v {
                    self.items[write] = v;
                    write += 1;
                }
            }
            start = end;
            self.offsets[i + 1] = write;
        }
        self.items.truncate(write);
        self.items.shrink_to_fit();
    }
}

/// Adjacency of a triangle mesh with `n_vertices` vertices.
///
/// Edges are undirected, stored as `[a, b]` with `a < b`, sorted; edge ids are
/// positions in [`Topology::edges`]. Faces are assumed valid (indices in range,
/// no repeated index: see [`crate::TriMesh::validate`]). The adjacency tables
/// are flat ([`Rows`]): about 100 bytes per triangle while building, 70 after.
#[derive(Clone, Debug)]
pub struct Topology {
    n_vertices: usize,
    faces: Vec<[u32; 3]>,
    vertex_neighbors: Rows,
    vertex_faces: Rows,
    edges: Vec<[u32; 2]>,
    edge_faces: Rows,
    face_neighbors: Rows,
}

impl Topology {
    /// Builds the adjacency. Panics if a face index is `>= n_vertices`
    /// (validate untrusted meshes first).
    pub fn new(n_vertices: usize, faces: &[[u32; 3]]) -> Self {
        let mut degree = vec![0usize; n_vertices];
        for face in faces {
            for &v in face {
                degree[v as usize] += 1;
            }
        }
        // Every corner of a face adds its face to its vertex, and its two
        // face-neighbours (both edges through it) to its vertex's neighbours.
        let (mut vertex_faces, mut vf_cursor) = Rows::with_lengths(degree.iter().copied());
        let (mut vertex_neighbors, mut vn_cursor) = Rows::with_lengths(degree.iter().map(|d| 2 * d));
        drop(degree);
        for (f, face) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b, c) = (face[k], face[(k + 1) % 3], face[(k + 2) % 3]);
                vertex_faces.fill(&mut vf_cursor, a as usize, f as u32);
                vertex_neighbors.fill(&mut vn_cursor, a as usize, b);
                vertex_neighbors.fill(&mut vn_cursor, a as usize, c);
            }
        }
        drop((vf_cursor, vn_cursor));
        vertex_neighbors.sort_dedup_rows();

        // Edges [a, b], a <= b, in sorted order: row a's neighbours from a on.
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut first_edge = Vec::with_capacity(n_vertices + 1);
        for a in 0..n_vertices {
            first_edge.push(edges.len());
            let row = vertex_neighbors.row(a);
            let from = row.partition_point(|&b| (b as usize) < a);
            edges.extend(row[from..].iter().map(|&b| [a as u32, b]));
        }
        first_edge.push(edges.len());
        let edge_of = |a: u32, b: u32| -> usize {
            let (a, b) = (a.min(b), a.max(b));
            let row = &edges[first_edge[a as usize]..first_edge[a as usize + 1]];
            first_edge[a as usize] + row.partition_point(|e| e[1] < b)
        };
        // The three edges of every face, looked up once.
        let face_edges: Vec<[u32; 3]> = faces
            .iter()
            .map(|face| std::array::from_fn(|k| edge_of(face[k], face[(k + 1) % 3]) as u32))
            .collect();
        drop(first_edge);
        let mut edge_degree = vec![0usize; edges.len()];
        for fe in &face_edges {
            for &e in fe {
                edge_degree[e as usize] += 1;
            }
        }
        let (mut edge_faces, mut ef_cursor) = Rows::with_lengths(edge_degree.into_iter());
        for (f, fe) in face_edges.iter().enumerate() {
            for &e in fe {
                // Faces are visited in order, so every row comes out ascending.
                edge_faces.fill(&mut ef_cursor, e as usize, f as u32);
            }
        }
        drop(ef_cursor);

        let mut face_neighbors = Rows { offsets: Vec::with_capacity(faces.len() + 1), items: Vec::new() };
        face_neighbors.offsets.push(0);
        let mut scratch = Vec::new();
        for (f, fe) in face_edges.iter().enumerate() {
            scratch.clear();
            for &e in fe {
                scratch.extend(edge_faces.row(e as usize).iter().copied().filter(|&g| g != f as u32));
            }
            scratch.sort_unstable();
            scratch.dedup();
            face_neighbors.items.extend_from_slice(&scratch);
            face_neighbors.offsets.push(face_neighbors.items.len());
        }
        face_neighbors.items.shrink_to_fit();
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
        self.vertex_neighbors.row(v as usize)
    }
    /// Faces using vertex `v`, ascending.
    pub fn vertex_faces(&self, v: u32) -> &[u32] {
        self.vertex_faces.row(v as usize)
    }
    /// All undirected edges `[a, b]`, `a < b`, sorted.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
    /// Faces containing edge `e` (one on a boundary, two inside a manifold).
    pub fn edge_faces(&self, e: usize) -> &[u32] {
        self.edge_faces.row(e)
    }
    /// Faces sharing an edge with face `f`, sorted ascending.
    pub fn face_neighbors(&self, f: u32) -> &[u32] {
        self.face_neighbors.row(f as usize)
    }
    /// Id of the edge between `a` and `b`, if they are adjacent.
    pub fn edge_index(&self, a: u32, b: u32) -> Option<usize> {
        self.edges.binary_search(&[a.min(b), a.max(b)]).ok()
    }
    pub fn are_adjacent(&self, a: u32, b: u32) -> bool {
        (a as usize) < self.n_vertices && self.vertex_neighbors.row(a as usize).binary_search(&b).is_ok()
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
        for (e, ef) in self.edges.iter().zip(self.edge_faces.iter()) {
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
                for &w in self.vertex_neighbors.row(v as usize) {
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

    /// Edge-path distance (Dijkstra, Euclidean edge lengths from `positions`) from the nearest
    /// of `sources` to every vertex; `f64::INFINITY` where unreachable. Ties are broken by
    /// vertex id.
    pub fn edge_distances(&self, positions: &[Vector3<f64>], sources: &[u32]) -> Vec<f64> {
        let mut dist = vec![f64::INFINITY; self.n_vertices];
        let mut heap = BinaryHeap::new();
        for &s in sources.iter().filter(|&&s| (s as usize) < self.n_vertices) {
            dist[s as usize] = 0.0;
            heap.push(Node { cost: 0.0, v: s });
        }
        while let Some(Node { cost, v }) = heap.pop() {
            if cost > dist[v as usize] {
                continue;
            }
            for &w in self.vertex_neighbors.row(v as usize) {
                let c = cost + (positions[v as usize] - positions[w as usize]).norm();
                if c < dist[w as usize] {
                    dist[w as usize] = c;
                    heap.push(Node { cost: c, v: w });
                }
            }
        }
        dist
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
            for &w in self.vertex_neighbors.row(v as usize) {
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

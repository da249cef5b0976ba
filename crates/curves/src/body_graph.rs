//! The template as one graph for geodesic distances: its mesh edges plus the joins between its
//! connected components ([`mesh_core::component_joins`]), each weighted by its Euclidean length.
//! A body made of several pieces (a game character's separate limbs, head and props) is then
//! measured as one, the same way the segmentation floods it.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use mesh_core::topology::Topology;
use mesh_core::TriMesh;
use nalgebra::Vector3;

pub struct BodyGraph<'a> {
    pub mesh: &'a TriMesh,
    pub topology: Topology,
    /// Each vertex's neighbours across component joins.
    pub joins: Vec<Vec<u32>>,
    /// Connected component (through mesh edges) of each vertex.
    pub component: Vec<u32>,
    pub n_components: usize,
}

/// Shortest distances from a set of sources, with each vertex's predecessor on its shortest path.
pub struct Distances {
    pub d: Vec<f64>,
    pub previous: Vec<u32>,
}

impl Distances {
    /// The shortest path from `v` back to the nearest source (both ends included).
    pub fn path_from(&self, mut v: u32) -> Vec<u32> {
        let mut path = vec![v];
        while self.previous[v as usize] != u32::MAX {
            v = self.previous[v as usize];
            path.push(v);
        }
        path
    }
}

#[derive(PartialEq)]
struct Node {
    cost: f64,
    v: u32,
}
impl Eq for Node {}
impl Ord for Node {
    fn cmp(&self, o: &Self) -> Ordering {
        o.cost.total_cmp(&self.cost).then_with(|| o.v.cmp(&self.v))
    }
}
impl PartialOrd for Node {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl<'a> BodyGraph<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let n = mesh.vertices.len();
        let topology = Topology::new(n, &mesh.faces);
        let components = topology.connected_components();
        let mut component = vec![0u32; n];
        for (c, comp) in components.iter().enumerate() {
            for &v in comp {
                component[v as usize] = c as u32;
            }
        }
        let joins = mesh_core::component_joins::join_neighbours(
            n,
            &mesh_core::component_joins::component_joins(&topology, &mesh.vertices),
        );
        BodyGraph { mesh, topology, joins, component, n_components: components.len() }
    }

    pub fn n_vertices(&self) -> usize {
        self.mesh.vertices.len()
    }

    pub fn position(&self, v: u32) -> Vector3<f64> {
        self.mesh.vertices[v as usize]
    }

    /// The neighbours of `v` along mesh edges and joins.
    pub fn neighbours(&self, v: u32) -> impl Iterator<Item = &u32> {
        self.topology.vertex_neighbors(v).iter().chain(&self.joins[v as usize])
    }

    /// Dijkstra from `sources` over mesh edges and joins.
    pub fn distances(&self, sources: &[u32]) -> Distances {
        let n = self.n_vertices();
        let pos = &self.mesh.vertices;
        let mut d = vec![f64::INFINITY; n];
        let mut previous = vec![u32::MAX; n];
        let mut heap = BinaryHeap::new();
        for &s in sources.iter().filter(|&&s| (s as usize) < n) {
            d[s as usize] = 0.0;
            heap.push(Node { cost: 0.0, v: s });
        }
        while let Some(Node { cost, v }) = heap.pop() {
            if cost > d[v as usize] {
                continue;
            }
            for &w in self.topology.vertex_neighbors(v).iter().chain(&self.joins[v as usize]) {
                let c = cost + (pos[v as usize] - pos[w as usize]).norm();
                if c < d[w as usize] {
                    d[w as usize] = c;
                    previous[w as usize] = v;
                    heap.push(Node { cost: c, v: w });
                }
            }
        }
        Distances { d, previous }
    }
}

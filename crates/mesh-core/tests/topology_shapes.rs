//! Topology of the test shapes (closed icosphere and capsule, open
//! cylinder), boundary loops, components, and Dijkstra on a grid with known
//! shortest path lengths.

use mesh_core::shapes::{capsule_body, cylinder, icosphere};
use mesh_core::topology::Topology;
use mesh_core::TriMesh;
use nalgebra::Vector3;

fn topo(m: &TriMesh) -> Topology {
    m.validate().unwrap();
    Topology::new(m.n_vertices(), &m.faces)
}

/// Signed volume by the divergence theorem: positive iff faces point outward.
fn signed_volume(m: &TriMesh) -> f64 {
    m.faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| m.vertices[i as usize]);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

/// Every interior edge is used once in each direction (consistent orientation).
fn consistently_oriented(m: &TriMesh) -> bool {
    let mut directed: Vec<(u32, u32)> = m
        .faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k], f[(k + 1) % 3])))
        .collect();
    let n = directed.len();
    directed.sort_unstable();
    directed.dedup();
    directed.len() == n
}

#[test]
fn icosphere_is_a_closed_oriented_sphere() {
    for level in 0..4 {
        let m = icosphere(level);
        let t = topo(&m);
        let k = 4usize.pow(level as u32);
        assert_eq!(m.n_vertices(), 10 * k + 2);
        assert_eq!(m.n_faces(), 20 * k);
        assert_eq!(t.n_edges(), 30 * k);
        assert_eq!(t.euler_characteristic(), 2);
        assert!(t.is_closed() && t.is_edge_manifold());
        assert!(t.boundary_loops().is_empty());
        assert!(consistently_oriented(&m));
        assert_eq!(t.connected_components().len(), 1);
        assert!(m.vertices.iter().all(|v| (v.norm() - 1.0).abs() < 1e-12));
        // Inscribed polyhedron volume approaches 4/3 pi from below.
        let vol = signed_volume(&m);
        assert!(vol > 0.0 && vol < 4.0 / 3.0 * std::f64::consts::PI);
        if level == 3 {
            assert!((vol / (4.0 / 3.0 * std::f64::consts::PI) - 1.0).abs() < 0.02);
        }
        // Vertex normals of a sphere point along the position (exactly on the
        // icosahedron by its 5-fold symmetry, closely after subdivision).
        for (v, n) in m.vertices.iter().zip(m.vertex_normals()) {
            assert!((n.norm() - 1.0).abs() < 1e-12);
            if level == 0 {
                assert!((v - n).norm() < 1e-12);
            }
            assert!(v.dot(&n) > 0.99);
        }
        // Icosahedron vertices have 5 neighbours, all others 6.
        assert!((0..12).all(|v| t.vertex_neighbors(v).len() == 5 && t.vertex_faces(v).len() == 5));
        assert!((12..m.n_vertices() as u32).all(|v| t.vertex_neighbors(v).len() == 6));
        assert!((0..m.n_faces() as u32).all(|f| t.face_neighbors(f).len() == 3));
    }
}

#[test]
fn capsule_is_closed_with_the_capsule_volume() {
    let (m, layout) = capsule_body(12, 48, 0.25, 1.0);
    let t = topo(&m);
    assert_eq!(t.euler_characteristic(), 2);
    assert!(t.is_closed() && t.is_edge_manifold() && consistently_oriented(&m));
    let r: f64 = 0.25;
    let exact = std::f64::consts::PI * r * r * 1.0 + 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let vol = signed_volume(&m);
    assert!(
        vol > 0.0 && (vol / exact - 1.0).abs() < 0.02,
        "{vol} vs {exact}"
    );
    // The layout's rings are horizontal circles at the documented heights.
    let ring = layout.ring(layout.body_ring(3));
    let y = 3.0 / 11.0;
    assert!(ring
        .iter()
        .all(|&v| (m.vertices[v as usize].y - y).abs() < 1e-12));
    assert!(ring.windows(2).all(|w| t.are_adjacent(w[0], w[1])));
    assert_eq!(
        m.vertices[layout.top_pole() as usize],
        Vector3::new(0.0, 1.25, 0.0)
    );
    assert_eq!(layout.top_pole() as usize, m.n_vertices() - 1);
}

#[test]
fn open_cylinder_has_two_ordered_boundary_loops() {
    let (rings, segs) = (5, 16);
    let m = cylinder(rings, segs, 0.5, 2.0);
    let t = topo(&m);
    assert_eq!(t.euler_characteristic(), 0);
    assert!(!t.is_closed() && t.is_edge_manifold() && consistently_oriented(&m));
    let loops = t.boundary_loops();
    assert_eq!(loops.len(), 2);
    for lp in &loops {
        assert_eq!(lp.len(), segs);
        // Consecutive (cyclically) loop vertices share a boundary edge.
        for k in 0..lp.len() {
            let e = t
                .edge_index(lp[k], lp[(k + 1) % lp.len()])
                .expect("loop step is an edge");
            assert_eq!(t.edge_faces(e).len(), 1);
        }
        // All on one ring: constant y, either bottom or top.
        let y = m.vertices[lp[0] as usize].y;
        assert!(y == 0.0 || y == 2.0);
        assert!(lp.iter().all(|&v| m.vertices[v as usize].y == y));
        // Perimeter of the inscribed polygon.
        let per: f64 = (0..lp.len())
            .map(|k| {
                (m.vertices[lp[k] as usize] - m.vertices[lp[(k + 1) % lp.len()] as usize]).norm()
            })
            .sum();
        let exact = 2.0 * segs as f64 * 0.5 * (std::f64::consts::PI / segs as f64).sin();
        assert!((per - exact).abs() < 1e-12);
    }
    // The two loops run in opposite directions around the axis (faces on the left).
    let turn = |lp: &Vec<u32>| {
        let (a, b) = (m.vertices[lp[0] as usize], m.vertices[lp[1] as usize]);
        a.x * b.z - a.z * b.x
    };
    assert!(turn(&loops[0]) * turn(&loops[1]) < 0.0);
}

#[test]
fn components_of_disjoint_shapes() {
    let a = icosphere(1);
    let b = cylinder(3, 8, 1.0, 1.0);
    let off = a.n_vertices() as u32;
    let mut m = a.clone();
    m.vertices
        .extend(b.vertices.iter().map(|v| v + Vector3::new(5.0, 0.0, 0.0)));
    m.faces.extend(b.faces.iter().map(|f| f.map(|i| i + off)));
    m.vertices.push(Vector3::zeros()); // an isolated vertex
    let t = topo(&m);
    let comps = t.connected_components();
    assert_eq!(comps.len(), 3);
    assert_eq!(comps[0], (0..off).collect::<Vec<_>>());
    assert_eq!(comps[1].len(), b.n_vertices());
    assert_eq!(comps[2], vec![m.n_vertices() as u32 - 1]);
    assert!(t.shortest_path(&m.vertices, 0, off).is_none());
}

/// `n x n` grid of unit squares in the xy plane, each split along the
/// `(i, j) -> (i + 1, j + 1)` diagonal. Vertex `(i, j)` is `j * (n + 1) + i`.
fn grid(n: usize) -> TriMesh {
    let w = n + 1;
    let vertices = (0..w * w)
        .map(|k| Vector3::new((k % w) as f64, (k / w) as f64, 0.0))
        .collect();
    let mut faces = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let v = |i: usize, j: usize| (j * w + i) as u32;
            faces.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            faces.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    TriMesh::new(vertices, faces)
}

#[test]
fn dijkstra_on_a_grid_has_the_known_lengths() {
    let n = 10;
    let m = grid(n);
    let t = topo(&m);
    let v = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let s2 = 2f64.sqrt();
    // Along the diagonals' direction: min(a, b) diagonal steps + |a - b| axis steps.
    for (a, b) in [(7, 3), (2, 9), (10, 10), (5, 0)] {
        let (path, len) = t.shortest_path(&m.vertices, v(0, 0), v(a, b)).unwrap();
        let exact = a.min(b) as f64 * s2 + a.abs_diff(b) as f64;
        assert!((len - exact).abs() < 1e-12, "({a},{b}): {len} vs {exact}");
        assert_eq!(path[0], v(0, 0));
        assert_eq!(*path.last().unwrap(), v(a, b));
        let walked: f64 = path
            .windows(2)
            .map(|w| {
                assert!(t.are_adjacent(w[0], w[1]));
                (m.vertices[w[0] as usize] - m.vertices[w[1] as usize]).norm()
            })
            .sum();
        assert!((walked - len).abs() < 1e-12);
    }
    // Against the diagonals: no diagonal helps, Manhattan distance.
    let (_, len) = t.shortest_path(&m.vertices, v(10, 0), v(3, 6)).unwrap();
    assert!((len - 13.0).abs() < 1e-12);
    // Unit weights count hops: max(a, b) with diagonals, a + b against them.
    let (p, hops) = t
        .shortest_path_by(v(0, 0), v(7, 3), |_, _| Some(1.0))
        .unwrap();
    assert_eq!((p.len(), hops), (8, 7.0));
    // Restricted to the bottom row and right column: an L whose corner is cut
    // by the one diagonal (9,0)-(10,1) inside the subset: 9 + sqrt 2 + 6.
    let allowed: Vec<bool> = m
        .vertices
        .iter()
        .map(|p| p.y == 0.0 || p.x == 10.0)
        .collect();
    let (p, len) = t
        .shortest_path_within(&m.vertices, &allowed, v(0, 0), v(10, 7))
        .unwrap();
    assert!((len - (15.0 + s2)).abs() < 1e-12, "{len}");
    assert!(p.iter().all(|&q| allowed[q as usize]));
    // Nothing allowed in between: unreachable.
    let allowed: Vec<bool> = m.vertices.iter().map(|p| p.x != 5.0).collect();
    assert!(t
        .shortest_path_within(&m.vertices, &allowed, v(0, 0), v(10, 0))
        .is_none());
    // Trivial path.
    assert_eq!(t.shortest_path(&m.vertices, 4, 4).unwrap(), (vec![4], 0.0));
}

#[test]
fn grid_boundary_is_one_counter_clockwise_loop() {
    let m = grid(4);
    let t = topo(&m);
    let loops = t.boundary_loops();
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].len(), 16);
    // Shoelace area of the loop: +16 for counter-clockwise seen from +z.
    let lp = &loops[0];
    let area: f64 = (0..lp.len())
        .map(|k| {
            let (a, b) = (
                m.vertices[lp[k] as usize],
                m.vertices[lp[(k + 1) % lp.len()] as usize],
            );
            0.5 * (a.x * b.y - b.x * a.y)
        })
        .sum();
    assert!((area - 16.0).abs() < 1e-12);
    assert_eq!(t.euler_characteristic(), 1);
}

#[test]
fn edge_distances_from_several_sources_are_the_nearest_known_path_length() {
    let m = grid(10);
    let t = topo(&m);
    let v = |i: usize, j: usize| (j * 11 + i) as u32;
    let s2 = 2f64.sqrt();
    let path = |(i0, j0): (usize, usize), (i, j): (usize, usize)| {
        // From the lower-left source, diagonals run up-right; from the upper-right one,
        // down-left: the same min(a, b) diagonal + |a - b| axis steps.
        let (a, b) = (i.abs_diff(i0), j.abs_diff(j0));
        a.min(b) as f64 * s2 + a.abs_diff(b) as f64
    };
    let d = t.edge_distances(&m.vertices, &[v(0, 0), v(10, 10)]);
    for j in 0..=10 {
        for i in 0..=10 {
            let want = path((0, 0), (i, j)).min(path((10, 10), (i, j)));
            assert!((d[v(i, j) as usize] - want).abs() < 1e-12, "({i},{j})");
        }
    }
    // No source in reach: infinite; out-of-range sources are ignored.
    let mut split = m.clone();
    split.vertices.push(Vector3::new(50.0, 0.0, 0.0));
    let t2 = Topology::new(split.vertices.len(), &split.faces);
    let d2 = t2.edge_distances(&split.vertices, &[v(3, 4), 9999]);
    assert_eq!(d2[v(3, 4) as usize], 0.0);
    assert!(d2[split.vertices.len() - 1].is_infinite());
}

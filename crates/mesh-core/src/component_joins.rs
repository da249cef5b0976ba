//! Joins between a mesh's connected components, so that a template made of several pieces
//! (a game character's separate limbs, head, belt, hair or props) is one graph.
//!
//! Every component but the largest is joined, at its closest vertex pair, to the nearest other
//! component; the joined groups are then treated as components and joined the same way until
//! one group remains (Borůvka's rounds on closest-pair distances). A piece that no loop crosses
//! thereby goes with the part of the body it is nearest to: the segmentation floods across the
//! joins ([`crate::segmentation`]). A mesh of one component has no joins.

use nalgebra::Vector3;

use crate::topology::Topology;

/// The join edges `[a, b]` (a vertex of each of two components) that make `topology` one
/// connected graph; empty when it already is. Deterministic: ties go to the smaller indices.
pub fn component_joins(topology: &Topology, positions: &[Vector3<f64>]) -> Vec<[u32; 2]> {
    let components = topology.connected_components();
    if components.len() <= 1 {
        return Vec::new();
    }
    let n = positions.len();
    let mut group = vec![0usize; n];
    for (c, comp) in components.iter().enumerate() {
        for &v in comp {
            group[v as usize] = c;
        }
    }
    let mut parent: Vec<usize> = (0..components.len()).collect();
    fn find(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    // Vertices sorted by x: the nearest vertex of another group is searched outward in x,
    // stopping once the x gap alone exceeds the best distance found for the group.
    let mut by_x: Vec<u32> = (0..n as u32).collect();
    by_x.sort_by(|&a, &b| positions[a as usize].x.total_cmp(&positions[b as usize].x).then(a.cmp(&b)));
    let mut rank = vec![0usize; n];
    for (r, &v) in by_x.iter().enumerate() {
        rank[v as usize] = r;
    }
    let mut joins = Vec::new();
    let mut groups = components.len();
    while groups > 1 {
        let root: Vec<usize> = (0..n).map(|v| find(&mut parent, group[v])).collect();
        let mut size = vec![0usize; components.len()];
        for &r in &root {
            size[r] += 1;
        }
        let largest = (0..size.len()).max_by(|&a, &b| size[a].cmp(&size[b]).then(b.cmp(&a))).unwrap_or(0);
        // Per group: (squared distance, vertex, other vertex) of its closest outside pair.
        let mut best: Vec<Option<(f64, u32, u32)>> = vec![None; components.len()];
        for v in 0..n {
            let g = root[v];
            if g == largest {
                continue;
            }
            let p = positions[v];
            let mut bound = best[g].map_or(f64::INFINITY, |b| b.0);
            for dir in [1i64, -1] {
                let mut r = rank[v] as i64 + dir;
                while r >= 0 && (r as usize) < n {
                    let w = by_x[r as usize] as usize;
                    let dx = positions[w].x - p.x;
                    if dx * dx > bound {
                        break;
                    }
                    if root[w] != g {
                        let d2 = (positions[w] - p).norm_squared();
                        let better = match best[g] {
                            None => true,
                            Some((b, bv, bw)) => d2 < b || (d2 == b && (v as u32, w as u32) < (bv, bw)),
                        };
                        if better {
                            best[g] = Some((d2, v as u32, w as u32));
                            bound = d2;
                        }
                    }
                    r += dir;
                }
            }
        }
        for pair in best.into_iter().flatten() {
            let (a, b) = (find(&mut parent, group[pair.1 as usize]), find(&mut parent, group[pair.2 as usize]));
            if a != b {
                parent[a.max(b)] = a.min(b);
                joins.push([pair.1, pair.2]);
                groups -= 1;
            }
        }
    }
    joins
}

/// Each vertex's neighbours across the joins (empty rows for most vertices).
pub fn join_neighbours(n_vertices: usize, joins: &[[u32; 2]]) -> Vec<Vec<u32>> {
    let mut rows = vec![Vec::new(); n_vertices];
    for &[a, b] in joins {
        rows[a as usize].push(b);
        rows[b as usize].push(a);
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::icosphere;
    use crate::TriMesh;

    /// Copies of a unit icosphere at the given centres, as one mesh.
    fn spheres(centres: &[f64]) -> TriMesh {
        let s = icosphere(1);
        let mut v = Vec::new();
        let mut f = Vec::new();
        for &c in centres {
            let base = v.len() as u32;
            v.extend(s.vertices.iter().map(|p| p + Vector3::new(c, 0.0, 0.0)));
            f.extend(s.faces.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        }
        TriMesh::new(v, f)
    }

    #[test]
    fn one_component_needs_no_join() {
        let m = spheres(&[0.0]);
        let t = Topology::new(m.vertices.len(), &m.faces);
        assert!(component_joins(&t, &m.vertices).is_empty());
    }

    #[test]
    fn spheres_in_a_row_are_joined_to_their_neighbours_at_the_facing_points() {
        // Spheres of radius 1 at x = 0, 3, 10: the joins link 0-1 and 1-2 at their facing
        // extreme vertices (x = +-xmax about each centre).
        let m = spheres(&[0.0, 3.0, 10.0]);
        let t = Topology::new(m.vertices.len(), &m.faces);
        let joins = component_joins(&t, &m.vertices);
        assert_eq!(joins.len(), 2);
        let n = icosphere(1).vertices.len() as u32;
        let mut pairs: Vec<(u32, u32)> = joins.iter().map(|j| { let (a, b) = (j[0] / n, j[1] / n); (a.min(b), a.max(b)) }).collect();
        pairs.sort();
        assert_eq!(pairs, vec![(0, 1), (1, 2)]);
        let xmax = icosphere(1).vertices.iter().map(|p| p.x).fold(f64::MIN, f64::max);
        let mut gaps: Vec<f64> = joins.iter().map(|j| (m.vertices[j[0] as usize] - m.vertices[j[1] as usize]).norm()).collect();
        gaps.sort_by(f64::total_cmp);
        assert!((gaps[0] - (3.0 - 2.0 * xmax)).abs() < 1e-9 && (gaps[1] - (7.0 - 2.0 * xmax)).abs() < 1e-9, "{gaps:?}");
        let rows = join_neighbours(m.vertices.len(), &joins);
        assert_eq!(rows.iter().map(|r| r.len()).sum::<usize>(), 4);
    }
}

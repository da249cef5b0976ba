//! Smooth part weights over the overlap bands, for merging parts by a weighted average
//! ("feathering") instead of Poisson stitching.
//!
//! Across the band a child shares with its parent, the child's weight rises from 0 on the
//! band's parent-side rim to 1 on its child-side rim, `w = 3t² − 2t³` of the relative position
//! `t = d_p / (d_p + d_c)`, with `d_p` and `d_c` the template's edge-path distances to the two
//! rims; the parent gets `1 − w`. Where the band meets a single part the weight is already
//! that part's alone, so the merged surface has no step at the band's border (a uniform
//! average jumps from 1/2 to 1 there), and the slope `dw/dt` is 0 at both rims. Weights
//! depend on the template only: they are computed once per model.

use mesh_core::topology::Topology;
use nalgebra::Vector3;

use crate::stitch::LayoutPart;

/// Per part, per vertex of the part (in `LayoutPart::vertices` order): its weight in the merged
/// position. The weights of every template vertex sum to 1 over the parts that hold it.
/// Vertices held by one part get 1; vertices of a child's band with its parent get the ramp
/// of the module doc; any other shared vertex (held by more than two parts, or by two parts
/// that are not parent and child) gets the uniform `1 / count`.
pub fn band_weights(
    template: &[Vector3<f64>],
    faces: &[[u32; 3]],
    parts: &[LayoutPart],
) -> Vec<Vec<f64>> {
    let n = template.len();
    let topo = Topology::new(n, faces);
    let mut holders: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (k, p) in parts.iter().enumerate() {
        for &v in &p.vertices {
            if let Some(h) = holders.get_mut(v as usize) {
                if h.last() != Some(&k) {
                    h.push(k);
                }
            }
        }
    }
    let mut weights: Vec<Vec<f64>> = parts
        .iter()
        .map(|p| {
            p.vertices
                .iter()
                .map(|&v| 1.0 / holders.get(v as usize).map_or(1, |h| h.len().max(1)) as f64)
                .collect()
        })
        .collect();
    for (k, p) in parts.iter().enumerate() {
        let Some(q) = p.parent.filter(|&q| q < parts.len() && q != k) else {
            continue;
        };
        let in_band = |v: usize| holders[v].len() == 2 && holders[v].contains(&q) && holders[v].contains(&k);
        let held_by = |v: usize, part: usize| holders[v].contains(&part);
        // Rims: band vertices next to a vertex of one of the two parts only.
        let (mut parent_rim, mut child_rim) = (Vec::new(), Vec::new());
        for &v in &p.vertices {
            let v = v as usize;
            if v >= n || !in_band(v) {
                continue;
            }
            let next = topo.vertex_neighbors(v as u32);
            if next.iter().any(|&w| held_by(w as usize, q) && !held_by(w as usize, k)) {
                parent_rim.push(v as u32);
            }
            if next.iter().any(|&w| held_by(w as usize, k) && !held_by(w as usize, q)) {
                child_rim.push(v as u32);
            }
        }
        if parent_rim.is_empty() || child_rim.is_empty() {
            continue;
        }
        let dp = topo.edge_distances(template, &parent_rim);
        let dc = topo.edge_distances(template, &child_rim);
        let local_q: std::collections::HashMap<u32, usize> = parts[q]
            .vertices
            .iter()
            .enumerate()
            .map(|(i, &v)| (v, i))
            .collect();
        for (i, &v) in p.vertices.iter().enumerate() {
            let u = v as usize;
            if u >= n || !in_band(u) {
                continue;
            }
            let t = ramp_position(dp[u], dc[u]);
            let w = t * t * (3.0 - 2.0 * t);
            weights[k][i] = w;
            if let Some(&j) = local_q.get(&v) {
                weights[q][j] = 1.0 - w;
            }
        }
    }
    weights
}

/// Relative position across a band from the distances to its parent-side and child-side
/// rims: 0 on the parent rim, 1 on the child rim, 1/2 where neither rim is reachable.
fn ramp_position(d_parent: f64, d_child: f64) -> f64 {
    let total = d_parent + d_child;
    if total.is_finite() && total > 0.0 {
        (d_parent / total).clamp(0.0, 1.0)
    } else if d_parent.is_finite() && !d_child.is_finite() {
        0.0
    } else if d_child.is_finite() && !d_parent.is_finite() {
        1.0
    } else {
        0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `len` × 2 quads along x: columns 0..len, two triangles per quad.
    fn strip(len: usize) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        let mut pos = Vec::new();
        for i in 0..=len {
            pos.push(Vector3::new(i as f64, 0.0, 0.0));
            pos.push(Vector3::new(i as f64, 1.0, 0.0));
        }
        let mut faces = Vec::new();
        for i in 0..len as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            faces.push([a, c, b]);
            faces.push([b, c, d]);
        }
        (pos, faces)
    }

    fn columns(from: usize, to: usize) -> Vec<u32> {
        (2 * from as u32..=2 * to as u32 + 1).collect()
    }

    #[test]
    fn weights_ramp_smoothly_across_the_band_and_sum_to_one() {
        // Parent: columns 0..=6, child: columns 4..=10, band: columns 4..=6.
        let (pos, faces) = strip(10);
        let parent = LayoutPart { parent: None, vertices: columns(0, 6) };
        let child = LayoutPart { parent: Some(0), vertices: columns(4, 10) };
        let w = band_weights(&pos, &faces, &[parent.clone(), child.clone()]);
        let child_w = |col: usize| w[1][child.vertices.iter().position(|&v| v == 2 * col as u32).unwrap()];
        let parent_w = |col: usize| w[0][parent.vertices.iter().position(|&v| v == 2 * col as u32).unwrap()];
        // Rims at columns 4 (parent side) and 6 (child side); the middle column is half way.
        assert_eq!(child_w(4), 0.0);
        assert_eq!(child_w(6), 1.0);
        assert!((child_w(5) - 0.5).abs() < 1e-12);
        assert_eq!(child_w(8), 1.0);
        assert_eq!(parent_w(2), 1.0);
        for col in 4..=6 {
            assert!((child_w(col) + parent_w(col) - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn unrelated_sharing_parts_get_the_uniform_average() {
        let (pos, faces) = strip(4);
        let a = LayoutPart { parent: None, vertices: columns(0, 3) };
        let b = LayoutPart { parent: None, vertices: columns(2, 4) };
        let w = band_weights(&pos, &faces, &[a.clone(), b]);
        let shared = a.vertices.iter().position(|&v| v == 4).unwrap();
        assert_eq!(w[0][shared], 0.5);
        assert_eq!(w[0][0], 1.0);
    }

    #[test]
    fn ramp_position_handles_unreachable_rims() {
        assert_eq!(ramp_position(0.0, 0.0), 0.5);
        assert_eq!(ramp_position(1.0, f64::INFINITY), 0.0);
        assert_eq!(ramp_position(f64::INFINITY, 1.0), 1.0);
        assert_eq!(ramp_position(1.0, 3.0), 0.25);
    }
}

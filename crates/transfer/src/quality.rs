//! Quality checks of the surface reconstruction (CVPR §6)
//! against the truth, for one predicted sequence with the target's topology:
//! * closedness: the output reuses the template's faces, so it is closed exactly where
//!   the template is (`boundary_edges` counts the template's open edges); geometric
//!   gaps would show as degenerate or stretched faces: `degenerate_faces` counts faces
//!   whose area falls below 1e-12 m²;
//! * seams: per edge, `|log(l_pred / l_truth)|` and `|θ_pred − θ_truth|` (dihedral
//!   angle), averaged over the edges inside the overlap bands (where parts meet and
//!   the stitching loops lie) and over all other edges;
//! * parts: per part and frame, signed volume (faces coned to the part centroid)
//!   and mean edge length, as ratios to the truth's.

use std::collections::HashMap;

use mesh_core::segmentation::Segmentation;
use nalgebra::Vector3;
use serde::Serialize;

/// Summary of one predicted sequence.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Quality {
    pub boundary_edges: usize,
    pub degenerate_faces: usize,
    pub seam_edge_log_ratio: f64,
    pub other_edge_log_ratio: f64,
    pub seam_dihedral_err_rad: f64,
    pub other_dihedral_err_rad: f64,
    /// Mean over parts and frames of `|V_pred / V_truth − 1|`.
    pub part_volume_err: f64,
    /// Mean over parts and frames of `|mean edge_pred / mean edge_truth − 1|`.
    pub part_edge_err: f64,
}

struct Edges {
    /// (u, v, face a, face b or usize::MAX on the boundary)
    list: Vec<(u32, u32, usize, usize)>,
}

fn edges(faces: &[[u32; 3]]) -> Edges {
    let mut map: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    for (f, t) in faces.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let key = (a.min(b), a.max(b));
            map.entry(key)
                .and_modify(|e| e.1 = f)
                .or_insert((f, usize::MAX));
        }
    }
    let mut list: Vec<_> = map
        .into_iter()
        .map(|((u, v), (a, b))| (u, v, a, b))
        .collect();
    list.sort_unstable();
    Edges { list }
}

fn normal(x: &[Vector3<f64>], t: &[u32; 3]) -> Vector3<f64> {
    let [a, b, c] = t.map(|i| x[i as usize]);
    (b - a)
        .cross(&(c - a))
        .try_normalize(1e-300)
        .unwrap_or_else(Vector3::zeros)
}

fn dihedral(x: &[Vector3<f64>], faces: &[[u32; 3]], fa: usize, fb: usize) -> f64 {
    normal(x, &faces[fa])
        .dot(&normal(x, &faces[fb]))
        .clamp(-1.0, 1.0)
        .acos()
}

/// Signed volume of a (possibly open) part: tetrahedra from its centroid.
pub fn part_volume(x: &[Vector3<f64>], faces: &[[u32; 3]]) -> f64 {
    let c = x.iter().sum::<Vector3<f64>>() / x.len().max(1) as f64;
    faces
        .iter()
        .map(|t| {
            let [a, b, d] = t.map(|i| x[i as usize] - c);
            a.dot(&b.cross(&d)) / 6.0
        })
        .sum()
}

/// Mean edge length over a face list.
pub fn mean_edge(x: &[Vector3<f64>], faces: &[[u32; 3]]) -> f64 {
    let s: f64 = faces
        .iter()
        .map(|t| {
            (0..3)
                .map(|i| (x[t[i] as usize] - x[t[(i + 1) % 3] as usize]).norm())
                .sum::<f64>()
        })
        .sum();
    s / (3 * faces.len()).max(1) as f64
}

/// Measures `pred` against `truth` (frames of the template's topology `faces`).
pub fn measure(
    faces: &[[u32; 3]],
    seg: &Segmentation,
    pred: &[Vec<Vector3<f64>>],
    truth: &[Vec<Vector3<f64>>],
) -> Quality {
    let e = edges(faces);
    let mut in_band = vec![false; seg.n_vertices];
    for p in seg.parts.iter().filter(|p| p.parent.is_some()) {
        let parent = seg.part(p.parent.as_deref().unwrap_or_default());
        if let Some(q) = parent {
            let mut inq = vec![false; seg.n_vertices];
            q.vertices.iter().for_each(|&v| inq[v as usize] = true);
            p.vertices
                .iter()
                .filter(|&&v| inq[v as usize])
                .for_each(|&v| in_band[v as usize] = true);
        }
    }
    let boundary = e.list.iter().filter(|x| x.3 == usize::MAX).count();
    let (mut sums, mut counts) = ([0.0f64; 4], [0usize; 2]);
    for (p, t) in pred.iter().zip(truth) {
        for &(u, v, fa, fb) in &e.list {
            let k = if in_band[u as usize] && in_band[v as usize] {
                0
            } else {
                1
            };
            let lp = (p[u as usize] - p[v as usize]).norm();
            let lt = (t[u as usize] - t[v as usize]).norm();
            sums[k] += (lp / lt).ln().abs();
            if fb != usize::MAX {
                sums[2 + k] += (dihedral(p, faces, fa, fb) - dihedral(t, faces, fa, fb)).abs();
            }
            counts[k] += 1;
        }
    }
    let (mut vol, mut edge, mut n) = (0.0, 0.0, 0usize);
    for part in &seg.parts {
        for (p, t) in pred.iter().zip(truth) {
            let pp: Vec<Vector3<f64>> = part.vertices.iter().map(|&v| p[v as usize]).collect();
            let tp: Vec<Vector3<f64>> = part.vertices.iter().map(|&v| t[v as usize]).collect();
            vol += (part_volume(&pp, &part.faces) / part_volume(&tp, &part.faces) - 1.0).abs();
            edge += (mean_edge(&pp, &part.faces) / mean_edge(&tp, &part.faces) - 1.0).abs();
            n += 1;
        }
    }
    let c = |i: usize| counts[i].max(1) as f64;
    Quality {
        boundary_edges: boundary,
        degenerate_faces: pred
            .iter()
            .map(|p| {
                faces
                    .iter()
                    .filter(|t| {
                        let [a, b, c] = t.map(|i| p[i as usize]);
                        0.5 * (b - a).cross(&(c - a)).norm() < 1e-12
                    })
                    .count()
            })
            .max()
            .unwrap_or(0),
        seam_edge_log_ratio: sums[0] / c(0),
        other_edge_log_ratio: sums[1] / c(1),
        seam_dihedral_err_rad: sums[2] / c(0),
        other_dihedral_err_rad: sums[3] / c(1),
        part_volume_err: vol / n.max(1) as f64,
        part_edge_err: edge / n.max(1) as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::segmentation::Part;

    /// Known answers: the truth against itself scores 0; the truth scaled by
    /// 0.9 has every edge ratio 0.9 (|ln 0.9| on seams and elsewhere), the
    /// same dihedral angles, volume ratio 0.729 and edge ratio 0.9.
    #[test]
    fn known_answers_on_a_scaled_sphere() {
        let m = mesh_core::shapes::icosphere(2);
        let n = m.n_vertices();
        let all: Vec<u32> = (0..n as u32).collect();
        let seg = Segmentation {
            n_vertices: n,
            parts: vec![
                Part {
                    name: "a".into(),
                    parent: None,
                    vertices: all.clone(),
                    faces: m.faces.clone(),
                    overlap: vec![],
                    loops: vec![],
                },
                Part {
                    name: "b".into(),
                    parent: Some("a".into()),
                    vertices: all,
                    faces: m.faces.clone(),
                    overlap: vec![],
                    loops: vec![],
                },
            ],
        };
        let truth = vec![m.vertices.clone()];
        let q = measure(&m.faces, &seg, &truth, &truth);
        assert_eq!(q.boundary_edges, 0);
        assert!(
            q.seam_edge_log_ratio.abs() < 1e-12
                && q.part_volume_err < 1e-12
                && q.other_dihedral_err_rad < 1e-12
        );
        let scaled = vec![m.vertices.iter().map(|v| 0.9 * v).collect::<Vec<_>>()];
        let q = measure(&m.faces, &seg, &scaled, &truth);
        assert!((q.seam_edge_log_ratio - 0.9f64.ln().abs()).abs() < 1e-12);
        assert!(q.seam_dihedral_err_rad < 1e-6, "{q:?}");
        assert!((q.part_volume_err - 0.271).abs() < 1e-9, "{q:?}");
        assert!((q.part_edge_err - 0.1).abs() < 1e-12);
    }
}

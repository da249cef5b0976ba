//! Maps another topology of the same body onto the body mesh: every vertex of the other mesh
//! as barycentric coordinates on a body triangle (its closest point). For `notoes.obj` the
//! vertices coincide with body vertices, so the map is exact (one weight of 1).

use nalgebra::Vector3;
use rayon::prelude::*;

/// Per target vertex: up to three (body vertex, weight) pairs, weights summing to one.
pub type Embedding = Vec<Vec<(usize, f64)>>;

/// Closest point on triangle (a, b, c) to p, as barycentric weights (Ericson, RTCD 5.1.5).
pub fn closest_barycentric(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> [f64; 3] {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    [1.0 - v - w, v, w]
}

/// Embeds `points` on the body mesh (`vertices`, `faces`): exact vertex hits within `1e-6`,
/// otherwise the closest point among the triangles around the 12 nearest body vertices.
pub fn embed(points: &[Vector3<f64>], vertices: &[Vector3<f64>], faces: &[[u32; 3]]) -> Embedding {
    let mut vf: Vec<Vec<usize>> = vec![Vec::new(); vertices.len()];
    for (f, t) in faces.iter().enumerate() {
        for &v in t {
            vf[v as usize].push(f);
        }
    }
    points
        .par_iter()
        .map(|p| {
            let mut near: Vec<(f64, usize)> = Vec::with_capacity(13);
            for (i, v) in vertices.iter().enumerate() {
                if vf[i].is_empty() {
                    continue;
                }
                let d = (v - p).norm_squared();
                if near.len() < 12 || d < near[near.len() - 1].0 {
                    let k = near.partition_point(|&(e, j)| (e, j) < (d, i));
                    near.insert(k, (d, i));
                    near.truncate(12);
                }
            }
            if near[0].0 < 1e-12 {
                return vec![(near[0].1, 1.0)];
            }
            let mut best = (f64::INFINITY, vec![(near[0].1, 1.0)]);
            for &(_, i) in &near {
                for &f in &vf[i] {
                    let t = faces[f];
                    let [a, b, c] = t.map(|k| vertices[k as usize]);
                    let w = closest_barycentric(p, &a, &b, &c);
                    let q = a * w[0] + b * w[1] + c * w[2];
                    let d = (q - p).norm_squared();
                    if d < best.0 {
                        best = (
                            d,
                            (0..3)
                                .map(|k| (t[k] as usize, w[k]))
                                .filter(|e| e.1 > 0.0)
                                .collect(),
                        );
                    }
                }
            }
            best.1
        })
        .collect()
}

/// Applies an embedding to per-body-vertex values.
pub fn apply(e: &Embedding, values: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    e.iter()
        .map(|row| row.iter().map(|&(i, w)| values[i] * w).sum())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_points_on_a_triangle() {
        let (a, b, c) = (Vector3::zeros(), Vector3::x(), Vector3::y());
        let w = closest_barycentric(&Vector3::new(0.25, 0.25, 3.0), &a, &b, &c);
        assert!(
            (w[0] - 0.5).abs() < 1e-12
                && (w[1] - 0.25).abs() < 1e-12
                && (w[2] - 0.25).abs() < 1e-12
        );
        assert_eq!(
            closest_barycentric(&Vector3::new(-1.0, -1.0, 0.0), &a, &b, &c),
            [1.0, 0.0, 0.0]
        );
        let w = closest_barycentric(&Vector3::new(1.0, 1.0, 0.0), &a, &b, &c);
        assert!((w[1] - 0.5).abs() < 1e-12 && (w[2] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn embedding_reproduces_points_on_the_mesh() {
        let v = vec![
            Vector3::zeros(),
            Vector3::x(),
            Vector3::y(),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        let f = vec![[0, 1, 2], [1, 3, 2]];
        let pts = vec![
            Vector3::new(0.2, 0.3, 0.0),
            Vector3::new(0.9, 0.8, 0.0),
            Vector3::x(),
        ];
        let e = embed(&pts, &v, &f);
        assert_eq!(e[2], vec![(1, 1.0)]);
        for (p, q) in pts.iter().zip(apply(&e, &v)) {
            assert!((p - q).norm() < 1e-12);
        }
    }
}

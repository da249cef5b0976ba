//! Laplacian, gradient operator, Poisson solver and polar decomposition against analytic truth.
mod common;
use common::*;
use faer::sparse::SparseColMat;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;
use surface::deformation_gradient::{triangle_deformation, GradientOperator, StiffnessPattern};
use surface::laplacian::{cotangent_laplacian, lumped_mass};
use surface::poisson::{reconstruct, PoissonSolver};
use surface::polar::{polar, triangle_rotation};

fn matvec(a: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let (cp, ri, val) = (a.symbolic().col_ptr(), a.symbolic().row_idx(), a.val());
    let mut y = vec![0.0; a.nrows()];
    for j in 0..a.ncols() {
        for p in cp[j]..cp[j + 1] {
            y[ri[p]] += val[p] * x[j];
        }
    }
    y
}

fn entries(a: &SparseColMat<usize, f64>) -> HashMap<(usize, usize), f64> {
    let (cp, ri, val) = (a.symbolic().col_ptr(), a.symbolic().row_idx(), a.val());
    let mut m = HashMap::new();
    for j in 0..a.ncols() {
        for p in cp[j]..cp[j + 1] {
            *m.entry((ri[p], j)).or_insert(0.0) += val[p];
        }
    }
    m
}

#[test]
fn laplacian_of_linear_function_vanishes_inside_flat_mesh() {
    let (v, f, interior) = grid(12, 9, 0.6);
    let l = cotangent_laplacian(&v, &f);
    let lin: Vec<f64> = v.iter().map(|p| 2.0 * p.x - 3.0 * p.y + 1.0).collect();
    let y = matvec(&l, &lin);
    let mut boundary = 0.0;
    for (i, yi) in y.iter().enumerate() {
        if interior[i] {
            assert!(yi.abs() < 1e-12, "interior vertex {i}: {yi}");
        } else {
            boundary += yi.abs();
        }
    }
    // Not trivially zero: the boundary rows carry the flux of the linear function.
    assert!(boundary > 1.0, "{boundary}");
    // Constants are in the kernel everywhere, and the Dirichlet energy of x is the area.
    assert!(matvec(&l, &vec![1.0; v.len()])
        .iter()
        .all(|y| y.abs() < 1e-12));
    let x: Vec<f64> = v.iter().map(|p| p.x).collect();
    let energy: f64 = matvec(&l, &x).iter().zip(&x).map(|(a, b)| a * b).sum();
    assert!((energy - 1.0).abs() < 1e-12, "{energy}");
    let mass: f64 = lumped_mass(&v, &f).iter().sum();
    assert!((mass - 1.0).abs() < 1e-12);
}

#[test]
fn gradient_operator_matches_cotangent_formula() {
    let (mut v, f) = tube(9, 6, 1.0, 0.4, true);
    v.iter_mut()
        .enumerate()
        .for_each(|(i, p)| p.x += 0.1 * hash01(i as u64));
    let op = GradientOperator::new(&v, &f);
    let (k, l) = (
        entries(&op.stiffness()),
        entries(&cotangent_laplacian(&v, &f)),
    );
    for (key, val) in &l {
        assert!(
            (k.get(key).copied().unwrap_or(0.0) - val).abs() < 1e-12,
            "{key:?}"
        );
    }
    // The reusable pattern refills to the same matrix, also for a second geometry.
    let mut pattern = StiffnessPattern::new(v.len(), &f);
    for geometry in [v.clone(), bend(&v, 0.5, 1.0, 0.8)] {
        let o = GradientOperator::new(&geometry, &f);
        let (a, b) = (entries(pattern.fill(&o)), entries(&o.stiffness()));
        assert!(b.iter().all(|(key, val)| (a[key] - val).abs() < 1e-12));
    }
    // Gᵀ A G through the explicit sparse G.
    let g = entries(&op.matrix());
    let mut gtag: HashMap<(usize, usize), f64> = HashMap::new();
    let mut rows: HashMap<usize, Vec<(usize, f64)>> = HashMap::new();
    for (&(r, c), &x) in &g {
        rows.entry(r).or_default().push((c, x));
    }
    for (r, cols) in &rows {
        let a = op.areas()[r / 3];
        for &(i, x) in cols {
            for &(j, y) in cols {
                *gtag.entry((i, j)).or_insert(0.0) += a * x * y;
            }
        }
    }
    for (key, val) in &gtag {
        assert!(
            (l.get(key).copied().unwrap_or(0.0) - val).abs() < 1e-12,
            "{key:?}"
        );
    }
}

#[test]
fn gradient_of_positions_maps_edges_and_kills_normal() {
    let (v, f) = tube(7, 4, 1.0, 0.5, false);
    let op = GradientOperator::new(&v, &f);
    let moved: Vec<Vector3<f64>> = v
        .iter()
        .map(|p| rot([1.0, 2.0, 0.5], 0.7) * p * 1.3)
        .collect();
    let j = op.gradient(&moved);
    for (fi, t) in f.iter().enumerate() {
        let [a, b, c] = t.map(|i| v[i as usize]);
        let n = (b - a).cross(&(c - a)).normalize();
        let e = b - a;
        let e2 = moved[t[1] as usize] - moved[t[0] as usize];
        assert!((j[fi] * e - e2).norm() < 1e-12);
        assert!((j[fi] * n).norm() < 1e-12);
    }
}

#[test]
fn deformation_gradient_of_similarity_is_the_similarity() {
    let t = [
        Vector3::new(0.1, 0.2, 0.3),
        Vector3::new(1.0, 0.1, -0.2),
        Vector3::new(0.3, 0.9, 0.4),
    ];
    let (r, s, off) = (
        rot([0.3, -1.0, 0.2], 1.1),
        0.8,
        Vector3::new(3.0, -1.0, 2.0),
    );
    let d = triangle_deformation(&t, &t.map(|p| s * r * p + off)).unwrap();
    assert!((d - s * r).norm() < 1e-12);
    let flat = [Vector3::zeros(), Vector3::x(), 2.0 * Vector3::x()];
    assert!(triangle_deformation(&flat, &t).is_none());
}

#[test]
fn poisson_reproduces_mesh_from_its_own_gradients() {
    let (mut v, f) = tube(24, 20, 1.0, 0.25, true);
    v.iter_mut().enumerate().for_each(|(i, p)| {
        *p += 0.05
            * Vector3::new(
                hash01(3 * i as u64),
                hash01(3 * i as u64 + 1),
                hash01(3 * i as u64 + 2),
            )
    });
    let op = GradientOperator::new(&v, &f);
    let x = reconstruct(&op, &op.gradient(&v), &[5], &[v[5]]).unwrap();
    assert!(max_dist(&x, &v) < 1e-10, "{}", max_dist(&x, &v));

    // A different pose of the same topology, gradients taken on the first geometry.
    let target = bend(&v, 1.5, 1.0, 1.2);
    let j = op.gradient(&target);
    let mut solver = PoissonSolver::new(&op.stiffness(), &[0]).unwrap();
    let y = solver.solve(&op.divergence(&j), &[target[0]]).unwrap();
    assert!(max_dist(&y, &target) < 1e-10, "{}", max_dist(&y, &target));
    assert_eq!(solver.jitter(), 0.0);
    // Same pattern, other fixed set: symbolic factorisation reused, answer unchanged.
    let fixed = [3usize, 100, 200];
    solver.refactor(&op.stiffness(), &fixed).unwrap();
    let y2 = solver
        .solve(&op.divergence(&j), &fixed.map(|i| target[i]))
        .unwrap();
    assert!(max_dist(&y2, &target) < 1e-10);
    // Dirichlet values are honoured exactly when they disagree with the gradients.
    let shifted = [
        target[3] + Vector3::new(0.0, 0.0, 0.5),
        target[100],
        target[200],
    ];
    let y3 = solver.solve(&op.divergence(&j), &shifted).unwrap();
    assert!((y3[3] - shifted[0]).norm() < 1e-12 && max_dist(&y3, &target) > 0.1);
}

#[test]
fn poisson_without_anchor_is_refused() {
    let (v, f) = tube(8, 5, 1.0, 0.5, true);
    let op = GradientOperator::new(&v, &f);
    let e = PoissonSolver::new(&op.stiffness(), &[])
        .err()
        .expect("singular system accepted");
    assert!(e.to_string().contains("no fixed vertex"), "{e}");
    // Two components, one anchored: still refused.
    let mut f2 = f.clone();
    let n = v.len() as u32;
    f2.extend(f.iter().map(|t| t.map(|i| i + n)));
    let v2: Vec<_> = v.iter().chain(v.iter()).map(|p| p + Vector3::x()).collect();
    let op2 = GradientOperator::new(&v2, &f2);
    assert!(PoissonSolver::new(&op2.stiffness(), &[0]).is_err());
    assert!(PoissonSolver::new(&op2.stiffness(), &[0, n as usize]).is_ok());
    assert!(PoissonSolver::new(&op.stiffness(), &[v.len()]).is_err());
}

#[test]
fn polar_recovers_rotation_and_stretch() {
    for k in 0..20u64 {
        let r = rot(
            [
                hash01(k) - 0.5,
                hash01(k + 100) - 0.5,
                hash01(k + 200) - 0.5,
            ],
            3.0 * hash01(k + 300),
        );
        let b = Matrix3::from_fn(|i, j| hash01(k * 9 + (3 * i + j) as u64 + 1000) - 0.5);
        let s = b * b.transpose() + Matrix3::identity() * 0.1;
        let (r2, s2) = polar(&(r * s));
        assert!((r2 - r).norm() < 1e-10, "{k}");
        assert!((s2 - s).norm() < 1e-10, "{k}");
    }
}

#[test]
fn polar_handles_reflections() {
    let (r, s) = polar(&Matrix3::from_diagonal(&Vector3::new(2.0, 3.0, -0.5)));
    assert!((r - Matrix3::identity()).norm() < 1e-12);
    assert!((s - Matrix3::from_diagonal(&Vector3::new(2.0, 3.0, -0.5))).norm() < 1e-12);
    for k in 0..10u64 {
        let q = rot([hash01(k), 1.0, hash01(k + 7)], 2.0 * hash01(k + 11));
        let a = q
            * Matrix3::from_diagonal(&Vector3::new(1.5, 1.0, -0.3))
            * rot([1.0, hash01(k + 3), 0.0], 0.4);
        let (r, s) = polar(&a);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
        assert!((r * s - a).norm() < 1e-12 && (s - s.transpose()).norm() < 1e-12);
        // Closest rotation: no sampled rotation is nearer to A.
        let best = (a - r).norm();
        for m in 0..300u64 {
            let c = rot(
                [hash01(m) - 0.5, hash01(m + 1) - 0.5, hash01(m + 2) - 0.5],
                3.14 * hash01(m + 3),
            );
            assert!((a - c).norm() >= best - 1e-12);
        }
    }
}

#[test]
fn closed_form_triangle_rotation_equals_svd_polar() {
    let tri = |k: u64| {
        [0, 1, 2].map(|i| {
            Vector3::new(
                hash01(k * 9 + 3 * i),
                hash01(k * 9 + 3 * i + 1),
                hash01(k * 9 + 3 * i + 2),
            )
        })
    };
    let mut flipped = 0;
    for k in 0..500u64 {
        let (a, b) = (tri(k), tri(k + 1000));
        let want = polar(&triangle_deformation(&a, &b).unwrap()).0;
        let got = triangle_rotation(&a, &b).unwrap();
        assert!((got - want).norm() < 1e-9, "{k}: {}", (got - want).norm());
        let n = |t: &[Vector3<f64>; 3]| (t[1] - t[0]).cross(&(t[2] - t[0]));
        flipped += (n(&a).dot(&n(&b)) < 0.0) as usize;
    }
    assert!(
        flipped > 0,
        "triangles whose normal turned over are covered"
    );
    let flat = [Vector3::zeros(), Vector3::x(), 2.0 * Vector3::x()];
    assert!(triangle_rotation(&flat, &tri(1)).is_none());
}

#[test]
fn blend_decomposition_equals_the_svd_polar_of_every_face() {
    // A tube bent and stretched non-uniformly: every face has its own rotation and stretch.
    let (rest, faces) = tube(12, 10, 1.0, 0.25, true);
    let pose: Vec<Vector3<f64>> = rest
        .iter()
        .map(|p| {
            let a = 0.8 * p.y;
            Vector3::new(p.x * a.cos() * (1.0 + 0.3 * p.z), p.x * a.sin() + 0.2 * p.y, 1.4 * p.z)
        })
        .collect();
    let blender = surface::blend::Blender::new(rest.clone(), faces.clone()).unwrap();
    let g = blender.decompose(&pose).unwrap();
    for (f, face) in faces.iter().enumerate() {
        let (a, b) = (face.map(|i| rest[i as usize]), face.map(|i| pose[i as usize]));
        let d = triangle_deformation(&a, &b).unwrap();
        let (r, s) = polar(&d);
        let got_r = g.rotations[f].to_rotation_matrix().into_inner();
        assert!((got_r - r).norm() < 1e-9, "face {f}: rotation off by {}", (got_r - r).norm());
        assert!((g.stretches[f] - s).norm() < 1e-9, "face {f}: stretch off by {}", (g.stretches[f] - s).norm());
        assert_eq!(g.stretches[f], g.stretches[f].transpose());
        assert!((got_r * g.stretches[f] - d).norm() < 1e-9 * d.norm());
    }
}

#[test]
fn supernodal_poisson_equals_the_default_factorisation() {
    use surface::poisson::Factorisation;
    let (v, f) = tube(24, 20, 1.0, 0.25, true);
    let op = GradientOperator::new(&v, &f);
    let target = bend(&v, 1.5, 1.0, 1.2);
    let rhs = op.divergence(&op.gradient(&target));
    let mut auto = PoissonSolver::new(&op.stiffness(), &[0]).unwrap();
    let mut sn =
        PoissonSolver::with_factorisation(&op.stiffness(), &[0], Factorisation::Supernodal)
            .unwrap();
    assert_eq!(sn.factorisation(), Factorisation::Supernodal);
    for fixed in [vec![0usize], vec![3, 100, 200], vec![7, 8, 9, 300]] {
        auto.refactor(&op.stiffness(), &fixed).unwrap();
        sn.refactor(&op.stiffness(), &fixed).unwrap();
        // Dirichlet values off the target, so that the solution is not the target itself.
        let values: Vec<Vector3<f64>> =
            fixed.iter().map(|&i| target[i] + Vector3::new(0.0, 0.1, 0.0)).collect();
        let a = auto.solve(&rhs, &values).unwrap();
        let b = sn.solve(&rhs, &values).unwrap();
        let d = max_dist(&a, &b);
        assert!(d < 1e-12, "fixed {fixed:?}: {d}");
        assert!((b[fixed[0]] - values[0]).norm() < 1e-12);
    }
    assert_eq!(sn.factorisation(), Factorisation::Supernodal);
}

#[test]
fn a_mesh_of_several_parts_blends_each_part_as_it_would_alone() {
    // Two tubes side by side (a body and its separate eye or jacket) and a vertex in no face.
    let (v1, f1) = tube(12, 10, 1.0, 0.25, true);
    let n1 = v1.len() as u32;
    let (v2, f2) = tube(8, 6, 0.5, 0.1, true);
    let mut rest: Vec<Vector3<f64>> = v1.clone();
    rest.extend(v2.iter().map(|p| p + Vector3::new(3.0, 0.0, 0.0)));
    rest.push(Vector3::new(-2.0, 0.0, 0.0));
    let mut faces = f1.clone();
    faces.extend(f2.iter().map(|f| f.map(|i| i + n1)));
    let pose = |s: f64| -> Vec<Vector3<f64>> {
        rest.iter()
            .map(|p| {
                let a = s * p.y;
                Vector3::new(p.x * a.cos() + 0.3 * s, p.x * a.sin() + p.y, (1.0 + 0.2 * s) * p.z)
            })
            .collect()
    };
    let (a, b) = (pose(0.4), pose(1.3));
    let whole = surface::blend::Blender::new(rest.clone(), faces.clone()).unwrap();
    assert!(max_dist(&whole.blend(&a, &b, 0.0).unwrap(), &a) < 1e-9);
    assert!(max_dist(&whole.blend(&a, &b, 1.0).unwrap(), &b) < 1e-9);
    let mid = whole.blend(&a, &b, 0.35).unwrap();
    // Each tube alone, through a blender of its own mesh.
    let n2 = v2.len();
    for (range, f) in [(0..n1 as usize, f1.clone()), (n1 as usize..n1 as usize + n2, f2.clone())] {
        let part = |m: &[Vector3<f64>]| m[range.clone()].to_vec();
        let alone = surface::blend::Blender::new(part(&rest), f).unwrap();
        let want = alone.blend(&part(&a), &part(&b), 0.35).unwrap();
        let d = max_dist(&part(&mid), &want);
        assert!(d < 1e-9, "part {range:?}: {d} from its blend alone");
    }
    // The loose vertex follows the linear blend.
    let last = rest.len() - 1;
    assert!((mid[last] - (a[last] * 0.65 + b[last] * 0.35)).norm() < 1e-12);
}

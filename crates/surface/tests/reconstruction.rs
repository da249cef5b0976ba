//! correct (§6.1), optimal boundary and stitch (§6.2), blend: known answers on synthetic meshes.
mod common;
use common::*;
use nalgebra::Vector3;
use surface::blend::{linear_blend, Blender};
use surface::correct::{distance_weights, Corrector};
use surface::optimal_boundary::optimal_loop;
use surface::stitch::{LayoutPart, PartLayout, Stitcher};

/// A flat sheet of width 2 and height 1 rolled with curvature `kappa` (an isometric family).
fn rolled_sheet(kappa: f64) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let (g, f, _) = grid(16, 8, 0.0);
    let v = g
        .iter()
        .map(|p| {
            let u = 2.0 * p.x - 1.0;
            if kappa.abs() < 1e-12 {
                Vector3::new(u, p.y, 0.0)
            } else {
                Vector3::new(
                    (kappa * u).sin() / kappa,
                    p.y,
                    (1.0 - (kappa * u).cos()) / kappa,
                )
            }
        })
        .collect();
    (v, f)
}

fn mean_edge_ratio(x: &[Vector3<f64>], reference: &[Vector3<f64>], f: &[[u32; 3]]) -> (f64, f64) {
    let (a, b) = (edge_lengths(x, f), edge_lengths(reference, f));
    let r: Vec<f64> = a.iter().zip(&b).map(|(p, q)| p / q).collect();
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let worst = r.iter().map(|x| (x - 1.0).abs()).fold(0.0, f64::max);
    (mean, worst)
}

#[test]
fn weights_decrease_with_distance_and_exact_match_wins() {
    let w = distance_weights(&[1.0, 2.0, 4.0], 1e-12);
    assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15 && w[0] > w[1] && w[1] > w[2]);
    assert!((w[0] / w[1] - 2.0).abs() < 1e-12);
    assert_eq!(distance_weights(&[0.0, 2.0], 1e-12), vec![1.0, 0.0]);
}

#[test]
fn correct_restores_size_of_shrunk_rotated_prediction() {
    let kappas = [0.0, 0.4, 0.8, 1.2, 1.6, 2.0];
    let f = rolled_sheet(0.0).1;
    let training: Vec<_> = kappas.iter().map(|&k| rolled_sheet(k).0).collect();
    let corrector = Corrector::new(f.clone(), training.clone()).unwrap();
    let truth = &training[3];
    let r = rot([0.2, 1.0, 0.3], 0.5);
    let c = surface::centroid(truth);
    let prediction: Vec<_> = truth
        .iter()
        .map(|p| r * ((p - c) * 0.9) + c + Vector3::new(0.1, 0.0, 0.0))
        .collect();
    let (m0, _) = mean_edge_ratio(&prediction, truth, &f);
    assert!((m0 - 0.9).abs() < 1e-9);
    for m in [1, 3] {
        let out = corrector.correct(&prediction, m).unwrap();
        let (mean, worst) = mean_edge_ratio(&out, truth, &f);
        eprintln!("correct M={m}: mean edge ratio {mean:.5}, worst {worst:.5}");
        assert!((mean - 1.0).abs() < 0.01, "M={m}: mean edge ratio {mean}");
        assert!(worst < 0.03, "M={m}: worst edge ratio error {worst}");
        // The shape follows the prediction: rigidly aligned to the truth rotated by r.
        let want: Vec<_> = truth
            .iter()
            .map(|p| r * (p - c) + surface::centroid(&prediction))
            .collect();
        assert!(
            max_dist(&out, &want) < 0.05,
            "M={m}: {}",
            max_dist(&out, &want)
        );
        assert!((surface::centroid(&out) - surface::centroid(&prediction)).norm() < 1e-12);
    }
    // An exact training mesh is returned unchanged.
    let same = corrector.correct(&training[2], 3).unwrap();
    assert!(max_dist(&same, &training[2]) < 1e-10);
}

#[test]
fn correct_rejects_bad_input() {
    let (v, f) = rolled_sheet(0.5);
    assert!(Corrector::new(f.clone(), vec![]).is_err());
    assert!(Corrector::new(vec![[0, 1, 9999]], vec![v.clone()]).is_err());
    let c = Corrector::new(f, vec![v.clone()]).unwrap();
    assert!(c.correct(&v[1..], 1).is_err());
    let mut nan = v.clone();
    nan[3].x = f64::NAN;
    assert!(c
        .correct(&nan, 1)
        .unwrap_err()
        .to_string()
        .contains("vertex 3"));
}

/// Tube band of `rings` rings; vertices of `ring` have zero discrepancy, all others positive.
#[test]
fn optimal_loop_finds_the_zero_discrepancy_ring() {
    let (around, rings) = (16, 9);
    let (mut v, f) = tube(around, rings, 1.0, 0.2, false);
    v.iter_mut()
        .enumerate()
        .for_each(|(i, p)| p.z += 0.05 * hash01(i as u64));
    for target in [0, 3, 5, 8] {
        let cost: Vec<f64> = (0..v.len())
            .map(|i| {
                if i / around == target {
                    0.0
                } else {
                    0.2 + hash01(i as u64 + 77)
                }
            })
            .collect();
        let l = optimal_loop(&v, &f, &cost).unwrap();
        let mut got = l.vertices.clone();
        got.sort_unstable();
        let want: Vec<usize> = (target * around..(target + 1) * around).collect();
        assert_eq!(got, want, "ring {target}");
    }
    // A tilted loop (rising by diagonals, falling by vertical steps) with zero cost.
    let mut cheap = Vec::new();
    let mut k = 3;
    for j in 0..around {
        cheap.push(k * around + j);
        if (1..4).contains(&j) {
            k += 1;
        } else if (9..12).contains(&j) {
            k -= 1;
            cheap.push(k * around + j);
        }
    }
    let cost: Vec<f64> = (0..v.len())
        .map(|i| if cheap.contains(&i) { 0.0 } else { 1.0 })
        .collect();
    let l = optimal_loop(&v, &f, &cost).unwrap();
    let mut got = l.vertices.clone();
    got.sort_unstable();
    cheap.sort_unstable();
    assert_eq!(got, cheap);
    // Not a cylinder: a disc.
    let (g, gf, _) = grid(4, 4, 0.0);
    assert!(optimal_loop(&g, &gf, &vec![1.0; g.len()]).is_err());
}

fn halves(
    around: usize,
    rings: usize,
    lo: usize,
    hi: usize,
) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>, Vec<LayoutPart>) {
    let (v, f) = tube(around, rings, 1.0, 0.2, true);
    let (bot, top) = ((rings * around) as u32, (rings * around + 1) as u32);
    let ring = |a: usize, b: usize| (a * around..(b + 1) * around).map(|i| i as u32);
    let root: Vec<u32> = ring(0, hi).chain([bot]).collect();
    let child: Vec<u32> = ring(lo, rings - 1).chain([top]).collect();
    (
        v,
        f,
        vec![
            LayoutPart {
                vertices: root,
                parent: None,
            },
            LayoutPart {
                vertices: child,
                parent: Some(0),
            },
        ],
    )
}

#[test]
fn stitch_puts_rigidly_moved_half_back() {
    let (mut v, f, parts) = halves(20, 30, 10, 16);
    v = bend(&v, 2.0, 1.0, 1.0);
    let layout = PartLayout::new(v.len(), f.clone(), parts.clone()).unwrap();
    let mut stitcher = Stitcher::new(layout);
    let r = rot([1.0, 0.3, -0.2], 0.8);
    let t = Vector3::new(5.0, -2.0, 1.0);
    let pos: Vec<Vec<Vector3<f64>>> = vec![
        parts[0].vertices.iter().map(|&i| v[i as usize]).collect(),
        parts[1]
            .vertices
            .iter()
            .map(|&i| r * v[i as usize] + t)
            .collect(),
    ];
    let out = stitcher.stitch(&pos).unwrap();
    assert!(
        max_dist(&out.vertices, &v) < 1e-9,
        "{}",
        max_dist(&out.vertices, &v)
    );
    let lp = out.loops[1].as_ref().unwrap();
    assert!(lp.vertices.iter().all(|&i| (10 * 20..17 * 20).contains(&i)));
    // Second frame reuses the factorisation; a deformed child still gives a closed mesh
    // that follows the root on its side and the child on the other.
    let noisy: Vec<Vector3<f64>> = pos[1]
        .iter()
        .enumerate()
        .map(|(i, p)| p + 0.01 * Vector3::new(hash01(i as u64), 0.0, 0.0))
        .collect();
    let out2 = stitcher.stitch(&[pos[0].clone(), noisy]).unwrap();
    assert!(out2
        .vertices
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite())));
    assert!((out2.vertices[0] - v[0]).norm() < 0.02 && max_dist(&out2.vertices, &v) < 0.05);
}

#[test]
fn stitch_rejects_bad_layouts() {
    let (v, f, mut parts) = halves(12, 10, 4, 6);
    parts[1].parent = None;
    assert!(PartLayout::new(v.len(), f.clone(), parts.clone()).is_err());
    let (v, f, mut parts) = halves(12, 10, 7, 6);
    assert!(
        PartLayout::new(v.len(), f.clone(), parts.clone()).is_err(),
        "no overlap"
    );
    parts[0].vertices.push(99999);
    assert!(PartLayout::new(v.len(), f, parts).is_err());
}

#[test]
fn blend_keeps_edges_and_volume_where_linear_blend_collapses() {
    let (rest, f) = tube(24, 41, 0.5, 0.1, true);
    let bent = bend(&rest, 1.0, 0.8, 0.75 * std::f64::consts::PI); // 135 degrees
    let blender = Blender::new(rest.clone(), f.clone()).unwrap();
    for (w, want) in [(0.0, &rest), (1.0, &bent)] {
        let x = blender.blend(&rest, &bent, w).unwrap();
        assert!(max_dist(&x, want) < 1e-9, "w={w}: {}", max_dist(&x, want));
    }
    let half = blender.blend(&rest, &bent, 0.5).unwrap();
    let lin = linear_blend(&rest, &bent, 0.5);
    let (v0, v1) = (volume(&rest, &f), volume(&bent, &f));
    let vref = 0.5 * (v0 + v1);
    let (vh, vl) = (volume(&half, &f), volume(&lin, &f));
    let (eh, _) = mean_edge_ratio(&half, &rest, &f);
    let (el, _) = mean_edge_ratio(&lin, &rest, &f);
    let (e1, _) = mean_edge_ratio(&bent, &rest, &f);
    eprintln!("volume rest {v0:.4} bent {v1:.4} blend {vh:.4} linear {vl:.4}; edge ratio bent {e1:.4} blend {eh:.4} linear {el:.4}");
    assert!(
        (vh / vref - 1.0).abs() < 0.03,
        "blend volume {vh} vs {vref}"
    );
    assert!((eh - 1.0).abs() < 0.03, "blend edges {eh}");
    // The baseline collapses: both volume and edge lengths lose more than 10 %.
    assert!(vl / vref < 0.9 && el < 0.9, "linear {vl} {el}");
    // The far end turned by about half the angle: tip axis direction at 67.5 degrees.
    let top = rest.len() - 1;
    let ring = |x: &[Vector3<f64>], k: usize| surface::centroid(&x[k * 24..(k + 1) * 24]);
    let dir = (half[top] - ring(&half, 32)).normalize();
    let angle = dir.z.acos().to_degrees();
    assert!((angle - 67.5).abs() < 3.0, "tip angle {angle}");
    let seq = blender
        .blend_sequences(
            &[rest.clone(), bent.clone()],
            &[bent.clone(), rest.clone()],
            1.0,
        )
        .unwrap();
    assert!(max_dist(&seq[0], &bent) < 1e-9 && max_dist(&seq[1], &rest) < 1e-9);
}

#[test]
fn stitch_of_non_rigidly_different_parts_has_no_seam() {
    let (around, rings) = (16, 40);
    let (v, f, parts) = halves(around, rings, 16, 22);
    // The child bends from z = 3.6 (ring 18) on: in the band it agrees with the
    // root up to ring 18 and departs from it beyond.
    let child_shape = bend(&v, 3.6, 3.0, 0.4);
    let r = rot([0.3, 1.0, 0.0], 0.6);
    let child: Vec<Vector3<f64>> = parts[1]
        .vertices
        .iter()
        .map(|&i| r * child_shape[i as usize] + Vector3::new(1.0, 2.0, 3.0))
        .collect();
    let root: Vec<Vector3<f64>> = parts[0].vertices.iter().map(|&i| v[i as usize]).collect();
    let mut st = Stitcher::new(PartLayout::new(v.len(), f.clone(), parts.clone()).unwrap());
    let out = st.stitch(&[root, child.clone()]).unwrap();
    let lp = out.loops[1].as_ref().unwrap();
    // The loop is no more expensive than any ring of the band (same cost formula).
    let c = |i: usize| {
        let aligned = out.alignments[1].apply(&(r * child_shape[i] + Vector3::new(1.0, 2.0, 3.0)));
        (aligned - v[i]).norm()
    };
    let delta = 1e-3 * (16 * around..23 * around).map(c).sum::<f64>() / (7 * around) as f64;
    for k in 16..23 {
        let ring_cost: f64 = (0..around)
            .map(|j| {
                let (a, b) = (k * around + j, k * around + (j + 1) % around);
                (v[a] - v[b]).norm() * (0.5 * (c(a) + c(b)) + delta)
            })
            .sum();
        assert!(
            lp.cost <= ring_cost + 1e-12,
            "ring {k}: {ring_cost} < loop {}",
            lp.cost
        );
    }
    assert!(
        lp.vertices
            .iter()
            .all(|&i| (16 * around..20 * around).contains(&i)),
        "{:?}",
        lp.vertices
    );
    // No seam: every edge keeps the length it has in the part(s) it comes from (5 %).
    let (in_root, in_child) = (
        |i: u32| (i as usize) < 23 * around || i as usize == rings * around,
        |i: u32| (i as usize) >= 16 * around,
    );
    let len = |x: &[Vector3<f64>], a: u32, b: u32| (x[a as usize] - x[b as usize]).norm();
    let mut worst: f64 = 0.0;
    for t in &f {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let got = len(&out.vertices, a, b);
            let mut refs = vec![];
            if in_root(a) && in_root(b) {
                refs.push(len(&v, a, b));
            }
            if in_child(a) && in_child(b) {
                refs.push(len(&child_shape, a, b));
            }
            let lo = refs.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = refs.iter().cloned().fold(0.0, f64::max);
            worst = worst.max((lo / got - 1.0).max(got / hi - 1.0));
        }
    }
    assert!(worst < 0.05, "edge length off by {worst}");
    // The far end follows the (aligned) child.
    let motion = &out.alignments[1];
    let tip = rings * around + 1;
    let want = motion.apply(&(r * child_shape[tip] + Vector3::new(1.0, 2.0, 3.0)));
    assert!(
        (out.vertices[tip] - want).norm() < 0.05,
        "{}",
        (out.vertices[tip] - want).norm()
    );
}

/// A child that is its parent's shape shifted by `t` (no band alignment): the loop at the
/// parent's instantiation (weight 1) gives back the parent's mesh everywhere, at the child's
/// (weight 0) the mesh shifted by `t`, since a constant on the loop extends harmonically as
/// that constant; weight 0.5 is `stitch`.
#[test]
fn stitch_weighted_fixes_the_loop_between_parent_and_child() {
    let (v, f, parts) = halves(16, 20, 8, 12);
    let t = Vector3::new(0.03, -0.02, 0.01);
    let pos: Vec<Vec<Vector3<f64>>> = vec![
        parts[0].vertices.iter().map(|&i| v[i as usize]).collect(),
        parts[1].vertices.iter().map(|&i| v[i as usize] + t).collect(),
    ];
    let mut st = Stitcher::new(PartLayout::new(v.len(), f, parts).unwrap()).with_band_alignment(false);
    let at_parent = st.stitch_weighted(&pos, &[0.5, 1.0]).unwrap().vertices;
    assert!(max_dist(&at_parent, &v) < 1e-9, "{}", max_dist(&at_parent, &v));
    let at_child = st.stitch_weighted(&pos, &[0.5, 0.0]).unwrap().vertices;
    let shifted: Vec<Vector3<f64>> = v.iter().map(|p| p + t).collect();
    assert!(max_dist(&at_child, &shifted) < 1e-9, "{}", max_dist(&at_child, &shifted));
    let half = st.stitch_weighted(&pos, &[0.5, 0.5]).unwrap().vertices;
    assert_eq!(half, st.stitch(&pos).unwrap().vertices);
    assert!(st.stitch_weighted(&pos, &[0.5, 1.5]).is_err());
    assert!(st.stitch_weighted(&pos, &[0.5]).is_err());
}

#[test]
fn supernodal_stitch_equals_the_default_factorisation() {
    use surface::poisson::Factorisation;
    let (around, rings) = (16, 40);
    let (v, f, parts) = halves(around, rings, 16, 22);
    let layout = || PartLayout::new(v.len(), f.clone(), parts.clone()).unwrap();
    let mut auto = Stitcher::new(layout());
    let mut sn = Stitcher::new(layout()).with_factorisation(Factorisation::Supernodal);
    assert_eq!(auto.factorisation(), Factorisation::Auto);
    assert_eq!(sn.factorisation(), Factorisation::Supernodal);
    // Several frames through the same stitchers: new geometry and new loops each time.
    for (k, angle) in [0.2, 0.6, 1.1].into_iter().enumerate() {
        let child_shape = bend(&v, 3.6, 3.0, angle);
        let r = rot([0.3, 1.0, 0.1 * k as f64], angle);
        let child: Vec<Vector3<f64>> = parts[1]
            .vertices
            .iter()
            .map(|&i| r * child_shape[i as usize] + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        let root: Vec<Vector3<f64>> =
            parts[0].vertices.iter().map(|&i| v[i as usize]).collect();
        let a = auto.stitch(&[root.clone(), child.clone()]).unwrap();
        let b = sn.stitch(&[root, child]).unwrap();
        assert_eq!(a.loops, b.loops);
        // Same system, another elimination order: equal to rounding (the mesh is ~8 units).
        let d = max_dist(&a.vertices, &b.vertices);
        assert!(d < 1e-11, "frame {k}: {d}");
    }
}

/// Stitching's one-pass system: the matrix of `StiffnessPattern::fill` bit for bit, and the
/// divergence of every face's own gradient to rounding, with faces from two geometries.
#[test]
fn one_pass_stitch_system_equals_operator_assembly() {
    use surface::deformation_gradient::{GradientOperator, StiffnessPattern};
    let (v, f, _) = halves(12, 20, 8, 12);
    let bent = bend(&v, 2.0, 1.0, 0.7);
    let tri = |k: usize| f[k].map(|i| if k % 3 == 0 { bent[i as usize] } else { v[i as usize] });
    let op = GradientOperator::from_triangles(v.len(), &f, tri);
    let field: Vec<_> = (0..f.len()).map(|k| op.face_gradient(k, &tri(k))).collect();
    let want_b = op.divergence(&field);
    let mut pattern = StiffnessPattern::new(v.len(), &f);
    let want_l = pattern.fill(&op).val().to_vec();
    let mut b = Vec::new();
    let got_l = pattern.fill_with_own_field(tri, &mut b).val().to_vec();
    assert_eq!(got_l, want_l);
    let scale = want_b.iter().map(|x| x.norm()).fold(0.0, f64::max);
    assert!(scale > 0.1);
    let d = max_dist(&b, &want_b);
    assert!(d < 1e-13 * scale, "{d} against {scale}");
}

/// Refactorising in place (new values, new fixed set, matrix modified in place) solves as a
/// solver built from scratch, bit for bit, and still rejects a fixed set that leaves a part of
/// the mesh unanchored.
#[test]
fn in_place_refactorisation_equals_a_new_solver() {
    use surface::deformation_gradient::{GradientOperator, StiffnessPattern};
    use surface::poisson::{Factorisation, PoissonSolver};
    let (v, f, _) = halves(12, 20, 8, 12);
    let mut pattern = StiffnessPattern::new(v.len(), &f);
    for how in [Factorisation::Auto, Factorisation::Supernodal] {
        let mut reused: Option<PoissonSolver> = None;
        for frame in 0..3 {
            let x = bend(&v, 2.0, 1.0, 0.3 * frame as f64);
            let op = GradientOperator::new(&x, &f);
            let field = op.gradient(&x);
            let rhs = op.divergence(&field);
            let fixed: Vec<usize> = (frame * 12..frame * 12 + 12).collect();
            let values: Vec<_> = fixed.iter().map(|&i| x[i]).collect();
            let fresh =
                PoissonSolver::with_factorisation(&pattern.fill(&op).clone(), &fixed, how).unwrap();
            let want = fresh.solve(&rhs, &values).unwrap();
            let l = pattern.fill(&op);
            match reused.as_mut() {
                Some(s) => s.refactor_in_place(l, &fixed).unwrap(),
                None => reused = Some(PoissonSolver::with_factorisation(l, &fixed, how).unwrap()),
            }
            let got = reused.as_ref().unwrap().solve(&rhs, &values).unwrap();
            assert_eq!(got, want, "{how:?} frame {frame}");
            assert!(max_dist(&got, &x) < 1e-9);
        }
        // Without a fixed vertex the Laplacian is singular (constants): refused.
        let op = GradientOperator::new(&v, &f);
        let err = reused.unwrap().refactor_in_place(pattern.fill(&op), &[]);
        assert!(err.is_err());
    }
}

/// A part modelled as several pieces (a rolled sheet, a separate flat pad beside it, and a
/// vertex in no face), as game characters' parts are: each piece is corrected on its own and
/// lands where the prediction has it. The prediction is training mesh 1 with the pad moved
/// 10 cm and turned: the sheet comes back as training mesh 1, the pad as the prediction's.
#[test]
fn a_part_of_separate_pieces_is_corrected_piece_by_piece() {
    let pieces = |k: f64| {
        let (mut v, mut f) = rolled_sheet(k);
        let (pad, pad_faces, _) = grid(3, 3, 0.0);
        let base = v.len() as u32;
        v.extend(pad.iter().map(|p| p * 0.3 + Vector3::new(2.0, 0.0, 0.0)));
        f.extend(pad_faces.iter().map(|t| t.map(|i| i + base)));
        v.push(Vector3::new(-1.0, 0.5, 0.0));
        (v, f)
    };
    let f = pieces(0.0).1;
    let training: Vec<_> = [0.0, 0.8, 1.6].iter().map(|&k| pieces(k).0).collect();
    let corrector = Corrector::new(f.clone(), training.clone()).unwrap();
    let pad_start = rolled_sheet(0.0).0.len();
    let r = rot([0.0, 0.0, 1.0], 0.4);
    let mut prediction = training[1].clone();
    let n = prediction.len();
    let pad_centre = surface::centroid(&prediction[pad_start..n - 1]);
    for p in &mut prediction[pad_start..n - 1] {
        *p = r * (*p - pad_centre) + pad_centre + Vector3::new(0.0, 0.1, 0.0);
    }
    let out = corrector.correct(&prediction, 1).unwrap();
    assert!(max_dist(&out, &prediction) < 1e-9, "{}", max_dist(&out, &prediction));
}

/// One symbolic analysis shared by the solvers of several geometries of one topology gives
/// each the solution of a solver factorised from scratch on that geometry: bit for bit (the
/// same ordering and numeric steps), so certainly within 1e-12, for both factorisations.
#[test]
fn a_shared_symbolic_analysis_solves_as_a_fresh_factorisation() {
    use surface::deformation_gradient::GradientOperator;
    use surface::poisson::{Factorisation, PoissonSolver, SymbolicPoisson};
    let (v, f, _) = halves(12, 20, 8, 12);
    for how in [Factorisation::Auto, Factorisation::Supernodal] {
        let shared = SymbolicPoisson::new(&GradientOperator::new(&v, &f).stiffness(), how).unwrap();
        assert_eq!(shared.factorisation(), how);
        for frame in 0..4 {
            let x = bend(&v, 2.0, 1.0, 0.25 * frame as f64);
            let op = GradientOperator::new(&x, &f);
            let l = op.stiffness();
            let rhs = op.divergence(&op.gradient(&x));
            let fixed = [frame, 100 + frame];
            let values: Vec<_> = fixed.iter().map(|&i| x[i]).collect();
            let want = PoissonSolver::with_factorisation(&l, &fixed, how).unwrap().solve(&rhs, &values).unwrap();
            let got = shared.factorise(&l, &fixed).unwrap().solve(&rhs, &values).unwrap();
            assert!(max_dist(&got, &want) <= 1e-12 * max_dist(&want, &vec![Vector3::zeros(); want.len()]));
            assert_eq!(got, want, "{how:?} frame {frame}");
        }
        // A matrix of another pattern is refused, not factorised on the wrong analysis.
        let (v2, f2, _) = halves(10, 20, 8, 12);
        let other = GradientOperator::new(&v2, &f2).stiffness();
        assert!(shared.factorise(&other, &[0]).is_err());
    }
}

/// The correction of many predictions with their nearest meshes found together (blocked
/// products, [`Corrector::nearest_all`]) is the correction of each alone, bit for bit, and its
/// factorisations, made once per training mesh on one shared analysis, are reused: a second
/// pass gives the same meshes.
#[test]
fn correcting_a_sequence_equals_correcting_each_frame_alone() {
    let kappas: Vec<f64> = (0..40).map(|k| 0.05 * k as f64).collect();
    let f = rolled_sheet(0.0).1;
    let training: Vec<_> = kappas.iter().map(|&k| rolled_sheet(k).0).collect();
    let corrector = Corrector::new(f, training.clone()).unwrap();
    let predictions: Vec<Vec<Vector3<f64>>> = (0..45)
        .map(|i| {
            let (k, s) = (0.043 * i as f64, 0.9 + 0.002 * i as f64);
            let x = rolled_sheet(k).0;
            x.iter().map(|p| p * s).collect()
        })
        .chain([training[7].clone()])
        .collect();
    for m in [1, 3] {
        let near = corrector.nearest_all(&predictions, m);
        for (p, near) in predictions.iter().zip(&near) {
            assert_eq!(near, &corrector.nearest(p, m));
            let want = corrector.correct(p, m).unwrap();
            assert_eq!(corrector.correct_with(p, near).unwrap(), want);
            assert_eq!(corrector.correct_with(p, near).unwrap(), want, "cached factorisation");
        }
    }
    assert!(corrector.correct_with(&predictions[0], &[(40, 1.0)]).is_err());
}

/// A corrector whose factorisation cache holds about one training mesh corrects a sequence,
/// in parallel, to the same bits as one that keeps them all, rebuilding what it dropped.
#[test]
fn a_bounded_factorisation_cache_corrects_to_the_same_bits() {
    use rayon::prelude::*;
    let f = rolled_sheet(0.0).1;
    let training: Vec<_> = (0..30).map(|k| rolled_sheet(0.07 * k as f64).0).collect();
    let kept = Corrector::new(f.clone(), training.clone()).unwrap();
    let mut bounded = Corrector::new(f, training).unwrap();
    bounded.set_cache_limit(1);
    let predictions: Vec<Vec<Vector3<f64>>> = (0..60)
        .map(|i| rolled_sheet(0.031 * i as f64).0.iter().map(|p| p * 0.95).collect())
        .collect();
    let correct_all = |c: &Corrector| -> Vec<Vec<Vector3<f64>>> {
        let near = c.nearest_all(&predictions, 3);
        predictions.par_iter().zip(&near).map(|(p, n)| c.correct_with(p, n).unwrap()).collect()
    };
    let want = correct_all(&kept);
    let (first, again) = (correct_all(&bounded), correct_all(&bounded));
    assert_eq!(first, want);
    assert_eq!(again, want);
    let distinct = kept.factorisations();
    assert!(distinct >= 10, "the sequence uses {distinct} training meshes");
    assert!(bounded.factorisations() > distinct, "{} builds", bounded.factorisations());
    assert_eq!(correct_all(&kept), want);
    assert_eq!(kept.factorisations(), distinct, "an unbounded cache builds each mesh once");
}

/// Stitchers forked from one another stitch a sequence's frames to the same meshes as one
/// stitcher alone, bit for bit, in any order.
#[test]
fn forked_stitchers_stitch_as_one() {
    let (v, f, parts) = halves(12, 20, 8, 12);
    let frames: Vec<Vec<Vec<Vector3<f64>>>> = (0..4)
        .map(|i| {
            let x = bend(&v, 2.0, 1.0, 0.2 * i as f64);
            parts.iter().map(|p| p.vertices.iter().map(|&k| x[k as usize]).collect()).collect()
        })
        .collect();
    let mut one = Stitcher::new(PartLayout::new(v.len(), f.clone(), parts.clone()).unwrap());
    let want: Vec<_> = frames.iter().map(|fr| one.stitch(fr).unwrap().vertices).collect();
    let mut fresh = Stitcher::new(PartLayout::new(v.len(), f, parts).unwrap());
    let mut fork = fresh.fork();
    let mut late = one.fork();
    for (i, fr) in frames.iter().enumerate().rev() {
        let s = if i % 2 == 0 { &mut fork } else { &mut fresh };
        assert_eq!(s.stitch(fr).unwrap().vertices, want[i], "frame {i}");
        assert_eq!(late.stitch(fr).unwrap().vertices, want[i], "frame {i}, forked after use");
    }
}

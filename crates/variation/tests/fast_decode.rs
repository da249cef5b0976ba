//! The bulk decoding path (`Decoder::decode_average_into`, kernel-basis predictors) against
//! `Decoder::decode` with `Assembly::Average`, and multi-chain sampling determinism.

use gpdm::hmc::HmcOptions;
use gpdm::{Gpdm, GpdmConfig};
use mesh_core::rigid::RigidMotion;
use nalgebra::{DMatrix, Rotation3, Vector3};
use variation::group::PartDef;
use variation::part_data::{DisplacementScale, TORSO_EXTRA};
use variation::reconstruct::{Assembly, DecodeScratch, Decoder, FusedScratch};
use variation::sample::{sequence_variations_len, Sampler};
use variation::train::{PartModel, SequenceInfo, VariationModel};

/// A 162-vertex sphere in two overlapping parts (upper = torso, lower = child), two 30-frame
/// sequences in which the child also rotates, so that the band alignment is not trivial.
fn model() -> VariationModel {
    model_on(mesh_core::shapes::icosphere(2), -0.3, 0.1)
}

/// The same motions on another mesh: upper part `y > upper_min`, lower part `y < lower_max`.
fn model_on(mesh: mesh_core::mesh::TriMesh, upper_min: f64, lower_max: f64) -> VariationModel {
    let n = mesh.vertices.len() as u32;
    let upper: Vec<u32> = (0..n)
        .filter(|&v| mesh.vertices[v as usize].y > upper_min)
        .collect();
    let lower: Vec<u32> = (0..n)
        .filter(|&v| mesh.vertices[v as usize].y < lower_max)
        .collect();
    let pose = |t: usize, s: usize, p: &Vector3<f64>, child: bool| {
        let ph = 0.25 * t as f64 * (1.0 + 0.3 * s as f64);
        let q = p * (1.0 + 0.05 * (ph + 3.0 * p.x).sin());
        if child {
            Rotation3::from_euler_angles(0.2 * ph.sin(), 0.0, 0.1 * ph.cos()) * q
                + Vector3::new(0.01 * ph.cos(), 0.0, 0.0)
        } else {
            q
        }
    };
    let rows = |verts: &[u32], child: bool, s: usize| {
        let extra = if child { 0 } else { TORSO_EXTRA };
        DMatrix::from_fn(30, 3 * verts.len() + extra, |t, c| {
            if c < 3 * verts.len() {
                pose(t, s, &mesh.vertices[verts[c / 3] as usize], child)[c % 3]
            } else {
                let ph = 0.25 * t as f64;
                [0.02, 0.0, 0.03, 0.0, 0.05, 0.0, 1.0, 0.05, 1.0, 0.0][c - 3 * verts.len()]
                    + 0.01 * (ph + c as f64).sin()
            }
        })
    };
    let part = |name: &str, parent, vertices: &[u32], child| {
        let seqs = vec![rows(vertices, child, 0), rows(vertices, child, 1)];
        let mut gpdm = Gpdm::new(&seqs, GpdmConfig::default()).unwrap();
        gpdm.alpha = [0.01, 0.5, 1e4];
        gpdm.beta = [1.0, 1.0, 0.1, 1e3];
        PartModel {
            part: PartDef {
                name: name.into(),
                parent,
                vertices: vertices.to_vec(),
            },
            reference: vertices
                .iter()
                .map(|&v| mesh.vertices[v as usize])
                .collect(),
            gpdm,
        }
    };
    let info = |name: &str| SequenceInfo {
        name: name.into(),
        blend: None,
        blend_of: None,
        start_pose: RigidMotion::new(
            Rotation3::from_euler_angles(0.0, 0.3, 0.0),
            Vector3::new(0.5, 1.0, -0.2),
        ),
        contacts: None,
        reference: Default::default(),
    };
    let mut m = VariationModel {
        group: "test".into(),
        subject: "sphere".into(),
        fps: 25.0,
        up: Vector3::y(),
        template: mesh.vertices.clone(),
        faces: mesh.faces.clone(),
        parts: vec![
            part("upper", None, &upper, false),
            part("lower", Some(0), &lower, true),
        ],
        scale: DisplacementScale {
            translation: 2.0,
            rotation: 3.0,
        },
        sequences: vec![info("a"), info("b")],
        pair: Some((0, 1)),
        stride: 1,
        frames: 0,
        capture_limits: Default::default(),
    };
    m.frames = m.parts[0].gpdm.seq_lens[0];
    m
}

fn max_dev(fast: &[Vector3<f64>], old: &[Vec<Vector3<f64>>]) -> f64 {
    old.iter()
        .flatten()
        .zip(fast)
        .map(|(a, b)| (a - b).abs().max())
        .fold(0.0, f64::max)
}

#[test]
fn fast_average_decoding_matches_decode() {
    let m = model();
    let nv = m.template.len();
    let start = m.sequences[1].start_pose;
    // Latents: the training trajectories, and the same scaled (off the training points).
    let lat: Vec<Vec<DMatrix<f64>>> = [1.0, 1.1]
        .iter()
        .map(|f| m.latents(1).iter().map(|x| x * *f).collect())
        .collect();
    let exact = Decoder::new(&m, &mut Vec::new()).unwrap();
    let mut scratch = DecodeScratch::default();
    let mut out = vec![Vector3::zeros(); 30 * nv];
    for x in &lat {
        let old = exact
            .decode::<rand_chacha::ChaCha8Rng>(x, &start, Assembly::Average, None)
            .unwrap();
        exact
            .decode_average_into(x, &start, &mut scratch, &mut out)
            .unwrap();
        let dev = max_dev(&out, &old);
        assert!(dev < 1e-10, "exact predictors: deviation {dev}");
        // The motion is not trivial: bodies move between frames.
        assert!((old[0][0] - old[29][0]).norm() > 1e-3);
    }
    // Kernel basis: close to the exact decoding (the certified part bound is per coordinate
    // before assembly; the body stays within a small multiple of it).
    let (fast, info) = Decoder::with_pose_basis(&m, 1e-9, &mut Vec::new()).unwrap();
    assert!(info.iter().all(|&(r, b)| r >= 1 && b <= 1e-9));
    for x in &lat {
        let old = exact
            .decode::<rand_chacha::ChaCha8Rng>(x, &start, Assembly::Average, None)
            .unwrap();
        fast.decode_average_into(x, &start, &mut scratch, &mut out)
            .unwrap();
        let dev = max_dev(&out, &old);
        assert!(dev < 1e-6, "kernel basis: deviation {dev}");
    }
    // Many at once, in parallel: the same bodies as one by one.
    let got = std::sync::Mutex::new(vec![Vec::new(); lat.len()]);
    exact
        .decode_average_many(&lat, &start, |k, f| got.lock().unwrap()[k] = f.to_vec())
        .unwrap();
    for (k, x) in lat.iter().enumerate() {
        exact
            .decode_average_into(x, &start, &mut scratch, &mut out)
            .unwrap();
        assert_eq!(got.lock().unwrap()[k], out);
    }
    // Bad input: wrong part count or output size.
    assert!(exact
        .decode_average_into(&lat[0][..1], &start, &mut scratch, &mut out)
        .is_err());
    assert!(exact
        .decode_average_into(&lat[0], &start, &mut scratch, &mut out[1..])
        .is_err());
}

#[test]
fn multi_chain_variations_are_reproducible_for_any_thread_count() {
    let m = model();
    let dec = Decoder::new(&m, &mut Vec::new()).unwrap();
    let opts = HmcOptions {
        n_samples: 5,
        burn_in: 6,
        thin: 1,
        leapfrog_steps: 3,
        seed: 11,
        ..Default::default()
    };
    let run_with = |sampler: Sampler, threads: usize, opts: &HmcOptions| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| sequence_variations_len(&dec, 0, 40, sampler, 1.0, opts, 2).unwrap())
    };
    let run = |threads: usize, opts: &HmcOptions| run_with(Sampler::Hmc, threads, opts);
    let (a, stats) = run(1, &opts);
    let (b, _) = run(2, &opts);
    assert_eq!(a, b, "1 vs 2 threads");
    assert_eq!(a.len(), 5);
    assert_eq!(stats.len(), 4, "2 parts x 2 chains");
    assert!(a.iter().all(|v| v.len() == 2 && v[0].shape() == (40, 3)));
    // Samples start at the sequence's first latent point and differ from one another.
    let x1 = m.parts[0]
        .gpdm
        .sequence_latent(0)
        .unwrap()
        .row(0)
        .into_owned();
    assert!(a.iter().all(|v| v[0].row(0) == x1));
    assert!((&a[0][0] - &a[3][0]).norm() > 1e-6, "chains 0 and 1 differ");
    let (c, _) = run(2, &HmcOptions { seed: 12, ..opts });
    assert_ne!(a, c, "another seed, other samples");
    // Ancestral draws: one task per part, same answer on 1 or 2 threads, first point kept.
    let (e, estats) = run_with(Sampler::Ancestral, 1, &opts);
    assert_eq!(
        e,
        run_with(Sampler::Ancestral, 2, &opts).0,
        "ancestral: 1 vs 2 threads"
    );
    assert_eq!((e.len(), estats.len()), (5, 2));
    assert!(e.iter().all(|v| v[0].row(0) == x1));
    assert!(
        (&e[0][0] - &e[1][0]).norm() > 1e-6,
        "ancestral draws differ"
    );
    let h = HmcOptions::default();
    assert!(sequence_variations_len(&dec, 0, 1, Sampler::Hmc, 1.0, &h, 1).is_err());
    assert!(sequence_variations_len(&dec, 0, 40, Sampler::Hmc, 1.0, &h, 0).is_err());
    assert!(sequence_variations_len(&dec, 0, 1, Sampler::Ancestral, 1.0, &h, 1).is_err());
}

/// Max coordinate difference of two body sequences of the same layout.
fn max_diff(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs().max())
        .fold(0.0, f64::max)
}

#[test]
fn fused_decoding_matches_bulk_decoding() {
    let m = model();
    let nv = m.template.len();
    let start = m.sequences[1].start_pose;
    let lat: Vec<Vec<DMatrix<f64>>> = [1.0, 1.1, 0.9]
        .iter()
        .map(|f| m.latents(1).iter().map(|x| x * *f).collect())
        .collect();
    let exact = Decoder::new(&m, &mut Vec::new()).unwrap();
    let (basis, _) = Decoder::with_pose_basis(&m, 1e-9, &mut Vec::new()).unwrap();
    let mut scratch = DecodeScratch::default();
    let mut fscratch = FusedScratch::default();
    let (mut want, mut got) = (
        vec![Vector3::zeros(); 30 * nv],
        vec![Vector3::zeros(); 30 * nv],
    );
    for dec in [&exact, &basis] {
        let fused = dec.fused(Assembly::Average).unwrap();
        // One block per part, and blocks of 7 vertices (several blocks, a short last one).
        for f in [
            fused.with_block_vertices(1000),
            dec.fused(Assembly::Average).unwrap().with_block_vertices(7),
        ] {
            for x in &lat {
                dec.decode_average_into(x, &start, &mut scratch, &mut want)
                    .unwrap();
                got.fill(Vector3::new(9.0, 9.0, 9.0)); // stale values must be overwritten
                f.decode_average_into(x, &start, &mut fscratch, &mut got)
                    .unwrap();
                let d = max_diff(&got, &want);
                assert!(d < 1e-10, "fused vs bulk: {d}");
            }
        }
    }
    // Many variations: the same bodies on 1 and 2 threads, and as one by one.
    let fused = basis.fused(Assembly::Average).unwrap().with_block_vertices(16);
    let run = |threads: usize| {
        let got = std::sync::Mutex::new(vec![Vec::new(); lat.len()]);
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                fused.decode_average_many(&lat, &start, 2, |k, f| {
                    got.lock().unwrap()[k] = f.to_vec()
                })
            })
            .unwrap();
        got.into_inner().unwrap()
    };
    let one = run(1);
    assert_eq!(one, run(2), "1 vs 2 threads");
    for (k, x) in lat.iter().enumerate() {
        fused
            .decode_average_into(x, &start, &mut fscratch, &mut got)
            .unwrap();
        let d = max_diff(&one[k], &got);
        assert!(d < 1e-12, "batch vs one by one: {d}");
    }
    // A batch with a shorter variation goes one by one: same bodies.
    let short: Vec<DMatrix<f64>> = lat[2].iter().map(|x| x.rows(0, 20).into_owned()).collect();
    let mixed = vec![lat[0].clone(), short.clone()];
    let got2 = std::sync::Mutex::new(vec![Vec::new(); 2]);
    fused
        .decode_average_many(&mixed, &start, 2, |k, f| {
            got2.lock().unwrap()[k] = f.to_vec()
        })
        .unwrap();
    let got2 = got2.into_inner().unwrap();
    let mut s_out = vec![Vector3::zeros(); 20 * nv];
    fused
        .decode_average_into(&short, &start, &mut fscratch, &mut s_out)
        .unwrap();
    assert_eq!(got2[1], s_out);
    assert!(max_diff(&got2[0], &one[0]) < 1e-12);
    // Bad input: wrong part count, output size, latent dimension.
    assert!(fused
        .decode_average_into(&lat[0][..1], &start, &mut fscratch, &mut got)
        .is_err());
    assert!(fused
        .decode_average_into(&lat[0], &start, &mut fscratch, &mut got[1..])
        .is_err());
    let wide: Vec<DMatrix<f64>> = lat[0]
        .iter()
        .map(|x| x.clone().insert_column(0, 0.0))
        .collect();
    assert!(fused
        .decode_average_into(&wide, &start, &mut fscratch, &mut got)
        .is_err());
}

#[test]
fn stitched_assembly_matches_the_default_factorisation_on_any_thread_count() {
    use surface::poisson::Factorisation;
    // A tube from y = 0 to 2 in 12 rings; the parts overlap on rings 4 to 7 (a cylinder
    // band, as the stitch needs).
    let m = model_on(mesh_core::shapes::cylinder(12, 12, 0.5, 2.0), 0.7, 1.3);
    let dec = Decoder::new(&m, &mut Vec::new()).unwrap();
    let lat: Vec<DMatrix<f64>> = m.latents(1).iter().map(|x| x * 1.05).collect();
    let parts = dec
        .part_poses::<rand_chacha::ChaCha8Rng>(&lat, None)
        .unwrap();
    let on = |threads: usize, how: Factorisation| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| dec.assemble_with(&parts, Assembly::Stitch, how).unwrap())
    };
    let reference = on(1, Factorisation::Auto);
    assert_eq!(reference.len(), 30);
    // The frames differ (the stitch is not handed one frame 30 times).
    assert!(max_diff(&reference[0], &reference[29]) > 1e-3);
    // Frames stitched in parallel by pooled stitchers: the same bodies on 1 and 2 threads.
    let one = on(1, Factorisation::Supernodal);
    let two = on(2, Factorisation::Supernodal);
    assert_eq!(one, two, "1 vs 2 threads");
    // `assemble` (the stage's path) is the supernodal one.
    assert_eq!(dec.assemble(&parts, Assembly::Stitch).unwrap(), one);
    // Supernodal vs faer's default elimination: equal to rounding (a 2-unit tube).
    for (a, b) in reference.iter().zip(&one) {
        let d = max_diff(a, b);
        assert!(d < 1e-12, "{d}");
    }
}

#[test]
fn feathered_assembly_fused_matches_exact_and_differs_from_averaging_only_inside_bands() {
    let m = model();
    let nv = m.template.len();
    let start = m.sequences[1].start_pose;
    let x: Vec<DMatrix<f64>> = m.latents(1).iter().map(|x| x * 1.1).collect();
    let exact = Decoder::new(&m, &mut Vec::new()).unwrap();
    let feathered = exact
        .decode::<rand_chacha::ChaCha8Rng>(&x, &start, Assembly::Feather, None)
        .unwrap();
    let averaged = exact
        .decode::<rand_chacha::ChaCha8Rng>(&x, &start, Assembly::Average, None)
        .unwrap();
    // Fused (exact predictors, then kernel bases) against the exact decoding.
    let (basis, _) = Decoder::with_pose_basis(&m, 1e-9, &mut Vec::new()).unwrap();
    let mut fscratch = FusedScratch::default();
    let mut got = vec![Vector3::zeros(); 30 * nv];
    for (dec, tol) in [(&exact, 1e-10), (&basis, 1e-6)] {
        let f = dec.fused(Assembly::Feather).unwrap().with_block_vertices(7);
        f.decode_average_into(&x, &start, &mut fscratch, &mut got).unwrap();
        let dev = max_dev(&got, &feathered);
        assert!(dev < tol, "fused feathered vs exact: {dev}");
    }
    assert!(exact.fused(Assembly::Stitch).is_err());
    // Outside the band both merges are the part's own vertices (up to the body's alignment to
    // the template, which the band moves slightly): equal distances between them; inside the
    // band they differ (the child rotates against the torso, so the parts disagree there).
    let in_both: Vec<bool> = (0..nv as u32)
        .map(|v| m.parts.iter().all(|p| p.part.vertices.contains(&v)))
        .collect();
    let (mut outside, mut inside) = (0.0f64, 0.0f64);
    for (f, a) in feathered.iter().zip(&averaged) {
        for face in &m.faces {
            for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                let (u, v) = (face[i] as usize, face[j] as usize);
                let d = ((f[u] - f[v]).norm() - (a[u] - a[v]).norm()).abs();
                if in_both[u] || in_both[v] {
                    inside = inside.max(d);
                } else {
                    outside = outside.max(d);
                }
            }
        }
    }
    assert!(outside < 1e-9, "outside the band: {outside}");
    assert!(inside > 1e-4, "inside the band: {inside}");
}

#[test]
fn ancestral_parts_whose_draws_leave_the_data_take_hmc_chains() {
    let m = model();
    let dec = Decoder::new(&m, &mut Vec::new()).unwrap();
    let opts = HmcOptions { n_samples: 4, burn_in: 20, thin: 1, leapfrog_steps: 5, seed: 3, ..Default::default() };
    let off_points = |vars: &[Vec<DMatrix<f64>>], k: usize| -> usize {
        vars.iter()
            .map(|v| {
                dec.predictors[k]
                    .pose_variance_ratio(&v[k])
                    .unwrap()
                    .into_iter()
                    .filter(|&r| r > gpdm::hmc::OFF_DATA_VARIANCE)
                    .count()
            })
            .sum()
    };
    for kappa in [1.0, 400.0] {
        let (vars, stats) =
            sequence_variations_len(&dec, 0, 40, Sampler::Ancestral, kappa, &opts, 1).unwrap();
        for (k, st) in stats.iter().enumerate() {
            // The report counts the points off the data of what it returns, and ancestral
            // draws are kept only where none is.
            assert_eq!(st.off_data_points, off_points(&vars, k));
            assert_eq!(
                st.off_data_points > 0,
                st.max_pose_variance_ratio > gpdm::hmc::OFF_DATA_VARIANCE
            );
            assert!(st.max_pose_variance_ratio > 0.0 && st.max_pose_variance_ratio <= 1.0 + 1e-12);
            if !st.hmc_instead {
                assert_eq!(st.off_data_points, 0, "κ {kappa}, part {k}");
                assert_eq!(st.step_size, 0.0);
            } else {
                assert!(st.step_size > 0.0, "HMC statistics for the chains");
            }
        }
        if kappa == 1.0 {
            assert!(stats.iter().all(|s| !s.hmc_instead), "the model's density stays on its data");
        } else {
            assert!(stats.iter().any(|s| s.hmc_instead), "a 400x wider density leaves it");
        }
    }
}

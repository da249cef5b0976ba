//! Speed of the surface stage on a ~13k-vertex body-like mesh (goal: correct + stitch
//! >= 30 frames/s on 2 cores, factorisations reused across frames).
//!
//! Run: `OPENBLAS_NUM_THREADS=1 cargo test --release -p surface --bench surface -- --bench`
//! (`cargo test` without `-- --bench` runs each benchmark once as a smoke test).
//!
//! Mesh: `mesh_core::shapes::capsule_body(170, 64, ...)` (12 930 vertices, 25 856 faces) cut
//! along its axis into 5 overlapping parts in a tree (root in the middle, two chains of two),
//! 6-ring overlap bands; 10 smoothly deformed training meshes per part; predictions are a
//! training-like pose shrunk by 5 % with noise.

use criterion::{criterion_group, criterion_main, Criterion};
use mesh_core::shapes::capsule_body;
use nalgebra::Vector3;
use surface::correct::Corrector;
use surface::deformation_gradient::GradientOperator;
use surface::poisson::PoissonSolver;
use surface::stitch::{LayoutPart, PartLayout, Stitcher};

fn hash01(i: u64) -> f64 {
    let mut x = i
        .wrapping_mul(0x9E3779B97F4A7C15)
        .wrapping_add(0x632BE59BD9B4E019);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58476D1CE4E5B9);
    (x >> 11) as f64 / (1u64 << 53) as f64
}

fn pose(v: &[Vector3<f64>], a: f64) -> Vec<Vector3<f64>> {
    v.iter()
        .map(|p| {
            p + Vector3::new(
                a * (0.6 * p.y).sin(),
                0.0,
                0.5 * a * (0.9 * p.y).cos() * p.x,
            )
        })
        .collect()
}

struct Setup {
    faces: Vec<[u32; 3]>,
    vertices: Vec<Vector3<f64>>,
    parts: Vec<LayoutPart>,
    correctors: Vec<Corrector>,
    predictions: Vec<Vec<Vector3<f64>>>,
}

fn setup() -> Setup {
    let (mesh, layout) = capsule_body(170, 64, 1.0, 17.0);
    let rings = |a: usize, b: usize| -> Vec<u32> { (a..=b).flat_map(|k| layout.ring(k)).collect() };
    let last = layout.n_rings() - 1;
    let mut p2 = rings(0, 41);
    p2.push(layout.bottom_pole());
    let mut p4 = rings(161, last);
    p4.push(layout.top_pole());
    let parts = vec![
        LayoutPart {
            vertices: rings(70, 132),
            parent: None,
        },
        LayoutPart {
            vertices: rings(36, 75),
            parent: Some(0),
        },
        LayoutPart {
            vertices: p2,
            parent: Some(1),
        },
        LayoutPart {
            vertices: rings(127, 166),
            parent: Some(0),
        },
        LayoutPart {
            vertices: p4,
            parent: Some(3),
        },
    ];
    let mut correctors = Vec::new();
    let mut predictions = Vec::new();
    for part in &parts {
        let mut local = vec![u32::MAX; mesh.vertices.len()];
        part.vertices
            .iter()
            .enumerate()
            .for_each(|(i, &v)| local[v as usize] = i as u32);
        let faces: Vec<[u32; 3]> = mesh
            .faces
            .iter()
            .filter(|f| f.iter().all(|&v| local[v as usize] != u32::MAX))
            .map(|f| f.map(|v| local[v as usize]))
            .collect();
        let rest: Vec<Vector3<f64>> = part
            .vertices
            .iter()
            .map(|&v| mesh.vertices[v as usize])
            .collect();
        let training: Vec<_> = (0..10).map(|k| pose(&rest, 0.05 * k as f64)).collect();
        let pred: Vec<_> = pose(&rest, 0.23)
            .iter()
            .enumerate()
            .map(|(i, p)| {
                p * 0.95 + 0.002 * Vector3::new(hash01(3 * i as u64), hash01(3 * i as u64 + 1), 0.0)
            })
            .collect();
        correctors.push(Corrector::new(faces, training).unwrap());
        predictions.push(pred);
    }
    Setup {
        faces: mesh.faces.clone(),
        vertices: mesh.vertices.clone(),
        parts,
        correctors,
        predictions,
    }
}

fn benches(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let s = setup();
    eprintln!(
        "mesh: {} vertices, {} faces",
        s.vertices.len(),
        s.faces.len()
    );

    let op = GradientOperator::new(&s.vertices, &s.faces);
    let l = op.stiffness();
    let rhs = op.divergence(&op.gradient(&s.vertices));
    let mut solver = PoissonSolver::new(&l, &[0]).unwrap();
    c.bench_function("poisson_solve_3rhs_13k", |b| {
        b.iter(|| solver.solve(&rhs, &[s.vertices[0]]).unwrap())
    });
    c.bench_function("poisson_refactor_13k", |b| {
        b.iter(|| solver.refactor(&l, &[0]).unwrap())
    });
    c.bench_function("poisson_symbolic_and_factor_13k", |b| {
        b.iter(|| PoissonSolver::new(&l, &[0]).unwrap())
    });

    let mut stitcher =
        Stitcher::new(PartLayout::new(s.vertices.len(), s.faces.clone(), s.parts.clone()).unwrap());
    let frame = |stitcher: &mut Stitcher| {
        let corrected: Vec<_> = s
            .correctors
            .iter()
            .zip(&s.predictions)
            .map(|(c, p)| c.correct(p, 3).unwrap())
            .collect();
        stitcher.stitch(&corrected).unwrap()
    };
    frame(&mut stitcher); // warm-up: per-training-mesh factorisations are cached
    c.bench_function("correct_parts_13k", |b| {
        b.iter(|| {
            s.correctors
                .iter()
                .zip(&s.predictions)
                .map(|(c, p)| c.correct(p, 3).unwrap())
                .count()
        })
    });
    let corrected: Vec<_> = s
        .correctors
        .iter()
        .zip(&s.predictions)
        .map(|(c, p)| c.correct(p, 3).unwrap())
        .collect();
    c.bench_function("stitch_frame_13k", |b| {
        b.iter(|| stitcher.stitch(&corrected).unwrap())
    });
    c.bench_function("correct_and_stitch_frame_13k", |b| {
        b.iter(|| frame(&mut stitcher))
    });
    // Step 1 of the correction for a sequence: 64 predictions of the root part (4,032
    // vertices) against 600 training meshes, by blocked products and by brute force.
    let rest: Vec<Vector3<f64>> = s.parts[0].vertices.iter().map(|&v| s.vertices[v as usize]).collect();
    let many: Vec<_> = (0..600).map(|k| pose(&rest, 0.0005 * k as f64)).collect();
    let queries: Vec<_> = (0..64).map(|k| pose(&rest, 0.0047 * k as f64)).collect();
    let search = surface::nearest::MeshSearch::new(&many);
    c.bench_function("nearest_3_of_600_meshes_64_predictions_blocked", |b| {
        b.iter(|| search.nearest(&many, &queries, 3))
    });
    c.bench_function("nearest_3_of_600_meshes_64_predictions_brute_force", |b| {
        b.iter(|| {
            queries
                .iter()
                .map(|q| surface::nearest::brute_force(&many, q, 3))
                .count()
        })
    });
    drop(many);
    // Throughput over a sequence: two frames in flight, one Stitcher (factorisation) each.
    let mut other = stitcher.fork();
    frame(&mut other);
    c.bench_function("correct_and_stitch_2_frames_in_parallel_13k", |b| {
        b.iter(|| rayon::join(|| frame(&mut stitcher), || frame(&mut other)))
    });
}

criterion_group! {
    name = group;
    config = Criterion::default().sample_size(10);
    targets = benches
}
criterion_main!(group);

//! Speed goal (docs/PERFORMANCE.md): 100 variations of a 100-frame motion decoded to meshes in <= 1 s on
//! 2 cores. Decoding = pose mean (3DV eq. 12) for every latent point, assembly, displacement and
//! gravity placement; the latent trajectories are given (HMC is benchmarked in `gpdm`).
//! Bodies: icospheres of 2562 vertices (the paper's DAN meshes have 2667) and 10242 vertices,
//! as one part (the part-averaging assembly costs O(vertices) per frame either way), 200
//! training frames. Run with `OPENBLAS_NUM_THREADS=1 cargo bench -p variation`.

use criterion::{criterion_group, criterion_main, Criterion};
use gpdm::{Gpdm, GpdmConfig};
use mesh_core::rigid::RigidMotion;
use nalgebra::{DMatrix, Vector3};
use rayon::prelude::*;
use std::hint::black_box;
use variation::group::PartDef;
use variation::part_data::{DisplacementScale, TORSO_EXTRA};
use variation::reconstruct::{Assembly, Decoder};
use variation::train::{PartModel, SequenceInfo, VariationModel};

fn model(level: usize) -> VariationModel {
    let mesh = mesh_core::shapes::icosphere(level);
    let n = mesh.vertices.len();
    let seqs: Vec<DMatrix<f64>> = (0..2)
        .map(|s| {
            DMatrix::from_fn(100, 3 * n + TORSO_EXTRA, |t, c| {
                let ph = 0.2 * t as f64 * (1.0 + 0.3 * s as f64);
                if c < 3 * n {
                    let p = mesh.vertices[c / 3][c % 3];
                    p * (1.0 + 0.1 * (ph + p).sin())
                        + 1e-3 * ((t * 7919 + c * 104729) % 1000) as f64 / 1000.0
                } else {
                    [0.02, 0.0, 0.03, 0.0, 0.01, 0.0, 1.0, 0.0, 1.0, 0.0][c - 3 * n]
                        + 0.001 * ph.sin()
                }
            })
        })
        .collect();
    let gpdm = Gpdm::new(&seqs, GpdmConfig::default()).unwrap();
    let part = PartDef {
        name: "body".into(),
        parent: None,
        vertices: (0..n as u32).collect(),
    };
    let info = |name: &str| SequenceInfo {
        name: name.into(),
        blend: None,
        blend_of: None,
        start_pose: RigidMotion::identity(),
        contacts: None,
        reference: Default::default(),
    };
    let mut m = VariationModel {
        group: "bench".into(),
        subject: "sphere".into(),
        fps: 25.0,
        up: Vector3::y(),
        template: mesh.vertices.clone(),
        faces: mesh.faces.clone(),
        parts: vec![PartModel {
            part,
            reference: mesh.vertices.clone(),
            gpdm,
        }],
        scale: DisplacementScale {
            translation: 1.0,
            rotation: 1.0,
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

fn decode(c: &mut Criterion) {
    let mut group = c.benchmark_group("decode 100 variations x 100 frames");
    group.sample_size(10);
    for level in [4usize, 5] {
        let m = model(level);
        let dec = Decoder::new(&m, &mut Vec::new()).unwrap();
        let x = m.latents(0);
        let vars: Vec<Vec<DMatrix<f64>>> = (0..100)
            .map(|k| {
                x.iter()
                    .map(|l| l.map(|v| v * (1.0 + 0.001 * k as f64)))
                    .collect()
            })
            .collect();
        let start = RigidMotion::identity();
        group.bench_function(format!("{} vertices", m.template.len()), |b| {
            b.iter(|| {
                let out: Vec<_> = vars
                    .par_iter()
                    .map(|v| {
                        dec.decode::<rand_chacha::ChaCha8Rng>(v, &start, Assembly::Average, None)
                            .unwrap()
                    })
                    .collect();
                black_box(out)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);

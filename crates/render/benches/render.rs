//! Rendering speed: one 512x512 frame of a ~13k-vertex mesh, rasterization
//! and PNG encoding, on the calling thread. Goal: >= 50 frames/s on one core.
//! Run: `scripts/bench-render` (builds with `cargo test --release`, then runs
//! the criterion binary with `--bench`).

use criterion::{criterion_group, criterion_main, Criterion};
use render::{Aabb, Axis, Layer, ProjectionKind, Renderer, Style, View};

fn bench(c: &mut Criterion) {
    // Closed capsule, 80 x (122 + 2 * 20) rings + 2 poles = 12,962 vertices, 25,920 faces.
    let (m, _) = mesh_core::shapes::capsule_body(122, 80, 0.25, 1.3);
    assert!((12_000..14_000).contains(&m.vertices.len()));
    let (v, f) = (m.vertices, m.faces);
    let bbox = Aabb::from_points(&v);
    for (name, style) in [
        ("aa2x2", Style::default()),
        (
            "no_aa",
            Style {
                supersample: 1,
                ..Style::default()
            },
        ),
    ] {
        let r = Renderer::new(
            &bbox,
            &View::THREE_QUARTER,
            &Axis::PLUS_Y,
            ProjectionKind::Orthographic,
            512,
            512,
            style,
        );
        let layer = Layer {
            vertices: &v,
            faces: &f,
            colour: render::colour::palette(0),
            vertex_colours: None,
        };
        c.bench_function(&format!("render_13k_512_{name}"), |b| {
            b.iter(|| r.render(std::hint::black_box(&[layer])))
        });
        c.bench_function(&format!("render_png_13k_512_{name}"), |b| {
            b.iter(|| r.render(&[layer]).encode_png())
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = bench
}
criterion_main!(benches);

//! Synthesis speed (needs the fetched assets: scripts/fetch-assets). Goals: the tiny preset in a
//! few seconds, the default preset within 1-2 minutes on 2 cores; posing and skinning one frame
//! of the 13k-vertex body well under 10 ms. Run: `cargo bench -p synth` (release profile).

use criterion::{criterion_group, criterion_main, Criterion};
use synth::capture_set_writer::{load_motion, synthesise};
use synth::preset::{preset, subject_a};
use synth::retarget::Retarget;
use synth::subject::{BodyAssets, Subject, Topology};

fn bench(c: &mut Criterion) {
    let dir = synth::assets::asset_dir().expect("assets missing: run scripts/fetch-assets");
    let body = BodyAssets::load(&dir).unwrap();
    let a = Subject::build(&body, &subject_a(Topology::Body, 25.0)).unwrap();
    let cfg = preset("default", 0, true).unwrap();
    let m = load_motion(&dir, &cfg.train[0], cfg.max_duration).unwrap();
    let rt = Retarget::new(&a.skeleton, &m.clip, m.kind).unwrap();
    c.bench_function("pose_and_skin_13k_vertices", |b| {
        b.iter(|| a.skin(&a.pose_at(&m.clip, &rt, 0.7, 0.0)))
    });
    let tmp = tempfile::tempdir().unwrap();
    let tiny = preset("tiny", 0, true).unwrap();
    let mut g = c.benchmark_group("sets");
    g.sample_size(10);
    g.bench_function("tiny_preset", |b| {
        b.iter(|| synthesise(&tiny, &tmp.path().join("tiny"), false, &|_| {}, &|| {}).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! `pca-fit` on the `tiny` preset of `synth` (needs the synth assets, as `make test` does) with a memory budget too small to hold the training
//! rows (the motions read again pass by pass) fits the model it fits with the rows held, to
//! rounding: same means, variances, explained variance and reconstruction error, axes up to
//! sign, and the same meshes when a training motion is encoded and decoded through either.

use std::path::{Path, PathBuf};
use std::process::Command;

use capture::align::AlignedMotion;
use capture::part_pca::PcaModel;
use mesh_core::artifact::Artifact;

fn run(bin: &str, args: &[&str]) {
    let out = Command::new(bin).args(args).output().unwrap();
    assert!(out.status.success(), "{bin}: {}", String::from_utf8_lossy(&out.stderr));
}

fn report(path: &Path) -> Vec<(f64, f64)> {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| (p["explained_variance"].as_f64().unwrap(), p["reconstruction_rms_m"].as_f64().unwrap()))
        .collect()
}

#[test]
fn pca_fit_on_a_budget_too_small_to_hold_the_rows_fits_the_held_model_to_rounding() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = synth::preset::preset("tiny", 0, true).unwrap();
    synth::capture_set_writer::synthesise(&cfg, &dir.path().join("set"), false, &|_| {}, &|| {}).unwrap();
    let set = dir.path().join("set/A");
    let w = |name: &str| dir.path().join(name).display().to_string();
    let s = |p: PathBuf| p.display().to_string();
    let template = s(set.join("walk/000000.ply"));
    let subject = s(set.join("subject.json"));
    run(env!("CARGO_BIN_EXE_segment"), &[&subject, "--template", &template, "--out", &w("A.seg")]);
    let mut motions = Vec::new();
    for m in ["walk", "run", "jump"] {
        let out = w(&format!("{m}.aligned"));
        run(
            env!("CARGO_BIN_EXE_align"),
            &["--subject", &subject, "--template", &template, "--segmentation", &w("A.seg"), &s(set.join(m)), "--out", &out],
        );
        motions.push(out);
    }
    let fit = |name: &str, budget: &str| {
        let seg = w("A.seg");
        let mut args = vec!["--template", &template, "--segmentation", &seg];
        let (model, json) = (w(&format!("{name}.model")), w(&format!("{name}.json")));
        args.extend(["--memory-budget", budget, "--out", &model, "--report", &json]);
        args.extend(motions.iter().map(String::as_str));
        run(env!("CARGO_BIN_EXE_pca-fit"), &args);
        (PcaModel::load(&model).unwrap(), report(Path::new(&json)))
    };
    let (held, held_report) = fit("held", "1024");
    let (streamed, streamed_report) = fit("streamed", "1");
    assert_eq!(held.parts.len(), streamed.parts.len());
    assert!(held != streamed, "a budget of 1 MiB streams the tiny set's rows (their sums differ in the last digits)");
    for (a, b) in held.parts.iter().zip(&streamed.parts) {
        let (p, q) = (&a.pca, &b.pca);
        assert_eq!((a.vertices.clone(), p.n_components(), p.rank), (b.vertices.clone(), q.n_components(), q.rank), "part {}", a.name);
        assert!((&p.mean - &q.mean).amax() < 1e-12, "part {}: means", a.name);
        for k in 0..p.n_components() {
            assert!((p.variances[k] - q.variances[k]).abs() <= 1e-9 * p.variances[k], "part {}: variance {k}", a.name);
            let cos = p.components.row(k).dot(&q.components.row(k)).abs();
            assert!((cos - 1.0).abs() < 1e-8, "part {}: axis {k}: |cos| {cos}", a.name);
        }
        assert!((p.total_variance - q.total_variance).abs() <= 1e-12 * p.total_variance);
    }
    for ((ea, ra), (eb, rb)) in held_report.iter().zip(&streamed_report) {
        assert!((ea - eb).abs() < 1e-12 && (ra - rb).abs() < 1e-9 * ra, "reports {ea} {ra} vs {eb} {rb}");
    }
    // A real consumer: the walk encoded and decoded through either model gives the same parts.
    let walk = AlignedMotion::load(&motions[0]).unwrap();
    let decode = |m: &PcaModel| m.decode(&m.encode(&walk).unwrap()).unwrap();
    let (da, db) = (decode(&held), decode(&streamed));
    let mut worst: f64 = 0.0;
    for (pa, pb) in da.iter().zip(&db) {
        for (fa, fb) in pa.iter().zip(pb) {
            for (x, y) in fa.iter().zip(fb) {
                worst = worst.max((x - y).norm());
            }
        }
    }
    assert!(worst < 1e-9, "decoded meshes differ by {worst} m");
}

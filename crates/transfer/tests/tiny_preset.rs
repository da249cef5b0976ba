//! The transfer pipeline with its default settings on the `tiny` preset of `synth` (real
//! MakeHuman bodies on decimated topologies and real mocap; needs the synth assets, as
//! `make test` does), run stage by stage as `make transfer` runs them. Checked against the
//! set's ground truth on every test motion: the full pipeline (correction and stitching)
//! is no worse than the raw regression, and the default placement beats the paper's
//! regressed displacement.

mod common;

use common::run;

use std::path::{Path, PathBuf};

use mesh_core::sequence::MeshSequence;
use transfer::evaluate::rms_errors;

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

const TRAIN: [&str; 5] = ["walk", "run", "jump", "kick", "dance"];
const TEST: [&str; 3] = ["punch", "spinkick", "cmu_jump"];

#[test]
fn defaults_on_the_tiny_preset_never_lose_to_raw_regression_or_the_papers_placement() {
    let dir = tempfile::tempdir().unwrap();
    let set = dir.path().join("set");
    let work = dir.path().join("work");
    let cfg = synth::preset::preset("tiny", 0, true).unwrap();
    synth::capture_set_writer::synthesise(&cfg, &set, false, &|_| {}, &|| {}).unwrap();
    let tpl = |x: &str| set.join(x).join("walk").join("000000.ply");
    let w = |rel: String| -> PathBuf { work.join(rel) };
    for x in ["A", "B"] {
        std::fs::create_dir_all(work.join(x)).unwrap();
        let seg = w(format!("{x}/parts.seg"));
        run("segment", &[s(&set.join(x).join("subject.json")), "--template".into(), s(&tpl(x)), "--out".into(), s(&seg)]);
        let motions: Vec<&str> = TRAIN.iter().chain(if x == "A" { &TEST[..] } else { &[] }).copied().collect();
        for m in motions {
            run("align", &["--segmentation".into(), s(&seg), "--subject".into(), s(&set.join(x).join("subject.json")), "--template".into(), s(&tpl(x)), s(&set.join(x).join(m)), "--out".into(), s(&w(format!("{x}/{m}.aligned")))]);
        }
        let mut args = vec!["--template".into(), s(&tpl(x)), "--parts".into(), s(&seg), "--out".into(), s(&w(format!("{x}/pca.model")))];
        args.extend(TRAIN.iter().map(|m| s(&w(format!("{x}/{m}.aligned")))));
        run("pca-fit", &args);
    }
    let mut train_args = vec![
        "--source-pca".into(), s(&w("A/pca.model".into())), "--target-pca".into(), s(&w("B/pca.model".into())),
        "--out".into(), s(&w("model".into())),
    ];
    for m in TRAIN {
        let corr = w(format!("{m}.corr"));
        run("dtw-densify", &[
            "--set".into(), s(&set.join("set.json")), "--pair".into(), m.into(),
            "--source-pca".into(), s(&w("A/pca.model".into())), "--target-pca".into(), s(&w("B/pca.model".into())),
            s(&w(format!("A/{m}.aligned"))), s(&w(format!("B/{m}.aligned"))),
            "--out".into(), s(&corr),
        ]);
        train_args.extend(["--pair".into(), s(&w(format!("A/{m}.aligned"))), s(&w(format!("B/{m}.aligned"))), s(&corr)]);
    }
    run("gpr-train", &train_args);
    let predict = |m: &str, extra: &[&str], name: &str| -> (f64, f64) {
        let out = w(format!("out/{m}/{name}"));
        let mut args = vec![
            "--model".into(), s(&w("model".into())), "--source-pca".into(), s(&w("A/pca.model".into())),
            "--target-pca".into(), s(&w("B/pca.model".into())), "--target-template".into(), s(&tpl("B")),
            s(&w(format!("A/{m}.aligned"))), "--out".into(), s(&out),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        run("gpr-predict", &args);
        let pred = MeshSequence::load_dir(&out).unwrap();
        let truth = MeshSequence::load_dir(&set.join("truth").join("B").join(m)).unwrap();
        rms_errors(&pred, &truth).unwrap()
    };
    let seg_b = s(&w("B/parts.seg".into()));
    let mut surface_args: Vec<String> = vec!["--surface".into(), "correct-stitch".into(), "--segmentation".into(), seg_b];
    for t in TRAIN {
        surface_args.extend(["--target-training".into(), s(&w(format!("B/{t}.aligned")))]);
    }
    let surface_args: Vec<&str> = surface_args.iter().map(|a| a.as_str()).collect();
    for m in TEST {
        let (raw_pose, default_placed) = predict(m, &[], "gpr-nn");
        let (_, regressed_placed) = predict(m, &["--placement", "regressed"], "gpr-nn-regressed");
        let (full_pose, _) = predict(m, &surface_args, "gpr-nn+correct+stitch");
        eprintln!(
            "{m}: pose raw {raw_pose:.4} full {full_pose:.4}; placed default {default_placed:.4} regressed {regressed_placed:.4}"
        );
        assert!(full_pose <= raw_pose, "{m}: full pipeline {full_pose} worse than raw regression {raw_pose}");
        assert!(
            default_placed < regressed_placed,
            "{m}: default placement {default_placed} not below regressed {regressed_placed}"
        );
    }
}

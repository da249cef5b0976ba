//! Provenance on the small synthetic capture set of `common` (subjects at 25 and 50 fps): every
//! artifact a stage writes lists, in its header, every input file it was given with that
//! file's SHA-256 (computed here independently), and the aligned motions carry the subject's
//! frame rate, up axis and template hash, which is where `dtw-densify`, `gpr-train` and
//! `learning-curves` take the frame rates from.

mod common;

use std::path::{Path, PathBuf};

use capture::align::AlignedMotion;
use clap::Parser;
use common::run;
use mesh_core::artifact::{read_header, Artifact, Header};
use sha2::{Digest, Sha256};

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

fn sha256(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap();
    Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect()
}

/// Asserts that `artifact`'s header records every file of `given`, by path and hash.
fn assert_inputs(artifact: &Path, given: &[PathBuf]) -> Header {
    let (_, _, header) = read_header(artifact).unwrap();
    for f in given {
        let rec = header.inputs.iter().find(|r| r.path == s(f));
        let rec = rec.unwrap_or_else(|| panic!("{}: input {} not recorded", artifact.display(), f.display()));
        assert_eq!(rec.sha256, sha256(f), "{}: hash of {}", artifact.display(), f.display());
    }
    header
}

fn frames(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    v.sort();
    v
}

fn subject_fps(set: &Path, x: &str) -> f64 {
    let text = std::fs::read_to_string(set.join(x).join("subject.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["fps"].as_f64().unwrap()
}

#[test]
fn every_artifact_header_lists_every_input_file_and_its_hash() {
    let dir = tempfile::tempdir().unwrap();
    let w = |rel: &str| dir.path().join(rel);
    let set = dir.path().join("set");
    common::write_set(&set);
    let tpl = |x: &str| set.join(x).join("walk").join("000000.ply");
    let motions = ["walk", "run"];
    for x in ["A", "B"] {
        let subject = set.join(x).join("subject.json");
        let seg = w(&format!("{x}.seg"));
        run("segment", &[s(&subject), "--template".into(), s(&tpl(x)), "--out".into(), s(&seg)]);
        assert_inputs(&seg, &[subject.clone(), tpl(x)]);
        for m in motions {
            let out = w(&format!("{x}-{m}.aligned"));
            let motion = set.join(x).join(m);
            run("align", &[
                "--segmentation".into(), s(&seg), "--subject".into(), s(&subject), "--template".into(),
                s(&tpl(x)), s(&motion), "--out".into(), s(&out),
            ]);
            let mut given = vec![subject.clone(), tpl(x), seg.clone()];
            given.extend(frames(&motion));
            assert!(given.len() > 10, "the motion has frames");
            assert_inputs(&out, &given);
            let aligned = AlignedMotion::load(&out).unwrap();
            assert_eq!(aligned.capture.fps, subject_fps(&set, x));
            assert_eq!(aligned.capture.up, [0.0, 1.0, 0.0], "subject.json says +y");
            assert_eq!(aligned.capture.template_sha256, sha256(&tpl(x)));
        }
        let aligned: Vec<PathBuf> = motions.iter().map(|m| w(&format!("{x}-{m}.aligned"))).collect();
        let pca = w(&format!("{x}.pca"));
        let mut args = vec!["--template".into(), s(&tpl(x)), "--segmentation".into(), s(&seg), "--out".into(), s(&pca)];
        args.extend(aligned.iter().map(|p| s(p)));
        run("pca-fit", &args);
        let mut given = vec![tpl(x), seg.clone()];
        given.extend(aligned.iter().cloned());
        assert_inputs(&pca, &given);
        let whole = w(&format!("{x}-whole.pca"));
        let mut args = vec!["--whole-body".into(), "--template".into(), s(&tpl(x)), "--out".into(), s(&whole)];
        args.extend(aligned.iter().map(|p| s(p)));
        run("pca-fit", &args);
        let mut given = vec![tpl(x)];
        given.extend(aligned.iter().cloned());
        let header = assert_inputs(&whole, &given);
        assert_eq!(header.params["whole_body"], true);
        assert_eq!(header.params["part_alignment"], "body", "the command-line spelling (docs/FORMATS.md)");
    }

    let set_json = set.join("set.json");
    let corr = w("walk.corr");
    let (sa, ta) = (w("A-walk.aligned"), w("B-walk.aligned"));
    run("dtw-densify", &[
        "--set".into(), s(&set), "--motion".into(), "walk".into(), "--source-pca".into(), s(&w("A.pca")),
        "--target-pca".into(), s(&w("B.pca")), s(&sa), s(&ta), "--out".into(), s(&corr),
    ]);
    assert_inputs(&corr, &[set_json, w("A.pca"), w("B.pca"), sa.clone(), ta.clone()]);

    for (reverse, src, tgt) in [(false, "A", "B"), (true, "B", "A")] {
        let model = w(&format!("{src}-{tgt}.model"));
        let mut args = vec![
            "--source-pca".into(), s(&w(&format!("{src}.pca"))), "--target-pca".into(),
            s(&w(&format!("{tgt}.pca"))), "--max-iter".into(), "5".into(), "--pair".into(), s(&sa), s(&ta),
            s(&corr), "--out".into(), s(&model),
        ];
        if reverse {
            args.push("--reverse".into());
        }
        run("gpr-train", &args);
        let header = assert_inputs(&model, &[w(&format!("{src}.pca")), w(&format!("{tgt}.pca")), sa.clone(), ta.clone(), corr.clone()]);
        assert_eq!(header.params["source_fps"], subject_fps(&set, src), "from the aligned motions");
        assert_eq!(header.params["target_fps"], subject_fps(&set, tgt));
        assert_eq!(header.params["max_iter"], 5);
        // Every option is recorded under its flag's name, defaults included (the stage's Params).
        assert_eq!(header.params["reverse"], reverse);
        assert_eq!(header.params["method"], "gpr-nn", "the command-line name");
        assert_eq!(header.params["sparse"], "auto", "the default: the exact GP up to 1024 pairs, sparse above");
        assert_eq!(header.params["pair"], serde_json::json!([s(&sa), s(&ta), s(&corr)]));
        assert_eq!(header.params["out"], s(&model));
        for key in ["prior_weight", "mean", "mean_prior", "mean_ridge", "noise_var", "learn_noise", "nn_bias", "keyposes_only", "source_pca", "target_pca"] {
            assert!(!header.params[key].is_null(), "{key} missing from the header");
        }
    }

    // Invocation independence: the same options in another order, `--flag=value` and `-o` forms,
    // with flags that change no output (-v, --threads), write the same bytes.
    // The loop above wrote A-B.model from `--source-pca A --target-pca B --max-iter 5 --pair ... --out`.
    let model = w("A-B.model");
    let first = std::fs::read(&model).unwrap();
    run("gpr-train", &[
        "-v".into(), "--max-iter=5".into(), format!("--target-pca={}", s(&w("B.pca"))), "--pair".into(), s(&sa), s(&ta), s(&corr),
        format!("--out={}", s(&model)), "--threads=1".into(), "--source-pca".into(), s(&w("A.pca")),
    ]);
    assert!(std::fs::read(&model).unwrap() == first, "gpr-train: the model's bytes depend on how the options were written");

    let predict = |out: &Path, args: Vec<String>| {
        let mut all = args;
        all.extend(["--out".into(), s(out)]);
        run("gpr-predict", &all);
    };
    let (p1, p2) = (w("pred-1"), w("pred-2"));
    predict(&p1, vec![
        "--model".into(), s(&model), "--source-pca".into(), s(&w("A.pca")), "--target-pca".into(), s(&w("B.pca")),
        "--target-template".into(), s(&tpl("B")), "--placement".into(), "regressed".into(), s(&sa),
    ]);
    predict(&p2, vec![
        s(&sa), "--placement=regressed".into(), format!("--target-template={}", s(&tpl("B"))), "-v".into(),
        format!("--target-pca={}", s(&w("B.pca"))), "--threads".into(), "1".into(), "--source-pca".into(), s(&w("A.pca")),
        format!("--model={}", s(&model)),
    ]);
    let listing = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    assert_eq!(listing(&p1), listing(&p2));
    assert!(listing(&p1).len() > 10, "one frame per source frame");
    for name in listing(&p1) {
        assert!(std::fs::read(p1.join(&name)).unwrap() == std::fs::read(p2.join(&name)).unwrap(), "gpr-predict: {name} differs");
    }
}

#[test]
fn an_aligned_motion_of_the_previous_version_is_refused_with_its_version() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("old.aligned");
    let mesh = mesh_core::shapes::cylinder(8, 4, 0.1, 1.0);
    let seq = mesh_core::sequence::MeshSequence::new(mesh.faces.clone(), vec![mesh.vertices.clone(); 2]);
    let m = capture::align::align_motion(&mesh, &seq).unwrap();
    let header = Header::new("align", "0");
    mesh_core::artifact::write_artifact(&path, AlignedMotion::KIND, AlignedMotion::VERSION - 1, &header, &m).unwrap();
    let err = AlignedMotion::load(&path).unwrap_err().to_string();
    assert!(err.contains("old.aligned") && err.contains("version 2"), "{err}");
}

/// Every option of a stage's `Params` is in its JSON record (what `Header::with_params` stores)
/// under its flag's name, given or left at its default.
#[test]
fn every_stage_params_record_every_option_under_its_flag_name() {
    use crate::recorded_but_part as missing;
    let cases: Vec<(&str, Vec<String>)> = vec![
        ("gpr-predict", missing::<transfer::stage::gpr_predict::Params>(&[
            "gpr-predict", "--model", "m", "--source-pca", "s", "--target-pca", "t", "--target-template", "tpl", "a.aligned", "-o", "out",
        ]).unwrap()),
        ("gpr-predict --surface", missing::<transfer::stage::gpr_predict::Params>(&[
            "gpr-predict", "--model", "m", "--source-pca", "s", "--target-pca", "t", "--target-template", "tpl", "--surface", "correct-stitch",
            "--segmentation", "seg", "--target-training", "x.aligned", "--timing", "t.json", "--confidence", "c.json", "a.aligned", "-o", "out",
        ]).unwrap()),
        ("gpr-train", missing::<transfer::stage::gpr_train::Params>(&[
            "gpr-train", "--source-pca", "s", "--target-pca", "t", "--pair", "a", "b", "c", "-o", "m",
        ]).unwrap()),
        ("dtw-densify", missing::<transfer::stage::dtw_densify::Params>(&[
            "dtw-densify", "--set", "set", "--motion", "walk", "--source-pca", "s", "--target-pca", "t", "a", "b", "-o", "c",
        ]).unwrap()),
        ("transfer-eval", missing::<transfer::stage::transfer_eval::Params>(&[
            "transfer-eval", "pred", "truth", "--direction", "A->B", "--motion", "punch", "--method", "gpr-nn",
        ]).unwrap()),
        ("surface-quality", missing::<transfer::stage::surface_quality::Params>(&[
            "surface-quality", "--segmentation", "seg", "--truth", "t", "p1", "p2", "-o", "q.json",
        ]).unwrap()),
        ("representation-error", missing::<transfer::stage::representation_error::Params>(&[
            "representation-error", "--template", "tpl", "--segmentation", "seg", "--truth", "t", "a.aligned", "-o", "r.json",
        ]).unwrap()),
        ("correct", missing::<surface::stage::correct::Params>(&["correct", "--training", "tr", "pred", "-o", "out"]).unwrap()),
        ("stitch", missing::<surface::stage::stitch::Params>(&[
            "stitch", "parts", "--segmentation", "seg", "--template", "tpl", "-o", "out",
        ]).unwrap()),
        ("blend", missing::<surface::stage::blend::Params>(&["blend", "a.ply", "b.ply", "-o", "out.ply"]).unwrap()),
        ("align", missing::<capture::stage::align::Params>(&[
            "align", "--subject", "s.json", "--template", "tpl", "--frame", "body", "motion", "-o", "out",
        ]).unwrap()),
    ];
    for (stage, unrecorded) in cases {
        assert!(unrecorded.is_empty(), "{stage}: {unrecorded:?} not recorded");
    }
    // The record spells choices and paths as the command line does.
    let p = transfer::stage::gpr_predict::Params::try_parse_from([
        "gpr-predict", "--model", "m", "--source-pca", "s", "--target-pca", "t", "--target-template", "tpl", "a.aligned", "-o", "out",
    ]).unwrap();
    let record = serde_json::to_value(&p).unwrap();
    assert_eq!(record["surface"], "assemble");
    assert_eq!(record["placement"], "scaled-source");
    assert_eq!(record["motion"], "a.aligned");
    assert_eq!(record["target_training"], serde_json::json!([]));
}

/// `mesh_core::cli::unrecorded_options` without `part`: `--part` is left out of the Params record
/// on purpose (`part_merge::save_piece` adds it to a piece's header; the whole model's header must
/// not name it, so that merge-parts writes the same bytes as one run).
fn recorded_but_part<P: clap::Parser + serde::Serialize>(args: &[&str]) -> Result<Vec<String>, String> {
    mesh_core::cli::unrecorded_options::<P>(args).map(|v| v.into_iter().filter(|o| o != "part").collect())
}

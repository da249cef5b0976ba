//! The transfer model's configurations and methods on the `tiny` preset of `synth` (real bodies
//! and mocap; needs the synth assets, as `make test` does):
//! - `gpr-train --config auto`: every candidate configuration is also trained on its own, fixed
//!   by name with the orientation weight auto chose, and its cross-validated error measured
//!   there; the automatic choice is the one the one-standard-error rule picks from those
//!   independent runs (`default` unless another
//!   is lower on the held-out motions by more than a standard error of the paired
//!   differences; then the lowest of those), the auto run reports the same errors, and the
//!   model it writes is the one `--config NAME` trains for the chosen name.
//! - `--orientation-weight auto` keeps the weight of lowest error with whole motions held out,
//!   as each weight trained on its own measures it.
//! - `--hyperparameters-from` a trained model gives that model and its estimate again.
//! - The method rows `make transfer` writes, at the default configuration and at `paper`, are
//!   different models: no two transfer a test motion to the same meshes.

mod common;

use common::run;

use std::path::{Path, PathBuf};
use std::process::Command;

use capture::align::AlignedMotion;
use mesh_core::artifact::{read_header, Artifact};
use mesh_core::sequence::MeshSequence;
use transfer::gpr_model::{GprModel, Regressor};

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

const TRAIN: [&str; 5] = ["walk", "run", "jump", "kick", "dance"];
const CANDIDATES: [&str; 4] = ["default", "affine-mean", "no-prior", "zero-mean"];

/// The header's `cross_validation` of a model.
fn cross_validation(model: &Path) -> serde_json::Value {
    let (_, _, header) = read_header(model).unwrap();
    header.params["cross_validation"].clone()
}

/// The tiny preset's training pairs made ready for `gpr-train` in `dir`: the set, the work
/// folder (segmentation, aligned motions, part and whole-body PCA models of both subjects, the
/// test motion `punch` of A aligned) and `gpr-train`'s arguments for the pairs.
fn tiny_training(dir: &Path) -> (PathBuf, PathBuf, Vec<String>) {
    let set = dir.join("set");
    let work = dir.join("work");
    let cfg = synth::preset::preset("tiny", 0, true).unwrap();
    synth::capture_set_writer::synthesise(&cfg, &set, false, &|_| {}, &|| {}).unwrap();
    let tpl = |x: &str| set.join(x).join("walk").join("000000.ply");
    let w = |rel: String| -> PathBuf { work.join(rel) };
    for x in ["A", "B"] {
        std::fs::create_dir_all(work.join(x)).unwrap();
        let seg = w(format!("{x}/parts.seg"));
        run("segment", &[s(&set.join(x).join("subject.json")), "--template".into(), s(&tpl(x)), "--out".into(), s(&seg)]);
        let motions: &[&str] = if x == "A" { &["walk", "run", "jump", "kick", "dance", "punch"] } else { &TRAIN };
        for m in motions {
            run("align", &["--segmentation".into(), s(&seg), "--subject".into(), s(&set.join(x).join("subject.json")), "--template".into(), s(&tpl(x)), s(&set.join(x).join(m)), "--out".into(), s(&w(format!("{x}/{m}.aligned")))]);
        }
        let mut args = vec!["--template".into(), s(&tpl(x)), "--segmentation".into(), s(&seg), "--out".into(), s(&w(format!("{x}/pca.model")))];
        args.extend(TRAIN.iter().map(|m| s(&w(format!("{x}/{m}.aligned")))));
        run("pca-fit", &args);
        let mut args = vec!["--whole-body".into(), "--components".into(), "100".into(), "--template".into(), s(&tpl(x)), "--out".into(), s(&w(format!("{x}/pca-whole.model")))];
        args.extend(TRAIN.iter().map(|m| s(&w(format!("{x}/{m}.aligned")))));
        run("pca-fit", &args);
    }
    let mut train_args = Vec::new();
    for m in TRAIN {
        let corr = w(format!("{m}.corr"));
        run("dtw-densify", &[
            "--set".into(), s(&set), "--motion".into(), m.into(),
            "--source-pca".into(), s(&w("A/pca.model".into())), "--target-pca".into(), s(&w("B/pca.model".into())),
            s(&w(format!("A/{m}.aligned"))), s(&w(format!("B/{m}.aligned"))),
            "--out".into(), s(&corr),
        ]);
        train_args.extend(["--pair".into(), s(&w(format!("A/{m}.aligned"))), s(&w(format!("B/{m}.aligned"))), s(&corr)]);
    }
    (set, work, train_args)
}

#[test]
fn auto_keeps_the_configuration_the_one_standard_error_rule_picks_from_the_fixed_runs() {
    let dir = tempfile::tempdir().unwrap();
    let (_, work, pair_args) = tiny_training(dir.path());
    let w = |rel: String| -> PathBuf { work.join(rel) };
    let mut train_args = vec!["--source-pca".into(), s(&w("A/pca.model".into())), "--target-pca".into(), s(&w("B/pca.model".into()))];
    train_args.extend(pair_args);
    let train = |extra: &[&str], out: &Path| {
        let mut args = train_args.clone();
        args.extend(extra.iter().map(|a| a.to_string()));
        args.extend(["--out".into(), s(out)]);
        run("gpr-train", &args);
    };

    // Auto chooses the limb orientation weight first (tested below) and gives it to every
    // candidate.
    let auto = w("auto.model".into());
    let report = w("auto.json".into());
    train(&["--config", "auto", "--report", &s(&report)], &auto);
    let (_, _, header) = read_header(&auto).unwrap();
    let weight = header.params["orientation_weight_choice"]["weight"].as_f64().unwrap().to_string();

    // Each candidate fixed by name, its error measured in its own run.
    let mut fixed = Vec::new();
    for name in CANDIDATES {
        let model = w(format!("{name}.model"));
        train(&["--config", name, "--orientation-weight", &weight, "--cross-validate"], &model);
        let cv = cross_validation(&model);
        assert_eq!(cv["config"], name);
        let motions = cv["motions"].as_array().unwrap();
        assert_eq!(motions.len(), TRAIN.len(), "one error per training motion");
        for (m, want) in motions.iter().zip(TRAIN) {
            assert_eq!(m["motion"], want);
            // Every source frame of the held-out motion is compared once (the path covers them).
            let frames = AlignedMotion::load(w(format!("A/{want}.aligned"))).unwrap().frames.len();
            assert_eq!(m["frames"].as_u64().unwrap() as usize, frames, "{name}: {want}");
        }
        let e = cv["cv_rms_pose_m"].as_f64().unwrap();
        // A transfer error of a few centimetres on bodies of 1.6-1.9 m: neither zero nor a
        // different body.
        assert!(e > 1e-3 && e < 0.3, "{name}: {e} m");
        assert_eq!(cv["folds"], "halves", "the default folds");
        let per_motion: Vec<f64> = motions.iter().map(|m| m["rms_pose_m"].as_f64().unwrap()).collect();
        fixed.push((name, e, per_motion));
    }

    // Whole motions held out: the same frames compared, another estimate.
    let whole = w("default-motions.model".into());
    train(&["--cross-validate", "--cv-folds", "motions"], &whole);
    let (halves, motions) = (cross_validation(&w("default.model".into())), cross_validation(&whole));
    assert_eq!(motions["folds"], "motions");
    for (h, m) in halves["motions"].as_array().unwrap().iter().zip(motions["motions"].as_array().unwrap()) {
        assert_eq!((&h["motion"], &h["frames"]), (&m["motion"], &m["frames"]));
    }
    let (eh, em) = (halves["cv_rms_pose_m"].as_f64().unwrap(), motions["cv_rms_pose_m"].as_f64().unwrap());
    assert!((eh - em).abs() > 1e-4 * em && em > 1e-3 && em < 0.3, "halves {eh} m, motions {em} m");

    let cv = cross_validation(&auto);
    let from_report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(cv, from_report, "the report is the header's record");
    // The rule, from the fixed runs: a candidate is clearly better than `default` (the first)
    // when the mean of its per-motion differences plus their standard error is below zero.
    let first = &fixed[0].2;
    let clearly_better = |errors: &[f64]| {
        let d: Vec<f64> = errors.iter().zip(first).map(|(a, b)| a - b).collect();
        let n = d.len() as f64;
        let mean = d.iter().sum::<f64>() / n;
        let se = (d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0) / n).sqrt();
        mean + se < 0.0
    };
    let (best, best_e) = fixed[1..]
        .iter()
        .filter(|f| clearly_better(&f.2))
        .map(|f| (f.0, f.1))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((fixed[0].0, fixed[0].1));
    eprintln!("kept {best}: {:?}", fixed.iter().map(|f| (f.0, f.1)).collect::<Vec<_>>());
    assert_eq!(cv["config"], best, "fixed runs: {fixed:?}");
    let candidates = cv["candidates"].as_array().unwrap();
    assert_eq!(candidates.len(), CANDIDATES.len());
    for ((name, e, _), c) in fixed.iter().zip(candidates) {
        assert_eq!(c["config"], *name);
        let got = c["cv_rms_pose_m"].as_f64().unwrap();
        assert!((got - e).abs() <= 1e-9 * e, "{name}: {got} in the auto run, {e} on its own");
    }
    assert!((cv["cv_rms_pose_m"].as_f64().unwrap() - best_e).abs() <= 1e-9 * best_e);
    // The model kept is the chosen configuration's, and the header says which flags it used.
    let (chosen, alone) = (GprModel::load(&auto).unwrap(), GprModel::load(w(format!("{best}.model"))).unwrap());
    assert_eq!((&chosen.parts, &chosen.displacement, &chosen.orientation, &chosen.reports), (&alone.parts, &alone.displacement, &alone.orientation, &alone.reports));
    let ((_, _, ha), (_, _, hb)) = (read_header(&auto).unwrap(), read_header(w(format!("{best}.model"))).unwrap());
    for key in ["mean", "prior_weight", "orientation_weight"] {
        assert_eq!(ha.params[key], hb.params[key], "{key}");
    }

    // Leaving motions out needs whole models.
    let mut args = train_args.clone();
    args.extend(["--config", "auto", "--part", "displacement", "--out"].map(String::from));
    args.push(s(&w("piece".into())));
    let out = Command::new(common::bin("gpr-train")).args(&args).env("OPENBLAS_NUM_THREADS", "1").output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not with --part"));
}

/// `gpr-train --orientation-weight auto`: each candidate weight is also trained on its own with
/// whole motions held out (`--cv-folds motions`); the auto run records the same estimates, keeps
/// the weight of the lowest, and writes the model `--orientation-weight <kept>` trains. Refused
/// with `--part`.
#[test]
fn orientation_weight_auto_keeps_the_weight_of_lowest_whole_motion_error() {
    let dir = tempfile::tempdir().unwrap();
    let (_, work, pair_args) = tiny_training(dir.path());
    let w = |rel: &str| -> PathBuf { work.join(rel) };
    let mut base = vec!["--source-pca".into(), s(&w("A/pca.model")), "--target-pca".into(), s(&w("B/pca.model"))];
    base.extend(pair_args);
    let train = |extra: &[&str]| -> std::process::Output {
        let mut args = base.clone();
        args.extend(extra.iter().map(|a| a.to_string()));
        Command::new(common::bin("gpr-train")).args(&args).env("OPENBLAS_NUM_THREADS", "1").output().unwrap()
    };
    let weights = ["0.5", "0.3", "0"];
    let mut kept_indices = Vec::new();
    // Two configurations: on the tiny preset the default keeps 0.5, zero-mean 0.3.
    for config in ["default", "zero-mean"] {
        let mut fixed = Vec::new();
        for weight in weights {
            let model = w(&format!("{config}-{weight}.model"));
            let out = train(&["--config", config, "--orientation-weight", weight, "--cross-validate", "--cv-folds", "motions", "--out", &s(&model)]);
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            let cv = cross_validation(&model);
            assert_eq!(cv["folds"], "motions");
            fixed.push(cv["cv_rms_pose_m"].as_f64().unwrap());
        }
        // The weights give different estimates, or the choice tests nothing.
        assert!(fixed.iter().zip(&fixed[1..]).all(|(a, b)| (a - b).abs() > 1e-6 * a), "{config}: {fixed:?}");

        let auto = w(&format!("{config}-auto.model"));
        let out = train(&["--config", config, "--orientation-weight", "auto", "--out", &s(&auto)]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let (_, _, header) = read_header(&auto).unwrap();
        let choice = &header.params["orientation_weight_choice"];
        assert_eq!(choice["folds"], "motions");
        let tried: Vec<(f64, f64)> = choice["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| (c["weight"].as_f64().unwrap(), c["cv_rms_pose_m"].as_f64().unwrap()))
            .collect();
        assert_eq!(tried.iter().map(|t| t.0.to_string()).collect::<Vec<_>>(), weights);
        for ((weight, e), f) in tried.iter().zip(&fixed) {
            assert!((e - f).abs() <= 1e-9 * f, "{config}, weight {weight}: auto {e} m, alone {f} m");
        }
        let lowest = (0..fixed.len()).min_by(|&a, &b| fixed[a].total_cmp(&fixed[b])).unwrap();
        assert_eq!(choice["weight"].as_f64(), Some(tried[lowest].0), "{config}");
        assert_eq!(header.params["orientation_weight"].as_f64(), Some(tried[lowest].0), "{config}");
        let kept = GprModel::load(&auto).unwrap();
        let alone = GprModel::load(w(&format!("{config}-{}.model", weights[lowest]))).unwrap();
        assert_eq!((&kept.parts, &kept.displacement, &kept.orientation), (&alone.parts, &alone.displacement, &alone.orientation), "{config}");
        kept_indices.push(lowest);
    }
    assert!(kept_indices.iter().any(|&i| i != 0), "every configuration kept the first weight: {kept_indices:?}");

    let refused = train(&["--orientation-weight", "auto", "--part", "displacement", "--out", &s(&w("piece"))]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("not with --part"));
    let bad = train(&["--orientation-weight", "half", "--out", &s(&w("bad.model"))]);
    assert_eq!(bad.status.code(), Some(2), "{}", String::from_utf8_lossy(&bad.stderr));
    assert!(!w("piece").exists() && !w("bad.model").exists());
}

/// `--hyperparameters-from` a model trained on the same pairs gives that model again (every GP,
/// mean and limb orientation equal, without learning the hyperparameters) and the same
/// cross-validated estimate, as the pipeline's estimate task relies on; it refuses
/// `--config auto` and a model of another method.
#[test]
fn hyperparameters_from_a_trained_model_give_that_model_and_its_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let (_, work, pair_args) = tiny_training(dir.path());
    let w = |rel: &str| -> PathBuf { work.join(rel) };
    let mut base = vec!["--source-pca".into(), s(&w("A/pca.model")), "--target-pca".into(), s(&w("B/pca.model"))];
    base.extend(pair_args);
    let train = |extra: &[String]| -> std::process::Output {
        let mut args = base.clone();
        args.extend(extra.iter().cloned());
        Command::new(common::bin("gpr-train")).args(&args).env("OPENBLAS_NUM_THREADS", "1").output().unwrap()
    };
    let (learnt, given) = (w("learnt.model"), w("given.model"));
    assert!(train(&["--cross-validate".into(), "--out".into(), s(&learnt)]).status.success());
    let out = train(&["-v".into(), "--cross-validate".into(), "--hyperparameters-from".into(), s(&learnt), "--out".into(), s(&given)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (a, b) = (GprModel::load(&learnt).unwrap(), GprModel::load(&given).unwrap());
    assert_eq!((&a.parts, &a.displacement, &a.orientation), (&b.parts, &b.displacement, &b.orientation));
    assert_eq!(cross_validation(&learnt), cross_validation(&given));
    // Nothing was optimised: every GP's report shows no iteration.
    assert!(b.reports.iter().all(|r| r.iterations == 0), "{:?}", b.reports);
    assert!(a.reports.iter().any(|r| r.iterations > 0));

    let refused = train(&["--config".into(), "auto".into(), "--hyperparameters-from".into(), s(&learnt), "--out".into(), s(&w("auto.model"))]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("not with --config auto"));
    let other = train(&["--method".into(), "keypose-affine".into(), "--hyperparameters-from".into(), s(&learnt), "--out".into(), s(&w("k.model"))]);
    assert_eq!(other.status.code(), Some(1));
    let err = String::from_utf8_lossy(&other.stderr);
    assert!(err.contains("learnt.model") && err.contains("a gpr-nn model"), "{err}");
    assert!(!w("auto.model").exists() && !w("k.model").exists());
}

/// Every method row of `make transfer` at the default configuration (gpr-nn, the key-pose
/// baseline, the whole body, gpr-nn on key-poses) and at `--config paper` (the three kernels
/// besides) transfers the test motion to meshes at least 1 mm apart somewhere from every other
/// row's; the key-pose baseline is Baran et al.'s model class throughout (affine key-pose maps
/// for every part and the displacement, no limb orientation).
#[test]
fn method_rows_are_different_models() {
    let dir = tempfile::tempdir().unwrap();
    let (set, work, pair_args) = tiny_training(dir.path());
    let w = |rel: &str| -> PathBuf { work.join(rel) };
    let transfer = |config: &str, method: &str, keyposes: bool| -> MeshSequence {
        let kind = if method == "whole-body" { "pca-whole" } else { "pca" };
        let (src, tgt) = (s(&w(&format!("A/{kind}.model"))), s(&w(&format!("B/{kind}.model"))));
        let name = format!("{config}-{method}{}", if keyposes { "-keyposes" } else { "" });
        let model = w(&format!("{name}.model"));
        let mut args = vec!["--config".into(), config.into(), "--method".into(), method.into(), "--source-pca".into(), src.clone(), "--target-pca".into(), tgt.clone()];
        if keyposes {
            args.push("--keyposes-only".into());
        }
        args.extend(pair_args.iter().cloned());
        args.extend(["--out".into(), s(&model)]);
        run("gpr-train", &args);
        if method == "keypose-affine" {
            let m = GprModel::load(&model).unwrap();
            assert!(m.orientation.is_none(), "{name}: the key-pose baseline has a limb orientation");
            assert!(matches!(m.displacement, Regressor::Affine(_)), "{name}: its displacement is not the key-pose map");
        }
        let out = w(&name);
        run("gpr-predict", &[
            "--model".into(), s(&model), "--source-pca".into(), src, "--target-pca".into(), tgt,
            "--target-template".into(), s(&set.join("B").join("walk").join("000000.ply")), s(&w("A/punch.aligned")),
            "--out".into(), s(&out),
        ]);
        MeshSequence::load_dir(&out).unwrap()
    };
    let rows = |config: &str, methods: &[&str]| -> Vec<(String, MeshSequence)> {
        let mut rows: Vec<(String, MeshSequence)> = methods.iter().map(|m| (m.to_string(), transfer(config, m, false))).collect();
        rows.push(("gpr-nn-keyposes".into(), transfer(config, "gpr-nn", true)));
        rows
    };
    for (config, methods) in [
        ("default", &["gpr-nn", "keypose-affine", "whole-body"][..]),
        ("paper", &["gpr-nn", "gpr-se", "gpr-linear", "keypose-affine", "whole-body"][..]),
    ] {
        let rows = rows(config, methods);
        for (i, (a, ma)) in rows.iter().enumerate() {
            for (b, mb) in &rows[i + 1..] {
                let apart = ma
                    .frames
                    .iter()
                    .zip(&mb.frames)
                    .flat_map(|(fa, fb)| fa.iter().zip(fb).map(|(p, q)| (p - q).norm()))
                    .fold(0.0, f64::max);
                eprintln!("{config}: {a} and {b} at most {:.1} mm apart", apart * 1e3);
                assert!(apart > 1e-3, "{config}: {a} and {b} transfer punch to the same meshes ({apart} m apart at most)");
            }
        }
    }
}

/// `--cv-hyperparameters refit` learns every held-out model's hyperparameters on the other
/// motions: its estimate does not depend on the hyperparameters handed to it (the full model's,
/// here replaced by a noise variance ten times the learnt one), where `fixed` conditions with
/// exactly those; and it is not the `fixed` estimate, for the zero-mean GP whose hyperparameters
/// carry what the held-out motion taught the full model.
#[test]
fn refit_folds_learn_their_hyperparameters_without_the_held_out_motion() {
    use capture::choices::{MeanFunction, Method};
    use capture::part_pca::PcaModel;
    use gp::gpr::{GprOptions, PAPER_NOISE_VAR};
    use transfer::gpr_model::{train_rows, FixedHyperparameters, OrientationOptions, Regression, MEAN_RIDGE};
    use transfer::cross_validation::{cross_validate, Candidate, FoldUnit, Folds, HeldOut, Hyperparameters};
    use transfer::training_rows::{PairFiles, TrainingRows};

    let dir = tempfile::tempdir().unwrap();
    let (_, work, _) = tiny_training(dir.path());
    let (src, tgt) = (PcaModel::load(work.join("A/pca.model")).unwrap(), PcaModel::load(work.join("B/pca.model")).unwrap());
    let names: Vec<String> = src.parts.iter().map(|p| p.name.clone()).collect();
    let mut pairs = Vec::new();
    let mut held_out = Vec::new();
    for m in TRAIN {
        let files = [work.join(format!("A/{m}.aligned")), work.join(format!("B/{m}.aligned")), work.join(format!("{m}.corr"))];
        pairs.push(PairFiles::read_encoded(&files, &src, &tgt).unwrap().data);
        held_out.push(HeldOut { motion: m.to_string(), truth: files[1].clone() });
    }
    let opts = GprOptions { noise_var: PAPER_NOISE_VAR, ..Default::default() };
    let regression = |fixed| Regression { method: Method::GprNn, nn_bias: false, mean: MeanFunction::Zero, mean_ridge: MEAN_RIDGE, mean_priors: None, opts: &opts, fixed };
    let rows = TrainingRows::new(Method::GprNn, &names, &pairs, 1.0, false).unwrap();
    let full = FixedHyperparameters::of(&train_rows(&regression(None), &names, &rows).unwrap()).unwrap();
    let mut noisy = full.clone();
    for (_, noise) in noisy.parts.iter_mut().flatten().chain(noisy.displacement.as_mut()) {
        *noise *= 10.0;
    }
    let estimate = |how, fixed| {
        let folds = Folds { unit: FoldUnit::Motions, hyperparameters: how, pairs: &pairs, held_out: &held_out, frame_ratio: 1.0, keyposes_only: false, part_names: &names, source_pca: &src, target_pca: &tgt };
        let candidate = Candidate { regression: regression(Some(fixed)), orientation: OrientationOptions { weight: 0.0, attached: &[] } };
        cross_validate(&folds, &[candidate]).unwrap().remove(0).cv_rms_pose_m
    };
    let (fixed, fixed_noisy) = (estimate(Hyperparameters::Fixed, &full), estimate(Hyperparameters::Fixed, &noisy));
    let (refit, refit_noisy) = (estimate(Hyperparameters::Refit, &full), estimate(Hyperparameters::Refit, &noisy));
    assert_eq!(refit.to_bits(), refit_noisy.to_bits(), "refit: {refit} with the full model's hyperparameters, {refit_noisy} with others");
    assert!((fixed - fixed_noisy).abs() > 1e-4 * fixed, "fixed conditions with the hyperparameters it is given: {fixed} and {fixed_noisy}");
    assert!((refit - fixed).abs() > 1e-4 * fixed, "refit {refit} and fixed {fixed}");
    assert!(refit > 1e-3 && refit < 0.3, "{refit} m");
}

//! The transfer pipeline with its default settings on the `tiny` preset of `synth` (real
//! MakeHuman bodies on decimated topologies and real mocap; needs the synth assets, as
//! `make test` does), run stage by stage as `make transfer` runs them. Checked against the
//! set's ground truth: the full pipeline (correction and stitching) is no worse than the raw
//! regression over the test motions' frames pooled (on one motion it may be: it pulls each part
//! toward the nearest training meshes), and on every test motion the default placement beats
//! the paper's regressed displacement, whose foot height moves the body rather than the pose
//! (within 1 cm of the transfer without it). And the affine mean held at its geometric prior (no
//! training pair shapes the map; the residual GPs still learn; `--config affine-mean`, the
//! affine-mean GP alone) carries the source's pose: its transfer is far closer than the target's
//! mean pose (a transfer that ignores the source).

mod common;

use common::run;

use std::path::{Path, PathBuf};

use mesh_core::artifact::Artifact;
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
        let mut args = vec!["--template".into(), s(&tpl(x)), "--segmentation".into(), s(&seg), "--out".into(), s(&w(format!("{x}/pca.model")))];
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
            "--set".into(), s(&set), "--motion".into(), m.into(),
            "--source-pca".into(), s(&w("A/pca.model".into())), "--target-pca".into(), s(&w("B/pca.model".into())),
            s(&w(format!("A/{m}.aligned"))), s(&w(format!("B/{m}.aligned"))),
            "--out".into(), s(&corr),
        ]);
        train_args.extend(["--pair".into(), s(&w(format!("A/{m}.aligned"))), s(&w(format!("B/{m}.aligned"))), s(&corr)]);
    }
    run("gpr-train", &train_args);
    let mut prior_args = train_args.clone();
    let at = prior_args.iter().position(|a| a == "--out").unwrap();
    prior_args[at + 1] = s(&w("prior-model".into()));
    prior_args.extend(["--config".into(), "affine-mean".into(), "--mean-prior".into(), "geometric".into(), "--mean-ridge".into(), "1e3".into()]);
    run("gpr-train", &prior_args);
    let predict_with = |model: &str, m: &str, extra: &[&str], name: &str| -> (f64, f64) {
        let out = w(format!("out/{m}/{name}"));
        let mut args = vec![
            "--model".into(), s(&w(model.into())), "--source-pca".into(), s(&w("A/pca.model".into())),
            "--target-pca".into(), s(&w("B/pca.model".into())), "--target-template".into(), s(&tpl("B")),
            s(&w(format!("A/{m}.aligned"))), "--out".into(), s(&out),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        run("gpr-predict", &args);
        let pred = MeshSequence::load_dir(&out).unwrap();
        let truth = MeshSequence::load_dir(&set.join("truth").join("B").join(m)).unwrap();
        rms_errors(&pred, &truth).unwrap()
    };
    let predict = |m: &str, extra: &[&str], name: &str| predict_with("model", m, extra, name);
    // The target's mean pose on every frame: a transfer that ignores the source.
    let target_pca = capture::part_pca::PcaModel::load(w("B/pca.model".into())).unwrap();
    let template_b = MeshSequence::load_files(&[tpl("B")]).unwrap();
    let mean_pose_error = |m: &str| -> f64 {
        let truth = MeshSequence::load_dir(&set.join("truth").join("B").join(m)).unwrap();
        let zeros: Vec<nalgebra::DMatrix<f64>> = target_pca
            .parts
            .iter()
            .map(|p| nalgebra::DMatrix::zeros(truth.n_frames(), p.pca.components.nrows()))
            .collect();
        let plan = capture::assemble::plan(&target_pca).unwrap();
        let frames = capture::assemble::assemble(&plan, &target_pca, &target_pca.decode(&zeros).unwrap());
        let mean = MeshSequence::new(template_b.faces.clone(), frames);
        rms_errors(&mean, &truth).unwrap().0
    };
    let seg_b = s(&w("B/parts.seg".into()));
    let mut surface_args: Vec<String> = vec!["--surface".into(), "correct-stitch".into(), "--segmentation".into(), seg_b];
    for t in TRAIN {
        surface_args.extend(["--target-training".into(), s(&w(format!("B/{t}.aligned")))]);
    }
    let surface_args: Vec<&str> = surface_args.iter().map(|a| a.as_str()).collect();
    // Squared errors summed over frames, raw and full pipeline, and the frames.
    let mut pooled = (0.0, 0.0, 0);
    for m in TEST {
        let (raw_pose, default_placed) = predict(m, &[], "gpr-nn");
        let (regressed_pose, regressed_placed) = predict(m, &["--placement", "regressed"], "gpr-nn-regressed");
        let (unplanted_pose, _) = predict(m, &["--placement", "regressed", "--no-foot-height"], "gpr-nn-regressed-unplanted");
        // Where the root's height is regressed it drifts: the foot height lowers the body
        // rather than stretching the legs by the drift, so the pose barely moves.
        let (planted, unplanted) = (w(format!("out/{m}/gpr-nn-regressed")), w(format!("out/{m}/gpr-nn-regressed-unplanted")));
        let moved = rms_errors(&MeshSequence::load_dir(&planted).unwrap(), &MeshSequence::load_dir(&unplanted).unwrap()).unwrap().0;
        eprintln!("{m}: regressed placement pose {regressed_pose:.4}, without the foot height {unplanted_pose:.4}, moved {moved:.4}");
        assert!(moved < 0.01, "{m}: the foot height bends the regressed transfer's pose by {moved} m");
        let (full_pose, _) = predict(m, &surface_args, "gpr-nn+correct+stitch");
        eprintln!(
            "{m}: pose raw {raw_pose:.4} full {full_pose:.4}; placed default {default_placed:.4} regressed {regressed_placed:.4}"
        );
        let frames = MeshSequence::load_dir(&set.join("truth").join("B").join(m)).unwrap().n_frames();
        pooled = (pooled.0 + raw_pose * raw_pose * frames as f64, pooled.1 + full_pose * full_pose * frames as f64, pooled.2 + frames);
        let (prior_pose, _) = predict_with("prior-model", m, &[], "gpr-nn-prior");
        let mean_pose = mean_pose_error(m);
        eprintln!("{m}: geometric prior alone {prior_pose:.4}, target mean pose {mean_pose:.4}");
        assert!(prior_pose < mean_pose, "{m}: geometric prior {prior_pose} no better than the mean pose {mean_pose}");
        assert!(
            default_placed < regressed_placed,
            "{m}: default placement {default_placed} not below regressed {regressed_placed}"
        );
    }
    let (raw, full) = ((pooled.0 / pooled.2 as f64).sqrt(), (pooled.1 / pooled.2 as f64).sqrt());
    assert!(full <= raw, "pooled: full pipeline {full} worse than raw regression {raw}");

    // A transfer is made a block of frames at a time (a motion of any length holds one block):
    // made 6 frames at a time and kept on disk, through correction, stitching and both feet
    // clean-ups, every frame is the one `gpr-predict` wrote (one block, in memory, on this
    // body), to the bit.
    let source_pca = capture::part_pca::PcaModel::load(w("A/pca.model".into())).unwrap();
    let model = transfer::gpr_model::GprModel::load(w("model".into())).unwrap();
    let source = transfer::predict::SourceMotion::read(&w("A/punch.aligned".into()), &source_pca).unwrap();
    assert!(capture::part_pca::blocks_of(source.n_frames(), 6).len() >= 3, "{} frames", source.n_frames());
    let seg = mesh_core::segmentation::Segmentation::load(w("B/parts.seg".into())).unwrap();
    let training: Vec<PathBuf> = TRAIN.iter().map(|t| w(format!("B/{t}.aligned"))).collect();
    let training = transfer::reconstruct::training_part_meshes(&target_pca, &training, transfer::reconstruct::Stride::Every(1)).unwrap().0;
    let mut recon = transfer::reconstruct::Reconstructor::with_training_meshes(
        &target_pca, &seg, &template_b.faces, training, transfer::reconstruct::Surface::CorrectStitch,
        surface::correct::DEFAULT_NEIGHBOURS,
    )
    .unwrap()
    .with_corrected_assembly(true);
    let clean_up = transfer::feet::CleanUp { footskate: true, foot_height: true, smoothness: transfer::feet::SMOOTHNESS, faces: &template_b.faces };
    let (out, corrected_out) = (w("blocks/stitched".into()), w("blocks/corrected".into()));
    let mut made = transfer::predict::transfer_motion(
        &model, &source_pca, &target_pca, &source, transfer::placement::Placement::PREDICT_DEFAULT,
        Some(&mut recon), &clean_up,
        &transfer::predict::Streaming { output: &out, corrected_output: Some(&corrected_out), block: 6, memory_budget: 0 },
    )
    .unwrap();
    assert!(made.planted.as_ref().is_some_and(|p| p.planted_frames > 0), "{:?}", made.planted);
    let frames_of = |placed: &mut transfer::placed_frames::PlacedFrames| {
        let mut all = Vec::new();
        placed.for_each(&mut |f| Ok(all.push(f.to_vec()))).unwrap();
        all
    };
    let written_corrected = s(&w("out/punch/gpr-nn+correct".into()));
    let both: Vec<&str> = surface_args.iter().copied().chain(["--corrected-out", &written_corrected]).collect();
    predict("punch", &both, "gpr-nn+correct+stitch");
    let written = MeshSequence::load_dir(w("out/punch/gpr-nn+correct+stitch".into())).unwrap();
    let written_corrected = MeshSequence::load_dir(&written_corrected).unwrap();
    assert!(frames_of(&mut made.frames) == written.frames, "frames made in blocks of 6 differ");
    let corrected = frames_of(made.corrected_frames.as_mut().expect("corrected frames"));
    assert!(corrected == written_corrected.frames, "corrected frames made in blocks of 6 differ");
    assert!(corrected != written.frames, "the corrected frames are the stitched ones");
    drop(made);
    assert!(!out.parent().unwrap().exists() || std::fs::read_dir(out.parent().unwrap()).unwrap().count() == 0, "scratch files left");

    // The transfer plays at the source motion's rate (one output frame per source frame): A's
    // 20 fps in rate.json; a motion at another rate than the model's source motions keeps its
    // own, with a warning.
    let rate = |dir: PathBuf| -> f64 {
        let text = std::fs::read_to_string(dir.join("rate.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()["fps"].as_f64().unwrap()
    };
    assert_eq!(rate(w("out/punch/gpr-nn".into())), cfg.source.fps);
    let mut faster = capture::align::AlignedMotion::load(w("A/punch.aligned".into())).unwrap();
    faster.capture.fps = 2.0 * cfg.source.fps;
    faster.save(w("A/punch-faster.aligned".into()), &mesh_core::artifact::Header::new("test", "0")).unwrap();
    let out = w("out/punch-faster".into());
    let predicted = std::process::Command::new(common::bin("gpr-predict"))
        .args([
            "--model", &s(&w("model".into())), "--source-pca", &s(&w("A/pca.model".into())),
            "--target-pca", &s(&w("B/pca.model".into())), "--target-template", &s(&tpl("B")),
            &s(&w("A/punch-faster.aligned".into())), "--out", &s(&out),
        ])
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&predicted.stderr);
    assert!(predicted.status.success(), "{stderr}");
    assert_eq!(rate(out), 2.0 * cfg.source.fps);
    assert!(stderr.contains("punch-faster.aligned") && stderr.contains("the model's source motions 20 fps"), "{stderr}");
}

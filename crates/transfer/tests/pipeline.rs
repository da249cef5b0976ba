//! End to end on the synthetic capture set of `common`: every stage binary of
//! the crate, run as a user would, against known answers.

mod common;

use std::path::{Path, PathBuf};

use mesh_core::sequence::MeshSequence;
use transfer::evaluate::{rms_errors, EvalRecord};

use common::run;

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

struct Work {
    set: PathBuf,
    w: PathBuf,
}

impl Work {
    fn path(&self, rel: &str) -> PathBuf {
        self.w.join(rel)
    }

    /// align, segment, pca-fit (parts and whole body), dtw-densify.
    fn prepare(&self) -> Vec<String> {
        let mut pairs = Vec::new();
        let train: Vec<&str> = common::TRAIN.iter().map(|(n, _)| *n).collect();
        for s in ["A", "B"] {
            let tpl = self.set.join(s).join("walk").join("000000.ply");
            std::fs::create_dir_all(self.w.join(s)).unwrap();
            let mut motions: Vec<&str> = train.clone();
            if s == "A" {
                motions.push(common::TEST.0);
            }
            let seg = self.path(&format!("{s}/parts.seg"));
            run(
                "segment",
                &[
                    "-q",
                    p(&self.set.join(s).join("subject.json")),
                    "--template",
                    p(&tpl),
                    "--out",
                    p(&seg),
                ],
            );
            for m in &motions {
                let out = self.path(&format!("{s}/{m}.aligned"));
                run(
                    "align",
                    &[
                        "-q",
                        "--segmentation",
                        p(&seg),
                        "--subject",
                        p(&self.set.join(s).join("subject.json")),
                        "--template",
                        p(&tpl),
                        p(&self.set.join(s).join(m)),
                        "--out",
                        p(&out),
                    ],
                );
            }
            let aligned: Vec<String> = train
                .iter()
                .map(|m| p(&self.path(&format!("{s}/{m}.aligned"))).to_string())
                .collect();
            let mut args = vec!["-q", "--template", p(&tpl), "--segmentation", p(&seg), "--out"];
            let pca = self.path(&format!("{s}/pca.model"));
            args.push(p(&pca));
            args.extend(aligned.iter().map(|s| s.as_str()));
            run("pca-fit", &args);
            let whole = self.path(&format!("{s}/pca-whole.model"));
            let mut args = vec![
                "-q",
                "--whole-body",
                "--template",
                p(&tpl),
                "--out",
                p(&whole),
            ];
            args.extend(aligned.iter().map(|s| s.as_str()));
            run("pca-fit", &args);
        }
        for m in &train {
            let corr = self.path(&format!("{m}.corr"));
            run(
                "dtw-densify",
                &[
                    "-q",
                    "--set",
                    p(&self.set),
                    "--motion",
                    m,
                    "--source-pca",
                    p(&self.path("A/pca.model")),
                    "--target-pca",
                    p(&self.path("B/pca.model")),
                    p(&self.path(&format!("A/{m}.aligned"))),
                    p(&self.path(&format!("B/{m}.aligned"))),
                    "--out",
                    p(&corr),
                ],
            );
            pairs.extend([
                "--pair".to_string(),
                p(&self.path(&format!("A/{m}.aligned"))).to_string(),
                p(&self.path(&format!("B/{m}.aligned"))).to_string(),
                p(&corr).to_string(),
            ]);
        }
        pairs
    }
}

/// The error of standing still in the rest pose at the true world poses:
/// what a transfer that learnt nothing about the pose would score.
fn rest_pose_error(truth: &MeshSequence) -> f64 {
    let b = common::body_b();
    let rest = MeshSequence::new(
        truth.faces.clone(),
        vec![b.mesh.vertices.clone(); truth.n_frames()],
    );
    rms_errors(&rest, truth).unwrap().0
}

#[test]
fn transfer_pipeline_on_a_known_synthetic_set() {
    // TRANSFER_TEST_DIR=<dir> keeps the set and the outputs for inspection.
    let tmp = tempfile::tempdir().unwrap();
    let root = std::env::var_os("TRANSFER_TEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| tmp.path().to_path_buf());
    let work = Work {
        set: root.join("set"),
        w: root.join("work"),
    };
    common::write_set(&work.set);
    let pairs = work.prepare();
    let pair_args: Vec<&str> = pairs.iter().map(|s| s.as_str()).collect();
    let truth_dir = work.set.join("truth/B").join(common::TEST.0);
    let truth = MeshSequence::load_dir(&truth_dir).unwrap();
    let baseline = rest_pose_error(&truth);

    let mut results: Vec<EvalRecord> = Vec::new();
    for method in ["gpr-nn", "gpr-linear", "keypose-affine"] {
        let model = work.path(&format!("{method}.model"));
        let mut args = vec![
            "-q",
            "--method",
            method,
            "--source-pca",
            p(&work.path("A/pca.model")).to_owned().leak(),
            "--target-pca",
            p(&work.path("B/pca.model")).to_owned().leak(),
            "--out",
            p(&model).to_owned().leak(),
        ];
        args.extend(&pair_args);
        run("gpr-train", &args);
        for placement in ["regressed", "scaled-source", "blended"] {
            let out = work.path(&format!("out/{method}/{placement}"));
            run(
                "gpr-predict",
                &[
                    "-q",
                    "--model",
                    p(&model),
                    "--source-pca",
                    p(&work.path("A/pca.model")),
                    "--target-pca",
                    p(&work.path("B/pca.model")),
                    "--target-template",
                    p(&work.set.join("B/walk/000000.ply")),
                    "--placement",
                    placement,
                    p(&work.path(&format!("A/{}.aligned", common::TEST.0))),
                    "--out",
                    p(&out),
                ],
            );
            let pred = MeshSequence::load_dir(&out).unwrap();
            assert_eq!(
                pred.n_frames(),
                common::N_SOURCE,
                "one output frame per source frame"
            );
            assert_eq!(pred.faces, truth.faces, "the target's topology");
            let json = run(
                "transfer-eval",
                &[
                    "-q",
                    p(&out),
                    p(&truth_dir),
                    "--direction",
                    "A->B",
                    "--motion",
                    common::TEST.0,
                    "--method",
                    method,
                    "--placement",
                    placement,
                ],
            );
            results.push(serde_json::from_str(&json).unwrap());
        }
    }
    for r in &results {
        eprintln!(
            "{} {:<15} {:<14} pose {:.4} m placed {:.4} m",
            r.direction, r.method, r.placement, r.rms_pose_m.unwrap(), r.rms_placed_m.unwrap()
        );
    }
    eprintln!("rest-pose baseline: {baseline:.4} m");
    let get = |m: &str, pl: &str| {
        results
            .iter()
            .find(|r| r.method == m && r.placement == pl)
            .unwrap()
    };
    let nn = get("gpr-nn", "regressed");
    // The pose transfer must explain most of the deformation the rest pose misses.
    assert!(
        nn.rms_pose_m.unwrap() < 0.3 * baseline,
        "gpr-nn pose error {} vs rest pose {baseline}",
        nn.rms_pose_m.unwrap()
    );
    // Placement: the integrated displacements must follow the truth's path far
    // better than not travelling at all (the RMS distance of the truth's
    // centroid from where it starts, about 1 m here). The synthetic bodies'
    // large bends make the whole-body alignment wobble, which the
    // displacement-to-displacement GP cannot fully predict: errors of ~0.1 m.
    let centroid =
        |f: &Vec<nalgebra::Vector3<f64>>| f.iter().sum::<nalgebra::Vector3<f64>>() / f.len() as f64;
    let c0 = centroid(&truth.frames[0]);
    let travel = (truth
        .frames
        .iter()
        .map(|f| (centroid(f) - c0).norm_squared())
        .sum::<f64>()
        / truth.n_frames() as f64)
        .sqrt();
    eprintln!("truth travel (RMS centroid distance from start): {travel:.4} m");
    for pl in ["regressed", "scaled-source", "blended"] {
        let r = get("gpr-nn", pl);
        assert!(
            r.rms_placed_m.unwrap() < 0.25 * travel,
            "{pl}: placed error {} vs travel {travel}",
            r.rms_placed_m.unwrap()
        );
    }
    // The pose is the same whatever the placement.
    assert!((get("gpr-nn", "blended").rms_pose_m.unwrap() - nn.rms_pose_m.unwrap()).abs() < 1e-9);

    // Paper section 6 after gpr-nn: correction (M = 3) and stitching give the
    // target's topology, one frame per source frame, and do not lose the pose.
    let training: Vec<String> = common::TRAIN
        .iter()
        .map(|(m, _)| p(&work.path(&format!("B/{m}.aligned"))).to_string())
        .collect();
    for surface in ["correct", "correct-stitch"] {
        let out = work.path(&format!("out/gpr-nn+{surface}"));
        let mut args = vec![
            "-q",
            "--model",
            p(&work.path("gpr-nn.model")).to_owned().leak(),
            "--source-pca",
            p(&work.path("A/pca.model")).to_owned().leak(),
            "--target-pca",
            p(&work.path("B/pca.model")).to_owned().leak(),
            "--target-template",
            p(&work.set.join("B/walk/000000.ply")).to_owned().leak(),
            "--surface",
            surface,
            "--segmentation",
            p(&work.path("B/parts.seg")).to_owned().leak(),
        ];
        for t in &training {
            args.extend(["--target-training", t.as_str()]);
        }
        let motion = p(&work.path(&format!("A/{}.aligned", common::TEST.0))).to_owned();
        args.extend([motion.as_str(), "--out", p(&out)]);
        run("gpr-predict", &args);
        let pred = MeshSequence::load_dir(&out).unwrap();
        assert_eq!(pred.n_frames(), common::N_SOURCE);
        assert_eq!(pred.faces, truth.faces);
        let (pose, _) = transfer::evaluate::rms_errors(&pred, &truth).unwrap();
        eprintln!(
            "gpr-nn+{surface}: pose {pose:.4} m (gpr-nn {:.4} m)",
            nn.rms_pose_m.unwrap()
        );
        assert!(
            pose < 1.5 * nn.rms_pose_m.unwrap() + 1e-3,
            "{surface}: pose error {pose} vs gpr-nn {}",
            nn.rms_pose_m.unwrap()
        );
    }

    // Reverse direction trains from the same pairs and predicts B's frames onto A.
    let model = work.path("rev.model");
    let mut args = vec![
        "-q",
        "--reverse",
        "--source-pca",
        p(&work.path("B/pca.model")).to_owned().leak(),
        "--target-pca",
        p(&work.path("A/pca.model")).to_owned().leak(),
        "--out",
        p(&model).to_owned().leak(),
    ];
    args.extend(&pair_args);
    run("gpr-train", &args);
    let out = work.path("out/rev");
    run(
        "gpr-predict",
        &[
            "-q",
            "--model",
            p(&model),
            "--source-pca",
            p(&work.path("B/pca.model")),
            "--target-pca",
            p(&work.path("A/pca.model")),
            "--target-template",
            p(&work.set.join("A/walk/000000.ply")),
            p(&work.path("B/walk.aligned")),
            "--out",
            p(&out),
        ],
    );
    // B's walk (61 frames) mapped back onto A: A's own walk at the matching frames.
    let pred = MeshSequence::load_dir(&out).unwrap();
    assert_eq!(pred.n_frames(), 2 * common::N_SOURCE - 1);
    let a_walk = MeshSequence::load_dir(work.set.join("A/walk")).unwrap();
    let matched = MeshSequence::new(
        a_walk.faces.clone(),
        (0..pred.n_frames())
            .step_by(2)
            .map(|j| pred.frames[j].clone())
            .collect(),
    );
    let (pose, _) = rms_errors(&matched, &a_walk).unwrap();
    assert!(
        pose < 0.02,
        "reverse transfer of a training motion: pose error {pose}"
    );
}

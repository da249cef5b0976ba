//! The bad-input matrix: every row builds one bad input (or a valid input in
//! the wrong combination), runs one stage on it and checks the README's
//! promise: the expected exit code, exactly one line `stage: ...` on stderr
//! matching the row's pattern, no control bytes, no panic, and no output left
//! under the output name. Also: the same inputs give the same output bytes for
//! `--threads 1` and `2`, and for `-v` and `-q` (payloads compared; the header
//! records the command line).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use mesh_core::artifact::Artifact;
use mesh_core::segmentation::Segmentation;
use capture::align::AlignedMotion;
use capture::part_pca::PcaModel;

/// Inputs shared by the rows: the synthetic set, A's and B's segmentations,
/// aligned motions and PCA models.
struct Base {
    _dir: tempfile::TempDir,
    root: PathBuf,
}

impl Base {
    fn p(&self, rel: &str) -> String {
        self.root.join(rel).to_str().unwrap().to_string()
    }
}

fn base() -> &'static Base {
    static BASE: OnceLock<Base> = OnceLock::new();
    BASE.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().to_path_buf();
        common::write_set(&root.join("set"));
        let b = Base { _dir: dir, root };
        // Subject x's motion m aligned to the template `x/walk/<frame>.ply`, as `<out>.aligned`.
        let align = |x: &str, m: &str, frame: &str, out: &str| {
            common::run(
                "align",
                &["-q", "--segmentation", &b.p(&format!("{x}.seg")), "--subject", &b.p(&format!("set/{x}/subject.json")), "--template",
                  &b.p(&format!("set/{x}/walk/{frame}.ply")), &b.p(&format!("set/{x}/{m}")), "--out", &b.p(&format!("{out}.aligned"))],
            );
        };
        for s in ["A", "B"] {
            let tpl = b.p(&format!("set/{s}/walk/000000.ply"));
            common::run(
                "segment",
                &["-q", &b.p(&format!("set/{s}/subject.json")), "--template", &tpl, "--out", &b.p(&format!("{s}.seg"))],
            );
            for m in ["walk", "run"] {
                align(s, m, "000000", &format!("{s}-{m}"));
            }
            common::run(
                "pca-fit",
                &["-q", "--template", &tpl, "--segmentation", &b.p(&format!("{s}.seg")), "--out",
                  &b.p(&format!("{s}.pca")), &b.p(&format!("{s}-walk.aligned")), &b.p(&format!("{s}-run.aligned"))],
            );
        }
        // Same topology, another template: A's and B's walks aligned to their second walk frame
        // (as a second subject of one body model would be).
        for x in ["A", "B"] {
            align(x, "walk", "000001", &format!("{x}1-walk"));
        }
        common::run(
            "pca-fit",
            &["-q", "--template", &b.p("set/A/walk/000001.ply"), "--segmentation", &b.p("A.seg"), "--out", &b.p("A1.pca"), &b.p("A1-walk.aligned")],
        );
        common::run(
            "dtw-densify",
            &["-q", "--set", &b.p("set"), "--motion", "walk", "--source-pca", &b.p("A.pca"), "--target-pca", &b.p("B.pca"),
              "--out", &b.p("walk.corr"), &b.p("A-walk.aligned"), &b.p("B-walk.aligned")],
        );
        common::run(
            "gpr-train",
            &["-q", "--source-pca", &b.p("A.pca"), "--target-pca", &b.p("B.pca"), "--max-iter", "5", "--pair", &b.p("A-walk.aligned"),
              &b.p("B-walk.aligned"), &b.p("walk.corr"), "--out", &b.p("A-B.model")],
        );
        b
    })
}

/// One row of the matrix.
struct Case {
    name: &'static str,
    /// Writes the row's bad input into the case folder; returns the arguments.
    build: fn(&Base, &Path) -> Vec<String>,
    stage: &'static str,
    code: i32,
    /// Every fragment must appear in the error line.
    pattern: &'static [&'static str],
}

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

/// A copy of A's walk motion folder in `dir/motion` with frame 3 replaced by `bytes`.
fn motion_with_frame(b: &Base, dir: &Path, name: &str, bytes: &[u8]) -> String {
    let m = dir.join("motion");
    std::fs::create_dir_all(&m).unwrap();
    for e in std::fs::read_dir(b.root.join("set/A/walk")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), m.join(e.file_name())).unwrap();
    }
    std::fs::remove_file(m.join("000003.ply")).unwrap();
    std::fs::write(m.join(name), bytes).unwrap();
    s(&m)
}

/// `hmc-sample` arguments with `extra` (the model and group are never read: the rows that use
/// it are usage errors).
fn hmc_args(dir: &Path, extra: &[&str]) -> Vec<String> {
    let mut a: Vec<String> = vec!["-q".into(), "--model".into(), s(&dir.join("x.model")), "--group".into(), s(&dir.join("x.group")),
        "--out".into(), s(&dir.join("out"))];
    a.extend(extra.iter().map(|x| x.to_string()));
    a
}

/// `align` arguments for the motion folder `motion`, output `dir/out.aligned`.
fn align_args(b: &Base, dir: &Path, motion: String) -> Vec<String> {
    vec![
        "-q".into(), "--segmentation".into(), b.p("A.seg"), "--subject".into(), b.p("set/A/subject.json"),
        "--template".into(), b.p("set/A/walk/000000.ply"), motion, "--out".into(), s(&dir.join("out.aligned")),
    ]
}

/// A copy of A's `subject.json` in `dir` with `"fps"` set to `fps` (JSON number text).
fn subject_with_fps(b: &Base, dir: &Path, fps: &str) -> String {
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(b.root.join("set/A/subject.json")).unwrap()).unwrap();
    v["fps"] = serde_json::from_str(fps).unwrap();
    let path = dir.join("subject.json");
    std::fs::write(&path, v.to_string()).unwrap();
    s(&path)
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

/// `pca-fit` of A on `aligned` (its template and parts), output `dir/out.pca`.
fn pca_args(b: &Base, dir: &Path, parts: String, aligned: String) -> Vec<String> {
    vec![
        "-q".into(), "--template".into(), b.p("set/A/walk/000000.ply"), "--segmentation".into(), parts,
        "--out".into(), s(&dir.join("out.pca")), aligned,
    ]
}

/// Saves `value` under `dir/name` with a valid checksum (the writer does not validate).
fn rewrite<T: Artifact>(dir: &Path, name: &str, value: &T) -> String {
    let p = dir.join(name);
    value.save(&p, &mesh_core::artifact::Header::new("crafted", "0")).unwrap();
    s(&p)
}

/// `dtw-densify` of the walk pair with the given source motion and PCA.
fn dtw_args(b: &Base, dir: &Path, source: String, source_pca: String) -> Vec<String> {
    vec![
        "-q".into(), "--set".into(), b.p("set"), "--motion".into(), "walk".into(),
        "--source-pca".into(), source_pca, "--target-pca".into(), b.p("B.pca"),
        "--out".into(), s(&dir.join("out.corr")), source, b.p("B-walk.aligned"),
    ]
}

/// `gpr-train` A -> B on the walk pair with the given source PCA, output `dir/out.model`.
fn train_args(b: &Base, dir: &Path, source_pca: String) -> Vec<String> {
    vec![
        "-q".into(), "--source-pca".into(), source_pca, "--target-pca".into(), b.p("B.pca"), "--max-iter".into(), "5".into(),
        "--pair".into(), b.p("A-walk.aligned"), b.p("B-walk.aligned"), b.p("walk.corr"), "--out".into(), s(&dir.join("out.model")),
    ]
}

/// `gpr-predict` of A's run with the A -> B model, the given PCAs and target template, output `dir/out`.
fn predict_args(b: &Base, dir: &Path, source_pca: String, target_template: String) -> Vec<String> {
    vec![
        "-q".into(), "--model".into(), b.p("A-B.model"), "--source-pca".into(), source_pca, "--target-pca".into(), b.p("B.pca"),
        "--target-template".into(), target_template, b.p("A-run.aligned"), "--out".into(), s(&dir.join("out")),
    ]
}

fn cases() -> Vec<Case> {
    vec![
        // ---- PLY frames
        Case { name: "ply truncated payload", stage: "align", code: 1, pattern: &["000003.ply"],
            build: |b, d| { let mut x = std::fs::read(b.root.join("set/A/walk/000003.ply")).unwrap(); x.truncate(x.len() / 2);
                align_args(b, d, motion_with_frame(b, d, "000003.ply", &x)) } },
        Case { name: "ply escape bytes in the header", stage: "align", code: 1, pattern: &["000003.ply", "\\x1b"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty fl\x1b[2J\x1b]0;owned\x07 x\nend_header\n")) },
        Case { name: "ply NaN coordinate", stage: "align", code: 1, pattern: &["000003.ply", "nan"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.ply", format!("{PLY_HEAD}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").as_bytes())) },
        Case { name: "ply face index out of range", stage: "align", code: 1, pattern: &["000003.ply", "vertex 7"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.ply", format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").as_bytes())) },
        Case { name: "ply of another vertex count", stage: "align", code: 1, pattern: &["000003.ply", "vertices"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.ply", format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").as_bytes())) },
        Case { name: "ply with no vertices", stage: "align", code: 1, pattern: &["000003.ply", "no vertices"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.ply", b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n")) },
        Case { name: "ply huge vertex count", stage: "align", code: 1, pattern: &["000003.ply"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0")) },
        Case { name: "frame is a FIFO", stage: "align", code: 1, pattern: &["000003.ply", "FIFO"],
            build: |b, d| { let m = motion_with_frame(b, d, "000003.ply", b""); let f = Path::new(&m).join("000003.ply");
                std::fs::remove_file(&f).unwrap(); assert!(Command::new("mkfifo").arg(&f).status().unwrap().success()); align_args(b, d, m) } },
        Case { name: "frame is a directory", stage: "align", code: 1, pattern: &["000003.ply", "directory"],
            build: |b, d| { let m = motion_with_frame(b, d, "000003.ply", b""); let f = Path::new(&m).join("000003.ply");
                std::fs::remove_file(&f).unwrap(); std::fs::create_dir(&f).unwrap(); align_args(b, d, m) } },
        Case { name: "frame missing in the numbering", stage: "align", code: 1, pattern: &["motion", "000003"],
            build: |b, d| { let m = motion_with_frame(b, d, "notes.txt", b""); align_args(b, d, m) } },
        // ---- OBJ frames
        Case { name: "obj index 0", stage: "align", code: 1, pattern: &["000003.obj", "index 0"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")) },
        Case { name: "obj malformed exponent", stage: "align", code: 1, pattern: &["000003.obj", "3.1+e2"],
            build: |b, d| align_args(b, d, motion_with_frame(b, d, "000003.obj", b"v 3.1+e2 0 0\n")) },
        // ---- capture set
        Case { name: "subject.json not JSON", stage: "segment", code: 1, pattern: &["subject.json", "JSON"],
            build: |b, d| { std::fs::write(d.join("subject.json"), "{\"fps\": 25,").unwrap();
                vec!["-q".into(), s(&d.join("subject.json")), "--template".into(), b.p("set/A/walk/000000.ply"), "--out".into(), s(&d.join("out.seg"))] } },
        Case { name: "curve index out of range", stage: "segment", code: 1, pattern: &["99999"],
            build: |b, d| { std::fs::write(d.join("subject.json"), r#"{"fps": 25, "parts": {"torso": null, "limb": "torso"}, "curves": {"limb": [[0, 1, 99999], [5, 6, 7]]}}"#).unwrap();
                vec!["-q".into(), s(&d.join("subject.json")), "--template".into(), b.p("set/A/walk/000000.ply"), "--out".into(), s(&d.join("out.seg"))] } },
        Case { name: "subject.json frame rate 1e-300", stage: "align", code: 1, pattern: &["subject.json", "frame rate 1e-300 fps is outside 1 to 10000 fps"],
            build: |b, d| { let subject = subject_with_fps(b, d, "1e-300");
                let mut args = align_args(b, d, b.p("set/A/walk")); args[4] = subject; args } },
        Case { name: "subject.json frame rate 1e300 in check-set", stage: "check-set", code: 1, pattern: &["subject.json", "frame rate 1e300 fps is outside"],
            build: |b, d| { let set = d.join("set");
                assert!(Command::new("cp").arg("-r").arg(b.root.join("set")).arg(&set).status().unwrap().success());
                std::fs::copy(subject_with_fps(b, d, "1e300"), set.join("A/subject.json")).unwrap();
                vec!["-q".into(), s(&set)] } },
        Case { name: "rate.json frame rate 1e300", stage: "mesh-export", code: 1, pattern: &["rate.json", "frame rate 1e300 fps is outside"],
            build: |b, d| { let m = motion_with_frame(b, d, "rate.json", br#"{"fps": 1e300}"#);
                std::fs::copy(b.root.join("set/A/walk/000003.ply"), Path::new(&m).join("000003.ply")).unwrap();
                vec!["-q".into(), m, "--out".into(), s(&d.join("out.glb"))] } },
        Case { name: "mesh-export --fps 1e-300", stage: "mesh-export", code: 1, pattern: &["--fps", "frame rate 1e-300 fps is outside"],
            build: |b, d| vec!["-q".into(), b.p("set/A/walk"), "--fps".into(), "1e-300".into(), "--out".into(), s(&d.join("out.usda"))] },
        Case { name: "subject.json missing", stage: "segment", code: 1, pattern: &["subject.json", "No such file"],
            build: |b, d| vec!["-q".into(), s(&d.join("subject.json")), "--template".into(), b.p("set/A/walk/000000.ply"), "--out".into(), s(&d.join("out.seg"))] },
        // ---- artifacts
        Case { name: "aligned motion truncated", stage: "pca-fit", code: 1, pattern: &["bad.aligned", "truncated"],
            build: |b, d| { let x = std::fs::read(b.root.join("A-walk.aligned")).unwrap(); std::fs::write(d.join("bad.aligned"), &x[..x.len() / 3]).unwrap();
                pca_args(b, d, b.p("A.seg"), s(&d.join("bad.aligned"))) } },
        Case { name: "aligned motion flipped byte", stage: "pca-fit", code: 1, pattern: &["bad.aligned", "checksum"],
            build: |b, d| { let mut x = std::fs::read(b.root.join("A-walk.aligned")).unwrap(); let k = x.len() - 100; x[k] ^= 1; std::fs::write(d.join("bad.aligned"), &x).unwrap();
                pca_args(b, d, b.p("A.seg"), s(&d.join("bad.aligned"))) } },
        Case { name: "not an artifact", stage: "pca-fit", code: 1, pattern: &["bad.aligned", "magic"],
            build: |b, d| { std::fs::write(d.join("bad.aligned"), b"hello").unwrap(); pca_args(b, d, b.p("A.seg"), s(&d.join("bad.aligned"))) } },
        Case { name: "wrong artifact kind", stage: "pca-fit", code: 1, pattern: &["A.seg", "expected artifact kind"],
            build: |b, d| pca_args(b, d, b.p("A.seg"), b.p("A.seg")) },
        Case { name: "segmentation index rewritten, checksum recomputed", stage: "pca-fit", code: 1, pattern: &["bad.seg", "invalid 'segmentation' payload"],
            build: |b, d| { let mut seg = Segmentation::load(b.root.join("A.seg")).unwrap(); seg.parts[1].vertices.push(1 << 30);
                pca_args(b, d, rewrite(d, "bad.seg", &seg), b.p("A-walk.aligned")) } },
        Case { name: "segmentation of 20M empty loops", stage: "pca-fit", code: 1, pattern: &["bad.seg", "invalid"],
            build: |b, d| { let mut seg = Segmentation::load(b.root.join("A.seg")).unwrap(); seg.parts[0].loops = vec![Vec::new(); 2_000_000]; seg.parts[0].vertices.push(1 << 30);
                pca_args(b, d, rewrite(d, "bad.seg", &seg), b.p("A-walk.aligned")) } },
        Case { name: "aligned faces rewritten, checksum recomputed", stage: "pca-fit", code: 1, pattern: &["bad.aligned", "invalid 'aligned-motion' payload"],
            build: |b, d| { let mut m = AlignedMotion::load(b.root.join("A-walk.aligned")).unwrap(); m.faces[0][0] = u32::MAX;
                pca_args(b, d, b.p("A.seg"), rewrite(d, "bad.aligned", &m)) } },
        Case { name: "aligned frame shortened, checksum recomputed", stage: "pca-fit", code: 1, pattern: &["bad.aligned", "frame 2"],
            build: |b, d| { let mut m = AlignedMotion::load(b.root.join("A-walk.aligned")).unwrap(); m.frames[2].truncate(5);
                pca_args(b, d, b.p("A.seg"), rewrite(d, "bad.aligned", &m)) } },
        Case { name: "pca model index rewritten, checksum recomputed", stage: "dtw-densify", code: 1, pattern: &["bad.pca", "invalid 'pca-model' payload"],
            build: |b, d| { let mut m = PcaModel::load(b.root.join("A.pca")).unwrap(); m.parts[1].vertices[0] = 1 << 30;
                dtw_args(b, d, b.p("A-walk.aligned"), rewrite(d, "bad.pca", &m)) } },
        // ---- valid files in the wrong combination
        Case { name: "motion with fewer vertices than the PCA", stage: "dtw-densify", code: 1, pattern: &["A-walk.aligned", "vertices", "PCA model"],
            build: |b, d| dtw_args(b, d, b.p("A-walk.aligned"), b.p("B.pca")) },
        Case { name: "motion with more vertices than the PCA", stage: "dtw-densify", code: 1, pattern: &["B-walk.aligned", "vertices", "PCA model"],
            build: |b, d| dtw_args(b, d, b.p("B-walk.aligned"), b.p("A.pca")) },
        Case { name: "pca-fit on another subject's motions", stage: "pca-fit", code: 1, pattern: &["B-walk.aligned", "aligned to template"],
            build: |b, d| pca_args(b, d, b.p("A.seg"), b.p("B-walk.aligned")) },
        Case { name: "pca-fit on motions aligned to another template of the same topology", stage: "pca-fit", code: 1,
            pattern: &["A1-walk.aligned", "the motion was aligned to template", "--template is template"],
            build: |b, d| pca_args(b, d, b.p("A.seg"), b.p("A1-walk.aligned")) },
        Case { name: "PCA of another template of the same topology (dtw-densify)", stage: "dtw-densify", code: 1,
            pattern: &["A-walk.aligned", "the PCA model was fitted on template"],
            build: |b, d| dtw_args(b, d, b.p("A-walk.aligned"), b.p("A1.pca")) },
        Case { name: "PCA of another template of the same topology (gpr-train)", stage: "gpr-train", code: 1,
            pattern: &["A-walk.aligned", "the PCA model was fitted on template"],
            build: |b, d| train_args(b, d, b.p("A1.pca")) },
        Case { name: "misspelt attached limb (gpr-train)", stage: "gpr-train", code: 1,
            pattern: &["attached limb 'arm_x' is not a limb of the PCA models"],
            build: |b, d| { let mut a = train_args(b, d, b.p("A.pca")); a.extend(["--attached-limbs".into(), "limb,arm_x".into()]); a } },
        Case { name: "PCA of another template than the transfer model's (gpr-predict)", stage: "gpr-predict", code: 1,
            pattern: &["A-B.model", "A1.pca", "the transfer model was trained with template"],
            build: |b, d| predict_args(b, d, b.p("A1.pca"), b.p("set/B/walk/000000.ply")) },
        Case { name: "target template other than the target PCA's (gpr-predict)", stage: "gpr-predict", code: 1,
            pattern: &["000001.ply", "the target PCA model was fitted on template"],
            build: |b, d| predict_args(b, d, b.p("A.pca"), b.p("set/B/walk/000001.ply")) },
        Case { name: "surface training motions of another template (gpr-predict --surface)", stage: "gpr-predict", code: 1,
            pattern: &["B1-walk.aligned", "the PCA model was fitted on template"],
            build: |b, d| { let mut a = predict_args(b, d, b.p("A.pca"), b.p("set/B/walk/000000.ply"));
                a.extend(["--surface".into(), "correct".into(), "--segmentation".into(), b.p("B.seg"), "--target-training".into(), b.p("B1-walk.aligned")]); a } },
        Case { name: "pca-fit with another subject's parts", stage: "pca-fit", code: 1, pattern: &["segmentation"],
            build: |b, d| pca_args(b, d, b.p("B.seg"), b.p("A-walk.aligned")) },
        // ---- outputs
        Case { name: "output is an existing directory", stage: "pca-fit", code: 1, pattern: &["out.pca", "directory"],
            build: |b, d| { std::fs::create_dir(d.join("out.pca")).unwrap(); std::fs::write(d.join("out.pca/keep"), "x").unwrap();
                pca_args(b, d, b.p("A.seg"), b.p("A-walk.aligned")) } },
        Case { name: "output folder parent is a file", stage: "pca-fit", code: 1, pattern: &["file"],
            build: |b, d| { std::fs::write(d.join("file"), "x").unwrap(); let mut a = pca_args(b, d, b.p("A.seg"), b.p("A-walk.aligned"));
                let k = a.iter().position(|x| x == "--out").unwrap(); a[k + 1] = s(&d.join("file/out.pca")); a } },
        // ---- usage
        Case { name: "unknown flag", stage: "pca-fit", code: 2, pattern: &["--frobnicate"],
            build: |b, d| { let mut a = pca_args(b, d, b.p("A.seg"), b.p("A-walk.aligned")); a.push("--frobnicate".into()); a } },
        Case { name: "missing --out", stage: "pca-fit", code: 2, pattern: &["--out"],
            build: |b, _| vec!["--template".into(), b.p("set/A/walk/000000.ply"), b.p("A-walk.aligned")] },
        Case { name: "--threads 0", stage: "pca-fit", code: 2, pattern: &["threads"],
            build: |b, d| { let mut a = pca_args(b, d, b.p("A.seg"), b.p("A-walk.aligned")); a.push("--threads".into()); a.push("0".into()); a } },
        Case { name: "hmc-sample --thin 0", stage: "hmc-sample", code: 2, pattern: &["--thin"],
            build: |_, d| hmc_args(d, &["--thin", "0"]) },
        Case { name: "hmc-sample -n 0", stage: "hmc-sample", code: 2, pattern: &["-n"],
            build: |_, d| hmc_args(d, &["-n", "0"]) },
        Case { name: "hmc-sample --frame-count 1", stage: "hmc-sample", code: 2, pattern: &["--frame-count"],
            build: |_, d| hmc_args(d, &["--frame-count", "1"]) },
        Case { name: "bad enum value", stage: "align", code: 2, pattern: &["--frame"],
            build: |b, d| { let mut a = align_args(b, d, b.p("set/A/walk")); a.push("--frame".into()); a.push("torso".into()); a } },
    ]
}

/// Output names a row's stage may write: none of them may exist afterwards.
const OUTPUTS: [&str; 8] = ["out.aligned", "out.seg", "out.pca", "out.corr", "out.model", "out", "out.glb", "out.usda"];

/// Runs one row; returns a description of what broke the promise, if anything.
fn check(b: &Base, case: &Case) -> Option<String> {
    let dir = tempfile::tempdir().unwrap();
    let args = (case.build)(b, dir.path());
    let existing: Vec<bool> = OUTPUTS.iter().map(|o| dir.path().join(o).exists()).collect();
    let out = Command::new(common::bin(case.stage))
        .args(&args)
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let mut problems = Vec::new();
    if out.status.code() != Some(case.code) {
        problems.push(format!("exit {:?}, expected {}", out.status.code(), case.code));
    }
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    if case.code == 1 {
        if lines.len() != 1 {
            problems.push(format!("{} stderr lines", lines.len()));
        }
        if !lines.first().is_some_and(|l| l.starts_with(&format!("{}: ", case.stage))) {
            problems.push("the line does not start with the stage name".into());
        }
    }
    if err.contains("internal error") || err.contains("panicked") {
        problems.push("panic".into());
    }
    if err.chars().any(|c| c.is_control() && c != '\n') {
        problems.push("raw control bytes on stderr".into());
    }
    for frag in case.pattern {
        if !err.contains(frag) {
            problems.push(format!("message lacks '{frag}'"));
        }
    }
    for (o, before) in OUTPUTS.iter().zip(existing) {
        let p = dir.path().join(o);
        if p.exists() && !before {
            problems.push(format!("output {o} left behind"));
        }
    }
    let temps: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".surfcap-"))
        .collect();
    if !temps.is_empty() {
        problems.push(format!("temporaries left: {temps:?}"));
    }
    (!problems.is_empty()).then(|| format!("{}: {} (stderr: {})", case.name, problems.join("; "), err.trim()))
}

#[test]
fn every_bad_input_row_is_one_line_and_a_clean_exit() {
    let b = base();
    let cases = cases();
    let failures: Vec<String> = cases.iter().filter_map(|c| check(b, c)).collect();
    eprintln!("bad-input matrix: {}/{} rows handled", cases.len() - failures.len(), cases.len());
    assert!(failures.is_empty(), "{} of {} rows fail:\n{}", failures.len(), cases.len(), failures.join("\n"));
}

/// A full disk (a 64 KiB tmpfs, when this process may mount one): the
/// artifact write fails with one line and leaves nothing.
#[test]
fn full_disk_leaves_no_output() {
    on_a_small_tmpfs("size=64k", "out.pca", "No space left", pca_fit);
}

/// A read-only file system, for an artifact and for a frame folder: one line naming the output,
/// nothing written (root ignores a read-only directory's permissions; a read-only mount refuses
/// root too).
#[test]
fn read_only_file_system_leaves_no_output() {
    on_a_small_tmpfs("ro,size=64k", "out.pca", "Read-only file system", pca_fit);
    on_a_small_tmpfs("ro,size=64k", "run", "Read-only file system", |b, out| {
        let mut c = Command::new(common::bin("gpr-predict"));
        c.args(["-q", "--model", &b.p("A-B.model"), "--source-pca", &b.p("A.pca"), "--target-pca", &b.p("B.pca")])
            .args(["--target-template", &b.p("set/B/walk/000000.ply"), &b.p("A-run.aligned"), "--out"])
            .arg(out)
            .env("OPENBLAS_NUM_THREADS", "1");
        c
    });
}

/// `pca-fit` of two of the base's motions into `out`.
fn pca_fit(b: &Base, out: &Path) -> Command {
    let mut c = Command::new(common::bin("pca-fit"));
    c.args(["-q", "--template", &b.p("set/A/walk/000000.ply"), "--segmentation", &b.p("A.seg"), "--out"])
        .arg(out)
        .args([b.p("A-walk.aligned"), b.p("A-run.aligned")])
        .env("OPENBLAS_NUM_THREADS", "1");
    c
}

/// Runs `stage(base, mount/output)` with a tmpfs mounted with `options`: exit 1, one line naming
/// the output and containing `problem`, nothing left on the mount. Skipped where mounting is not
/// allowed.
fn on_a_small_tmpfs(options: &str, output: &str, problem: &str, stage: impl Fn(&Base, &Path) -> Command) {
    let b = base();
    let mnt = tempfile::tempdir().unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", options, "tmpfs"])
        .arg(mnt.path())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        eprintln!("a tmpfs with {options}: cannot mount one here, skipped");
        return;
    }
    struct Unmount<'a>(&'a Path);
    impl Drop for Unmount<'_> {
        fn drop(&mut self) {
            let _ = Command::new("umount").arg(self.0).status();
        }
    }
    let _guard = Unmount(mnt.path());
    let out_path = mnt.path().join(output);
    let out = stage(b, &out_path).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    let named = format!("{}: {problem}", out_path.display());
    assert!(err.contains(&named), "expected '{named}' in: {err}");
    assert!(!err.contains(".surfcap-"), "the line names a temporary: {err}");
    assert_eq!(std::fs::read_dir(mnt.path()).unwrap().count(), 0, "something left on the tmpfs");
}

/// `pca-fit` of two motions gives the same model for `--threads 1` and `2`,
/// and for `-v` and `-q`.
#[test]
fn pca_fit_is_independent_of_threads_and_verbosity() {
    let b = base();
    let dir = tempfile::tempdir().unwrap();
    let fit = |name: &str, flags: &[&str]| -> PcaModel {
        let out = s(&dir.path().join(name));
        let mut args: Vec<String> = flags.iter().map(|f| f.to_string()).collect();
        args.extend(["--template".into(), b.p("set/A/walk/000000.ply"), "--segmentation".into(), b.p("A.seg"), "--out".into(), out.clone(),
            b.p("A-walk.aligned"), b.p("A-run.aligned")]);
        common::run("pca-fit", &args);
        PcaModel::load(&out).unwrap()
    };
    let one = fit("t1.pca", &["-q", "--threads", "1"]);
    let two = fit("t2.pca", &["-q", "--threads", "2"]);
    let verbose = fit("v.pca", &["-v", "--threads", "2"]);
    // Bit-identical values (PartialEq on f64 compares exactly).
    assert!(one == two, "pca-fit depends on the thread count");
    assert!(one == verbose, "pca-fit depends on the verbosity");
}

/// `SURFCAP_VERBOSE` gives a `-q` command line the messages of `-v`, and the model's bytes do not
/// change with it or with the thread count (`RAYON_NUM_THREADS`, the default of `--threads`).
#[test]
fn surfcap_verbose_overrides_quiet_and_changes_no_output() {
    let b = base();
    let dir = tempfile::tempdir().unwrap();
    // One output path for both runs: the header records it.
    let train = |env: &[(&str, &str)]| -> (Vec<u8>, String) {
        let args = train_args(b, dir.path(), b.p("A.pca"));
        let out = Command::new(common::bin("gpr-train")).args(&args).envs(env.iter().copied()).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        (std::fs::read(dir.path().join("out.model")).unwrap(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (quiet, quiet_err) = train(&[("RAYON_NUM_THREADS", "2")]);
    let (verbose, verbose_err) = train(&[("RAYON_NUM_THREADS", "1"), ("SURFCAP_VERBOSE", "1")]);
    assert_eq!(quiet_err, "", "-q prints nothing on success");
    assert!(verbose_err.lines().any(|l| l.starts_with("gpr-train: trained")), "{verbose_err}");
    assert!(quiet == verbose, "gpr-train's model depends on the verbosity or thread count");
}

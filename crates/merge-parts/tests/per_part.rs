//! Per-part fits joined by `merge-parts` on the `tiny` preset of `synth` (needs the synth
//! assets, as `make test` does): for each of `pca-fit`, `gpr-train` and `gpdm-train`, every
//! part fitted alone (`--part`) and merged is byte-identical to the single-process run, and
//! `merge-parts` refuses a missing part, a duplicate part, pieces of another model and pieces
//! of another kind, each with one line naming the problem.
//!
//! The stages other than `merge-parts` are run from the folder cargo builds them into, so the
//! workspace's binaries must be built first (`cargo build --release --workspace`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A stage binary: this crate's own, or one next to this test's folder (`target/<profile>/deps/..`).
fn bin(name: &str) -> PathBuf {
    if name == "merge-parts" {
        return PathBuf::from(env!("CARGO_BIN_EXE_merge-parts"));
    }
    let exe = std::env::current_exe().unwrap();
    let path = exe.parent().and_then(|d| d.parent()).unwrap().join(name);
    assert!(path.is_file(), "{} is missing: build the workspace first (cargo build --release --workspace)", path.display());
    path
}

fn exec(name: &str, args: &[String]) -> Output {
    Command::new(bin(name)).args(args).env("OPENBLAS_NUM_THREADS", "1").output().unwrap()
}

/// Runs stage `name`; panics with its stderr on failure.
fn run(name: &str, args: &[String]) {
    let out = exec(name, args);
    assert!(out.status.success(), "{name} {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
}

/// Runs stage `name` expecting the bad-input exit (1) and a single line of stderr containing
/// every one of `needles`; returns that line.
fn fails(name: &str, args: &[String], needles: &[&str]) -> String {
    let out = exec(name, args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{name} {args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{name}: not one line: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: '{n}' missing from: {err}");
    }
    err
}

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|x| x.to_string()).collect()
}

/// The part names of a segmentation artifact.
fn part_names(seg: &Path) -> Vec<String> {
    use mesh_core::artifact::Artifact;
    mesh_core::segmentation::Segmentation::load(seg).unwrap().parts.into_iter().map(|p| p.name).collect()
}

/// A report's JSON without its measured times (keys starting with `seconds`), which differ
/// from run to run.
fn untimed(path: &Path) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|k, _| !k.starts_with("seconds"));
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    strip(&mut v);
    v
}

/// A report's text with the values of its measured times (`"seconds...": x`) masked: what must
/// be the whole run's byte for byte (the times themselves differ between runs, and so do their
/// lengths).
fn layout(text: &[u8]) -> String {
    String::from_utf8_lossy(text)
        .lines()
        .map(|line| match line.split_once(':') {
            Some((key, value)) if key.trim_start().starts_with("\"seconds") => {
                format!("{key}: #{}", if value.ends_with(',') { "," } else { "" })
            }
            _ => line.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Runs `stage args` once whole (to `whole`) and once per unit with `--part UNIT` (to
/// `whole.UNIT`), merges the pieces in reverse order and asserts the merged file is the whole
/// run's, byte for byte. With `reports`, every run also writes its `--report` (`<out>.json`)
/// and the merge joins the pieces' reports, which must be the whole run's but for measured
/// times. Returns the piece paths in unit order.
fn split_and_merge(stage: &str, args: &[String], whole: &Path, units: &[String], reports: bool) -> Vec<PathBuf> {
    let report_of = |out: &Path| PathBuf::from(format!("{}.json", out.display()));
    let with_out = |out: &Path| -> Vec<String> {
        let mut a = args.to_vec();
        a.extend(["--out".to_string(), s(out)]);
        if reports {
            a.extend(["--report".to_string(), s(&report_of(out))]);
        }
        a
    };
    run(stage, &with_out(whole));
    let pieces: Vec<PathBuf> = units.iter().map(|u| PathBuf::from(format!("{}.{u}", whole.display()))).collect();
    for (u, piece) in units.iter().zip(&pieces) {
        let mut a = with_out(piece);
        a.extend(["--part".to_string(), u.clone()]);
        run(stage, &a);
    }
    // The merge writes the whole model to the path the whole run wrote (the header records it).
    let w = std::fs::read(whole).unwrap();
    std::fs::remove_file(whole).unwrap();
    let whole_report = report_of(whole);
    let before = reports.then(|| (std::fs::read(&whole_report).unwrap(), untimed(&whole_report)));
    let mut a: Vec<String> = pieces.iter().rev().map(|p| s(p)).collect();
    a.extend(["--out".to_string(), s(whole)]);
    if reports {
        std::fs::remove_file(&whole_report).unwrap();
        for p in &pieces {
            a.extend(["--piece-report".to_string(), s(&report_of(p))]);
        }
        a.extend(["--report".to_string(), s(&whole_report)]);
    }
    run("merge-parts", &a);
    let m = std::fs::read(whole).unwrap();
    assert!(w == m, "{stage}: merged pieces ({} bytes) differ from the whole run ({} bytes)", m.len(), w.len());
    if let Some((bytes, json)) = before {
        assert_eq!(untimed(&whole_report), json, "{stage}: the joined report is not the whole run's");
        let joined = std::fs::read(&whole_report).unwrap();
        assert_eq!(layout(&joined), layout(&bytes), "{stage}: the joined report is not laid out as the whole run's");
        if stage == "pca-fit" {
            assert!(joined == bytes, "pca-fit: the joined report differs from the whole run's");
        }
        report_errors(&pieces.iter().map(|p| report_of(p)).collect::<Vec<_>>(), &pieces, &a);
    }
    // A piece is not the whole model: its consumers name the kind they expected.
    let (kind, _, header) = mesh_core::artifact::read_header(&pieces[0]).unwrap();
    assert!(kind.ends_with("-part"), "{kind}");
    assert_eq!(header.params["part"], units[0].as_str());
    pieces
}

/// The report-joining errors: a missing report, a report given twice, a report of the whole
/// model in place of a piece's. `merge` is the successful merge's arguments; nothing may be
/// written by a failing one.
fn report_errors(reports: &[PathBuf], pieces: &[PathBuf], merge: &[String]) {
    let dir = tempfile::tempdir().unwrap();
    let (out, report) = (dir.path().join("m.model"), dir.path().join("m.json"));
    let args = |rs: &[PathBuf]| -> Vec<String> {
        let mut a: Vec<String> = pieces.iter().map(|p| s(p)).collect();
        a.extend(["--out".to_string(), s(&out)]);
        for r in rs {
            a.extend(["--piece-report".to_string(), s(r)]);
        }
        a.extend(["--report".to_string(), s(&report)]);
        a
    };
    let rest = &reports[..reports.len() - 1];
    if !rest.is_empty() {
        fails("merge-parts", &args(rest), &["no report for part"]);
        let mut dup = reports.to_vec();
        dup.push(reports[0].clone());
        fails("merge-parts", &args(&dup), &[&s(&reports[0]), "is already"]);
    }
    let whole_report = &merge[merge.len() - 1];
    let mut bad = rest.to_vec();
    bad.push(PathBuf::from(whole_report));
    if reports.len() > 1 {
        fails("merge-parts", &args(&bad), &[whole_report, "not of one piece's part"]);
    }
    assert!(!out.exists() && !report.exists(), "a failed merge wrote its outputs");
}

/// The merge errors, on the pieces of one model.
fn merge_errors(pieces: &[PathBuf], foreign: &Path, other_kind: &Path, out: &Path) {
    let names = |ps: &[PathBuf]| -> Vec<String> {
        let mut a: Vec<String> = ps.iter().map(|p| s(p)).collect();
        a.extend(["--out".to_string(), s(out)]);
        a
    };
    // Missing part: the last piece left out.
    let (last, rest) = pieces.split_last().unwrap();
    let unit = last.extension().unwrap().to_str().unwrap();
    fails("merge-parts", &names(rest), &["no piece for part", unit]);
    // Duplicate part: the first piece twice.
    let mut dup = pieces.to_vec();
    dup.push(pieces[0].clone());
    fails("merge-parts", &names(&dup), &["is already in", &s(&pieces[0])]);
    // A piece of another model (other inputs) in place of one of this model's.
    let mut mixed = rest.to_vec();
    mixed.push(foreign.to_path_buf());
    fails("merge-parts", &names(&mixed), &[&s(foreign), "not a piece of the same model"]);
    // A piece of another kind.
    let mut kinds = pieces.to_vec();
    kinds.push(other_kind.to_path_buf());
    fails("merge-parts", &names(&kinds), &[&s(other_kind), "expected artifact kind"]);
    assert!(!out.exists(), "a failed merge wrote {}", out.display());
}

#[test]
fn parts_fitted_alone_and_merged_are_the_whole_run() {
    let dir = tempfile::tempdir().unwrap();
    let set = dir.path().join("set");
    let work = dir.path().join("work");
    let cfg = synth::preset::preset("tiny", 0, true).unwrap();
    synth::capture_set_writer::synthesise(&cfg, &set, false, &|_| {}, &|| {}).unwrap();
    let tpl = |x: &str| set.join(x).join("walk").join("000000.ply");
    let w = |rel: &str| work.join(rel);
    let train = ["walk", "run"];

    // pca-fit, per subject.
    let mut pca_pieces = Vec::new();
    for x in ["A", "B"] {
        std::fs::create_dir_all(work.join(x)).unwrap();
        let seg = w(&format!("{x}/parts.seg"));
        run("segment", &[s(&set.join(x).join("subject.json")), "--template".into(), s(&tpl(x)), "--out".into(), s(&seg)]);
        for m in train {
            run("align", &[
                "--segmentation".into(), s(&seg), "--subject".into(), s(&set.join(x).join("subject.json")),
                "--template".into(), s(&tpl(x)), s(&set.join(x).join(m)), "--out".into(), s(&w(&format!("{x}/{m}.aligned"))),
            ]);
        }
        let mut args = vec!["-q".into(), "--template".into(), s(&tpl(x)), "--segmentation".into(), s(&seg)];
        args.extend(train.iter().map(|m| s(&w(&format!("{x}/{m}.aligned")))));
        pca_pieces.push(split_and_merge("pca-fit", &args, &w(&format!("{x}/pca.model")), &part_names(&seg), true));
    }
    let seg_a = w("A/parts.seg");
    let known = part_names(&seg_a);
    let mut args = strings(&["--template", &s(&tpl("A")), "--segmentation", &s(&seg_a), &s(&w("A/walk.aligned"))]);
    args.extend(strings(&["--out", &s(&w("A/bad.model")), "--part", "tentacle"]));
    fails("pca-fit", &args, &[&s(&seg_a), "no part 'tentacle'", &known.join(", ")]);
    let whole_body = strings(&["--template", &s(&tpl("A")), "--whole-body", &s(&w("A/walk.aligned"))]);
    split_and_merge("pca-fit", &whole_body, &w("A/whole-body.model"), &strings(&["body"]), false);

    // gpr-train, on the merged PCA models (the same bytes as the whole ones).
    let (pca_a, pca_b) = (s(&w("A/pca.model")), s(&w("B/pca.model")));
    let mut args = strings(&["-q", "--source-pca", &pca_a, "--target-pca", &pca_b, "--max-iter", "15"]);
    for m in train {
        let corr = w(&format!("{m}.corr"));
        run("dtw-densify", &strings(&[
            "--set", &s(&set), "--motion", m, "--source-pca", &pca_a, "--target-pca", &pca_b,
            &s(&w(&format!("A/{m}.aligned"))), &s(&w(&format!("B/{m}.aligned"))), "--out", &s(&corr),
        ]));
        args.extend(strings(&["--pair", &s(&w(&format!("A/{m}.aligned"))), &s(&w(&format!("B/{m}.aligned"))), &s(&corr)]));
    }
    let mut units = known.clone();
    units.push("displacement".into());
    let gpr_pieces = split_and_merge("gpr-train", &args, &w("gpr.model"), &units, false);
    let mut with_report: Vec<String> = gpr_pieces.iter().map(|p| s(p)).collect();
    with_report.extend(strings(&["--out", &s(&w("never.model")), "--piece-report", &s(&w("A/pca.model.json")), "--report", &s(&w("never.json"))]));
    fails("merge-parts", &with_report, &["have no reports", "gpr-model-part"]);
    // The same training with the walk pair alone: a piece of another model.
    let walk_only: Vec<String> = args[..args.len() - 4].to_vec();
    let mut bad = args.clone();
    bad.extend(strings(&["--out", &s(&w("bad.model")), "--part", "tentacle"]));
    fails("gpr-train", &bad, &["no part 'tentacle'", "displacement"]);

    // gpdm-train, on a prealigned group of subject A.
    let group = w("locomotion.group");
    run("prealign", &strings(&[
        "-q", "--set", &s(&set), "--segmentation", &s(&seg_a), "--group-name", "locomotion", "--blend-weights", "0.5", &s(&w("A/walk.aligned")),
        &s(&w("A/run.aligned")), "--out", &s(&group),
    ]));
    let args = strings(&["-q", "--group", &s(&group), "--max-iter", "20"]);
    let gpdm_pieces = split_and_merge("gpdm-train", &args, &w("locomotion.model"), &known, true);
    let mut bad = args.clone();
    bad.extend(strings(&["--out", &s(&w("bad.model")), "--part", "tentacle"]));
    fails("gpdm-train", &bad, &[&s(&group), "no part 'tentacle'"]);

    // Merge errors, per kind: the foreign piece is of the other subject's PCA model, of a GPR
    // model trained on fewer pairs, of a group prealigned with another blend weight.
    let out = w("never.model");
    merge_errors(&pca_pieces[0], &pca_pieces[1][0], &gpr_pieces[0], &out);
    let foreign = w("walk-only.model.piece");
    run("gpr-train", &{
        let mut a = walk_only;
        a.extend(strings(&["--out", &s(&foreign), "--part", &known[0]]));
        a
    });
    merge_errors(&gpr_pieces, &foreign, &gpdm_pieces[0], &out);
    let other_group = w("other.group");
    run("prealign", &strings(&[
        "-q", "--set", &s(&set), "--segmentation", &s(&seg_a), "--group-name", "locomotion", "--blend-weights", "0.25", &s(&w("A/walk.aligned")),
        &s(&w("A/run.aligned")), "--out", &s(&other_group),
    ]));
    let foreign = w("other.model.piece");
    run("gpdm-train", &strings(&["-q", "--group", &s(&other_group), "--max-iter", "20", "--part", &known[0], "--out", &s(&foreign)]));
    merge_errors(&gpdm_pieces, &foreign, &pca_pieces[0][0], &out);
    // Not a piece at all.
    fails("merge-parts", &strings(&[&s(&w("gpr.model")), "--out", &s(&out)]), &["is not a piece of a model", "pca-model-part"]);
}

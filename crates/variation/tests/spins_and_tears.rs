//! Variations a viewer accepts, on the tiny preset through the stage binaries: no frame turns
//! the whole body (or its heading about the vertical) faster than 1.25 × the captures' fastest
//! frame-to-frame turn, and none holds
//! an edge longer than 1.5 × the captures' longest (`variation::turns_and_tears`), under the
//! default sampler, `--sampler ancestral` and for blends. Also: a query the machine cannot hold
//! is refused in one line before sampling.

mod common;

use std::path::Path;

use common::{ok, stage, tiny_model};

/// Every spinning and torn frame of an `hmc-sample --report`, one line each.
fn spins_and_tears(report: &Path) -> Vec<String> {
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    let limits = &r["capture_limits"];
    assert!(limits["max_turn_deg"].as_f64().unwrap() > 0.0 && limits["max_edge_m"].as_f64().unwrap() > 0.0, "{limits}");
    let mut bad = Vec::new();
    for s in r["sequences"].as_array().unwrap() {
        let per = s["turns_and_tears"].as_array().unwrap();
        assert!(!per.is_empty(), "{}: no turns_and_tears", s["label"]);
        for (k, v) in per.iter().enumerate() {
            for kind in ["spinning_frames", "heading_spinning_frames", "torn_frames"] {
                let frames = v[kind].as_array().unwrap();
                if !frames.is_empty() {
                    bad.push(format!("{} var{k}: {kind} {frames:?} (max turn {} deg, captures' {limits})", s["label"], v["max_turn_deg"]));
                }
            }
        }
    }
    bad
}

#[test]
fn no_variation_of_the_tiny_preset_spins_or_tears_under_either_sampler_or_in_a_blend() {
    let dir = tempfile::tempdir().unwrap();
    let (group, model) = tiny_model(dir.path());
    let (g, m) = (group.to_string_lossy().into_owned(), model.to_string_lossy().into_owned());
    let mut bad = Vec::new();
    for (name, extra) in [
        ("hmc", vec!["--blends", "0.25,0.75"]),
        ("ancestral", vec!["--sampler", "ancestral", "--blends", "0.25,0.75"]),
        ("blend", vec!["--blend", "walk:run", "--weight", "0.3"]),
    ] {
        let (out, report) = (dir.path().join(name), dir.path().join(format!("{name}.json")));
        let mut args = vec!["-q", "--seed", "0", "-n", "5", "--variance-scale", "0.3", "--group", &g, "--model", &m];
        args.extend(extra);
        let (o, r) = (out.to_string_lossy().into_owned(), report.to_string_lossy().into_owned());
        args.extend(["--out", &o, "--report", &r]);
        ok(env!("CARGO_BIN_EXE_hmc-sample"), &args);
        bad.extend(spins_and_tears(&report).into_iter().map(|l| format!("{name}: {l}")));
    }
    assert!(bad.is_empty(), "{} variations spin or tear:\n{}", bad.len(), bad.join("\n"));

    // The turn limit touches only the variations it slows: every other one is the same bytes
    // as without it, and a slowed one keeps its frame count.
    let (free, report) = (dir.path().join("free"), dir.path().join("free.json"));
    let (o, r) = (free.to_string_lossy().into_owned(), report.to_string_lossy().into_owned());
    let args = ["-q", "--seed", "0", "-n", "5", "--variance-scale", "0.3", "--group", &g, "--model", &m];
    ok(env!("CARGO_BIN_EXE_hmc-sample"), &[&args[..], &["--sampler", "ancestral", "--blends", "0.25,0.75", "--no-turn-limit", "--out", &o, "--report", &r]].concat());
    let limited: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("ancestral.json")).unwrap()).unwrap();
    let mut compared = 0;
    for s in limited["sequences"].as_array().unwrap() {
        let label = s["label"].as_str().unwrap();
        for (k, v) in s["turns_and_tears"].as_array().unwrap().iter().enumerate() {
            let (a, b) = (dir.path().join("ancestral").join(label).join(format!("var{k}")), free.join(label).join(format!("var{k}")));
            let files = |d: &Path| -> Vec<Vec<u8>> {
                let mut names: Vec<_> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().path()).collect();
                names.sort();
                names.iter().map(|n| std::fs::read(n).unwrap()).collect()
            };
            let (fa, fb) = (files(&a), files(&b));
            assert_eq!(fa.len(), fb.len(), "{label} var{k}: frame count changed by the turn limit");
            if v["slowed_steps"].as_u64() == Some(0) {
                assert!(fa == fb, "{label} var{k}: not slowed, yet not the same bytes as without the turn limit");
                compared += 1;
            }
        }
    }
    assert!(compared > 0, "no variation left as sampled to compare");
}

/// The largest turn from the first frame of every variation of an `hmc-sample --report` and
/// the captures' own, with the frames past the course bound, one line per off-course variation.
fn off_course(report: &Path) -> Vec<String> {
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    let captures = r["capture_limits"]["max_course_turn_deg"].as_f64().unwrap();
    assert!(captures > 0.0, "{}", r["capture_limits"]);
    let mut bad = Vec::new();
    for s in r["sequences"].as_array().unwrap() {
        for (k, v) in s["turns_and_tears"].as_array().unwrap().iter().enumerate() {
            let frames = v["off_course_frames"].as_array().unwrap();
            if !frames.is_empty() {
                bad.push(format!("{} var{k}: {} frames off course, turned {:.0} deg from the start (captures {captures:.0})", s["label"], frames.len(), v["max_course_turn_deg"]));
            }
        }
    }
    bad
}

#[test]
fn no_variation_of_the_tiny_preset_turns_off_its_captures_course_under_either_sampler() {
    let dir = tempfile::tempdir().unwrap();
    let (group, model) = tiny_model(dir.path());
    let (g, m) = (group.to_string_lossy().into_owned(), model.to_string_lossy().into_owned());
    let mut bad = Vec::new();
    for (name, extra) in [("hmc", vec!["--blends", "0.25,0.75"]), ("ancestral", vec!["--sampler", "ancestral"])] {
        let (out, report) = (dir.path().join(name), dir.path().join(format!("{name}.json")));
        let (o, r) = (out.to_string_lossy().into_owned(), report.to_string_lossy().into_owned());
        let mut args = vec!["-q", "--seed", "0", "-n", "5", "--variance-scale", "0.3", "--group", &g, "--model", &m];
        args.extend(extra);
        args.extend(["--out", &o, "--report", &r]);
        ok(env!("CARGO_BIN_EXE_hmc-sample"), &args);
        bad.extend(off_course(&report).into_iter().map(|l| format!("{name}: {l}")));
    }
    assert!(bad.is_empty(), "{} variations go off course:\n{}", bad.len(), bad.join("\n"));
}

/// Without the course step (`--no-course`, the paper's integrated heading) the same query goes
/// off course: the check above can fail, and the step is what keeps the variations on course.
#[test]
fn without_the_course_step_the_tiny_presets_runs_go_off_course() {
    let dir = tempfile::tempdir().unwrap();
    let (group, model) = tiny_model(dir.path());
    let (g, m) = (group.to_string_lossy().into_owned(), model.to_string_lossy().into_owned());
    let (out, report) = (dir.path().join("out"), dir.path().join("r.json"));
    let (o, r) = (out.to_string_lossy().into_owned(), report.to_string_lossy().into_owned());
    ok(
        env!("CARGO_BIN_EXE_hmc-sample"),
        &["-q", "--seed", "0", "-n", "5", "--variance-scale", "0.3", "--motion", "run", "--no-course", "--group", &g, "--model", &m, "--out", &o, "--report", &r],
    );
    assert!(off_course(&report).len() >= 3, "{:?}", off_course(&report));
}

#[test]
fn a_frame_count_the_machine_cannot_hold_is_refused_in_one_line_before_sampling() {
    let dir = tempfile::tempdir().unwrap();
    let (group, model) = tiny_model(dir.path());
    let out = dir.path().join("out");
    let o = stage(
        env!("CARGO_BIN_EXE_hmc-sample"),
        &["-q", "--group", &group.to_string_lossy(), "--model", &model.to_string_lossy(), "--motion", "walk",
          "--frame-count", "1000000000", "--out", &out.to_string_lossy()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].starts_with("hmc-sample: ") && lines[0].contains("--frame-count 1000000000") && lines[0].contains("memory"), "{err}");
    assert!(!out.exists(), "no output for a refused query");
}

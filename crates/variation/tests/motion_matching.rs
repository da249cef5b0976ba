//! `hmc-sample --sampler motion-matching` on the tiny preset through the stage binaries: its
//! variations revisit part of their capture (coverage above 0), none tears and none spins
//! (`variation::turns_and_tears`) more than the decoded learned trajectory itself does, the same
//! seed writes the same report figures, and a query longer than the capture and a blend work.
//!
//! The spin bound is the captures' fastest turn per *capture* frame; the tiny run's time-aligned
//! training sequence skips capture frames where the DTW compresses it, so its own learned
//! trajectory decoded (`--match-start source`, which finds its own patches again: a copy) turns
//! past the bound at those frames. The variations are held to that copy's count.

mod common;

use std::path::Path;

use common::{ok, tiny_model};

fn report(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn motion_matching_on_the_tiny_preset_covers_its_captures_without_spins_or_tears() {
    let dir = tempfile::tempdir().unwrap();
    let (group, model) = tiny_model(dir.path());
    let (g, m) = (group.to_string_lossy().into_owned(), model.to_string_lossy().into_owned());
    let run = |name: &str, extra: &[&str]| {
        let (out, rep) = (dir.path().join(name), dir.path().join(format!("{name}.json")));
        let (o, r) = (out.to_string_lossy().into_owned(), rep.to_string_lossy().into_owned());
        let mut args = vec!["-q", "--seed", "0", "-n", "5", "--sampler", "motion-matching", "--group", &g, "--model", &m];
        args.extend(extra);
        args.extend(["--out", &o, "--report", &r]);
        ok(env!("CARGO_BIN_EXE_hmc-sample"), &args);
        report(&rep)
    };
    let r = run("mm", &["--blends", "0.25,0.75"]);
    let copy = run("copy", &["--blends", "0.25,0.75", "--match-start", "source"]);
    let spins = |s: &serde_json::Value| -> Vec<usize> {
        s["turns_and_tears"].as_array().unwrap().iter().map(|v| v["spinning_frames"].as_array().unwrap().len()).collect()
    };
    let mut bad = Vec::new();
    for (s, c) in r["sequences"].as_array().unwrap().iter().zip(copy["sequences"].as_array().unwrap()) {
        assert_eq!(s["label"], c["label"]);
        let coverage = s["diversity"]["coverage"].as_f64().unwrap();
        if s["blend"].is_null() && coverage <= 0.0 {
            bad.push(format!("{}: coverage {coverage}", s["label"]));
        }
        let own = spins(c).into_iter().max().unwrap_or(0);
        for (k, n) in spins(s).into_iter().enumerate() {
            if n > own {
                bad.push(format!("{} var{k}: {n} spinning frames, the learned trajectory {own}", s["label"]));
            }
        }
        for (k, v) in s["turns_and_tears"].as_array().unwrap().iter().enumerate() {
            if !v["torn_frames"].as_array().unwrap().is_empty() {
                bad.push(format!("{} var{k}: torn frames {}", s["label"], v["torn_frames"]));
            }
        }
    }
    // The walk's learned trajectory does not spin: neither do its variations.
    let walk = r["sequences"].as_array().unwrap().iter().find(|s| s["label"] == "walk").unwrap();
    assert!(spins(walk).iter().all(|&n| n == 0), "walk spins: {:?}", spins(walk));
    assert!(bad.is_empty(), "{}", bad.join("\n"));
    assert_eq!(r["config"]["sampler"], "motion-matching");
    // The same seed, the same variations (their distances to the source to the last digit).
    let again = run("mm2", &["--blends", "0.25,0.75"]);
    let d = |r: &serde_json::Value| r["sequences"].as_array().unwrap().iter().map(|s| s["distance_to_source_m"].clone()).collect::<Vec<_>>();
    assert_eq!(d(&r), d(&again));
    // Longer than the capture, and a blend of the pair.
    let frames = r["sequences"][0]["frames"].as_u64().unwrap();
    let long = (2 * frames).to_string();
    let l = run("long", &["--motion", "run", "--frame-count", &long]);
    assert_eq!(l["sequences"][0]["frames"].as_u64().unwrap(), frames, "measured against the capture");
    let run_dir = dir.path().join("long").join("run").join("var0");
    let written = std::fs::read_dir(&run_dir)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "ply"))
        .count() as u64;
    assert_eq!(written, 2 * frames, "{}", run_dir.display());
    run("blend", &["--blend", "walk:run", "--weight", "0.3"]);
}

//! A movement group of three motions with several pre-blend weights, through the stage
//! binaries on the tiny preset: `prealign --blend-weights 0.25,0.75 --blend-pairs walk:run,run:kick`
//! (walk:kick left without pre-blends), a short `gpdm-train`, then `hmc-sample --blend A:B
//! --weight w` for every pair of the three motions, in both orders. Each blend is guided by the
//! nearest learned weights on each side of `w` among that pair's pre-blends (the captured
//! motions at 0 and 1), and only by the endpoints for the pair without pre-blends.

use std::path::Path;
use std::process::Command;

mod common;

use mesh_core::artifact::Artifact;
use mesh_core::sequence::MeshSequence;
use nalgebra::Vector3;
use variation::group::Group;
use variation::train::VariationModel;

fn stage(bin: &str, args: &[&str]) -> std::process::Output {
    let out = Command::new(bin).args(args).env("OPENBLAS_NUM_THREADS", "1").output().unwrap();
    assert!(out.status.success(), "{bin} {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

/// Mean per-vertex distance between two frames.
fn dist(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).sum::<f64>() / a.len() as f64
}

#[test]
fn three_motion_group_blends_every_pair() {
    let dir = tempfile::tempdir().unwrap();
    let set = common::tiny_set(dir.path());
    let p = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let set_s = set.to_string_lossy().into_owned();
    let front = common::front_end(&set, "A", &["walk", "run", "kick"], dir.path());
    let prealign = |pairs: &str, out: &str| {
        Command::new(env!("CARGO_BIN_EXE_prealign"))
            .args(["-q", "--set", &set_s, "--group-name", "moves"])
            .args(&front)
            .args(["--blend-weights", "0.25,0.75", "--blend-pairs", pairs, "--out", out])
            .env("OPENBLAS_NUM_THREADS", "1")
            .output()
            .unwrap()
    };
    // A pair must name motions of the group, once, and two different ones.
    for (pairs, want) in [("walk:swim", "'swim' is not one of the group's motions"), ("run:run", "itself"), ("walk:run,run:walk", "listed twice")] {
        let o = prealign(pairs, &p("bad.group"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{pairs}: {err}");
    }
    let o = prealign("walk:run,run:kick", &p("moves.group"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let group = Group::load(p("moves.group")).unwrap();
    let names: Vec<&str> = group.sequences.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        ["walk", "run", "kick", "blend-0.25", "blend-0.75", "blend-run-kick-0.25", "blend-run-kick-0.75"]
    );
    let (walk, run, kick) = (0, 1, 2);
    assert_eq!(group.pair, Some((walk, run)), "the first pair is the group's blend pair");
    for s in &group.sequences[3..] {
        let (a, b) = s.blend_of.unwrap();
        let w = s.blend.unwrap();
        // A pre-blend's poses lie nearer the motion with the larger share (mesh blends of
        // time-aligned frames; the frames are aligned to the template, so this is pose only).
        let frames = s.motion.frames.len();
        let nearer_a = (0..frames)
            .filter(|&t| {
                let f = &s.motion.frames[t];
                dist(f, &group.sequences[a].motion.frames[t]) < dist(f, &group.sequences[b].motion.frames[t])
            })
            .count();
        let want_a = w < 0.5;
        assert!(
            if want_a { nearer_a * 4 >= frames * 3 } else { nearer_a * 4 <= frames },
            "{}: {nearer_a} of {frames} frames nearer {}",
            s.name,
            group.sequences[a].name
        );
    }

    stage(env!("CARGO_BIN_EXE_gpdm-train"), &["-q", "--rounds", "1", "--iters", "30", "--group", &p("moves.group"), "--out", &p("moves.model")]);
    let model = VariationModel::load(p("moves.model")).unwrap();
    assert_eq!(model.sequences.len(), 7);
    assert_eq!(model.sequences[5].blend_of, Some((run, kick)));

    // Every pair, both orders: (A, B, w, learned weights that guide it).
    let cases = [
        ("walk", "run", 0.3, (0.25, 0.75)),
        ("run", "walk", 0.3, (0.25, 0.75)),
        ("run", "kick", 0.9, (0.75, 1.0)),
        ("kick", "run", 0.1, (0.0, 0.25)),
        ("kick", "run", 0.75, (0.75, 0.75)),
        ("walk", "kick", 0.3, (0.0, 1.0)),
        ("kick", "walk", 0.6, (0.0, 1.0)),
    ];
    for (a, b, w, guided) in cases {
        let label = format!("{a}-{b}-{w}");
        let run_query = |out: &str, report: &str| {
            stage(
                env!("CARGO_BIN_EXE_hmc-sample"),
                &[
                    "-q", "--group", &p("moves.group"), "--model", &p("moves.model"), "--blend", &format!("{a}:{b}"),
                    "--weight", &w.to_string(), "-n", "2", "--sampler", "ancestral", "--assembly", "average", "--seed", "3",
                    "--out", out, "--report", report,
                ],
            );
        };
        run_query(&p(&format!("q-{label}")), &p(&format!("q-{label}.json")));
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p(&format!("q-{label}.json"))).unwrap()).unwrap();
        let seq = &report["sequences"][0];
        assert_eq!(seq["label"], label.as_str());
        assert_eq!(seq["blend"], w);
        assert_eq!(seq["guided_from"], serde_json::json!([guided.0, guided.1]), "{label}");
        for k in 0..2 {
            let frames = MeshSequence::load_dir(Path::new(&p(&format!("q-{label}"))).join(&label).join(format!("var{k}"))).unwrap();
            assert_eq!(frames.n_frames(), group.n_frames(), "{label}");
            assert!(frames.frames.iter().flatten().all(|v| v.iter().all(|c| c.is_finite())));
        }
    }
    // Reproducible from (model, query, seed) alone, whatever the thread count.
    let again = p("again");
    stage(
        env!("CARGO_BIN_EXE_hmc-sample"),
        &[
            "-q", "--threads", "1", "--group", &p("moves.group"), "--model", &p("moves.model"), "--blend", "run:kick",
            "--weight", "0.9", "-n", "2", "--sampler", "ancestral", "--assembly", "average", "--seed", "3", "--out", &again,
        ],
    );
    for k in 0..2 {
        let var = format!("run-kick-0.9/var{k}");
        let (x, y) = (Path::new(&again).join(&var), Path::new(&p("q-run-kick-0.9")).join(&var));
        for f in ["000000.ply", "000010.ply"] {
            assert_eq!(std::fs::read(x.join(f)).unwrap(), std::fs::read(y.join(f)).unwrap(), "{var}/{f}");
        }
    }
}

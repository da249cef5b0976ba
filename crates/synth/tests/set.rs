//! The ground truth of a tiny capture set (needs the fetched assets: run scripts/fetch-assets).

use std::path::Path;

use mesh_core::capture_set::{SetSpec, SubjectSpec};
use nalgebra::Vector3;
use serde_json::Value;
use synth::capture_set_writer::synthesise;
use synth::preset::preset;

fn read<T: serde::de::DeserializeOwned>(p: &Path) -> T {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn frame(dir: &Path, k: usize) -> Vec<Vector3<f64>> {
    mesh_core::io::read_mesh(dir.join(format!("{k:06}.ply")))
        .unwrap()
        .vertices
}

fn max_dist(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}

fn build(noise: bool) -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = preset("tiny", 11, noise).unwrap();
    synthesise(&cfg, &tmp.path().join("set"), true, &|_| {}, &|| {})
        .expect("synth failed (are the assets fetched? run scripts/fetch-assets)");
    tmp
}

fn times(spec: &SubjectSpec, m: &str) -> Vec<f64> {
    spec.extra["mocap_time"][m]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

#[test]
fn truth_of_a_training_motion_equals_the_targets_own_sequence_at_corresponding_frames() {
    let tmp = build(false);
    let set = tmp.path().join("set");
    let spec: SetSpec = read(&set.join("set.json"));
    let b: SubjectSpec = read(&set.join("B/subject.json"));
    let a: SubjectSpec = read(&set.join("A/subject.json"));
    assert!(spec.train.len() >= 5 && spec.test.len() >= 3);
    for t in &spec.test {
        assert!(
            spec.train.iter().all(|p| &p.source != t && &p.target != t),
            "{t} is also trained on"
        );
        let na = std::fs::read_dir(set.join("A").join(t)).unwrap().count();
        assert_eq!(
            std::fs::read_dir(set.join("truth/B").join(t))
                .unwrap()
                .count(),
            na
        );
    }
    for pair in &spec.train {
        let m = &pair.source;
        let (ta, tb) = (times(&a, m), times(&b, m));
        let corr: Vec<[usize; 2]> =
            serde_json::from_value(pair.extra["correspondences"].clone()).unwrap();
        assert_eq!(corr.len(), ta.len());
        assert!(pair.keyposes.len() >= 4 && pair.keyposes.iter().all(|k| corr.contains(k)));
        let truth = set.join("truth/B").join(m);
        let own = set.join("B").join(m);
        // Frame 0 of both is the clip's first instant: identical meshes.
        assert_eq!(max_dist(&frame(&truth, 0), &frame(&own, 0)), 0.0, "{m}");
        // Lipschitz bound from B's own sequence: max vertex speed per unit of mocap time.
        let nb = tb.len();
        let mut speed: f64 = 0.0;
        for j in 1..nb {
            speed = speed.max(max_dist(&frame(&own, j), &frame(&own, j - 1)) / (tb[j] - tb[j - 1]));
        }
        let (mut err_corr, mut err_shift) = (0.0, 0.0);
        for &[i, j] in corr.iter().step_by(3) {
            let t = frame(&truth, i);
            let d = max_dist(&t, &frame(&own, j));
            assert!(
                d <= 1.5 * speed * (ta[i] - tb[j]).abs() + 1e-6,
                "{m} frame {i}->{j}: {d}"
            );
            err_corr += d;
            err_shift += max_dist(&t, &frame(&own, (j + nb / 3) % nb));
        }
        assert!(
            err_corr < 0.2 * err_shift,
            "{m}: corresponding frames are not closer ({err_corr} vs {err_shift})"
        );
    }
}

#[test]
fn noise_is_small_and_only_on_the_inputs() {
    let noisy = build(true);
    let clean = build(false);
    let (n, c) = (noisy.path().join("set"), clean.path().join("set"));
    for sub in ["A/walk", "B/run", "A/punch"] {
        let mut sum = 0.0;
        let mut cnt = 0.0;
        for k in [0, 5, 10] {
            let (p, q) = (frame(&n.join(sub), k), frame(&c.join(sub), k));
            assert!(max_dist(&p, &q) < 0.02, "{sub}: noise too large");
            sum += p
                .iter()
                .zip(&q)
                .map(|(a, b)| (a - b).norm_squared())
                .sum::<f64>();
            cnt += p.len() as f64;
        }
        let rms = (sum / cnt).sqrt();
        assert!(rms > 0.001 && rms < 0.006, "{sub}: rms noise {rms}");
    }
    // Truth is never noisy.
    for k in [0, 7] {
        assert_eq!(
            frame(&n.join("truth/B/punch"), k),
            frame(&c.join("truth/B/punch"), k)
        );
    }
}

#[test]
fn curves_contacts_and_heights_are_sound() {
    let tmp = build(false);
    let set = tmp.path().join("set");
    for (s, h) in [("A", 1.6), ("B", 1.9)] {
        let spec: SubjectSpec = read(&set.join(s).join("subject.json"));
        assert!((spec.extra["height_m"].as_f64().unwrap() - h).abs() < 0.05);
        assert_eq!(spec.parts.len(), 5);
        let rest = frame(&set.join(s).join("walk"), 0);
        for (part, loops) in &spec.curves {
            assert_eq!(loops.len(), 2, "{s} {part}");
            let centre = |l: &Vec<u32>| {
                l.iter().map(|&i| rest[i as usize]).sum::<Vector3<f64>>() / l.len() as f64
            };
            for l in loops {
                assert!(l.len() >= 4 && l.iter().all(|&i| (i as usize) < rest.len()));
                // A loop surrounds its centre: vertices spread around it, not on one side.
                let c = centre(l);
                let mean_off = l
                    .iter()
                    .map(|&i| rest[i as usize] - c)
                    .sum::<Vector3<f64>>()
                    .norm()
                    / l.len() as f64;
                let radius = l
                    .iter()
                    .map(|&i| (rest[i as usize] - c).norm())
                    .sum::<f64>()
                    / l.len() as f64;
                assert!(mean_off < 0.2 * radius && radius < 0.15, "{s} {part}");
            }
        }
        // Walking: each foot is sometimes down and sometimes up; mostly some foot is down.
        let c: Vec<[u8; 2]> =
            serde_json::from_value(spec.extra["contacts"]["walk"].clone()).unwrap();
        for side in 0..2 {
            assert!(
                c.iter().any(|f| f[side] == 1) && c.iter().any(|f| f[side] == 0),
                "{s} side {side}"
            );
        }
        assert!(
            c.iter().filter(|f| f[0] + f[1] > 0).count() * 10 >= c.len() * 8,
            "{s}: {c:?}"
        );
        let fps = spec.fps;
        assert!(fps > 0.0);
        let v: Value = spec.extra["mocap_time"]["walk"].clone();
        assert_eq!(v.as_array().unwrap().len(), c.len());
    }
}

#[test]
fn the_set_opens_with_mesh_core_and_its_curves_resolve() {
    let tmp = build(true);
    let set = mesh_core::capture_set::CaptureSet::open(tmp.path().join("set")).unwrap();
    for name in ["A", "B"] {
        let s = set
            .subject(name)
            .unwrap_or_else(|e| panic!("subject {name}: {e}"));
        assert_eq!(s.curves.len(), 4);
        for (part, [near, far]) in &s.curves {
            assert!(
                !near.iter().any(|v| far.contains(v)),
                "{name} {part}: loops share vertices"
            );
        }
        for m in set.motions(name).unwrap() {
            let seq =
                mesh_core::sequence::MeshSequence::load_dir(set.motion_dir(name, &m)).unwrap();
            assert_eq!(seq.n_vertices(), s.template.vertices.len(), "{name}/{m}");
        }
    }
    // The target's own test motion has the source's truth, frame for frame.
    let spec = &set.spec;
    let tt: Vec<String> = serde_json::from_value(spec.extra["target_test"].clone()).unwrap();
    assert!(!tt.is_empty());
    for m in &tt {
        let nb = set.frames("B", m).unwrap().len();
        let truth = mesh_core::sequence::frame_files(set.truth_dir("A", m))
            .unwrap()
            .len();
        assert_eq!(truth, nb, "{m}");
    }
}

/// The `long` preset: every training motion lasts two minutes of mocap time (looped, then cut),
/// B (slower cadence) gets more frames than A, the test motions are the demo's uncut clips, and
/// the bodies are the tiny preset's. No frames are written (2.8 GB).
#[test]
fn long_preset_has_two_minute_training_motions() {
    use synth::capture_set_writer::{count_frames, load_motion};
    let long = preset("long", 0, true).unwrap();
    let (tiny, default) = (preset("tiny", 0, true).unwrap(), preset("default", 0, true).unwrap());
    let dir = synth::assets::asset_dir().expect("assets (run scripts/fetch-assets)");
    for def in &long.train {
        let clip = load_motion(&dir, def, long.max_duration).unwrap().clip;
        let d = clip.duration();
        assert!(d > synth::preset::LONG_SECONDS - 1.0 && d <= synth::preset::LONG_SECONDS, "{}: {d} s", def.name);
    }
    let names = |v: &[synth::preset::MotionDef]| v.iter().map(|m| m.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&long.test), names(&default.test));
    assert_eq!(names(&long.train), names(&tiny.train));
    assert_eq!((long.source.fps, long.target.fps), (tiny.source.fps, tiny.target.fps));
    let motions: Vec<_> = long.train.iter().map(|d| load_motion(&dir, d, long.max_duration).unwrap()).collect();
    let train_only = synth::preset::Config { test: vec![], target_test: vec![], ..long.clone() };
    let frames = count_frames(&train_only, &motions);
    // 5 motions x 120 s x (20 fps for A + ~25/0.85 fps for B).
    assert!((25_000..35_000).contains(&frames), "{frames} training frames");
}

/// The `turning` preset is the demo set plus two turning walks: DeepMimic's walk whose root path
/// and pelvis turn about the vertical by the preset's rate times its length, to the left (+z, the
/// forward, toward +x, the body's left) for `turn_left` and to the right for `turn_right`; the
/// walk itself goes straight. No frames are written (the demo bodies).
#[test]
fn turning_preset_adds_a_left_and_a_right_turning_walk() {
    use synth::capture_set_writer::load_motion;
    let (turning, default) = (preset("turning", 0, true).unwrap(), preset("default", 0, true).unwrap());
    let names = |v: &[synth::preset::MotionDef]| v.iter().map(|m| m.name.clone()).collect::<Vec<_>>();
    let mut want = names(&default.train);
    want.extend(["turn_left".to_string(), "turn_right".to_string()]);
    assert_eq!(names(&turning.train), want);
    assert_eq!(names(&turning.test), names(&default.test));
    let dir = synth::assets::asset_dir().expect("assets (run scripts/fetch-assets)");
    // The heading of the root's travel over its first and last 0.3 s, and its change (degrees).
    let turned = |name: &str| {
        let def = turning.train.iter().find(|m| m.name == name).unwrap();
        let clip = load_motion(&dir, def, turning.max_duration).unwrap().clip;
        let heading = |a: f64, b: f64| {
            let d = clip.sample(b).root - clip.sample(a).root;
            d.x.atan2(d.z).to_degrees()
        };
        let end = clip.duration();
        (heading(end - 0.3, end) - heading(0.0, 0.3), end)
    };
    let (walk, _) = turned("walk");
    let (left, seconds) = turned("turn_left");
    let (right, _) = turned("turn_right");
    // The heading at the two windows' middles differs by the rate times (length - 0.3 s),
    // plus whatever the walk's own path does.
    let expected = synth::preset::TURN_DEG_PER_S * (seconds - 0.3);
    assert!(walk.abs() < 10.0, "the walk turns {walk}°");
    assert!((left - walk - expected).abs() < 5.0, "turn_left turns {left}° (expected {expected} + the walk's {walk})");
    assert!((right - walk + expected).abs() < 5.0, "turn_right turns {right}° (expected -{expected} + the walk's {walk})");
}

/// The files under `root/rel` (a folder), as paths relative to `root`, sorted.
fn files_under(root: &Path, rel: &Path) -> Vec<std::path::PathBuf> {
    let mut out: Vec<std::path::PathBuf> = std::fs::read_dir(root.join(rel))
        .unwrap()
        .map(|e| rel.join(e.unwrap().file_name()))
        .collect();
    out.sort();
    out
}

/// `synth --more-training` adds training pairs, each with its key-poses, and leaves the
/// preset's own pairs, frames and truth byte-identical: the two sets differ only in what is
/// trained on.
#[test]
fn more_training_adds_pairs_and_keeps_the_presets_own_motions() {
    let plain = build(true);
    let more = tempfile::tempdir().unwrap();
    let cfg = synth::preset::with_more_training(preset("tiny", 11, true).unwrap());
    synthesise(&cfg, &more.path().join("set"), true, &|_| {}, &|| {}).unwrap();
    let (p, m) = (plain.path().join("set"), more.path().join("set"));
    let (sp, sm): (SetSpec, SetSpec) = (read(&p.join("set.json")), read(&m.join("set.json")));
    assert_eq!(sm.extra["more_training"], Value::Bool(true));
    assert!(!sp.extra.contains_key("more_training"));
    assert_eq!(sm.train[..sp.train.len()], sp.train[..], "the preset's own pairs first, unchanged");
    assert!(sm.train.len() > sp.train.len());
    for pair in &sm.train[sp.train.len()..] {
        assert_eq!(pair.keyposes.len(), cfg.keyposes, "{}", pair.source);
        assert!(!sp.test.contains(&pair.source), "{} is a test motion", pair.source);
    }
    assert_eq!(sm.test, sp.test);
    let mut own = Vec::new();
    for subject in ["A", "B"] {
        for motion in std::fs::read_dir(p.join(subject)).unwrap().map(|e| e.unwrap().file_name()) {
            let rel = Path::new(subject).join(&motion);
            if p.join(&rel).is_dir() {
                own.extend(files_under(&p, &rel));
            }
        }
        for motion in std::fs::read_dir(p.join("truth").join(subject)).unwrap().map(|e| e.unwrap().file_name()) {
            own.extend(files_under(&p, &Path::new("truth").join(subject).join(motion)));
        }
    }
    assert!(own.len() > 100);
    for rel in &own {
        let (a, b) = (std::fs::read(p.join(rel)).unwrap(), std::fs::read(m.join(rel)).unwrap());
        assert!(a == b, "{} differs", rel.display());
    }
}

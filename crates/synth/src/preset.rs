//! The presets: `tiny` (decimated topologies: A `notoes_collapse10pc`, 1,229 vertices; B
//! `notoes_collapse5pc` subdivided once, 2,454 vertices; ~1.2 s clips; builds in seconds, for
//! tests), `default` (full body and `notoes` topologies, 25 and 50 fps: the demo set),
//! `holdout` (two other bodies, styles, topologies and frame rates, the demo's training
//! motions and test motions from clips the demo never uses: the second benchmark, on which
//! nothing is tuned), `outside` (a third pair of bodies, styles and frame rates, and test
//! clips neither of the two uses: measured with the defaults, never tuned on) and `long` (the
//! tiny preset's bodies and frame rates with every training motion looped to two minutes:
//! ~15,000 dense training pairs, the size of a lab's five minutes at 50 fps, for the sparse
//! GP's benchmark on real pairs; docs/PERFORMANCE.md).

use crate::noise::NoiseLevel;
use crate::style::{Style, TimeWarp};
use crate::subject::{SubjectDef, Topology};

/// Where a motion's frames come from.
#[derive(Clone, Debug)]
pub enum MotionSource {
    /// A DeepMimic clip under `pybullet_data/data/motions/`, repeated `cycles` times if cyclic,
    /// its heading turned at `turn` degrees per second about the vertical (positive: to the
    /// left; 0: as captured; [`crate::mocap::Clip::turned`]).
    DeepMimic { file: String, cycles: usize, turn: f64 },
    /// The CMU BVH `01_01.bvh` between two times (seconds).
    Cmu { t0: f64, t1: f64 },
}

/// One motion of the set.
#[derive(Clone, Debug)]
pub struct MotionDef {
    pub name: String,
    pub source: MotionSource,
}

/// Everything that defines a capture set.
#[derive(Clone, Debug)]
pub struct Config {
    pub preset: String,
    pub seed: u64,
    pub noise: Option<NoiseLevel>,
    pub source: SubjectDef,
    pub target: SubjectDef,
    pub train: Vec<MotionDef>,
    pub test: Vec<MotionDef>,
    /// The target subject's own test motions (their truth is the source performing them).
    pub target_test: Vec<MotionDef>,
    /// Longest clip, in mocap seconds.
    pub max_duration: f64,
    /// Key-poses per training pair.
    pub keyposes: usize,
    /// The other benchmark sets' test clips are training motions too ([`with_more_training`]).
    pub more_training: bool,
}

fn dm(name: &str, file: &str, cycles: usize) -> MotionDef {
    MotionDef {
        name: name.to_string(),
        source: MotionSource::DeepMimic {
            file: format!("humanoid3d_{file}.txt"),
            cycles,
            turn: 0.0,
        },
    }
}

/// The turning walks of the `turning` preset: DeepMimic's walk, its heading turned at this many
/// degrees per second to the left and to the right (about a quarter turn over its 2.4 s).
pub const TURN_DEG_PER_S: f64 = 40.0;

fn turning_walk(name: &str, turn: f64) -> MotionDef {
    MotionDef {
        name: name.to_string(),
        source: MotionSource::DeepMimic { file: "humanoid3d_walk.txt".into(), cycles: 2, turn },
    }
}

/// Subject A: 1.6 m slim young woman, mild style (slightly smaller arm swing), 25 fps.
pub fn subject_a(topology: Topology, fps: f64) -> SubjectDef {
    SubjectDef {
        name: "A".into(),
        description: "1.6 m slim young woman (MakeHuman caucasian-female-young + 0.3 minmuscle-averageweight)".into(),
        targets: vec![
            ("macrodetails/caucasian-female-young".into(), 1.0),
            ("macrodetails/universal-female-young-minmuscle-averageweight".into(), 0.3),
        ],
        topology,
        fps,
        style: Style {
            arm_gain: 0.85,
            arm_max: 2.0,
            arm_abduction: 4f64.to_radians(),
            elbow_gain: 1.0,
            knee_k: 0.05,
            hip_abduction: 0.0,
            lean_per_speed: 0.02,
            warp: TimeWarp { rate: 1.0, amp: 0.025, period: 1.4, phase: 0.0 },
        },
    }
}

/// Subject B: 1.9 m heavy young man, large saturated arm swing, arms and legs held wider,
/// deeper knee bend, leaning with speed, slower cadence, 50 fps.
pub fn subject_b(topology: Topology, fps: f64) -> SubjectDef {
    SubjectDef {
        name: "B".into(),
        description: "1.9 m heavy young man (MakeHuman caucasian-male-young + 0.6 averagemuscle-maxweight + 0.25 maxheight)".into(),
        targets: vec![
            ("macrodetails/caucasian-male-young".into(), 1.0),
            ("macrodetails/universal-male-young-averagemuscle-maxweight".into(), 0.6),
            ("macrodetails/height/male-young-averagemuscle-averageweight-maxheight".into(), 0.25),
        ],
        topology,
        fps,
        style: Style {
            arm_gain: 1.6,
            arm_max: 1.2,
            arm_abduction: 10f64.to_radians(),
            elbow_gain: 1.2,
            knee_k: 0.35,
            hip_abduction: 3f64.to_radians(),
            lean_per_speed: 0.06,
            warp: TimeWarp { rate: 0.85, amp: 0.035, period: 1.9, phase: 0.7 },
        },
    }
}

/// Holdout subject C: 1.8 m slim young African man, stiff arms held close, long strides,
/// quick cadence; `notoes_collapse10pc` subdivided once (about 4,900 vertices), 50 fps.
pub fn subject_c() -> SubjectDef {
    SubjectDef {
        name: "C".into(),
        description: "1.8 m slim young man (MakeHuman african-male-young + 0.5 minmuscle-minweight)".into(),
        targets: vec![
            ("macrodetails/african-male-young".into(), 1.0),
            ("macrodetails/universal-male-young-minmuscle-minweight".into(), 0.5),
        ],
        topology: Topology::ObjSubdivided("notoes_collapse10pc.obj".into()),
        fps: 50.0,
        style: Style {
            arm_gain: 0.7,
            arm_max: 1.6,
            arm_abduction: 2f64.to_radians(),
            elbow_gain: 0.8,
            knee_k: 0.15,
            hip_abduction: 1f64.to_radians(),
            lean_per_speed: 0.04,
            warp: TimeWarp { rate: 1.1, amp: 0.03, period: 1.2, phase: 1.3 },
        },
    }
}

/// Holdout subject D: 1.35 m muscular young Asian woman, wide arm swing held out, bent knees,
/// slow cadence; `notoes_collapse5pc` subdivided once (2,454 vertices), 25 fps.
pub fn subject_d() -> SubjectDef {
    SubjectDef {
        name: "D".into(),
        description: "1.35 m muscular young woman (MakeHuman asian-female-young + 0.7 maxmuscle-averageweight + 0.4 minheight)".into(),
        targets: vec![
            ("macrodetails/asian-female-young".into(), 1.0),
            ("macrodetails/universal-female-young-maxmuscle-averageweight".into(), 0.7),
            ("macrodetails/height/female-young-maxmuscle-averageweight-minheight".into(), 0.4),
        ],
        topology: Topology::ObjSubdivided("notoes_collapse5pc.obj".into()),
        fps: 25.0,
        style: Style {
            arm_gain: 1.35,
            arm_max: 1.4,
            arm_abduction: 14f64.to_radians(),
            elbow_gain: 1.3,
            knee_k: 0.25,
            hip_abduction: 5f64.to_radians(),
            lean_per_speed: 0.08,
            warp: TimeWarp { rate: 0.9, amp: 0.03, period: 1.7, phase: 2.1 },
        },
    }
}

/// Outside subject E: 1.71 m heavy old man, small stiff arm swing, bent knees, slow cadence;
/// `notoes_collapse5pc` subdivided once (2,454 vertices), 30 fps.
pub fn subject_e() -> SubjectDef {
    SubjectDef {
        name: "E".into(),
        description: "1.71 m heavy old man (MakeHuman caucasian-male-old + 0.6 averagemuscle-maxweight)".into(),
        targets: vec![
            ("macrodetails/caucasian-male-old".into(), 1.0),
            ("macrodetails/universal-male-old-averagemuscle-maxweight".into(), 0.6),
        ],
        topology: Topology::ObjSubdivided("notoes_collapse5pc.obj".into()),
        fps: 30.0,
        style: Style {
            arm_gain: 0.6,
            arm_max: 1.0,
            arm_abduction: 6f64.to_radians(),
            elbow_gain: 1.1,
            knee_k: 0.3,
            hip_abduction: 2f64.to_radians(),
            lean_per_speed: 0.05,
            warp: TimeWarp { rate: 0.8, amp: 0.04, period: 1.5, phase: 0.4 },
        },
    }
}

/// Outside subject F: 1.67 m athletic young African woman, wide quick arm swing, straight
/// legs; the `notoes` body (12,272 vertices), 25 fps.
pub fn subject_f() -> SubjectDef {
    SubjectDef {
        name: "F".into(),
        description: "1.67 m athletic young woman (MakeHuman african-female-young + 0.6 maxmuscle-minweight)".into(),
        targets: vec![
            ("macrodetails/african-female-young".into(), 1.0),
            ("macrodetails/universal-female-young-maxmuscle-minweight".into(), 0.6),
        ],
        topology: Topology::Obj("notoes.obj".into()),
        fps: 25.0,
        style: Style {
            arm_gain: 1.2,
            arm_max: 1.8,
            arm_abduction: 8f64.to_radians(),
            elbow_gain: 0.9,
            knee_k: 0.1,
            hip_abduction: 0.0,
            lean_per_speed: 0.03,
            warp: TimeWarp { rate: 1.05, amp: 0.02, period: 1.3, phase: 1.7 },
        },
    }
}

/// Test motions of the outside set: clips neither the demo nor the holdout set uses.
fn outside_tests() -> (Vec<MotionDef>, Vec<MotionDef>) {
    let test = vec![
        dm("getup_facedown", "getup_facedown", 1),
        dm("roll", "roll", 1),
        MotionDef {
            name: "cmu_playground".into(),
            source: MotionSource::Cmu { t0: 12.0, t1: 15.0 },
        },
    ];
    (test, vec![dm("crawl", "crawl", 1)])
}

/// Test motions of the holdout set: clips the demo set never uses.
fn holdout_tests() -> (Vec<MotionDef>, Vec<MotionDef>) {
    let test = vec![
        dm("spin", "spin", 1),
        dm("cartwheel", "cartwheel", 1),
        dm("getup", "getup_faceup", 1),
        MotionDef {
            name: "cmu_walkturn".into(),
            source: MotionSource::Cmu { t0: 5.0, t1: 8.0 },
        },
    ];
    (test, vec![dm("backflip", "backflip", 1)])
}

fn motions() -> (Vec<MotionDef>, Vec<MotionDef>) {
    let train = vec![
        dm("walk", "walk", 2),
        dm("run", "run", 3),
        dm("jump", "jump", 1),
        dm("kick", "kick", 1),
        dm("dance", "dance_a", 1),
    ];
    let test = vec![
        dm("punch", "punch", 1),
        dm("spinkick", "spinkick", 1),
        MotionDef {
            name: "cmu_jump".into(),
            source: MotionSource::Cmu { t0: 1.0, t1: 3.5 },
        },
    ];
    (train, test)
}

/// Capture-like noise of the default set: 1 mm surface noise, 2 mm coherent jitter.
pub fn default_noise() -> NoiseLevel {
    NoiseLevel {
        surface: 0.001,
        jitter: 0.002,
    }
}

/// The preset names [`preset`] knows.
pub const PRESETS: [&str; 6] = ["default", "tiny", "holdout", "outside", "long", "turning"];

/// A preset, as the command line names it (one of [`PRESETS`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The demo set: full body at 25 fps and the notoes body at 50 fps.
    #[default]
    Default,
    /// Coarse bodies, for tests.
    Tiny,
    /// Other bodies, styles, rates and test clips: the second benchmark.
    Holdout,
    /// Third bodies, styles, rates and test clips, measured and never tuned on.
    Outside,
    /// The tiny bodies with two-minute training motions (~15,000 pairs): the sparse GP's benchmark.
    Long,
    /// The demo set with a left and a right turning walk among the training motions: the 3DV
    /// paper's four-sequence locomotion group (walk, run, left turn, right turn).
    Turning,
}

impl Preset {
    /// Its name in [`PRESETS`].
    pub fn name(self) -> &'static str {
        match self {
            Preset::Default => "default",
            Preset::Tiny => "tiny",
            Preset::Holdout => "holdout",
            Preset::Outside => "outside",
            Preset::Long => "long",
            Preset::Turning => "turning",
        }
    }
}

/// A preset by name (one of [`PRESETS`]).
pub fn preset(name: &str, seed: u64, noise: bool) -> Option<Config> {
    let (train, test) = motions();
    let noise = noise.then(default_noise);
    match name {
        "tiny" => Some(Config {
            preset: name.into(),
            seed,
            noise,
            source: subject_a(Topology::Obj("notoes_collapse10pc.obj".into()), 20.0),
            target: subject_b(
                Topology::ObjSubdivided("notoes_collapse5pc.obj".into()),
                25.0,
            ),
            train: train.clone(),
            test: test.clone(),
            target_test: vec![dm("dance_b", "dance_b", 1)],
            max_duration: 1.2,
            keyposes: 5,
            more_training: false,
        }),
        "default" => Some(Config {
            preset: name.into(),
            seed,
            noise,
            source: subject_a(Topology::Body, 25.0),
            target: subject_b(Topology::Obj("notoes.obj".into()), 50.0),
            train: train.clone(),
            test: test.clone(),
            target_test: vec![dm("dance_b", "dance_b", 1)],
            max_duration: 3.0,
            keyposes: 5,
            more_training: false,
        }),
        "turning" => {
            let mut cfg = preset("default", seed, noise.is_some())?;
            cfg.preset = name.into();
            cfg.train.extend([turning_walk("turn_left", TURN_DEG_PER_S), turning_walk("turn_right", -TURN_DEG_PER_S)]);
            Some(cfg)
        }
        "holdout" => {
            let (test, target_test) = holdout_tests();
            Some(Config {
                preset: name.into(),
                seed,
                noise,
                source: subject_c(),
                target: subject_d(),
                train,
                test,
                target_test,
                max_duration: 3.0,
                keyposes: 5,
                more_training: false,
            })
        }
        "outside" => {
            let (test, target_test) = outside_tests();
            Some(Config {
                preset: name.into(),
                seed,
                noise,
                source: subject_e(),
                target: subject_f(),
                train,
                test,
                target_test,
                max_duration: 3.0,
                keyposes: 5,
                more_training: false,
            })
        }
        "long" => Some(Config {
            preset: name.into(),
            seed,
            noise,
            source: subject_a(Topology::Obj("notoes_collapse10pc.obj".into()), 20.0),
            target: subject_b(
                Topology::ObjSubdivided("notoes_collapse5pc.obj".into()),
                25.0,
            ),
            train: long_motions(&train),
            test,
            target_test: vec![dm("dance_b", "dance_b", 1)],
            max_duration: LONG_SECONDS,
            keyposes: 5,
            more_training: false,
        }),
        _ => None,
    }
}

/// The test clips of the benchmark sets (`default`, `holdout`, `outside`, in that order) from
/// performances `cfg` neither tests nor trains on, added to its training motions: the
/// training-coverage study (`synth --more-training`; docs/studies/09-training-coverage.md). Every
/// preset tests on a
/// window of the CMU take, so the other windows of that take are never added: a test motion
/// gains only from other motions, not from the rest of its own performance. The preset's own
/// motions are unchanged.
pub fn with_more_training(mut cfg: Config) -> Config {
    let tests: Vec<MotionDef> = cfg.test.iter().chain(&cfg.target_test).cloned().collect();
    for name in ["default", "holdout", "outside"] {
        let other = preset(name, cfg.seed, false).expect("a benchmark preset");
        for m in other.test.iter().chain(&other.target_test) {
            // `cfg.train` grows: a clip two other sets share is added once.
            if !tests.iter().chain(&cfg.train).any(|o| same_performance(o, m) || o.name == m.name) {
                cfg.train.push(m.clone());
            }
        }
    }
    cfg.more_training = true;
    cfg
}

/// Whether two motions come from the same performance: the same DeepMimic clip, or any two
/// windows of the one CMU take (`01_01`, a single continuous performance).
fn same_performance(a: &MotionDef, b: &MotionDef) -> bool {
    match (&a.source, &b.source) {
        (MotionSource::DeepMimic { file: f, .. }, MotionSource::DeepMimic { file: g, .. }) => f == g,
        (MotionSource::Cmu { .. }, MotionSource::Cmu { .. }) => true,
        _ => false,
    }
}

/// Length of each training motion of the `long` preset, in mocap seconds.
pub const LONG_SECONDS: f64 = 120.0;

/// The training motions looped until they last [`LONG_SECONDS`] (then cut there). The
/// non-cyclic clips (jump, kick, dance) restart from their first pose each cycle, as a
/// performer repeating a move would.
fn long_motions(train: &[MotionDef]) -> Vec<MotionDef> {
    train
        .iter()
        .map(|m| match &m.source {
            MotionSource::DeepMimic { file, .. } => MotionDef {
                name: m.name.clone(),
                // The shortest clip (run) lasts ~0.7 s: 200 cycles always reach LONG_SECONDS.
                source: MotionSource::DeepMimic { file: file.clone(), cycles: 200, turn: 0.0 },
            },
            MotionSource::Cmu { .. } => m.clone(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    fn clip(m: &MotionDef) -> String {
        match &m.source {
            MotionSource::DeepMimic { file, .. } => file.clone(),
            MotionSource::Cmu { t0, t1 } => format!("cmu {t0}-{t1}"),
        }
    }

    /// Every name of [`PRESETS`] is a preset of the command line and builds a configuration.
    #[test]
    fn every_preset_name_is_on_the_command_line_and_builds() {
        let names: Vec<&str> = Preset::value_variants().iter().map(|p| p.name()).collect();
        assert_eq!(names.len(), PRESETS.len());
        for name in PRESETS {
            assert!(names.contains(&name), "{name}: not a command-line preset");
            assert_eq!(preset(name, 0, true).map(|c| c.preset), Some(name.to_string()));
        }
        assert!(preset("nope", 0, true).is_none());
    }

    /// `--more-training` adds exactly the other benchmark sets' test clips but the CMU take's
    /// windows, after the preset's own training motions, and leaves its test motions alone.
    #[test]
    fn more_training_adds_the_other_sets_test_clips() {
        let tests_of = |name: &str| {
            let c = preset(name, 0, true).unwrap();
            c.test.iter().chain(&c.target_test).map(clip).collect::<Vec<_>>()
        };
        for (name, others) in [("holdout", ["default", "outside"]), ("outside", ["default", "holdout"]), ("default", ["holdout", "outside"])] {
            let base = preset(name, 0, true).unwrap();
            let more = with_more_training(base.clone());
            assert!(more.more_training && !base.more_training);
            let train: Vec<String> = more.train.iter().map(clip).collect();
            let (own, added) = train.split_at(base.train.len());
            assert_eq!(own, base.train.iter().map(clip).collect::<Vec<_>>(), "{name}: own training motions first");
            let mut expected: Vec<String> = others.iter().flat_map(|o| tests_of(o)).filter(|c| !c.starts_with("cmu")).collect();
            let mut added = added.to_vec();
            expected.sort();
            added.sort();
            assert_eq!(added, expected, "{name}");
            assert_eq!(more.test.iter().chain(&more.target_test).map(clip).collect::<Vec<_>>(), tests_of(name));
            let mut names: Vec<&str> = more.train.iter().map(|m| m.name.as_str()).collect();
            names.sort_unstable();
            names.dedup();
            assert_eq!(names.len(), more.train.len(), "{name}: motion names stay unique");
        }
        // The tiny preset tests on the demo's clips: they are not added to its training.
        let tiny = with_more_training(preset("tiny", 0, true).unwrap());
        assert!(tiny.train.iter().all(|m| !tests_of("default").contains(&clip(m))));
    }

    /// The benchmark sets share the training clips and nothing else: no test clip of one is a
    /// test or training clip of another, and their four bodies are different subjects.
    #[test]
    fn benchmark_sets_test_on_clips_no_other_set_uses() {
        let sets: Vec<Config> = ["default", "holdout", "outside"].iter().map(|n| preset(n, 0, true).unwrap()).collect();
        let train: Vec<String> = sets[0].train.iter().map(clip).collect();
        for (i, a) in sets.iter().enumerate() {
            assert_eq!(a.train.iter().map(clip).collect::<Vec<_>>(), train, "{}: other training clips", a.preset);
            let tests: Vec<String> = a.test.iter().chain(&a.target_test).map(clip).collect();
            for t in &tests {
                assert!(!train.contains(t), "{}: {t} is a training clip", a.preset);
                for b in sets.iter().skip(i + 1) {
                    let other: Vec<String> = b.test.iter().chain(&b.target_test).map(clip).collect();
                    assert!(!other.contains(t), "{t}: a test clip of both {} and {}", a.preset, b.preset);
                }
            }
        }
        let mut bodies: Vec<String> = sets.iter().flat_map(|c| [c.source.description.clone(), c.target.description.clone()]).collect();
        bodies.sort();
        bodies.dedup();
        assert_eq!(bodies.len(), 6);
    }
}

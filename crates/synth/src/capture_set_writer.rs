//! Builds a whole capture set (format in docs/FORMATS.md) from a [`Config`]: both subjects'
//! training motions, each subject's test motions with the other subject's truth of them, subject and
//! set descriptions with the ground truth (correspondences, key-poses, contacts, curves).
//!
//! Written into a temporary sibling folder, then renamed over the output: the set is either
//! complete or absent. Every frame is independent (own noise stream), so the files are
//! byte-identical for a seed whatever the number of threads.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use rayon::prelude::*;
use serde_json::{json, Value};

use crate::assets::{self, paths};
use crate::mocap::{self, Clip};
use crate::noise::{self, Jitter, NoiseLevel};
use crate::parts;
use crate::preset::{Config, MotionDef, MotionSource};
use crate::retarget::{Retarget, SourceKind};
use crate::subject::{BodyAssets, Subject};
use crate::truth;
use mesh_core::capture_set::{SetSpec, SubjectSpec, TrainPair};
use mesh_core::{Error, Result, TriMesh};

/// A loaded motion clip and its source kind.
pub struct Motion {
    pub def: MotionDef,
    pub clip: Clip,
    pub kind: SourceKind,
}

/// Loads a motion's clip (looped / windowed, cut to `max_duration`).
pub fn load_motion(dir: &Path, def: &MotionDef, max_duration: f64) -> Result<Motion> {
    let (clip, kind) = match &def.source {
        MotionSource::DeepMimic { file, cycles, turn } => {
            let leg = mocap::deepmimic_leg_length(&dir.join(paths::HUMANOID_URDF))?;
            let c = mocap::parse_deepmimic(&dir.join(paths::MOTIONS).join(file), &def.name, leg)?;
            (c.looped(*cycles).turned(turn.to_radians()), SourceKind::DeepMimic)
        }
        MotionSource::Cmu { t0, t1 } => (
            mocap::parse_bvh(&dir.join(paths::CMU_BVH), &def.name)?.window(*t0, *t1),
            SourceKind::Cmu,
        ),
    };
    let clip = clip.window(0.0, max_duration);
    Ok(Motion {
        def: def.clone(),
        clip,
        kind,
    })
}

/// One generated sequence: per frame its mocap time and feet contacts.
pub struct Sequence {
    pub times: Vec<f64>,
    pub contacts: Vec<[bool; 2]>,
}

/// Poses `s` at mocap `times` of `m`, writes frames to `dir` (with noise if given).
pub fn write_sequence(
    s: &Subject,
    m: &Motion,
    times: &[f64],
    dir: &Path,
    noise: Option<(&NoiseLevel, u64)>,
    tick: &(dyn Fn() + Sync),
) -> Result<Sequence> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let rt = Retarget::new(&s.skeleton, &m.clip, m.kind)?;
    let ground = s.ground_offset(&m.clip, &rt);
    let jitter = noise.map(|(lvl, id)| Jitter::new(id, lvl.jitter));
    let feet: Vec<(Vector3<f64>, Vector3<f64>)> = times
        .par_iter()
        .enumerate()
        .map(|(k, &t)| {
            let pose = s.pose_at(&m.clip, &rt, t, ground);
            let mut v = s.skin(&pose);
            let foot = |idx: &[usize]| {
                let mut c =
                    idx.iter().map(|&i| v[i]).sum::<Vector3<f64>>() / idx.len().max(1) as f64;
                c.y = idx.iter().map(|&i| v[i].y).fold(f64::INFINITY, f64::min);
                c
            };
            let f = (foot(&s.sole_left), foot(&s.sole_right));
            if let (Some((lvl, id)), Some(j)) = (noise, &jitter) {
                noise::add_noise(&mut v, lvl, j, id, k, k as f64 / s.def.fps);
            }
            let path = dir.join(format!("{k:06}.ply"));
            mesh_core::io::write_ply(&path, &TriMesh::new(v, s.faces.clone()))?;
            tick();
            Ok(f)
        })
        .collect::<Result<_>>()?;
    let (l, r): (Vec<_>, Vec<_>) = feet.into_iter().unzip();
    Ok(Sequence {
        times: times.to_vec(),
        contacts: truth::contacts(&l, &r, s.def.fps, &truth::ContactRule::default()),
    })
}

/// Frame counts of the whole set (for a progress bar).
pub fn count_frames(cfg: &Config, motions: &[Motion]) -> usize {
    let n = |s: &crate::subject::SubjectDef, m: &Motion| {
        truth::frame_times(&s.style.warp, s.fps, m.clip.duration(), MAX_FRAMES).len()
    };
    let (ntrain, ntest) = (cfg.train.len(), cfg.test.len());
    motions
        .iter()
        .enumerate()
        .map(|(i, m)| {
            if i < ntrain {
                n(&cfg.source, m) + n(&cfg.target, m)
            } else if i < ntrain + ntest {
                2 * n(&cfg.source, m)
            } else {
                2 * n(&cfg.target, m)
            }
        })
        .sum()
}

/// Upper bound on the frames of one sequence.
const MAX_FRAMES: usize = 100_000;

fn contacts_json(c: &[[bool; 2]]) -> Value {
    json!(c
        .iter()
        .map(|[l, r]| [*l as u8, *r as u8])
        .collect::<Vec<_>>())
}

fn round6(x: f64) -> f64 {
    (x * 1e6).round() / 1e6
}

/// Summary of a written set.
pub struct Summary {
    pub frames: usize,
    pub heights: [f64; 2],
    pub vertices: [usize; 2],
}

/// Loads assets, motions and subjects for `cfg`.
pub fn prepare(cfg: &Config) -> Result<(Subject, Subject, Vec<Motion>)> {
    let dir = assets::asset_dir()?;
    let body = BodyAssets::load(&dir)?;
    let a = Subject::build(&body, &cfg.source)?;
    let b = Subject::build(&body, &cfg.target)?;
    let motions = cfg
        .train
        .iter()
        .chain(&cfg.test)
        .chain(&cfg.target_test)
        .map(|d| load_motion(&dir, d, cfg.max_duration))
        .collect::<Result<Vec<_>>>()?;
    Ok((a, b, motions))
}

/// Writes the capture set of `cfg` to `out` (replacing an existing capture set there).
/// `truth_for_train` also writes `truth/<target>/<train motion>/` (used by tests).
pub fn synthesise(
    cfg: &Config,
    out: &Path,
    truth_for_train: bool,
    start: &dyn Fn(usize),
    tick: &(dyn Fn() + Sync),
) -> Result<Summary> {
    let (a, b, motions) = prepare(cfg)?;
    start(count_frames(cfg, &motions));
    if out.exists() && !out.join("set.json").is_file() {
        return Err(Error::file(
            out,
            "exists and is not a capture set (no set.json): not replacing it",
        ));
    }
    let parent = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
    let name = out
        .file_name()
        .ok_or_else(|| Error::file(out, "not a folder name"))?
        .to_string_lossy();
    let tmp: PathBuf = parent.join(format!(".{name}.tmp-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    if let Err(e) = std::fs::create_dir(&tmp) {
        // The temporary's own name would puzzle: the line names the set being written.
        return Err(Error::io(out, e));
    }
    let result = write_all(cfg, &a, &b, &motions, &tmp, truth_for_train, tick);
    if let Err(e) = result {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    if out.exists() {
        std::fs::remove_dir_all(out).map_err(|e| Error::io(out, e))?;
    }
    std::fs::rename(&tmp, out).map_err(|e| Error::io(out, e))?;
    result
}

fn write_all(
    cfg: &Config,
    a: &Subject,
    b: &Subject,
    motions: &[Motion],
    root: &Path,
    truth_for_train: bool,
    tick: &(dyn Fn() + Sync),
) -> Result<Summary> {
    let (ntrain, ntest) = (cfg.train.len(), cfg.test.len());
    let mut frames = 0;
    let mut times: [BTreeMap<String, Value>; 2] = Default::default();
    let mut contacts: [BTreeMap<String, Value>; 2] = Default::default();
    let mut truth_contacts: [BTreeMap<String, Value>; 2] = Default::default();
    let mut pairs = Vec::new();
    let mut sources = BTreeMap::new();
    let subjects = [a, b];
    for (mi, m) in motions.iter().enumerate() {
        let name = &m.def.name;
        sources.insert(
            name.clone(),
            json!(match &m.def.source {
                MotionSource::DeepMimic { file, cycles, turn } if *turn == 0.0 =>
                    format!("pybullet_data/data/motions/{file} x{cycles}"),
                MotionSource::DeepMimic { file, cycles, turn } =>
                    format!("pybullet_data/data/motions/{file} x{cycles}, turned {turn} deg/s"),
                MotionSource::Cmu { t0, t1 } => format!("CMU 01_01.bvh {t0}-{t1} s"),
            }),
        );
        let d = m.clip.duration();
        let noise_of = |s: &Subject| {
            cfg.noise
                .as_ref()
                .map(|l| (l, noise::stream(cfg.seed, &[&s.def.name, name])))
        };
        // Who performs it: training motions both; test motions the source, the target's own
        // test motions the target. The other subject gets the truth (at the performer's times).
        let performers: &[usize] = if mi < ntrain {
            &[0, 1]
        } else if mi < ntrain + ntest {
            &[0]
        } else {
            &[1]
        };
        let mut perf_times = Vec::new();
        for &k in performers {
            let s = subjects[k];
            let t = truth::frame_times(&s.def.style.warp, s.def.fps, d, MAX_FRAMES);
            let seq = write_sequence(
                s,
                m,
                &t,
                &root.join(&s.def.name).join(name),
                noise_of(s),
                tick,
            )?;
            frames += t.len();
            times[k].insert(
                name.clone(),
                json!(t.iter().map(|&x| round6(x)).collect::<Vec<_>>()),
            );
            contacts[k].insert(name.clone(), contacts_json(&seq.contacts));
            perf_times.push(t);
        }
        if performers.len() == 2 {
            let corr = truth::correspondences(&perf_times[0], &perf_times[1]);
            let mut extra = BTreeMap::new();
            extra.insert("correspondences".to_string(), json!(corr));
            pairs.push(TrainPair {
                source: name.clone(),
                target: name.clone(),
                keyposes: truth::keyposes(&corr, cfg.keyposes),
                extra,
            });
        }
        if performers.len() == 1 || truth_for_train {
            // Truth: the other subject performing the motion in its own style, frame for frame
            // with the performer (the source, for training motions).
            let other = 1 - performers[0];
            let s = subjects[other];
            let dir = root.join("truth").join(&s.def.name).join(name);
            let st = write_sequence(s, m, &perf_times[0], &dir, None, tick)?;
            frames += perf_times[0].len();
            truth_contacts[other].insert(name.clone(), contacts_json(&st.contacts));
        }
    }
    for (k, s) in subjects.iter().enumerate() {
        let mut extra = BTreeMap::new();
        extra.insert("description".into(), json!(s.def.description));
        extra.insert("height_m".into(), json!(round6(s.height())));
        extra.insert("n_vertices".into(), json!(s.rest.len()));
        extra.insert("mocap_time".into(), json!(times[k]));
        extra.insert("contacts".into(), json!(contacts[k]));
        if !truth_contacts[k].is_empty() {
            extra.insert("truth_contacts".into(), json!(truth_contacts[k]));
        }
        let spec = SubjectSpec {
            fps: s.def.fps,
            units: "m".into(),
            up: "+y".into(),
            parts: parts::part_tree(),
            curves: parts::part_curves(s)?,
            extra,
        };
        write_json(&root.join(&s.def.name).join("subject.json"), &spec)?;
    }
    let mut extra = BTreeMap::new();
    extra.insert("preset".into(), json!(cfg.preset));
    extra.insert("seed".into(), json!(cfg.seed));
    if cfg.more_training {
        extra.insert("more_training".into(), json!(true));
    }
    extra.insert(
        "noise".into(),
        match &cfg.noise {
            Some(n) => json!({"surface_sigma_m": n.surface, "jitter_m": n.jitter}),
            None => Value::Null,
        },
    );
    extra.insert("mocap".into(), json!(sources));
    if !cfg.target_test.is_empty() {
        let names: Vec<&str> = cfg.target_test.iter().map(|m| m.name.as_str()).collect();
        extra.insert("target_test".into(), json!(names));
    }
    let set = SetSpec {
        source: a.def.name.clone(),
        target: b.def.name.clone(),
        train: pairs,
        test: cfg.test.iter().map(|m| m.name.clone()).collect(),
        extra,
    };
    write_json(&root.join("set.json"), &set)?;
    Ok(Summary {
        frames,
        heights: [a.height(), b.height()],
        vertices: [a.rest.len(), b.rest.len()],
    })
}

fn write_json<T: serde::Serialize>(path: &Path, v: &T) -> Result<()> {
    let mut s = serde_json::to_string_pretty(v).map_err(|e| Error::file(path, e.to_string()))?;
    s.push('\n');
    mesh_core::atomic::write_bytes_atomic(path, s.as_bytes())
}

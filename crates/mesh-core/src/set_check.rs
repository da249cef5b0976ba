//! Validation of a whole capture set (layout in [`crate::capture_set`] and
//! docs/FORMATS.md) that collects every problem instead of stopping at the
//! first, for the `check-set` stage.
//!
//! Checked, in this order (a problem that makes later checks meaningless,
//! such as an unreadable `set.json`, ends the check of what depends on it):
//! - `set.json`: readable JSON of the documented shape, plain subject and
//!   motion names, at least one training pair, key-poses in every pair;
//! - every subject named: its folder and `subject.json`, the frame rate
//!   (`fps` within 1 to 10,000 frames per second), the up axis, the part tree, and every curve
//!   (a closed loop of the template, [`crate::capture_set::resolve_loop`])
//!   and, when all curves are valid, that they cut the template into parts
//!   ([`crate::segmentation::segment`]);
//! - every motion named (training pairs, `test`, `target_test`): its folder
//!   exists and holds a readable frame sequence ([`crate::sequence::frame_files`]);
//! - every frame of every motion folder of both subjects and of every folder
//!   of their ground truth (`truth/<subject>/*`): readable, with the
//!   template's vertex count and faces;
//! - every key-pose `[source frame, target frame]` within its two motions.
//!
//! Beside the problems, the report lists what the set lacks that only
//! `synth`'s sets or a lab's annotation have, and what the pipelines do
//! without it ([`Report::notes`]): part curves, true frame correspondences,
//! foot contacts, ground truth of the test motions.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::cli::ProgressBar;
use crate::capture_set::{check_name, CaptureSet, SetSpec, SubjectSpec};
use crate::mesh::TriMesh;
use crate::topology::Topology;

/// One problem: the file or folder it is about, and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    pub path: PathBuf,
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.message)
    }
}

/// What [`check_set`] found: every problem, and how much it looked at.
#[derive(Clone, Debug, Default)]
pub struct Report {
    pub problems: Vec<Problem>,
    /// What the set lacks and what the pipelines do without it: not problems.
    pub notes: Vec<Problem>,
    pub subjects: usize,
    pub motions: usize,
    pub frames: usize,
}

impl Report {
    fn add(&mut self, path: impl AsRef<Path>, message: impl Into<String>) {
        self.problems.push(Problem { path: path.as_ref().to_path_buf(), message: message.into() });
    }

    fn note(&mut self, path: impl AsRef<Path>, message: impl Into<String>) {
        self.notes.push(Problem { path: path.as_ref().to_path_buf(), message: message.into() });
    }
}

/// A subject's template with its topology, once loaded.
struct Template {
    path: PathBuf,
    mesh: TriMesh,
}

/// Checks the capture set in `dir` (see the module doc).
pub fn check_set(dir: impl AsRef<Path>) -> Report {
    let root = dir.as_ref().to_path_buf();
    let mut report = Report::default();
    let set_json = root.join("set.json");
    let spec: SetSpec = match read_json(&set_json) {
        Ok(s) => s,
        Err(e) => {
            report.add(&set_json, e);
            return report;
        }
    };
    check_set_json(&spec, &set_json, &mut report);
    let set = CaptureSet { root: root.clone(), spec };

    // Motions named by set.json, per subject.
    let mut named: BTreeMap<&str, Vec<(String, &str)>> = BTreeMap::new();
    for t in &set.spec.train {
        named.entry(&set.spec.source).or_default().push((t.source.clone(), "training"));
        named.entry(&set.spec.target).or_default().push((t.target.clone(), "training"));
    }
    for m in &set.spec.test {
        named.entry(&set.spec.source).or_default().push((m.clone(), "test"));
    }
    match set.spec.extra.get("target_test") {
        None => {}
        Some(serde_json::Value::Array(a)) if a.iter().all(|v| v.is_string()) => {
            for m in a.iter().filter_map(|v| v.as_str()) {
                named.entry(&set.spec.target).or_default().push((m.to_string(), "target test"));
            }
        }
        Some(_) => report.add(&set_json, "'target_test' must be a list of motion names"),
    }

    let mut subjects: Vec<&str> = vec![&set.spec.source, &set.spec.target];
    subjects.dedup();
    let mut n_frames: BTreeMap<(String, String), usize> = BTreeMap::new();
    // Frames read so far out of those listed so far (the total grows folder by folder).
    let bar = crate::cli::stage_progress(0, "frames read");
    for subject in subjects {
        if check_name("subject", subject).is_err() {
            continue;
        }
        report.subjects += 1;
        let sdir = set.subject_dir(subject);
        if !sdir.is_dir() {
            report.add(&sdir, format!("subject '{subject}' named in set.json has no folder"));
            continue;
        }
        let template = check_subject(&set, subject, &mut report);
        // Named motions must exist.
        let mut seen = std::collections::BTreeSet::new();
        for (m, role) in named.get(subject).into_iter().flatten() {
            if check_name("motion", m).is_err() || !seen.insert(m.clone()) {
                continue;
            }
            let d = set.motion_dir(subject, m);
            if !d.is_dir() {
                report.add(&d, format!("{role} motion '{m}' of subject '{subject}' (named in set.json) has no folder"));
            }
        }
        // Every motion folder's frames, and its ground truth.
        let motions = match set.motions(subject) {
            Ok(m) => m,
            Err(e) => {
                report.add(&sdir, e.to_string());
                continue;
            }
        };
        for m in motions {
            report.motions += 1;
            let d = set.motion_dir(subject, &m);
            if let Some(n) = check_frames(&d, template.as_ref(), &mut report, &bar) {
                n_frames.insert((subject.to_string(), m.clone()), n);
            }
        }
        // Ground truth: the subject performing motions (its own or the other subject's).
        let truth = set.root.join("truth").join(subject);
        if truth.is_dir() {
            let mut dirs: Vec<PathBuf> = match std::fs::read_dir(&truth) {
                Ok(rd) => rd.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.is_dir()).collect(),
                Err(e) => {
                    report.add(&truth, e.to_string());
                    Vec::new()
                }
            };
            dirs.sort();
            for t in dirs {
                check_frames(&t, template.as_ref(), &mut report, &bar);
            }
        }
    }

    bar.finish_and_clear();
    // Key-poses within their motions.
    for (i, t) in set.spec.train.iter().enumerate() {
        let a = n_frames.get(&(set.spec.source.clone(), t.source.clone()));
        let b = n_frames.get(&(set.spec.target.clone(), t.target.clone()));
        let (Some(&na), Some(&nb)) = (a, b) else { continue };
        for kp in &t.keyposes {
            if kp[0] >= na || kp[1] >= nb {
                report.add(
                    &set_json,
                    format!(
                        "training pair {i} ({} / {}): key-pose {kp:?} is outside the motions' {na} / {nb} frames (frames count from 0)",
                        t.source, t.target
                    ),
                );
            }
        }
    }
    missing_annotations(&set, &set_json, &mut report);
    // A template that is also a frame is reported once.
    let mut seen = std::collections::BTreeSet::new();
    report.problems.retain(|p| seen.insert(p.to_string()));
    report
}

/// The checks of `set.json` that need no other file.
fn check_set_json(spec: &SetSpec, set_json: &Path, report: &mut Report) {
    for (what, name) in [("source subject", &spec.source), ("target subject", &spec.target)] {
        if let Err(e) = check_name(what, name) {
            report.add(set_json, e);
        }
    }
    if spec.train.is_empty() {
        report.add(set_json, "no training motion pairs ('train' is empty)");
    }
    for (i, t) in spec.train.iter().enumerate() {
        for (what, name) in [("training source motion", &t.source), ("training target motion", &t.target)] {
            if let Err(e) = check_name(what, name) {
                report.add(set_json, format!("training pair {i}: {e}"));
            }
        }
        if t.keyposes.is_empty() {
            report.add(set_json, format!("training pair {i} ({} / {}) has no key-poses", t.source, t.target));
        }
    }
    for m in &spec.test {
        if let Err(e) = check_name("test motion", m) {
            report.add(set_json, e);
        }
    }
}

/// Checks `subject.json` and the curves against the template; returns the
/// template when it could be read.
fn check_subject(set: &CaptureSet, subject: &str, report: &mut Report) -> Option<Template> {
    let json = set.subject_json(subject);
    if !json.is_file() {
        report.add(&json, format!("subject '{subject}' has no description (subject.json is missing)"));
        return None;
    }
    let mut value: serde_json::Value = match read_json(&json) {
        Ok(v) => v,
        Err(e) => {
            report.add(&json, e);
            return None;
        }
    };
    let fps_ok = match value.get("fps") {
        None => {
            report.add(&json, "no frame rate ('fps' is missing)");
            false
        }
        Some(v) => match v.as_f64() {
            Some(f) => match crate::frame_rate::check_fps(f) {
                Ok(_) => true,
                Err(e) => {
                    report.add(&json, format!("'fps': {e}"));
                    false
                }
            },
            None => {
                report.add(&json, format!("'fps' must be a number of frames per second, got {v}"));
                false
            }
        },
    };
    if !fps_ok {
        // Reported; the rest of the description is still checked.
        if let Some(o) = value.as_object_mut() {
            o.insert("fps".into(), serde_json::json!(1.0));
        }
    }
    let spec: SubjectSpec = match serde_json::from_value(value) {
        Ok(s) => s,
        Err(e) => {
            report.add(&json, format!("invalid subject description: {e}"));
            return None;
        }
    };
    if spec.up_vector().is_none() {
        report.add(&json, format!("'up' must be one of +x -x +y -y +z -z, got '{}'", spec.up));
    }
    let parts_ok = if spec.needs_curves() {
        report.note(
            &json,
            "no part curves: the pipelines propose them (propose-curves) and draw them to <out>/work/<subject>/curves.png",
        );
        false
    } else {
        match spec.check_parts() {
            Ok(()) => true,
            Err(e) => {
                report.add(&json, e.to_string());
                false
            }
        }
    };
    if !spec.extra.contains_key("contacts") {
        report.note(&json, "no foot contacts ('contacts'): detected from the meshes where needed");
    }
    let template = template_of(set, subject, &spec, report)?;
    let topology = Topology::new(template.mesh.vertices.len(), &template.mesh.faces);
    let mut curves_ok = parts_ok;
    for (part, loops) in &spec.curves {
        for (k, lp) in loops.iter().enumerate() {
            if let Err(e) = crate::capture_set::resolve_loop(&template.mesh, &topology, lp) {
                report.add(&json, format!("part '{part}', curve {}: {e}", k + 1));
                curves_ok = false;
            }
        }
    }
    if curves_ok {
        if let Err(e) = crate::segmentation::segment(&template.mesh, &spec) {
            report.add(&json, format!("curves against the template {}: {e}", template.path.display()));
        }
    }
    Some(template)
}

/// Notes what the set lacks that a lab may not have: true frame correspondences of
/// the training pairs, and ground truth of the test motions.
fn missing_annotations(set: &CaptureSet, set_json: &Path, report: &mut Report) {
    let without: Vec<&str> = set
        .spec
        .train
        .iter()
        .filter(|t| !t.extra.contains_key("correspondences"))
        .map(|t| t.source.as_str())
        .collect();
    if !without.is_empty() {
        report.note(
            set_json,
            format!(
                "no true frame correspondences ('correspondences') for {} of {} training pairs: the learning curves use the DTW pairs (labelled 'dtw')",
                without.len(),
                set.spec.train.len()
            ),
        );
    }
    let target = &set.spec.target;
    let no_truth: Vec<&str> = set.spec.test.iter().filter(|m| !set.has_truth(target, m)).map(String::as_str).collect();
    if !no_truth.is_empty() {
        report.note(
            set.root.join("truth").join(target),
            format!(
                "no ground truth of the test motions {}: their transfers are scored without it (per-frame confidence, foot sliding on the source's contacts, surface quality)",
                no_truth.join(", ")
            ),
        );
    }
}

/// Reads the subject's template (its `template` field, else the first frame
/// of its first training motion).
fn template_of(set: &CaptureSet, subject: &str, spec: &SubjectSpec, report: &mut Report) -> Option<Template> {
    // A missing training motion is reported with the named motions.
    let path = set.template_path(subject, spec).ok()?;
    match crate::io::read_mesh(&path) {
        Ok(mesh) => Some(Template { path, mesh }),
        Err(e) => {
            report.add(&path, strip(&e.to_string(), &path));
            None
        }
    }
}

/// Reads a JSON file; the error is one line without the file name.
fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, String> {
    let bytes = crate::input::read_regular_file(path).map_err(|e| strip(&e.to_string(), path))?;
    serde_json::from_slice(&bytes).map_err(|e| format!("invalid JSON: {e}"))
}

fn strip(msg: &str, path: &Path) -> String {
    let prefix = format!("{}: ", path.display());
    msg.strip_prefix(&prefix).unwrap_or(msg).to_string()
}

/// Checks a folder of frames: the numbering, each frame readable, and (with
/// a template) each frame's vertex count and faces. Returns the frame count
/// when the numbering is valid.
fn check_frames(dir: &Path, template: Option<&Template>, report: &mut Report, bar: &ProgressBar) -> Option<usize> {
    let files = match crate::frame_pattern::detect(dir) {
        Ok(l) => l.files,
        Err(e) => {
            report.add(dir, strip(&e.to_string(), dir));
            return None;
        }
    };
    report.frames += files.len();
    bar.inc_length(files.len() as u64);
    // Per frame: None when it matches, else the problem.
    let results: Vec<Option<(PathBuf, String, bool)>> = files
        .par_iter()
        .map(|f| match crate::io::read_mesh(f) {
            Err(e) => Some((f.clone(), strip(&e.to_string(), f), true)),
            Ok(m) => {
                let t = template?;
                if m.vertices.len() != t.mesh.vertices.len() {
                    Some((f.clone(), format!("has {} vertices but the template ({}) has {}", m.vertices.len(), t.path.display(), t.mesh.vertices.len()), false))
                } else if m.faces != t.mesh.faces {
                    Some((f.clone(), format!("its faces differ from the template's ({}): a subject's frames share one topology", t.path.display()), false))
                } else {
                    None
                }
            }
        })
        .inspect(|_| bar.inc(1))
        .collect();
    // Unreadable frames one line each; topology mismatches one line per
    // folder (naming the first), since a whole folder usually shares the cause.
    let mut mismatched: Vec<(PathBuf, String)> = Vec::new();
    for (path, msg, unreadable) in results.into_iter().flatten() {
        if unreadable {
            report.add(&path, msg);
        } else {
            mismatched.push((path, msg));
        }
    }
    if let Some((path, msg)) = mismatched.first() {
        let more = match mismatched.len() {
            1 => String::new(),
            n => format!(" ({n} of the folder's {} frames differ)", files.len()),
        };
        report.add(path, format!("{msg}{more}"));
    }
    Some(files.len())
}

//! A capture set (docs/FORMATS.md, "Capture set") from two characters: what
//! a lab would have, the frames, the frame rate and key-poses, and the
//! target's own performance of each test motion as a reference for scoring.
//!
//! ```text
//! <set>/set.json                          source, target, training pairs with 5 key-poses, test motions
//! <set>/<subject>/subject.json            fps, units, up (no parts, curves or contacts)
//! <set>/<subject>/<motion>/000000.ply     the source's training and test motions, the target's training motions
//! <set>/reference/<target>/<motion>/      the target performing each test motion its own way
//! ```
//!
//! The reference is not ground truth: the two characters' motions of one
//! name have different lengths and timing, so frame `i` of the reference is
//! not the instant of source frame `i`. Scoring compares them after time
//! normalisation.

use std::path::{Path, PathBuf};

use mesh_core::sequence::MeshSequence;
use mesh_core::topology::Topology;
use mesh_core::{Error, Result};
use serde_json::json;

use crate::character::{Character, METRES_PER_UNIT};
use crate::motions::{keyposes, motion, sample, MotionSpec};

/// Key-poses per training pair.
pub const KEYPOSES: usize = 5;

/// What one set is made of.
#[derive(Clone, Debug)]
pub struct SetPlan<'a> {
    pub source: &'a Character,
    pub target: &'a Character,
    pub train: &'a [&'a str],
    pub test: &'a [&'a str],
    pub fps: f64,
    /// Where the characters came from, recorded in `set.json`.
    pub provenance: &'a str,
}

/// Per subject of a written set: its vertex, face and piece counts and its height.
#[derive(Clone, Debug, PartialEq)]
pub struct SubjectSummary {
    pub name: String,
    pub vertices: usize,
    pub faces: usize,
    pub components: usize,
    pub height_m: f64,
}

/// A character performing `spec` at `fps`.
pub fn perform(character: &Character, spec: &MotionSpec, fps: f64) -> Result<MeshSequence> {
    let frames = sample(character, spec, fps).map_err(Error::invalid)?;
    Ok(MeshSequence::new(
        character.faces(),
        frames.iter().map(|(legs, torso)| character.pose(*legs, *torso)).collect(),
    ))
}

fn spec_of(name: &str) -> Result<&'static MotionSpec> {
    motion(name).ok_or_else(|| Error::invalid(format!("no motion named '{name}'")))
}

/// Vertex, face and piece counts and the standing height of a character.
pub fn summary(character: &Character, fps: f64) -> Result<SubjectSummary> {
    let stand = perform(character, spec_of("walk")?, fps)?;
    let faces = character.faces();
    let components = Topology::new(character.n_vertices(), &faces).connected_components().len();
    let ys = stand.frames[0].iter().map(|p| p.y);
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
    Ok(SubjectSummary {
        name: character.name.clone(),
        vertices: character.n_vertices(),
        faces: faces.len(),
        components,
        height_m: hi - lo,
    })
}

fn write_json(path: &Path, value: &serde_json::Value) -> Result<()> {
    let mut s = serde_json::to_string_pretty(value).map_err(|e| Error::file(path, e.to_string()))?;
    s.push('\n');
    mesh_core::atomic::write_bytes_atomic(path, s.as_bytes())
}

/// Writes the set of `plan` to `out`, replacing an earlier capture set there
/// as a whole (a folder that is not a capture set is left alone, with an error).
pub fn write_set(plan: &SetPlan, out: &Path) -> Result<[SubjectSummary; 2]> {
    if plan.source.name == plan.target.name {
        return Err(Error::invalid(format!("a pair needs two characters, got {} twice", plan.source.name)));
    }
    if out.exists() && !out.join("set.json").is_file() {
        return Err(Error::file(out, "exists and is not a capture set (no set.json): not replacing it"));
    }
    let train: Vec<&MotionSpec> = plan.train.iter().map(|m| spec_of(m)).collect::<Result<_>>()?;
    let test: Vec<&MotionSpec> = plan.test.iter().map(|m| spec_of(m)).collect::<Result<_>>()?;
    let summaries = [summary(plan.source, plan.fps)?, summary(plan.target, plan.fps)?];
    mesh_core::atomic::write_dir_atomic(out, &|_| false, |tmp| {
        let (src, tgt) = (&plan.source.name, &plan.target.name);
        let mut pairs = Vec::new();
        for spec in &train {
            let a = perform(plan.source, spec, plan.fps)?;
            let b = perform(plan.target, spec, plan.fps)?;
            a.write_dir(tmp.join(src).join(spec.name))?;
            b.write_dir(tmp.join(tgt).join(spec.name))?;
            pairs.push(json!({
                "source": spec.name,
                "target": spec.name,
                "keyposes": keyposes(a.n_frames(), b.n_frames(), KEYPOSES),
            }));
        }
        for spec in &test {
            perform(plan.source, spec, plan.fps)?.write_dir(tmp.join(src).join(spec.name))?;
            perform(plan.target, spec, plan.fps)?.write_dir(reference_dir(tmp, tgt, spec.name))?;
        }
        for s in &summaries {
            write_json(
                &tmp.join(&s.name).join("subject.json"),
                &json!({
                    "fps": plan.fps,
                    "units": "m",
                    "up": "+y",
                    "description": format!("{} (Quake 3 MD3 player, {METRES_PER_UNIT} m per unit)", s.name),
                    "height_m": s.height_m,
                    "n_vertices": s.vertices,
                }),
            )?;
        }
        let mut reference = serde_json::Map::new();
        reference.insert(tgt.clone(), json!(plan.test));
        write_json(
            &tmp.join("set.json"),
            &json!({
                "source": src,
                "target": tgt,
                "train": pairs,
                "test": plan.test,
                "reference": reference,
                "characters": plan.provenance,
                "motions": train.iter().chain(&test).map(|m| (m.name, m.about)).collect::<std::collections::BTreeMap<_, _>>(),
            }),
        )
    })?;
    Ok(summaries)
}

/// `<set>/reference/<subject>/<motion>`: `subject` performing `motion` its own way.
pub fn reference_dir(set: &Path, subject: &str, motion: &str) -> PathBuf {
    set.join("reference").join(subject).join(motion)
}

//! The subject descriptions the pipelines' stages read. A subject whose `subject.json` has its
//! part curves is read as it is; one without them (a lab's own set) gets a `propose-curves` task
//! that writes a described copy, `OUT/work/<subject>/subject.json`, with the check picture
//! `OUT/work/<subject>/curves.png` beside it, and every later stage reads the copy.

use anyhow::{Context, Result};
use mesh_core::capture_set::{CaptureSet, SubjectSpec, PROPOSED_PART_TREE};

use crate::flag::{flag, ProposeCurves};
use crate::task::{s, Graph, Task};

/// One subject as the pipelines' stages see it.
#[derive(Clone, Debug)]
pub struct Subject {
    /// The `subject.json` the stages read (the set's own, or the proposed copy).
    pub json: String,
    /// The subject's template mesh.
    pub template: String,
    /// Its part names, in name order (as the part tree's keys).
    pub parts: Vec<String>,
    /// The set's own `subject.json`, and the description loaded from it.
    pub source_json: String,
    pub spec: SubjectSpec,
}

impl Subject {
    /// Whether the pipelines propose the subject's curves.
    pub fn proposed(&self) -> bool {
        self.json != self.source_json
    }
}

/// The subject `name` of `set`, adding the `propose-curves` task to `graph` (once) when its
/// description has no curves. `work` is the pipelines' `OUT/work`.
pub fn subject(set: &CaptureSet, work: &str, name: &str, graph: &mut Graph) -> Result<Subject> {
    let source_json = set.subject_json(name).to_string_lossy().into_owned();
    let spec = SubjectSpec::load(&source_json)?;
    let template = set
        .template_path(name, &spec)
        .with_context(|| format!("subject {name}"))?
        .to_string_lossy()
        .into_owned();
    if !spec.needs_curves() {
        let parts = spec.parts.keys().cloned().collect();
        return Ok(Subject { json: source_json.clone(), template, parts, source_json, spec });
    }
    let json = format!("{work}/{name}/subject.json");
    if graph.producer(&json).is_none() {
        let picture = format!("{work}/{name}/curves.png");
        let args = vec![
            s("-q"), source_json.clone(), flag!(ProposeCurves, template), template.clone(), flag!(ProposeCurves, render), picture,
            flag!(ProposeCurves, out), json.clone(),
        ];
        graph.push(Task::run("propose-curves", json.clone(), vec![source_json.clone(), template.clone()], args).mkdir_target());
    }
    let mut parts: Vec<String> = match spec.parts.is_empty() {
        true => PROPOSED_PART_TREE.iter().map(|(p, _)| p.to_string()).collect(),
        false => spec.parts.keys().cloned().collect(),
    };
    parts.sort();
    Ok(Subject { json, template, parts, source_json, spec })
}

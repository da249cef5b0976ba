//! Whether a variation model was trained on a given group: the stages that take both
//! (`hmc-sample`, `variation-eval`) refuse a group the model was not trained on, which would
//! otherwise give sources, statistics and grounding of another body or motion set.

use mesh_core::{Error, Result};

use crate::group::Group;
use crate::train::VariationModel;

/// Fails unless `group` is the one `model` was trained on: the same name and subject, the same
/// template (vertex positions and faces, exactly) and the same sequences (names, in order, of the
/// model's frame count).
pub fn check(model: &VariationModel, group: &Group) -> Result<()> {
    let names = |v: Vec<&str>| v.join(", ");
    let model_seqs = names(model.sequences.iter().map(|s| s.name.as_str()).collect());
    let group_seqs = names(group.sequences.iter().map(|s| s.name.as_str()).collect());
    let problem = if (model.group.as_str(), model.subject.as_str()) != (group.name.as_str(), group.subject.as_str()) {
        Some(format!(
            "the model was trained on group '{}' of subject '{}', not on '{}' of '{}'",
            model.group, model.subject, group.name, group.subject
        ))
    } else if model.template != group.template || model.faces != group.faces {
        Some(format!("the model was trained on another template of subject '{}' (rebuilt since?)", model.subject))
    } else if model_seqs != group_seqs || model.frames != group.n_frames() {
        Some(format!(
            "the model was trained on sequences [{model_seqs}] of {} frames, the group holds [{group_seqs}] of {}",
            model.frames,
            group.n_frames()
        ))
    } else {
        None
    };
    match problem {
        Some(p) => Err(Error::invalid(p)),
        None => Ok(()),
    }
}

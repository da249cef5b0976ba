//! Feet-contact annotations: which foot touches the ground in each frame.
//!
//! A subject description (`subject.json`) may carry an extra field
//! `"contacts": { "<motion>": [[left, right], ...] }` with one `[0|1, 0|1]` pair per frame of the
//! motion (1 = the foot is on the ground), and `"truth_contacts"` in the same form for the
//! subject's ground-truth sequences. `synth` writes both; users annotate their own captures the
//! same way (see `docs/FORMATS.md`).

use crate::capture_set::SubjectSpec;
use crate::{Error, Result};

/// Per-frame `[left, right]` contact flags.
pub type Contacts = Vec<[bool; 2]>;

/// Contacts of `motion` from `spec`'s `contacts` field; `None` when the motion is not annotated.
/// `n_frames` is the motion's frame count: an annotation of another length is an error.
pub fn from_subject(spec: &SubjectSpec, motion: &str, n_frames: usize) -> Result<Option<Contacts>> {
    from_subject_field(spec, "contacts", motion, n_frames)
}

/// Contacts of `motion` from the field `field` of `spec` (`contacts` or `truth_contacts`).
pub fn from_subject_field(
    spec: &SubjectSpec,
    field: &str,
    motion: &str,
    n_frames: usize,
) -> Result<Option<Contacts>> {
    let Some(all) = spec.extra.get(field) else {
        return Ok(None);
    };
    let Some(obj) = all.as_object() else {
        return Err(Error::invalid(format!(
            "\"{field}\" must be an object {{motion: [[left, right], ...]}}"
        )));
    };
    let Some(list) = obj.get(motion) else {
        return Ok(None);
    };
    let frames = list.as_array().ok_or_else(|| {
        Error::invalid(format!(
            "contacts of '{motion}' must be a list of [left, right] pairs"
        ))
    })?;
    if frames.len() != n_frames {
        return Err(Error::invalid(format!(
            "contacts of '{motion}' list {} frames but the motion has {n_frames}",
            frames.len()
        )));
    }
    let flag = |v: &serde_json::Value| match v {
        serde_json::Value::Bool(b) => Some(*b),
        serde_json::Value::Number(n) => match n.as_u64() {
            Some(0) => Some(false),
            Some(1) => Some(true),
            _ => None,
        },
        _ => None,
    };
    frames
        .iter()
        .enumerate()
        .map(|(i, f)| match f.as_array().map(|p| p.as_slice()) {
            Some([l, r]) => match (flag(l), flag(r)) {
                (Some(l), Some(r)) => Ok([l, r]),
                _ => Err(Error::invalid(format!(
                    "contacts of '{motion}', frame {i}: flags must be 0/1 or true/false"
                ))),
            },
            _ => Err(Error::invalid(format!(
                "contacts of '{motion}', frame {i}: expected [left, right]"
            ))),
        })
        .collect::<Result<Contacts>>()
        .map(Some)
}

/// Number of feet whose contact state differs between two frames (0, 1 or 2).
pub fn mismatch(a: [bool; 2], b: [bool; 2]) -> usize {
    (a[0] != b[0]) as usize + (a[1] != b[1]) as usize
}

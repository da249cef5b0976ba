//! The front end's tasks both pipelines read, per subject: `segment` (its parts,
//! `OUT/work/<subject>/parts.seg`) and `align` of a motion (`OUT/work/<subject>/<motion>.aligned`,
//! in the plan's alignment frame). Each task is added once, by the first pipeline that needs it.
//! A variation group modelled as one part reads motions aligned on the whole body without the
//! parts (`OUT/work/<subject>/body/<motion>.aligned`), so that it needs no segmentation.

use anyhow::{Context, Result};
use capture::align::AlignFrame;
use mesh_core::capture_set::CaptureSet;

use crate::flag::{flag, Align, Segment};
use crate::options::value_name;
use crate::subjects::Subject;
use crate::task::{s, Graph, Task};
use crate::transfer::join;

/// The subject `x`'s segmentation, under `work` (`OUT/work`).
pub fn seg(work: &str, x: &str) -> String {
    format!("{work}/{x}/parts.seg")
}

/// The subject `x`'s motion `m` aligned in the plan's frame.
pub fn aligned(work: &str, x: &str, m: &str) -> String {
    format!("{work}/{x}/{m}.aligned")
}

/// The subject `x`'s motion `m` aligned on the whole body, without the parts.
pub fn aligned_whole_body(work: &str, x: &str, m: &str) -> String {
    format!("{work}/{x}/body/{m}.aligned")
}

/// Adds the `segment` task of subject `x` unless the graph has it; returns its target.
pub fn segment(work: &str, x: &str, subject: &Subject, graph: &mut Graph) -> String {
    let target = seg(work, x);
    if graph.producer(&target).is_none() {
        let args = vec![s("-q"), subject.json.clone(), flag!(Segment, template), subject.template.clone(), flag!(Segment, out), target.clone()];
        graph.push(Task::run("segment", target.clone(), vec![subject.json.clone(), subject.template.clone()], args).mkdir_target());
    }
    target
}

/// Adds the `align` task of subject `x`'s motion `m` in `frame` (fitted with the subject's
/// segmentation, which the caller adds) unless the graph has it; returns its target.
pub fn align(set: &CaptureSet, work: &str, x: &str, m: &str, subject: &Subject, frame: AlignFrame, graph: &mut Graph) -> Result<String> {
    let target = aligned(work, x, m);
    if graph.producer(&target).is_none() {
        let frames = set.frames(x, m).with_context(|| format!("subject {x}, motion {m}"))?;
        let mut inputs = vec![subject.json.clone(), subject.template.clone(), seg(work, x)];
        inputs.extend(frames.iter().map(|f| f.to_string_lossy().into_owned()));
        let args = vec![
            s("-q"), flag!(Align, frame), value_name(frame), flag!(Align, segmentation), seg(work, x),
            flag!(Align, subject), subject.json.clone(), flag!(Align, template), subject.template.clone(), join(&set.root, &[x, m]),
            flag!(Align, out), target.clone(),
        ];
        graph.push(Task::run("align", target.clone(), inputs, args).mkdir_target());
    }
    Ok(target)
}

/// Adds the `align --frame body` task (no segmentation) of subject `x`'s motion `m` unless the
/// graph has it; returns its target.
pub fn align_whole_body(set: &CaptureSet, work: &str, x: &str, m: &str, subject: &Subject, graph: &mut Graph) -> Result<String> {
    let target = aligned_whole_body(work, x, m);
    if graph.producer(&target).is_none() {
        let frames = set.frames(x, m).with_context(|| format!("subject {x}, motion {m}"))?;
        let mut inputs = vec![subject.json.clone(), subject.template.clone()];
        inputs.extend(frames.iter().map(|f| f.to_string_lossy().into_owned()));
        let args = vec![
            s("-q"), flag!(Align, frame), value_name(AlignFrame::Body), flag!(Align, subject), subject.json.clone(), flag!(Align, template),
            subject.template.clone(), join(&set.root, &[x, m]), flag!(Align, out), target.clone(),
        ];
        graph.push(Task::run("align", target.clone(), inputs, args).mkdir_target());
    }
    Ok(target)
}

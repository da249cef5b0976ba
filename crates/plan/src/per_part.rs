//! Models fitted part by part: a model of several parts becomes one task per part (`<stage>
//! --part NAME`, writing a piece and, where the stage reports, the piece's report) and one
//! `merge-parts` task joining them into the model the single-process run writes, byte for
//! byte (docs/CLUSTER.md). One array task then fits one part.

use crate::task::{Task, Step};

fn s(x: impl Into<String>) -> String {
    x.into()
}

/// The folder of a model's pieces: `work/A/pca.model` -> `work/A/pca.parts`.
pub fn pieces_dir(model: &str) -> String {
    format!("{}.parts", model.strip_suffix(".model").unwrap_or(model))
}

/// The kind (job array) of the merges of `stage`'s pieces: `merge-pca-fit`, ...; apart from the
/// stage's own, because its consumers and the next stage's pieces read them.
pub fn merge_kind(stage: &str) -> String {
    format!("merge-{stage}")
}

/// The tasks writing `model` (and `report`) with `stage args --out model [--report report]`:
/// that one task when `parts` has fewer than two names, otherwise one `--part` task per name
/// and their merge. `inputs` are the stage's; the merge's target is `model`, written last.
/// Every task creates its target's folder.
pub fn fit(stage: &str, model: &str, report: Option<&str>, inputs: Vec<String>, args: Vec<String>, parts: &[String]) -> Vec<Task> {
    let with_outputs = |out: &str, rep: Option<String>| {
        let mut a = args.clone();
        a.extend([s("--out"), s(out)]);
        if let Some(r) = rep {
            a.extend([s("--report"), r]);
        }
        a
    };
    if parts.len() < 2 {
        return vec![Task::run(stage, model, inputs, with_outputs(model, report.map(s))).mkdir_target()];
    }
    let dir = pieces_dir(model);
    let mut tasks = Vec::new();
    let mut merge_args: Vec<String> = Vec::new();
    let mut piece_reports: Vec<String> = Vec::new();
    let mut pieces = Vec::new();
    for part in parts {
        let piece = format!("{dir}/{part}.piece");
        let piece_report = report.map(|_| format!("{dir}/{part}.json"));
        let mut a = with_outputs(&piece, piece_report.clone());
        a.extend([s("--part"), part.clone()]);
        tasks.push(Task::run(stage, piece.clone(), inputs.clone(), a).mkdir_target());
        merge_args.push(piece.clone());
        pieces.push(piece);
        if let Some(r) = piece_report {
            piece_reports.extend([s("--piece-report"), r]);
        }
    }
    let mut a = vec![s("-q")];
    a.extend(merge_args);
    a.extend([s("--out"), s(model)]);
    if let Some(r) = report {
        a.extend(piece_reports);
        a.extend([s("--report"), s(r)]);
    }
    tasks.push(Task {
        kind: merge_kind(stage),
        target: s(model),
        inputs: pieces,
        dirs: Vec::new(),
        steps: vec![Step::Run { bin: s("merge-parts"), args: a }],
    });
    tasks
}

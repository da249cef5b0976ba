//! Models of several parts: under Slurm one task per part (`<stage> --part NAME`, writing a
//! piece and, where the stage reports, the piece's report) and one `merge-parts` task joining
//! them into the model the single-process run writes, byte for byte (docs/FORMATS.md,
//! "Per-part pieces"), so that one array task fits one part; under make one task per model,
//! whose stage fits the parts in parallel on the machine's cores ([`PartTasks`]).

use crate::flag::{flag, GpdmTrain, GprTrain, MergeParts, PcaFit};
use crate::task::{s, PartTasks, Task};

/// The folder of a model's pieces: `work/A/pca.model` -> `work/A/pca.parts`.
pub fn pieces_dir(model: &str) -> String {
    format!("{}.parts", model.strip_suffix(".model").unwrap_or(model))
}

/// The kind (job array) of the merges of `stage`'s pieces: `merge-pca-fit`, ... A kind of its
/// own, apart from the stage's: a merge reads the stage's pieces, so it runs after their array.
pub fn merge_kind(stage: &str) -> String {
    format!("merge-{stage}")
}

/// The tasks writing `model` (and `report`) with `stage args --out model [--report report]`:
/// that one task when `parts` has fewer than two names or `split` is
/// [`PartTasks::OnePerModel`], otherwise one task per part writing `<pieces_dir>/<part>.piece`
/// (and `<part>.json`, its report) and the merge of the pieces, whose target is `model`
/// (merge-parts writes the report before the model). `inputs` are the stage's. Every task
/// creates its target's folder.
pub fn fit(
    split: PartTasks,
    stage: &str,
    model: &str,
    report: Option<&str>,
    inputs: Vec<String>,
    args: Vec<String>,
    parts: &[String],
) -> Vec<Task> {
    let with_outputs = |out: &str, report: Option<&str>| {
        let mut a = args.clone();
        a.extend([flag!(PcaFit | GprTrain | GpdmTrain, out), s(out)]);
        if let Some(r) = report {
            a.extend([flag!(PcaFit | GpdmTrain, report), s(r)]);
        }
        a
    };
    if parts.len() < 2 || split == PartTasks::OnePerModel {
        return vec![Task::run(stage, model, inputs, with_outputs(model, report)).mkdir_target()];
    }
    let dir = pieces_dir(model);
    let mut tasks = Vec::new();
    let mut pieces = Vec::new();
    let mut piece_reports = Vec::new();
    for part in parts {
        let piece = format!("{dir}/{part}.piece");
        let piece_report = report.map(|_| format!("{dir}/{part}.json"));
        let mut a = with_outputs(&piece, piece_report.as_deref());
        a.extend([flag!(PcaFit | GprTrain | GpdmTrain, part), part.clone()]);
        tasks.push(Task::run(stage, piece.clone(), inputs.clone(), a).mkdir_target());
        pieces.push(piece);
        if let Some(r) = piece_report {
            piece_reports.extend([flag!(MergeParts, piece_report), r]);
        }
    }
    let mut a = vec![s("-q")];
    a.extend(pieces.iter().cloned());
    a.extend([flag!(MergeParts, out), s(model)]);
    if let Some(r) = report {
        a.extend(piece_reports);
        a.extend([flag!(MergeParts, report), s(r)]);
    }
    let mut merge = Task::run("merge-parts", model, pieces, a).mkdir_target();
    merge.kind = merge_kind(stage);
    tasks.push(merge);
    tasks
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::task::Step;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn one_part_is_one_task_of_the_stage() {
        let t = fit(PartTasks::OnePerPart, "pca-fit", "w/A/pca-whole.model", Some("w/A/pca-whole.json"), names(&["in"]), names(&["-q"]), &names(&["body"]));
        assert_eq!(t.len(), 1);
        assert_eq!(t[0].kind, "pca-fit");
        assert_eq!(t[0].target, "w/A/pca-whole.model");
        assert_eq!(t[0].dirs, names(&["w/A"]));
        assert_eq!(
            t[0].steps,
            vec![Step::Run { bin: s("pca-fit"), args: names(&["-q", "--out", "w/A/pca-whole.model", "--report", "w/A/pca-whole.json"]) }]
        );
    }

    #[test]
    fn parts_are_pieces_joined_by_a_merge_that_writes_the_model_and_report() {
        let t = fit(PartTasks::OnePerPart, "gpdm-train", "w/g.model", Some("w/g-train.json"), names(&["w/g.group"]), names(&["--group", "w/g.group"]), &names(&["torso", "arm_l"]));
        assert_eq!(t.len(), 3);
        for (task, part) in t.iter().zip(["torso", "arm_l"]) {
            assert_eq!(task.kind, "gpdm-train");
            assert_eq!(task.target, format!("w/g.parts/{part}.piece"));
            assert_eq!(task.inputs, names(&["w/g.group"]));
            assert_eq!(task.dirs, names(&["w/g.parts"]));
            let want = format!("--group w/g.group --out w/g.parts/{part}.piece --report w/g.parts/{part}.json --part {part}");
            assert_eq!(task.steps, vec![Step::Run { bin: s("gpdm-train"), args: want.split(' ').map(s).collect() }]);
        }
        let m = &t[2];
        assert_eq!(m.kind, "merge-gpdm-train");
        assert_eq!(m.target, "w/g.model");
        assert_eq!(m.inputs, names(&["w/g.parts/torso.piece", "w/g.parts/arm_l.piece"]));
        assert_eq!(m.dirs, names(&["w"]));
        let want = "-q w/g.parts/torso.piece w/g.parts/arm_l.piece --out w/g.model --piece-report w/g.parts/torso.json \
                    --piece-report w/g.parts/arm_l.json --report w/g-train.json";
        assert_eq!(m.steps, vec![Step::Run { bin: s("merge-parts"), args: want.split_whitespace().map(s).collect() }]);
        assert_eq!(m.bins(), vec!["merge-parts"]);
    }

    #[test]
    fn one_task_per_model_fits_every_part_in_one_run() {
        let t = fit(PartTasks::OnePerModel, "gpdm-train", "w/g.model", Some("w/g-train.json"), names(&["w/g.group"]), names(&["--group", "w/g.group"]), &names(&["torso", "arm_l"]));
        assert_eq!(t.len(), 1);
        assert_eq!((t[0].kind.as_str(), t[0].target.as_str(), &t[0].inputs), ("gpdm-train", "w/g.model", &names(&["w/g.group"])));
        let want = "--group w/g.group --out w/g.model --report w/g-train.json";
        assert_eq!(t[0].steps, vec![Step::Run { bin: s("gpdm-train"), args: want.split(' ').map(s).collect() }]);
    }

    #[test]
    fn without_a_report_the_merge_joins_the_pieces_alone() {
        let t = fit(PartTasks::OnePerPart, "gpr-train", "w/m/nn.model", None, Vec::new(), Vec::new(), &names(&["torso", "displacement"]));
        assert!(t.iter().all(|x| match &x.steps[..] {
            [Step::Run { args, .. }] => !args.iter().any(|a| a == "--report" || a == "--piece-report"),
            _ => false,
        }));
        assert_eq!(pieces_dir("w/m/nn.model"), "w/m/nn.parts");
        assert_eq!(t[2].inputs, names(&["w/m/nn.parts/torso.piece", "w/m/nn.parts/displacement.piece"]));
    }
}

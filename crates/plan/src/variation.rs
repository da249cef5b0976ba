//! The variation pipeline's tasks (3DV): per movement group `prealign` (the front end's aligned
//! motions time-aligned, and pre-blends; [`front_end`]'s tasks, shared with the transfer), `gpdm-train` (one GPDM per part, one task per part joined by `merge-parts`:
//! [`per_part`]), `hmc-sample` (variations, then their contact sheets), `variation-eval`; and
//! the merge of every group's records into `variation.json`. A group none of whose motions the
//! subject has is left out; when no group is left (a lab's own set, whose motions have other
//! names), each of the subject's training motions is a group of its own.

use anyhow::Result;
use capture::align::AlignFrame;
use mesh_core::capture_set::CaptureSet;

use crate::front_end;
use crate::options::{words, VariationOptions};
use crate::per_part;
use crate::flag::{flag, GpdmTrain, HmcSample, Prealign, Render, VariationEval};
use crate::task::{s, Graph, Step, Task};

/// Adds the variation pipeline's tasks and its variables (`VARIATION_RECORDS`,
/// `VARIATION_REPORT_VIEWS`) to `graph`.
pub fn plan(set: &CaptureSet, out: &str, opt: &VariationOptions, align_frame: AlignFrame, graph: &mut Graph) -> Result<()> {
    let front = format!("{out}/work");
    let work = format!("{out}/work/variation");
    let vout = format!("{out}/variation");
    let (groups, prealign_defaults) = if opt.groups.is_empty() {
        (VariationOptions::default_groups(), opt.prealign_flags.is_empty())
    } else {
        (opt.groups.clone(), false)
    };
    let subject = opt.variation_subject.clone().unwrap_or_else(|| set.spec.source.clone());
    let described = crate::subjects::subject(set, &front, &subject, graph)?;
    let groups = groups_present(set, &subject, groups)?;
    let set_root = set.root.to_string_lossy().into_owned();
    let mut records = Vec::new();
    let mut names = Vec::new();
    for (g, motions) in &groups {
        // prealign reads the set, the subject's description and template, and the front end's
        // segmentation and aligned motions (`front_end`: those of the transfer when it has the
        // subject) of the group's motions (those the subject has, `groups_present`). A group
        // modelled as one part reads motions aligned on the whole body and no segmentation, so
        // that a subject whose curves do not segment still runs (then one task fits it).
        let whole_body = opt.prealign_words(g).iter().any(|w| *w == flag!(Prealign, whole_body) || *w == flag!(Prealign, fallback_whole_body));
        let parts: Vec<String> = if whole_body { Vec::new() } else { described.parts.clone() };
        let mut inputs = vec![set.set_json().to_string_lossy().into_owned(), described.json.clone(), described.template.clone()];
        let segmentation = (!whole_body).then(|| front_end::segment(&front, &subject, &described, graph));
        inputs.extend(segmentation.clone());
        let mut aligned = Vec::new();
        for m in motions.split(',').filter(|m| !m.is_empty()) {
            aligned.push(match whole_body {
                true => front_end::align_whole_body(set, &front, &subject, m, &described, graph)?,
                false => front_end::align(set, &front, &subject, m, &described, align_frame, graph)?,
            });
        }
        inputs.extend(aligned.iter().cloned());
        let group = format!("{work}/{g}.group");
        let mut args = vec![s("-q"), flag!(Prealign, set), set_root.clone()];
        if let Some(sub) = &opt.variation_subject {
            args.extend([flag!(Prealign, subject_name), sub.clone()]);
        }
        if described.proposed() {
            args.extend([flag!(Prealign, subject), described.json.clone()]);
        }
        if let Some(seg) = segmentation {
            args.extend([flag!(Prealign, segmentation), seg]);
        }
        args.extend([flag!(Prealign, group_name), g.clone()]);
        if prealign_defaults && g == "locomotion" {
            args.push(flag!(Prealign, gait_cycles));
        }
        args.extend(opt.prealign_words(g));
        args.extend([flag!(Prealign, blend_weights), opt.variation_w.clone()]);
        args.extend(aligned);
        args.extend([flag!(Prealign, out), group.clone()]);
        graph.push(Task::run("prealign", group.clone(), inputs, args).mkdir_target());

        let model = format!("{work}/{g}.model");
        let mut args = vec![s("-q")];
        args.extend(words(&opt.variation_train_flags));
        args.extend([flag!(GpdmTrain, group), group.clone()]);
        let report = format!("{work}/{g}-train.json");
        for t in per_part::fit(graph.part_tasks, "gpdm-train", &model, Some(&report), vec![group.clone()], args, &parts) {
            graph.push(t);
        }

        // hmc-sample writes its report under a temporary name, the sheets follow, and the
        // report's rename marks the whole task complete. A group of one motion has nothing to
        // blend, so it is sampled without the blend weights.
        let samples = format!("{work}/{g}-samples.json");
        let blends = match motions.split(',').filter(|m| !m.is_empty()).count() {
            0 | 1 => String::new(),
            _ => opt.variation_blends.clone(),
        };
        let tmp = format!("{samples}.tmp");
        let mut args = vec![s("-q"), flag!(HmcSample, common.seed), opt.variation_seed.to_string(), s("-n"), opt.variation_n.to_string()];
        if let Some(kappa) = &opt.variation_variance_scale {
            args.extend([flag!(HmcSample, variance_scale), kappa.clone()]);
        }
        args.extend([flag!(HmcSample, blends), blends]);
        args.extend(words(&opt.variation_sample_flags));
        args.extend([flag!(HmcSample, group), group.clone(), flag!(HmcSample, model), model.clone(), flag!(HmcSample, out), format!("{vout}/{g}"), flag!(HmcSample, report), tmp.clone()]);
        graph.push(Task {
            kind: "hmc-sample".into(),
            target: samples.clone(),
            inputs: vec![model.clone()],
            dirs: Vec::new(),
            steps: vec![
                Step::Remove { paths: vec![format!("{vout}/{g}"), format!("{vout}/render/{g}")] },
                Step::Run { bin: "hmc-sample".into(), args },
                Step::RenderVariations {
                    dir: format!("{vout}/{g}"),
                    out_dir: format!("{vout}/render/{g}"),
                    flags: vec![s("-q"), flag!(Render, no_frames), flag!(Render, stride), s("2"), flag!(Render, separate_rows), flag!(Render, follow)],
                },
                Step::Rename { from: tmp, to: samples.clone() },
            ],
        });

        let eval = format!("{work}/{g}-eval.json");
        let args = vec![
            s("-q"), flag!(VariationEval, common.seed), opt.variation_seed.to_string(), flag!(VariationEval, group), group.clone(), flag!(VariationEval, model), model.clone(),
            flag!(VariationEval, plots), format!("{vout}/plots/{g}"), flag!(VariationEval, out), eval.clone(),
        ];
        graph.push(Task::run("variation-eval", eval.clone(), vec![model.clone()], args));
        records.extend([samples, eval]);
        names.push(g.clone());
    }
    graph.variable("VARIATION_RECORDS", records.clone());
    // The report's 3D view: the first three variations of the first group's first motion.
    let first = groups.first().and_then(|(g, motions)| motions.split(',').find(|m| !m.is_empty()).map(|m| (g, m)));
    let views = first.map_or_else(Vec::new, |(g, m)| (0..opt.variation_n.min(3)).map(|k| format!("var{k}={vout}/{g}/{m}/var{k}")).collect());
    graph.variable("VARIATION_REPORT_VIEWS", views);
    let table = format!("{out}/variation.json");
    let mut args = vec![s("collect"), s("variation"), s("--work"), work.clone(), s("--out"), table.clone()];
    args.extend(names);
    graph.push(Task {
        kind: "collect-variation".into(),
        target: table,
        inputs: records,
        dirs: Vec::new(),
        steps: vec![Step::Run { bin: "plan".into(), args }],
    });
    Ok(())
}

/// The groups of which the subject has at least one motion; when there is none, one group per
/// training motion of the subject, named after it.
fn groups_present(set: &CaptureSet, subject: &str, groups: Vec<(String, String)>) -> Result<Vec<(String, String)>> {
    let have = set.motions(subject)?;
    // Each group keeps the motions the subject has (a group of one motion is sampled without
    // blends); a group with none is dropped.
    let kept: Vec<(String, String)> = groups
        .into_iter()
        .map(|(g, motions)| {
            let present: Vec<&str> = motions.split(',').filter(|m| have.iter().any(|h| h == m)).collect();
            (g, present.join(","))
        })
        .filter(|(_, motions)| !motions.is_empty())
        .collect();
    if !kept.is_empty() {
        return Ok(kept);
    }
    let mut own: Vec<String> = set
        .spec
        .train
        .iter()
        .map(|p| if subject == set.spec.target { p.target.clone() } else { p.source.clone() })
        .collect();
    own.dedup();
    Ok(own.into_iter().map(|m| (m.clone(), m)).collect())
}

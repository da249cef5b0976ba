//! The transfer pipeline's tasks (CVPR sections 4 to 7), from a capture set:
//! per subject `segment`, `align` of every motion, `pca-fit` (per part and whole body); per
//! training pair `dtw-densify`; per direction and method `gpr-train` (the part models and the
//! regressors part by part, joined by `merge-parts`: [`per_part`]); per test motion
//! `gpr-predict` (every placement for gpr-nn, plus correction and stitching, CVPR §6),
//! `transfer-eval` where truth exists, contact sheets; the learning curves (CVPR figs. 7-9) and the
//! paper figures 3, 5 and 10; and the merge of every evaluation record into `results.json`.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result};
use mesh_core::capture_set::{CaptureSet, SubjectSpec};

use crate::options::{value_name, Method, Placement, TransferOptions};
use crate::per_part;
use crate::task::{s, Graph, Step, Task};

/// Path strings joined as the command line shows them.
pub(crate) fn join(base: &Path, parts: &[&str]) -> String {
    let mut p = base.to_path_buf();
    for s in parts {
        p.push(s);
    }
    p.to_string_lossy().into_owned()
}

/// A frame rate as printf's `%g` writes it (6 significant digits, no trailing zeros).
pub fn fmt_g(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    // The exponent after rounding to 6 significant digits decides the notation.
    let sci = format!("{x:.5e}");
    let (mant, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let trim = |t: &str| {
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t.to_string()
        }
    };
    if !(-4..6).contains(&exp) {
        return format!("{}e{}{:02}", trim(mant), if exp < 0 { '-' } else { '+' }, exp.abs());
    }
    trim(&format!("{:.*}", (5 - exp) as usize, x))
}

/// Adds the transfer pipeline's tasks and its variables (`TRANSFER_RECORDS`, `TRANSFER_STAMPS`,
/// `TRANSFER_REPORT_VIEWS`) to `graph`. `out` is the pipeline's output folder.
pub fn plan(set: &CaptureSet, out: &str, opt: &TransferOptions, graph: &mut Graph) -> Result<()> {
    let root = &set.root;
    let w = format!("{out}/work");
    let (src_subj, tgt_subj) = (set.spec.source.clone(), set.spec.target.clone());
    let subjects = [src_subj.clone(), tgt_subj.clone()];
    let mut spec: BTreeMap<String, SubjectSpec> = BTreeMap::new();
    let mut tpl: BTreeMap<String, String> = BTreeMap::new();
    for x in &subjects {
        let sp = SubjectSpec::load(set.subject_json(x))?;
        tpl.insert(x.clone(), set.template_path(x, &sp)?.to_string_lossy().into_owned());
        spec.insert(x.clone(), sp);
    }
    let train: BTreeMap<&str, Vec<String>> = BTreeMap::from([
        (src_subj.as_str(), set.spec.train.iter().map(|p| p.source.clone()).collect()),
        (tgt_subj.as_str(), set.spec.train.iter().map(|p| p.target.clone()).collect()),
    ]);
    let seg = |x: &str| format!("{w}/{x}/parts.seg");
    let aligned = |x: &str, m: &str| format!("{w}/{x}/{m}.aligned");
    let pca = |x: &str, kind: &str| format!("{w}/{x}/{kind}.model");
    // transfer-eval's foot-sliding inputs: the subject's truth contacts, its parts and its template.
    let feet = |x: &str| {
        vec![
            s("--contacts"),
            set.subject_json(x).to_string_lossy().into_owned(),
            s("--segmentation"),
            seg(x),
            s("--template"),
            tpl[x].clone(),
        ]
    };
    let mut records: Vec<String> = Vec::new();
    let mut stamps: Vec<String> = Vec::new();

    for x in &subjects {
        for m in set.motions(x)? {
            let frames = set.frames(x, &m).with_context(|| format!("subject {x}, motion {m}"))?;
            let subject = set.subject_json(x).to_string_lossy().into_owned();
            let mut inputs = vec![subject.clone(), tpl[x].clone(), seg(x)];
            inputs.extend(frames.iter().map(|f| f.to_string_lossy().into_owned()));
            let args = vec![
                s("-q"), s("--frame"), value_name(opt.align_frame), s("--segmentation"), seg(x),
                s("--subject"), subject, s("--template"), tpl[x].clone(), join(root, &[x, &m]),
                s("--out"), aligned(x, &m),
            ];
            graph.push(Task::run("align", aligned(x, &m), inputs, args).mkdir_target());
        }
        let subject_json = set.subject_json(x).to_string_lossy().into_owned();
        graph.push(
            Task::run(
                "segment",
                seg(x),
                vec![subject_json.clone(), tpl[x].clone()],
                vec![s("-q"), subject_json, s("--template"), tpl[x].clone(), s("--out"), seg(x)],
            )
            .mkdir_target(),
        );
        let training: Vec<String> = train[x.as_str()].iter().map(|m| aligned(x, m)).collect();
        let mut inputs = vec![seg(x)];
        inputs.extend(training.iter().cloned());
        let mut args = vec![
            s("-q"), s("--components"), opt.pca_components.to_string(), s("--part-alignment"),
            value_name(opt.part_alignment), s("--template"), tpl[x].clone(), s("--segmentation"), seg(x),
        ];
        args.extend(training.iter().cloned());
        let parts: Vec<String> = spec[x].parts.keys().cloned().collect();
        let report = format!("{w}/{x}/pca.json");
        for t in per_part::fit(graph.part_tasks, "pca-fit", &pca(x, "pca"), Some(&report), inputs, args, &parts) {
            graph.push(t);
        }
        // The whole-body comparison at the parts' total dimension (CVPR fig. 9: "equivalent
        // total number of input and output dimensions").
        let whole = opt.pca_components as usize * spec[x].parts.len();
        let mut args = vec![
            s("-q"), s("--whole-body"), s("--components"), whole.to_string(), s("--template"),
            tpl[x].clone(),
        ];
        args.extend(training.iter().cloned());
        args.extend([s("--out"), pca(x, "pca-whole"), s("--report"), format!("{w}/{x}/pca-whole.json")]);
        graph.push(Task::run("pca-fit", pca(x, "pca-whole"), training.clone(), args));
    }

    let set_json = set.set_json().to_string_lossy().into_owned();
    let (sn, tn) = (src_subj.as_str(), tgt_subj.as_str());
    let mut pair_args: Vec<String> = Vec::new();
    let mut corrs: Vec<String> = Vec::new();
    for p in &set.spec.train {
        let c = format!("{w}/pairs/{}.corr", p.source);
        let (sa, ta) = (aligned(sn, &p.source), aligned(tn, &p.target));
        let args = vec![
            s("-q"), s("--set"), join(root, &[]), s("--motion"), p.source.clone(), s("--source-pca"),
            pca(sn, "pca"), s("--target-pca"), pca(tn, "pca"), sa.clone(),
            ta.clone(), s("--out"), c.clone(), s("--report"), format!("{w}/pairs/{}.json", p.source),
        ];
        let inputs = vec![set_json.clone(), sa.clone(), ta.clone(), pca(sn, "pca"), pca(tn, "pca")];
        graph.push(Task::run("dtw-densify", c.clone(), inputs, args).mkdir_target());
        pair_args.extend([s("--pair"), sa.clone(), ta.clone(), c.clone()]);
        corrs.extend([sa, ta, c]);
    }

    // Directions: forward tests the set's test motions; reverse tests the target's motions that
    // have truth for the source subject (plus an optional "target_test" list in set.json).
    let mut rev_tests: Vec<String> = set
        .motions(tn)?
        .into_iter()
        .filter(|m| set.has_truth(sn, m))
        .collect();
    if let Some(extra) = set.spec.extra.get("target_test").and_then(|v| v.as_array()) {
        for m in extra.iter().filter_map(|v| v.as_str()) {
            if !rev_tests.iter().any(|r| r == m) {
                rev_tests.push(m.to_string());
            }
        }
    }
    rev_tests.sort();
    let directions = [
        (sn, tn, false, set.spec.test.clone()),
        (tn, sn, true, rev_tests),
    ];
    let mut variants: Vec<(String, Method, bool)> =
        opt.methods.iter().map(|m| (m.name().to_string(), *m, false)).collect();
    variants.push(("gpr-nn-keyposes".into(), Method::GprNn, true));
    let default_pl = opt.placement;
    for (src, tgt, rev, tests) in &directions {
        let (src, tgt) = (*src, *tgt);
        let dn = format!("{src}-to-{tgt}");
        let label = format!("{src}->{tgt}");
        for (name, method, keys) in &variants {
            let kind = if *method == Method::WholeBody { "pca-whole" } else { "pca" };
            let model = format!("{w}/models/{dn}/{name}.model");
            let mut inputs = vec![pca(src, kind), pca(tgt, kind)];
            inputs.extend(corrs.iter().cloned());
            let mut args = vec![s("-q"), s("--mean"), value_name(opt.gpr_mean)];
            args.extend(crate::options::words(&opt.gpr_train_flags));
            args.extend([s("--method"), method.name().to_string()]);
            if *keys {
                args.push(s("--keyposes-only"));
            }
            if *rev {
                args.push(s("--reverse"));
            }
            args.extend([
                s("--source-pca"), pca(src, kind), s("--target-pca"), pca(tgt, kind),
            ]);
            args.extend(pair_args.iter().cloned());
            // One regressor per part of the PCA models, and the displacement's.
            let mut units: Vec<String> = match method {
                Method::WholeBody => vec![s("body")],
                _ => spec[src].parts.keys().cloned().collect(),
            };
            units.push(s("displacement"));
            for t in per_part::fit(graph.part_tasks, "gpr-train", &model, None, inputs, args, &units) {
                graph.push(t);
            }
            stamps.push(model.clone());
            for m in tests {
                if !set.motion_dir(src, m).is_dir() {
                    continue;
                }
                let truth = set.truth_dir(tgt, m).to_string_lossy().into_owned();
                let has_truth = set.has_truth(tgt, m);
                let mut places = vec![default_pl];
                if name == "gpr-nn" {
                    let all = [Placement::ScaledSource, Placement::Regressed, Placement::Blended];
                    places.extend(all.into_iter().filter(|&p| p != default_pl));
                }
                for pl in places {
                    let seq = if pl == default_pl {
                        format!("{out}/transfer/{dn}/{m}/{name}")
                    } else {
                        format!("{w}/placement/{dn}/{m}/{}", pl.name())
                    };
                    let timing = format!("{w}/predict/{dn}/{m}/{name}-{}.json", pl.name());
                    let args = vec![
                        s("-q"), s("--model"), model.clone(), s("--source-pca"), pca(src, kind),
                        s("--target-pca"), pca(tgt, kind), s("--target-template"), tpl[tgt].clone(),
                        s("--placement"), pl.name().into(), aligned(src, m), s("--out"), seq.clone(),
                        s("--timing"), timing.clone(),
                    ];
                    let inputs = vec![model.clone(), aligned(src, m)];
                    stamps.push(graph.push(Task::run("gpr-predict", timing.clone(), inputs, args).mkdir_target()));
                    if has_truth {
                        let rec = format!("{w}/eval/{dn}/{m}/{name}-{}.json", pl.name());
                        let mut args = vec![s("-q"), seq.clone(), truth.clone()];
                        args.extend(feet(tgt));
                        args.extend([
                            s("--direction"), label.clone(), s("--motion"), m.clone(), s("--method"),
                            method.name().into(), s("--placement"), pl.name().into(), s("--correspondences"),
                            s(if *keys { "keyposes" } else { "dense" }), s("--out"), rec.clone(),
                        ]);
                        records.push(graph.push(Task::run("transfer-eval", rec, vec![timing.clone()], args).mkdir_target()));
                    }
                }
                if name != "gpr-nn" {
                    continue;
                }
                // CVPR §6 after the regression: correction (M = 3), then stitching.
                let training: Vec<String> = train[tgt].iter().map(|t| aligned(tgt, t)).collect();
                for (surf, meth) in [("correct", "gpr-nn+correct"), ("correct-stitch", "gpr-nn+correct+stitch")] {
                    let seq = format!("{out}/transfer/{dn}/{m}/{meth}");
                    let timing = format!("{w}/predict/{dn}/{m}/{meth}-{}.json", default_pl.name());
                    // Per-frame confidence (docs/FORMATS.md) beside the full pipeline's output.
                    let conf_dir = format!("{w}/confidence/{dn}");
                    let conf = format!("{conf_dir}/{m}.json");
                    let mut inputs = vec![model.clone(), aligned(src, m), seg(tgt)];
                    inputs.extend(training.iter().cloned());
                    let mut args = vec![
                        s("-q"), s("--model"), model.clone(), s("--source-pca"), pca(src, "pca"),
                        s("--target-pca"), pca(tgt, "pca"), s("--target-template"), tpl[tgt].clone(),
                        s("--placement"), default_pl.name().into(), s("--surface"), s(surf),
                        s("--segmentation"), seg(tgt),
                    ];
                    for t in &training {
                        args.extend([s("--target-training"), t.clone()]);
                    }
                    args.extend([s("-m"), s("3"), aligned(src, m), s("--out"), seq.clone(), s("--timing"), timing.clone()]);
                    if surf == "correct-stitch" {
                        args.extend([s("--confidence"), conf.clone()]);
                    }
                    stamps.push(graph.push(
                        Task::run("gpr-predict", timing.clone(), inputs, args).mkdir_target().mkdir(conf_dir),
                    ));
                    let rec = format!("{w}/eval/{dn}/{m}/{meth}-{}.json", default_pl.name());
                    if has_truth {
                        let mut args = vec![s("-q"), seq.clone(), truth.clone()];
                        args.extend(feet(tgt));
                        args.extend([
                            s("--direction"), label.clone(), s("--motion"), m.clone(), s("--method"),
                            s(meth), s("--placement"), default_pl.name().into(), s("--correspondences"),
                            s("dense"), s("--out"), rec.clone(),
                        ]);
                        records.push(graph.push(Task::run("transfer-eval", rec.clone(), vec![timing.clone()], args).mkdir_target()));
                    }
                    if surf == "correct-stitch" {
                        // Per-frame confidence beside the error (where truth exists), for the report.
                        let plot = format!("{out}/figures/confidence-{dn}-{m}.png");
                        let mut inputs = vec![timing.clone()];
                        let mut args = vec![s("confidence"), s("-q"), s("--confidence"), conf.clone()];
                        if has_truth {
                            inputs.push(rec.clone());
                            args.extend([s("--eval"), rec.clone()]);
                        }
                        args.extend([
                            s("--title"), format!("{label} {m}: confidence and error per frame"), s("--out"),
                            plot.clone(),
                        ]);
                        stamps.push(graph.push(Task::run("paper-figure", plot, inputs, args).mkdir_target()));
                    }
                    let sheet = format!("{out}/render/{dn}/{m}/{meth}/contact.png");
                    let mut seqs = vec![join(root, &[src, m]), seq.clone()];
                    if has_truth {
                        seqs.push(truth.clone());
                    }
                    let labels = format!("source,{meth}{}", if has_truth { ",truth" } else { "" });
                    stamps.push(graph.push(render_sheet(&sheet, vec![timing.clone()], &labels, false, seqs)));
                }
                let sheet = format!("{out}/render/{dn}/{m}/contact.png");
                let mut seqs = vec![join(root, &[src, m]), format!("{out}/transfer/{dn}/{m}/gpr-nn")];
                let mut labels = s("source,transfer");
                if has_truth {
                    seqs.push(truth.clone());
                    labels.push_str(",truth");
                }
                let timing = format!("{w}/predict/{dn}/{m}/gpr-nn-{}.json", default_pl.name());
                stamps.push(graph.push(render_sheet(&sheet, vec![timing], &labels, false, seqs)));
            }
        }
    }

    // Learning curves (CVPR figs. 7-9) on the set's true correspondences, errors against the true
    // parts (PCA truncation included), the paper's zero-mean GPs; the whole body at the parts'
    // total dimensions (fitted by learning-curves itself).
    let lc = format!("{out}/learning-curves/learning_curves.csv");
    let mut inputs = vec![set_json.clone(), pca(sn, "pca"), pca(tn, "pca")];
    let mut args = vec![
        s("-q"), s("--seed"), s("0"), s("--mean"), s("zero"), s("--set"), join(root, &[]),
        s("--source-pca"), pca(sn, "pca"), s("--target-pca"), pca(tn, "pca"),
        s("--source-name"), s(sn), s("--target-name"), s(tn),
    ];
    for p in &set.spec.train {
        args.extend([s("--true-pair"), p.source.clone(), aligned(sn, &p.source), aligned(tn, &p.target)]);
    }
    for p in &set.spec.train {
        inputs.extend([aligned(sn, &p.source), aligned(tn, &p.target)]);
    }
    args.extend([s("--out"), crate::task::parent(&lc)]);
    stamps.push(graph.push(Task::run("learning-curves", lc, inputs, args).mkdir_target()));

    // CVPR fig. 3: the association cost of the first training pair, its DTW path, key-poses and truth.
    let p0 = &set.spec.train[0];
    let fig3 = format!("{out}/figures/fig3-{}.png", p0.source);
    let inputs = vec![pca(sn, "pca"), pca(tn, "pca"), aligned(sn, &p0.source), aligned(tn, &p0.target)];
    let args = vec![
        s("cost-matrix"), s("-q"), s("--set"), join(root, &[]), s("--motion"), p0.source.clone(),
        s("--source-pca"), pca(sn, "pca"), s("--target-pca"), pca(tn, "pca"), aligned(sn, &p0.source),
        aligned(tn, &p0.target), s("--out"), fig3.clone(),
    ];
    stamps.push(graph.push(Task::run("paper-figure", fig3, inputs, args).mkdir_target()));

    // CVPR fig. 5 (a correction example) and fig. 10 (every method's raw output on one motion):
    // the first forward test motion.
    let mut views = Vec::new();
    if let Some(m0) = directions[0].3.first() {
        let dn0 = format!("{sn}-to-{tn}");
        let model0 = format!("{w}/models/{dn0}/gpr-nn.model");
        let training: Vec<String> = train[tn].iter().map(|t| aligned(tn, t)).collect();
        let truth0 = set.truth_dir(tn, m0).to_string_lossy().into_owned();
        let has_truth0 = set.has_truth(tn, m0);
        let fig5 = format!("{out}/figures/fig5-{m0}.png");
        let mut inputs = vec![model0.clone(), seg(tn), aligned(sn, m0)];
        inputs.extend(training.iter().cloned());
        let mut args = vec![
            s("correction"), s("-q"), s("--model"), model0, s("--source-pca"), pca(sn, "pca"),
            s("--target-pca"), pca(tn, "pca"), s("--segmentation"), seg(tn),
        ];
        for t in &training {
            args.extend([s("--target-training"), t.clone()]);
        }
        if has_truth0 {
            args.extend([s("--truth"), truth0.clone()]);
        }
        args.extend([
            s("--size"), s("300"), aligned(sn, m0), s("--out"), fig5.clone(), s("--report"),
            format!("{out}/figures/fig5-{m0}.json"),
        ]);
        stamps.push(graph.push(Task::run("paper-figure", fig5, inputs, args).mkdir_target()));
        let names: Vec<String> = Method::ALL
            .into_iter()
        .filter(|m| opt.methods.contains(m))
        .map(|m| m.name().to_string())
        .chain(std::iter::once(s("gpr-nn-keyposes")))
        .collect();
        let fig10 = format!("{out}/figures/fig10-{dn0}-{m0}/contact.png");
        let mut seqs = vec![join(root, &[sn, m0])];
        seqs.extend(names.iter().map(|n| format!("{out}/transfer/{dn0}/{m0}/{n}")));
        if has_truth0 {
            seqs.push(truth0.clone());
        }
        let inputs = names
            .iter()
            .map(|n| format!("{w}/predict/{dn0}/{m0}/{n}-{}.json", default_pl.name()))
            .collect();
        let labels = format!("source,{}{}", names.join(","), if has_truth0 { ",truth" } else { "" });
        stamps.push(graph.push(render_sheet(&fig10, inputs, &labels, true, seqs)));
        // The report's 3D view: the first forward test motion, after correction and stitching.
        views = vec![
            format!("source={}", join(root, &[sn, m0])),
            format!("transfer={out}/transfer/{dn0}/{m0}/gpr-nn+correct+stitch"),
            format!("truth={truth0}"),
        ];
    }
    graph.variable("TRANSFER_REPORT_VIEWS", views);
    graph.variable("TRANSFER_RECORDS", records.clone());
    graph.variable("TRANSFER_STAMPS", stamps.clone());

    // Every evaluation record merged into one list; the other products are prerequisites so
    // that `results.json` stands for the whole run.
    let results = format!("{out}/results.json");
    let mut inputs = records.clone();
    inputs.extend(stamps);
    let mut args = vec![s("collect"), s("transfer"), s("--out"), results.clone()];
    args.extend(records);
    graph.push(Task {
        kind: "collect-results".into(),
        target: results,
        inputs,
        dirs: Vec::new(),
        steps: vec![Step::Run { bin: "plan".into(), args }],
    });
    Ok(())
}

/// A contact sheet of overlaid sequences, rows apart (`render --separate-rows`); its target is
/// `<dir>/contact.png` and render writes into `<dir>`.
fn render_sheet(sheet: &str, inputs: Vec<String>, labels: &str, follow: bool, seqs: Vec<String>) -> Task {
    let mut args = vec![s("-q"), s("--separate-rows"), s("--no-frames"), s("--no-gif")];
    if follow {
        args.push(s("--follow"));
    }
    args.extend([s("--labels"), s(labels), s("--out"), crate::task::parent(sheet)]);
    args.extend(seqs);
    Task::run("render", sheet, inputs, args)
}

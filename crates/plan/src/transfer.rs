//! The transfer pipeline's tasks (CVPR sections 4 to 7), from a capture set:
//! per subject `propose-curves` when its description has no curves ([`crate::subjects`]),
//! `segment`, `align` of every motion ([`crate::front_end`]), `pca-fit` (per part and whole body); per training pair
//! `dtw-densify`; per direction and method `gpr-train` (the part models and the regressors part
//! by part, joined by `merge-parts`: [`per_part`]); per test motion `gpr-predict` (every
//! placement for gpr-nn, plus correction and stitching, CVPR §6), `transfer-eval` (against the
//! truth where it exists, always on the source's contacts), contact sheets; the learning curves
//! (CVPR figs. 7-9, on the set's true correspondences or else the DTW pairs) and the paper
//! figures 3, 5 and 10; and the merge of every evaluation record into `results.json`.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;
use mesh_core::capture_set::CaptureSet;

use crate::front_end;
use crate::options::{value_name, ConfigName, Method, Placement, TransferOptions};
use crate::per_part;
use crate::subjects::{subject, Subject};
use crate::flag::{
    flag, ConfidenceFigure, CorrectionFigure, CostMatrixFigure, DtwDensify, GprPredict, GprTrain, LearningCurves, PcaFit,
    Render, TransferEval,
};
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

/// What every part of the transfer plan shares: the set, the output folders, the options, the
/// two subjects as the stages see them, and each subject's training motions.
struct Plan<'a> {
    set: &'a CaptureSet,
    out: &'a str,
    work: String,
    opt: &'a TransferOptions,
    subjects: BTreeMap<String, Subject>,
    train: BTreeMap<String, Vec<String>>,
    /// Every evaluation record (results.json's rows) and every other product of the run.
    records: Vec<String>,
    stamps: Vec<String>,
    /// Per direction label, its cross-validation report (`gpr-train --cross-validate`).
    cross_validations: Vec<(String, String)>,
}

/// One direction of the transfer: from `src` onto `tgt`, its test motions, and whether it is the
/// set's reverse direction (`gpr-train --reverse`).
struct Direction<'a> {
    src: &'a str,
    tgt: &'a str,
    reverse: bool,
    tests: Vec<String>,
}

impl Direction<'_> {
    fn name(&self) -> String {
        format!("{}-to-{}", self.src, self.tgt)
    }
    fn label(&self) -> String {
        format!("{}->{}", self.src, self.tgt)
    }
}

impl<'a> Plan<'a> {
    fn seg(&self, x: &str) -> String {
        front_end::seg(&self.work, x)
    }
    fn aligned(&self, x: &str, m: &str) -> String {
        front_end::aligned(&self.work, x, m)
    }
    fn pca(&self, x: &str, kind: &str) -> String {
        format!("{}/{x}/{kind}.model", self.work)
    }
    fn template(&self, x: &str) -> String {
        self.subjects[x].template.clone()
    }
    fn truth(&self, x: &str, m: &str) -> Option<String> {
        self.set.has_truth(x, m).then(|| self.set.truth_dir(x, m).to_string_lossy().into_owned())
    }
    /// transfer-eval's foot-sliding inputs against the truth: the target's truth contacts, its
    /// parts and its template.
    fn truth_feet(&self, x: &str) -> Vec<String> {
        vec![
            flag!(TransferEval, contacts), self.subjects[x].json.clone(), flag!(TransferEval, segmentation), self.seg(x), flag!(TransferEval, template),
            self.template(x),
        ]
    }

    /// `align` of every motion, `segment`, and the per-part and whole-body `pca-fit` of subject `x`.
    fn front_end(&mut self, x: &str, graph: &mut Graph) -> Result<()> {
        for m in self.set.motions(x)? {
            front_end::align(self.set, &self.work, x, &m, &self.subjects[x], self.opt.align_frame(), graph)?;
        }
        front_end::segment(&self.work, x, &self.subjects[x], graph);
        let training: Vec<String> = self.train[x].iter().map(|m| self.aligned(x, m)).collect();
        let mut inputs = vec![self.seg(x)];
        inputs.extend(training.iter().cloned());
        let mut args = vec![
            s("-q"), flag!(PcaFit, components), self.opt.pca_components().to_string(), flag!(PcaFit, part_alignment),
            value_name(self.opt.part_alignment), flag!(PcaFit, template), self.template(x), flag!(PcaFit, segmentation),
            self.seg(x),
        ];
        args.extend(training.iter().cloned());
        let parts = self.subjects[x].parts.clone();
        let report = format!("{}/{x}/pca.json", self.work);
        for t in per_part::fit(graph.part_tasks, "pca-fit", &self.pca(x, "pca"), Some(&report), inputs, args, &parts) {
            graph.push(t);
        }
        // The whole-body comparison at the parts' total dimension (CVPR fig. 9: "equivalent
        // total number of input and output dimensions").
        let whole = self.opt.pca_components() * parts.len();
        let mut args = vec![
            s("-q"), flag!(PcaFit, whole_body), flag!(PcaFit, components), whole.to_string(), flag!(PcaFit, template), self.template(x),
        ];
        args.extend(training.iter().cloned());
        args.extend([
            flag!(PcaFit, out), self.pca(x, "pca-whole"), flag!(PcaFit, report), format!("{}/{x}/pca-whole.json", self.work),
        ]);
        graph.push(Task::run("pca-fit", self.pca(x, "pca-whole"), training, args));
        Ok(())
    }

    /// `dtw-densify` of every training pair; returns `gpr-train`'s `--pair` arguments and the
    /// files they name.
    fn pairs(&self, graph: &mut Graph) -> (Vec<String>, Vec<String>) {
        let (sn, tn) = (self.set.spec.source.as_str(), self.set.spec.target.as_str());
        let set_json = self.set.set_json().to_string_lossy().into_owned();
        let (mut pair_args, mut files) = (Vec::new(), Vec::new());
        for p in &self.set.spec.train {
            let c = format!("{}/pairs/{}.corr", self.work, p.source);
            let (sa, ta) = (self.aligned(sn, &p.source), self.aligned(tn, &p.target));
            let args = vec![
                s("-q"), flag!(DtwDensify, set), join(&self.set.root, &[]), flag!(DtwDensify, motion), p.source.clone(), flag!(DtwDensify, source_pca),
                self.pca(sn, "pca"), flag!(DtwDensify, target_pca), self.pca(tn, "pca"), sa.clone(), ta.clone(), flag!(DtwDensify, out),
                c.clone(), flag!(DtwDensify, report), format!("{}/pairs/{}.json", self.work, p.source),
            ];
            let inputs = vec![set_json.clone(), sa.clone(), ta.clone(), self.pca(sn, "pca"), self.pca(tn, "pca")];
            graph.push(Task::run("dtw-densify", c.clone(), inputs, args).mkdir_target());
            pair_args.extend([flag!(GprTrain, pair), sa.clone(), ta.clone(), c.clone()]);
            files.extend([sa, ta, c]);
        }
        (pair_args, files)
    }

    /// The two directions: forward tests the set's test motions; reverse tests the target's
    /// motions that have truth for the source subject (plus `target_test` of set.json).
    fn directions(&self) -> Result<[Direction<'a>; 2]> {
        let set: &'a CaptureSet = self.set;
        let (sn, tn) = (set.spec.source.as_str(), set.spec.target.as_str());
        let mut rev_tests: Vec<String> =
            self.set.motions(tn)?.into_iter().filter(|m| self.set.has_truth(sn, m)).collect();
        if let Some(extra) = self.set.spec.extra.get("target_test").and_then(|v| v.as_array()) {
            for m in extra.iter().filter_map(|v| v.as_str()) {
                if !rev_tests.iter().any(|r| r == m) {
                    rev_tests.push(m.to_string());
                }
            }
        }
        rev_tests.sort();
        Ok([
            Direction { src: sn, tgt: tn, reverse: false, tests: self.set.spec.test.clone() },
            Direction { src: tn, tgt: sn, reverse: true, tests: rev_tests },
        ])
    }

    /// A `transfer-eval` task of the sequence `seq` of test motion `m` made by the model `name`
    /// (its record's `method`, `placement` and `training` in `label`): against the truth where
    /// it exists, and always on the source's contacts (sliding, floor offset).
    fn eval(&mut self, d: &Direction, m: &str, seq: &str, name: &str, label: (&str, Placement, &str), after: String, graph: &mut Graph) -> String {
        let (method, placement, training) = label;
        let rec = format!("{}/eval/{}/{m}/{name}-{}.json", self.work, d.name(), placement.name());
        let mut args = vec![s("-q"), s(seq)];
        let mut inputs = vec![after, self.aligned(d.src, m), self.pca(d.src, "pca"), self.pca(d.tgt, "pca")];
        if let Some(truth) = self.truth(d.tgt, m) {
            args.push(truth);
            args.extend(self.truth_feet(d.tgt));
            inputs.push(self.subjects[d.tgt].json.clone());
        }
        args.extend([
            flag!(TransferEval, source_motion), self.aligned(d.src, m), flag!(TransferEval, source_pca), self.pca(d.src, "pca"), flag!(TransferEval, target_pca),
            self.pca(d.tgt, "pca"), flag!(TransferEval, direction), d.label(), flag!(TransferEval, motion), s(m), flag!(TransferEval, method), s(method),
            flag!(TransferEval, placement), placement.name().into(), flag!(TransferEval, correspondences), s(training), flag!(TransferEval, out), rec.clone(),
        ]);
        let rec = graph.push(Task::run("transfer-eval", rec, inputs, args).mkdir_target());
        self.records.push(rec.clone());
        rec
    }

    /// The models of direction `d` (every method, and gpr-nn on key-poses only), the transfer of
    /// each test motion with each, and their evaluations and contact sheets.
    fn direction(&mut self, d: &Direction, pairs: &(Vec<String>, Vec<String>), graph: &mut Graph) {
        let mut variants: Vec<(String, Method, bool)> =
            self.opt.methods().into_iter().map(|m| (m.name().to_string(), m, false)).collect();
        variants.push(("gpr-nn-keyposes".into(), Method::GprNn, true));
        for (name, method, keys) in &variants {
            let kind = if *method == Method::WholeBody { "pca-whole" } else { "pca" };
            let model = format!("{}/models/{}/{name}.model", self.work, d.name());
            let mut inputs = vec![self.pca(d.src, kind), self.pca(d.tgt, kind)];
            inputs.extend(pairs.1.iter().cloned());
            let mut args = vec![s("-q")];
            if let Some(config) = self.opt.config {
                args.extend([flag!(GprTrain, config), value_name(config)]);
            }
            if let Some(mean) = self.opt.gpr_mean {
                args.extend([flag!(GprTrain, mean), value_name(mean)]);
            }
            args.extend(crate::options::words(&self.opt.gpr_train_flags));
            args.extend([flag!(GprTrain, method), method.name().to_string()]);
            if *keys {
                args.push(flag!(GprTrain, keyposes_only));
            }
            if d.reverse {
                args.push(flag!(GprTrain, reverse));
            }
            args.extend([flag!(GprTrain, source_pca), self.pca(d.src, kind), flag!(GprTrain, target_pca), self.pca(d.tgt, kind)]);
            args.extend(pairs.0.iter().cloned());
            // One regressor per part of the PCA models, and the displacement's.
            let mut units: Vec<String> = match method {
                Method::WholeBody => vec![s("body")],
                _ => self.subjects[d.src].parts.clone(),
            };
            units.push(s("displacement"));
            if name == "gpr-nn" && self.set.spec.train.len() >= 2 {
                self.cross_validation(d, &model, &inputs, &args, graph);
            }
            for t in per_part::fit(graph.part_tasks, "gpr-train", &model, None, inputs, args, &units) {
                graph.push(t);
            }
            self.stamps.push(model.clone());
            for m in &d.tests {
                if !self.set.motion_dir(d.src, m).is_dir() {
                    continue;
                }
                self.predictions(d, m, (name, *method, *keys), &model, kind, graph);
                if name == "gpr-nn" {
                    self.surface_methods(d, m, &model, graph);
                    self.transfer_sheet(d, m, graph);
                }
            }
        }
        for m in &d.tests {
            if self.set.motion_dir(d.src, m).is_dir() {
                self.method_sheet(d, m, graph);
            }
        }
    }

    /// CVPR fig. 10 of test motion `m` in direction `d`: every method's raw output (no §6)
    /// beside the source and the truth if any.
    fn method_sheet(&mut self, d: &Direction, m: &str, graph: &mut Graph) {
        let dn = d.name();
        let names: Vec<String> = Method::ALL
            .into_iter()
            .filter(|x| self.opt.methods().contains(x))
            .map(|x| x.name().to_string())
            .chain(std::iter::once(s("gpr-nn-keyposes")))
            .collect();
        let truth = self.truth(d.tgt, m);
        let sheet = format!("{}/figures/fig10-{dn}-{m}/contact.png", self.out);
        let mut seqs = vec![join(&self.set.root, &[d.src, m])];
        seqs.extend(names.iter().map(|n| format!("{}/transfer/{dn}/{m}/{n}", self.out)));
        let labels = format!("source,{}{}", names.join(","), if truth.is_some() { ",truth" } else { "" });
        seqs.extend(truth);
        let inputs = names
            .iter()
            .map(|n| format!("{}/predict/{dn}/{m}/{n}-{}.json", self.work, self.opt.placement().name()))
            .collect();
        self.stamps.push(graph.push(render_sheet(&sheet, inputs, &labels, true, seqs)));
    }

    /// The cross-validated estimate of direction `d`'s pose error: the gpr-nn model trained
    /// whole once more (`--cross-validate` needs every part in one task, whatever the cluster
    /// split) with the hyperparameters `model` learnt, and its report, whose `cv_rms_pose_m`
    /// results.json carries beside the direction's records.
    fn cross_validation(&mut self, d: &Direction, model: &str, inputs: &[String], args: &[String], graph: &mut Graph) {
        let report = model.replace(".model", ".cv.json");
        let mut a = args.to_vec();
        let mut inputs = inputs.to_vec();
        // `--config auto` learns every configuration's hyperparameters; one model holds one's.
        let auto = args.windows(2).any(|w| w[0] == flag!(GprTrain, config) && w[1] == value_name(ConfigName::Auto))
            || args.iter().any(|w| *w == format!("{}={}", flag!(GprTrain, config), value_name(ConfigName::Auto)));
        if !auto {
            a.extend([flag!(GprTrain, hyperparameters_from), model.to_string()]);
            inputs.push(model.to_string());
        }
        a.extend([flag!(GprTrain, cross_validate), flag!(GprTrain, report), report.clone(), flag!(GprTrain, out), model.replace(".model", ".cv.model")]);
        let mut task = Task::run("gpr-train", report.clone(), inputs, a).mkdir_target();
        // Its own job array on a cluster: it waits for the models of the `gpr-train` array.
        task.kind = s("cross-validate");
        graph.push(task);
        self.cross_validations.push((d.label(), report));
    }

    /// `gpr-predict` of test motion `m` with one model (gpr-nn at every placement) and the
    /// evaluations.
    fn predictions(&mut self, d: &Direction, m: &str, variant: (&str, Method, bool), model: &str, kind: &str, graph: &mut Graph) {
        let (name, method, keys) = variant;
        let default_pl = self.opt.placement();
        let mut places = vec![default_pl];
        if name == "gpr-nn" {
            let all = [Placement::ScaledSource, Placement::Regressed, Placement::Blended];
            places.extend(all.into_iter().filter(|&p| p != default_pl));
        }
        for pl in places {
            let dn = d.name();
            let seq = if pl == default_pl {
                format!("{}/transfer/{dn}/{m}/{name}", self.out)
            } else {
                format!("{}/placement/{dn}/{m}/{}", self.work, pl.name())
            };
            let timing = format!("{}/predict/{dn}/{m}/{name}-{}.json", self.work, pl.name());
            let mut args = vec![
                s("-q"), flag!(GprPredict, model), s(model), flag!(GprPredict, source_pca), self.pca(d.src, kind), flag!(GprPredict, target_pca),
                self.pca(d.tgt, kind), flag!(GprPredict, target_template), self.template(d.tgt), flag!(GprPredict, placement),
                pl.name().into(),
            ];
            args.extend(self.opt.predict_flags());
            args.extend([self.aligned(d.src, m), flag!(GprPredict, out), seq.clone(), flag!(GprPredict, timing), timing.clone()]);
            let inputs = vec![s(model), self.aligned(d.src, m)];
            self.stamps.push(graph.push(Task::run("gpr-predict", timing.clone(), inputs, args).mkdir_target()));
            let training = if keys { "keyposes" } else { "dense" };
            self.eval(d, m, &seq, name, (method.name(), pl, training), timing, graph);
        }
    }

    /// The contact sheet of test motion `m`: source, gpr-nn's transfer and the truth if any.
    fn transfer_sheet(&mut self, d: &Direction, m: &str, graph: &mut Graph) {
        let default_pl = self.opt.placement();
        {
            let sheet = format!("{}/render/{dn}/{m}/contact.png", self.out, dn = d.name());
            let mut seqs = vec![join(&self.set.root, &[d.src, m]), format!("{}/transfer/{}/{m}/gpr-nn", self.out, d.name())];
            let mut labels = s("source,transfer");
            if let Some(truth) = self.truth(d.tgt, m) {
                seqs.push(truth);
                labels.push_str(",truth");
            }
            let timing = format!("{}/predict/{}/{m}/gpr-nn-{}.json", self.work, d.name(), default_pl.name());
            self.stamps.push(graph.push(render_sheet(&sheet, vec![timing], &labels, false, seqs)));
        }
    }

    /// CVPR §6 after the regression, of test motion `m` with gpr-nn: one `gpr-predict` that
    /// corrects (M = 3) and writes both the corrected parts averaged (`gpr-nn+correct`) and
    /// stitched (`gpr-nn+correct+stitch`); their evaluations, the per-frame confidence figure
    /// and contact sheets.
    fn surface_methods(&mut self, d: &Direction, m: &str, model: &str, graph: &mut Graph) {
        let default_pl = self.opt.placement();
        let dn = d.name();
        let training: Vec<String> = self.train[d.tgt].iter().map(|t| self.aligned(d.tgt, t)).collect();
        let truth = self.truth(d.tgt, m);
        let seq = |meth: &str| format!("{}/transfer/{dn}/{m}/{meth}", self.out);
        let (corrected, stitched) = (seq("gpr-nn+correct"), seq("gpr-nn+correct+stitch"));
        let timing = format!("{}/predict/{dn}/{m}/gpr-nn+correct+stitch-{}.json", self.work, default_pl.name());
        // Per-frame confidence (docs/FORMATS.md) beside the full pipeline's output.
        let conf_dir = format!("{}/confidence/{dn}", self.work);
        let conf = format!("{conf_dir}/{m}.json");
        let mut inputs = vec![s(model), self.aligned(d.src, m), self.seg(d.tgt)];
        inputs.extend(training.iter().cloned());
        let mut args = vec![
            s("-q"), flag!(GprPredict, model), s(model), flag!(GprPredict, source_pca), self.pca(d.src, "pca"), flag!(GprPredict, target_pca),
            self.pca(d.tgt, "pca"), flag!(GprPredict, target_template), self.template(d.tgt), flag!(GprPredict, placement),
            default_pl.name().into(), flag!(GprPredict, surface), s("correct-stitch"), flag!(GprPredict, segmentation), self.seg(d.tgt),
        ];
        args.extend(self.opt.predict_flags());
        for t in &training {
            args.extend([flag!(GprPredict, target_training), t.clone()]);
        }
        args.extend([
            flag!(GprPredict, neighbours), s("3"), self.aligned(d.src, m), flag!(GprPredict, corrected_out), corrected.clone(), flag!(GprPredict, out), stitched.clone(),
            flag!(GprPredict, timing), timing.clone(), flag!(GprPredict, confidence), conf.clone(),
        ]);
        self.stamps.push(graph.push(
            Task::run("gpr-predict", timing.clone(), inputs, args).mkdir_target().mkdir(conf_dir),
        ));
        for (meth, seq) in [("gpr-nn+correct", &corrected), ("gpr-nn+correct+stitch", &stitched)] {
            let rec = self.eval(d, m, seq, meth, (meth, default_pl, "dense"), timing.clone(), graph);
            if meth == "gpr-nn+correct+stitch" {
                // Per-frame confidence beside the error (where truth exists), for the report.
                let plot = format!("{}/figures/confidence-{dn}-{m}.png", self.out);
                let mut inputs = vec![timing.clone()];
                let mut args = vec![s("confidence"), s("-q"), flag!(ConfidenceFigure, confidence), conf.clone()];
                if truth.is_some() {
                    inputs.push(rec.clone());
                    args.extend([flag!(ConfidenceFigure, eval), rec.clone()]);
                }
                args.extend([
                    flag!(ConfidenceFigure, title), format!("{} {m}: confidence and error per frame", d.label()), flag!(ConfidenceFigure, out),
                    plot.clone(),
                ]);
                self.stamps.push(graph.push(Task::run("paper-figure", plot, inputs, args).mkdir_target()));
            }
            let sheet = format!("{}/render/{dn}/{m}/{meth}/contact.png", self.out);
            let mut seqs = vec![join(&self.set.root, &[d.src, m]), seq.clone()];
            seqs.extend(truth.clone());
            let labels = format!("source,{meth}{}", if truth.is_some() { ",truth" } else { "" });
            self.stamps.push(graph.push(render_sheet(&sheet, vec![timing.clone()], &labels, false, seqs)));
        }
    }

    /// Learning curves (CVPR figs. 7-9), errors against the true parts (PCA truncation
    /// included), the paper's zero-mean GPs; the whole body at the parts' total dimensions
    /// (the `pca-whole` models). On the set's true correspondences when every training pair has
    /// them, else on the DTW pairs (labelled `dtw` in the CSV and the figures).
    fn learning_curves(&mut self, pairs: &(Vec<String>, Vec<String>), graph: &mut Graph) {
        let (sn, tn) = (self.set.spec.source.as_str(), self.set.spec.target.as_str());
        let lc = format!("{}/learning-curves/learning_curves.csv", self.out);
        let mut inputs = vec![self.set.set_json().to_string_lossy().into_owned()];
        inputs.extend([sn, tn].into_iter().flat_map(|x| [self.pca(x, "pca"), self.pca(x, "pca-whole")]));
        let mut args = vec![
            s("-q"), flag!(LearningCurves, common.seed), s("0"), flag!(LearningCurves, mean), s("zero"), flag!(LearningCurves, set), join(&self.set.root, &[]),
            flag!(LearningCurves, source_pca), self.pca(sn, "pca"), flag!(LearningCurves, target_pca), self.pca(tn, "pca"),
            flag!(LearningCurves, source_whole), self.pca(sn, "pca-whole"), flag!(LearningCurves, target_whole), self.pca(tn, "pca-whole"),
            flag!(LearningCurves, source_name), s(sn), flag!(LearningCurves, target_name), s(tn),
        ];
        let true_pairs = self.set.spec.train.iter().all(|p| p.extra.contains_key("correspondences"));
        if true_pairs {
            for p in &self.set.spec.train {
                args.extend([flag!(LearningCurves, true_pair), p.source.clone(), self.aligned(sn, &p.source), self.aligned(tn, &p.target)]);
            }
            for p in &self.set.spec.train {
                inputs.extend([self.aligned(sn, &p.source), self.aligned(tn, &p.target)]);
            }
        } else {
            args.extend(pairs.0.iter().cloned());
            inputs.extend(pairs.1.iter().cloned());
        }
        args.extend([flag!(LearningCurves, out), crate::task::parent(&lc)]);
        self.stamps.push(graph.push(Task::run("learning-curves", lc, inputs, args).mkdir_target()));
    }

    /// CVPR fig. 3 (the association cost of the first training pair, its DTW path, key-poses
    /// and truth) and fig. 5 (a correction example) on the first forward test motion; returns
    /// the report's 3D views.
    fn figures(&mut self, first_test: Option<&str>, graph: &mut Graph) -> Vec<String> {
        let (sn, tn) = (self.set.spec.source.clone(), self.set.spec.target.clone());
        let (sn, tn) = (sn.as_str(), tn.as_str());
        let set: &'a CaptureSet = self.set;
        let p0 = &set.spec.train[0];
        let fig3 = format!("{}/figures/fig3-{}.png", self.out, p0.source);
        let inputs = vec![
            self.pca(sn, "pca"), self.pca(tn, "pca"), self.aligned(sn, &p0.source), self.aligned(tn, &p0.target),
        ];
        let args = vec![
            s("cost-matrix"), s("-q"), flag!(CostMatrixFigure, set), join(&self.set.root, &[]), flag!(CostMatrixFigure, motion), p0.source.clone(),
            flag!(CostMatrixFigure, source_pca), self.pca(sn, "pca"), flag!(CostMatrixFigure, target_pca), self.pca(tn, "pca"),
            self.aligned(sn, &p0.source), self.aligned(tn, &p0.target), flag!(CostMatrixFigure, out), fig3.clone(),
        ];
        self.stamps.push(graph.push(Task::run("paper-figure", fig3, inputs, args).mkdir_target()));

        let Some(m0) = first_test else { return Vec::new() };
        let dn0 = format!("{sn}-to-{tn}");
        let model0 = format!("{}/models/{dn0}/gpr-nn.model", self.work);
        let training: Vec<String> = self.train[tn].iter().map(|t| self.aligned(tn, t)).collect();
        let truth0 = self.truth(tn, m0);
        let fig5 = format!("{}/figures/fig5-{m0}.png", self.out);
        let mut inputs = vec![model0.clone(), self.seg(tn), self.aligned(sn, m0)];
        inputs.extend(training.iter().cloned());
        let mut args = vec![
            s("correction"), s("-q"), flag!(CorrectionFigure, model), model0, flag!(CorrectionFigure, source_pca), self.pca(sn, "pca"),
            flag!(CorrectionFigure, target_pca), self.pca(tn, "pca"), flag!(CorrectionFigure, segmentation), self.seg(tn),
        ];
        for t in &training {
            args.extend([flag!(CorrectionFigure, target_training), t.clone()]);
        }
        if let Some(t) = &truth0 {
            args.extend([flag!(CorrectionFigure, truth), t.clone()]);
        }
        args.extend([
            flag!(CorrectionFigure, size), s("300"), self.aligned(sn, m0), flag!(CorrectionFigure, out), fig5.clone(), flag!(CorrectionFigure, report),
            format!("{}/figures/fig5-{m0}.json", self.out),
        ]);
        self.stamps.push(graph.push(Task::run("paper-figure", fig5, inputs, args).mkdir_target()));
        // The report's 3D view: the first forward test motion, after correction and stitching.
        let mut views = vec![
            format!("source={}", join(&self.set.root, &[sn, m0])),
            format!("transfer={}/transfer/{dn0}/{m0}/gpr-nn+correct+stitch", self.out),
        ];
        views.extend(truth0.map(|t| format!("truth={t}")));
        views
    }
}

/// Adds the transfer pipeline's tasks and its variables (`TRANSFER_RECORDS`, `TRANSFER_STAMPS`,
/// `TRANSFER_REPORT_VIEWS`) to `graph`. `out` is the pipeline's output folder.
pub fn plan(set: &CaptureSet, out: &str, opt: &TransferOptions, graph: &mut Graph) -> Result<()> {
    let work = format!("{out}/work");
    let (sn, tn) = (set.spec.source.clone(), set.spec.target.clone());
    let mut subjects = BTreeMap::new();
    for x in [&sn, &tn] {
        subjects.insert(x.clone(), subject(set, &work, x, graph)?);
    }
    let train = BTreeMap::from([
        (sn.clone(), set.spec.train.iter().map(|p| p.source.clone()).collect()),
        (tn.clone(), set.spec.train.iter().map(|p| p.target.clone()).collect()),
    ]);
    let mut plan = Plan { set, out, work, opt, subjects, train, records: Vec::new(), stamps: Vec::new(), cross_validations: Vec::new() };
    for x in [&sn, &tn] {
        plan.front_end(x, graph)?;
    }
    let pairs = plan.pairs(graph);
    let directions = plan.directions()?;
    let first_test = directions[0].tests.first().cloned();
    for d in &directions {
        plan.direction(d, &pairs, graph);
    }
    drop(directions);
    plan.learning_curves(&pairs, graph);
    let views = plan.figures(first_test.as_deref(), graph);
    graph.variable("TRANSFER_REPORT_VIEWS", views);
    graph.variable("TRANSFER_RECORDS", plan.records.clone());
    graph.variable("TRANSFER_STAMPS", plan.stamps.clone());

    // Every evaluation record merged into one list; the other products are prerequisites so
    // that `results.json` stands for the whole run.
    let results = format!("{out}/results.json");
    let mut inputs = plan.records.clone();
    inputs.extend(plan.stamps);
    let mut args = vec![s("collect"), s("transfer"), s("--out"), results.clone()];
    for (label, report) in plan.cross_validations {
        args.extend([s("--cross-validation"), format!("{label}={report}")]);
        inputs.push(report);
    }
    args.extend(plan.records);
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
    let mut args = vec![s("-q"), flag!(Render, separate_rows), flag!(Render, no_frames), flag!(Render, no_gif)];
    if follow {
        args.push(flag!(Render, follow));
    }
    args.extend([flag!(Render, labels), s(labels), flag!(Render, out), crate::task::parent(sheet)]);
    args.extend(seqs);
    Task::run("render", sheet, inputs, args)
}

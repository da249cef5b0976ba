//! Golden files of the plan on the tiny preset's description (`fixtures/tiny-set`: set.json,
//! subject.json and empty frame files named as `synth --preset tiny` writes them): the make
//! fragment and the Slurm arrays (kinds, task counts, dependencies, resources, targets).
//! `UPDATE_GOLDEN=1 cargo test --release -p plan --test golden` rewrites them after a reviewed
//! change of the pipelines.

use std::path::{Path, PathBuf};
use std::process::Command;

use plan::task::PartTasks;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

fn check(golden: &str, text: &str) {
    let path = repo().join("fixtures/plan").join(golden);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, text).unwrap();
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if want != text {
        let line = want.lines().zip(text.lines()).position(|(a, b)| a != b).unwrap_or(0);
        panic!(
            "{} differs from the plan at line {}:\n golden: {}\n   plan: {}",
            path.display(),
            line + 1,
            want.lines().nth(line).unwrap_or(""),
            text.lines().nth(line).unwrap_or("")
        );
    }
}

fn plan(args: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_plan"))
        .current_dir(repo())
        .args(args)
        .output()
        .unwrap();
    assert!(out.status.success(), "plan {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

#[test]
fn make_fragment_of_the_tiny_set() {
    let dir = tempfile::tempdir().unwrap();
    let frag = dir.path().join("plan.mk");
    plan(&["make", "--set", "fixtures/tiny-set", "--pipeline-out", "out", "--out", frag.to_str().unwrap()]);
    check("tiny-set.plan.mk", &std::fs::read_to_string(&frag).unwrap());
}

/// The variation report's 3D view shows the first variations of the first group the plan keeps:
/// at most `--variation-n` of them, and on a set none of whose motions the named groups hold,
/// the group of its own the first training motion becomes.
#[test]
fn the_variation_report_views_the_first_planned_group() {
    let views = |args: &[&str]| {
        let dir = tempfile::tempdir().unwrap();
        let frag = dir.path().join("plan.mk");
        let mut all = vec!["make", "--set", "fixtures/tiny-set", "--pipeline-out", "out", "--out", frag.to_str().unwrap()];
        all.extend(args);
        plan(&all);
        let text = std::fs::read_to_string(&frag).unwrap();
        text.lines().find_map(|l| l.strip_prefix("VARIATION_REPORT_VIEWS := ")).map(str::to_string).unwrap()
    };
    assert_eq!(views(&["--variation-group", "moves=kick,punch", "--variation-n", "2"]), "var0=out/variation/moves/kick/var0 var1=out/variation/moves/kick/var1");
    assert_eq!(
        views(&["--variation-group", "dances=salsa,tango"]),
        "var0=out/variation/walk/walk/var0 var1=out/variation/walk/walk/var1 var2=out/variation/walk/walk/var2"
    );
}

/// `plan make --part-tasks` writes Slurm's split for make: a `--part` task per part and the merges.
#[test]
fn make_fragment_with_part_tasks_has_the_pieces_and_merges() {
    let dir = tempfile::tempdir().unwrap();
    let frag = dir.path().join("plan.mk");
    plan(&["make", "--part-tasks", "--set", "fixtures/tiny-set", "--pipeline-out", "out", "--out", frag.to_str().unwrap()]);
    let text = std::fs::read_to_string(&frag).unwrap();
    // Each pipeline counts its own steps: the first task is the first of the transfer's.
    let graph = tiny_graph();
    let (transfer, variation) = (graph.place(0).1, graph.place(graph.tasks.len() - 1));
    assert_eq!(variation.0, variation.1, "the last task is the variation's last");
    assert_eq!(transfer + variation.1, graph.tasks.len());
    assert!(text.contains(&format!("--of 1/{transfer} ")), "not the Slurm graph's {transfer} transfer tasks");
    assert!(text.contains(&format!("--of 1/{} ", variation.1)), "not the Slurm graph's {} variation tasks", variation.1);
    for want in ["out/work/variation/locomotion.parts/torso.piece:", "--part torso", "$(BIN)/merge-parts -q out/work/A/pca.parts/"] {
        assert!(text.contains(want), "no `{want}` in the fragment");
    }
}

#[test]
fn slurm_arrays_of_the_tiny_set() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slurm-run");
    plan(&[
        "slurm", "--set", "fixtures/tiny-set", "--pipeline-out", "out", "--bin", "/opt/surfcap/bin",
        "--workdir", "/work/surfcap", "--out", out.to_str().unwrap(),
    ]);
    // One summary line per array (in submission order) and its tasks' targets, with the
    // temporary directory replaced so the golden file does not depend on it.
    let tmp = out.to_str().unwrap();
    let run = std::fs::read_to_string(out.join("run.sbatch")).unwrap().replace(tmp, "OUT");
    let mut text = run.clone();
    for line in run.lines().filter(|l| l.contains("=$(sbatch")) {
        let kind = line.split('=').next().unwrap().replace('_', "-");
        let script = std::fs::read_to_string(out.join("slurm").join(format!("{kind}.sbatch"))).unwrap();
        text.push_str(&format!("\n== {kind}.sbatch\n{}", script.replace(tmp, "OUT")));
        let table = std::fs::read_to_string(out.join("slurm").join(format!("{kind}.tasks"))).unwrap();
        for (i, row) in table.lines().enumerate() {
            let task: plan::task::Task = serde_json::from_str(row).unwrap();
            assert_eq!(task.kind, kind);
            text.push_str(&format!("{i} {}\n", task.target));
        }
        assert!(out.join("slurm/logs").join(&kind).is_dir(), "no log directory for {kind}");
    }
    check("tiny-set.slurm.txt", &text);
}

/// Every input of every task is either a file of the capture set or the target of another task,
/// and no two tasks write the same target: the graph is closed and make/Slurm can order it.
#[test]
fn graph_is_closed_and_targets_unique() {
    for split in [PartTasks::OnePerPart, PartTasks::OnePerModel] {
        graph_is_closed(&tiny_graph_split(split, &[]));
    }
}

fn graph_is_closed(g: &plan::task::Graph) {
    let set = repo().join("fixtures/tiny-set");
    let mut targets: Vec<&str> = g.tasks.iter().map(|t| t.target.as_str()).collect();
    targets.sort();
    let n = targets.len();
    targets.dedup();
    assert_eq!(targets.len(), n, "two tasks write the same target");
    for t in &g.tasks {
        for i in &t.inputs {
            let from_set = Path::new(i).starts_with(&set);
            assert!(from_set || targets.binary_search(&i.as_str()).is_ok(), "{}: input {i} has no producer", t.target);
        }
    }
    // Slurm needs the kinds in an order where each array only reads earlier ones.
    let arrays = plan::slurm::arrays(g).unwrap();
    for (k, (kind, _, deps)) in arrays.iter().enumerate() {
        for d in deps {
            assert!(arrays[..k].iter().any(|(e, _, _)| e == d), "{kind} submitted before {d}");
        }
    }
}

/// Every stage binary the plan runs has a request in the built-in table (from measured peaks),
/// the merges of per-part pieces included: none falls back to the 500 MB guess.
#[test]
fn every_stage_the_plan_runs_has_a_measured_request() {
    let g = tiny_graph();
    let table = plan::resources::Table::default();
    for t in &g.tasks {
        for b in t.bins() {
            assert!(table.get(b).is_some(), "{} ({}): no request for {b}", t.target, t.kind);
        }
    }
    assert!(g.tasks.iter().any(|t| t.bins() == ["merge-parts"]), "no merge task in the plan");
}

#[derive(clap::Parser)]
struct T {
    #[command(flatten)]
    t: plan::options::TransferOptions,
    #[command(flatten)]
    v: plan::options::VariationOptions,
}

/// The Slurm plan of the tiny preset's description with the default options, into `out`.
fn tiny_graph() -> plan::task::Graph {
    tiny_graph_with(&[])
}

/// The tiny set's Slurm graph (one task per part) with these pipeline options (the rest at
/// their defaults).
fn tiny_graph_with(args: &[&str]) -> plan::task::Graph {
    tiny_graph_split(PartTasks::OnePerPart, args)
}

fn tiny_graph_split(split: PartTasks, args: &[&str]) -> plan::task::Graph {
    let t = <T as clap::Parser>::parse_from(std::iter::once("t").chain(args.iter().copied()));
    let opts = plan::options::PipelineOptions {
        paths: plan::options::Paths { set: repo().join("fixtures/tiny-set"), pipeline_out: "out".into() },
        transfer: t.t,
        variation: t.v,
    };
    plan::stage::graph(&opts, split).unwrap()
}

/// make's graph (one task per model) is Slurm's with each model's part tasks and merge folded
/// into one run of the stage: the same targets but the pieces, each model's task with the part
/// tasks' arguments but `--part` and the merge's `--out` and `--report`, and nothing else changed.
#[test]
fn one_task_per_model_is_the_part_tasks_folded() {
    let (make, slurm) = (tiny_graph_split(PartTasks::OnePerModel, &[]), tiny_graph());
    let run_args = |t: &plan::task::Task| match &t.steps[..] {
        [plan::task::Step::Run { args, .. }] => args.clone(),
        _ => panic!("{}: not one stage run", t.target),
    };
    let piece = |t: &plan::task::Task| t.target.ends_with(".piece");
    assert!(make.tasks.iter().all(|t| !piece(t) && !t.kind.starts_with("merge-")), "make's graph has part tasks");
    let folded: Vec<&plan::task::Task> = slurm.tasks.iter().filter(|t| !piece(t)).collect();
    assert_eq!(make.tasks.len(), folded.len());
    let mut merges = 0;
    for (m, s) in make.tasks.iter().zip(folded) {
        assert_eq!(m.target, s.target);
        let Some(stage) = s.kind.strip_prefix("merge-") else {
            assert_eq!(m, s);
            continue;
        };
        merges += 1;
        assert_eq!(m.kind, stage);
        // The first piece's task, without `--part NAME` and with the merge's outputs.
        let first = slurm.producer(&s.inputs[0]).unwrap();
        let (piece_args, merge_args) = (run_args(first), run_args(s));
        let after = |a: &[String], flag: &str| a.iter().position(|x| x == flag).map(|k| a[k + 1].clone());
        let mut want: Vec<String> = Vec::new();
        let mut k = 0;
        while k < piece_args.len() {
            match piece_args[k].as_str() {
                "--part" => k += 2,
                "--out" => {
                    want.extend(["--out".into(), m.target.clone()]);
                    k += 2;
                }
                "--report" => {
                    want.extend(["--report".into(), after(&merge_args, "--report").unwrap()]);
                    k += 2;
                }
                _ => {
                    want.push(piece_args[k].clone());
                    k += 1;
                }
            }
        }
        assert_eq!(run_args(m), want, "{}", m.target);
        assert_eq!((&m.inputs, &m.dirs), (&first.inputs, &s.dirs), "{}", m.target);
    }
    assert_eq!(merges, 2 + 8 + 2, "pca-fit, gpr-train and gpdm-train models");
}

/// The models of several parts are fitted part by part: every part model (`pca.model`), every
/// regression (`gpr-train`: the parts and the displacement) and every group's GPDMs (`gpdm-train`)
/// is the target of a `merge-parts` task whose pieces are `--part` tasks of that stage, one
/// per name of the subject's parts; the whole-body PCA (one part) stays one task.
#[test]
fn multi_part_models_are_fitted_part_by_part() {
    let set = repo().join("fixtures/tiny-set");
    let g = tiny_graph();
    let spec = mesh_core::capture_set::SubjectSpec::load(set.join("A/subject.json")).unwrap();
    let mut parts: Vec<String> = spec.parts.keys().cloned().collect();
    parts.sort();
    let args = |t: &plan::task::Task| match &t.steps[..] {
        [plan::task::Step::Run { args, .. }] => args.clone(),
        _ => panic!("{}: not one stage run", t.target),
    };
    let mut merged = std::collections::BTreeMap::<String, usize>::new();
    for t in g.tasks.iter().filter(|t| t.kind.starts_with("merge-")) {
        let stage = t.kind.trim_start_matches("merge-");
        let mut names: Vec<String> = t
            .inputs
            .iter()
            .map(|piece| {
                let p = g.producer(piece).unwrap_or_else(|| panic!("{piece}: no producer"));
                assert_eq!(p.kind, stage, "{piece}");
                let a = args(p);
                let k = a.iter().position(|x| x == "--part").unwrap_or_else(|| panic!("{piece}: no --part"));
                a[k + 1].clone()
            })
            .collect();
        names.sort();
        let mut want = if t.target.contains("whole-body") { vec!["body".to_string()] } else { parts.clone() };
        if stage == "gpr-train" {
            want.push("displacement".into());
            want.sort();
        }
        assert_eq!(names, want, "{}", t.target);
        *merged.entry(stage.to_string()).or_default() += 1;
    }
    // Two subjects' part models; 2 directions x 4 models (gpr-nn, keypose-affine, whole-body,
    // gpr-nn on key-poses); 2 groups.
    assert_eq!(merged.get("pca-fit"), Some(&2));
    assert_eq!(merged.get("gpr-train"), Some(&8));
    assert_eq!(merged.get("gpdm-train"), Some(&2));
    // Nothing reads a piece but its merge, and no whole-model task of these stages is left but
    // the cross-validated estimate of each direction, which needs every part at once (and
    // reads the merged model's hyperparameters).
    let mut cross_validations = 0;
    for t in &g.tasks {
        for i in t.inputs.iter().filter(|i| i.ends_with(".piece")) {
            assert!(t.kind.starts_with("merge-"), "{} reads the piece {i}", t.target);
        }
        if ["gpr-train", "gpdm-train"].contains(&t.kind.as_str()) {
            assert!(args(t).contains(&"--part".to_string()), "{}: a whole-model task", t.target);
        }
        if t.kind == "cross-validate" {
            let a = args(t);
            assert!(a.contains(&"--cross-validate".to_string()) && !a.contains(&"--part".to_string()), "{}", t.target);
            let model = &a[a.iter().position(|x| x == "--hyperparameters-from").expect("--hyperparameters-from") + 1];
            assert!(t.inputs.contains(model) && g.tasks.iter().any(|m| m.kind == "merge-gpr-train" && &m.target == model), "{}: {model}", t.target);
            cross_validations += 1;
        }
    }
    assert_eq!(cross_validations, 2, "one per direction");
}

/// A group of three motions pre-blended on two pairs at three weights: `prealign` gets the
/// subject's segmentation and every motion aligned (among its inputs too), the weights and the
/// pairs as given, and the group's GPDMs, samples and evaluation follow as for any group.
#[test]
fn a_group_of_three_motions_blends_the_pairs_asked() {
    let g = tiny_graph_with(&[
        "--variation-group",
        "moves=walk,run,kick",
        "--prealign-flags",
        "moves=--blend-pairs walk:run,run:kick",
        "--variation-w",
        "0.25,0.5,0.75",
    ]);
    let pre = g.producer("out/work/variation/moves.group").expect("a prealign task");
    let args = match &pre.steps[..] {
        [plan::task::Step::Run { args, .. }] => args.clone(),
        _ => panic!("prealign: not one stage run"),
    };
    let after = |flag: &str| args[args.iter().position(|a| a == flag).unwrap_or_else(|| panic!("{flag} missing: {args:?}")) + 1].clone();
    let aligned: Vec<&String> = args.iter().filter(|a| a.ends_with(".aligned")).collect();
    assert_eq!(aligned, ["out/work/A/walk.aligned", "out/work/A/run.aligned", "out/work/A/kick.aligned"]);
    assert_eq!(after("--segmentation"), "out/work/A/parts.seg");
    assert_eq!(after("--blend-pairs"), "walk:run,run:kick");
    assert_eq!(after("--blend-weights"), "0.25,0.5,0.75");
    for i in aligned.into_iter().chain([&after("--segmentation")]) {
        assert!(pre.inputs.contains(i), "{i}: not among the inputs");
    }
    for target in ["out/work/variation/moves.model", "out/work/variation/moves-samples.json", "out/work/variation/moves-eval.json"] {
        assert!(g.producer(target).is_some(), "{target}: no task");
    }
}

/// A group of one motion is sampled without blends (they need two motions; `hmc-sample` refuses
/// blend weights for such a group), while a group of two keeps the weights asked.
#[test]
fn a_group_of_one_motion_is_sampled_without_blends() {
    let g = tiny_graph_with(&[
        "--variation-group",
        "solo=jump",
        "--variation-group",
        "pair=walk,run",
        "--variation-blends",
        "0.3,0.6",
    ]);
    let blends = |group: &str| {
        let task = g.producer(&format!("out/work/variation/{group}-samples.json")).expect("a sampling task");
        let args = task
            .steps
            .iter()
            .find_map(|st| match st {
                plan::task::Step::Run { bin, args } if bin == "hmc-sample" => Some(args.clone()),
                _ => None,
            })
            .expect("an hmc-sample run");
        args[args.iter().position(|a| a == "--blends").expect("--blends") + 1].clone()
    };
    assert_eq!(blends("solo"), "");
    assert_eq!(blends("pair"), "0.3,0.6");
}

/// `gpr-train` gets `--mean` only when the pipeline is given one (GPR_MEAN), so a configuration
/// in GPR_TRAIN_FLAGS (`--config zero-mean`, `--config auto`) decides the mean otherwise.
#[test]
fn the_mean_is_the_configurations_unless_the_pipeline_names_one() {
    let means = |g: &plan::task::Graph| -> Vec<Option<String>> {
        g.tasks
            .iter()
            .filter(|t| t.kind == "gpr-train")
            .map(|t| match &t.steps[..] {
                [plan::task::Step::Run { args, .. }] => args.iter().position(|a| a == "--mean").map(|k| args[k + 1].clone()),
                _ => panic!("{}: not one stage run", t.target),
            })
            .collect()
    };
    let default = means(&tiny_graph_with(&["--gpr-train-flags", "--config zero-mean"]));
    assert!(!default.is_empty() && default.iter().all(Option::is_none), "{default:?}");
    let named = means(&tiny_graph_with(&["--gpr-mean", "zero"]));
    assert!(named.iter().all(|m| m.as_deref() == Some("zero")), "{named:?}");
}

/// A variation group naming a motion the subject does not have keeps the ones it has (a group of
/// one motion is sampled without blends), and a group with none of its motions is left out:
/// prealign is never asked for a missing motion.
#[test]
fn a_variation_group_keeps_the_motions_the_subject_has() {
    let g = tiny_graph_with(&["--variation-group", "jumps=jump,backflip", "--variation-group", "none=backflip,cartwheel"]);
    let prealigns: Vec<&plan::task::Task> = g.tasks.iter().filter(|t| t.kind == "prealign").collect();
    assert_eq!(prealigns.len(), 1, "{:?}", prealigns.iter().map(|t| &t.target).collect::<Vec<_>>());
    let plan::task::Step::Run { args, .. } = &prealigns[0].steps[0] else { panic!("prealign is not one stage run") };
    let motions: Vec<&String> = args.iter().filter(|a| a.ends_with(".aligned")).collect();
    assert_eq!(motions, ["out/work/A/jump.aligned"]);
    assert!(prealigns[0].target.ends_with("jumps.group"));
}

/// The variation reads the front end the transfer runs: each group's `prealign` reads the
/// `segment` and `align` tasks' outputs of its subject (one task per file, whichever pipeline
/// asked first, B's too with `--variation-subject B`); a group modelled as one part reads
/// motions aligned on the whole body (`align --frame body`, no segmentation), so that a subject
/// whose curves do not segment still runs.
#[test]
fn the_variation_reads_the_front_ends_segmentation_and_aligned_motions() {
    let g = tiny_graph_with(&["--variation-subject", "B", "--variation-group", "loco=walk,run", "--variation-group", "hop=jump", "--prealign-flags", "hop=--fallback-whole-body"]);
    let mut targets: Vec<&str> = g.tasks.iter().map(|t| t.target.as_str()).collect();
    let n = targets.len();
    targets.sort();
    targets.dedup();
    assert_eq!(targets.len(), n, "a target made by two tasks");
    let prealign = |group: &str| {
        let t = g.producer(&format!("out/work/variation/{group}.group")).expect("a prealign task");
        let [plan::task::Step::Run { args, .. }] = &t.steps[..] else { panic!("prealign: not one stage run") };
        (t.inputs.clone(), args.clone())
    };
    let kind_of = |target: &str| g.producer(target).map(|t| t.kind.clone());
    let (inputs, args) = prealign("loco");
    assert_eq!(after(&args, "--segmentation"), Some("out/work/B/parts.seg"));
    assert_eq!(kind_of("out/work/B/parts.seg").as_deref(), Some("segment"));
    for m in ["walk", "run"] {
        let f = format!("out/work/B/{m}.aligned");
        assert!(args.contains(&f) && inputs.contains(&f), "{f}");
        let align = g.producer(&f).expect("an align task");
        let [plan::task::Step::Run { args, .. }] = &align.steps[..] else { panic!("align: not one stage run") };
        assert_eq!(after(args, "--frame"), Some("root"));
        assert!(g.tasks.iter().position(|t| t.target == f) < g.tasks.iter().position(|t| t.kind == "prealign"), "the transfer's task");
    }
    let (inputs, args) = prealign("hop");
    assert_eq!(after(&args, "--segmentation"), None);
    assert!(!inputs.iter().any(|i| i.ends_with(".seg")), "{inputs:?}");
    let f = "out/work/B/body/jump.aligned".to_string();
    assert!(args.contains(&f) && inputs.contains(&f), "{args:?}");
    let align = g.producer(&f).expect("an align task");
    let [plan::task::Step::Run { args, .. }] = &align.steps[..] else { panic!("align: not one stage run") };
    assert_eq!(after(args, "--frame"), Some("body"));
    assert_eq!(after(args, "--segmentation"), None);
    assert!(!align.inputs.iter().any(|i| i.ends_with(".seg")), "{:?}", align.inputs);
}

/// The stage arguments of every task of `kind`.
fn runs_of(g: &plan::task::Graph, kind: &str) -> Vec<Vec<String>> {
    g.tasks
        .iter()
        .filter(|t| t.kind == kind)
        .map(|t| match &t.steps[..] {
            [plan::task::Step::Run { args, .. }] => args.clone(),
            _ => panic!("{}: not one stage run", t.target),
        })
        .collect()
}

/// The value after `flag` in `args`.
fn after<'a>(args: &'a [String], flag: &str) -> Option<&'a str> {
    args.iter().position(|a| a == flag).map(|k| args[k + 1].as_str())
}

/// `--config paper` runs the paper's pipeline: whole-body alignment, every model trained with
/// `--config paper`, every prediction placed by the regressed displacement without the foot
/// clean-ups, and the paper's five methods with a fig. 10 sheet per test motion and direction.
/// Without it the stages' defaults hold and the kernel rows are left out.
#[test]
fn config_paper_runs_the_papers_pipeline() {
    let paper = tiny_graph_with(&["--config", "paper"]);
    let aligns = runs_of(&paper, "align");
    assert!(!aligns.is_empty() && aligns.iter().all(|a| after(a, "--frame") == Some("body")), "{aligns:?}");
    let trains = runs_of(&paper, "gpr-train");
    assert!(trains.iter().all(|a| after(a, "--config") == Some("paper")), "{trains:?}");
    let mut methods: Vec<&str> = trains.iter().filter_map(|a| after(a, "--method")).collect();
    methods.sort();
    methods.dedup();
    assert_eq!(methods, ["gpr-linear", "gpr-nn", "gpr-se", "keypose-affine", "whole-body"]);
    // Every method's output is placed the configuration's way (gpr-nn also the other ways, under
    // the work folder); none has the foot clean-ups.
    let predicts = runs_of(&paper, "gpr-predict");
    for a in &predicts {
        if after(a, "--out").is_some_and(|o| o.starts_with("out/transfer/")) {
            assert_eq!(after(a, "--placement"), Some("regressed"), "{a:?}");
        }
        assert!(a.contains(&"--no-footskate".to_string()) && a.contains(&"--no-foot-height".to_string()), "{a:?}");
    }
    let sheets: Vec<&str> =
        paper.tasks.iter().filter(|t| t.kind == "render" && t.target.contains("/fig10-")).map(|t| t.target.as_str()).collect();
    let tests = ["out/figures/fig10-A-to-B-", "out/figures/fig10-B-to-A-"];
    for d in tests {
        assert!(sheets.iter().any(|s| s.starts_with(d)), "no fig. 10 sheet for {d}: {sheets:?}");
    }

    let default = tiny_graph_with(&[]);
    let aligns = runs_of(&default, "align");
    assert!(aligns.iter().all(|a| after(a, "--frame") == Some("root")), "{aligns:?}");
    let trains = runs_of(&default, "gpr-train");
    assert!(trains.iter().all(|a| after(a, "--config").is_none()), "{trains:?}");
    assert!(trains.iter().all(|a| !["gpr-se", "gpr-linear"].contains(&after(a, "--method").unwrap_or(""))));
    let predicts = runs_of(&default, "gpr-predict");
    assert!(predicts.iter().all(|a| !a.contains(&"--no-footskate".to_string())));
    let explicit = tiny_graph_with(&["--config", "paper", "--placement", "scaled-source", "--methods", "gpr-nn", "gpr-se"]);
    let mut methods: Vec<String> = runs_of(&explicit, "gpr-train").iter().filter_map(|a| after(a, "--method").map(str::to_string)).collect();
    methods.sort();
    methods.dedup();
    assert_eq!(methods, ["gpr-nn", "gpr-se"]);
    let outputs = runs_of(&explicit, "gpr-predict");
    let placed: Vec<_> = outputs.iter().filter(|a| after(a, "--out").is_some_and(|o| o.starts_with("out/transfer/"))).collect();
    assert!(!placed.is_empty() && placed.iter().all(|a| after(a, "--placement") == Some("scaled-source")));
}

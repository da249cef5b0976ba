//! The `plan` stage: its [`Params`] (the command line, one subcommand each) and what each
//! subcommand does ([`run`]). The record of `Params` names the subcommand as `"subcommand"`
//! (and `collect`'s as `"table"`) beside its options.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args as ClapArgs, Parser, Subcommand};
use mesh_core::capture_set::CaptureSet;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::options::PipelineOptions;
use crate::task::{Graph, PartTasks};

/// Write the pipelines' task graph (every stage invocation with its inputs and outputs) as a make fragment or Slurm job arrays
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "plan",
    version,
    after_help = "e.g.: plan make --set out/demo/set --pipeline-out out --out out/work/plan.mk\n      \
                  plan slurm --set out/demo/set --pipeline-out out/slurm --out out/slurm\n      \
                  plan run-task --table out/slurm/slurm/align.tasks --task 0\n      \
                  plan step --label 'align A/walk' --of 3/120 -- target/release/align ..."
)]
pub struct Params {
    #[command(subcommand)]
    #[serde(flatten)]
    pub command: Command,
}

#[derive(Subcommand, Debug, Serialize)]
#[serde(tag = "subcommand", rename_all = "kebab-case")]
pub enum Command {
    /// The make fragment both pipelines include (pipelines/plan.mk)
    Make(MakeArgs),
    /// Slurm batch scripts: one job array per stage kind, chained by afterok, and run.sbatch
    Slurm(SlurmArgs),
    /// Run task N of a task table, or skip it when its target is newer than its inputs
    RunTask(RunTaskArgs),
    /// Merge the pipelines' records into one table (results.json, variation.json)
    #[command(subcommand)]
    Collect(Collect),
    /// Run one command of a pipeline recipe and print one line: its label, place and time
    Step(StepArgs),
}

#[derive(ClapArgs, Debug, Serialize)]
pub struct StepArgs {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// What the line calls the step (e.g. `gpr-predict A-to-B/punch/gpr-nn`)
    #[arg(long)]
    pub label: String,
    /// The step's place among the graph's tasks
    #[arg(long, value_name = "I/N", value_parser = crate::step_line::parse_place)]
    pub of: Option<(usize, usize)>,
    /// The command and its arguments, after `--`
    #[arg(required = true, last = true)]
    pub command: Vec<String>,
}

#[derive(ClapArgs, Debug, Serialize)]
pub struct MakeArgs {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub options: PipelineOptions,
    /// One task per part of each model of several parts, joined by merge-parts, as `plan slurm`
    /// writes [default: one task per model, whose stage fits the parts in parallel]
    #[arg(long)]
    pub part_tasks: bool,
    /// Output make fragment
    #[arg(short, long)]
    pub out: PathBuf,
}

#[derive(ClapArgs, Debug, Serialize)]
pub struct SlurmArgs {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub options: PipelineOptions,
    /// Stage binaries the jobs run
    #[arg(long, value_name = "DIR", default_value = "target/release")]
    pub bin: PathBuf,
    /// Directory the jobs start in (the pipelines' paths are relative to it) [default: the current one]
    #[arg(long, value_name = "DIR")]
    pub workdir: Option<PathBuf>,
    /// Measured peaks per stage (scripts/slurm-measure's output) for --mem and --cpus-per-task
    /// [default: the tiny preset's, docs/CLUSTER.md]
    #[arg(long, value_name = "FILE")]
    pub resources: Option<PathBuf>,
    /// Output folder: run.sbatch, and slurm/ with the arrays, task tables and logs
    #[arg(short, long)]
    pub out: PathBuf,
}

#[derive(ClapArgs, Debug, Serialize)]
pub struct RunTaskArgs {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Stage binaries
    #[arg(long, value_name = "DIR", default_value = "target/release")]
    pub bin: PathBuf,
    /// Task table (one task per line, written by `plan slurm`)
    #[arg(long)]
    pub table: PathBuf,
    /// Task index (0-based line of the table; Slurm's SLURM_ARRAY_TASK_ID)
    #[arg(long, value_name = "N")]
    pub task: usize,
}

#[derive(Subcommand, Debug, Serialize)]
#[serde(tag = "table", rename_all = "kebab-case")]
pub enum Collect {
    /// Transfer evaluation records into one list sorted by direction, motion, method
    Transfer {
        #[command(flatten)]
        #[serde(skip)]
        common: CommonArgs,
        /// Output table (results.json)
        #[arg(short, long)]
        out: PathBuf,
        /// DIRECTION=REPORT: the direction's cross-validation report (gpr-train
        /// --cross-validate --report); its `cv_rms_pose_m` goes into each of the direction's
        /// records (repeat per direction)
        #[arg(long, value_name = "DIRECTION=REPORT")]
        cross_validation: Vec<String>,
        /// Evaluation records (transfer-eval --out)
        #[arg(required = true)]
        records: Vec<PathBuf>,
    },
    /// Every group's <g>-train.json, <g>-eval.json and <g>-samples.json into one object
    Variation {
        #[command(flatten)]
        #[serde(skip)]
        common: CommonArgs,
        /// Folder of the group records (OUT/work/variation)
        #[arg(long, value_name = "DIR")]
        work: PathBuf,
        /// Output table (variation.json)
        #[arg(short, long)]
        out: PathBuf,
        /// Group names
        #[arg(required = true)]
        groups: Vec<String>,
    },
}

/// Both pipelines' task graph, models of several parts split into tasks as `part_tasks` says.
pub fn graph(options: &PipelineOptions, part_tasks: PartTasks) -> Result<Graph> {
    let set = CaptureSet::open(&options.paths.set)?;
    let out = options.paths.pipeline_out.to_string_lossy().into_owned();
    let mut graph = Graph { part_tasks, ..Graph::default() };
    crate::transfer::plan(&set, &out, &options.transfer, &mut graph)?;
    graph.transfer_tasks = graph.tasks.len();
    crate::variation::plan(&set, &out, &options.variation, options.transfer.align_frame(), &mut graph)?;
    Ok(graph)
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).with_context(|| format!("{}: cannot make the path absolute", p.display()))
}

/// Runs the subcommand (each initialises its `CommonArgs` first).
pub fn run(args: &Params) -> Result<()> {
    match &args.command {
        Command::Make(a) => {
            a.common.init()?;
            let out = a.options.paths.pipeline_out.to_string_lossy();
            let split = if a.part_tasks { PartTasks::OnePerPart } else { PartTasks::OnePerModel };
            let text = crate::make_fragment::fragment(&graph(&a.options, split)?, &out);
            mesh_core::atomic::write_bytes_atomic(&a.out, text.as_bytes())?;
        }
        Command::Slurm(a) => {
            a.common.init()?;
            let graph = graph(&a.options, PartTasks::OnePerPart)?;
            let workdir = match &a.workdir {
                Some(w) => absolute(w)?,
                None => std::env::current_dir().context("cannot read the current directory")?,
            };
            let resources = match &a.resources {
                Some(p) => {
                    let text = std::fs::read_to_string(p).with_context(|| p.display().to_string())?;
                    crate::resources::Table::parse(&text).with_context(|| p.display().to_string())?
                }
                None => crate::resources::Table::default(),
            };
            let layout = crate::slurm::Layout { workdir, bin: absolute(&a.bin)?, out: absolute(&a.out)?, resources };
            let files = crate::slurm::scripts(&graph, &layout)?;
            for d in crate::slurm::log_dirs(&graph, &layout) {
                std::fs::create_dir_all(&d).with_context(|| format!("{}: cannot create", d.display()))?;
            }
            for (path, text) in files {
                mesh_core::atomic::write_bytes_atomic(&path, text.as_bytes())?;
            }
        }
        Command::RunTask(a) => {
            a.common.init()?;
            let task = crate::task_table::read_task(&a.table, a.task)?;
            if crate::task_table::up_to_date(&task, &a.bin) {
                mesh_core::info!("{}: up to date, skipped", task.target);
                return Ok(());
            }
            crate::task_table::run_task(&task, &a.bin).with_context(|| task.target.clone())?;
        }
        Command::Collect(Collect::Transfer { common, out, cross_validation, records }) => {
            common.init()?;
            crate::collect::transfer(records, cross_validation, out)?;
        }
        Command::Collect(Collect::Variation { common, work, out, groups }) => {
            common.init()?;
            crate::collect::variation(work, groups, out)?;
        }
        Command::Step(a) => {
            a.common.init()?;
            let line = crate::step_line::StepLine { label: a.label.clone(), place: a.of };
            let status = crate::step_line::run(&line, &a.command[0], &a.command[1..], &a.common)?;
            if !status.success() {
                return Err(mesh_core::cli::AlreadyReported.into());
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::cli::unrecorded_options as missing;

    #[test]
    fn every_option_is_recorded_under_its_flag_name() {
        let cases: [&[&str]; 5] = [
            &["plan", "make", "--set", "s", "--pipeline-out", "o", "--out", "o/work/plan.mk"],
            &["plan", "slurm", "--set", "s", "--pipeline-out", "o", "--out", "o/slurm", "--workdir", "w"],
            &["plan", "run-task", "--table", "t.tasks", "--task", "3"],
            &["plan", "step", "--label", "align A/walk", "--of", "3/120", "--", "align", "-q"],
            &["plan", "collect", "transfer", "--out", "r.json", "a.json"],
        ];
        for argv in cases {
            assert_eq!(missing::<Params>(argv).unwrap(), Vec::<String>::new(), "{argv:?}");
        }
    }

    #[test]
    fn the_record_names_the_subcommand_beside_its_options() {
        let p = Params::try_parse_from(["plan", "make", "--set", "s", "--pipeline-out", "o", "--out", "f", "--variation-group", "g=walk"]).unwrap();
        let r = serde_json::to_value(&p).unwrap();
        assert_eq!(r["subcommand"], "make");
        assert_eq!(r["set"], "s");
        assert_eq!(r["variation_group"], serde_json::json!([["g", "walk"]]));
        assert_eq!(r["part_alignment"], "body", "a default, by its command-line name");
        assert_eq!(r["placement"], serde_json::Value::Null, "unset: the configuration's or the stage's");
        let p = Params::try_parse_from(["plan", "collect", "variation", "--work", "w", "--out", "v.json", "g"]).unwrap();
        let r = serde_json::to_value(&p).unwrap();
        assert_eq!((&r["subcommand"], &r["table"], &r["groups"]), (&"collect".into(), &"variation".into(), &serde_json::json!(["g"])));
    }
}

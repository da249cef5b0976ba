//! `plan`: the pipelines' task graph as a make fragment or Slurm job arrays.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = plan::stage::Args::parse();
    mesh_core::cli::run_stage("plan", || plan::stage::run(&args))
}

//! `plan`: the pipelines' task graph as a make fragment or Slurm job arrays.

use std::process::ExitCode;


fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<plan::stage::Args>();
    mesh_core::cli::run_stage("plan", || plan::stage::run(&args))
}

//! `plan`: see [`plan::stage`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<plan::stage::Params>();
    mesh_core::cli::run_stage("plan", || plan::stage::run(&p))
}

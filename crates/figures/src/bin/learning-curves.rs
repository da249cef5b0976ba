//! `learning-curves`: see [`figures::learning_curves`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<figures::learning_curves::Params>();
    mesh_core::cli::run_stage("learning-curves", || {
        p.common.init()?;
        figures::learning_curves::run(&p)
    })
}

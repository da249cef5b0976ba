//! `learning-curves`: see [`transfer::stage::learning_curves`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::learning_curves::Params>();
    mesh_core::cli::run_stage("learning-curves", || {
        p.common.init()?;
        transfer::stage::learning_curves::run(&p)
    })
}

//! `representation-error`: see [`transfer::stage::representation_error`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::representation_error::Params>();
    mesh_core::cli::run_stage("representation-error", || {
        p.common.init()?;
        transfer::stage::representation_error::run(&p)
    })
}

//! `inspect`: see [`mesh_core::stage::inspect`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<mesh_core::stage::inspect::Params>();
    mesh_core::cli::run_stage("inspect", || {
        p.common.init()?;
        mesh_core::stage::inspect::run(&p)
    })
}

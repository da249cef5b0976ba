//! `fuzz`: see [`fuzz::stage`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<fuzz::stage::Params>();
    mesh_core::cli::run_stage("fuzz", || {
        p.common.init()?;
        fuzz::stage::run(&p)
    })
}

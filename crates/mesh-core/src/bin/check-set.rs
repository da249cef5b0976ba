//! `check-set`: see [`mesh_core::stage::check_set`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<mesh_core::stage::check_set::Params>();
    mesh_core::cli::run_stage("check-set", || {
        p.common.init()?;
        mesh_core::stage::check_set::run(&p)
    })
}

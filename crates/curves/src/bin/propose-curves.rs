//! `propose-curves`: see [`curves::stage`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<curves::stage::Params>();
    mesh_core::cli::run_stage("propose-curves", || {
        p.common.init()?;
        curves::stage::run(&p)
    })
}

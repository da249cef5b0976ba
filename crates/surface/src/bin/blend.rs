//! `blend`: see [`surface::stage::blend`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<surface::stage::blend::Params>();
    mesh_core::cli::run_stage("blend", || {
        p.common.init()?;
        surface::stage::blend::run(&p)
    })
}

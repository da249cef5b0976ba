//! `surface-quality`: see [`transfer::stage::surface_quality`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::surface_quality::Params>();
    mesh_core::cli::run_stage("surface-quality", || {
        p.common.init()?;
        transfer::stage::surface_quality::run(&p)
    })
}

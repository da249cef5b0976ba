//! `dtw-densify`: see [`transfer::stage::dtw_densify`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::dtw_densify::Params>();
    mesh_core::cli::run_stage("dtw-densify", || {
        p.common.init()?;
        transfer::stage::dtw_densify::run(&p)
    })
}

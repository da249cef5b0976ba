//! `prealign`: see [`variation::stage::prealign`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<variation::stage::prealign::Params>();
    mesh_core::cli::run_stage("prealign", || {
        p.common.init()?;
        variation::stage::prealign::run(&p)
    })
}

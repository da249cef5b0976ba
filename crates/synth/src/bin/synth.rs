//! `synth`: see [`synth::stage`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<synth::stage::Params>();
    mesh_core::cli::run_stage("synth", || {
        p.common.init()?;
        synth::stage::run(&p)
    })
}

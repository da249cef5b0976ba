//! `render`: mesh sequences to PNG frames, a contact sheet and an animated GIF.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<render::stage::Args>();
    mesh_core::cli::run_stage("render", || {
        args.common.init()?;
        render::stage::run(&args)
    })
}

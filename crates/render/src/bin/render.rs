//! `render`: mesh sequences to PNG frames, a contact sheet and an animated GIF.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = render::stage::Args::parse();
    mesh_core::cli::run_stage("render", || {
        args.common.init()?;
        render::stage::run(&args)
    })
}

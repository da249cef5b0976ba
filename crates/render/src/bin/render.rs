//! `render`: see [`render::stage`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<render::stage::Params>();
    mesh_core::cli::run_stage("render", || {
        p.common.init()?;
        render::stage::run(&p)
    })
}

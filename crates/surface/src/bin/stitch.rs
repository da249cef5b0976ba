//! `stitch`: see [`surface::stage::stitch`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<surface::stage::stitch::Params>();
    mesh_core::cli::run_stage("stitch", || {
        p.common.init()?;
        surface::stage::stitch::run(&p)
    })
}

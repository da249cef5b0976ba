//! `align`: see [`capture::stage::align`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<capture::stage::align::Params>();
    mesh_core::cli::run_stage("align", || {
        p.common.init()?;
        capture::stage::align::run(&p)
    })
}

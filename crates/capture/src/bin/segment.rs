//! `segment`: see [`capture::stage::segment`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<capture::stage::segment::Params>();
    mesh_core::cli::run_stage("segment", || {
        p.common.init()?;
        capture::stage::segment::run(&p)
    })
}

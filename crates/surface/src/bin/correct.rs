//! `correct`: see [`surface::stage::correct`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<surface::stage::correct::Params>();
    mesh_core::cli::run_stage("correct", || {
        p.common.init()?;
        surface::stage::correct::run(&p)
    })
}

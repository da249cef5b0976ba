//! `mesh-export`: see [`export::stage::mesh_export`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<export::stage::mesh_export::Params>();
    mesh_core::cli::run_stage("mesh-export", || {
        p.common.init()?;
        export::stage::mesh_export::run(&p)
    })
}

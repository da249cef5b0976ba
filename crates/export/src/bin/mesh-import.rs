//! `mesh-import`: see [`export::stage::mesh_import`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<export::stage::mesh_import::Params>();
    mesh_core::cli::run_stage("mesh-import", || {
        p.common.init()?;
        export::stage::mesh_import::run(&p)
    })
}

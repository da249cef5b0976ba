//! `gpr-train`: see [`transfer::stage::gpr_train`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::gpr_train::Params>();
    mesh_core::cli::run_stage("gpr-train", || {
        p.common.init()?;
        transfer::stage::gpr_train::run(&p)
    })
}

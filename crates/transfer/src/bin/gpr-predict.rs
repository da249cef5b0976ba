//! `gpr-predict`: see [`transfer::stage::gpr_predict`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::gpr_predict::Params>();
    mesh_core::cli::run_stage("gpr-predict", || {
        p.common.init()?;
        transfer::stage::gpr_predict::run(&p)
    })
}

//! `gpdm-train`: see [`variation::stage::gpdm_train`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<variation::stage::gpdm_train::Params>();
    mesh_core::cli::run_stage("gpdm-train", || {
        p.common.init()?;
        variation::stage::gpdm_train::run(&p)
    })
}

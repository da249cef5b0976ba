//! `transfer-eval`: see [`transfer::stage::transfer_eval`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::transfer_eval::Params>();
    mesh_core::cli::run_stage("transfer-eval", || {
        p.common.init()?;
        transfer::stage::transfer_eval::run(&p)
    })
}

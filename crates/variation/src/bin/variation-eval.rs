//! `variation-eval`: see [`variation::stage::variation_eval`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<variation::stage::variation_eval::Params>();
    mesh_core::cli::run_stage("variation-eval", || {
        p.common.init()?;
        variation::stage::variation_eval::run(&p)
    })
}

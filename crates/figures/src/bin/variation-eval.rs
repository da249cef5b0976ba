//! `variation-eval`: see [`figures::variation_eval`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<figures::variation_eval::Params>();
    mesh_core::cli::run_stage("variation-eval", || {
        p.common.init()?;
        figures::variation_eval::run(&p)
    })
}

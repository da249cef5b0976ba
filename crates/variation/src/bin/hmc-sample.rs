//! `hmc-sample`: see [`variation::stage::hmc_sample`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<variation::stage::hmc_sample::Params>();
    mesh_core::cli::run_stage("hmc-sample", || {
        p.common.init()?;
        variation::stage::hmc_sample::run(&p)
    })
}

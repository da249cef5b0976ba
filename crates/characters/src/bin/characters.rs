//! `characters`: see [`characters::stage`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<characters::stage::Params>();
    mesh_core::cli::run_stage("characters", || {
        p.common.init()?;
        characters::stage::run(&p)
    })
}

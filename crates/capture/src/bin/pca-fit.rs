//! `pca-fit`: see [`capture::stage::pca_fit`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<capture::stage::pca_fit::Params>();
    mesh_core::cli::run_stage("pca-fit", || {
        p.common.init()?;
        capture::stage::pca_fit::run(&p)
    })
}

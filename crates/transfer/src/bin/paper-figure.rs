//! `paper-figure`: see [`transfer::stage::paper_figure`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<transfer::stage::paper_figure::Params>();
    mesh_core::cli::run_stage("paper-figure", || {
        p.common().init()?;
        transfer::stage::paper_figure::run(&p)
    })
}

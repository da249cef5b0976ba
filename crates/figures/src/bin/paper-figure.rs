//! `paper-figure`: see [`figures::paper_figure`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<figures::paper_figure::Params>();
    mesh_core::cli::run_stage("paper-figure", || {
        p.common().init()?;
        figures::paper_figure::run(&p)
    })
}

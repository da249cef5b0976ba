//! `html-report`: see [`export::stage::html_report`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<export::stage::html_report::Params>();
    mesh_core::cli::run_stage("html-report", || {
        p.common.init()?;
        export::stage::html_report::run(&p)
    })
}

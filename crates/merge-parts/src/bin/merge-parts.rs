//! `merge-parts`: see [`merge_parts`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let p = mesh_core::cli::parse::<merge_parts::Params>();
    mesh_core::cli::run_stage("merge-parts", || {
        p.common.init()?;
        merge_parts::run(&p)
    })
}

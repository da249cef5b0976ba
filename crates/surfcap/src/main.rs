//! `surfcap`: one entry point to every stage (see the library).
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<std::ffi::OsString> = std::env::args_os().skip(1).collect();
    match surfcap::run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => match e.downcast_ref::<surfcap::UsageError>() {
            Some(u) => {
                eprintln!("{u}");
                ExitCode::from(2)
            }
            None => {
                eprintln!("surfcap: {}", mesh_core::cli::error_line(&e));
                ExitCode::FAILURE
            }
        },
    }
}

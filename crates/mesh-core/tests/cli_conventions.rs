//! The shared command-line flags and the one-line error format.

use clap::Parser;
use mesh_core::cli::{error_line, progress_bar, CommonArgs};
use mesh_core::Error;

/// Test stage
#[derive(Parser, Debug)]
#[command(name = "stage", after_help = "e.g.: stage in.ply")]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    input: Option<String>,
}

fn parse(args: &[&str]) -> Result<Args, clap::Error> {
    Args::try_parse_from(std::iter::once("stage").chain(args.iter().copied()))
}

#[test]
fn common_flags_parse() {
    let a = parse(&[]).unwrap().common;
    assert_eq!(
        a,
        CommonArgs {
            verbose: 0,
            quiet: false,
            threads: None,
            seed: 0
        }
    );
    let a = parse(&["-vv", "--threads", "3", "--seed", "42", "x.ply"]).unwrap();
    assert_eq!(
        a.common,
        CommonArgs {
            verbose: 2,
            quiet: false,
            threads: Some(3),
            seed: 42
        }
    );
    assert_eq!(a.input.as_deref(), Some("x.ply"));
    assert!(parse(&["-q"]).unwrap().common.quiet);
}

#[test]
fn usage_errors_are_clap_errors_with_exit_code_2() {
    for bad in [
        &["-q", "-v"][..],
        &["--threads", "0"],
        &["--seed", "-1"],
        &["--bogus"],
        &["a", "b"],
    ] {
        let e = parse(bad).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{bad:?}: {e}");
    }
    let help = parse(&["--help"]).unwrap_err();
    assert_eq!(help.exit_code(), 0);
    assert!(help.to_string().contains("e.g.: stage in.ply"));
}

#[test]
fn error_chain_is_one_line_without_repetition() {
    // Error::Io embeds its source in its own message; the chain must not repeat it.
    let io = Error::io(
        "frames/000001.ply",
        std::io::Error::new(std::io::ErrorKind::NotFound, "No such file"),
    );
    let e = anyhow::Error::new(io);
    assert_eq!(error_line(&e), "frames/000001.ply: No such file");

    let inner = anyhow::anyhow!("vertex count 10\ndiffers from 12");
    let e = inner
        .context("frames/000002.ply")
        .context("loading sequence walk");
    assert_eq!(
        error_line(&e),
        "loading sequence walk: frames/000002.ply: vertex count 10 differs from 12"
    );
}

#[test]
fn progress_bar_is_hidden_when_quiet_or_not_a_terminal() {
    let quiet = CommonArgs {
        quiet: true,
        ..Default::default()
    };
    assert!(progress_bar(10, "x", &quiet).is_hidden());
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        assert!(progress_bar(10, "x", &CommonArgs::default()).is_hidden());
    }
}

#[test]
fn init_makes_blas_single_threaded() {
    CommonArgs {
        threads: Some(2),
        ..Default::default()
    }
    .init()
    .unwrap();
    assert_eq!(std::env::var("OPENBLAS_NUM_THREADS").unwrap(), "1");
    assert_eq!(rayon::current_num_threads(), 2);
    // faer sequential: its parallel kernels split reductions by thread count
    // (pca-fit's eigen-decomposition differed between --threads 1 and 2).
    assert!(matches!(faer::get_global_parallelism(), faer::Par::Seq));
    // The global pool can only be set once: a second request is an error, not a panic.
    assert!(CommonArgs {
        threads: Some(1),
        ..Default::default()
    }
    .init()
    .is_err());
}

#[test]
fn run_stage_maps_outcomes_to_exit_codes() {
    use mesh_core::cli::{run_stage, AlreadyReported};
    use std::process::ExitCode;
    assert_eq!(run_stage("t", || Ok(())), ExitCode::SUCCESS);
    assert_eq!(
        run_stage("t", || Err(anyhow::anyhow!("bad input"))),
        ExitCode::FAILURE
    );
    assert_eq!(
        run_stage("t", || Err(AlreadyReported.into())),
        ExitCode::FAILURE
    );
    assert_eq!(run_stage("t", || panic!("bug")), ExitCode::FAILURE);
    let _ = std::panic::take_hook();
}

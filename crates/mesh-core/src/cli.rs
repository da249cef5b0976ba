//! Command-line conventions shared by every stage binary.
//!
//! A stage is a thin `main` that parses its clap arguments, calls its library
//! and reports:
//!
//! ```ignore
//! use clap::Parser;
//! use mesh_core::cli::{run_stage, CommonArgs};
//!
//! /// Rigidly align every frame of a capture set (transfer paper §4).
//! #[derive(Parser)]
//! #[command(name = "align", version,
//!           after_help = "e.g.: align data/set --out work/set.aligned")]
//! struct Args {
//!     #[command(flatten)]
//!     common: CommonArgs,
//!     /// Capture-set folder
//!     set: std::path::PathBuf,
//! }
//!
//! fn main() -> std::process::ExitCode {
//!     let args = Args::parse();
//!     run_stage("align", || {
//!         args.common.init()?;
//!         align::run(&args.set, &args.common)
//!     })
//! }
//! ```
//!
//! Conventions:
//! - **Usage text**: the clap `about` (the struct's doc comment) is one line
//!   saying what the stage does; `after_help` holds an `e.g.:` line with a real
//!   invocation. `--help` and `--version` print to stdout and exit 0.
//! - **Common flags** ([`CommonArgs`]): `-v`/`--verbose` (repeatable), `-q`/`--quiet`,
//!   `--threads N`, `--seed S` (default 0). The same flag means the same thing
//!   in every stage.
//! - **Exit codes**: 0 success; 1 bad input or failure; 2 usage error (clap's
//!   own `parse()` exits 2 on unknown flags or missing arguments).
//! - **Errors**: exactly one line on stderr, `stage: file: problem` (the error
//!   chain joined by `": "`), via [`run_stage`]. A stage that carries on past a
//!   bad item prints it with [`report_error`] and returns [`AlreadyReported`]
//!   at the end, so nothing is printed twice. Panics (bugs) are also one line.
//! - **Quiet on success**: nothing on stdout unless stdout is the stage's
//!   product; progress bars ([`progress_bar`]) appear only when stderr is a
//!   terminal and without `-q`; [`info!`] messages only with `-v`,
//!   [`warn!`] messages unless `-q`.
//! - **Outputs and `--force`**: there is no `--force`. Stages always
//!   overwrite their outputs, atomically ([`crate::atomic`]), so an output
//!   either is complete or does not exist; deciding what is stale is the
//!   Makefile's job.
//! - **Threads**: rayon does the parallelism; BLAS is kept single-threaded
//!   (OpenBLAS threads fight rayon's).

use std::fmt;
use std::io::IsTerminal;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::OnceLock;

pub use indicatif::ProgressBar;
use indicatif::ProgressStyle;

use crate::artifact::Header;

/// Parses a stage's arguments (`A::parse()`: usage errors exit 2). The
/// hidden first argument `--surfcap-generate man|completions DIR` instead
/// writes the stage's man page or shell completions, generated from `A`'s
/// clap definition ([`crate::clap_docs`]), and exits (0, or 1 with one error line).
pub fn parse<A: clap::Parser>() -> A {
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args.get(1).is_some_and(|a| a == crate::clap_docs::GENERATE_FLAG) {
        let cmd = A::command();
        let name = cmd.get_name().to_string();
        let result = (|| -> anyhow::Result<()> {
            let [kind, dir] = &args[2..] else {
                anyhow::bail!("usage: {name} {} man|completions DIR", crate::clap_docs::GENERATE_FLAG);
            };
            let kind: crate::clap_docs::Kind = kind.to_string_lossy().parse()?;
            crate::clap_docs::write(cmd, kind, std::path::Path::new(dir))
        })();
        match result {
            Ok(()) => std::process::exit(0),
            Err(e) => {
                eprintln!("{name}: {}", error_line(&e));
                std::process::exit(1);
            }
        }
    }
    A::parse()
}

/// The default `--memory-budget` (MiB) of the stages that bound what they hold.
pub const DEFAULT_MEMORY_BUDGET_MIB: usize = 1024;

/// Flags every stage accepts; `#[command(flatten)]` it into the stage's args.
#[derive(clap::Args, Clone, Debug, Default, PartialEq, Eq)]
pub struct CommonArgs {
    /// More messages on stderr (repeat for more detail)
    #[arg(short, long, action = clap::ArgAction::Count)]
    pub verbose: u8,
    /// Only errors on stderr: no progress bars, no messages
    #[arg(short, long, conflicts_with = "verbose")]
    pub quiet: bool,
    /// Worker threads [default: one per core, or RAYON_NUM_THREADS]; BLAS always uses one thread
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,
    /// Random seed: the same inputs and seed give byte-identical outputs
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
}

static VERBOSITY: AtomicU8 = AtomicU8::new(0);
static QUIET: AtomicBool = AtomicBool::new(false);
/// Set by [`CommonArgs::init`]: library code draws progress only inside a stage.
static IN_STAGE: AtomicBool = AtomicBool::new(false);
static STAGE: OnceLock<String> = OnceLock::new();

/// `SURFCAP_VERBOSE=N` (0-255): the verbosity of `-v` repeated N times, over the command line's
/// `-v`/`-q`, so that a pipeline's jobs (whose command lines say `-q`) log in detail without
/// editing them; `None` when unset or not a number.
fn env_verbosity() -> Option<u8> {
    std::env::var("SURFCAP_VERBOSE").ok().and_then(|v| v.trim().parse().ok())
}

impl CommonArgs {
    /// Applies the flags to the process; call once, first thing in the stage
    /// (before any BLAS call or rayon use): records verbosity, sets up rayon's
    /// global pool with `--threads` workers, and makes BLAS single-threaded
    /// (`OPENBLAS_NUM_THREADS=1` for child processes, plus
    /// `openblas_set_num_threads(1)` if OpenBLAS is linked in, because OpenBLAS
    /// reads the variable when it is loaded, before `main`) and faer sequential.
    pub fn init(&self) -> anyhow::Result<()> {
        let (verbosity, quiet) = match env_verbosity() {
            Some(v) => (v, false),
            None => (if self.quiet { 0 } else { self.verbose }, self.quiet),
        };
        VERBOSITY.store(verbosity, Ordering::Relaxed);
        QUIET.store(quiet, Ordering::Relaxed);
        IN_STAGE.store(true, Ordering::Relaxed);
        std::env::set_var("OPENBLAS_NUM_THREADS", "1");
        blas_single_thread();
        // faer's own parallel kernels split reductions by thread count, so
        // results would differ in the last digits between `--threads 1` and
        // `2`; sequential faer keeps every output independent of the core
        // count (and is faster on 2 cores).
        faer::set_global_parallelism(faer::Par::Seq);
        if let Some(n) = self.threads {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n as usize)
                .build_global()
                .map_err(|e| anyhow::anyhow!("cannot start {n} worker threads: {e}"))?;
        }
        Ok(())
    }

    /// An artifact header for this run: producer, this process's command
    /// line and the seed. Add params and inputs with the `Header::with_*` methods.
    pub fn header(&self, stage: &str, version: &str) -> Header {
        Header::new(stage, version)
            .with_process_command_line()
            .with_seed(self.seed)
    }
}

/// The options of a stage's `Params` that its JSON record (what [`Header::with_params`] stores)
/// lacks, after parsing `argv` (the program name first): every argument but the
/// [`CommonArgs`] must appear under its long flag's name with `_` for `-` (a positional
/// under its own name), given or not; with subcommands, the chosen subcommand's arguments.
/// Empty when the record is complete. `Err` is clap's message for a bad `argv`.
pub fn unrecorded_options<P>(argv: &[&str]) -> Result<Vec<String>, String>
where
    P: clap::Parser + serde::Serialize,
{
    let params = P::try_parse_from(argv).map_err(|e| e.to_string())?;
    let record = serde_json::to_value(&params).map_err(|e| e.to_string())?;
    let mut cmd = P::command();
    let matches = cmd.try_get_matches_from_mut(argv).map_err(|e| e.to_string())?;
    let cmd = match matches.subcommand_name() {
        Some(name) => cmd.find_subcommand(name).cloned().unwrap_or(cmd),
        None => cmd,
    };
    let common = <CommonArgs as clap::Args>::augment_args(clap::Command::new("common"));
    let skip: Vec<&str> = common.get_arguments().map(|a| a.get_id().as_str()).chain(["help", "version"]).collect();
    Ok(cmd
        .get_arguments()
        .filter(|a| !skip.contains(&a.get_id().as_str()))
        .map(|a| a.get_long().map_or_else(|| a.get_id().to_string(), |l| l.replace('-', "_")))
        .filter(|key| record.get(key).is_none())
        .collect())
}

/// Calls `openblas_set_num_threads(1)` when the process has OpenBLAS loaded;
/// does nothing otherwise (looked up with `dlsym` so that stages without BLAS
/// do not have to link it).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn blas_single_thread() {
    use std::ffi::{c_char, c_int, c_void};
    extern "C" {
        fn dlsym(handle: *mut c_void, symbol: *const c_char) -> *mut c_void;
    }
    // RTLD_DEFAULT is the null handle on glibc.
    let sym = unsafe { dlsym(std::ptr::null_mut(), c"openblas_set_num_threads".as_ptr()) };
    if !sym.is_null() {
        // SAFETY: OpenBLAS declares `void openblas_set_num_threads(int)`.
        let set: extern "C" fn(c_int) = unsafe { std::mem::transmute(sym) };
        set(1);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn blas_single_thread() {}

/// Current verbosity (0 unless `-v` was given; always 0 with `-q`).
pub fn verbosity() -> u8 {
    VERBOSITY.load(Ordering::Relaxed)
}

/// Whether `-q` was given.
pub fn is_quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// Name of the running stage (set by [`run_stage`]), for message prefixes.
pub fn stage_name() -> &'static str {
    STAGE.get().map(String::as_str).unwrap_or("surfcap")
}

/// Prints `stage: message` on stderr when `-v` was given.
#[macro_export]
macro_rules! info {
    ($($arg:tt)*) => {
        if $crate::cli::verbosity() >= 1 {
            eprintln!(
                "{}: {}",
                $crate::cli::stage_name(),
                $crate::input::escape_control(&format!($($arg)*))
            );
        }
    };
}

/// Prints `stage: warning: message` on stderr unless `-q` was given.
#[macro_export]
macro_rules! warn {
    ($($arg:tt)*) => {
        if !$crate::cli::is_quiet() {
            eprintln!(
                "{}: warning: {}",
                $crate::cli::stage_name(),
                $crate::input::escape_control(&format!($($arg)*))
            );
        }
    };
}

/// Prints `stage: note: message` on stderr unless `-q` was given: something the
/// input lacks and what the stage or pipeline does instead.
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {
        if !$crate::cli::is_quiet() {
            eprintln!(
                "{}: note: {}",
                $crate::cli::stage_name(),
                $crate::input::escape_control(&format!($($arg)*))
            );
        }
    };
}

/// Error returned by a stage that has already printed its errors with
/// [`report_error`]: [`run_stage`] exits 1 without printing anything more.
#[derive(Debug)]
pub struct AlreadyReported;

impl fmt::Display for AlreadyReported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("errors reported above")
    }
}

impl std::error::Error for AlreadyReported {}

/// An error chain as one line: causes joined by `": "`, a cause skipped when
/// its text is already part of the message (as when a `Display` embeds its
/// `source`), line breaks replaced by spaces.
pub fn error_line(err: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if text.is_empty() || line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    let line = line.split_whitespace().collect::<Vec<_>>().join(" ");
    crate::input::escape_control(&line).into_owned()
}

/// Prints `stage: <error>` as one line on stderr (for stages that report a
/// bad item and carry on).
pub fn report_error(err: &anyhow::Error) {
    eprintln!("{}: {}", stage_name(), error_line(err));
}

/// Runs a stage's body: on error prints one line `stage: file: problem` on
/// stderr and returns exit code 1; on success returns 0. A panic is printed
/// as one line `stage: internal error: ...` and also gives 1.
pub fn run_stage(stage_name: &str, main: impl FnOnce() -> anyhow::Result<()>) -> ExitCode {
    let stage = STAGE.get_or_init(|| stage_name.to_string()).clone();
    let hook_stage = stage.clone();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".to_string());
        let place = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()));
        let msg = msg.split_whitespace().collect::<Vec<_>>().join(" ");
        let msg = crate::input::escape_control(&msg);
        eprintln!(
            "{hook_stage}: internal error: {msg}{}",
            place.unwrap_or_default()
        );
    }));
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(main)) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            if !e.is::<AlreadyReported>() {
                eprintln!("{stage}: {}", error_line(&e));
            }
            ExitCode::FAILURE
        }
        Err(_) => ExitCode::FAILURE,
    }
}

/// A progress bar on stderr for work of `len` steps, hidden when stderr is
/// not a terminal or with `-q` (so logs of batch jobs stay clean).
pub fn progress_bar(len: u64, message: &str, args: &CommonArgs) -> ProgressBar {
    if args.quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let style =
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})")
            .expect("valid progress template")
            .progress_chars("=> ");
    let bar = ProgressBar::new(len)
        .with_style(style)
        .with_message(message.to_string());
    register(&bar);
    bar
}

/// Whether progress may be drawn: inside a stage ([`CommonArgs::init`] was called), without
/// `-q`, and stderr is a terminal.
fn progress_wanted() -> bool {
    IN_STAGE.load(Ordering::Relaxed) && !is_quiet() && std::io::stderr().is_terminal()
}

/// Every visible bar or spinner made here, so that a library loop's bar inside a stage's
/// own bar stays hidden (two bars drawing on one terminal line garble each other).
static LIVE_BARS: std::sync::Mutex<Vec<indicatif::WeakProgressBar>> = std::sync::Mutex::new(Vec::new());

fn register(bar: &ProgressBar) {
    if let Ok(mut live) = LIVE_BARS.lock() {
        live.retain(|w| w.upgrade().is_some_and(|b| !b.is_finished()));
        live.push(bar.downgrade());
    }
}

/// Whether a bar or spinner made here is still drawing (not finished, not dropped).
fn bar_active() -> bool {
    LIVE_BARS
        .lock()
        .is_ok_and(|live| live.iter().any(|w| w.upgrade().is_some_and(|b| !b.is_finished())))
}

/// [`progress_bar`] for library loops, which have no [`CommonArgs`] at hand: drawn only in a
/// stage process after [`CommonArgs::init`], without `-q`, on a terminal, and while no other
/// bar is drawing (an inner loop of a stage that shows its own bar stays silent); hidden
/// otherwise, so library calls from tests or other programs print nothing. The message is
/// prefixed with the stage's name. `finish_and_clear` it when the loop ends.
pub fn stage_progress(len: u64, message: &str) -> ProgressBar {
    if !progress_wanted() || bar_active() {
        return ProgressBar::hidden();
    }
    progress_bar(len, &format!("{}: {message}", stage_name()), &CommonArgs::default())
}

/// A spinner with the elapsed time on stderr for work of unknown length (a
/// message that can carry counts), hidden like [`progress_bar`]. It ticks on
/// its own; `finish_and_clear` it when the work ends.
pub fn spinner(message: &str, args: &CommonArgs) -> ProgressBar {
    if args.quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template("{spinner} {msg} {elapsed}")
        .expect("valid spinner template");
    let bar = ProgressBar::new_spinner()
        .with_style(style)
        .with_message(message.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    register(&bar);
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(clap::Parser, serde::Serialize)]
    struct Params {
        #[command(flatten)]
        #[serde(skip)]
        common: CommonArgs,
        #[arg(long, default_value_t = 3)]
        max_iter: usize,
        #[arg(long)]
        #[serde(skip)]
        hidden: Option<String>,
        #[arg(long = "renamed-flag")]
        field: bool,
        input: String,
    }

    #[test]
    fn unrecorded_options_names_the_flags_missing_from_the_record() {
        let missing = unrecorded_options::<Params>(&["x", "in", "--seed", "4", "-v"]).unwrap();
        // `max_iter` and `input` are there (the default and the positional); `hidden` is
        // skipped and `--renamed-flag` recorded as `field`; the common flags are not asked for.
        assert_eq!(missing, ["hidden", "renamed_flag"]);
        assert!(unrecorded_options::<Params>(&["x"]).is_err(), "INPUT is required");
    }
}

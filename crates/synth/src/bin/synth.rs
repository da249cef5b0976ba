//! `synth`: build a capture set from real MakeHuman bodies driven by real mocap.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mesh_core::cli::{progress_bar, run_stage, CommonArgs};

/// Synthesise a capture set (two real bodies, real mocap, per-subject style, ground truth)
#[derive(Parser)]
#[command(
    name = "synth",
    version,
    after_help = "e.g.: synth --preset tiny --out out/tiny\n      synth --seed 7 --no-noise --out data/demo\n(needs scripts/fetch-assets first)"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Preset: `default` (demo set: full body 25 fps + notoes body 50 fps), `tiny` (coarse, for
    /// tests) or `holdout` (other bodies, styles, rates and test clips: the second benchmark)
    #[arg(long, value_enum, default_value_t = synth::preset::Preset::Default)]
    preset: synth::preset::Preset,
    /// No capture-like noise on the input sequences (truth is always clean)
    #[arg(long)]
    no_noise: bool,
    /// Output capture-set folder (replaced if it holds a capture set)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("synth", || {
        args.common.init()?;
        let cfg = synth::preset::preset(args.preset.name(), args.common.seed, !args.no_noise)
            .ok_or_else(|| anyhow::anyhow!("unknown preset {}", args.preset.name()))?;
        let pb = std::sync::OnceLock::new();
        let start = |n: usize| {
            let _ = pb.set(progress_bar(n as u64, "synth", &args.common));
        };
        let tick = || {
            if let Some(p) = pb.get() {
                p.inc(1)
            }
        };
        let s = synth::capture_set_writer::synthesise(&cfg, &args.out, false, &start, &tick)?;
        if let Some(p) = pb.get() {
            p.finish_and_clear();
        }
        mesh_core::info!(
            "wrote {} frames to {} (A {} vertices {:.2} m, B {} vertices {:.2} m)",
            s.frames,
            args.out.display(),
            s.vertices[0],
            s.heights[0],
            s.vertices[1],
            s.heights[1]
        );
        Ok(())
    })
}

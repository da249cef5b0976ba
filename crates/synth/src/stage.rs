//! The `synth` stage: a capture set from real MakeHuman bodies driven by real mocap.
//! `src/bin/synth.rs` only parses [`Params`] and calls [`run`]. The set records what made it
//! (preset, seed, noise, `--more-training`) in its `set.json`, not the command line.

use std::path::PathBuf;

use clap::Parser;
use mesh_core::cli::{progress_bar, CommonArgs};
use serde::Serialize;

use crate::preset::Preset;

/// Synthesise a capture set (two real bodies, real mocap, per-subject style, ground truth)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "synth",
    version,
    after_help = "e.g.: synth --preset tiny --out out/tiny\n      synth --seed 7 --no-noise --out data/demo\n(needs scripts/fetch-assets first)"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Preset: `default` (demo set: full body 25 fps + notoes body 50 fps), `tiny` (coarse, for
    /// tests), `holdout` (other bodies, styles, rates and test clips: the second benchmark),
    /// `outside` (a third such set, never tuned on) or `long` (two-minute training motions)
    #[arg(long, value_enum, default_value_t = Preset::Default)]
    pub preset: Preset,
    /// No capture-like noise on the input sequences (truth is always clean)
    #[arg(long)]
    pub no_noise: bool,
    /// Also train on the other benchmark sets' test clips from other performances than this
    /// preset's (not the CMU take it tests on): the training-coverage study
    #[arg(long)]
    pub more_training: bool,
    /// Output capture-set folder (replaced if it holds a capture set)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the capture set of the preset (seeded by `--seed`) to `--out`, with a progress bar
/// over its frames on a terminal.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let cfg = crate::preset::preset(p.preset.name(), p.common.seed, !p.no_noise)
        .ok_or_else(|| anyhow::anyhow!("unknown preset {}", p.preset.name()))?;
    let cfg = if p.more_training { crate::preset::with_more_training(cfg) } else { cfg };
    // The frame count is known once the mocap is read: the bar starts then.
    let pb = std::sync::OnceLock::new();
    let start = |n: usize| {
        let _ = pb.set(progress_bar(n as u64, "synth", &p.common));
    };
    let tick = || {
        if let Some(b) = pb.get() {
            b.inc(1)
        }
    };
    let s = crate::capture_set_writer::synthesise(&cfg, &p.out, false, &start, &tick)?;
    if let Some(b) = pb.get() {
        b.finish_and_clear();
    }
    mesh_core::info!(
        "wrote {} frames to {} (A {} vertices {:.2} m, B {} vertices {:.2} m)",
        s.frames,
        p.out.display(),
        s.vertices[0],
        s.heights[0],
        s.vertices[1],
        s.heights[1]
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_option_is_recorded_under_its_flag_name() {
        let argv = ["synth", "--preset", "tiny", "--out", "set"];
        assert_eq!(mesh_core::cli::unrecorded_options::<Params>(&argv).unwrap(), Vec::<String>::new());
        let r = serde_json::to_value(Params::try_parse_from(argv).unwrap()).unwrap();
        assert_eq!((&r["preset"], &r["no_noise"]), (&"tiny".into(), &false.into()), "by their command-line names");
    }
}

//! The `html-report` stage: the static HTML page of a pipeline run (OUT/index.html), playing the
//! 3D views at their sequences' own frame rate.

use std::path::PathBuf;

use clap::Parser;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::rate::{sequence_fps, RateSource, FALLBACK_FPS};
use crate::report::{write_report, ReportOptions};

/// Write OUT/index.html: 3D view, result tables, contact sheets, GIFs, plots and provenance of a pipeline run
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "html-report",
    version,
    after_help = "The page works from disk (file://), with no server and no network.\n\
                  e.g.: html-report --out out --view source=data/set/A/test/walk \\\n\
                  \x20      --view transfer=out/transfer/A-to-B/walk/gpr-nn --view truth=data/set/truth/B/walk"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Pipeline output folder to report on; index.html is written there
    #[arg(short, long)]
    pub out: PathBuf,
    /// A sequence for the 3D view, LABEL=FOLDER of numbered frames (repeat, shown side by side)
    #[arg(long, value_name = "LABEL=DIR", value_parser = parse_view)]
    pub view: Vec<(String, PathBuf)>,
    /// Page title
    #[arg(long, default_value = "surfcap report")]
    pub title: String,
    /// Frames per second of the sequences [default: the first view's rate.json or subject.json, else 30]
    #[arg(long, value_name = "F")]
    pub fps: Option<f64>,
    /// Frames kept at most per sequence in the 3D view (evenly subsampled)
    #[arg(long, default_value_t = 60, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_frames: u32,
    /// Megabytes of packed positions at most in the 3D view (fewer frames are kept beyond it)
    #[arg(long, default_value_t = 12, value_name = "MB", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_data_mb: u32,
    /// Folder of the npm package `three` [default: crates/export/web/node_modules/three]
    #[arg(long, value_name = "DIR")]
    pub three: Option<PathBuf>,
}

/// `LABEL=DIR` of `--view`.
fn parse_view(s: &str) -> Result<(String, PathBuf), String> {
    match s.split_once('=') {
        Some((label, dir)) if !label.is_empty() && !dir.is_empty() => Ok((label.to_string(), dir.into())),
        _ => Err(format!("expected LABEL=DIR, got '{s}'")),
    }
}

/// The rate the player runs at without `--fps`: the first view's recorded rate (a warning
/// names each view recorded at another); views without a recorded rate (a truth folder, an
/// old output) follow the others; `None` when no view records one.
fn views_fps(views: &[(String, PathBuf)]) -> anyhow::Result<Option<f64>> {
    let rates = views
        .iter()
        .map(|(label, dir)| Ok((label, sequence_fps(dir, None)?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let recorded: Vec<_> = rates.iter().filter(|(_, (_, from))| *from != RateSource::Fallback).collect();
    match recorded.first() {
        Some((_, (first, _))) => {
            for (label, (f, from)) in &recorded {
                if f != first {
                    mesh_core::warn!("view {label}: {f} fps ({from}), played at {first} fps");
                }
            }
            Ok(Some(*first))
        }
        None => {
            if !rates.is_empty() {
                mesh_core::warn!(
                    "no view records its frame rate (rate.json or subject.json): {FALLBACK_FPS} fps assumed, pass --fps"
                );
            }
            Ok(None)
        }
    }
}

/// Writes `--out`/index.html and its assets.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let fps = match p.fps {
        Some(f) => Some(f),
        None => views_fps(&p.view)?,
    };
    let page = write_report(&ReportOptions {
        out: p.out.clone(),
        views: p.view.clone(),
        title: p.title.clone(),
        fps: fps.unwrap_or(FALLBACK_FPS),
        max_frames: p.max_frames as usize,
        max_data_bytes: p.max_data_mb as usize * 1_000_000,
        three_dir: p.three.clone().unwrap_or_else(|| crate::viewer::DEFAULT_THREE_DIR.into()),
    })?;
    mesh_core::info!("wrote {}", page.display());
    Ok(())
}

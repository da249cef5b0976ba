//! `html-report`: the static HTML page of a pipeline run (OUT/index.html).
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use export::report::{write_report, ReportOptions};
use mesh_core::cli::{run_stage, CommonArgs};

/// Write OUT/index.html: 3D view, result tables, contact sheets, GIFs, plots and provenance of a pipeline run
#[derive(Parser)]
#[command(
    name = "html-report",
    version,
    after_help = "The page works from disk (file://), with no server and no network.\n\
                  e.g.: html-report --out out --view source=data/set/A/test/walk \\\n\
                  \x20      --view transfer=out/transfer/A-to-B/walk/gpr-nn --view truth=data/set/truth/B/walk"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Pipeline output folder to report on; index.html is written there
    #[arg(short, long)]
    out: PathBuf,
    /// A sequence for the 3D view, LABEL=FOLDER of numbered frames (repeat, shown side by side)
    #[arg(long, value_name = "LABEL=DIR", value_parser = parse_view)]
    view: Vec<(String, PathBuf)>,
    /// Page title
    #[arg(long, default_value = "surfcap report")]
    title: String,
    /// Frames per second of the sequences [default: the first view's rate.json or subject.json, else 30]
    #[arg(long, value_name = "F")]
    fps: Option<f64>,
    /// Frames kept at most per sequence in the 3D view (evenly subsampled)
    #[arg(long, default_value_t = 60, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    max_frames: u32,
    /// Megabytes of packed positions at most in the 3D view (fewer frames are kept beyond it)
    #[arg(long, default_value_t = 12, value_name = "MB", value_parser = clap::value_parser!(u32).range(1..))]
    max_data_mb: u32,
    /// Folder of the npm package `three` [default: crates/export/web/node_modules/three]
    #[arg(long, value_name = "DIR")]
    three: Option<PathBuf>,
}

fn parse_view(s: &str) -> Result<(String, PathBuf), String> {
    match s.split_once('=') {
        Some((label, dir)) if !label.is_empty() && !dir.is_empty() => {
            Ok((label.to_string(), dir.into()))
        }
        _ => Err(format!("expected LABEL=DIR, got '{s}'")),
    }
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("html-report", || {
        args.common.init()?;
        // The player runs at the views' own rate: the first view's, checked against the others.
        let mut fps = args.fps;
        if fps.is_none() {
            let rates = args
                .view
                .iter()
                .map(|(label, dir)| Ok((label, export::rate::sequence_fps(dir, None)?)))
                .collect::<anyhow::Result<Vec<_>>>()?;
            // Views without a recorded rate (a truth folder, an old output) follow the others.
            let recorded: Vec<_> =
                rates.iter().filter(|(_, (_, from))| *from != export::rate::RateSource::Fallback).collect();
            match recorded.first() {
                Some((_, (first, _))) => {
                    for (label, (f, from)) in &recorded {
                        if f != first {
                            mesh_core::warn!("view {label}: {f} fps ({from}), played at {first} fps");
                        }
                    }
                    fps = Some(*first);
                }
                None if !rates.is_empty() => mesh_core::warn!(
                    "no view records its frame rate (rate.json or subject.json): {} fps assumed, pass --fps",
                    export::rate::FALLBACK_FPS
                ),
                None => {}
            }
        }
        let page = write_report(&ReportOptions {
            out: args.out.clone(),
            views: args.view.clone(),
            title: args.title.clone(),
            fps: fps.unwrap_or(export::rate::FALLBACK_FPS),
            max_frames: args.max_frames as usize,
            max_data_bytes: args.max_data_mb as usize * 1_000_000,
            three_dir: args
                .three
                .clone()
                .unwrap_or_else(|| export::viewer::DEFAULT_THREE_DIR.into()),
        })?;
        mesh_core::info!("wrote {}", page.display());
        Ok(())
    })
}

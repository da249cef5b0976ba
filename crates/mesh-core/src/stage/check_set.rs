//! The `check-set` stage: validate a whole capture set, every problem one line.

use std::path::PathBuf;

use clap::Parser;
use serde::Serialize;

use crate::cli::{report_error, AlreadyReported, CommonArgs};

/// Validate a capture set (set.json, subjects, curves, motions, frames, key-poses) and list every problem, one line each
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "check-set",
    version,
    after_help = "Exit status 1 when there is any problem. What the set lacks that the pipelines can do\n\
                  without (curves, true correspondences, contacts, ground truth) is listed as notes, with\n\
                  what they do instead; -q leaves the notes out. docs/FORMATS.md describes the layout.\n\
                  e.g.: check-set out/demo/set\n\
                  e.g.: check-set -v fixtures/tiny-set     # also a summary of what was checked"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Capture-set folder (holding set.json)
    pub set: PathBuf,
}

/// Prints every problem of the set as one error line (and, with `-v`, a summary of what was
/// checked); fails, without a further message, when there is any.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let report = crate::set_check::check_set(&p.set);
    for problem in &report.problems {
        report_error(&anyhow::anyhow!("{problem}"));
    }
    for note in &report.notes {
        crate::note!("{note}");
    }
    crate::info!(
        "{}: {} subjects, {} motion folders, {} frames: {} problems",
        p.set.display(),
        report.subjects,
        report.motions,
        report.frames,
        report.problems.len()
    );
    if !report.problems.is_empty() {
        return Err(AlreadyReported.into());
    }
    Ok(())
}


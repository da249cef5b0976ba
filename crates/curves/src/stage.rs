//! The `propose-curves` stage: read, propose, check by segmenting, write (and draw, on request).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Parser;
use mesh_core::capture_set::SubjectSpec;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::limb_loops::{propose, with_curves, Settings};

/// Find the limbs' part curves on a template without annotation and write them into a copy of subject.json
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "propose-curves",
    version,
    after_help = "Check them by eye with --render: the template from the front, the side and the back, parts coloured, loops in black\n\
                  e.g.: propose-curves set/A/subject.json --template set/A/walk/000000.ply --out set/A/subject.json --render curves-A.png"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// The subject's subject.json (its curves and part tree may be missing)
    pub subject: PathBuf,
    /// The mesh the curves index into (the subject's template)
    #[arg(long)]
    pub template: PathBuf,
    /// Output subject.json (may be SUBJECT itself)
    #[arg(short, long)]
    pub out: PathBuf,
    /// Also draw the template with its loops and parts coloured (PNG), for checking them
    #[arg(long, value_name = "PNG")]
    pub render: Option<PathBuf>,
}

/// Runs [`propose_into`] with the stage's options.
pub fn run(p: &Params) -> Result<()> {
    propose_into(&p.subject, &p.template, &p.out, p.render.as_deref())
}

/// Proposes curves for `template`, writes `subject` with them to `out`, and with `render` a
/// PNG of the loops and parts there ([`crate::check_image`]).
pub fn propose_into(subject: &Path, template: &Path, out: &Path, render: Option<&Path>) -> Result<()> {
    let bytes = mesh_core::input::read_regular_file(subject)?;
    let value: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|e| anyhow::anyhow!("{}: invalid JSON: {e}", subject.display()))?;
    let up = match value.get("up").and_then(|u| u.as_str()).unwrap_or("+y") {
        u => SubjectSpec { fps: 1.0, units: "m".into(), up: u.into(), parts: Default::default(), curves: Default::default(), extra: Default::default() }
            .up_vector()
            .with_context(|| format!("{}: 'up' must be one of +x -x +y -y +z -z", subject.display()))?,
    };
    let mesh = mesh_core::io::read_mesh(template)?;
    let limbs = propose(&mesh, &up, &Settings::default()).with_context(|| template.display().to_string())?;
    let proposed = with_curves(value, &limbs).with_context(|| subject.display().to_string())?;
    let spec: SubjectSpec = serde_json::from_value(proposed.clone()).with_context(|| subject.display().to_string())?;
    let seg = mesh_core::segmentation::segment(&mesh, &spec)
        .with_context(|| format!("{}: the proposed curves do not cut the template into parts", template.display()))?;
    for l in &limbs {
        let n = seg.part(&l.part).map_or(0, |p| p.vertices.len());
        mesh_core::info!("{}: loops at {:.3} and {:.3} m from vertex {}, {n} vertices", l.part, l.levels[0], l.levels[1], l.extremity);
    }
    let mut text = serde_json::to_string_pretty(&proposed)?;
    text.push('\n');
    mesh_core::atomic::write_bytes_atomic(out, text.as_bytes())?;
    if let Some(png) = render {
        crate::check_image::write_check_image(&mesh, &spec, out, png)?;
    }
    Ok(())
}

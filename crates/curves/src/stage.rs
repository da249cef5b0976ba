//! The `propose-curves` stage: read, propose, check by segmenting, write (and draw, on request).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Parser;
use mesh_core::capture_set::SubjectSpec;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::limb_loops::{propose, with_curves, Limb, Settings};

/// Find the limbs' part curves on a template without annotation and write them into a copy of subject.json
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "propose-curves",
    version,
    after_help = "Check them by eye with --render: the template from the front, the side and the back, parts coloured, loops in black, extremities named; -v names the extremities chosen\n\
                  e.g.: propose-curves set/A/subject.json --template set/A/walk/000000.ply --out set/A/subject.json --render curves-A.png\n\
                  e.g.: propose-curves A.json --template sarge.obj --out A.json --extremity hand_r=211 --render curves.png"
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
    /// Also draw the template with its loops and parts coloured and the extremities named (PNG), for checking them; drawn also when no curves can be proposed
    #[arg(long, value_name = "PNG")]
    pub render: Option<PathBuf>,
    /// Take this vertex as an extremity instead of choosing it (repeat; NAME one of head, hand_l, hand_r, foot_l, foot_r)
    #[arg(long, value_name = "NAME=VERTEX", value_parser = crate::extremities::check_hint)]
    pub extremity: Vec<String>,
}

/// Runs [`propose_into`] with the stage's options.
pub fn run(p: &Params) -> Result<()> {
    propose_into(&p.subject, &p.template, &p.out, p.render.as_deref(), &p.extremity)
}

/// Proposes curves for `template` (taking the `extremity` hints, `NAME=VERTEX`), writes
/// `subject` with them to `out`, and with `render` a PNG of the loops, parts and extremities
/// there ([`crate::check_image`]); when no curves can be proposed the PNG still shows the
/// extremities chosen and whatever loops were found, and nothing is written to `out`.
pub fn propose_into(subject: &Path, template: &Path, out: &Path, render: Option<&Path>, extremity: &[String]) -> Result<()> {
    let bytes = mesh_core::input::read_regular_file(subject)?;
    let value: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|e| anyhow::anyhow!("{}: invalid JSON: {e}", subject.display()))?;
    let up = match value.get("up").and_then(|u| u.as_str()).unwrap_or("+y") {
        u => SubjectSpec { fps: 1.0, units: "m".into(), up: u.into(), parts: Default::default(), curves: Default::default(), extra: Default::default() }
            .up_vector()
            .with_context(|| format!("{}: 'up' must be one of +x -x +y -y +z -z", subject.display()))?,
    };
    let mesh = mesh_core::io::read_mesh(template)?;
    let hints = crate::extremities::parse_hints(extremity, mesh.vertices.len())?;
    let proposal = propose(&mesh, &up, &Settings::default(), &hints);
    let extremities = proposal.extremities.clone();
    // The picture of a failure: the extremities and the loops found, on the subject as it is.
    let draw_failure = |limbs: &[Limb]| -> Result<()> {
        if let Some(png) = render {
            let partial = with_curves(value.clone(), limbs).unwrap_or_else(|_| value.clone());
            let up_name = value.get("up").and_then(|u| u.as_str()).unwrap_or("+y");
            let spec: SubjectSpec = serde_json::from_value(partial).unwrap_or(SubjectSpec {
                fps: 1.0, units: "m".into(), up: up_name.into(), parts: Default::default(), curves: Default::default(), extra: Default::default(),
            });
            crate::check_image::write_check_image(&mesh, &spec, extremities.as_ref(), subject, png)?;
        }
        Ok(())
    };
    let limbs = match proposal.error {
        None => proposal.limbs,
        Some(e) => {
            draw_failure(&proposal.limbs)?;
            return Err(e.context(template.display().to_string()));
        }
    };
    let proposed = with_curves(value.clone(), &limbs).with_context(|| subject.display().to_string())?;
    let spec: SubjectSpec = serde_json::from_value(proposed.clone()).with_context(|| subject.display().to_string())?;
    let seg = match mesh_core::segmentation::segment(&mesh, &spec) {
        Ok(seg) => seg,
        Err(e) => {
            draw_failure(&limbs)?;
            let named = extremities.as_ref().map(|x| x.describe(&mesh)).unwrap_or_default();
            bail!("{}: the proposed curves do not cut the template into parts: {e} (extremities {named}; give them with --extremity NAME=VERTEX)", template.display());
        }
    };
    for l in &limbs {
        let n = seg.part(&l.part).map_or(0, |p| p.vertices.len());
        mesh_core::info!("{}: loops at {:.3} and {:.3} from vertex {}, {n} vertices", l.part, l.levels[0], l.levels[1], l.extremity);
    }
    let mut text = serde_json::to_string_pretty(&proposed)?;
    text.push('\n');
    mesh_core::atomic::write_bytes_atomic(out, text.as_bytes())?;
    if let Some(png) = render {
        crate::check_image::write_check_image(&mesh, &spec, extremities.as_ref(), out, png)?;
    }
    Ok(())
}

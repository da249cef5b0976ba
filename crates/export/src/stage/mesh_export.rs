//! The `mesh-export` stage: a mesh sequence folder written for other tools: OBJ/PLY per frame,
//! template OBJ + PC2 point cache, animated glTF (.glb) or USD (.usda); the format follows `--out`.

use std::path::PathBuf;

use clap::Parser;
use mesh_core::cli::CommonArgs;
use mesh_core::sequence::MeshSequence;
use serde::Serialize;

use crate::glb::{GlbOptions, Interpolation};
use crate::usd::{UpAxis, UsdOptions};

/// Write a mesh sequence for other tools: OBJ/PLY per frame, template OBJ + PC2 point cache, animated glTF (.glb) or USD (.usda)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "mesh-export",
    version,
    after_help = "The format follows OUT: a .glb file, a .usda file, a .pc2 file (plus the template OBJ\n\
                  beside it, same stem), or a folder of numbered frames (--frame-format obj|ply).\n\
                  e.g.: mesh-export out/transfer/A-to-B/walk/gpr-nn --out walk.glb --stride 2\n\
                  e.g.: mesh-export out/transfer/A-to-B/walk/gpr-nn --out walk.pc2   # writes walk.obj + walk.pc2\n\
                  e.g.: mesh-export out/transfer/A-to-B/walk/gpr-nn --out walk.usda  # time-sampled points"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Folder of numbered frames (000000.ply, ... or .obj)
    pub input: PathBuf,
    /// Output: NAME.glb, NAME.usda, NAME.pc2, or a folder
    #[arg(short, long)]
    pub out: PathBuf,
    /// Frame files' format when OUT is a folder
    #[arg(long, value_enum, default_value_t = crate::frames::FrameFormat::Obj)]
    pub frame_format: crate::frames::FrameFormat,
    /// glb, usda: keep every N-th frame
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub stride: u32,
    /// glb, usda: frames per second [default: the folder's rate.json, else its capture's subject.json, else 30]
    #[arg(long, value_name = "F")]
    pub fps: Option<f64>,
    /// glb: blend linearly between frames instead of stepping
    #[arg(long)]
    pub linear: bool,
    /// glb: int16 positions and morph deltas (KHR_mesh_quantization; about half the size)
    #[arg(long)]
    pub quantize: bool,
}

/// Writes OUT in the format its name asks for.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let seq = MeshSequence::load_dir(&p.input)?;
    let ext = p
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("glb") => {
            let fps = sequence_rate(p)?;
            let opts = GlbOptions {
                stride: p.stride as usize,
                fps,
                interpolation: if p.linear {
                    Interpolation::Linear
                } else {
                    Interpolation::Step
                },
                quantize: p.quantize,
            };
            crate::glb::write_glb(&p.out, &seq, &opts)?;
        }
        Some("usda") => {
            let fps = sequence_rate(p)?;
            let (up_axis, meters_per_unit) = usd_axes(&p.input)?;
            let opts = UsdOptions { stride: p.stride as usize, fps, up_axis, meters_per_unit };
            crate::usd::write_usda(&p.out, &seq, &opts)?;
        }
        Some("pc2") => {
            mesh_core::io::pc2::write_obj_pc2(&p.out.with_extension("obj"), &p.out, &seq)?
        }
        Some(other) if !p.out.is_dir() => anyhow::bail!(
            "{}: unknown output format '.{other}' (expected NAME.glb, NAME.usda, NAME.pc2 or a folder)",
            p.out.display()
        ),
        _ => crate::frames::write_frames(&p.out, &seq, p.frame_format)?,
    }
    mesh_core::info!("wrote {} frames to {}", seq.n_frames(), p.out.display());
    Ok(())
}

/// The sequence's frame rate (`--fps`, its rate file, its capture's `subject.json`, else 30 with
/// a warning), stated with `-v`.
fn sequence_rate(p: &Params) -> anyhow::Result<f64> {
    let (fps, from) = crate::rate::sequence_fps(&p.input, p.fps)?;
    if from == crate::rate::RateSource::Fallback {
        mesh_core::warn!(
            "{}: no frame rate recorded (rate.json or subject.json): {fps} fps assumed, pass --fps",
            p.input.display()
        );
    } else {
        mesh_core::info!("{fps} fps ({from})");
    }
    Ok(fps)
}

/// USD's `upAxis` and `metersPerUnit` of the sequence folder `dir`: from its capture's
/// `subject.json` (`up` `+y` or `+z`, `units` `m`, `cm` or `mm`), else +Y up in metres.
fn usd_axes(dir: &std::path::Path) -> anyhow::Result<(UpAxis, f64)> {
    let Some((path, spec)) = crate::rate::sequence_subject(dir)? else {
        return Ok((UpAxis::Y, 1.0));
    };
    let up = match spec.up.as_str() {
        "+y" => UpAxis::Y,
        "+z" => UpAxis::Z,
        other => anyhow::bail!("{}: up '{other}' has no USD up axis (USD knows +y and +z)", path.display()),
    };
    let meters = match spec.units.as_str() {
        "m" => 1.0,
        "cm" => 0.01,
        "mm" => 0.001,
        other => anyhow::bail!("{}: units '{other}' unknown to the USD export (m, cm or mm)", path.display()),
    };
    Ok((up, meters))
}

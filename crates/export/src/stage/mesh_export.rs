//! The `mesh-export` stage: a mesh sequence folder written for other tools: OBJ/PLY per frame,
//! template OBJ + PC2 point cache, or animated glTF (.glb); the format follows `--out`.

use std::path::PathBuf;

use clap::Parser;
use mesh_core::cli::CommonArgs;
use mesh_core::sequence::MeshSequence;
use serde::Serialize;

use crate::glb::{GlbOptions, Interpolation};

/// Write a mesh sequence for other tools: OBJ/PLY per frame, template OBJ + PC2 point cache, or animated glTF (.glb)
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "mesh-export",
    version,
    after_help = "The format follows OUT: a .glb file, a .pc2 file (plus the template OBJ beside it,\n\
                  same stem), or a folder of numbered frames (--frame-format obj|ply).\n\
                  e.g.: mesh-export out/transfer/A-to-B/walk/gpr-nn --out walk.glb --stride 2\n\
                  e.g.: mesh-export out/transfer/A-to-B/walk/gpr-nn --out walk.pc2   # writes walk.obj + walk.pc2"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Folder of numbered frames (000000.ply, ... or .obj)
    pub input: PathBuf,
    /// Output: NAME.glb, NAME.pc2, or a folder
    #[arg(short, long)]
    pub out: PathBuf,
    /// Frame files' format when OUT is a folder
    #[arg(long, value_enum, default_value_t = crate::frames::FrameFormat::Obj)]
    pub frame_format: crate::frames::FrameFormat,
    /// glb: keep every N-th frame
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub stride: u32,
    /// glb: frames per second [default: the folder's rate.json, else its capture's subject.json, else 30]
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
            let (fps, from) = crate::rate::sequence_fps(&p.input, p.fps)?;
            if from == crate::rate::RateSource::Fallback {
                mesh_core::warn!(
                    "{}: no frame rate recorded (rate.json or subject.json): {fps} fps assumed, pass --fps",
                    p.input.display()
                );
            } else {
                mesh_core::info!("{fps} fps ({from})");
            }
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
        Some("pc2") => {
            crate::pc2::write_obj_pc2(&p.out.with_extension("obj"), &p.out, &seq)?
        }
        Some(other) if !p.out.is_dir() => anyhow::bail!(
            "{}: unknown output format '.{other}' (expected NAME.glb, NAME.pc2 or a folder)",
            p.out.display()
        ),
        _ => crate::frames::write_frames(&p.out, &seq, p.frame_format)?,
    }
    mesh_core::info!("wrote {} frames to {}", seq.n_frames(), p.out.display());
    Ok(())
}

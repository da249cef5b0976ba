//! `mesh-export`: a mesh sequence folder to OBJ/PLY frames, OBJ + PC2, or glTF .glb.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use export::glb::{GlbOptions, Interpolation};
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::sequence::MeshSequence;

/// Write a mesh sequence for other tools: OBJ/PLY per frame, template OBJ + PC2 point cache, or animated glTF (.glb)
#[derive(Parser)]
#[command(
    name = "mesh-export",
    version,
    after_help = "The format follows OUT: a .glb file, a .pc2 file (plus the template OBJ beside it,\n\
                  same stem), or a folder of numbered frames (--frame-format obj|ply).\n\
                  e.g.: mesh-export out/transfer/A-to-B/walk/gpr-nn --out walk.glb --stride 2\n\
                  e.g.: mesh-export out/transfer/A-to-B/walk/gpr-nn --out walk.pc2   # writes walk.obj + walk.pc2"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Folder of numbered frames (000000.ply, ... or .obj)
    input: PathBuf,
    /// Output: NAME.glb, NAME.pc2, or a folder
    #[arg(short, long)]
    out: PathBuf,
    /// Frame files' format when OUT is a folder
    #[arg(long, value_enum, default_value_t = export::frames::FrameFormat::Obj)]
    frame_format: export::frames::FrameFormat,
    /// glb: keep every N-th frame
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    stride: u32,
    /// glb: frames per second [default: the folder's rate.json, else its capture's subject.json, else 30]
    #[arg(long, value_name = "F")]
    fps: Option<f64>,
    /// glb: blend linearly between frames instead of stepping
    #[arg(long)]
    linear: bool,
    /// glb: int16 positions and morph deltas (KHR_mesh_quantization; about half the size)
    #[arg(long)]
    quantize: bool,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("mesh-export", || {
        args.common.init()?;
        let seq = MeshSequence::load_dir(&args.input)?;
        let ext = args
            .out
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("glb") => {
                let (fps, from) = export::rate::sequence_fps(&args.input, args.fps)?;
                if from == export::rate::RateSource::Fallback {
                    mesh_core::warn!(
                        "{}: no frame rate recorded (rate.json or subject.json): {fps} fps assumed, pass --fps",
                        args.input.display()
                    );
                } else {
                    mesh_core::info!("{fps} fps ({from})");
                }
                let opts = GlbOptions {
                    stride: args.stride as usize,
                    fps,
                    interpolation: if args.linear {
                        Interpolation::Linear
                    } else {
                        Interpolation::Step
                    },
                    quantize: args.quantize,
                };
                export::glb::write_glb(&args.out, &seq, &opts)?;
            }
            Some("pc2") => {
                export::pc2::write_obj_pc2(&args.out.with_extension("obj"), &args.out, &seq)?
            }
            Some(other) if !args.out.is_dir() => anyhow::bail!(
                "{}: unknown output format '.{other}' (expected NAME.glb, NAME.pc2 or a folder)",
                args.out.display()
            ),
            _ => export::frames::write_frames(&args.out, &seq, args.frame_format)?,
        }
        mesh_core::info!("wrote {} frames to {}", seq.n_frames(), args.out.display());
        Ok(())
    })
}

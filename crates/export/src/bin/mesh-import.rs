//! `mesh-import`: OBJ/PLY frames or a template + PC2 point cache to a surfcap sequence folder.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mesh_core::cli::{run_stage, CommonArgs};

/// Read a mesh sequence made by other tools (PC2 point cache + template, or OBJ/PLY frames) into a folder of PLY frames
#[derive(Parser)]
#[command(
    name = "mesh-import",
    version,
    after_help = "e.g.: mesh-import walk.pc2 --out work/walk            # template: walk.obj beside it\n\
                  e.g.: mesh-import walk.pc2 --out work/walk --template body.ply\n\
                  e.g.: mesh-import blender-export/ --out work/walk   # frames detected: 000000.obj, frame_0001.ply, punch0.obj, ...\n\
                  e.g.: mesh-import --pattern 'walk.%04d.obj' shots/ --out work/walk"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// A .pc2 file or a folder of numbered OBJ/PLY frames
    input: PathBuf,
    /// Output folder of numbered PLY frames
    #[arg(short, long)]
    out: PathBuf,
    /// Mesh holding the faces for a .pc2 input [default: INPUT with .obj]
    #[arg(long)]
    template: Option<PathBuf>,
    /// Frame file names in a folder INPUT, as a printf pattern (`walk.%04d.obj`, `punch%d.obj`)
    /// [default: detected; the reading is stated on stderr]
    #[arg(long)]
    pattern: Option<mesh_core::frame_pattern::FramePattern>,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("mesh-import", || {
        args.common.init()?;
        let is_pc2 = args
            .input
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("pc2"));
        let seq = if is_pc2 {
            let template = args
                .template
                .clone()
                .unwrap_or_else(|| args.input.with_extension("obj"));
            export::pc2::read_obj_pc2(&template, &args.input)?
        } else if args.input.is_file() {
            anyhow::bail!(
                "{}: cannot import this file (import reads a .pc2 point cache or a folder of numbered OBJ/PLY frames)",
                args.input.display()
            )
        } else {
            export::frames::read_frames(&args.input, args.pattern.as_ref())?
        };
        seq.write_dir(&args.out)?;
        mesh_core::info!("wrote {} frames to {}", seq.n_frames(), args.out.display());
        Ok(())
    })
}

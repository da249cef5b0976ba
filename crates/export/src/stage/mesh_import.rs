//! The `mesh-import` stage: a mesh sequence made by other tools (a PC2 point cache and its
//! template, or numbered OBJ/PLY frames) read into a folder of PLY frames.

use std::path::PathBuf;

use clap::Parser;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

/// Read a mesh sequence made by other tools (PC2 point cache + template, or OBJ/PLY frames) into a folder of PLY frames
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "mesh-import",
    version,
    after_help = "e.g.: mesh-import walk.pc2 --out work/walk            # template: walk.obj beside it\n\
                  e.g.: mesh-import walk.pc2 --out work/walk --template body.ply\n\
                  e.g.: mesh-import blender-export/ --out work/walk   # frames detected: 000000.obj, frame_0001.ply, punch0.obj, ...\n\
                  e.g.: mesh-import --pattern 'walk.%04d.obj' shots/ --out work/walk"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// A .pc2 file or a folder of numbered OBJ/PLY frames
    pub input: PathBuf,
    /// Output folder of numbered PLY frames
    #[arg(short, long)]
    pub out: PathBuf,
    /// Mesh holding the faces for a .pc2 input [default: INPUT with .obj]
    #[arg(long)]
    pub template: Option<PathBuf>,
    /// Frame file names in a folder INPUT, as a printf pattern (`walk.%04d.obj`, `punch%d.obj`)
    /// [default: detected; the reading is stated on stderr]
    #[arg(long)]
    #[serde(serialize_with = "pattern_as_text")]
    pub pattern: Option<mesh_core::frame_pattern::FramePattern>,
}

/// `--pattern` as written on the command line, or `null`.
fn pattern_as_text<S: serde::Serializer>(
    pattern: &Option<mesh_core::frame_pattern::FramePattern>,
    ser: S,
) -> Result<S::Ok, S::Error> {
    match pattern {
        Some(p) => ser.serialize_str(&p.to_string()),
        None => ser.serialize_none(),
    }
}

/// Writes the folder of PLY frames.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let is_pc2 = p
        .input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pc2"));
    let seq = if is_pc2 {
        let template = p
            .template
            .clone()
            .unwrap_or_else(|| p.input.with_extension("obj"));
        mesh_core::io::pc2::read_obj_pc2(&template, &p.input)?
    } else if p.input.is_file() {
        anyhow::bail!(
            "{}: cannot import this file (import reads a .pc2 point cache or a folder of numbered OBJ/PLY frames)",
            p.input.display()
        )
    } else {
        crate::frames::read_frames(&p.input, p.pattern.as_ref())?
    };
    seq.write_dir(&p.out)?;
    mesh_core::info!("wrote {} frames to {}", seq.n_frames(), p.out.display());
    Ok(())
}

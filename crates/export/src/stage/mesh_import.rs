//! The `mesh-import` stage: a mesh sequence made by other tools (a PC2 point cache and its
//! template, an Alembic mesh cache, or numbered OBJ/PLY frames) read into a folder of PLY frames.

use std::path::PathBuf;

use clap::Parser;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

/// Read a mesh sequence made by other tools (PC2 point cache + template, Alembic .abc, or OBJ/PLY frames) into a folder of PLY frames
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "mesh-import",
    version,
    after_help = "e.g.: mesh-import walk.pc2 --out work/walk            # template: walk.obj beside it\n\
                  e.g.: mesh-import walk.pc2 --out work/walk --template body.ply\n\
                  e.g.: mesh-import walk.abc --out work/walk            # the first PolyMesh; its rate in rate.json\n\
                  e.g.: mesh-import shot.abc --object bodyShape --out work/walk\n\
                  e.g.: mesh-import blender-export/ --out work/walk   # frames detected: 000000.obj, frame_0001.ply, punch0.obj, ...\n\
                  e.g.: mesh-import --pattern 'walk.%04d.obj' shots/ --out work/walk"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// A .pc2 file, an Alembic .abc file or a folder of numbered OBJ/PLY frames
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
    /// The PolyMesh to read from an .abc INPUT: its name (`bodyShape`) or path (`/body/bodyShape`),
    /// or an object above it (`body`: its first PolyMesh) [default: the first]
    #[arg(long)]
    pub object: Option<String>,
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
    let has_ext = |ext: &str| p.input.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext));
    if p.object.is_some() && !has_ext("abc") {
        anyhow::bail!("--object picks a PolyMesh of an .abc input; {} is not one", p.input.display());
    }
    if has_ext("abc") {
        let mesh = mesh_core::io::alembic::read_alembic(&p.input, p.object.as_deref())?;
        mesh_core::info!(
            "{}: PolyMesh {}: {} frames of {} vertices, {} triangles, {} fps (first sample at {} s)",
            p.input.display(),
            mesh_core::input::escape_control(&mesh.path),
            mesh.sequence.n_frames(),
            mesh.sequence.n_vertices(),
            mesh.sequence.n_faces(),
            mesh.fps,
            mesh.start_time
        );
        mesh.sequence.write_dir_at(&p.out, Some(mesh.fps))?;
        mesh_core::info!("wrote {} frames to {}", mesh.sequence.n_frames(), p.out.display());
        return Ok(());
    }
    let seq = if is_pc2 {
        let template = p
            .template
            .clone()
            .unwrap_or_else(|| p.input.with_extension("obj"));
        mesh_core::io::pc2::read_obj_pc2(&template, &p.input)?
    } else if p.input.is_file() {
        anyhow::bail!(
            "{}: cannot import this file (import reads a .pc2 point cache, an Alembic .abc file or a folder of numbered OBJ/PLY frames)",
            p.input.display()
        )
    } else {
        crate::frames::read_frames(&p.input, p.pattern.as_ref())?
    };
    seq.write_dir(&p.out)?;
    mesh_core::info!("wrote {} frames to {}", seq.n_frames(), p.out.display());
    Ok(())
}

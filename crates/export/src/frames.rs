//! A mesh sequence as one mesh file per frame: `000000.obj`, `000001.obj`, ...
//! (or `.ply`), the layout every stage reads with
//! [`MeshSequence::load_dir`]. OBJ coordinates are printed to round-trip
//! exactly; PLY is binary little-endian double.

use std::path::Path;
use std::str::FromStr;

use mesh_core::io::write_obj;
use mesh_core::sequence::{write_frames_atomic, MeshSequence};
use mesh_core::Result;

/// Which mesh format the frame files use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum FrameFormat {
    Obj,
    Ply,
}

impl FromStr for FrameFormat {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "obj" => Ok(FrameFormat::Obj),
            "ply" => Ok(FrameFormat::Ply),
            _ => Err(format!("unknown frame format '{s}' (expected obj or ply)")),
        }
    }
}

/// Writes every frame of `seq` into `dir`, replacing the folder atomically
/// ([`write_frames_atomic`]), so that `load_dir(dir)` reads back exactly `seq`.
pub fn write_frames(dir: &Path, seq: &MeshSequence, format: FrameFormat) -> Result<()> {
    match format {
        FrameFormat::Ply => seq.write_dir(dir),
        FrameFormat::Obj => write_frames_atomic(dir, seq.n_frames(), "obj", |i, p| {
            write_obj(p, &seq.frame_mesh(i))
        }),
    }
}

/// Reads a folder of numbered OBJ or PLY frames: the files `pattern` names
/// (`walk.%04d.obj`), or without one the sequence detected in the folder
/// (see [`mesh_core::sequence::frame_files`]).
pub fn read_frames(dir: &Path, pattern: Option<&mesh_core::frame_pattern::FramePattern>) -> Result<MeshSequence> {
    match pattern {
        Some(p) => MeshSequence::load_files(&mesh_core::sequence::frame_files_matching(dir, p)?),
        None => MeshSequence::load_dir(dir),
    }
}

//! A mesh sequence as one mesh file per frame: `000000.obj`, `000001.obj`, ...
//! (or `.ply`), the layout every stage reads with
//! [`MeshSequence::load_dir`]. OBJ coordinates are printed to round-trip
//! exactly; PLY is binary little-endian double.

use std::path::{Path, PathBuf};
use std::str::FromStr;

use mesh_core::io::{write_obj, MeshFormat};
use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};

/// Which mesh format the frame files use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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

/// Writes every frame of `seq` into `dir` (created if needed), each file
/// atomically, then removes frame files left by an earlier, longer sequence
/// or in the other format, so that `load_dir(dir)` reads back exactly `seq`.
pub fn write_frames(dir: &Path, seq: &MeshSequence, format: FrameFormat) -> Result<()> {
    if format == FrameFormat::Ply {
        return seq.write_dir(dir);
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let names: Vec<PathBuf> = (0..seq.n_frames())
        .map(|i| dir.join(format!("{i:06}.obj")))
        .collect();
    for (i, p) in names.iter().enumerate() {
        write_obj(p, &seq.frame_mesh(i))?;
    }
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        let numbered = path
            .file_stem()
            .and_then(|s| s.to_str())
            .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
        if numbered && MeshFormat::from_path(&path).is_some() && !names.contains(&path) {
            std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
        }
    }
    Ok(())
}

/// Reads a folder of numbered OBJ or PLY frames (see [`MeshSequence::load_dir`]).
pub fn read_frames(dir: &Path) -> Result<MeshSequence> {
    MeshSequence::load_dir(dir)
}

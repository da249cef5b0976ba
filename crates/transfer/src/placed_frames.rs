//! The placed frames of a transfer, kept until its feet clean-up is solved. The clean-up is a
//! solve over the whole motion (a frame's shift and leg drops depend on every frame's feet,
//! [`crate::feet`]), so a frame cannot be written when it is made. Instead each block of placed
//! frames is kept, with what the clean-up reads of it ([`FeetRecord`]); once the moves are
//! solved, the frames are handed on one at a time, moved ([`FeetMoves::apply`]), e.g. to the PLY
//! folder writer. The frames are held in memory up to a budget and beyond it in a scratch file
//! beside the output, so a transfer of any length holds at most the budget and one block of
//! frames in memory. On disk the coordinates are their `f64` bytes: the frames read back are
//! the frames made, to the bit.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use mesh_core::{Error, Result};
use nalgebra::Vector3;
use tempfile::NamedTempFile;

use crate::feet::{FeetMoves, FeetRecord, TargetFeet};

/// A transfer's placed frames (module doc).
pub struct PlacedFrames {
    /// The output the frames are for: errors name it, never the scratch file.
    output: PathBuf,
    /// Bytes of coordinates held in memory before the frames go to disk.
    budget: usize,
    /// The coordinates while they fit the budget.
    memory: Vec<f64>,
    /// The scratch file once they do not.
    file: Option<BufWriter<NamedTempFile>>,
    n_vertices: usize,
    n_frames: usize,
    feet: FeetRecord,
    moves: FeetMoves,
}

impl PlacedFrames {
    /// Frames of `n_vertices` vertices for `output`, held in memory up to `budget` bytes of
    /// coordinates, beyond it in a scratch file in the output's folder
    /// ([`mesh_core::atomic::scratch_file`]).
    pub fn new(output: &Path, n_vertices: usize, budget: usize) -> PlacedFrames {
        PlacedFrames {
            output: output.to_path_buf(),
            budget,
            memory: Vec::new(),
            file: None,
            n_vertices,
            n_frames: 0,
            feet: FeetRecord::default(),
            moves: FeetMoves::default(),
        }
    }

    /// Appends the next placed `frames`, recording their feet on `target` when given.
    pub fn push(&mut self, frames: &[Vec<Vector3<f64>>], target: Option<&TargetFeet>, up: &Vector3<f64>) -> Result<()> {
        if let Some(target) = target {
            self.feet.push(frames, target, up);
        }
        if let Some(f) = frames.iter().find(|f| f.len() != self.n_vertices) {
            return Err(Error::invalid(format!("{}: a frame of {} vertices, the body has {}", self.output.display(), f.len(), self.n_vertices)));
        }
        let coordinates = frames.iter().flatten().flat_map(|p| p.iter().copied());
        let held = 8 * (self.memory.len() + 3 * self.n_vertices * frames.len());
        if self.file.is_none() && held <= self.budget {
            self.memory.extend(coordinates);
        } else {
            let memory = std::mem::take(&mut self.memory);
            let file = match &mut self.file {
                Some(file) => file,
                None => self.file.insert(BufWriter::with_capacity(1 << 20, mesh_core::atomic::scratch_file(&self.output)?)),
            };
            let bytes: Vec<u8> = memory.into_iter().chain(coordinates).flat_map(f64::to_le_bytes).collect();
            let written = file.write_all(&bytes);
            written.map_err(|e| self.scratch_error(e))?;
        }
        self.n_frames += frames.len();
        Ok(())
    }

    /// Frames pushed so far.
    pub fn n_frames(&self) -> usize {
        self.n_frames
    }

    /// What the clean-up reads of the frames pushed with a target.
    pub fn feet(&self) -> &FeetRecord {
        &self.feet
    }

    /// The moves [`PlacedFrames::for_each`] applies to each frame.
    pub fn set_moves(&mut self, moves: FeetMoves) {
        self.moves = moves;
    }

    /// Hands every frame, in order and moved, to `sink` (again on every call).
    pub fn for_each(&mut self, sink: &mut dyn FnMut(&[Vector3<f64>]) -> Result<()>) -> Result<()> {
        let mut frame = vec![Vector3::zeros(); self.n_vertices];
        let Some(file) = &mut self.file else {
            for (t, coordinates) in self.memory.chunks_exact(3 * self.n_vertices.max(1)).enumerate() {
                for (p, c) in frame.iter_mut().zip(coordinates.chunks_exact(3)) {
                    *p = Vector3::new(c[0], c[1], c[2]);
                }
                self.moves.apply(t, &mut frame);
                sink(&frame)?;
            }
            return Ok(());
        };
        let flushed = file.flush();
        flushed.map_err(|e| self.scratch_error(e))?;
        let mut file: &File = self.file.as_ref().expect("on disk").get_ref().as_file();
        file.seek(SeekFrom::Start(0)).map_err(|e| self.scratch_error(e))?;
        let mut reader = BufReader::with_capacity(1 << 20, file);
        let mut bytes = vec![0u8; 24 * self.n_vertices];
        for t in 0..self.n_frames {
            reader.read_exact(&mut bytes).map_err(|e| self.scratch_error(e))?;
            for (p, b) in frame.iter_mut().zip(bytes.chunks_exact(24)) {
                *p = Vector3::from_fn(|c, _| f64::from_le_bytes(b[8 * c..8 * c + 8].try_into().expect("8 bytes")));
            }
            self.moves.apply(t, &mut frame);
            sink(&frame)?;
        }
        // Later frames are appended after the last.
        file.seek(SeekFrom::End(0)).map_err(|e| self.scratch_error(e))?;
        Ok(())
    }

    fn scratch_error(&self, e: std::io::Error) -> Error {
        Error::file(&self.output, format!("scratch file of the placed frames: {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_come_back_to_the_bit_in_order_from_memory_or_disk_and_the_scratch_file_goes() {
        let frames: Vec<Vec<Vector3<f64>>> = (0..7)
            .map(|t| (0..5).map(|v| Vector3::new(0.1 * t as f64, std::f64::consts::PI * v as f64, -1e-300 * t as f64)).collect())
            .collect();
        // All in memory; all on disk; three frames in memory, then the rest on disk.
        for (budget, on_disk) in [(usize::MAX, false), (0, true), (3 * 120, true)] {
            let dir = tempfile::tempdir().unwrap();
            let out = dir.path().join("out");
            let mut placed = PlacedFrames::new(&out, 5, budget);
            placed.push(&frames[..3], None, &Vector3::y()).unwrap();
            placed.push(&frames[3..], None, &Vector3::y()).unwrap();
            assert_eq!(placed.n_frames(), 7);
            assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), on_disk as usize, "budget {budget}");
            for _ in 0..2 {
                let mut back = Vec::new();
                placed.for_each(&mut |f| Ok(back.push(f.to_vec()))).unwrap();
                assert_eq!(back, frames, "budget {budget}");
            }
            let err = placed.push(&[vec![Vector3::zeros(); 4]], None, &Vector3::y()).unwrap_err().to_string();
            assert!(err.contains("out") && err.contains("4 vertices"), "{err}");
            drop(placed);
            assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "the scratch file stays behind");
        }
    }
}

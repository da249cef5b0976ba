//! Mesh sequences as the renderer sees them: borrowed views (so callers keep
//! their own types) and loading a folder of frames for the CLI.

use std::path::Path;

use nalgebra::Vector3;

use crate::camera::Aabb;
use crate::colour::Rgb;

/// A borrowed mesh sequence: one triangle list shared by every frame, plus
/// optional per-vertex colours (e.g. body parts). Build one from a
/// `mesh_core::sequence::MeshSequence` with `SeqView::new(&s.faces, &s.frames)`.
#[derive(Clone, Copy, Debug)]
pub struct SeqView<'a> {
    pub faces: &'a [[u32; 3]],
    pub frames: &'a [Vec<Vector3<f64>>],
    pub vertex_colours: Option<&'a [Rgb]>,
}

impl<'a> SeqView<'a> {
    pub fn new(faces: &'a [[u32; 3]], frames: &'a [Vec<Vector3<f64>>]) -> Self {
        SeqView { faces, frames, vertex_colours: None }
    }
    pub fn with_vertex_colours(mut self, colours: &'a [Rgb]) -> Self {
        self.vertex_colours = Some(colours);
        self
    }
    pub fn n_frames(&self) -> usize {
        self.frames.len()
    }
    /// Frame `i`, clamped to the last frame (shorter sequences hold their
    /// last pose when overlaid with longer ones). `None` if empty.
    pub fn frame_clamped(&self, i: usize) -> Option<&'a [Vector3<f64>]> {
        let n = self.frames.len();
        (n > 0).then(|| self.frames[i.min(n - 1)].as_slice())
    }
}

/// Bounding box of the given frames of all sequences.
pub fn bounding_box(seqs: &[SeqView], frames: std::ops::Range<usize>) -> Aabb {
    let mut b = Aabb::empty();
    for s in seqs {
        let hi = frames.end.min(s.frames.len());
        let lo = frames.start.min(hi);
        for f in &s.frames[lo..hi] {
            for p in f {
                b.add(p);
            }
        }
    }
    b
}

/// A sequence loaded from a folder: the shared faces and every frame's positions.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    pub faces: Vec<[u32; 3]>,
    pub frames: Vec<Vec<Vector3<f64>>>,
}

impl Loaded {
    pub fn view(&self) -> SeqView<'_> {
        SeqView::new(&self.faces, &self.frames)
    }
}

/// Loads `dir/NNNNNN.ply|.obj` frames in order, checking that every frame
/// has the first frame's vertex count and faces.
///
// NOTE(next): replace with `mesh_core::sequence::MeshSequence::load_dir` once
// it exists (it is being written with this exact contract).
pub fn load_dir(dir: &Path) -> mesh_core::Result<Loaded> {
    use mesh_core::Error;
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut files = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        let is_frame = path.file_stem().and_then(|s| s.to_str()).is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            && mesh_core::io::MeshFormat::from_path(&path).is_some();
        if is_frame {
            files.push(path);
        }
    }
    files.sort();
    if files.is_empty() {
        return Err(Error::file(dir, "no frames (expected NNNNNN.ply or NNNNNN.obj files)"));
    }
    let mut faces = Vec::new();
    let mut frames = Vec::with_capacity(files.len());
    for (i, path) in files.iter().enumerate() {
        let m = mesh_core::io::read_mesh(path)?;
        if i == 0 {
            faces = m.faces;
        } else if m.vertices.len() != frames_len(&frames) {
            return Err(Error::file(path, format!("{} vertices, but the first frame has {}", m.vertices.len(), frames_len(&frames))));
        } else if m.faces != faces {
            return Err(Error::file(path, "faces differ from the first frame's (one topology per sequence)"));
        }
        frames.push(m.vertices);
    }
    Ok(Loaded { faces, frames })
}

fn frames_len(frames: &[Vec<Vector3<f64>>]) -> usize {
    frames.first().map_or(0, Vec::len)
}

//! Mesh sequences as the renderer sees them: borrowed views, so callers keep
//! their own types (`mesh_core::sequence::MeshSequence` converts with `into()`).

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
        SeqView {
            faces,
            frames,
            vertex_colours: None,
        }
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

impl<'a> From<&'a mesh_core::sequence::MeshSequence> for SeqView<'a> {
    fn from(s: &'a mesh_core::sequence::MeshSequence) -> Self {
        SeqView::new(&s.faces, &s.frames)
    }
}

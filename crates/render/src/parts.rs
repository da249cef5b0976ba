//! Per-vertex body-part colours from a subject's curves (`subject.json`): the template cut into
//! parts exactly as the `segment` stage cuts it (`mesh_core::segmentation::segment`), each part
//! in its colour and each overlap band the 50/50 mix of its part's and its parent's colours.

use std::collections::BTreeMap;
use std::path::Path;

use mesh_core::capture_set::SubjectSpec;
use mesh_core::{Error, Result, TriMesh};
use nalgebra::Vector3;

use crate::colour::{self, Rgb};

/// Colour of each part: light grey for the root, palette colours for the
/// other parts in part-name order.
pub fn part_palette(spec: &SubjectSpec) -> BTreeMap<String, Rgb> {
    let mut i = 0;
    spec.parts
        .iter()
        .map(|(p, parent)| {
            let c = if parent.is_none() {
                ROOT_COLOUR
            } else {
                i += 1;
                colour::palette(i - 1)
            };
            (p.clone(), c)
        })
        .collect()
}

/// Colour of the root part (the torso).
pub const ROOT_COLOUR: Rgb = [200, 200, 200];

/// Reads and parses a `subject.json`.
pub fn read_subject(path: &Path) -> Result<SubjectSpec> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_str(&text)
        .map_err(|e| Error::file(path, format!("not a valid subject.json: {e}")))
}

/// Per-vertex colours for a mesh with `faces` and rest positions `positions`: the root's
/// colour, each other part's own, its overlap band the mix of its and its parent's. `spec_path`
/// names the subject file in errors (curves that do not cut the mesh into the part tree).
pub fn part_colours(
    spec: &SubjectSpec,
    spec_path: &Path,
    positions: &[Vector3<f64>],
    faces: &[[u32; 3]],
) -> Result<Vec<Rgb>> {
    let n = positions.len();
    if faces.iter().any(|f| f.iter().any(|&v| v as usize >= n)) {
        return Err(Error::invalid("mesh faces index past the vertex list"));
    }
    let mesh = TriMesh { vertices: positions.to_vec(), faces: faces.to_vec() };
    let seg = mesh_core::segmentation::segment(&mesh, spec).map_err(|e| Error::file(spec_path, e.to_string()))?;
    let palette = part_palette(spec);
    let colour = |p: &str| palette.get(p).copied().unwrap_or(ROOT_COLOUR);
    let mut colours = vec![ROOT_COLOUR; n];
    for part in seg.parts.iter().filter(|p| p.parent.is_some()) {
        let own = colour(&part.name);
        let band = colour::mix(own, colour(part.parent.as_deref().unwrap_or_default()), 0.5);
        for &v in &part.vertices {
            colours[v as usize] = own;
        }
        for &l in &part.overlap {
            colours[part.vertices[l as usize] as usize] = band;
        }
    }
    Ok(colours)
}

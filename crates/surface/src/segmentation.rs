//! The stitching layout of a subject's part decomposition
//! ([`mesh_core::segmentation::Segmentation`], written by the `segment` stage).

use crate::stitch::{LayoutPart, PartLayout};
use crate::{Error, Result};
use mesh_core::segmentation::Segmentation;

/// The stitching layout over `template_faces`, parts in
/// [`Segmentation::tree_order`] (parents before children).
pub fn part_layout(seg: &Segmentation, template_faces: Vec<[u32; 3]>) -> Result<PartLayout> {
    let order = seg.tree_order().map_err(|e| Error::invalid(e.to_string()))?;
    let pos = |name: &str| order.iter().position(|&k| seg.parts[k].name == name);
    let parts = order
        .iter()
        .map(|&k| {
            let p = &seg.parts[k];
            let parent = match &p.parent {
                None => None,
                Some(n) => Some(
                    pos(n).ok_or_else(|| Error::invalid(format!("part '{}': unknown parent '{n}'", p.name)))?,
                ),
            };
            Ok(LayoutPart { vertices: p.vertices.clone(), parent })
        })
        .collect::<Result<Vec<_>>>()?;
    PartLayout::new(seg.n_vertices, template_faces, parts)
}

//! The part decomposition written by the `segment` stage (crate `transfer`, artifact kind
//! `segmentation` v1), read into a [`PartLayout`] for stitching.
//!
//! `surface` cannot depend on `transfer` (transfer calls surface), so the payload struct is
//! mirrored here field for field; bincode decoding fails loudly (one line naming the file)
//! if the two drift apart.
// NOTE(next): move `Segmentation` into mesh-core so both crates share one definition.

use crate::stitch::{Part, PartLayout};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Mirror of `transfer::segment::Part`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentPart {
    pub name: String,
    pub parent: Option<String>,
    pub vertices: Vec<u32>,
    pub faces: Vec<[u32; 3]>,
    pub overlap: Vec<u32>,
    pub loops: Vec<Vec<u32>>,
}

/// Mirror of `transfer::segment::Segmentation`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segmentation {
    pub n_vertices: usize,
    pub parts: Vec<SegmentPart>,
}

impl mesh_core::artifact::Artifact for Segmentation {
    const KIND: &'static str = "segmentation";
    const VERSION: u32 = 1;
}

impl Segmentation {
    /// Part order with every parent before its children (root first), as indices into
    /// `self.parts`.
    pub fn tree_order(&self) -> Result<Vec<usize>> {
        let roots: Vec<usize> = (0..self.parts.len())
            .filter(|&k| self.parts[k].parent.is_none())
            .collect();
        if roots.len() != 1 {
            return Err(Error::invalid(format!(
                "segmentation has {} root parts, expected 1",
                roots.len()
            )));
        }
        let mut order = roots;
        let mut i = 0;
        while i < order.len() {
            let name = &self.parts[order[i]].name;
            order.extend(
                (0..self.parts.len()).filter(|&k| self.parts[k].parent.as_ref() == Some(name)),
            );
            i += 1;
        }
        if order.len() != self.parts.len() {
            return Err(Error::invalid(
                "segmentation: some parts are not connected to the root",
            ));
        }
        Ok(order)
    }

    /// The stitching layout over `template_faces`, parts in [`Self::tree_order`].
    pub fn layout(&self, template_faces: Vec<[u32; 3]>) -> Result<PartLayout> {
        let order = self.tree_order()?;
        let pos = |name: &str| order.iter().position(|&k| self.parts[k].name == name);
        let parts = order
            .iter()
            .map(|&k| {
                let p = &self.parts[k];
                let parent = match &p.parent {
                    None => None,
                    Some(n) => Some(pos(n).ok_or_else(|| {
                        Error::invalid(format!("part '{}': unknown parent '{n}'", p.name))
                    })?),
                };
                Ok(Part {
                    vertices: p.vertices.clone(),
                    parent,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        PartLayout::new(self.n_vertices, template_faces, parts)
    }

    /// Loads the artifact.
    pub fn load(path: &Path) -> Result<Self> {
        <Self as mesh_core::artifact::Artifact>::load(path)
    }
}

//! Per-vertex body-part colours from a subject's curves (`subject.json`).
//!
//! Stand-in until the segment stage exists. Each part's loops (first the one
//! near the parent, then the one down the limb; consecutive entries that are
//! not adjacent joined by shortest edge paths, last to first included) are
//! cut out of the mesh, and every remaining connected region is labelled by
//! the loops on its border:
//! - it touches both loops of part `p`: the overlap band of `p` with its
//!   parent (drawn as a 50/50 mix of the two part colours);
//! - else it touches the far loop of `p`: part `p` itself;
//! - else it touches the near loop of `p`: `p`'s parent;
//! - else: the root part.
//!
//! Vertices lying on both loops of a part (loops may touch on coarse meshes)
//! do not count as a border of that part. When several parts qualify the
//! deepest one in the part tree wins. Loop vertices take their band's
//! colour. The root is light grey, the other parts follow the palette in
//! part-name order.

use std::collections::BTreeMap;
use std::path::Path;

use mesh_core::capture_set::SubjectSpec;
use mesh_core::topology::Topology;
use mesh_core::{Error, Result};
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

/// Per-vertex colours for a mesh with `faces` and rest positions `positions`.
/// `spec_path` names the subject file in errors.
pub fn part_colours(
    spec: &SubjectSpec,
    spec_path: &Path,
    positions: &[Vector3<f64>],
    faces: &[[u32; 3]],
) -> Result<Vec<Rgb>> {
    let n = positions.len();
    let bad = |msg: String| Error::file(spec_path, msg);
    if faces.iter().any(|f| f.iter().any(|&v| v as usize >= n)) {
        return Err(Error::invalid("mesh faces index past the vertex list"));
    }
    // Part depths (root 0); reject unknown parents and cycles.
    let mut depth: BTreeMap<&str, usize> = BTreeMap::new();
    for p in spec.parts.keys() {
        let mut d = 0;
        let mut cur = p.as_str();
        while let Some(Some(parent)) = spec.parts.get(cur) {
            if !spec.parts.contains_key(parent) {
                return Err(bad(format!("part {cur:?} has unknown parent {parent:?}")));
            }
            d += 1;
            if d > spec.parts.len() {
                return Err(bad(format!("part tree has a cycle through {p:?}")));
            }
            cur = parent;
        }
        depth.insert(p, d);
    }
    let root = depth
        .iter()
        .find(|(_, &d)| d == 0)
        .map(|(p, _)| p.to_string());
    let Some(root) = root else {
        return Err(bad("part tree has no root (a part with parent null)".into()));
    };
    let topo = Topology::new(n, faces);
    // Closed vertex loops, per part: [near, far].
    let mut loops: Vec<(String, usize, Vec<u32>)> = Vec::new();
    for (part, curves) in &spec.curves {
        if !spec.parts.contains_key(part) {
            return Err(bad(format!("curves given for unknown part {part:?}")));
        }
        if curves.len() < 2 {
            return Err(bad(format!(
                "part {part:?} needs two loops (near the parent, down the limb), has {}",
                curves.len()
            )));
        }
        for (k, c) in curves.iter().take(2).enumerate() {
            if let Some(&v) = c.iter().find(|&&v| v as usize >= n) {
                return Err(bad(format!(
                    "curve of part {part:?} uses vertex {v}, the mesh has {n}"
                )));
            }
            if c.len() < 3 {
                return Err(bad(format!(
                    "loop {k} of part {part:?} has fewer than 3 vertices"
                )));
            }
            let mut closed = Vec::new();
            for i in 0..c.len() {
                let (a, b) = (c[i], c[(i + 1) % c.len()]);
                if a == b || topo.are_adjacent(a, b) {
                    closed.push(a);
                    continue;
                }
                let (path, _) = topo.shortest_path(positions, a, b).ok_or_else(|| {
                    bad(format!(
                        "loop {k} of part {part:?} is not closed: vertices {a} and {b} are not connected"
                    ))
                })?;
                closed.extend_from_slice(&path[..path.len() - 1]);
            }
            loops.push((part.clone(), k, closed));
        }
    }
    // Cut the loops out and flood-fill the rest.
    const NONE: u32 = u32::MAX;
    let mut on_loop: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (li, (_, _, l)) in loops.iter().enumerate() {
        for &v in l {
            on_loop[v as usize].push(li);
        }
    }
    let mut region = vec![NONE; n];
    let mut borders: Vec<Vec<usize>> = Vec::new();
    for seed in 0..n {
        if region[seed] != NONE || !on_loop[seed].is_empty() {
            continue;
        }
        let id = borders.len() as u32;
        let mut touched = Vec::new();
        let mut stack = vec![seed as u32];
        region[seed] = id;
        while let Some(v) = stack.pop() {
            for &w in topo.vertex_neighbors(v) {
                let wi = w as usize;
                if !on_loop[wi].is_empty() {
                    // A vertex on both loops of one part (loops may touch) says
                    // nothing about which side of that part the region is on.
                    let here = &on_loop[wi];
                    touched.extend(here.iter().copied().filter(|&li| {
                        !here
                            .iter()
                            .any(|&lj| loops[lj].0 == loops[li].0 && loops[lj].1 != loops[li].1)
                    }));
                } else if region[wi] == NONE {
                    region[wi] = id;
                    stack.push(w);
                }
            }
        }
        touched.sort_unstable();
        touched.dedup();
        borders.push(touched);
    }
    let pal = part_palette(spec);
    let part_colour = |p: &str| pal.get(p).copied().unwrap_or(colour::palette(0));
    let band_colour = |p: &str| {
        let parent = spec
            .parts
            .get(p)
            .cloned()
            .flatten()
            .unwrap_or_else(|| root.clone());
        colour::mix(part_colour(p), part_colour(&parent), 0.5)
    };
    let deeper = |a: &Option<(usize, Rgb)>, d: usize| a.is_none_or(|(da, _)| d > da);
    let region_colours: Vec<Rgb> = borders
        .iter()
        .map(|b| {
            let has =
                |part: &str, k: usize| b.iter().any(|&li| loops[li].0 == part && loops[li].1 == k);
            let (mut band, mut own, mut parent): (
                Option<(usize, Rgb)>,
                Option<(usize, Rgb)>,
                Option<(usize, Rgb)>,
            ) = (None, None, None);
            for part in spec.curves.keys() {
                let d = depth[part.as_str()];
                let (near, far) = (has(part, 0), has(part, 1));
                if near && far && deeper(&band, d) {
                    band = Some((d, band_colour(part)));
                } else if far && !near && deeper(&own, d) {
                    own = Some((d, part_colour(part)));
                } else if near && !far && deeper(&parent, d) {
                    let par = spec
                        .parts
                        .get(part)
                        .cloned()
                        .flatten()
                        .unwrap_or_else(|| root.clone());
                    parent = Some((d, part_colour(&par)));
                }
            }
            band.or(own)
                .or(parent)
                .map(|x| x.1)
                .unwrap_or_else(|| part_colour(&root))
        })
        .collect();
    Ok((0..n)
        .map(|v| match on_loop[v].first() {
            Some(&li) => band_colour(&loops[li].0),
            None => region_colours[region[v] as usize],
        })
        .collect())
}

//! Overlapping body parts cut from a subject's template by the user's curves
//! (transfer paper §4, "Body Parts", figure 2). Written by the `segment`
//! stage; read by transfer (PCA per part), surface (stitching) and variation.
//!
//! Every non-root part `c` has two closed loops: `near` (close to its parent)
//! and `far` (further down the limb). Removing a loop's vertices splits the
//! mesh; the *limb side* of a loop is what lies away from the parent.
//!
//! - Part `c` is `near` plus everything on the limb side of `near`.
//! - Its parent keeps everything up to and including `far`: only what lies
//!   strictly beyond `far` is removed from the parent.
//! - So the band between `near` and `far` (both loops included) belongs to
//!   both: it is `c`'s **overlap** with its parent, used later to align and
//!   stitch the parts.
//!
//! The limb side of `near` is found by flooding from `far` with `near`
//! blocked, and the parent side of `far` by flooding from `near` with `far`
//! blocked; a loop that does not cut the mesh (the flood reaches the other
//! side) is an error.
//!
//! A template of several connected components floods across the joins of
//! [`crate::component_joins`]: a piece that no loop crosses goes with the
//! part its closest vertex is in.

use std::collections::BTreeMap;

use crate::artifact::{check_cover, check_indices, Artifact};
use crate::capture_set::SubjectSpec;
use crate::topology::Topology;
use crate::{Error, Result, TriMesh};
use serde::{Deserialize, Serialize};

/// One body part: a sub-mesh of the template with its own local indexing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Part {
    pub name: String,
    pub parent: Option<String>,
    /// Template vertex index of each local vertex (sorted ascending).
    pub vertices: Vec<u32>,
    /// Triangles in local indices: template faces whose three corners are in the part.
    pub faces: Vec<[u32; 3]>,
    /// Local indices of the overlap band shared with the parent (empty for the root).
    pub overlap: Vec<u32>,
    /// The two loops (template indices): near the parent, down the limb (empty for the root).
    pub loops: Vec<Vec<u32>>,
}

/// All parts of one subject, root first, then children in name order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segmentation {
    pub n_vertices: usize,
    pub parts: Vec<Part>,
}

impl Artifact for Segmentation {
    const KIND: &'static str = "segmentation";
    const VERSION: u32 = 1;

    fn validate(&self) -> std::result::Result<(), String> {
        self.check()
    }
}

impl Segmentation {
    /// Checks what consumers index with: every part's template vertices
    /// ascending and below `n_vertices`, every template vertex in some part,
    /// local faces and overlap below the part's vertex count, loops below
    /// `n_vertices`, unique part names and one tree from a single root.
    pub fn check(&self) -> std::result::Result<(), String> {
        let lists: Vec<&[u32]> = self.parts.iter().map(|p| p.vertices.as_slice()).collect();
        check_cover(self.n_vertices, &lists)?;
        for (k, p) in self.parts.iter().enumerate() {
            let name = || format!("part {k} ('{}')", p.name);
            if self.parts[..k].iter().any(|q| q.name == p.name) {
                return Err(format!("{} appears twice", name()));
            }
            if p.vertices.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!("{}: vertices are not strictly ascending", name()));
            }
            let local = p.vertices.len();
            check_indices(p.faces.iter().flatten().copied(), local, || format!("{} face list", name()))?;
            check_indices(p.overlap.iter().copied(), local, || format!("{} overlap", name()))?;
            check_indices(p.loops.iter().flatten().copied(), self.n_vertices, || format!("{} loops", name()))?;
            if let Some(parent) = &p.parent {
                if !self.parts.iter().any(|q| &q.name == parent) {
                    return Err(format!("{}: parent '{parent}' is not a part", name()));
                }
            }
        }
        self.tree_order().map_err(|e| e.to_string())?;
        Ok(())
    }
}

impl Segmentation {
    pub fn part(&self, name: &str) -> Option<&Part> {
        self.parts.iter().find(|p| p.name == name)
    }

    /// Part indices with every parent before its children (root first).
    /// Errors unless there is exactly one root and every part hangs from it.
    pub fn tree_order(&self) -> Result<Vec<usize>> {
        let roots: Vec<usize> = (0..self.parts.len()).filter(|&k| self.parts[k].parent.is_none()).collect();
        if roots.len() != 1 {
            return Err(Error::invalid(format!("segmentation has {} root parts, expected 1", roots.len())));
        }
        let mut order = roots;
        let mut i = 0;
        while i < order.len() {
            let name = &self.parts[order[i]].name;
            order.extend((0..self.parts.len()).filter(|&k| self.parts[k].parent.as_ref() == Some(name)));
            i += 1;
        }
        if order.len() != self.parts.len() {
            return Err(Error::invalid("segmentation: some parts are not connected to the root"));
        }
        Ok(order)
    }

    /// Part index of every template vertex, for colouring: a vertex in an
    /// overlap band gets the child part (the more specific one).
    pub fn vertex_labels(&self) -> Vec<usize> {
        let mut labels = vec![0; self.n_vertices];
        for (k, part) in self.parts.iter().enumerate().filter(|(_, p)| p.parent.is_some()) {
            for &v in &part.vertices {
                labels[v as usize] = k;
            }
        }
        labels
    }
}

/// Floods the vertex graph (mesh edges and component `joins`) from `seeds`, never entering `blocked`.
fn flood(topology: &Topology, joins: &[Vec<u32>], seeds: &[u32], blocked: &[bool]) -> Vec<bool> {
    let mut seen = vec![false; topology.n_vertices()];
    let mut stack: Vec<u32> = seeds.iter().copied().filter(|&s| !blocked[s as usize]).collect();
    for &s in &stack {
        seen[s as usize] = true;
    }
    while let Some(v) = stack.pop() {
        for &w in topology.vertex_neighbors(v).iter().chain(&joins[v as usize]) {
            if !seen[w as usize] && !blocked[w as usize] {
                seen[w as usize] = true;
                stack.push(w);
            }
        }
    }
    seen
}

fn mask(n: usize, indices: &[u32]) -> Vec<bool> {
    let mut m = vec![false; n];
    for &i in indices {
        m[i as usize] = true;
    }
    m
}

/// Cuts `template` into the parts of `subject` (curves validated and
/// resolved against the template first).
pub fn segment(template: &TriMesh, subject: &SubjectSpec) -> Result<Segmentation> {
    let topology = Topology::new(template.n_vertices(), &template.faces);
    let loops = subject.validate(template, &topology)?;
    let n = template.n_vertices();
    let root = subject.root().ok_or_else(|| Error::invalid("the part tree has no root"))?.to_string();
    let joins = crate::component_joins::join_neighbours(n, &crate::component_joins::component_joins(&topology, &template.vertices));

    // Per child part: its own region (limb side of `near` plus `near`) and
    // what it removes from its parent (strictly beyond `far`).
    let mut region: BTreeMap<String, Vec<bool>> = BTreeMap::new();
    let mut beyond_far: BTreeMap<String, Vec<bool>> = BTreeMap::new();
    for (name, [near, far]) in &loops {
        let near_mask = mask(n, near);
        let far_mask = mask(n, far);
        if near.iter().any(|&v| far_mask[v as usize]) {
            return Err(Error::invalid(format!("part '{name}': its two curves share vertices")));
        }
        let limb = flood(&topology, &joins, far, &near_mask);
        let parent_side = flood(&topology, &joins, near, &far_mask);
        // `near` must separate: the limb side may not reach the parent side of `near`.
        let limb_count = limb.iter().filter(|b| **b).count();
        if limb_count + near.len() >= n {
            return Err(Error::invalid(format!(
                "part '{name}': curve 1 does not cut the mesh (everything is on the limb side)"
            )));
        }
        // Nor may it reach another part's curves, unless that part hangs below this one: a loop
        // that goes round a patch of skin instead of the limb leaves the rest of the body,
        // other limbs included, on the limb side.
        let below = |q: &str| {
            let mut at = Some(q.to_string());
            while let Some(p) = at {
                if p == *name {
                    return true;
                }
                at = subject.parts.get(&p).cloned().flatten();
            }
            false
        };
        if let Some((other, _)) = loops.iter().find(|(q, [a, b])| {
            !below(q.as_str()) && a.iter().chain(b).any(|&v| limb[v as usize] && !near_mask[v as usize])
        }) {
            return Err(Error::invalid(format!(
                "part '{name}': curve 1 does not cut the limb off the body (part '{other}''s curves lie on its limb side)"
            )));
        }
        let parent_count = parent_side.iter().filter(|b| **b).count();
        if parent_count + far.len() >= n {
            return Err(Error::invalid(format!(
                "part '{name}': curve 2 does not cut the mesh (nothing lies beyond it)"
            )));
        }
        let own: Vec<bool> = (0..n).map(|v| limb[v] || near_mask[v]).collect();
        let beyond: Vec<bool> = (0..n).map(|v| !parent_side[v] && !far_mask[v]).collect();
        region.insert(name.clone(), own);
        beyond_far.insert(name.clone(), beyond);
    }

    let mut names: Vec<String> = vec![root.clone()];
    names.extend(subject.parts.keys().filter(|k| **k != root).cloned());
    let mut parts = Vec::with_capacity(names.len());
    for name in &names {
        let mut members = match region.get(name) {
            Some(r) => r.clone(),
            None => vec![true; n],
        };
        for (child, parent) in &subject.parts {
            if parent.as_deref() == Some(name.as_str()) {
                for (m, b) in members.iter_mut().zip(&beyond_far[child]) {
                    *m &= !b;
                }
            }
        }
        let vertices: Vec<u32> = (0..n as u32).filter(|&v| members[v as usize]).collect();
        let mut local = vec![u32::MAX; n];
        for (i, &v) in vertices.iter().enumerate() {
            local[v as usize] = i as u32;
        }
        let faces: Vec<[u32; 3]> = template
            .faces
            .iter()
            .filter(|f| f.iter().all(|&v| members[v as usize]))
            .map(|f| [local[f[0] as usize], local[f[1] as usize], local[f[2] as usize]])
            .collect();
        let (overlap, part_loops) = match loops.get(name) {
            Some([near, far]) => {
                let beyond = &beyond_far[name];
                let overlap = vertices
                    .iter()
                    .filter(|&&v| !beyond[v as usize])
                    .map(|&v| local[v as usize])
                    .collect();
                (overlap, vec![near.clone(), far.clone()])
            }
            None => (Vec::new(), Vec::new()),
        };
        if vertices.is_empty() || faces.is_empty() {
            return Err(Error::invalid(format!("part '{name}' is empty after cutting")));
        }
        parts.push(Part {
            name: name.clone(),
            parent: subject.parts.get(name).cloned().flatten(),
            vertices,
            faces,
            overlap,
            loops: part_loops,
        });
    }
    Ok(Segmentation { n_vertices: n, parts })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::capsule_body;

    /// A capsule standing on +y with one "limb" part above two rings: the
    /// part sizes follow from the ring layout exactly.
    fn capsule_subject(near_ring: usize, far_ring: usize) -> (TriMesh, SubjectSpec, usize) {
        let (mesh, layout) = capsule_body(10, 12, 0.2, 2.0);
        let near = layout.ring(layout.body_ring(near_ring));
        let far = layout.ring(layout.body_ring(far_ring));
        let subject: SubjectSpec = serde_json::from_value(serde_json::json!({
            "fps": 25, "parts": {"torso": null, "limb": "torso"},
            "curves": {"limb": [near, far]}
        }))
        .unwrap();
        (mesh, subject, layout.segments)
    }

    #[test]
    fn parts_overlap_on_the_band_between_the_curves() {
        let (mesh, subject, seg) = capsule_subject(4, 6);
        let s = segment(&mesh, &subject).unwrap();
        let torso = s.part("torso").unwrap();
        let limb = s.part("limb").unwrap();
        // Band = rings 4..=6 of the body section: 3 rings.
        assert_eq!(limb.overlap.len(), 3 * seg);
        let in_torso: std::collections::HashSet<u32> = torso.vertices.iter().copied().collect();
        let shared = limb.vertices.iter().filter(|v| in_torso.contains(v)).count();
        assert_eq!(shared, 3 * seg, "torso and limb share exactly the band");
        // Together they cover the mesh.
        let mut all: Vec<u32> = torso.vertices.iter().chain(&limb.vertices).copied().collect();
        all.sort();
        all.dedup();
        assert_eq!(all.len(), mesh.n_vertices());
        // Faces are valid local triangles.
        for p in &s.parts {
            assert!(p.faces.iter().flatten().all(|&i| (i as usize) < p.vertices.len()));
        }
        // The overlap vertices of the limb lie between the two curves' heights.
        let ys: Vec<f64> = limb.overlap.iter().map(|&l| mesh.vertices[limb.vertices[l as usize] as usize].y).collect();
        let (lo, hi) = (2.0 * 4.0 / 9.0, 2.0 * 6.0 / 9.0);
        assert!(ys.iter().all(|&y| y > lo - 1e-9 && y < hi + 1e-9));
    }

    #[test]
    fn loop_round_a_patch_instead_of_the_limb_is_rejected() {
        // Two "limbs" on the capsule: the top above rings 6-8, the bottom below rings 3-1.
        let (mesh, layout) = capsule_body(10, 12, 0.2, 2.0);
        let ring = |r: usize| layout.ring(layout.body_ring(r));
        let spec = |top_near: Vec<u32>| -> SubjectSpec {
            serde_json::from_value(serde_json::json!({
                "fps": 25, "parts": {"torso": null, "top": "torso", "bottom": "torso"},
                "curves": {"top": [top_near, ring(8)], "bottom": [ring(3), ring(1)]}
            }))
            .unwrap()
        };
        let s = segment(&mesh, &spec(ring(6))).unwrap();
        assert!(s.part("top").unwrap().vertices.len() < mesh.n_vertices() / 2);
        // The top's near curve replaced by the 1-ring of a torso vertex (ring 5): it cuts off
        // that one vertex, so the "limb" side is everything else, the bottom's curves included.
        let v = ring(5)[0];
        let topology = Topology::new(mesh.n_vertices(), &mesh.faces);
        let mut next = std::collections::HashMap::new();
        for &f in topology.vertex_faces(v) {
            let face = mesh.faces[f as usize];
            let k = face.iter().position(|&x| x == v).unwrap();
            next.insert(face[(k + 1) % 3], face[(k + 2) % 3]);
        }
        let start = *next.keys().min().unwrap();
        let mut one_ring = vec![start];
        while next[one_ring.last().unwrap()] != start {
            one_ring.push(next[one_ring.last().unwrap()]);
        }
        let err = segment(&mesh, &spec(one_ring)).unwrap_err().to_string();
        assert!(err.contains("part 'top': curve 1 does not cut the limb off the body (part 'bottom'"), "{err}");
    }

    #[test]
    fn a_separate_piece_goes_with_the_part_it_is_nearest_to() {
        // The capsule (y from 0 to 2, limb above ring 4 of 9) with two small spheres beside it:
        // one next to the limb's end (y = 1.9), one next to the torso (y = 0.2).
        let (mut mesh, subject, _) = capsule_subject(4, 6);
        let n0 = mesh.n_vertices() as u32;
        let ball = crate::shapes::icosphere(1);
        for y in [1.9, 0.2] {
            let base = mesh.vertices.len() as u32;
            mesh.vertices.extend(ball.vertices.iter().map(|p| p * 0.05 + nalgebra::Vector3::new(0.3, y, 0.0)));
            mesh.faces.extend(ball.faces.iter().map(|f| [f[0] + base, f[1] + base, f[2] + base]));
        }
        let s = segment(&mesh, &subject).unwrap();
        s.check().unwrap();
        let nb = ball.vertices.len() as u32;
        let (near_limb_end, near_torso) = (n0..n0 + nb, n0 + nb..n0 + 2 * nb);
        let limb = s.part("limb").unwrap();
        let torso = s.part("torso").unwrap();
        assert!(near_limb_end.clone().all(|v| limb.vertices.binary_search(&v).is_ok() && torso.vertices.binary_search(&v).is_err()));
        assert!(near_torso.clone().all(|v| torso.vertices.binary_search(&v).is_ok() && limb.vertices.binary_search(&v).is_err()));
    }

    #[test]
    fn loop_that_does_not_cut_is_rejected() {
        let (mesh, mut subject, _) = capsule_subject(4, 6);
        // Replace the far curve with a short open arc re-closed along itself:
        // a triangle of three neighbouring vertices cuts nothing off.
        let tri = [mesh.faces[40][0], mesh.faces[40][1], mesh.faces[40][2]];
        subject.curves.get_mut("limb").unwrap()[1] = tri.to_vec();
        let err = segment(&mesh, &subject).unwrap_err().to_string();
        assert!(err.contains("does not cut") || err.contains("share"), "{err}");
    }
}

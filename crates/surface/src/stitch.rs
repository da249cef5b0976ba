//! Part stitching (transfer paper §6.2): rigid alignment of each child part to its parent on
//! their overlap band, optimal boundary loop in the band ([`crate::optimal_boundary`]), and
//! Poisson merging with the loops as Dirichlet boundary (Yu et al. 2004, paper ref. [30]).
//!
//! Parts form a tree (part 0 is the root, every other part names an earlier parent). For each
//! child in order: Procrustes (`mesh_core::rigid::procrustes`: rotation + translation,
//! reflection guarded) of the child onto
//! its already aligned parent over the band vertices; the loop minimising the discrepancy
//! between the two instantiations; the child's vertices beyond the loop take the child as
//! source. Then one Poisson solve on the whole template merges everything at once (the bands
//! are disjoint, so this equals merging child by child): each face's reference geometry and
//! target gradient come from its source part (the face's own shape, `J_f = ∇x^src` on the
//! source triangle, i.e. a mixed-geometry cotangent Laplacian), and loop vertices are fixed at
//! the mean of their two aligned instantiations. The result is in the root part's frame;
//! the caller applies the predicted global rigid displacement.
//!
//! The sparsity pattern depends only on the template, so the symbolic factorisation is
//! computed once and reused for every frame, also by the [`Stitcher::fork`]s that stitch other
//! frames on other threads.

use crate::deformation_gradient::StiffnessPattern;
use crate::optimal_boundary::{discrepancy, optimal_loop_in, BoundaryLoop};
use crate::poisson::{Factorisation, PoissonSolver, SymbolicPoisson};
use crate::{check_faces, check_vertices, Error, Result};
use mesh_core::rigid::{procrustes, RigidMotion};
use mesh_core::topology::Topology;
use nalgebra::Vector3;
use std::sync::Arc;

const ABSENT: u32 = u32::MAX;

/// One part of a [`PartLayout`]: its vertices as indices into the template, and its parent
/// part (an index into the layout). The segment stage's full record is
/// `mesh_core::segmentation::Part`.
#[derive(Clone, Debug)]
pub struct LayoutPart {
    pub vertices: Vec<u32>,
    pub parent: Option<usize>,
}

struct Band {
    /// Template indices of the overlap vertices.
    vertices: Vec<u32>,
    /// Connectivity of the template faces inside the overlap, in band-local indices.
    topology: Topology,
}

/// The template topology and its decomposition into overlapping parts.
pub struct PartLayout {
    n_vertices: usize,
    faces: Vec<[u32; 3]>,
    parts: Vec<LayoutPart>,
    /// Per part: template index -> part-local index (ABSENT if not in the part).
    local: Vec<Vec<u32>>,
    bands: Vec<Option<Band>>,
    topology: Topology,
    in_face: Vec<bool>,
}

impl PartLayout {
    pub fn new(n_vertices: usize, faces: Vec<[u32; 3]>, parts: Vec<LayoutPart>) -> Result<Self> {
        check_faces(n_vertices, &faces, "stitch: template")?;
        if parts.is_empty() || parts[0].parent.is_some() {
            return Err(Error::invalid(
                "stitch: part 0 must be the root (no parent)",
            ));
        }
        let mut local = Vec::with_capacity(parts.len());
        for (k, p) in parts.iter().enumerate() {
            if k > 0 && !matches!(p.parent, Some(q) if q < k) {
                return Err(Error::invalid(format!(
                    "stitch: part {k} must name an earlier part as parent"
                )));
            }
            let mut map = vec![ABSENT; n_vertices];
            for (i, &v) in p.vertices.iter().enumerate() {
                let slot = map.get_mut(v as usize).ok_or_else(|| {
                    Error::invalid(format!(
                        "stitch: part {k} uses vertex {v}, template has {n_vertices}"
                    ))
                })?;
                if *slot != ABSENT {
                    return Err(Error::invalid(format!(
                        "stitch: part {k} lists vertex {v} twice"
                    )));
                }
                *slot = i as u32;
            }
            local.push(map);
        }
        let mut in_face = vec![false; n_vertices];
        faces
            .iter()
            .flatten()
            .for_each(|&v| in_face[v as usize] = true);
        if let Some(v) =
            (0..n_vertices).find(|&v| in_face[v] && local.iter().all(|m| m[v] == ABSENT))
        {
            return Err(Error::invalid(format!(
                "stitch: template vertex {v} belongs to no part"
            )));
        }
        let mut bands = vec![None];
        for (k, p) in parts.iter().enumerate().skip(1) {
            let q = p.parent.expect("checked");
            let vertices: Vec<u32> = p
                .vertices
                .iter()
                .copied()
                .filter(|&v| local[q][v as usize] != ABSENT)
                .collect();
            let mut band_index = vec![ABSENT; n_vertices];
            vertices
                .iter()
                .enumerate()
                .for_each(|(i, &v)| band_index[v as usize] = i as u32);
            let bfaces: Vec<[u32; 3]> = faces
                .iter()
                .filter(|f| f.iter().all(|&v| band_index[v as usize] != ABSENT))
                .map(|f| f.map(|v| band_index[v as usize]))
                .collect();
            if bfaces.is_empty() {
                return Err(Error::invalid(format!(
                    "stitch: part {k} does not overlap its parent part {q}"
                )));
            }
            let topology = Topology::new(vertices.len(), &bfaces);
            bands.push(Some(Band { vertices, topology }));
        }
        let topology = Topology::new(n_vertices, &faces);
        Ok(PartLayout {
            n_vertices,
            faces,
            parts,
            local,
            bands,
            topology,
            in_face,
        })
    }

    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    pub fn parts(&self) -> &[LayoutPart] {
        &self.parts
    }
}

/// A stitched mesh and how it was made.
#[derive(Clone, Debug)]
pub struct Stitched {
    /// Positions of all template vertices, in the root part's frame.
    pub vertices: Vec<Vector3<f64>>,
    /// Per part (None for the root): the merging loop in template indices, and its cost.
    pub loops: Vec<Option<BoundaryLoop>>,
    /// Per part: the rigid motion taking its input positions into the root part's frame
    /// (fitted on the band to its already aligned parent; identity for the root).
    pub alignments: Vec<RigidMotion>,
}

/// Stitches part meshes into one template mesh; keeps the factorisation between frames.
pub struct Stitcher {
    layout: Arc<PartLayout>,
    pattern: StiffnessPattern,
    solver: Option<PoissonSolver>,
    /// The symbolic analysis to factorise on when there is no solver yet (a fork's).
    symbolic: Option<SymbolicPoisson>,
    factorisation: Factorisation,
    align_children: bool,
}

impl Stitcher {
    pub fn new(layout: PartLayout) -> Self {
        let pattern = StiffnessPattern::new(layout.n_vertices, &layout.faces);
        Stitcher {
            layout: Arc::new(layout),
            pattern,
            solver: None,
            symbolic: None,
            factorisation: Factorisation::Auto,
            align_children: true,
        }
    }

    /// The sparse Cholesky factorisation of the merge's Poisson system (default
    /// [`Factorisation::Auto`]; [`Factorisation::Supernodal`] is faster on body meshes and
    /// agrees to rounding).
    pub fn with_factorisation(mut self, how: Factorisation) -> Self {
        self.factorisation = how;
        self.solver = None;
        self.symbolic = None;
        self
    }

    /// A stitcher of the same layout and settings with a factorisation of its own, on the
    /// symbolic analysis of this one's once made: it stitches other frames, on another thread,
    /// to the same results bit for bit.
    pub fn fork(&self) -> Stitcher {
        Stitcher {
            layout: Arc::clone(&self.layout),
            pattern: self.pattern.clone(),
            solver: None,
            symbolic: self
                .solver
                .as_ref()
                .map(|s| s.symbolic().clone())
                .or_else(|| self.symbolic.clone()),
            factorisation: self.factorisation,
            align_children: self.align_children,
        }
    }

    /// With `false`, children are taken as given (already in the root part's frame, e.g. parts
    /// cut from whole-body-aligned frames) instead of Procrustes-aligned on their band.
    pub fn with_band_alignment(mut self, align: bool) -> Self {
        self.align_children = align;
        self
    }
    /// The factorisation of the merge's Poisson system.
    pub fn factorisation(&self) -> Factorisation {
        self.factorisation
    }
    pub fn layout(&self) -> &PartLayout {
        &self.layout
    }

    /// `parts[k]` holds part `k`'s vertex positions in the order of `LayoutPart::vertices`.
    /// Loop vertices are fixed at the mean of their parent's and child's instantiations.
    pub fn stitch(&mut self, parts: &[Vec<Vector3<f64>>]) -> Result<Stitched> {
        let half = vec![0.5; parts.len()];
        self.stitch_weighted(parts, &half)
    }

    /// [`Stitcher::stitch`] with the loop of part `k` fixed at `parent_weight[k]` times its
    /// parent's instantiation plus `1 - parent_weight[k]` times its own (the root's entry is
    /// not used).
    pub fn stitch_weighted(&mut self, parts: &[Vec<Vector3<f64>>], parent_weight: &[f64]) -> Result<Stitched> {
        let lay = &self.layout;
        if parent_weight.len() != parts.len() || parent_weight.iter().any(|w| !(0.0..=1.0).contains(w)) {
            return Err(Error::invalid(format!(
                "stitch: {} parent weights in [0, 1] needed for {} parts",
                parent_weight.len(),
                parts.len()
            )));
        }
        if parts.len() != lay.parts.len() {
            return Err(Error::invalid(format!(
                "stitch: {} part meshes for {} parts",
                parts.len(),
                lay.parts.len()
            )));
        }
        for (k, (x, p)) in parts.iter().zip(&lay.parts).enumerate() {
            check_vertices(x, p.vertices.len(), &format!("stitch: part {k}"))?;
        }
        let n = lay.n_vertices;
        let mut aligned: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(parts.len());
        let mut alignments = Vec::with_capacity(parts.len());
        let mut loops = vec![None];
        let mut owner = vec![0usize; n];
        let mut on_loop = vec![false; n];
        let mut loop_value = vec![Vector3::zeros(); n];
        aligned.push(parts[0].clone());
        alignments.push(RigidMotion::identity());
        for k in 1..parts.len() {
            let q = lay.parts[k].parent.expect("checked");
            let band = lay.bands[k].as_ref().expect("checked");
            let at =
                |part: usize, x: &[Vector3<f64>], v: u32| x[lay.local[part][v as usize] as usize];
            let in_parent: Vec<Vector3<f64>> = band
                .vertices
                .iter()
                .map(|&v| at(q, &aligned[q], v))
                .collect();
            let in_child: Vec<Vector3<f64>> =
                band.vertices.iter().map(|&v| at(k, &parts[k], v)).collect();
            let motion = if self.align_children {
                procrustes(&in_child, &in_parent, None)
            } else {
                RigidMotion::identity()
            };
            let child = motion.apply_all(&parts[k]);
            let in_child: Vec<Vector3<f64>> =
                band.vertices.iter().map(|&v| at(k, &child, v)).collect();
            let bl = optimal_loop_in(
                &band.topology,
                &in_parent,
                &discrepancy(&in_parent, &in_child),
            )
            .map_err(|e| Error::invalid(format!("stitch: part {k}: {e}")))?;
            for &i in &bl.vertices {
                let v = band.vertices[i] as usize;
                on_loop[v] = true;
                loop_value[v] = parent_weight[k] * in_parent[i] + (1.0 - parent_weight[k]) * in_child[i];
            }
            // Child side: flood from the child-only vertices without crossing the loop.
            let mut stack: Vec<usize> = lay.parts[k]
                .vertices
                .iter()
                .map(|&v| v as usize)
                .filter(|&v| lay.local[q][v] == ABSENT && !on_loop[v])
                .collect();
            let mut seen = vec![false; n];
            stack.iter().for_each(|&v| seen[v] = true);
            while let Some(u) = stack.pop() {
                owner[u] = k;
                for &w in lay.topology.vertex_neighbors(u as u32) {
                    let w = w as usize;
                    if !seen[w] && !on_loop[w] && lay.local[k][w] != ABSENT {
                        seen[w] = true;
                        stack.push(w);
                    }
                }
            }
            let template_loop = bl
                .vertices
                .iter()
                .map(|&i| band.vertices[i] as usize)
                .collect();
            loops.push(Some(BoundaryLoop {
                vertices: template_loop,
                cost: bl.cost,
            }));
            aligned.push(child);
            alignments.push(motion);
        }

        // Source part of every face: the owner of its first vertex off the loops.
        let mut src = Vec::with_capacity(lay.faces.len());
        for (f, face) in lay.faces.iter().enumerate() {
            let v = face
                .iter()
                .map(|&v| v as usize)
                .find(|&v| !on_loop[v])
                .unwrap_or(face[0] as usize);
            let o = owner[v];
            if face.iter().any(|&v| lay.local[o][v as usize] == ABSENT) {
                return Err(Error::invalid(format!(
                    "stitch: template face {f} is not inside its source part {o}"
                )));
            }
            src.push(o);
        }
        let tri = |f: usize| {
            lay.faces[f].map(|v| aligned[src[f]][lay.local[src[f]][v as usize] as usize])
        };
        // Mixed-geometry Laplacian and the divergence of every face's own gradient.
        let mut rhs = Vec::new();
        let l = self.pattern.fill_with_own_field(tri, &mut rhs);

        let mut fixed = Vec::new();
        let mut values = Vec::new();
        for v in 0..n {
            if on_loop[v] {
                fixed.push(v);
                values.push(loop_value[v]);
            } else if !lay.in_face[v] {
                // Isolated vertex: keep it where its part puts it (or at the origin).
                let o = (0..parts.len()).find(|&p| lay.local[p][v] != ABSENT);
                fixed.push(v);
                values.push(o.map_or(Vector3::zeros(), |p| aligned[p][lay.local[p][v] as usize]));
            }
        }
        if fixed.iter().all(|&v| !lay.in_face[v]) {
            // No loop (a single part): anchor one vertex of the root.
            let v = lay.parts[0]
                .vertices
                .iter()
                .map(|&v| v as usize)
                .find(|&v| lay.in_face[v]);
            if let Some(v) = v {
                fixed.push(v);
                values.push(aligned[0][lay.local[0][v] as usize]);
            }
        }
        match self.solver.as_mut() {
            Some(s) => s.refactor_in_place(l, &fixed)?,
            None => {
                self.solver = Some(match &self.symbolic {
                    Some(s) if s.matches(l) && s.factorisation() == self.factorisation => {
                        s.factorise(l, &fixed)?
                    }
                    _ => PoissonSolver::with_factorisation(l, &fixed, self.factorisation)?,
                })
            }
        }
        let vertices = self
            .solver
            .as_ref()
            .expect("set above")
            .solve(&rhs, &values)?;
        Ok(Stitched {
            vertices,
            loops,
            alignments,
        })
    }
}

//! Assembling decoded target parts into one mesh with the target template's
//! topology (the simple rule used until the `surface` crate's stitching, paper
//! §6, is wired in).
//!
//! With `PartAlignment::Body` the decoded parts already share the
//! whole-body-aligned frame: no part is moved, overlaps are averaged.
//! With `PartAlignment::Part` every decoded part is in its own reference frame
//! (pca-fit aligns each part to the template part). The first part (the root) is kept as decoded. Then,
//! repeatedly, the unplaced part sharing the most template vertices with the
//! parts already placed (its overlap band with its parent) is rigidly aligned
//! onto them: Procrustes of the part's copies of the shared vertices onto the
//! positions they already have. Vertices covered by several parts get the mean
//! of their aligned copies.
//!
//! Finally the assembled mesh is rigidly aligned to the whole template
//! (Procrustes, as `align` does for captured frames): the world poses of the
//! placement are defined for whole-body-aligned frames, while the assembly
//! leaves the root part where its own reference is.

use mesh_core::rigid::procrustes;
use mesh_core::{Error, Result};
use nalgebra::Vector3;
use rayon::prelude::*;

use crate::part_pca::{PartAlignment, PcaModel};

/// One step of the assembly: which part, and which of its local vertices
/// anchor it on already-placed template vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblyStep {
    pub part: usize,
    /// Local indices (into the part) of the anchor vertices (empty for the root).
    pub anchor_local: Vec<usize>,
    /// Template indices of the same vertices.
    pub anchor_global: Vec<u32>,
}

/// The order in which parts are placed and their anchors.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblyPlan {
    pub n_vertices: usize,
    pub steps: Vec<AssemblyStep>,
    /// How many parts cover each template vertex.
    pub coverage: Vec<u32>,
    /// The template (from the parts' references), for the final alignment.
    pub template: Vec<Vector3<f64>>,
    /// The vertices the final alignment fits on (the PCA model's anchor; empty: all).
    pub anchor: Vec<u32>,
}

impl AssemblyPlan {
    /// `mesh` brought back to the template frame on the anchor vertices, as `align` does.
    pub fn to_template_frame(&self, mesh: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        crate::align::fit_on(mesh, &self.template, &self.anchor).apply_all(mesh)
    }
}

/// Plans the assembly of `pca`'s parts; every template vertex must be in a
/// part and every non-root part must share at least 3 vertices with the others.
pub fn plan(pca: &PcaModel) -> Result<AssemblyPlan> {
    let n = pca.n_vertices;
    let mut coverage = vec![0u32; n];
    for p in &pca.parts {
        for &v in &p.vertices {
            let v = v as usize;
            if v >= n {
                return Err(Error::invalid(format!(
                    "part '{}' has vertex {v} beyond the {n} template vertices",
                    p.name
                )));
            }
            coverage[v] += 1;
        }
    }
    if let Some(v) = coverage.iter().position(|&c| c == 0) {
        return Err(Error::invalid(format!("template vertex {v} is in no part")));
    }
    let mut template = vec![Vector3::zeros(); n];
    for p in &pca.parts {
        for (&v, r) in p.vertices.iter().zip(&p.reference) {
            template[v as usize] = *r;
        }
    }
    let mut placed = vec![false; n];
    let mut done = vec![false; pca.parts.len()];
    let mut steps = Vec::with_capacity(pca.parts.len());
    let Some(root) = pca.parts.first() else {
        return Err(Error::invalid("the PCA model has no parts"));
    };
    for &v in &root.vertices {
        placed[v as usize] = true;
    }
    done[0] = true;
    steps.push(AssemblyStep {
        part: 0,
        anchor_local: Vec::new(),
        anchor_global: Vec::new(),
    });
    while steps.len() < pca.parts.len() {
        let best = pca
            .parts
            .iter()
            .enumerate()
            .filter(|(k, _)| !done[*k])
            .map(|(k, p)| {
                (
                    k,
                    p.vertices.iter().filter(|&&v| placed[v as usize]).count(),
                )
            })
            .max_by_key(|&(k, c)| (c, std::cmp::Reverse(k)))
            .expect("an unplaced part remains");
        let (k, shared) = best;
        if shared < 3 {
            return Err(Error::invalid(format!(
                "part '{}' shares {shared} vertices with the parts placed before it (need 3 to align it)",
                pca.parts[k].name
            )));
        }
        let part = &pca.parts[k];
        let (anchor_local, anchor_global) = part
            .vertices
            .iter()
            .enumerate()
            .filter(|(_, &v)| placed[v as usize])
            .map(|(i, &v)| (i, v))
            .unzip();
        for &v in &part.vertices {
            placed[v as usize] = true;
        }
        done[k] = true;
        steps.push(AssemblyStep {
            part: k,
            anchor_local,
            anchor_global,
        });
    }
    Ok(AssemblyPlan {
        n_vertices: n,
        steps,
        coverage,
        template,
        anchor: pca.anchor.clone(),
    })
}

/// Assembles one frame from its decoded parts (`parts[k]` in part-local order).
pub fn assemble_frame(
    plan: &AssemblyPlan,
    pca: &PcaModel,
    parts: &[&[Vector3<f64>]],
) -> Vec<Vector3<f64>> {
    let n = plan.n_vertices;
    let mut first: Vec<Option<Vector3<f64>>> = vec![None; n];
    let mut sum = vec![Vector3::zeros(); n];
    for step in &plan.steps {
        let verts = parts[step.part];
        let index = &pca.parts[step.part].vertices;
        let motion = if step.anchor_local.is_empty() || pca.alignment == PartAlignment::Body {
            mesh_core::rigid::RigidMotion::identity()
        } else {
            let src: Vec<Vector3<f64>> = step.anchor_local.iter().map(|&i| verts[i]).collect();
            let dst: Vec<Vector3<f64>> = step
                .anchor_global
                .iter()
                .map(|&v| first[v as usize].expect("anchor placed"))
                .collect();
            procrustes(&src, &dst, None)
        };
        for (p, &v) in verts.iter().zip(index) {
            let q = motion.apply(p);
            let v = v as usize;
            if first[v].is_none() {
                first[v] = Some(q);
            }
            sum[v] += q;
        }
    }
    let mean: Vec<Vector3<f64>> = sum
        .iter()
        .zip(&plan.coverage)
        .map(|(s, &c)| s / c as f64)
        .collect();
    plan.to_template_frame(&mean)
}

/// Assembles every frame: `decoded[part][frame]` as from `PcaModel::decode`.
pub fn assemble(
    plan: &AssemblyPlan,
    pca: &PcaModel,
    decoded: &[Vec<Vec<Vector3<f64>>>],
) -> Vec<Vec<Vector3<f64>>> {
    let n_frames = decoded.first().map_or(0, |d| d.len());
    (0..n_frames)
        .into_par_iter()
        .map(|f| {
            let parts: Vec<&[Vector3<f64>]> = decoded.iter().map(|d| d[f].as_slice()).collect();
            assemble_frame(plan, pca, &parts)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::part_pca::PartPca;
    use gp::pca::{Components, Pca};
    use mesh_core::rigid::{so3_exp, RigidMotion};
    use nalgebra::DMatrix;

    /// Parts cut from one mesh, each moved by its own rigid motion (as PCA
    /// decoding leaves them in their reference frames), assemble back into
    /// the mesh, exactly, in the template's frame.
    #[test]
    fn reassembles_rigidly_moved_parts() {
        let (mesh, l) = mesh_core::shapes::capsule_body(12, 8, 0.2, 2.0);
        let n = mesh.n_vertices();
        let ring = |r: usize| l.ring(l.body_ring(r))[0] as usize;
        // torso: up to body ring 7; limb: from body ring 4 up; tip: from ring 9 up.
        let torso: Vec<u32> = (0..n as u32).filter(|&v| (v as usize) < ring(8)).collect();
        let limb: Vec<u32> = (0..n as u32)
            .filter(|&v| (v as usize) >= ring(4) && (v as usize) < ring(10))
            .collect();
        let tip: Vec<u32> = (0..n as u32).filter(|&v| (v as usize) >= ring(9)).collect();
        let dummy = Pca::fit(
            &DMatrix::from_fn(2, 3, |i, j| (i + j) as f64),
            Components::Count(1),
        )
        .unwrap();
        let part = |name: &str, vs: &Vec<u32>| PartPca {
            name: name.into(),
            vertices: vs.clone(),
            reference: vs.iter().map(|&v| mesh.vertices[v as usize]).collect(),
            pca: dummy.clone(),
        };
        // The tip is listed before the limb: the plan must place the limb first.
        let pca = PcaModel {
            n_vertices: n,
            parts: vec![
                part("torso", &torso),
                part("tip", &tip),
                part("limb", &limb),
            ],
            alignment: PartAlignment::Part,
            anchor: Vec::new(),
            template_sha256: String::new(),
        };
        let plan = plan(&pca).unwrap();
        assert_eq!(
            plan.steps.iter().map(|s| s.part).collect::<Vec<_>>(),
            vec![0, 2, 1]
        );
        // A deformed frame: bend the upper half.
        let frame: Vec<Vector3<f64>> = mesh
            .vertices
            .iter()
            .map(|v| {
                if v.y > 1.0 {
                    so3_exp(&Vector3::new(0.0, 0.0, 0.4)) * (v - Vector3::new(0.0, 1.0, 0.0))
                        + Vector3::new(0.0, 1.0, 0.0)
                } else {
                    *v
                }
            })
            .collect();
        let moves = [
            RigidMotion::new(
                so3_exp(&Vector3::new(0.1, 0.2, 0.3)),
                Vector3::new(1.0, 2.0, 3.0),
            ),
            RigidMotion::new(
                so3_exp(&Vector3::new(-0.5, 0.0, 0.1)),
                Vector3::new(0.0, -2.0, 0.5),
            ),
            RigidMotion::new(
                so3_exp(&Vector3::new(0.0, 1.0, 0.0)),
                Vector3::new(0.3, 0.0, 0.0),
            ),
        ];
        let parts: Vec<Vec<Vector3<f64>>> = pca
            .parts
            .iter()
            .zip(&moves)
            .map(|(p, m)| {
                p.vertices
                    .iter()
                    .map(|&v| m.apply(&frame[v as usize]))
                    .collect()
            })
            .collect();
        let refs: Vec<&[Vector3<f64>]> = parts.iter().map(|p| p.as_slice()).collect();
        let out = assemble_frame(&plan, &pca, &refs);
        // Same shape as the frame, in the template's frame: equal to the frame
        // aligned to the template.
        let want = procrustes(&frame, &mesh.vertices, None).apply_all(&frame);
        for (a, b) in out.iter().zip(&want) {
            assert!((a - b).norm() < 1e-9, "{a} vs {b}");
        }
    }

    #[test]
    fn rejects_parts_that_do_not_overlap() {
        let dummy = Pca::fit(
            &DMatrix::from_fn(2, 3, |i, j| (i + j) as f64),
            Components::Count(1),
        )
        .unwrap();
        let p = |name: &str, vs: Vec<u32>| PartPca {
            name: name.into(),
            reference: vec![Vector3::zeros(); vs.len()],
            vertices: vs,
            pca: dummy.clone(),
        };
        let pca = PcaModel {
            n_vertices: 6,
            parts: vec![p("a", vec![0, 1, 2]), p("b", vec![3, 4, 5])],
            alignment: PartAlignment::Part,
            anchor: Vec::new(),
            template_sha256: String::new(),
        };
        assert!(plan(&pca)
            .unwrap_err()
            .to_string()
            .contains("part 'b' shares 0 vertices"));
    }
}

//! How far two sets of curves agree: the fraction of template vertices that
//! the two segmentations give the same part (a vertex in an overlap band
//! counts as the child part, [`mesh_core::segmentation::Segmentation::vertex_labels`]).

use anyhow::Result;
use mesh_core::capture_set::SubjectSpec;
use mesh_core::TriMesh;

/// Per part `(name, agreement)` and the whole-mesh agreement, in `[0, 1]`.
pub fn vertex_agreement(mesh: &TriMesh, a: &SubjectSpec, b: &SubjectSpec) -> Result<(Vec<(String, f64)>, f64)> {
    let (sa, sb) = (mesh_core::segmentation::segment(mesh, a)?, mesh_core::segmentation::segment(mesh, b)?);
    let name = |s: &mesh_core::segmentation::Segmentation, l: usize| s.parts[l].name.clone();
    let (la, lb) = (sa.vertex_labels(), sb.vertex_labels());
    let la: Vec<String> = la.iter().map(|&l| name(&sa, l)).collect();
    let lb: Vec<String> = lb.iter().map(|&l| name(&sb, l)).collect();
    let same = la.iter().zip(&lb).filter(|(x, y)| x == y).count();
    let mut per = Vec::new();
    for p in &sa.parts {
        // Agreement on the union of the vertices either gives this part (intersection over union).
        let inter = la.iter().zip(&lb).filter(|(x, y)| **x == p.name && **y == p.name).count();
        let union = la.iter().zip(&lb).filter(|(x, y)| **x == p.name || **y == p.name).count();
        per.push((p.name.clone(), inter as f64 / union.max(1) as f64));
    }
    Ok((per, same as f64 / la.len().max(1) as f64))
}

//! Seam quality of written variations without a ground truth: every edge of the body is compared
//! with the model's template, split into the overlap bands where parts are merged (both
//! endpoints in two or more parts: averaged or Poisson-stitched, 3DV §6) and the rest.
//!
//! Per variation: mean |ln(l / l_template)| over the edges (as `metrics::edge_distortion`) and
//! mean |θ − θ_template| over the interior edges, θ the dihedral angle between the two faces'
//! normals, seam / band border (one endpoint in a band) / elsewhere. A crease left by averaging raises the seam's dihedral figure
//! above the rest's; the sources (the training sequences) give the level of the captures.
//!
//! Usage: seam_check GROUP MODEL DIR... (DIR = hmc-sample --out; one line per sequence and DIR,
//! means over its variations)

use clap::Parser;
use std::collections::HashMap;

use mesh_core::artifact::Artifact;
use mesh_core::sequence::MeshSequence;
use nalgebra::Vector3;
use variation::group::Group;
use variation::train::VariationModel;

/// Edge log ratios (seam, border, elsewhere) then dihedral deviations (same order) of a sequence.
fn measure(
    frames: &[Vec<Vector3<f64>>],
    template: &[Vector3<f64>],
    faces: &[[u32; 3]],
    edges: &[(u32, u32, usize, Option<usize>)],
    band: &[bool],
) -> [f64; 6] {
    let normal = |p: &[Vector3<f64>], f: usize| {
        let [a, b, c] = faces[f].map(|i| p[i as usize]);
        (b - a).cross(&(c - a)).normalize()
    };
    let angle = |p: &[Vector3<f64>], fa: usize, fb: usize| normal(p, fa).dot(&normal(p, fb)).clamp(-1.0, 1.0).acos();
    let (mut s, mut n) = ([0.0; 6], [0usize; 6]);
    for p in frames {
        for &(u, v, fa, fb) in edges {
            let k = match (band[u as usize], band[v as usize]) {
                (true, true) => 0,
                (false, false) => 2,
                _ => 1,
            };
            let l = (p[u as usize] - p[v as usize]).norm();
            let lt = (template[u as usize] - template[v as usize]).norm();
            s[k] += (l / lt).ln().abs();
            n[k] += 1;
            if let Some(fb) = fb {
                s[3 + k] += (angle(p, fa, fb) - angle(template, fa, fb)).abs();
                n[3 + k] += 1;
            }
        }
    }
    std::array::from_fn(|i| s[i] / n[i].max(1) as f64)
}

/// Seams of written variations: edge log ratios to the template inside the bands and on their
/// border, one line per sequence and folder.
#[derive(Parser)]
struct Cli {
    /// The prealigned group (prealign's output).
    group: String,
    /// The variation model (gpdm-train's output).
    model: String,
    /// Variation folders (hmc-sample --out).
    #[arg(required = true)]
    dirs: Vec<String>,
}

fn main() -> mesh_core::Result<()> {
    let cli = Cli::parse();
    let group = Group::load(&cli.group)?;
    let model = VariationModel::load(&cli.model)?;
    let mut count = vec![0u8; model.template.len()];
    for p in &model.parts {
        for &v in &p.part.vertices {
            count[v as usize] = count[v as usize].saturating_add(1);
        }
    }
    let band: Vec<bool> = count.iter().map(|&c| c >= 2).collect();
    let mut by_edge: HashMap<(u32, u32), (usize, Option<usize>)> = HashMap::new();
    for (f, t) in model.faces.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            by_edge.entry((u, v)).and_modify(|e| e.1 = Some(f)).or_insert((f, None));
        }
    }
    let mut edges: Vec<_> = by_edge.into_iter().map(|((u, v), (fa, fb))| (u, v, fa, fb)).collect();
    edges.sort_unstable();
    println!(
        "band vertices {} of {}; columns: edge log ratio seam / border / elsewhere, dihedral deviation (rad) seam / border / elsewhere",
        band.iter().filter(|&&b| b).count(),
        band.len()
    );
    for s in &group.sequences {
        let q = measure(&s.motion.world_frames(), &model.template, &model.faces, &edges, &band);
        println!("{:<12} source {:.4} / {:.4} / {:.4}  {:.4} / {:.4} / {:.4}", s.name, q[0], q[1], q[2], q[3], q[4], q[5]);
    }
    for dir in &cli.dirs {
        let mut seqs: Vec<_> = std::fs::read_dir(dir).expect("an hmc-sample --out folder").filter_map(|e| e.ok()).filter(|e| e.path().is_dir()).collect();
        seqs.sort_by_key(|e| e.file_name());
        for e in seqs {
            let mut sum = [0.0; 6];
            let mut k = 0;
            while let Ok(v) = MeshSequence::load_dir(e.path().join(format!("var{k}"))) {
                let q = measure(&v.frames, &model.template, &model.faces, &edges, &band);
                (0..6).for_each(|i| sum[i] += q[i]);
                k += 1;
            }
            let m = |i: usize| sum[i] / k.max(1) as f64;
            println!(
                "{:<12} {dir} ({k} var) {:.4} / {:.4} / {:.4}  {:.4} / {:.4} / {:.4}",
                e.file_name().to_string_lossy(),
                m(0),
                m(1),
                m(2),
                m(3),
                m(4),
                m(5)
            );
        }
    }
    Ok(())
}

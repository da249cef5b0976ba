//! Which part's error costs most: the raw transfer (parts assembled, no §6, limb orientation
//! applied as gpr-predict does) with one part at a time replaced by the truth's part (in the root
//! frame), and the pose error of each against the truth.
//!
//! cargo run --release --example part_oracle -- WORK SET SOURCE TARGET MOTION

use capture::align::{align_motion_on, AlignedMotion};
use capture::assemble::{assemble, plan};
use capture::part_pca::PcaModel;
use mesh_core::artifact::Artifact;
use mesh_core::sequence::MeshSequence;
use transfer::gpr_model::GprModel;
use transfer::limb_orientation::{apply, limbs, orientation, reference, turn_to};
use nalgebra::Vector3;
use transfer::reconstruct::rows_to_meshes;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let [_, work, set, s, t, m] = &a[..] else {
        anyhow::bail!("usage: part_oracle WORK SET SOURCE TARGET MOTION");
    };
    let model = GprModel::load(format!("{work}/models/{s}-to-{t}/gpr-nn.model"))?;
    let (spca, tpca) = (PcaModel::load(format!("{work}/{s}/pca.model"))?, PcaModel::load(format!("{work}/{t}/pca.model"))?);
    let motion = AlignedMotion::load(format!("{work}/{s}/{m}.aligned"))?;
    let template = mesh_core::io::read_mesh(format!("{set}/{t}/walk/000000.ply"))?;
    let truth = align_motion_on(&template, &MeshSequence::load_dir(format!("{set}/truth/{t}/{m}"))?, &tpca.anchor)?;
    let truth_parts: Vec<_> = tpca.part_rows(&truth)?.iter().map(rows_to_meshes).collect();
    let xs = spca.encode(&motion)?;
    let xd = transfer::predict::displacement_matrix(&motion.displacements);
    let mut pred = tpca.decode(&transfer::predict::predict(&model, &xs, &xd, false)?.coeffs)?;
    if let Some(o) = &model.orientation {
        apply(o, &spca, &tpca, &xs, &mut pred)?;
    }
    let plan = plan(&tpca)?;
    let truth_seq = MeshSequence::new(template.faces.clone(), truth.frames.clone());
    let score = |parts: &Vec<_>| -> anyhow::Result<f64> {
        let p = MeshSequence::new(template.faces.clone(), assemble(&plan, &tpca, parts));
        Ok(100.0 * transfer::evaluate::rms_errors(&p, &truth_seq)?.0)
    };
    println!("{s}->{t} {m} transfer: {:.2} cm", score(&pred)?);
    // Oracles of the limbs' orientation: the proximal half turned to the truth's (as
    // limb_oracle), then also the distal half turned about the elbow/knee to the truth's.
    let mut prox = pred.clone();
    let mut both = pred.clone();
    for limb in limbs(&tpca)? {
        let mean = reference(&tpca, limb.part);
        let n = mean.len();
        let distal: Vec<usize> = (0..n).filter(|i| limb.proximal.binary_search(i).is_err()).collect();
        // The elbow: the proximal vertices farthest from the joint (the last tenth).
        let pivot_of = |f: &[Vector3<f64>]| {
            let jc = limb.joint.iter().map(|&i| f[i]).sum::<Vector3<f64>>() / limb.joint.len() as f64;
            let mut d: Vec<(f64, usize)> = limb.proximal.iter().map(|&i| ((mean[i] - jc).norm(), i)).collect();
            d.sort_by(|a, b| b.0.total_cmp(&a.0));
            let k = (d.len() / 5).max(1);
            d[..k].iter().map(|&(_, i)| f[i]).sum::<Vector3<f64>>() / k as f64
        };
        for ((fp, fb), tr) in prox[limb.part].iter_mut().zip(both[limb.part].iter_mut()).zip(&truth_parts[limb.part]) {
            let want = orientation(&mean, tr, &limb.proximal);
            let now = orientation(&mean, fp, &limb.proximal);
            turn_to(fp, &limb, &now, &want);
            turn_to(fb, &limb, &now, &want);
            let dn = orientation(&mean, fb, &distal);
            let dw = orientation(&mean, tr, &distal);
            let turn = dw * dn.inverse();
            let pivot = pivot_of(fb);
            for &i in &distal {
                fb[i] = pivot + turn * (fb[i] - pivot);
            }
        }
    }
    println!("{s}->{t} {m} truth's proximal orientation: {:.2} cm", score(&prox)?);
    println!("{s}->{t} {m} truth's proximal and distal orientation: {:.2} cm", score(&both)?);
    for (k, part) in tpca.parts.iter().enumerate() {
        let mut o = pred.clone();
        o[k] = truth_parts[k].clone();
        println!("{s}->{t} {m} truth's {}: {:.2} cm", part.name, score(&o)?);
    }
    Ok(())
}

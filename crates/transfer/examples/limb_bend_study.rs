//! A second, distal orientation map per limb (the elbow's and knee's bend), scored on the raw
//! transfer (parts assembled, no §6) after the default limb orientation (docs/RESULTS.md,
//! study 6). The distal half of a limb (the vertices farther from its joint than the proximal
//! half) has a rotation relative to the proximal half's; an affine map of that relative
//! log-rotation, source to target, is fitted on the training pairs like the proximal map
//! (ridge 0.1 toward the identity), and at prediction the distal half is turned about the
//! elbow (the proximal vertices farthest from the joint, the last fifth) by the geodesic weight
//! w toward the map's bend, ramped in smoothly over the vertices between 40 % and 60 % of the
//! limb's distance ranks.
//!
//! cargo run --release --example limb_bend_study -- WORK SET SOURCE TARGET MOTION... -- TRAIN...

#[path = "common/study_pairs.rs"]
mod study_pairs;

use capture::align::{align_motion_on, AlignedMotion};
use capture::assemble::{assemble, plan};
use capture::part_pca::PcaModel;
use mesh_core::artifact::Artifact;
use mesh_core::rigid::{so3_exp, so3_log};
use mesh_core::sequence::MeshSequence;
use nalgebra::{DMatrix, Rotation3, Vector3};
use transfer::gpr_model::{training_set, GprModel};
use transfer::limb_orientation::{apply, limbs, orientation, reference, Limb, LimbMap};

fn points(flat: &[f64]) -> Vec<Vector3<f64>> {
    flat.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect()
}

fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// A limb's distal half, the rank of every vertex by distance from the joint in the mean shape
/// (0 nearest, 1 farthest), and its elbow vertices.
struct Bend {
    distal: Vec<usize>,
    rank: Vec<f64>,
    elbow: Vec<usize>,
}

fn bend(limb: &Limb, mean: &[Vector3<f64>]) -> Bend {
    let n = mean.len();
    let jc = limb.joint.iter().map(|&i| mean[i]).sum::<Vector3<f64>>() / limb.joint.len() as f64;
    let mut order: Vec<(f64, usize)> = mean.iter().enumerate().map(|(i, p)| ((p - jc).norm(), i)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut rank = vec![0.0; n];
    for (r, &(_, i)) in order.iter().enumerate() {
        rank[i] = r as f64 / (n - 1).max(1) as f64;
    }
    let distal: Vec<usize> = (0..n).filter(|i| limb.proximal.binary_search(i).is_err()).collect();
    let mut prox: Vec<(f64, usize)> = limb.proximal.iter().map(|&i| (rank[i], i)).collect();
    prox.sort_by(|a, b| b.0.total_cmp(&a.0));
    let elbow = prox.iter().take((prox.len() / 5).max(1)).map(|x| x.1).collect();
    Bend { distal, rank, elbow }
}

/// The distal half's rotation relative to the proximal half's.
fn relative(mean: &[Vector3<f64>], frame: &[Vector3<f64>], limb: &Limb, b: &Bend) -> Rotation3<f64> {
    orientation(mean, frame, &limb.proximal).inverse() * orientation(mean, frame, &b.distal)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let split = args.iter().position(|a| a == "--").ok_or_else(|| anyhow::anyhow!("usage: see the file"))?;
    let [work, set, s, t] = [&args[1], &args[2], &args[3], &args[4]];
    let tests = &args[5..split];
    let train = &args[split + 1..];
    let (spca, tpca) = (PcaModel::load(format!("{work}/{s}/pca.model"))?, PcaModel::load(format!("{work}/{t}/pca.model"))?);
    let model = GprModel::load(format!("{work}/models/{s}-to-{t}/gpr-nn.model"))?;
    let (pairs, _) = study_pairs::load(work, set, s, t, &spca, &tpca, train)?;
    let rows = training_set(&pairs, 1.0, false)?;
    let template = mesh_core::io::read_mesh(format!("{set}/{t}/walk/000000.ply"))?;
    let plan = plan(&tpca)?;
    let (ls, lt) = (limbs(&spca)?, limbs(&tpca)?);
    let weights = [0.0, 0.25, 0.5, 0.75, 1.0];
    let bends = |pca: &PcaModel, limb: &Limb, coeffs: &DMatrix<f64>| -> Vec<Vector3<f64>> {
        let mean = reference(pca, limb.part);
        let b = bend(limb, &mean);
        let decoded = pca.parts[limb.part].pca.decode(coeffs).unwrap();
        (0..decoded.nrows())
            .map(|r| {
                let row: Vec<f64> = decoded.row(r).iter().copied().collect();
                so3_log(&relative(&mean, &points(&row), limb, &b))
            })
            .collect()
    };
    // One map per limb, from the training pairs.
    let maps: Vec<LimbMap> = ls
        .iter()
        .zip(&lt)
        .map(|(sl, tl)| LimbMap::fit(&bends(&spca, sl, &rows.x_parts[sl.part]), &bends(&tpca, tl, &rows.y_parts[tl.part]), 0.1))
        .collect::<Result<_, _>>()?;
    let mut totals = vec![(0.0f64, 0usize); weights.len()];
    for m in tests {
        let motion = AlignedMotion::load(format!("{work}/{s}/{m}.aligned"))?;
        let truth = align_motion_on(&template, &MeshSequence::load_dir(format!("{set}/truth/{t}/{m}"))?, &tpca.anchor)?;
        let truth_seq = MeshSequence::new(template.faces.clone(), truth.frames.clone());
        let xs = spca.encode(&motion)?;
        let xd = transfer::predict::displacement_matrix(&motion.displacements);
        let mut base = tpca.decode(&transfer::predict::predict(&model, &xs, &xd, false)?.coeffs)?;
        if let Some(o) = &model.orientation {
            apply(o, &spca, &tpca, &xs, &mut base)?;
        }
        print!("{s}->{t} {m}:");
        for (wi, &w) in weights.iter().enumerate() {
            let mut turned = base.clone();
            for ((sl, tl), map) in ls.iter().zip(&lt).zip(&maps) {
                let k = tl.part;
                let tmean = reference(&tpca, k);
                let b = bend(tl, &tmean);
                let src = bends(&spca, sl, &xs[k]);
                for (frame, x) in turned[k].iter_mut().zip(&src) {
                    let prox = orientation(&tmean, frame, &tl.proximal);
                    let now = relative(&tmean, frame, tl, &b);
                    let want = now * so3_exp(&(w * so3_log(&(now.inverse() * so3_exp(&map.apply(x))))));
                    // World turn of the distal half, ramped in across the elbow.
                    let turn = so3_log(&(prox * want * now.inverse() * prox.inverse()));
                    let pivot = b.elbow.iter().map(|&i| frame[i]).sum::<Vector3<f64>>() / b.elbow.len() as f64;
                    for (i, p) in frame.iter_mut().enumerate() {
                        let a = smoothstep((b.rank[i] - 0.4) / 0.2);
                        if a > 0.0 {
                            *p = pivot + so3_exp(&(turn * a)) * (*p - pivot);
                        }
                    }
                }
            }
            let pred = MeshSequence::new(template.faces.clone(), assemble(&plan, &tpca, &turned));
            let e = transfer::evaluate::rms_errors(&pred, &truth_seq)?.0;
            totals[wi].0 += e * e * base[0].len() as f64;
            totals[wi].1 += base[0].len();
            print!(" w{w} {:.2}", 100.0 * e);
        }
        println!();
    }
    print!("pooled:");
    for (wi, w) in weights.iter().enumerate() {
        print!(" w{w} {:.3}", 100.0 * (totals[wi].0 / totals[wi].1 as f64).sqrt());
    }
    println!();
    Ok(())
}

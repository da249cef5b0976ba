//! How well the limb orientation map (`transfer::limb_orientation`, root frame) fits and
//! predicts (docs/studies/06-limb-orientation.md). Per limb: the map's RMS angle on its training
//! pairs (and
//! the identity's), its coefficients; per test motion: the mean log-rotations of the source,
//! the truth, the GP and the map, the RMS angle of the GP's, the map's and the half-way
//! orientation against the truth's, the source's distance to the nearest training orientation,
//! and how far the pose GP's attachment region (the 20 % of root vertices nearest the joint)
//! is from the truth's.
//!
//! cargo run --release -p studies --bin limb_map_diag -- WORK SET SOURCE TARGET MOTION... -- TRAIN...
//! (`--true-pairs`: trained on the set's true correspondences)

use studies::study_pairs;

use capture::align::align_motion_on;
use mesh_core::rigid::{so3_exp, so3_log};
use mesh_core::sequence::MeshSequence;
use nalgebra::{Rotation3, Vector3};
use transfer::gpr_model::training_set;
use transfer::limb_orientation::{limbs, orientation, reference, LimbMap, RIDGE};
use transfer::reconstruct::rows_to_meshes;

fn points(flat: &[f64]) -> Vec<Vector3<f64>> {
    flat.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect()
}
fn ang(a: &Rotation3<f64>, b: &Rotation3<f64>) -> f64 {
    so3_log(&(a.inverse() * b)).norm().to_degrees()
}

fn main() -> anyhow::Result<()> {
    let study = study_pairs::Study::from_command_line(
        env!("CARGO_BIN_NAME"),
        "How well the limb orientation map fits its training pairs and predicts each test motion (docs/studies/06-limb-orientation.md)",
    )?;
    let study_pairs::Study { work, set, s, t, tests, train, spca, tpca, model, template, true_pairs } = &study;
    let (pairs, _) = study_pairs::load(work, set, s, t, spca, tpca, train, *true_pairs)?;
    let rows = training_set(&pairs, 1.0, false)?;
    let (ls, lt) = (limbs(spca)?, limbs(tpca)?);
    for (sl, tl) in ls.iter().zip(&lt) {
        let k = sl.part;
        let (sm, tm) = (reference(spca, k), reference(tpca, k));
        let feat = |pca: &capture::part_pca::PcaModel, mean: &[Vector3<f64>], prox: &[usize], c: &nalgebra::DMatrix<f64>| -> Vec<Vector3<f64>> {
            let d = pca.parts[k].pca.decode(c).unwrap();
            (0..d.nrows()).map(|r| { let row: Vec<f64> = d.row(r).iter().copied().collect(); so3_log(&orientation(mean, &points(&row), prox)) }).collect()
        };
        let xf = feat(spca, &sm, &sl.proximal, &rows.x_parts[k]);
        let yf = feat(tpca, &tm, &tl.proximal, &rows.y_parts[k]);
        let map = LimbMap::fit(&xf, &yf, RIDGE)?;
        let res: f64 = xf.iter().zip(&yf).map(|(x, y)| ang(&so3_exp(&map.apply(x)), &so3_exp(y)).powi(2)).sum::<f64>() / xf.len() as f64;
        let ident: f64 = xf.iter().zip(&yf).map(|(x, y)| ang(&so3_exp(x), &so3_exp(y)).powi(2)).sum::<f64>() / xf.len() as f64;
        let mut na: Vec<f64> = xf.iter().chain(&yf).map(|v| v.norm().to_degrees()).collect();
        na.sort_by(f64::total_cmp);
        let q = |p: f64| na[((na.len() - 1) as f64 * p) as usize];
        let big = xf.iter().zip(&yf).filter(|(x, y)| ang(&so3_exp(&map.apply(x)), &so3_exp(y)) > 30.0).count();
        println!("   |log| percentiles 50/90/99/max: {:.0} {:.0} {:.0} {:.0} deg; pairs off by > 30 deg: {big} of {}", q(0.5), q(0.9), q(0.99), q(1.0), xf.len());
        let xmean = xf.iter().sum::<Vector3<f64>>() / xf.len() as f64;
        let xsd = (xf.iter().map(|x| (x - xmean).component_mul(&(x - xmean))).sum::<Vector3<f64>>() / xf.len() as f64).map(|v| v.sqrt().to_degrees());
        println!("{s}->{t} part {} train: map rms {:.1} deg, identity {:.1}; x sd {:.1} {:.1} {:.1} deg; W {:?}", tpca.parts[k].name, res.sqrt(), ident.sqrt(), xsd.x, xsd.y, xsd.z,
            map.w.iter().map(|r| r.iter().map(|v| (v * 100.0).round() / 100.0).collect::<Vec<_>>()).collect::<Vec<_>>());
        for m in tests {
            let tmn = study.test_motion(m)?;
            let truth = align_motion_on(template, &MeshSequence::load_dir(format!("{set}/truth/{t}/{m}"))?, &tpca.anchor)?;
            let tp: Vec<_> = tpca.part_rows(&truth)?.iter().map(rows_to_meshes).collect();
            let gp = tpca.decode(&transfer::predict::predict(model, &tmn.xs, &tmn.xd, false)?.coeffs)?;
            let src = feat(spca, &sm, &sl.proximal, &tmn.xs[k]);
            let (mut eg, mut em, mut eh, mut dmin) = (0.0, 0.0, 0.0, 0.0);
            let (mut ms, mut mt, mut mg, mut mm) = (Vector3::zeros(), Vector3::zeros(), Vector3::zeros(), Vector3::zeros());
            let n = src.len();
            for f in 0..n {
                let rt = orientation(&tm, &tp[k][f], &tl.proximal);
                let rg = orientation(&tm, &gp[k][f], &tl.proximal);
                let rm = so3_exp(&map.apply(&src[f]));
                let rh = rg * so3_exp(&(0.5 * so3_log(&(rg.inverse() * rm))));
                ms += src[f]; mt += so3_log(&rt); mg += so3_log(&rg); mm += so3_log(&rm);
                eg += ang(&rg, &rt).powi(2); em += ang(&rm, &rt).powi(2); eh += ang(&rh, &rt).powi(2);
                dmin += xf.iter().map(|x| (x - src[f]).norm()).fold(f64::INFINITY, f64::min).to_degrees();
            }
            let r = |e: f64| (e / n as f64).sqrt();
            {
                // The attachment region (the 20 % of root vertices nearest the joint): the GP's against the truth's.
                let rm = reference(tpca, 0);
                let joint = tl.joint.iter().map(|&i| tm[i]).sum::<Vector3<f64>>() / tl.joint.len() as f64;
                let mut d: Vec<(f64, usize)> = rm.iter().enumerate().map(|(i, p)| ((p - joint).norm(), i)).collect();
                d.sort_by(|a, b| a.0.total_cmp(&b.0));
                let near: Vec<usize> = d.iter().take((rm.len() as f64 * 0.2).ceil() as usize).map(|x| x.1).collect();
                let (mut e, mut spread) = (0.0, 0.0);
                for f in 0..n {
                    let (a, b) = (orientation(&rm, &gp[0][f], &near), orientation(&rm, &tp[0][f], &near));
                    e += ang(&a, &b).powi(2);
                    spread += so3_log(&b).norm().to_degrees().powi(2);
                }
                println!("   {m}: attachment region angle rms GP vs truth {:.1} deg; truth's own rms turn {:.1} deg", r(e), r(spread));
            }
            let d = |v: Vector3<f64>| format!("({:.0} {:.0} {:.0})", v.x.to_degrees() / n as f64, v.y.to_degrees() / n as f64, v.z.to_degrees() / n as f64);
            println!("   {m}: mean log-rotation, deg: source {} truth {} GP {} map {}", d(ms), d(mt), d(mg), d(mm));
            println!("   {m}: angle rms GP {:.1} map {:.1} half {:.1}; source's mean distance to nearest training orientation {:.1} deg", r(eg), r(em), r(eh), dmin / n as f64);
        }
    }
    Ok(())
}

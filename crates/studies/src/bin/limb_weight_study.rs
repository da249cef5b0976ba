//! How far to turn each limb from the GP's orientation toward the map's, chosen from the training
//! data alone: leave one training motion out, train the model (default settings) and the limb maps
//! on the others, predict the held-out motion's pairs, and take per limb the geodesic weight
//! `w` with the least RMS angle to the held-out target's orientation. The weights are then scored
//! on the run's test motions (raw transfer, parts assembled, no §6) beside the fixed default
//! (docs/studies/06-limb-orientation.md).
//!
//! cargo run --release -p studies --bin limb_weight_study -- WORK SET SOURCE TARGET MOTION... -- TRAIN...
//! e.g. `limb_weight_study out/demo-run/work out/demo/set A B punch spinkick cmu_jump -- walk run jump kick dance`

use studies::study_pairs;

use capture::assemble::{assemble, plan};
use capture::part_pca::PcaModel;
use gp::gpr::GprOptions;
use mesh_core::rigid::{so3_exp, so3_log};
use mesh_core::sequence::MeshSequence;
use nalgebra::{DMatrix, Rotation3, Vector3};
use transfer::gpr_model::{train, training_set, MeanFunction, MeanPriors, Method, MEAN_RIDGE, PRIOR_WEIGHT};
use transfer::limb_orientation::{limbs, orientation, reference, turn_to, Limb, LimbMap, RIDGE, WEIGHT};

/// The weights tried: 0, 0.05, ..., 1.
const STEPS: usize = 20;

fn points(flat: &[f64]) -> Vec<Vector3<f64>> {
    flat.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect()
}

/// Orientations of `limb` in the decoded rows `coeffs` of its part.
fn orientations(pca: &PcaModel, limb: &Limb, coeffs: &DMatrix<f64>) -> Vec<Rotation3<f64>> {
    let rows = pca.parts[limb.part].pca.decode(coeffs).expect("coefficients of the model's size");
    let mean = reference(pca, limb.part);
    (0..rows.nrows())
        .map(|r| orientation(&mean, &points(&rows.row(r).iter().copied().collect::<Vec<_>>()), &limb.proximal))
        .collect()
}

/// The geodesic point `w` of the way from `from` to `to`.
fn toward(from: &Rotation3<f64>, to: &Rotation3<f64>, w: f64) -> Rotation3<f64> {
    from * so3_exp(&(w * so3_log(&(from.inverse() * to))))
}

fn angle(a: &Rotation3<f64>, b: &Rotation3<f64>) -> f64 {
    so3_log(&(a.inverse() * b)).norm()
}

fn main() -> anyhow::Result<()> {
    let study = study_pairs::Study::from_command_line(
        env!("CARGO_BIN_NAME"),
        "Per-limb turn weights chosen by leaving one training motion out, scored on the test motions beside the fixed default (docs/studies/06-limb-orientation.md)",
    )?;
    let study_pairs::Study { work, set, s, t, tests, train: train_motions, spca, tpca, model, template, true_pairs } = &study;
    let (pairs, ratio) = study_pairs::load(work, set, s, t, &spca, &tpca, train_motions, *true_pairs)?;
    let names = model.part_names.clone();
    let maps = transfer::geometric_prior::part_priors(&spca, &tpca);
    let priors = MeanPriors { maps: &maps, ridge_toward: false, weight: PRIOR_WEIGHT };
    let (ls, lt) = (limbs(&spca)?, limbs(&tpca)?);
    let grid: Vec<f64> = (0..=STEPS).map(|i| i as f64 / STEPS as f64).collect();

    // Leave one training motion out: squared angles per limb and weight.
    let mut squared = vec![vec![0.0f64; grid.len()]; ls.len()];
    let mut counts = vec![0usize; ls.len()];
    for fold in 0..pairs.len() {
        let others: Vec<_> = pairs.iter().enumerate().filter(|(i, _)| *i != fold).map(|(_, p)| p.clone()).collect();
        let m = train(Method::GprNn, false, MeanFunction::Affine, MEAN_RIDGE, Some(priors), &names, &others, ratio, false, &GprOptions::default())?;
        let rows = training_set(&others, ratio, false)?;
        let held = training_set(&pairs[fold..=fold], ratio, false)?;
        let predicted = transfer::predict::predict(&m, &held.x_parts, &held.x_disp, false)?.coeffs;
        for (li, (sl, tl)) in ls.iter().zip(&lt).enumerate() {
            let k = sl.part;
            let log = |r: Vec<Rotation3<f64>>| r.iter().map(so3_log).collect::<Vec<_>>();
            let map = LimbMap::fit(&log(orientations(&spca, sl, &rows.x_parts[k])), &log(orientations(&tpca, tl, &rows.y_parts[k])), RIDGE)?;
            let src = log(orientations(&spca, sl, &held.x_parts[k]));
            let gp = orientations(&tpca, tl, &predicted[k]);
            let truth = orientations(&tpca, tl, &held.y_parts[k]);
            for ((x, g), tr) in src.iter().zip(&gp).zip(&truth) {
                let mapped = so3_exp(&map.apply(x));
                for (wi, &w) in grid.iter().enumerate() {
                    squared[li][wi] += angle(&toward(g, &mapped, w), tr).powi(2);
                }
                counts[li] += 1;
            }
        }
        println!("fold {} ({}) done", fold, train_motions[fold]);
    }
    let rms_deg = |li: usize, wi: usize| (squared[li][wi] / counts[li].max(1) as f64).sqrt().to_degrees();
    let chosen: Vec<f64> = (0..ls.len())
        .map(|li| {
            let best = (0..grid.len()).min_by(|&a, &b| squared[li][a].total_cmp(&squared[li][b])).unwrap_or(0);
            grid[best]
        })
        .collect();
    for (li, l) in lt.iter().enumerate() {
        println!(
            "{s}->{t} limb {} ({}): held-out RMS angle w0 {:.1}° w0.5 {:.1}° w1 {:.1}°, best w {:.2} ({:.1}°)",
            l.part,
            names[l.part],
            rms_deg(li, 0),
            rms_deg(li, STEPS / 2),
            rms_deg(li, STEPS),
            chosen[li],
            rms_deg(li, (chosen[li] * STEPS as f64).round() as usize)
        );
    }

    // The test motions: the run's model, limbs turned at the default weight and at the chosen ones.
    let rows = training_set(&pairs, ratio, false)?;
    let plan = plan(&tpca)?;
    let mut totals = [(0.0f64, 0usize); 3];
    for mname in tests {
        let study_pairs::TestMotion { xs, xd, truth: truth_seq } = study.test_motion(mname)?;
        let gp = tpca.decode(&transfer::predict::predict(&model, &xs, &xd, false)?.coeffs)?;
        let score = |parts: &Vec<Vec<Vec<Vector3<f64>>>>| {
            let pred = MeshSequence::new(template.faces.clone(), assemble(&plan, &tpca, parts));
            transfer::evaluate::rms_errors(&pred, &truth_seq).map(|e| e.0)
        };
        let mut errors = [score(&gp)?, 0.0, 0.0];
        for (vi, weights) in [vec![WEIGHT; ls.len()], chosen.clone()].iter().enumerate() {
            let mut turned = gp.clone();
            for ((sl, tl), &w) in ls.iter().zip(&lt).zip(weights) {
                let k = sl.part;
                let log = |r: Vec<Rotation3<f64>>| r.iter().map(so3_log).collect::<Vec<_>>();
                let map = LimbMap::fit(&log(orientations(&spca, sl, &rows.x_parts[k])), &log(orientations(&tpca, tl, &rows.y_parts[k])), RIDGE)?;
                let tmean = reference(&tpca, k);
                for (frame, x) in turned[k].iter_mut().zip(log(orientations(&spca, sl, &xs[k]))) {
                    let now = orientation(&tmean, frame, &tl.proximal);
                    turn_to(frame, tl, &now, &toward(&now, &so3_exp(&map.apply(&x)), w));
                }
            }
            errors[vi + 1] = score(&turned)?;
        }
        let f = gp[0].len();
        for (total, e) in totals.iter_mut().zip(errors) {
            total.0 += e * e * f as f64;
            total.1 += f;
        }
        println!("{s}->{t} {mname}: GP {:.2} | w {WEIGHT} {:.2} | chosen {:.2}", 100.0 * errors[0], 100.0 * errors[1], 100.0 * errors[2]);
    }
    let pooled = |i: usize| 100.0 * (totals[i].0 / totals[i].1.max(1) as f64).sqrt();
    println!("{s}->{t} pooled: GP {:.3} | w {WEIGHT} {:.3} | chosen {:.3}", pooled(0), pooled(1), pooled(2));
    Ok(())
}

//! Where the surface stage gains or loses: a test motion's corrected parts merged by averaging
//! (`+correct`), by stitching (`+correct+stitch`) and by a feathered mean (`+correct+feather`),
//! with the pose error per part of each against the truth (docs/studies/03-surface-stage.md).
//!
//! cargo run --release -p studies --bin stitch_study -- WORK SET SOURCE TARGET MOTION -- TRAIN...
//!
//! With `--bend-weight W` the limbs' distal halves are also turned toward the bend map of
//! `studies::limb_bend` before the surface stage (docs/studies/06-limb-orientation.md). With
//! `--loop-weights ARM,LEG` it prints, in place of the distance-weighted loops, the stitch with the
//! arms' and the legs' loops at those weights on the parent (the torso; 0.5 is the default's
//! mean of the two parts), to 0.1 mm.

use studies::study_pairs;
use studies::limb_bend;

use clap::Parser;

use capture::align::{align_motion_on, AlignedMotion};
use capture::assemble::{assemble, plan};
use mesh_core::artifact::Artifact;
use mesh_core::rigid::procrustes;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use nalgebra::Vector3;
use transfer::limb_orientation::apply;
use transfer::reconstruct::{Reconstructor, Surface};

/// Per frame: the prediction rigidly fitted to the truth (whole body), then the RMS error
/// over every vertex and over each part's vertices.
fn errors(pred: &[Vec<Vector3<f64>>], truth: &[Vec<Vector3<f64>>], parts: &[Vec<u32>]) -> (f64, Vec<f64>) {
    let mut all = 0.0;
    let mut per = vec![0.0; parts.len()];
    let mut count = 0usize;
    for (p, t) in pred.iter().zip(truth) {
        let m = procrustes(p, t, None);
        let q = m.apply_all(p);
        all += q.iter().zip(t).map(|(a, b)| (a - b).norm_squared()).sum::<f64>() / q.len() as f64;
        for (k, vs) in parts.iter().enumerate() {
            per[k] += vs.iter().map(|&v| (q[v as usize] - t[v as usize]).norm_squared()).sum::<f64>() / vs.len() as f64;
        }
        count += 1;
    }
    let n = count.max(1) as f64;
    ((all / n).sqrt(), per.iter().map(|s| (s / n).sqrt()).collect())
}

/// A test motion's corrected parts merged by averaging, by stitching and by a feathered mean,
/// with the pose error per part of each against the truth (docs/studies/03-surface-stage.md).
#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    study: study_pairs::StudyArgs,
    /// Turns the limbs' distal halves toward the bend map by this geodesic weight (0 to 1)
    /// before the surface stage [default: no bend map].
    #[arg(long, value_name = "W")]
    bend_weight: Option<f64>,
    /// Prints, in place of the distance-weighted loops, the stitch with the arms' and the legs'
    /// loops at these weights on the parent (0.5 is the default's mean of the two parts).
    #[arg(long, value_delimiter = ',', value_name = "ARM,LEG")]
    loop_weights: Option<Vec<f64>>,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let study_pairs::Study { work, set, s, t, tests, train, spca, tpca, model, template, true_pairs } = &study_pairs::Study::open(&cli.study)?;
    let m = &tests[0];
    let seg = Segmentation::load(format!("{work}/{t}/parts.seg"))?;
    let training: Vec<AlignedMotion> =
        train.iter().map(|n| AlignedMotion::load(format!("{work}/{t}/{n}.aligned"))).collect::<Result<_, _>>()?;
    let refs: Vec<&AlignedMotion> = training.iter().collect();
    let motion = AlignedMotion::load(format!("{work}/{s}/{m}.aligned"))?;
    let truth = align_motion_on(&template, &MeshSequence::load_dir(format!("{set}/truth/{t}/{m}"))?, &tpca.anchor)?;

    let xs = spca.encode(&motion)?;
    let xd = transfer::predict::displacement_matrix(&motion.displacements);
    let mut decoded = tpca.decode(&transfer::predict::predict(&model, &xs, &xd, false)?.coeffs)?;
    if let Some(o) = &model.orientation {
        apply(o, &spca, &tpca, &xs, &mut decoded)?;
    }
    if let Some(w) = cli.bend_weight {
        let (pairs, _) = study_pairs::load(work, set, s, t, &spca, &tpca, train, *true_pairs)?;
        let bends = limb_bend::BendMaps::fit(&spca, &tpca, &transfer::gpr_model::training_set(&pairs, 1.0, false)?)?;
        bends.turn(&spca, &tpca, &xs, &mut decoded, w);
    }
    let mut recon = Reconstructor::new(&tpca, &seg, &template.faces, &refs, Surface::CorrectStitch, 3, 1)?;
    let corrected = recon.correct(&decoded)?;
    let plan = plan(&tpca)?;
    let parts: Vec<Vec<u32>> = seg.parts.iter().map(|p| p.vertices.clone()).collect();
    let names: Vec<&str> = seg.parts.iter().map(|p| p.name.as_str()).collect();
    let report = |label: &str, frames: &[Vec<Vector3<f64>>]| {
        let (all, per) = errors(frames, &truth.frames, &parts);
        let per: Vec<String> = names.iter().zip(&per).map(|(n, e)| format!("{n} {:.2}", 100.0 * e)).collect();
        println!("{s}->{t} {m} {label}: {:.2} cm | {}", 100.0 * all, per.join(", "));
    };
    report("gpr-nn", &assemble(&plan, &tpca, &decoded));
    report("+correct", &assemble(&plan, &tpca, &corrected));
    let full = recon.merge(&tpca, &corrected)?;
    report("+correct+stitch", &full);
    let averaged = assemble(&plan, &tpca, &corrected);
    for share in [0.25, 0.5] {
        let mixed: Vec<Vec<Vector3<f64>>> = full
            .iter()
            .zip(&averaged)
            .map(|(a, b)| a.iter().zip(b).map(|(p, q)| p * (1.0 - share) + q * share).collect())
            .collect();
        report(&format!("+correct+stitch mixed with +correct at {share}"), &mixed);
    }
    for (label, taps) in [("smoothed 1-2-1", vec![0.25, 0.5, 0.25]), ("smoothed 5-tap", vec![0.0625, 0.25, 0.375, 0.25, 0.0625])] {
        let h = taps.len() as i64 / 2;
        let n = full.len() as i64;
        let smoothed: Vec<Vec<Vector3<f64>>> = (0..n)
            .map(|f| {
                // Each neighbour frame rigidly fitted onto frame f first, so that only the pose is filtered.
                let mut acc = vec![Vector3::zeros(); full[0].len()];
                let mut wsum = 0.0;
                for (i, w) in taps.iter().enumerate() {
                    let g = f + i as i64 - h;
                    if g < 0 || g >= n {
                        continue;
                    }
                    let q = procrustes(&full[g as usize], &full[f as usize], None).apply_all(&full[g as usize]);
                    acc.iter_mut().zip(&q).for_each(|(a, b)| *a += *w * b);
                    wsum += w;
                }
                acc.iter().map(|a| a / wsum).collect()
            })
            .collect();
        report(label, &smoothed);
    }
    report("+stitch", &recon.merge(&tpca, &decoded)?);

    // Loops weighted by how near each part's source pose is to the training inputs.
    let order = seg.tree_order()?;
    let mut stitcher = surface::stitch::Stitcher::new(surface::segmentation::part_layout(&seg, template.faces.clone())?)
        .with_band_alignment(false);
    let dist: Vec<Vec<f64>> = model
        .parts
        .iter()
        .zip(&xs)
        .map(|(r, x)| match r.gp() {
            Some(gpr) => transfer::confidence::nearest_distances(gpr.inputs(), x),
            None => vec![1.0; x.nrows()],
        })
        .collect();
    let n = corrected[0].len();
    // Overlaps merged with weights ramping across each band (`surface::feather`).
    let parts_in_order = stitcher.layout().parts().to_vec();
    let weights = surface::feather::band_weights(&template.vertices, &template.faces, &parts_in_order);
    for (label, source) in [("+correct+feather", &corrected), ("+feather", &decoded)] {
        let frames: Vec<Vec<Vector3<f64>>> = (0..n)
            .map(|f| {
                let mut merged = vec![Vector3::zeros(); template.vertices.len()];
                for ((&k, part), w) in order.iter().zip(&parts_in_order).zip(&weights) {
                    for ((&v, x), wi) in part.vertices.iter().zip(&source[k][f]).zip(w) {
                        merged[v as usize] += *wi * x;
                    }
                }
                plan.to_template_frame(&merged)
            })
            .collect();
        report(label, &frames);
    }
    // With --loop-weights ARM,LEG: the arms' and the legs' loops at those weights on the parent.
    if let Some(ws) = &cli.loop_weights {
        anyhow::ensure!(ws.len() == 2, "--loop-weights: two weights ARM,LEG expected, got {ws:?}");
        let v = format!("{},{}", ws[0], ws[1]);
        let w: Vec<f64> = order
            .iter()
            .map(|&k| match seg.parts[k].name.as_str() {
                n if n.starts_with("arm") => ws[0],
                n if n.starts_with("leg") => ws[1],
                _ => 0.5,
            })
            .collect();
        let frames: Vec<Vec<Vector3<f64>>> = (0..n)
            .map(|f| {
                let frame: Vec<Vec<Vector3<f64>>> = order.iter().map(|&k| corrected[k][f].clone()).collect();
                plan.to_template_frame(&stitcher.stitch_weighted(&frame, &w).unwrap().vertices)
            })
            .collect();
        let (all, _) = errors(&frames, &truth.frames, &parts);
        println!("{s}->{t} {m} +correct+stitch loops {v}: {:.4} cm", 100.0 * all);
        return Ok(());
    }
    for (label, rule) in [("distance", 0), ("distance squared", 1), ("fixed 0.5", 2)] {
        let frames: Vec<Vec<Vector3<f64>>> = (0..n)
            .map(|f| {
                let frame: Vec<Vec<Vector3<f64>>> = order.iter().map(|&k| corrected[k][f].clone()).collect();
                let w: Vec<f64> = order
                    .iter()
                    .map(|&k| {
                        let parent = seg.parts[k].parent.as_ref().and_then(|p| seg.parts.iter().position(|q| &q.name == p)).unwrap_or(k);
                        let (dp, dc) = (dist[parent][f], dist[k][f]);
                        match rule {
                            0 => dc / (dp + dc).max(1e-12),
                            1 => dc * dc / (dp * dp + dc * dc).max(1e-12),
                            _ => 0.5,
                        }
                    })
                    .collect();
                plan.to_template_frame(&stitcher.stitch_weighted(&frame, &w).unwrap().vertices)
            })
            .collect();
        report(&format!("+correct+stitch {label}"), &frames);
    }
    Ok(())
}

//! A second, distal orientation map per limb (the elbow's and knee's bend, `studies::limb_bend`),
//! scored on the raw transfer (parts assembled, no §6) after the default limb orientation, at
//! bend weights 0 (the default model) to 1 (docs/studies/06-limb-orientation.md). `stitch_study`
//! scores
//! the full pipeline with it (`--bend-weight`).
//!
//! cargo run --release -p studies --bin limb_bend_study -- WORK SET SOURCE TARGET MOTION... -- TRAIN...

use studies::study_pairs;
use studies::limb_bend;

use capture::assemble::{assemble, plan};
use mesh_core::sequence::MeshSequence;
use transfer::gpr_model::training_set;
use transfer::limb_orientation::apply;

fn main() -> anyhow::Result<()> {
    let study = study_pairs::Study::from_command_line(
        env!("CARGO_BIN_NAME"),
        "A distal (bend) map per limb scored on the raw transfer of every test motion, at bend weights 0 to 1 (docs/studies/06-limb-orientation.md)",
    )?;
    let study_pairs::Study { work, set, s, t, tests, train, spca, tpca, model, template, true_pairs } = &study;
    let (pairs, _) = study_pairs::load(work, set, s, t, &spca, &tpca, train, *true_pairs)?;
    let bends = limb_bend::BendMaps::fit(&spca, &tpca, &training_set(&pairs, 1.0, false)?)?;
    let plan = plan(&tpca)?;
    let weights = [0.0, 0.25, 0.5, 0.75, 1.0];
    let mut totals = vec![(0.0f64, 0usize); weights.len()];
    for m in tests {
        let study_pairs::TestMotion { xs, xd, truth: truth_seq } = study.test_motion(m)?;
        let mut base = tpca.decode(&transfer::predict::predict(&model, &xs, &xd, false)?.coeffs)?;
        if let Some(o) = &model.orientation {
            apply(o, &spca, &tpca, &xs, &mut base)?;
        }
        print!("{s}->{t} {m}:");
        for (wi, &w) in weights.iter().enumerate() {
            let mut turned = base.clone();
            bends.turn(&spca, &tpca, &xs, &mut turned, w);
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

//! How much of a transfer's pose error is the limbs' orientation
//! (docs/studies/06-limb-orientation.md).
//! Transfers a test motion with a trained model (parts assembled, no §6) three ways: the limbs
//! as the pose GPs predict them, as the model's limb orientation turns them (what gpr-predict
//! does), and turned to the orientation of the truth's limbs (an oracle), and prints the pose
//! error of each against the truth. Then where the rest of the error is: the limbs' distal
//! halves (past the elbow or knee) also turned to the truth's, and, from the transfer with the
//! model's limb orientation, one part at a time replaced by the truth's part.
//!
//! cargo run --release -p studies --bin limb_oracle -- WORK SET SOURCE TARGET MOTION
//! e.g. `limb_oracle out/demo-run/work out/demo/set A B punch` (after `make transfer`)

use clap::Parser;
use studies::limb_bend;

use capture::align::{align_motion_on, AlignedMotion};
use capture::assemble::{assemble, plan};
use capture::part_pca::PcaModel;
use mesh_core::artifact::Artifact;
use mesh_core::sequence::MeshSequence;
use nalgebra::Vector3;
use transfer::gpr_model::GprModel;
use transfer::limb_orientation::{apply, limbs, orientation, reference, turn_to};
use transfer::reconstruct::rows_to_meshes;

/// How much of a transfer's pose error is the limbs' orientation
/// (docs/studies/06-limb-orientation.md).
#[derive(Parser)]
struct Cli {
    /// The run's work folder (e.g. out/demo-run/work).
    work: String,
    /// The capture set (e.g. out/demo/set).
    set: String,
    /// The source subject.
    source: String,
    /// The target subject.
    target: String,
    /// The test motion.
    motion: String,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let (work, set, s, t, m) = (&cli.work, &cli.set, &cli.source, &cli.target, &cli.motion);
    let model = GprModel::load(format!("{work}/models/{s}-to-{t}/gpr-nn.model"))?;
    let (spca, tpca) = (PcaModel::load(format!("{work}/{s}/pca.model"))?, PcaModel::load(format!("{work}/{t}/pca.model"))?);
    let motion = AlignedMotion::load(format!("{work}/{s}/{m}.aligned"))?;
    let template = mesh_core::io::read_mesh(format!("{set}/{t}/walk/000000.ply"))?;
    let truth = align_motion_on(&template, &MeshSequence::load_dir(format!("{set}/truth/{t}/{m}"))?, &tpca.anchor)?;
    let truth_parts: Vec<_> = tpca.part_rows(&truth)?.iter().map(rows_to_meshes).collect();

    let xs = spca.encode(&motion)?;
    let xd = transfer::predict::displacement_matrix(&motion.displacements);
    let gp = tpca.decode(&transfer::predict::predict(&model, &xs, &xd, false)?.coeffs)?;
    let mut turned = gp.clone();
    if let Some(o) = &model.orientation {
        apply(o, &spca, &tpca, &xs, &mut turned)?;
    }
    let mut oracle = gp.clone();
    for limb in limbs(&tpca)? {
        let mean = reference(&tpca, limb.part);
        for (frame, truth) in oracle[limb.part].iter_mut().zip(&truth_parts[limb.part]) {
            let now = orientation(&mean, frame, &limb.proximal);
            turn_to(frame, &limb, &now, &orientation(&mean, truth, &limb.proximal));
        }
    }
    // The distal halves too, each turned about its elbow (as the bend map of `limb_bend` turns
    // them) to the truth's orientation.
    let mut distal_oracle = oracle.clone();
    for limb in limbs(&tpca)? {
        let mean = reference(&tpca, limb.part);
        let b = limb_bend::bend(&limb, &mean);
        for (frame, truth) in distal_oracle[limb.part].iter_mut().zip(&truth_parts[limb.part]) {
            let turn = orientation(&mean, truth, &b.distal) * orientation(&mean, frame, &b.distal).inverse();
            let pivot = b.elbow.iter().map(|&i| frame[i]).sum::<Vector3<f64>>() / b.elbow.len() as f64;
            for &i in &b.distal {
                frame[i] = pivot + turn * (frame[i] - pivot);
            }
        }
    }
    let plan = plan(&tpca)?;
    let truth_seq = MeshSequence::new(template.faces.clone(), truth.frames.clone());
    let score = |parts: &Vec<Vec<Vec<Vector3<f64>>>>| -> anyhow::Result<f64> {
        let pred = MeshSequence::new(template.faces.clone(), assemble(&plan, &tpca, parts));
        Ok(100.0 * transfer::evaluate::rms_errors(&pred, &truth_seq)?.0)
    };
    for (name, parts) in [
        ("pose GPs", &gp),
        ("limb orientation", &turned),
        ("truth's limb orientation", &oracle),
        ("truth's limb orientation, distal halves too", &distal_oracle),
    ] {
        println!("{s}->{t} {m} {name}: {:.2} cm", score(parts)?);
    }
    for (k, part) in tpca.parts.iter().enumerate() {
        let mut one = turned.clone();
        one[k] = truth_parts[k].clone();
        println!("{s}->{t} {m} limb orientation, truth's {}: {:.2} cm", part.name, score(&one)?);
    }
    Ok(())
}

mod common;
use mesh_core::artifact::Artifact;
use mesh_core::sequence::MeshSequence;
use transfer::align::{align_motion, AlignedMotion};
use transfer::gpr_model::*;
use transfer::part_pca::PcaModel;

#[test]
#[ignore]
fn debug_displacement() {
    let w = std::path::PathBuf::from(std::env::var("H8W").unwrap());
    let set = std::path::PathBuf::from(std::env::var("H8S").unwrap());
    let model = GprModel::load(w.join("gpr-nn.model")).unwrap();
    for r in &model.reports { eprintln!("{}", r.line()); }
    let src = AlignedMotion::load(w.join("A/probe.aligned")).unwrap();
    let tpl = mesh_core::io::read_mesh(set.join("B/walk/000000.ply")).unwrap();
    let truth = MeshSequence::load_dir(set.join("truth/B/probe")).unwrap();
    let ta = align_motion(&tpl, &truth).unwrap();
    let sp = PcaModel::load(w.join("A/pca.model")).unwrap();
    let tp = PcaModel::load(w.join("B/pca.model")).unwrap();
    let xs = sp.encode(&src).unwrap();
    let pred = transfer::predict::predict(&model, &xs, &transfer::predict::displacement_matrix(&src.displacements), true).unwrap();
    for i in 0..src.displacements.len() {
        let s = src.displacements[i];
        let t = ta.displacements[i];
        let p: Vec<f64> = pred.displacement.row(i).iter().cloned().collect();
        eprintln!("{i:2} src {:?}\n   tru {:?}\n   prd {:?} w {:.3}", s.map(|v| (v*1000.0).round()/1000.0), t.map(|v| (v*1000.0).round()/1000.0), p.iter().map(|v| (v*1000.0).round()/1000.0).collect::<Vec<_>>(), pred.variance_ratio.as_ref().unwrap()[i]);
    }
    eprintln!("P0 src {:?} truth {:?}", src.poses[0].translation, ta.poses[0].translation);
    let _ = tp;
}

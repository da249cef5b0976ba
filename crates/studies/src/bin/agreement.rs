//! The proposed curves against a capture set's own (docs/RESULTS.md): per subject, the
//! fraction of template vertices given the same part, and each part's intersection over union.
//!   cargo run --release -p studies --bin agreement -- out/demo/set A B
use clap::Parser;
use mesh_core::capture_set::{CaptureSet, SubjectSpec};

/// The proposed curves against a capture set's own: per subject, the fraction of template
/// vertices given the same part, and each part's intersection over union.
#[derive(Parser)]
struct Cli {
    /// The capture set.
    set: String,
    /// The subjects.
    subjects: Vec<String>,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let set = CaptureSet::open(&cli.set)?;
    for x in &cli.subjects {
        let spec = SubjectSpec::load(set.subject_json(x))?;
        let tpl = set.template_path(x, &spec)?;
        let mesh = mesh_core::io::read_mesh(&tpl)?;
        let up = spec.up_vector().unwrap();
        let t = std::time::Instant::now();
        let limbs = curves::limb_loops::propose(&mesh, &up, &curves::limb_loops::Settings::default(), &Default::default()).into_result()?;
        let secs = t.elapsed().as_secs_f64();
        let topo = mesh_core::topology::Topology::new(mesh.vertices.len(), &mesh.faces);
        for l in &limbs {
            let d = topo.edge_distances(&mesh.vertices, &[l.extremity]);
            let mean = |lp: &[u32]| lp.iter().map(|&v| d[v as usize]).sum::<f64>() / lp.len() as f64;
            if let Some(c) = spec.curves.get(&l.part) {
                eprintln!("{x} {}: hand-built loops at {:.3} {:.3} m", l.part, mean(&c[0]), mean(&c[1]));
            }
            eprintln!("{x} {}: extremity {} levels {:.3} {:.3} loop sizes {} {}", l.part, l.extremity, l.levels[0], l.levels[1], l.loops[0].len(), l.loops[1].len());
        }
        let value = serde_json::to_value(&spec)?;
        let proposed: SubjectSpec = serde_json::from_value(curves::limb_loops::with_curves(value, &limbs)?)?;
        let (per, all) = curves::agreement::vertex_agreement(&mesh, &spec, &proposed)?;
        let per: Vec<String> = per.iter().map(|(n, a)| format!("{n} {:.3}", a)).collect();
        println!("{x}: {} vertices, {:.1}% same part; IoU {}; {secs:.2} s", mesh.vertices.len(), 100.0 * all, per.join(", "));
    }
    Ok(())
}

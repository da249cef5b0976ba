//! Precision and recall of `capture::contact_detector` against a capture set's contact
//! annotations (synth writes them from the skeleton's feet), per subject and motion.
//!
//! Usage: contact_check [capture set] (default out/demo/set; subjects A and B)

use clap::Parser;
use mesh_core::capture_set::{CaptureSet, SubjectSpec};
use mesh_core::sequence::MeshSequence;
use capture::contact_detector::{detect, precision_recall, Rule};
use variation::contacts;

/// Precision and recall of the contact detector against a capture set's contact annotations
/// (subjects A and B).
#[derive(Parser)]
struct Cli {
    /// The capture set.
    #[arg(default_value = "out/demo/set")]
    set: String,
}

fn main() -> mesh_core::Result<()> {
    let dir = Cli::parse().set;
    let set = CaptureSet::open(&dir)?;
    for subject in ["A".to_string(), "B".to_string()] {
        let spec = SubjectSpec::load(set.subject_json(&subject))?;
        let template = mesh_core::io::read_mesh(set.template_path(&subject, &spec)?)?;
        let up = spec.up_vector().expect("valid up");
        let soles = mesh_core::feet::soles(&[], &template.vertices, &up, mesh_core::feet::SOLE_TOLERANCE);
        for m in set.motions(&subject)? {
            let seq = MeshSequence::load_dir(set.motion_dir(&subject, &m))?;
            let Some(truth) = contacts::from_subject(&spec, &m, seq.n_frames())? else {
                continue;
            };
            let Some(found) = detect(&seq.frames, &soles, &up, spec.fps, &Rule::default()) else {
                println!("{subject} {m}: no soles");
                continue;
            };
            // Which sole is the left foot is not known without leg parts: score both orders.
            let swapped: Vec<[bool; 2]> = found.iter().map(|c| [c[1], c[0]]).collect();
            let (p, r) = precision_recall(&found, &truth);
            let (ps, rs) = precision_recall(&swapped, &truth);
            let (p, r) =
                if ps.unwrap_or(0.0) + rs.unwrap_or(0.0) > p.unwrap_or(0.0) + r.unwrap_or(0.0) {
                    (ps, rs)
                } else {
                    (p, r)
                };
            let f = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.2}"));
            println!(
                "{subject} {m}: {} frames, precision {}, recall {}",
                truth.len(),
                f(p),
                f(r)
            );
        }
    }
    Ok(())
}

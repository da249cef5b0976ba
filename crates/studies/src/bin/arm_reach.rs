//! How far each arm reaches out from the body in mesh sequences of one subject
//! (docs/studies/07-holdout-arm-error.md): per arm, the mean over frames of the angle between
//! world down and the line from the shoulder (the centroid of the arm's band with the torso) to
//! the hand (the centroid of the arm's quarter of vertices farthest from the shoulder), and the
//! mean gap between those hand vertices and the torso and legs. Comparing a motion's source, its
//! truth and its transfer with the subjects' training motions shows whether the training pairs
//! could have predicted the target's arms.
//!
//! cargo run --release -p studies --bin arm_reach -- SEGMENTATION SEQ_DIR...
//! e.g. `arm_reach out/holdout-run/work/D/parts.seg out/holdout/set/D/walk out/holdout/set/truth/D/cmu_walkturn`

use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::MeshSequence;
use nalgebra::Vector3;
use std::collections::HashSet;

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn centroid(frame: &[Vector3<f64>], vs: &[u32]) -> Vector3<f64> {
    vs.iter().map(|&v| frame[v as usize]).sum::<Vector3<f64>>() / vs.len().max(1) as f64
}

/// How far each arm reaches out from the body in mesh sequences of one subject.
#[derive(Parser)]
struct Cli {
    /// The subject's segmentation (parts.seg).
    segmentation: String,
    /// Mesh sequence folders of that subject.
    seq_dirs: Vec<String>,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let (seg_path, dirs) = (&cli.segmentation, &cli.seq_dirs);
    let seg = Segmentation::load(seg_path)?;
    let part = |name: &str| {
        seg.parts
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| anyhow::anyhow!("{seg_path}: no part '{name}'"))
    };
    for dir in dirs {
        let seq = MeshSequence::load_dir(dir)?;
        let mut cells = Vec::new();
        for arm in ["arm_l", "arm_r"] {
            let p = part(arm)?;
            let band: Vec<u32> = p.overlap.iter().map(|&i| p.vertices[i as usize]).collect();
            let own: HashSet<u32> = p.vertices.iter().copied().collect();
            // Every second vertex of the torso and legs is enough for a gap in centimetres.
            let body: Vec<u32> = seg
                .parts
                .iter()
                .filter(|q| q.name == "torso" || q.name.starts_with("leg"))
                .flat_map(|q| q.vertices.iter().copied())
                .filter(|v| !own.contains(v))
                .step_by(2)
                .collect();
            let (mut angles, mut gaps) = (Vec::new(), Vec::new());
            for f in &seq.frames {
                let shoulder = centroid(f, &band);
                let mut by_reach: Vec<(f64, u32)> =
                    p.vertices.iter().map(|&v| ((f[v as usize] - shoulder).norm(), v)).collect();
                by_reach.sort_by(|a, b| b.0.total_cmp(&a.0));
                let hand: Vec<u32> = by_reach[..by_reach.len() / 4].iter().map(|r| r.1).collect();
                let reach = (centroid(f, &hand) - shoulder).normalize();
                angles.push(reach.dot(&-Vector3::y()).clamp(-1.0, 1.0).acos().to_degrees());
                let gap = hand
                    .iter()
                    .step_by(3)
                    .flat_map(|&h| body.iter().map(move |&o| (h, o)))
                    .map(|(h, o)| (f[h as usize] - f[o as usize]).norm())
                    .fold(f64::INFINITY, f64::min);
                gaps.push(gap);
            }
            cells.push(format!(
                "{arm} {:.1}° from down, hand {:.1} cm from the body",
                mean(&angles),
                100.0 * mean(&gaps)
            ));
        }
        println!("{dir} ({} frames): {}", seq.frames.len(), cells.join(" | "));
    }
    Ok(())
}

//! Exports one body part's training matrix of a prealigned group (the rows gpdm-train fits)
//! as y.f64 (row-major N × D, little-endian f64) and meta.json, for the `fit_compare`
//! binary and `scripts/compare/gpdm_scipy.py --problem DIR`.
//!
//! Usage: export_part <group> <part> <out_dir>
//! e.g.: target/release/export_part out/work/variation/locomotion.group leg_l /tmp/leg_l

use clap::Parser;
use mesh_core::artifact::Artifact;
use variation::group::Group;
use variation::train::training_data;

/// Exports one body part's training matrix of a prealigned group as y.f64 and meta.json.
#[derive(Parser)]
struct Cli {
    /// The prealigned group (prealign's output).
    group: String,
    /// The body part's name.
    part: String,
    /// The output folder.
    out_dir: String,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let cli = Cli::parse();
    let (group, part, out) = (&cli.group, &cli.part, &cli.out_dir);
    let group = Group::load(group)?;
    let k = group
        .parts
        .iter()
        .position(|p| &p.name == part)
        .ok_or_else(|| format!("no part '{part}' in group '{}'", group.name))?;
    let (data, _) = training_data(&group, 1);
    let seqs = &data[k];
    let d = seqs[0].ncols();
    let mut bytes = Vec::new();
    for s in seqs {
        for i in 0..s.nrows() {
            for j in 0..d {
                bytes.extend_from_slice(&s[(i, j)].to_le_bytes());
            }
        }
    }
    let lens: Vec<usize> = seqs.iter().map(|s| s.nrows()).collect();
    std::fs::create_dir_all(out)?;
    std::fs::write(std::path::Path::new(out).join("y.f64"), bytes)?;
    let meta = serde_json::json!({"n": lens.iter().sum::<usize>(), "d_obs": d, "seq_lens": lens,
        "group": group.name, "part": part});
    std::fs::write(
        std::path::Path::new(out).join("meta.json"),
        meta.to_string(),
    )?;
    Ok(())
}

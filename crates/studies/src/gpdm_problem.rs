//! A GPDM training problem exported as `y.f64` (row-major N × D, little-endian f64) plus
//! `meta.json` with "d_obs" and "seq_lens" (written by the `fit_compare` and
//! `export_part` binaries), shared by the GPDM binaries.
use nalgebra::DMatrix;
use std::path::Path;

/// Loads the problem in `dir`, split into its sequences (each T_j × D).
pub fn load_problem(dir: &Path) -> Vec<DMatrix<f64>> {
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("meta.json")).expect("meta.json"))
            .expect("meta.json is JSON");
    let d = meta["d_obs"].as_u64().expect("d_obs") as usize;
    let lens: Vec<usize> = meta["seq_lens"]
        .as_array()
        .expect("seq_lens")
        .iter()
        .map(|v| v.as_u64().expect("sequence length") as usize)
        .collect();
    let v: Vec<f64> = std::fs::read(dir.join("y.f64"))
        .expect("y.f64")
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    assert_eq!(v.len(), lens.iter().sum::<usize>() * d, "y.f64 size");
    let mut start = 0;
    lens.iter()
        .map(|&l| {
            let m = DMatrix::from_row_slice(l, d, &v[start * d..(start + l) * d]);
            start += l;
            m
        })
        .collect()
}

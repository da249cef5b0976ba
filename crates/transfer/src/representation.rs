//! How much of the transfer error the representation alone causes: the
//! target's own truth frames are cut into parts, optionally passed through the
//! part PCA (encode + decode, no regression), and rebuilt into one mesh by each
//! [`Surface`] method; `rms_pose_m` against the truth (as `transfer-eval`) is then the
//! floor any regression can reach with that representation.

use mesh_core::sequence::MeshSequence;
use mesh_core::Result;
use serde::Serialize;

use capture::align::AlignedMotion;
use capture::part_pca::PcaModel;
use crate::reconstruct::{rows_to_meshes, Reconstructor};

/// Per part, the RMS per-vertex distance between the truth part (in the PCA's frame)
/// and its PCA reconstruction: the truncation error alone.
pub fn truncation_rms(pca: &PcaModel, truth: &AlignedMotion) -> Result<Vec<(String, f64)>> {
    let rows = pca.part_rows(truth)?;
    let coeffs = pca.encode_rows(&rows)?;
    let decoded = pca.decode(&coeffs)?;
    Ok(pca
        .parts
        .iter()
        .zip(rows.iter().zip(&decoded))
        .map(|(p, (r, d))| {
            let orig = rows_to_meshes(r);
            let (mut s, mut n) = (0.0, 0usize);
            for (a, b) in orig.iter().zip(d) {
                s += a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).norm_squared())
                    .sum::<f64>();
                n += a.len();
            }
            (p.name.clone(), (s / n.max(1) as f64).sqrt())
        })
        .collect())
}

/// One measured row of the diagnosis.
#[derive(Clone, Debug, Serialize)]
pub struct RepresentationRow {
    pub alignment: String,
    pub surface: String,
    /// Parts passed through PCA (else the exact truth parts).
    pub through_pca: bool,
    pub rms_pose_m: f64,
}

/// `rms_pose_m` of the truth rebuilt by `recon` (parts through PCA or exact).
pub fn rebuilt_error(
    pca: &PcaModel,
    recon: &mut Reconstructor,
    truth: &AlignedMotion,
    through_pca: bool,
) -> Result<f64> {
    let rows = pca.part_rows(truth)?;
    let parts = if through_pca {
        pca.decode(&pca.encode_rows(&rows)?)?
    } else {
        rows.iter().map(rows_to_meshes).collect()
    };
    let frames = recon.reconstruct(pca, &parts)?;
    let pred = MeshSequence::new(truth.faces.clone(), frames);
    let want = MeshSequence::new(truth.faces.clone(), truth.frames.clone());
    Ok(crate::evaluate::rms_errors(&pred, &want)?.0)
}

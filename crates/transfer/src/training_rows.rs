//! The training rows of the transfer's regressions: a pair of motions as coefficients and
//! frame pairs ([`PairData`], read from a `--pair` by [`PairFiles`]), stacked into per-part and
//! displacement regression problems ([`TrainingSet`], [`TrainingRows`]); the target's rigid
//! displacement over one source frame interval ([`target_step`]).

use mesh_core::artifact::Artifact;
use mesh_core::rigid::{integrate, RigidMotion};
use mesh_core::{Error, Result};
use std::path::PathBuf;

use capture::align::{AlignedMotion, CaptureInfo};
use capture::motion_stream::read_encoded;
use capture::part_pca::PcaModel;
use crate::densify::Correspondences;
use crate::gpr_model::Method;
use nalgebra::{DMatrix, Vector6};

/// The coefficients and displacements of one training pair of motions, with
/// the frame pairs to learn from.
#[derive(Clone, Debug)]
pub struct PairData {
    /// Source coefficients per part (`F_s x m_k`).
    pub source_coeffs: Vec<DMatrix<f64>>,
    /// Target coefficients per part (`F_t x m_k`).
    pub target_coeffs: Vec<DMatrix<f64>>,
    /// Source displacements `D_i` (align.rs), one per source frame.
    pub source_disp: Vec<[f64; 6]>,
    /// Target displacements, one per target frame.
    pub target_disp: Vec<[f64; 6]>,
    /// Dense `(source frame, target frame)` pairs.
    pub pairs: Vec<[usize; 2]>,
    /// Key-pose pairs (a subset of the path).
    pub keyposes: Vec<[usize; 2]>,
}

impl PairData {
    /// Swaps source and target (the B->A direction uses the A->B path reversed).
    pub fn reversed(self) -> PairData {
        let swap = |v: Vec<[usize; 2]>| v.into_iter().map(|[i, j]| [j, i]).collect();
        PairData {
            source_coeffs: self.target_coeffs,
            target_coeffs: self.source_coeffs,
            source_disp: self.target_disp,
            target_disp: self.source_disp,
            pairs: swap(self.pairs),
            keyposes: swap(self.keyposes),
        }
    }
}

/// A `--pair` as [`PairFiles::read_encoded`] reads it.
pub struct EncodedPair {
    /// The pair in the set's order.
    pub data: PairData,
    /// Capture records of the set's source and target motions.
    pub captures: [CaptureInfo; 2],
    /// SHA-256 of the three files, in the command line's order.
    pub sha256: [String; 3],
    /// The motion's name (the correspondences' source motion).
    pub motion: String,
}

/// One training pair as the stages name it on the command line (`--pair SOURCE TARGET CORR`):
/// the aligned motions of the set's source and target subjects and their correspondences.
pub struct PairFiles {
    pub source: AlignedMotion,
    pub target: AlignedMotion,
    pub corr: Correspondences,
    paths: [PathBuf; 2],
}

impl PairFiles {
    /// Loads the three files of one `--pair` (exactly three paths).
    pub fn load(files: &[PathBuf]) -> Result<PairFiles> {
        let [s, t, c] = files else {
            return Err(Error::invalid("--pair takes three files"));
        };
        Ok(PairFiles {
            source: AlignedMotion::load(s)?,
            target: AlignedMotion::load(t)?,
            corr: Correspondences::load(c)?,
            paths: [s.clone(), t.clone()],
        })
    }

    /// One `--pair` read and encoded in one pass per file, without holding its motions: the
    /// set's source motion encoded with `source_pca` and its target motion with `target_pca`
    /// frame block by frame block as they are decoded (`capture::part_pca::FrameEncoder`, the
    /// coefficients of [`PairFiles::encode`] to the bit), the three files in parallel. Returns
    /// the pair in set order, the two motions' capture records and each file's SHA-256 (in the
    /// files' order) for the output's input records, computed in the same pass.
    pub fn read_encoded(files: &[PathBuf], source_pca: &PcaModel, target_pca: &PcaModel) -> Result<EncodedPair> {
        let [s, t, c] = files else {
            return Err(Error::invalid("--pair takes three files"));
        };
        let encoded = |path: &PathBuf, pca: &PcaModel| read_encoded(path, pca);
        let ((source, target), corr) = rayon::join(
            || rayon::join(|| encoded(s, source_pca), || encoded(t, target_pca)),
            || Correspondences::load_hashed(c),
        );
        let ((source_coeffs, source, hs), (target_coeffs, target, ht), (corr, hc)) = (source?, target?, corr?);
        Ok(EncodedPair {
            data: PairData {
                source_coeffs,
                target_coeffs,
                source_disp: source.displacements,
                target_disp: target.displacements,
                pairs: corr.pairs,
                keyposes: corr.keyposes,
            },
            captures: [source.capture, target.capture],
            sha256: [hs, ht, hc],
            motion: corr.source_motion,
        })
    }

    /// The pair in coefficients: the set's source motion encoded with `source_pca`, its
    /// target motion with `target_pca` (set order; [`PairData::reversed`] for B->A).
    pub fn encode(&self, source_pca: &PcaModel, target_pca: &PcaModel) -> Result<PairData> {
        let coeffs = |pca: &PcaModel, m: &AlignedMotion, path: &PathBuf| {
            pca.encode(m).map_err(|e| Error::file(path, e.to_string()))
        };
        Ok(PairData {
            source_coeffs: coeffs(source_pca, &self.source, &self.paths[0])?,
            target_coeffs: coeffs(target_pca, &self.target, &self.paths[1])?,
            source_disp: self.source.displacements.clone(),
            target_disp: self.target.displacements.clone(),
            pairs: self.corr.pairs.clone(),
            keyposes: self.corr.keyposes.clone(),
        })
    }
}

/// Stacked regression problems: per part `(X_k, Y_k)` and the displacement `(X_d, Y_d)`.
#[derive(Clone, Debug)]
pub struct TrainingSet {
    pub x_parts: Vec<DMatrix<f64>>,
    pub y_parts: Vec<DMatrix<f64>>,
    pub x_disp: DMatrix<f64>,
    pub y_disp: DMatrix<f64>,
    /// Where each row comes from: `[pair, source frame, target frame]`, the pair indexed in the
    /// pairs the set was made from.
    pub origin: Vec<[usize; 3]>,
}

impl TrainingSet {
    pub fn len(&self) -> usize {
        self.x_disp.nrows()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The rows `rows` of every problem.
    pub fn subset(&self, rows: &[usize]) -> TrainingSet {
        let pick = |m: &DMatrix<f64>| m.select_rows(rows.iter());
        TrainingSet {
            x_parts: self.x_parts.iter().map(pick).collect(),
            y_parts: self.y_parts.iter().map(pick).collect(),
            x_disp: pick(&self.x_disp),
            y_disp: pick(&self.y_disp),
            origin: rows.iter().map(|&r| self.origin[r]).collect(),
        }
    }
}

/// The target's rigid displacement over **one source frame interval** ending
/// at target frame `j`, from per-target-frame displacements `disp` and the
/// frame ratio `q = fps_target / fps_source`.
///
/// With `c = ceil(q)` (`c = q` when `q` is an integer), the displacements of
/// target frames `j-c+1 ..= j` are composed (frames before 1 are the identity:
/// `D_0 = 0`). When `q` is not an integer (or `q < 1`), the composed 6-vector
/// is scaled by `q / c`: a first-order approximation of scaling the twist of
/// the motion, exact for straight-line translation at constant speed and for
/// rotation about a fixed axis without translation.
pub fn target_step(disp: &[[f64; 6]], j: usize, q: f64) -> [f64; 6] {
    let c = q.ceil().max(1.0) as usize;
    let first = (j + 1).saturating_sub(c);
    let steps: Vec<RigidMotion> = (first..=j)
        .map(|f| RigidMotion::from_6vec(&Vector6::from_column_slice(&disp[f])))
        .collect();
    let composed = *integrate(&RigidMotion::identity(), &steps)
        .last()
        .expect("integrate returns the start");
    let v = composed.to_6vec() * (q / c as f64);
    v.into()
}

/// Stacks the training rows of all pairs: pose rows for every dense pair (or
/// key-pose pair when `keyposes_only`), displacement rows `(D^s_i, target_step(j))`.
pub fn training_set(
    pairs: &[PairData],
    frame_ratio: f64,
    keyposes_only: bool,
) -> Result<TrainingSet> {
    let n_parts = pairs.first().map_or(0, |p| p.source_coeffs.len());
    if pairs.is_empty() || n_parts == 0 {
        return Err(Error::invalid("no training pairs or no parts"));
    }
    let mut rows: Vec<(usize, usize, usize)> = Vec::new();
    for (p, pair) in pairs.iter().enumerate() {
        if pair.source_coeffs.len() != n_parts || pair.target_coeffs.len() != n_parts {
            return Err(Error::invalid(format!(
                "training pair {p}: part counts differ"
            )));
        }
        let (fs, ft) = (pair.source_disp.len(), pair.target_disp.len());
        let chosen = if keyposes_only {
            &pair.keyposes
        } else {
            &pair.pairs
        };
        for &[i, j] in chosen {
            if i >= fs || j >= ft {
                return Err(Error::invalid(format!(
                    "training pair {p}: frame pair ({i}, {j}) outside the motions ({fs} and {ft} frames)"
                )));
            }
            rows.push((p, i, j));
        }
    }
    if rows.is_empty() {
        return Err(Error::invalid("no training frame pairs"));
    }
    let n = rows.len();
    let gather = |dim: usize, get: &dyn Fn(usize, usize, usize, usize) -> f64| {
        DMatrix::from_fn(n, dim, |r, c| {
            let (p, i, j) = rows[r];
            get(p, i, j, c)
        })
    };
    let mut x_parts = Vec::with_capacity(n_parts);
    let mut y_parts = Vec::with_capacity(n_parts);
    for k in 0..n_parts {
        let ms = pairs[0].source_coeffs[k].ncols();
        let mt = pairs[0].target_coeffs[k].ncols();
        x_parts.push(gather(ms, &|p, i, _, c| pairs[p].source_coeffs[k][(i, c)]));
        y_parts.push(gather(mt, &|p, _, j, c| pairs[p].target_coeffs[k][(j, c)]));
    }
    let steps: Vec<[f64; 6]> = rows
        .iter()
        .map(|&(p, _, j)| target_step(&pairs[p].target_disp, j, frame_ratio))
        .collect();
    let x_disp = gather(6, &|p, i, _, c| pairs[p].source_disp[i][c]);
    let y_disp = DMatrix::from_fn(n, 6, |r, c| steps[r][c]);
    Ok(TrainingSet {
        x_parts,
        y_parts,
        x_disp,
        y_disp,
        origin: rows.iter().map(|&(p, i, j)| [p, i, j]).collect(),
    })
}

/// The rows a model of `method` trains on, gathered once from the pairs: the dense or key-pose
/// rows, and the affine baseline's key-pose rows when they are other rows (not a copy: at 10^5
/// pairs the rows are hundreds of MB).
pub struct TrainingRows {
    pub(crate) data: TrainingSet,
    keys: Option<TrainingSet>,
    pub(crate) frame_ratio: f64,
    pub(crate) keyposes_only: bool,
}

impl TrainingRows {
    /// The rows of `method` from `pairs` (target frame rate over source, `frame_ratio`), checked
    /// against `part_names`.
    pub fn new(
        method: Method,
        part_names: &[String],
        pairs: &[PairData],
        frame_ratio: f64,
        keyposes_only: bool,
    ) -> Result<Self> {
        if !(frame_ratio > 0.0 && frame_ratio.is_finite()) {
            return Err(Error::invalid(format!(
                "frame-rate ratio must be positive, got {frame_ratio}"
            )));
        }
        let data = training_set(pairs, frame_ratio, keyposes_only)?;
        let keys = if method == Method::KeyposeAffine && !keyposes_only {
            Some(training_set(pairs, frame_ratio, true)?)
        } else {
            None
        };
        let rows = TrainingRows { data, keys, frame_ratio, keyposes_only };
        rows.check_parts(part_names)?;
        Ok(rows)
    }

    /// The number of training rows (of the key-pose rows for the affine baseline).
    pub fn len(&self, method: Method) -> usize {
        if method == Method::KeyposeAffine { self.keys().len() } else { self.data.len() }
    }

    pub(crate) fn check_parts(&self, part_names: &[String]) -> Result<()> {
        if self.data.x_parts.len() != part_names.len() {
            return Err(Error::invalid(format!(
                "{} part names for {} parts of coefficients",
                part_names.len(),
                self.data.x_parts.len()
            )));
        }
        Ok(())
    }

    /// The key-pose rows of the affine baseline.
    pub(crate) fn keys(&self) -> &TrainingSet {
        self.keys.as_ref().unwrap_or(&self.data)
    }
}

impl TrainingSet {
    /// Part `k`'s problem alone, with the displacement's.
    pub(crate) fn part(&self, k: usize) -> TrainingSet {
        TrainingSet {
            x_parts: vec![self.x_parts[k].clone()],
            y_parts: vec![self.y_parts[k].clone()],
            x_disp: self.x_disp.clone(),
            y_disp: self.y_disp.clone(),
            origin: self.origin.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pure translation at constant speed: one source interval is `q` target
    /// steps, for integer and fractional `q` (above and below 1).
    #[test]
    fn target_step_spans_one_source_interval() {
        let d = vec![
            [0.0; 6],
            [0.01, 0.0, 0.02, 0.0, 0.0, 0.0],
            [0.01, 0.0, 0.02, 0.0, 0.0, 0.0],
            [0.01, 0.0, 0.02, 0.0, 0.0, 0.0],
        ];
        for q in [2.0, 1.5, 0.8, 1.0, 3.0] {
            let s = target_step(&d, 3, q);
            assert!(
                (s[0] - 0.01 * q).abs() < 1e-12 && (s[2] - 0.02 * q).abs() < 1e-12,
                "q = {q}: {s:?}"
            );
        }
        // Pure rotation about a fixed axis composes exactly too.
        let r = vec![[0.0, 0.0, 0.0, 0.0, 0.1, 0.0]; 4];
        let s = target_step(&r, 3, 2.0);
        assert!((s[4] - 0.2).abs() < 1e-12 && s[3].abs() < 1e-12);
        // Near the start, frames before 0 count as the identity.
        assert!((target_step(&d, 1, 3.0)[0] - 0.01).abs() < 1e-12);
    }

}

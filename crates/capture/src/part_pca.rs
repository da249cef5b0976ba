//! `pca-fit`: per-part PCA of a subject's aligned training frames (transfer
//! paper §4, "PCA Dimension Reduction").
//!
//! The paper: "all body part sub-meshes for a given subject are first rigidly
//! aligned and PCA applied". Two readings, chosen by [`PartAlignment`]:
//! * `body` (default): the part is cut from the whole-body-aligned frame
//!   (`align`) with no further alignment; decoded parts are then already in one
//!   common frame and assembly only averages the overlaps;
//! * `part`: every frame's part is also rigidly aligned (Procrustes) to the
//!   part as it is in the template, so PCA sees only the part's own
//!   deformation; assembly must then re-orient children on their overlap band.
//!
//! `body` is the default because it is far more faithful: on the demo set,
//! subject B's unseen `punch` truth passed through its own 20-component part
//! PCA and reassembled scores `rms_pose_m` 0.0135 m with `body` against
//! 0.085 m with `part` (per-part orientation is lost from the coefficients and
//! re-estimated from the narrow overlap band); `representation-error` measures it.
//!
//! PCA on the stacked coordinates `(x_1, y_1, z_1, x_2, ...)` gives `m`
//! coefficients per frame (20 by default).

use gp::pca::{Components, Pca};
use mesh_core::artifact::{check_cover, check_indices, Artifact};
use mesh_core::part_merge::{PartReports, Partitioned};
use mesh_core::rigid::procrustes;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use rayon::prelude::*;
use mesh_core::cli::ProgressBar;
use serde::{Deserialize, Serialize};

use crate::align::AlignedMotion;
use mesh_core::segmentation::Segmentation;

/// How a part is aligned before PCA (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum PartAlignment {
    /// Parts cut from the whole-body-aligned frames, no per-part alignment.
    #[default]
    Body,
    /// Each part additionally Procrustes-aligned to the template part.
    Part,
}

/// PCA of one part.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartPca {
    pub name: String,
    /// Template vertex index of each part vertex.
    pub vertices: Vec<u32>,
    /// The part as it is in the template: each frame's part is aligned to it.
    pub reference: Vec<Vector3<f64>>,
    pub pca: Pca,
}

/// Per-part PCA of one subject (or a single whole-body "part").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PcaModel {
    pub n_vertices: usize,
    pub parts: Vec<PartPca>,
    /// How the parts were aligned before PCA; decoded parts are in that frame.
    pub alignment: PartAlignment,
    /// Template vertices the training frames were aligned on (`align`'s anchor; empty: all):
    /// assembled meshes are brought back to the template on the same vertices.
    pub anchor: Vec<u32>,
    /// SHA-256 (hex) of the template file the model was fitted on (`pca-fit --template`), the
    /// identity consumers compare with a motion's ([`PcaModel::check_motion`]) and a transfer
    /// model's; empty when fitted in memory.
    pub template_sha256: String,
}

impl Artifact for PcaModel {
    const KIND: &'static str = "pca-model";
    const VERSION: u32 = 4;

    /// Every part's vertices below `n_vertices` (and every template vertex in
    /// some part), one reference point per vertex, a PCA of dimension
    /// `3 x vertices`, the anchor below `n_vertices`.
    fn validate(&self) -> std::result::Result<(), String> {
        let lists: Vec<&[u32]> = self.parts.iter().map(|p| p.vertices.as_slice()).collect();
        check_cover(self.n_vertices, &lists)?;
        self.check_parts()
    }
}

/// A piece (`pca-fit --part NAME`) is the model holding that part alone.
impl Partitioned for PcaModel {
    const PIECE_KIND: &'static str = "pca-model-part";
    type Body = PcaModel;

    /// As [`PcaModel::validate`] without the cover of the template: one part, consistent.
    fn validate_body(body: &PcaModel) -> std::result::Result<(), String> {
        if body.parts.len() != 1 {
            return Err(format!("{} parts in a piece, expected 1", body.parts.len()));
        }
        body.check_parts()
    }

    /// The parts of the bodies in order; vertex count, alignment and anchor must agree.
    fn join(parts: &[String], bodies: Vec<PcaModel>) -> std::result::Result<PcaModel, String> {
        let mut bodies = bodies.into_iter();
        let mut whole = bodies.next().ok_or("no parts")?;
        for (b, name) in bodies.zip(&parts[1..]) {
            if (b.n_vertices, b.alignment, &b.anchor, &b.template_sha256)
                != (whole.n_vertices, whole.alignment, &whole.anchor, &whole.template_sha256)
            {
                return Err(format!("part '{name}' was fitted on another template, alignment or anchor"));
            }
            whole.parts.extend(b.parts);
        }
        match whole.parts.iter().zip(parts).find(|(p, n)| p.name != **n) {
            Some((p, n)) => Err(format!("the piece of part '{n}' holds part '{}'", p.name)),
            None => Ok(whole),
        }
    }
}

/// `pca-fit --report`: one [`PartReport`] per part, in the model's order.
impl PartReports for PcaModel {
    type Report = Vec<PartReport>;

    fn report_part(report: &Vec<PartReport>) -> std::result::Result<String, String> {
        match report.as_slice() {
            [one] => Ok(one.part.clone()),
            many => Err(format!("a report of {} parts, not of one piece's part", many.len())),
        }
    }

    fn join_reports(reports: Vec<Vec<PartReport>>) -> std::result::Result<Vec<PartReport>, String> {
        Ok(reports.into_iter().flatten().collect())
    }

    fn report_text(report: &Vec<PartReport>) -> serde_json::Result<String> {
        serde_json::to_string_pretty(report)
    }
}

impl PcaModel {
    /// Every part's vertices below `n_vertices`, one reference point per vertex, a PCA of
    /// dimension `3 x vertices`, the anchor below `n_vertices` (no cover of the template).
    fn check_parts(&self) -> std::result::Result<(), String> {
        for (k, p) in self.parts.iter().enumerate() {
            check_indices(p.vertices.iter().copied(), self.n_vertices, || format!("part {k}'s vertex list"))?;
            let d = 3 * p.vertices.len();
            let pca = &p.pca;
            if p.reference.len() != p.vertices.len()
                || pca.mean.len() != d
                || pca.components.ncols() != d
                || pca.variances.len() != pca.components.nrows()
            {
                return Err(format!(
                    "part {k} ('{}'): {} vertices, {} reference points, PCA of dimension {} (mean {}) with {} axes and {} variances",
                    p.name,
                    p.vertices.len(),
                    p.reference.len(),
                    pca.components.ncols(),
                    pca.mean.len(),
                    pca.components.nrows(),
                    pca.variances.len()
                ));
            }
        }
        check_indices(self.anchor.iter().copied(), self.n_vertices, || "the anchor".into())
    }
}

/// Explained variance and reconstruction error of one part on its training data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartReport {
    pub part: String,
    pub vertices: usize,
    pub components: usize,
    pub explained_variance: f64,
    /// RMS per-vertex distance (m) between aligned training parts and their reconstruction.
    pub reconstruction_rms_m: f64,
}

/// Flattens the part vertices of one frame, rigidly aligned to `reference`
/// with [`PartAlignment::Part`], as they are with [`PartAlignment::Body`].
pub(crate) fn aligned_part_row(
    frame: &[Vector3<f64>],
    vertices: &[u32],
    reference: &[Vector3<f64>],
    alignment: PartAlignment,
) -> Vec<f64> {
    let pts: Vec<Vector3<f64>> = vertices.iter().map(|&v| frame[v as usize]).collect();
    let to_ref = match alignment {
        PartAlignment::Part => procrustes(&pts, reference, None),
        PartAlignment::Body => mesh_core::rigid::RigidMotion::identity(),
    };
    pts.iter()
        .flat_map(|p| {
            let q = to_ref.apply(p);
            [q.x, q.y, q.z]
        })
        .collect()
}

fn part_rows(
    motions: &[&AlignedMotion],
    vertices: &[u32],
    reference: &[Vector3<f64>],
    alignment: PartAlignment,
) -> DMatrix<f64> {
    let frames: Vec<&[Vector3<f64>]> = motions.iter().flat_map(|m| m.frames.iter().map(Vec::as_slice)).collect();
    frame_rows(&frames, vertices, reference, alignment)
}

/// One row per frame of `frames`: the part's vertices as [`aligned_part_row`] flattens them.
fn frame_rows(
    frames: &[&[Vector3<f64>]],
    vertices: &[u32],
    reference: &[Vector3<f64>],
    alignment: PartAlignment,
) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = frames
        .par_iter()
        .map(|f| aligned_part_row(f, vertices, reference, alignment))
        .collect();
    // Filled a column at a time (contiguous writes; `from_row_iterator` scatters every value
    // with an index division, a fifth of gpr-train's reading time).
    let mut m = DMatrix::zeros(rows.len(), 3 * vertices.len());
    for (c, mut col) in m.column_iter_mut().enumerate() {
        for (x, row) in col.iter_mut().zip(&rows) {
            *x = row[c];
        }
    }
    m
}

/// The PCA of one part fitted on `data` (its rows, one per frame, as [`frame_rows`] makes them)
/// and its report: explained variance and the reconstruction error of `data`.
pub(crate) fn fit_part_rows(
    part: &mesh_core::segmentation::Part,
    reference: Vec<Vector3<f64>>,
    data: &DMatrix<f64>,
    components: Components,
) -> Result<(PartPca, PartReport)> {
    let pca = Pca::fit(data, components).map_err(|e| Error::invalid(format!("part '{}': {e}", part.name)))?;
    let rms = pca.reconstruction_rms(data).map_err(|e| Error::invalid(e.to_string()))?;
    Ok(part_result(part, reference, pca, rms))
}

/// A fitted part and its report, from its PCA and the RMS per coordinate of its reconstruction.
pub(crate) fn part_result(
    part: &mesh_core::segmentation::Part,
    reference: Vec<Vector3<f64>>,
    pca: Pca,
    rms_per_coordinate: f64,
) -> (PartPca, PartReport) {
    let report = PartReport {
        part: part.name.clone(),
        vertices: part.vertices.len(),
        components: pca.n_components(),
        explained_variance: pca.explained_variance_ratio().iter().sum(),
        // rms per coordinate -> per vertex distance: sqrt(3) * rms.
        reconstruction_rms_m: rms_per_coordinate * 3f64.sqrt(),
    };
    (PartPca { name: part.name.clone(), vertices: part.vertices.clone(), reference, pca }, report)
}

/// The whole body as a single part (the paper's "whole body" comparison).
pub fn whole_body(n_vertices: usize) -> Segmentation {
    Segmentation {
        n_vertices,
        parts: vec![mesh_core::segmentation::Part {
            name: "body".into(),
            parent: None,
            vertices: (0..n_vertices as u32).collect(),
            faces: Vec::new(),
            overlap: Vec::new(),
            loops: Vec::new(),
        }],
    }
}

/// Fits one PCA per part on all frames of `motions`; `template` gives each
/// part's reference position.
pub fn fit(
    template: &[Vector3<f64>],
    parts: &Segmentation,
    motions: &[&AlignedMotion],
    components: Components,
    alignment: PartAlignment,
) -> Result<(PcaModel, Vec<PartReport>)> {
    fit_with_progress(template, parts, motions, components, alignment, &ProgressBar::hidden())
}

/// [`fit`], advancing `bar` by one per part fitted (its length is set to the part count).
pub fn fit_with_progress(
    template: &[Vector3<f64>],
    parts: &Segmentation,
    motions: &[&AlignedMotion],
    components: Components,
    alignment: PartAlignment,
    bar: &ProgressBar,
) -> Result<(PcaModel, Vec<PartReport>)> {
    fit_selected(template, parts, motions, components, alignment, None, bar)
}

/// [`fit_with_progress`] of part `only` alone (an index into `parts.parts`; `None`: every
/// part): the model then holds that part only, fitted exactly as in the whole fit.
pub fn fit_selected(
    template: &[Vector3<f64>],
    parts: &Segmentation,
    motions: &[&AlignedMotion],
    components: Components,
    alignment: PartAlignment,
    only: Option<usize>,
    bar: &ProgressBar,
) -> Result<(PcaModel, Vec<PartReport>)> {
    let selected: Vec<&mesh_core::segmentation::Part> = match only {
        Some(k) => vec![parts.parts.get(k).ok_or_else(|| {
            Error::invalid(format!("part index {k} of {} parts", parts.parts.len()))
        })?],
        None => parts.parts.iter().collect(),
    };
    bar.set_length(selected.len() as u64);
    if template.len() != parts.n_vertices {
        return Err(Error::invalid(format!(
            "the template has {} vertices but the segmentation was made for {}",
            template.len(),
            parts.n_vertices
        )));
    }
    for (k, m) in motions.iter().enumerate() {
        if let Some(f) = m.frames.iter().find(|f| f.len() != template.len()) {
            return Err(Error::invalid(format!(
                "aligned motion {} has {} vertices per frame, the template {}",
                k + 1,
                f.len(),
                template.len()
            )));
        }
    }
    parts.check().map_err(Error::invalid)?;
    let anchor = motions.first().map(|m| m.anchor.clone()).unwrap_or_default();
    if motions.iter().any(|m| m.anchor != anchor) {
        return Err(Error::invalid(
            "the aligned motions were aligned on different vertices (align --frame): align them alike",
        ));
    }
    let fitted: Vec<(PartPca, PartReport)> = selected
        .par_iter()
        .map(|part| {
            let reference: Vec<Vector3<f64>> = part
                .vertices
                .iter()
                .map(|&v| template[v as usize])
                .collect();
            let data = part_rows(motions, &part.vertices, &reference, alignment);
            fit_part_rows(part, reference, &data, components)
        })
        .inspect(|_| bar.inc(1))
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    let (parts_pca, reports) = fitted.into_iter().unzip();
    Ok((
        PcaModel {
            n_vertices: parts.n_vertices,
            parts: parts_pca,
            alignment,
            anchor,
            template_sha256: String::new(),
        },
        reports,
    ))
}

/// Fails when two recorded template hashes differ (an empty one is unknown and passes): `a`
/// and `b` describe where each came from, e.g. "the motion was aligned to".
pub fn check_same_template(hash_a: &str, hash_b: &str, a: &str, b: &str) -> Result<()> {
    if hash_a.is_empty() || hash_b.is_empty() || hash_a == hash_b {
        return Ok(());
    }
    Err(Error::invalid(format!(
        "{a} template {} but {b} template {}: they belong to different subjects or templates",
        short_hash(hash_a),
        short_hash(hash_b)
    )))
}

/// The first 12 hex digits of a SHA-256, enough to tell templates apart in a message.
fn short_hash(h: &str) -> &str {
    h.get(..12).unwrap_or(h)
}

impl PcaModel {
    /// The template's vertex positions, from the parts' references (every template vertex
    /// is in some part; one not in any stays at the origin).
    pub fn template_vertices(&self) -> Vec<Vector3<f64>> {
        let mut template = vec![Vector3::zeros(); self.n_vertices];
        for p in &self.parts {
            for (&v, r) in p.vertices.iter().zip(&p.reference) {
                if let Some(t) = template.get_mut(v as usize) {
                    *t = *r;
                }
            }
        }
        template
    }

    /// Fails unless `motion` was aligned to this model's template (when both record it) and
    /// every frame has this model's vertex count (a motion of another subject or template).
    pub fn check_motion(&self, motion: &AlignedMotion) -> Result<()> {
        if let Some(i) = motion.frames.iter().position(|f| f.len() != self.n_vertices) {
            return Err(Error::invalid(format!(
                "the motion's frame {i} has {} vertices but the PCA model was fitted on {}: \
                 the motion and the model belong to different subjects or templates",
                motion.frames[i].len(),
                self.n_vertices
            )));
        }
        check_same_template(&motion.capture.template_sha256, &self.template_sha256, "the motion was aligned to", "the PCA model was fitted on")
    }

    /// The part vertices of every frame of `motion` in the frame PCA works in
    /// (`F x 3n_k` per part), as the model's [`PartAlignment`] prescribes.
    /// Fails unless the motion has the model's vertex count.
    pub fn part_rows(&self, motion: &AlignedMotion) -> Result<Vec<DMatrix<f64>>> {
        self.check_motion(motion)?;
        Ok(self
            .parts
            .par_iter()
            .map(|p| part_rows(&[motion], &p.vertices, &p.reference, self.alignment))
            .collect())
    }

    /// Each part's vertices of one aligned frame in the frame PCA works in: the frame's row of
    /// [`PcaModel::part_rows`] per part, as vertices. Fails unless the frame has the model's
    /// vertex count.
    pub fn frame_parts(&self, frame: &[Vector3<f64>]) -> Result<Vec<Vec<Vector3<f64>>>> {
        if frame.len() != self.n_vertices {
            return Err(Error::invalid(format!(
                "a frame of {} vertices for a PCA model fitted on {}",
                frame.len(),
                self.n_vertices
            )));
        }
        Ok(self
            .parts
            .iter()
            .map(|p| {
                aligned_part_row(frame, &p.vertices, &p.reference, self.alignment)
                    .chunks_exact(3)
                    .map(|c| Vector3::new(c[0], c[1], c[2]))
                    .collect()
            })
            .collect())
    }

    /// Coefficients of every frame of `motion`, per part (`F x m_k` each).
    pub fn encode(&self, motion: &AlignedMotion) -> Result<Vec<DMatrix<f64>>> {
        self.encode_rows(&self.part_rows(motion)?)
    }

    /// Coefficients of part rows as from [`PcaModel::part_rows`].
    pub fn encode_rows(&self, rows: &[DMatrix<f64>]) -> Result<Vec<DMatrix<f64>>> {
        if rows.len() != self.parts.len() {
            return Err(Error::invalid(format!(
                "{} row blocks for {} parts",
                rows.len(),
                self.parts.len()
            )));
        }
        self.parts
            .par_iter()
            .zip(rows)
            .map(|(p, data)| {
                p.pca
                    .encode(data)
                    .map_err(|e| Error::invalid(format!("part '{}': {e}", p.name)))
            })
            .collect()
    }

    /// The squared PCA truncation residual `|x - decode(c)|²` (m², summed over the part's
    /// vertices) of every row `x` of part rows as from [`PcaModel::part_rows`], given their
    /// coefficients `c` ([`PcaModel::encode_rows`]): `result[part][row]`.
    pub fn truncation(&self, rows: &[DMatrix<f64>], coefficients: &[DMatrix<f64>]) -> Result<Vec<Vec<f64>>> {
        if rows.len() != self.parts.len() || coefficients.len() != self.parts.len() {
            return Err(Error::invalid(format!(
                "{} row blocks and {} coefficient blocks for {} parts",
                rows.len(),
                coefficients.len(),
                self.parts.len()
            )));
        }
        self.parts
            .par_iter()
            .zip(rows.par_iter().zip(coefficients))
            .map(|(p, (x, c))| {
                let rec = p.pca.decode(c).map_err(|e| Error::invalid(format!("part '{}': {e}", p.name)))?;
                if rec.shape() != x.shape() {
                    return Err(Error::invalid(format!("part '{}': {} rows of {} values for {} coefficient rows", p.name, x.nrows(), x.ncols(), c.nrows())));
                }
                Ok((rec - x).row_iter().map(|r| r.norm_squared()).collect())
            })
            .collect()
    }

    /// Part meshes (vertex positions in the reference frame) from per-part
    /// coefficient rows: `result[part][frame]`.
    pub fn decode(&self, coefficients: &[DMatrix<f64>]) -> Result<Vec<Vec<Vec<Vector3<f64>>>>> {
        if coefficients.len() != self.parts.len() {
            return Err(Error::invalid(format!(
                "{} coefficient blocks for {} parts",
                coefficients.len(),
                self.parts.len()
            )));
        }
        self.parts
            .par_iter()
            .zip(coefficients)
            .map(|(p, c)| {
                let x = p
                    .pca
                    .decode(c)
                    .map_err(|e| Error::invalid(format!("part '{}': {e}", p.name)))?;
                Ok(x.row_iter()
                    .map(|r| {
                        (0..p.vertices.len())
                            .map(|i| Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]))
                            .collect()
                    })
                    .collect())
            })
            .collect()
    }
}

/// Most frames a [`FrameEncoder`] encodes at a time. Any count above 5 gives the same
/// coefficients (see [`FrameEncoder`]); 256 frames of a 1,000-vertex body are 6 MB.
const ENCODE_BLOCK: usize = 256;
/// Fewest frames a [`FrameEncoder`] encodes at a time (see [`FrameEncoder`]).
const MIN_ENCODE_BLOCK: usize = 6;
/// Bytes of frames a [`FrameEncoder`] encodes at a time, at most (unless [`MIN_ENCODE_BLOCK`]
/// frames are more): a block of a 100,000-vertex body is 13 frames.
const ENCODE_BLOCK_BYTES: usize = 32 << 20;

/// The frames of `n_vertices` vertices a [`FrameEncoder`] encodes at a time: 32 MiB of
/// frames, at least 6 and at most 256.
pub fn frames_per_block(n_vertices: usize) -> usize {
    let frame_bytes = n_vertices.max(1).saturating_mul(std::mem::size_of::<Vector3<f64>>());
    (ENCODE_BLOCK_BYTES / frame_bytes).clamp(MIN_ENCODE_BLOCK, ENCODE_BLOCK)
}

/// `0..n_frames` cut as a [`FrameEncoder`] of `block` frames at a time cuts a motion: blocks
/// of `b = max(block, 6)` frames while at least `2b` frames remain, then the rest (`b` to
/// `2b - 1` frames, or the whole motion when it is shorter). No block has fewer than 6 frames
/// unless the motion has, so a product of a block's rows takes the path the whole motion's
/// would and gives every row's entries to the bit (see [`FrameEncoder`]).
pub fn blocks_of(n_frames: usize, block: usize) -> Vec<std::ops::Range<usize>> {
    let block = block.max(MIN_ENCODE_BLOCK);
    let mut out = Vec::new();
    let mut start = 0;
    while n_frames - start >= 2 * block {
        out.push(start..start + block);
        start += block;
    }
    if start < n_frames || n_frames == 0 {
        out.push(start..n_frames);
    }
    out
}

/// Encodes a motion's frames into per-part coefficients as they arrive (e.g. from
/// [`crate::motion_stream::read_frames`]), a block of frames at a time, so that the motion is
/// never held whole. The coefficients are those [`PcaModel::encode`] gives on the whole motion,
/// to the bit: a frame's part row does not depend on the other frames, and nalgebra's product
/// of a block of rows with the basis computes every coefficient by the same sum in the same
/// order whatever the number of rows, on either of its two paths (matrixmultiply's packed
/// kernels, which split only the shared dimension; column-by-column `gemv` when a dimension is
/// at most 5). The path is chosen by the dimensions, so every block has more than 5 rows: with
/// blocks of `b` frames (256, or fewer for a body above 16,000 vertices: 32 MiB of frames, at
/// least 6), a block is encoded once `2b` frames wait, and [`FrameEncoder::finish`] encodes the
/// last `b` or more (or the whole motion, when it is shorter). The encoder holds at most `2b`
/// frames and their part rows, whatever the motion's length. [`FrameEncoder::with_truncation`]
/// also keeps every frame's PCA truncation residual ([`PcaModel::truncation`], the same values
/// to the bit: the decoding product takes the path the whole motion's would, as the encoding's).
pub struct FrameEncoder<'a> {
    model: &'a PcaModel,
    /// Frames encoded at a time.
    block: usize,
    waiting: Vec<Vec<Vector3<f64>>>,
    /// Coefficients of the blocks encoded so far: `[block][part]`.
    blocks: Vec<Vec<DMatrix<f64>>>,
    /// The truncation residuals of the frames encoded so far, `[part][frame]`, when kept.
    truncation: Option<Vec<Vec<f64>>>,
    n_frames: usize,
}

/// A motion's frames in a PCA model's coefficients, with their truncation residuals
/// ([`FrameEncoder::with_truncation`]).
#[derive(Clone, Debug)]
pub struct EncodedFrames {
    /// Per part, the coefficients of every frame (`F x m_k`).
    pub coefficients: Vec<DMatrix<f64>>,
    /// `truncation[part][frame]`: `|x - decode(encode(x))|²` (m², summed over the part's vertices).
    pub truncation: Vec<Vec<f64>>,
}

impl<'a> FrameEncoder<'a> {
    pub fn new(model: &'a PcaModel) -> Self {
        Self::with_block(model, frames_per_block(model.n_vertices))
    }

    /// An encoder that also keeps every frame's truncation residual
    /// ([`FrameEncoder::finish_with_truncation`]).
    pub fn with_truncation(model: &'a PcaModel) -> Self {
        let mut encoder = Self::new(model);
        encoder.truncation = Some(vec![Vec::new(); model.parts.len()]);
        encoder
    }

    /// An encoder of `block` frames at a time (at least [`MIN_ENCODE_BLOCK`]).
    fn with_block(model: &'a PcaModel, block: usize) -> Self {
        let block = block.max(MIN_ENCODE_BLOCK);
        FrameEncoder { model, block, waiting: Vec::new(), blocks: Vec::new(), truncation: None, n_frames: 0 }
    }

    /// Takes the next frame; fails unless it has the model's vertex count (the message of
    /// [`PcaModel::check_motion`]).
    pub fn push(&mut self, frame: Vec<Vector3<f64>>) -> Result<()> {
        if frame.len() != self.model.n_vertices {
            return Err(Error::invalid(format!(
                "the motion's frame {} has {} vertices but the PCA model was fitted on {}: \
                 the motion and the model belong to different subjects or templates",
                self.n_frames,
                frame.len(),
                self.model.n_vertices
            )));
        }
        self.n_frames += 1;
        self.waiting.push(frame);
        if self.waiting.len() >= 2 * self.block {
            let block: Vec<Vec<Vector3<f64>>> = self.waiting.drain(..self.block).collect();
            let coefficients = self.encode_block(&block)?;
            self.blocks.push(coefficients);
        }
        Ok(())
    }

    /// The coefficients of every frame pushed (`F x m_k` per part), after checking that the
    /// motion was aligned to the model's template (`template_sha256`, the motion's
    /// `capture.template_sha256`; as [`PcaModel::check_motion`]).
    pub fn finish(self, template_sha256: &str) -> Result<Vec<DMatrix<f64>>> {
        Ok(self.finish_with_truncation(template_sha256)?.coefficients)
    }

    /// As [`FrameEncoder::finish`], with the truncation residuals of every frame pushed (empty
    /// unless the encoder was made [`FrameEncoder::with_truncation`]).
    pub fn finish_with_truncation(mut self, template_sha256: &str) -> Result<EncodedFrames> {
        check_same_template(template_sha256, &self.model.template_sha256, "the motion was aligned to", "the PCA model was fitted on")?;
        let last = std::mem::take(&mut self.waiting);
        let coefficients = self.encode_block(&last)?;
        self.blocks.push(coefficients);
        let truncation = self.truncation.take().unwrap_or_default();
        let coefficients = self.concatenate()?;
        Ok(EncodedFrames { coefficients, truncation })
    }

    /// The coefficients of every block, one matrix per part.
    fn concatenate(&self) -> Result<Vec<DMatrix<f64>>> {
        let n = self.n_frames;
        (0..self.model.parts.len())
            .map(|k| {
                let m = self.blocks[0][k].ncols();
                let mut all = DMatrix::zeros(n, m);
                let mut row = 0;
                for b in &self.blocks {
                    let c = &b[k];
                    if c.ncols() != m || row + c.nrows() > n {
                        return Err(Error::invalid(format!("part {k}: block of {} x {} coefficients", c.nrows(), c.ncols())));
                    }
                    all.view_mut((row, 0), (c.nrows(), m)).copy_from(c);
                    row += c.nrows();
                }
                Ok(all)
            })
            .collect()
    }

    fn encode_block(&mut self, frames: &[Vec<Vector3<f64>>]) -> Result<Vec<DMatrix<f64>>> {
        let frames: Vec<&[Vector3<f64>]> = frames.iter().map(Vec::as_slice).collect();
        let rows: Vec<DMatrix<f64>> = self
            .model
            .parts
            .par_iter()
            .map(|p| frame_rows(&frames, &p.vertices, &p.reference, self.model.alignment))
            .collect();
        let coefficients = self.model.encode_rows(&rows)?;
        if let Some(kept) = &mut self.truncation {
            for (all, block) in kept.iter_mut().zip(self.model.truncation(&rows, &coefficients)?) {
                all.extend(block);
            }
        }
        Ok(coefficients)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::align::align_motion;
    use mesh_core::sequence::MeshSequence;
    use mesh_core::shapes::cylinder;

    #[test]
    fn frame_blocks_cover_the_motion_in_order_with_no_short_block() {
        for n in [0, 1, 5, 6, 11, 12, 13, 40, 1000] {
            for block in [1, 6, 7, 256] {
                let cut = blocks_of(n, block);
                let starts_at_zero = cut.first().is_some_and(|r| r.start == 0);
                assert!(starts_at_zero && cut.last().unwrap().end == n, "{n} {block}: {cut:?}");
                assert!(cut.windows(2).all(|w| w[0].end == w[1].start), "{n} {block}: {cut:?}");
                let b = block.max(MIN_ENCODE_BLOCK);
                assert!(cut.iter().all(|r| r.len() >= b.min(n) && r.len() < 2 * b.max(1)), "{n} {block}: {cut:?}");
            }
        }
    }

    /// A cylinder whose radius and bend vary with two hidden factors: with
    /// enough components, encode/decode reproduces every frame (round trip),
    /// and the explained variance is complete.
    #[test]
    fn round_trip_on_low_rank_deformation() {
        let t = cylinder(8, 10, 0.1, 1.0);
        let frames: Vec<Vec<Vector3<f64>>> = (0..12)
            .map(|i| {
                let (a, b) = ((i as f64 * 0.7).sin(), (i as f64 * 0.3).cos());
                t.vertices
                    .iter()
                    .map(|v| Vector3::new(v.x * (1.0 + 0.2 * a), v.y, v.z + 0.1 * b * v.y * v.y))
                    .collect()
            })
            .collect();
        let seq = MeshSequence::new(t.faces.clone(), frames);
        let aligned = align_motion(&t, &seq).unwrap();
        let seg = whole_body(t.n_vertices());
        let (model, reports) = fit(
            &t.vertices,
            &seg,
            &[&aligned],
            Components::Count(20),
            PartAlignment::Part,
        )
        .unwrap();
        assert!(reports[0].components <= 11);
        assert!(reports[0].explained_variance > 1.0 - 1e-9);
        assert!(reports[0].reconstruction_rms_m < 1e-9, "{:?}", reports[0]);
        let coeffs = model.encode(&aligned).unwrap();
        let decoded = model.decode(&coeffs).unwrap();
        // Decoded parts are in the reference frame: compare after Procrustes.
        for (f, frame) in decoded[0].iter().zip(&aligned.frames) {
            let m = procrustes(f, frame, None);
            for (a, b) in f.iter().zip(frame) {
                assert!((m.apply(a) - b).norm() < 1e-9);
            }
        }
    }

    /// The frames encoded a block at a time as they arrive give the bits `encode` gives on the
    /// whole motion, for motions shorter and longer than a block and around the block edges, for
    /// blocks of the fewest frames and the most, on both product paths (3 and 8 components) and
    /// both part alignments; a block is the most frames up to 32 MiB.
    #[test]
    fn frame_encoder_gives_the_whole_motion_encoding_to_the_bit() {
        let t = cylinder(6, 8, 0.1, 1.0);
        let frame = |i: usize| -> Vec<Vector3<f64>> {
            let x = i as f64;
            let (a, b, c) = ((x * 0.7).sin(), (x * 0.31).cos(), (x * 0.053).sin());
            t.vertices
                .iter()
                .map(|v| Vector3::new(v.x * (1.0 + 0.2 * a) + 0.01 * c * v.y, v.y + 0.05 * c * v.x, v.z + 0.1 * b * v.y * v.y))
                .collect()
        };
        let longest = 3 * ENCODE_BLOCK + 7;
        let seq = MeshSequence::new(t.faces.clone(), (0..longest).map(frame).collect());
        let aligned = align_motion(&t, &seq).unwrap();
        let seg = whole_body(t.n_vertices());
        for alignment in [PartAlignment::Body, PartAlignment::Part] {
            let fit_with = |m| fit(&t.vertices, &seg, &[&aligned], Components::Count(m), alignment).unwrap().0;
            let mut model = fit_with(3);
            model.parts.extend(fit_with(8).parts);
            assert_eq!((model.parts[0].pca.n_components(), model.parts[1].pca.n_components()), (3, 8));
            let blocks = [6, 7, 13, ENCODE_BLOCK].into_iter().flat_map(|b| {
                [1, 5, 6, b, 2 * b - 1, 2 * b, 2 * b + 1, 2 * b + 5, 3 * b + 7, longest].map(|n| (b, n))
            });
            for (block, n) in blocks {
                let mut motion = aligned.clone();
                motion.frames.truncate(n);
                let whole = model.encode(&motion).unwrap();
                let mut enc = FrameEncoder::with_block(&model, block);
                for f in &motion.frames {
                    enc.push(f.clone()).unwrap();
                }
                let streamed = enc.finish(&motion.capture.template_sha256).unwrap();
                for (k, (a, b)) in whole.iter().zip(&streamed).enumerate() {
                    assert_eq!(a.shape(), b.shape(), "{n} frames, part {k}");
                    let bits = |m: &DMatrix<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert!(bits(a) == bits(b), "{alignment:?}, blocks of {block}, {n} frames, part {k}: coefficients differ");
                }
            }
        }
        assert_eq!((frames_per_block(48), frames_per_block(100_000), frames_per_block(10_000_000)), (ENCODE_BLOCK, 13, MIN_ENCODE_BLOCK));
        let model = fit(&t.vertices, &seg, &[&aligned], Components::Count(3), PartAlignment::Body).unwrap().0;
        let mut enc = FrameEncoder::new(&model);
        enc.push(frame(0)).unwrap();
        let err = enc.push(frame(0)[1..].to_vec()).unwrap_err().to_string();
        assert!(err.contains("frame 1 has 47 vertices but the PCA model was fitted on 48"), "{err}");
    }

}

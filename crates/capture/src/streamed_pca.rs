//! `pca-fit` in a memory bound that does not grow with the training motions' length: the frames
//! are read as they are decoded ([`TrainingFrames`]: the `.aligned` files read again on every
//! pass), never held all at once once they exceed the bound.
//!
//! Each part's PCA is the one [`gp::pca::Pca::fit`] computes (transfer paper §4, "PCA Dimension
//! Reduction"), built from sums over frames instead of the `F x D` data matrix:
//! * a first pass counts the frames and sums each part's rows (`F`, the mean `μ`); while the
//!   rows of every part fit in half the bound they are also kept, and the part is then fitted by
//!   `Pca::fit` itself on them (the model is the in-memory fit's, to the bit);
//! * otherwise, with the centred rows `c_j = x_j - μ`, a part of `F <= D` (frames fewer than
//!   dimensions) builds the `F x F` Gram matrix `G_ij = c_i · c_j` a block of `B` rows at a time
//!   (one pass per block: the block's rows are kept, and every later frame's row is multiplied
//!   with them, `BATCH` frames per product), and a part of `F > D` the `D x D` scatter matrix
//!   `S = Σ_j c_j c_jᵀ` in one pass. Either is eigen-decomposed (`G = U Λ Uᵀ` or `S = V Λ Vᵀ`,
//!   same `λ_k`), the components kept as `Pca::fit` keeps them (rank tolerance, count or
//!   explained variance), and for the Gram route one more pass forms the axes
//!   `v_k = Σ_j u_jk c_j / sqrt(λ_k)` (the right singular vectors of the centred data);
//! * a last pass encodes and decodes every frame for the reconstruction error.
//!
//! Whether rows are held, how parts are grouped and how many rows a block keeps are decided
//! from the whole segmentation, whichever parts are fitted, so that a part fitted alone
//! (`pca-fit --part`) is the whole fit's part to the bit (`merge-parts` joins them into the
//! whole model's bytes).
//!
//! Memory: the bound covers the kept rows (half), and in the streamed routes the `min(F, D)²`
//! matrices of the parts fitted together (half: parts are fitted in groups that fit it, each
//! group with its own passes) and the block rows (half). The model itself (`m x D` per part) and
//! the eigen-decomposition's workspace (a few copies of one part's matrix) come on top. A part
//! whose `min(F, D)²` matrix alone exceeds half the bound is still fitted exactly, alone,
//! above the bound. The result is deterministic for any thread count: every sum over frames is
//! formed in the frames' order, and the parts' work, done in parallel, is independent.

use gp::linalg::symmetric_eigen;
use gp::pca::{Components, Pca};
use mesh_core::cli::ProgressBar;
use mesh_core::segmentation::{Part, Segmentation};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, DVector, Vector3};
use rayon::prelude::*;

use crate::align::AlignedMotion;
use crate::part_pca::{aligned_part_row, fit_part_rows, part_result, PartAlignment, PartPca, PartReport, PcaModel};

/// Frames whose rows are gathered before they are multiplied with the kept block (the width of
/// the products that build the Gram and scatter matrices).
const BATCH: usize = 64;

/// The training frames of a fit, which can be read any number of times, each time the same.
pub trait TrainingFrames {
    /// Hands every frame of every motion in order to `sink` (the motion's index and the
    /// frame); the first error stops the pass and is returned.
    fn pass(&mut self, sink: &mut dyn FnMut(usize, &[Vector3<f64>]) -> Result<()>) -> Result<()>;

    /// The anchor of every motion (the vertices it was aligned on), known after a pass.
    fn anchors(&self) -> Vec<Vec<u32>>;
}

/// Motions held in memory as training frames.
pub struct HeldMotions<'a>(pub &'a [&'a AlignedMotion]);

impl TrainingFrames for HeldMotions<'_> {
    fn pass(&mut self, sink: &mut dyn FnMut(usize, &[Vector3<f64>]) -> Result<()>) -> Result<()> {
        for (k, m) in self.0.iter().enumerate() {
            for f in &m.frames {
                sink(k, f)?;
            }
        }
        Ok(())
    }

    fn anchors(&self) -> Vec<Vec<u32>> {
        self.0.iter().map(|m| m.anchor.clone()).collect()
    }
}

/// A part as it is fitted: its vertices and its reference (the part in the template).
struct PartSpec<'a> {
    part: &'a Part,
    reference: Vec<Vector3<f64>>,
}

impl PartSpec<'_> {
    fn dim(&self) -> usize {
        3 * self.part.vertices.len()
    }

    fn row(&self, frame: &[Vector3<f64>], alignment: PartAlignment) -> Vec<f64> {
        aligned_part_row(frame, &self.part.vertices, &self.reference, alignment)
    }
}

/// [`crate::part_pca::fit_selected`] on frames read `TrainingFrames::pass` by pass, within
/// `memory_budget` bytes (see the module documentation): the same checks and messages, the
/// same model to the bit when every part's rows fit in half the budget, and otherwise the same
/// model to rounding (components up to sign).
#[allow(clippy::too_many_arguments)]
pub fn fit_streamed(
    template: &[Vector3<f64>],
    parts: &Segmentation,
    frames: &mut dyn TrainingFrames,
    components: Components,
    alignment: PartAlignment,
    only: Option<usize>,
    memory_budget: usize,
    bar: &ProgressBar,
) -> Result<(PcaModel, Vec<PartReport>)> {
    let selected: Vec<&Part> = match only {
        Some(k) => vec![parts
            .parts
            .get(k)
            .ok_or_else(|| Error::invalid(format!("part index {k} of {} parts", parts.parts.len())))?],
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
    parts.check().map_err(Error::invalid)?;
    let specs: Vec<PartSpec> = selected
        .iter()
        .map(|&part| PartSpec { part, reference: part.vertices.iter().map(|&v| template[v as usize]).collect() })
        .collect();

    // Every choice below (hold or stream, groups, block rows) is made for the whole
    // segmentation, whichever parts are fitted: a part alone (`--part`) is then fitted by the
    // same sums in the same order as in the whole fit, to the bit.
    let dims: Vec<usize> = parts.parts.iter().map(|p| 3 * p.vertices.len()).collect();
    let selected_index: Vec<usize> = match only {
        Some(k) => vec![k],
        None => (0..parts.parts.len()).collect(),
    };
    let row_bytes: usize = dims.iter().map(|d| 8 * d).sum();
    let first = first_pass(frames, template.len(), &specs, alignment, row_bytes, memory_budget / 2)?;
    let anchors = frames.anchors();
    let anchor = anchors.first().cloned().unwrap_or_default();
    if anchors.iter().any(|a| *a != anchor) {
        return Err(Error::invalid(
            "the aligned motions were aligned on different vertices (align --frame): align them alike",
        ));
    }
    let fitted: Vec<(PartPca, PartReport)> = match first.held {
        Some(held) => specs
            .into_par_iter()
            .zip(held)
            .map(|(s, rows)| {
                let d = s.dim();
                let data = DMatrix::from_vec(d, first.n_frames, rows).transpose();
                let fit = fit_part_rows(s.part, s.reference, &data, components);
                bar.inc(1);
                fit
            })
            .collect::<Result<_>>()?,
        None => {
            let plan = Plan { dims, selected: selected_index, memory_budget };
            fit_in_groups(frames, template.len(), specs, &plan, &first, components, alignment, bar)?
        }
    };
    bar.finish_and_clear();
    let (parts_pca, reports) = fitted.into_iter().unzip();
    Ok((
        PcaModel { n_vertices: parts.n_vertices, parts: parts_pca, alignment, anchor, template_sha256: String::new() },
        reports,
    ))
}

/// What the first pass learns: the frame count, every part's row sum and, while they fit in
/// the bound, every part's rows (row-major, a frame after another).
struct FirstPass {
    n_frames: usize,
    sums: Vec<DVector<f64>>,
    held: Option<Vec<Vec<f64>>>,
}

fn first_pass(
    frames: &mut dyn TrainingFrames,
    n_vertices: usize,
    specs: &[PartSpec],
    alignment: PartAlignment,
    row_bytes: usize,
    hold_limit: usize,
) -> Result<FirstPass> {
    let mut first = FirstPass {
        n_frames: 0,
        sums: specs.iter().map(|s| DVector::zeros(s.dim())).collect(),
        held: Some(vec![Vec::new(); specs.len()]),
    };
    frames.pass(&mut |k, frame| {
        if frame.len() != n_vertices {
            return Err(Error::invalid(format!(
                "aligned motion {} has {} vertices per frame, the template {n_vertices}",
                k + 1,
                frame.len()
            )));
        }
        first.n_frames += 1;
        if (first.n_frames * row_bytes) > hold_limit {
            first.held = None;
        }
        let held = first.held.as_mut();
        let mut held_rows: Vec<Option<&mut Vec<f64>>> = match held {
            Some(h) => h.iter_mut().map(Some).collect(),
            None => specs.iter().map(|_| None).collect(),
        };
        specs.par_iter().zip(first.sums.par_iter_mut()).zip(held_rows.par_iter_mut()).for_each(|((s, sum), keep)| {
            let row = s.row(frame, alignment);
            for (a, x) in sum.iter_mut().zip(&row) {
                *a += x;
            }
            if let Some(keep) = keep {
                keep.extend_from_slice(&row);
            }
        });
        Ok(())
    })?;
    Ok(first)
}

/// The sizes every choice of the streamed routes is made from: each part's dimension (of every
/// part of the segmentation), the fitted parts (indices into it) and the memory budget.
struct Plan {
    dims: Vec<usize>,
    selected: Vec<usize>,
    memory_budget: usize,
}

impl Plan {
    /// The parts of the segmentation in groups whose `min(F, D)²` matrices fit in half the
    /// budget (a part alone when its own matrix does not), in order.
    fn groups(&self, f: usize) -> Vec<Vec<usize>> {
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut used = usize::MAX;
        for (k, &d) in self.dims.iter().enumerate() {
            let b = 8 * f.min(d).pow(2);
            if used.saturating_add(b) > self.memory_budget / 2 {
                groups.push(Vec::new());
                used = 0;
            }
            groups.last_mut().expect("a group was opened").push(k);
            used += b;
        }
        groups
    }

    /// Rows of the Gram block kept per pass for `group`: as many as fit in half the budget for
    /// every part of the group taking the Gram route (`F <= D`).
    fn block_rows(&self, group: &[usize], f: usize) -> usize {
        let width: usize = group.iter().map(|&k| self.dims[k]).filter(|&d| f <= d).sum();
        (self.memory_budget / 2 / (8 * width.max(1))).clamp(1, f)
    }
}

/// The streamed routes: the fitted parts of each group of [`Plan::groups`] fitted together, each
/// group with its own passes.
#[allow(clippy::too_many_arguments)]
fn fit_in_groups(
    frames: &mut dyn TrainingFrames,
    n_vertices: usize,
    specs: Vec<PartSpec>,
    plan: &Plan,
    first: &FirstPass,
    components: Components,
    alignment: PartAlignment,
    bar: &ProgressBar,
) -> Result<Vec<(PartPca, PartReport)>> {
    let f = first.n_frames;
    if f < 2 {
        let name = specs.first().map(|s| s.part.name.as_str()).unwrap_or("");
        let d = specs.first().map(|s| s.dim()).unwrap_or(0);
        return Err(Error::invalid(format!(
            "part '{name}': invalid input: PCA needs at least 2 frames and 1 dimension, got {f} x {d}"
        )));
    }
    let means: Vec<DVector<f64>> = first.sums.iter().map(|s| s / f as f64).collect();
    let mut fitted: Vec<Option<(PartPca, PartReport)>> = specs.iter().map(|_| None).collect();
    let mut specs: Vec<Option<PartSpec>> = specs.into_iter().map(Some).collect();
    for group in plan.groups(f) {
        // Positions in `specs` of the group's fitted parts.
        let members: Vec<usize> = group.iter().filter_map(|k| plan.selected.iter().position(|s| s == k)).collect();
        if members.is_empty() {
            continue;
        }
        let member_specs: Vec<PartSpec> = members.iter().map(|&i| specs[i].take().expect("each part in one group")).collect();
        let group_means: Vec<&DVector<f64>> = members.iter().map(|&i| &means[i]).collect();
        let block_rows = plan.block_rows(&group, f);
        let results = fit_group(frames, n_vertices, member_specs, &group_means, f, components, alignment, block_rows)?;
        for (i, r) in members.into_iter().zip(results) {
            fitted[i] = Some(r);
            bar.inc(1);
        }
    }
    Ok(fitted.into_iter().map(|r| r.expect("every part fitted")).collect())
}

/// Which matrix a part is decomposed by.
#[derive(Clone, Copy, PartialEq)]
enum Route {
    /// `F x F` Gram matrix of the centred rows (`F <= D`, as `Pca::fit`).
    Gram,
    /// `D x D` scatter matrix of the centred rows (`F > D`).
    Scatter,
}

/// Rows of a pass gathered for one product: `rows` (`BATCH x D`, the first `idx.len()` in use)
/// and each row's frame index.
struct Pending {
    rows: DMatrix<f64>,
    idx: Vec<usize>,
}

impl Pending {
    fn new(d: usize) -> Self {
        Pending { rows: DMatrix::zeros(BATCH, d), idx: Vec::with_capacity(BATCH) }
    }

    /// Adds frame `j`'s row; true when the batch is full.
    fn push(&mut self, j: usize, row: &[f64]) -> bool {
        let r = self.idx.len();
        for (c, x) in row.iter().enumerate() {
            self.rows[(r, c)] = *x;
        }
        self.idx.push(j);
        self.idx.len() == BATCH
    }

    /// The rows in use.
    fn filled(&self) -> DMatrix<f64> {
        self.rows.rows(0, self.idx.len()).into_owned()
    }
}

/// One part's work in the current pass.
enum Work {
    /// Gram rows `[b0, b0 + block.nrows())`: the block's own rows are kept, every later row is
    /// multiplied with them.
    GramBlock { g: DMatrix<f64>, b0: usize, block: DMatrix<f64>, pending: Pending },
    /// The scatter matrix of all rows.
    Scatter { s: DMatrix<f64>, pending: Pending },
    /// The axes `Σ_j w_j c_jᵀ`, `w` = the kept Gram eigenvectors over `sqrt(λ)` (`F x m`).
    Axes { w: DMatrix<f64>, axes: DMatrix<f64>, pending: Pending },
    /// The reconstruction's squared error of the raw rows.
    Reconstruction { pca: Pca, squared: f64, pending: Pending },
}

impl Work {
    /// Takes frame `j`'s row (centred except for the reconstruction).
    fn take(&mut self, j: usize, row: &[f64]) {
        match self {
            Work::GramBlock { g, b0, block, pending } => {
                let b1 = *b0 + block.nrows();
                if j < *b0 {
                } else if j < b1 {
                    for (c, x) in row.iter().enumerate() {
                        block[(j - *b0, c)] = *x;
                    }
                    if j + 1 == b1 {
                        let own = &*block * block.transpose();
                        g.view_mut((*b0, *b0), own.shape()).copy_from(&own);
                    }
                } else if pending.push(j, row) {
                    Self::flush_gram(g, *b0, block, pending);
                }
            }
            Work::Scatter { s, pending } => {
                if pending.push(j, row) {
                    Self::flush_scatter(s, pending);
                }
            }
            Work::Axes { w, axes, pending } => {
                if pending.push(j, row) {
                    Self::flush_axes(w, axes, pending);
                }
            }
            Work::Reconstruction { pca, squared, pending } => {
                if pending.push(j, row) {
                    *squared += Self::flush_reconstruction(pca, pending);
                }
            }
        }
    }

    /// Uses the rows still pending at the end of a pass.
    fn end(&mut self) {
        match self {
            Work::GramBlock { g, b0, block, pending } => Self::flush_gram(g, *b0, block, pending),
            Work::Scatter { s, pending } => Self::flush_scatter(s, pending),
            Work::Axes { w, axes, pending } => Self::flush_axes(w, axes, pending),
            Work::Reconstruction { pca, squared, pending } => *squared += Self::flush_reconstruction(pca, pending),
        }
    }

    fn flush_gram(g: &mut DMatrix<f64>, b0: usize, block: &DMatrix<f64>, pending: &mut Pending) {
        if pending.idx.is_empty() {
            return;
        }
        let products = block * pending.filled().transpose();
        for (c, &j) in pending.idx.iter().enumerate() {
            for r in 0..block.nrows() {
                g[(b0 + r, j)] = products[(r, c)];
                g[(j, b0 + r)] = products[(r, c)];
            }
        }
        pending.idx.clear();
    }

    fn flush_scatter(s: &mut DMatrix<f64>, pending: &mut Pending) {
        if pending.idx.is_empty() {
            return;
        }
        let rows = pending.filled();
        s.gemm_tr(1.0, &rows, &rows, 1.0);
        pending.idx.clear();
    }

    fn flush_axes(w: &DMatrix<f64>, axes: &mut DMatrix<f64>, pending: &mut Pending) {
        if pending.idx.is_empty() {
            return;
        }
        let weights = DMatrix::from_fn(pending.idx.len(), w.ncols(), |r, k| w[(pending.idx[r], k)]);
        axes.gemm_tr(1.0, &weights, &pending.filled(), 1.0);
        pending.idx.clear();
    }

    /// `‖decode(encode(X)) - X‖²` of the pending rows (as `Pca::reconstruction_rms` forms it).
    fn flush_reconstruction(pca: &Pca, pending: &mut Pending) -> f64 {
        if pending.idx.is_empty() {
            return 0.0;
        }
        let rows = pending.filled();
        pending.idx.clear();
        let back = pca.encode(&rows).and_then(|c| pca.decode(&c)).expect("rows of the basis' dimension");
        (back - rows).norm_squared()
    }
}

/// Runs one pass in which part `k` does `work[k]` (none: skipped) on every frame from `from`
/// on, its rows centred on `means[k]` unless `raw[k]`.
#[allow(clippy::too_many_arguments)]
fn pass_rows(
    frames: &mut dyn TrainingFrames,
    n_vertices: usize,
    specs: &[PartSpec],
    means: &[&DVector<f64>],
    alignment: PartAlignment,
    from: usize,
    n_frames: usize,
    work: &mut [Option<Work>],
) -> Result<()> {
    let mut j = 0;
    frames.pass(&mut |_, frame| {
        if frame.len() != n_vertices {
            return Err(Error::invalid("the training frames changed between two passes"));
        }
        if j >= from {
            specs.par_iter().zip(means.par_iter()).zip(work.par_iter_mut()).for_each(|((s, mean), w)| {
                if let Some(w) = w {
                    let mut row = s.row(frame, alignment);
                    if !matches!(w, Work::Reconstruction { .. }) {
                        for (x, m) in row.iter_mut().zip(mean.iter()) {
                            *x -= m;
                        }
                    }
                    w.take(j, &row);
                }
            });
        }
        j += 1;
        Ok(())
    })?;
    if j != n_frames {
        return Err(Error::invalid(format!("the training frames changed between two passes ({n_frames} frames, then {j})")));
    }
    work.par_iter_mut().flatten().for_each(Work::end);
    Ok(())
}

/// Fits the parts of one group (see the module documentation) on `f` frames.
#[allow(clippy::too_many_arguments)]
fn fit_group(
    frames: &mut dyn TrainingFrames,
    n_vertices: usize,
    specs: Vec<PartSpec>,
    means: &[&DVector<f64>],
    f: usize,
    components: Components,
    alignment: PartAlignment,
    block_rows: usize,
) -> Result<Vec<(PartPca, PartReport)>> {
    let routes: Vec<Route> = specs.iter().map(|s| if f <= s.dim() { Route::Gram } else { Route::Scatter }).collect();
    // The decomposed matrices, built over one pass (scatter) or one pass per block (Gram).
    let mut matrices: Vec<DMatrix<f64>> = specs
        .iter()
        .zip(&routes)
        .map(|(s, r)| match r {
            Route::Gram => DMatrix::zeros(f, f),
            Route::Scatter => DMatrix::zeros(s.dim(), s.dim()),
        })
        .collect();
    let mut b0 = 0;
    loop {
        let rows = block_rows.min(f - b0);
        let mut work: Vec<Option<Work>> = specs
            .iter()
            .zip(&routes)
            .zip(matrices.iter_mut())
            .map(|((s, r), m)| match r {
                Route::Gram => Some(Work::GramBlock {
                    g: std::mem::take(m),
                    b0,
                    block: DMatrix::zeros(rows, s.dim()),
                    pending: Pending::new(s.dim()),
                }),
                Route::Scatter if b0 == 0 => Some(Work::Scatter { s: std::mem::take(m), pending: Pending::new(s.dim()) }),
                Route::Scatter => None,
            })
            .collect();
        let from = if routes.contains(&Route::Scatter) && b0 == 0 { 0 } else { b0 };
        pass_rows(frames, n_vertices, &specs, means, alignment, from, f, &mut work)?;
        for (m, w) in matrices.iter_mut().zip(work) {
            match w {
                Some(Work::GramBlock { g, .. }) | Some(Work::Scatter { s: g, .. }) => *m = g,
                _ => {}
            }
        }
        b0 += rows;
        if b0 >= f {
            break;
        }
    }
    // Eigen-decompositions, one part at a time (each frees its matrix).
    let mut bases: Vec<Basis> = Vec::with_capacity(specs.len());
    for ((s, r), (m, mean)) in specs.iter().zip(&routes).zip(matrices.into_iter().zip(means)) {
        let basis = Basis::new(m, *r, (*mean).clone(), f, components)
            .map_err(|e| Error::invalid(format!("part '{}': {e}", s.part.name)))?;
        bases.push(basis);
    }
    // The Gram route's axes.
    if routes.contains(&Route::Gram) {
        let mut work: Vec<Option<Work>> = specs
            .iter()
            .zip(&mut bases)
            .map(|(s, b)| {
                b.weights.take().map(|w| Work::Axes {
                    axes: DMatrix::zeros(w.ncols(), s.dim()),
                    w,
                    pending: Pending::new(s.dim()),
                })
            })
            .collect();
        pass_rows(frames, n_vertices, &specs, means, alignment, 0, f, &mut work)?;
        for (b, w) in bases.iter_mut().zip(work) {
            if let Some(Work::Axes { axes, .. }) = w {
                b.pca.components = axes;
            }
        }
    }
    // The reconstruction error on the training rows.
    let mut work: Vec<Option<Work>> = specs
        .iter()
        .zip(bases)
        .map(|(s, b)| Some(Work::Reconstruction { pca: b.pca, squared: 0.0, pending: Pending::new(s.dim()) }))
        .collect();
    pass_rows(frames, n_vertices, &specs, means, alignment, 0, f, &mut work)?;
    Ok(specs
        .into_iter()
        .zip(work)
        .map(|(s, w)| match w {
            Some(Work::Reconstruction { pca, squared, .. }) => {
                let rms = (squared / (f * s.dim()).max(1) as f64).sqrt();
                part_result(s.part, s.reference, pca, rms)
            }
            _ => unreachable!("every part's last work is its reconstruction"),
        })
        .collect())
}

/// A part's PCA from its decomposed matrix: complete for the scatter route; for the Gram route
/// the axes are still to be formed from `weights` (`F x m`: `u_k / sqrt(λ_k)`).
struct Basis {
    pca: Pca,
    weights: Option<DMatrix<f64>>,
}

impl Basis {
    /// Keeps the components as [`Pca::fit`] keeps them (the same rank tolerance and choice).
    fn new(matrix: DMatrix<f64>, route: Route, mean: DVector<f64>, f: usize, choice: Components) -> std::result::Result<Self, String> {
        let d = mean.len();
        if choice == Components::Count(0) {
            return Err("invalid input: the PCA needs at least 1 component, got 0".into());
        }
        if matrix.iter().any(|x| !x.is_finite()) {
            return Err("invalid input: PCA data contains non-finite values".into());
        }
        let (lambda, u) = symmetric_eigen(&matrix).map_err(|e| e.to_string())?;
        drop(matrix);
        let total: f64 = lambda.iter().map(|v| v.max(0.0)).sum();
        let tol = lambda[0].max(0.0) * (f.max(d) as f64) * f64::EPSILON * 10.0;
        let rank = lambda.iter().take_while(|&&v| v > tol && v > 0.0).count();
        let m = match choice {
            Components::Count(m) => m.min(rank),
            Components::ExplainedVariance(r) => {
                if !(r > 0.0 && r <= 1.0) {
                    return Err(format!("invalid input: explained-variance ratio must be in (0, 1], got {r}"));
                }
                let mut acc = 0.0;
                let mut m = rank;
                for (k, v) in lambda.iter().take(rank).enumerate() {
                    acc += v;
                    if acc >= r * total * (1.0 - 1e-12) {
                        m = k + 1;
                        break;
                    }
                }
                m
            }
        };
        let denom = (f - 1) as f64;
        let (components, weights) = match route {
            Route::Scatter => (u.columns(0, m).transpose(), None),
            Route::Gram => {
                let mut w = u.columns(0, m).into_owned();
                for k in 0..m {
                    w.column_mut(k).unscale_mut(lambda[k].sqrt());
                }
                (DMatrix::zeros(m, d), Some(w))
            }
        };
        let pca = Pca {
            mean,
            components,
            variances: lambda[..m].iter().map(|v| v / denom).collect(),
            total_variance: total / denom,
            rank,
        };
        Ok(Basis { pca, weights })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::align::CaptureInfo;
    use crate::part_pca::{fit_selected, whole_body};

    /// A reproducible value in [-1, 1) from an index (SplitMix64).
    fn noise(i: u64) -> f64 {
        let mut z = i.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// `n_frames` frames of `n_vertices` points: a mean shape plus six factors of decreasing
    /// scale plus small noise (distinct singular values), split over two motions.
    fn motions(n_frames: usize, n_vertices: usize) -> Vec<AlignedMotion> {
        let scale = [1.0, 0.6, 0.35, 0.2, 0.1, 0.05];
        let frame = |f: usize| -> Vec<Vector3<f64>> {
            (0..n_vertices)
                .map(|v| {
                    let c = |a: usize| {
                        let base = 1.0 + noise((v * 3 + a) as u64);
                        let factors: f64 = scale
                            .iter()
                            .enumerate()
                            .map(|(k, s)| s * noise(1_000_000 + (f * 7 + k) as u64) * noise(2_000_000 + ((v * 3 + a) * 7 + k) as u64))
                            .sum();
                        base + factors + 1e-3 * noise(3_000_000 + (f * n_vertices * 3 + v * 3 + a) as u64)
                    };
                    Vector3::new(c(0), c(1), c(2))
                })
                .collect()
        };
        let split = n_frames / 3;
        [0..split, split..n_frames]
            .into_iter()
            .map(|range| AlignedMotion {
                faces: Vec::new(),
                frames: range.clone().map(frame).collect(),
                poses: Vec::new(),
                displacements: Vec::new(),
                anchor: vec![0, 1],
                capture: CaptureInfo { fps: 25.0, up: [0.0, 1.0, 0.0], template_sha256: String::new() },
            })
            .collect()
    }

    /// The centred data of every frame, one row per frame (the whole body, no part alignment).
    fn data(ms: &[AlignedMotion]) -> DMatrix<f64> {
        let rows: Vec<Vec<f64>> = ms.iter().flat_map(|m| &m.frames).map(|f| f.iter().flat_map(|p| [p.x, p.y, p.z]).collect()).collect();
        DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
    }

    fn fit_whole(ms: &[AlignedMotion], m: usize, budget: usize) -> (PcaModel, Vec<PartReport>) {
        let refs: Vec<&AlignedMotion> = ms.iter().collect();
        let template = ms[0].frames[0].clone();
        let seg = whole_body(template.len());
        fit_streamed(&template, &seg, &mut HeldMotions(&refs), Components::Count(m), PartAlignment::Body, None, budget, &ProgressBar::hidden())
            .unwrap()
    }

    /// On a random matrix, the streamed fit by the Gram route (frames fewer than dimensions,
    /// several blocks and batches) and by the scatter route (frames more than dimensions), and
    /// the fit of held rows, all equal the singular value decomposition of the centred data:
    /// the axes (up to sign) are its right singular vectors, the variances `σ_k² / (F - 1)`, the
    /// explained variance `Σ_{k<m} σ_k² / Σ σ_k²`, the reconstruction error
    /// `sqrt(3 Σ_{k>=m} σ_k² / (F D))`.
    #[test]
    fn the_streamed_pca_equals_the_svd_of_the_centred_data() {
        // (frames, vertices, budget in bytes): Gram route in blocks of 5 rows, scatter route,
        // and held rows.
        for (f, n, budget) in [(150, 70, 2 * 8 * 210 * 5), (150, 20, 2 * 8 * 60 * 60), (150, 70, 1 << 30)] {
            let ms = motions(f, n);
            let x = data(&ms);
            let d = x.ncols();
            let mean = x.row_mean();
            let centred = DMatrix::from_fn(f, d, |i, j| x[(i, j)] - mean[j]);
            let svd = centred.clone().svd(false, true);
            let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
            order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
            let sigma2: Vec<f64> = order.iter().map(|&k| svd.singular_values[k].powi(2)).collect();
            let v_t = svd.v_t.unwrap();
            let m = 4;
            let (model, reports) = fit_whole(&ms, m, budget);
            let pca = &model.parts[0].pca;
            assert_eq!(pca.n_components(), m);
            let what = format!("{f} frames, {d} dimensions, budget {budget}");
            for k in 0..m {
                let want = sigma2[k] / (f - 1) as f64;
                assert!((pca.variances[k] - want).abs() < 1e-10 * want, "{what}: variance {k}: {} vs {want}", pca.variances[k]);
                let cos = pca.components.row(k).dot(&v_t.row(order[k]));
                assert!((cos.abs() - 1.0).abs() < 1e-9, "{what}: axis {k}: |cos| = {}", cos.abs());
            }
            for j in 0..d {
                assert!((pca.mean[j] - mean[j]).abs() < 1e-12, "{what}: mean {j}");
            }
            let total: f64 = sigma2.iter().sum();
            let explained: f64 = sigma2[..m].iter().sum::<f64>() / total;
            assert!((reports[0].explained_variance - explained).abs() < 1e-10, "{what}: explained variance");
            let rms = (3.0 * sigma2[m..].iter().sum::<f64>() / (f * d) as f64).sqrt();
            assert!((reports[0].reconstruction_rms_m - rms).abs() < 1e-9 * rms, "{what}: reconstruction {} vs {rms}", reports[0].reconstruction_rms_m);
            assert_eq!(model.anchor, vec![0, 1]);
        }
    }

    /// When the rows fit in half the budget, the fit is the in-memory fit to the bit, for one
    /// part alone or every part, with either part alignment and a variance-chosen count.
    #[test]
    fn held_rows_give_the_in_memory_fit_to_the_bit() {
        let ms = motions(40, 30);
        let refs: Vec<&AlignedMotion> = ms.iter().collect();
        let template = ms[0].frames[0].clone();
        let mut seg = whole_body(30);
        let mut second = seg.parts[0].clone();
        second.name = "upper".into();
        second.parent = Some("body".into());
        second.vertices = (10..30).collect();
        seg.parts[0].vertices = (0..15).collect();
        seg.parts.push(second);
        for alignment in [PartAlignment::Body, PartAlignment::Part] {
            for choice in [Components::Count(5), Components::ExplainedVariance(0.9)] {
                for only in [None, Some(1)] {
                    let bar = ProgressBar::hidden();
                    let want = fit_selected(&template, &seg, &refs, choice, alignment, only, &bar).unwrap();
                    let got = fit_streamed(&template, &seg, &mut HeldMotions(&refs), choice, alignment, only, 1 << 30, &bar).unwrap();
                    assert!(want == got, "{alignment:?} {choice:?} {only:?}");
                    let streamed = fit_streamed(&template, &seg, &mut HeldMotions(&refs), choice, alignment, only, 1000, &bar).unwrap();
                    if only.is_none() {
                        // One part alone is the whole fit's part to the bit, held or streamed,
                        // in a group of its own (1,000 bytes) or with the other part (40,000).
                        for budget in [1 << 30, 1000, 40_000] {
                            let whole = fit_streamed(&template, &seg, &mut HeldMotions(&refs), choice, alignment, None, budget, &bar).unwrap();
                            let one = fit_streamed(&template, &seg, &mut HeldMotions(&refs), choice, alignment, Some(1), budget, &bar).unwrap();
                            assert!(one.0.parts[0] == whole.0.parts[1] && one.1[0] == whole.1[1], "{alignment:?} {choice:?} budget {budget}");
                        }
                    }
                    assert!(want != streamed, "a budget of 1,000 bytes streams: the sums differ in the last digits");
                    for (a, b) in want.0.parts.iter().zip(&streamed.0.parts) {
                        assert_eq!(a.pca.n_components(), b.pca.n_components(), "{alignment:?} {choice:?}");
                        for k in 0..a.pca.n_components() {
                            let cos = a.pca.components.row(k).dot(&b.pca.components.row(k));
                            assert!((cos.abs() - 1.0).abs() < 1e-9, "{alignment:?} {choice:?} axis {k}");
                        }
                    }
                }
            }
        }
    }

    /// Bad input fails with the in-memory fit's messages: a frame of another vertex count,
    /// motions aligned on different anchors, a single frame.
    #[test]
    fn bad_training_frames_fail_as_the_in_memory_fit_fails() {
        let mut ms = motions(12, 10);
        let template = ms[0].frames[0].clone();
        let seg = whole_body(10);
        let fit_both = |ms: &[AlignedMotion]| {
            let refs: Vec<&AlignedMotion> = ms.iter().collect();
            let bar = ProgressBar::hidden();
            let c = Components::Count(3);
            let want = fit_selected(&template, &seg, &refs, c, PartAlignment::Body, None, &bar).unwrap_err().to_string();
            for budget in [1 << 30, 100] {
                let got = fit_streamed(&template, &seg, &mut HeldMotions(&refs), c, PartAlignment::Body, None, budget, &bar).unwrap_err().to_string();
                assert_eq!(got, want);
            }
            want
        };
        let mut short = ms.clone();
        short[1].frames[2].pop();
        assert!(fit_both(&short).contains("aligned motion 2 has 9 vertices per frame, the template 10"));
        ms[1].anchor = vec![3];
        assert!(fit_both(&ms).contains("aligned on different vertices"));
        let mut one = motions(3, 10);
        one.truncate(1);
        assert_eq!(one[0].frames.len(), 1);
        assert!(fit_both(&one).contains("at least 2 frames"));
    }
}

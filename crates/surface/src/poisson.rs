//! Poisson reconstruction `L x = div J` with Dirichlet vertices (CVPR
//! §6.1 uses it to rebuild the corrected part, §6.2 to merge parts).
//!
//! Minimising `Σ_f A_f |∇x - J_f|²` over the free vertices, with the fixed ones held at given
//! positions, gives `L_FF x_F = (Gᵀ A J)_F - L_FC x_C` (`L = Gᵀ A G`, cotangent Laplacian).
//! To keep one sparsity pattern whatever the fixed set is, the solver keeps all `|V|` unknowns:
//! rows and columns of fixed vertices are zeroed except the diagonal, and their right-hand
//! side is `L_ii x_i`. The pattern then only depends on the mesh topology, so the symbolic
//! Cholesky factorisation (faer `SymbolicLlt`) is computed once per topology and reused when
//! the values change (new geometry, new fixed set); the numeric factorisation is reused for
//! every right-hand side (3 coordinates at once, and across frames).

use crate::deformation_gradient::GradientOperator;
use crate::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SparseColMat;
use faer::{Conj, Mat, Par, Side};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// Which sparse Cholesky factorisation faer runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Factorisation {
    /// faer's own choice (its flop-ratio heuristic; simplicial on cotangent systems of body
    /// meshes).
    #[default]
    Auto,
    /// Always supernodal: dense blocks for the fill of the separators. On the 13k-vertex demo
    /// body's stitch system it refactorises several times faster than the simplicial
    /// factorisation; results agree to rounding (not bit for bit: another operation order).
    Supernodal,
}

/// The symbolic side of a factorisation, by [`Factorisation`].
enum SymbolicKind {
    Auto(SymbolicLlt<usize>),
    Supernodal(Arc<SymbolicCholesky<usize>>),
}

/// What a factorisation of one sparsity pattern keeps whatever the values are: the pattern,
/// its symbolic Cholesky factorisation (fill-reducing ordering, elimination tree) and the
/// connected components of its graph.
struct Pattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicKind,
    /// Number of values of the numeric factor `L`.
    factor_values: usize,
    /// Connected component of every vertex in the matrix graph (a representative vertex),
    /// checked against each fixed set.
    component: Vec<usize>,
}

/// The symbolic factorisation of one sparsity pattern (one mesh topology), shared by the
/// [`PoissonSolver`]s of every geometry of that topology: [`SymbolicPoisson::factorise`] runs
/// only the numeric factorisation. A solver made this way is the one
/// [`PoissonSolver::with_factorisation`] makes, bit for bit (the same ordering and the same
/// numeric steps). Cloning shares the analysis.
#[derive(Clone)]
pub struct SymbolicPoisson {
    pattern: Arc<Pattern>,
}

impl SymbolicPoisson {
    /// Analyses `laplacian`'s pattern (its values are not read). Sets faer to sequential mode
    /// (faster on 2 cores).
    pub fn new(laplacian: &SparseColMat<usize, f64>, how: Factorisation) -> Result<Self> {
        faer::set_global_parallelism(faer::Par::Seq);
        let n = laplacian.nrows();
        if laplacian.ncols() != n {
            return Err(Error::invalid("poisson: system matrix is not square"));
        }
        let symbolic_failed =
            |e| Error::invalid(format!("poisson: symbolic factorisation failed: {e:?}"));
        let (symbolic, factor_values) = match how {
            Factorisation::Auto => {
                // The same analysis again, for the factor's size: faer's solver keeps its own
                // to itself.
                let size = factorize_symbolic_cholesky(
                    laplacian.symbolic(),
                    Side::Lower,
                    Default::default(),
                    Default::default(),
                )
                .map_err(symbolic_failed)?
                .len_val();
                let llt = SymbolicLlt::try_new(laplacian.symbolic(), Side::Lower)
                    .map_err(symbolic_failed)?;
                (SymbolicKind::Auto(llt), size)
            }
            Factorisation::Supernodal => {
                let s = factorize_symbolic_cholesky(
                    laplacian.symbolic(),
                    Side::Lower,
                    SymmetricOrdering::Amd,
                    CholeskySymbolicParams {
                        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                        ..Default::default()
                    },
                )
                .map_err(symbolic_failed)?;
                let size = s.len_val();
                (SymbolicKind::Supernodal(Arc::new(s)), size)
            }
        };
        let (cp, ri) = (laplacian.symbolic().col_ptr(), laplacian.symbolic().row_idx());
        Ok(SymbolicPoisson {
            pattern: Arc::new(Pattern {
                n,
                component: components(n, cp, ri),
                col_ptr: cp.to_vec(),
                row_idx: ri.to_vec(),
                symbolic,
                factor_values,
            }),
        })
    }

    /// The factorisation this analysis is for.
    pub fn factorisation(&self) -> Factorisation {
        match self.pattern.symbolic {
            SymbolicKind::Auto(_) => Factorisation::Auto,
            SymbolicKind::Supernodal(_) => Factorisation::Supernodal,
        }
    }

    /// Whether `laplacian` has the analysed sparsity pattern.
    pub fn matches(&self, laplacian: &SparseColMat<usize, f64>) -> bool {
        let p = &self.pattern;
        laplacian.nrows() == p.n
            && laplacian.ncols() == p.n
            && laplacian.symbolic().col_ptr() == p.col_ptr.as_slice()
            && laplacian.symbolic().row_idx() == p.row_idx.as_slice()
    }

    /// The numeric factorisation of `laplacian` (the analysed pattern) with the vertices
    /// `fixed` held.
    pub fn factorise(
        &self,
        laplacian: &SparseColMat<usize, f64>,
        fixed: &[usize],
    ) -> Result<PoissonSolver> {
        if !self.matches(laplacian) {
            return Err(Error::invalid(
                "poisson: the matrix's sparsity pattern is not the analysed one",
            ));
        }
        let mut numeric = match &self.pattern.symbolic {
            SymbolicKind::Auto(symbolic) => Numeric::Auto {
                symbolic: symbolic.clone(),
                llt: None,
            },
            SymbolicKind::Supernodal(symbolic) => {
                let req = symbolic
                    .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
                    .or(symbolic.solve_in_place_scratch::<f64>(3, Par::Seq));
                let stack = MemBuffer::try_new(req)
                    .map_err(|_| Error::invalid("poisson: out of memory"))?;
                Numeric::Supernodal {
                    values: vec![0.0; symbolic.len_val()],
                    symbolic: symbolic.clone(),
                    stack: std::sync::Mutex::new(stack),
                }
            }
        };
        let parts = factor(&self.pattern, &mut numeric, &mut laplacian.clone(), fixed)?;
        Ok(PoissonSolver {
            symbolic: self.clone(),
            numeric,
            fixed: fixed.to_vec(),
            coupling: parts.coupling,
            fixed_diag: parts.fixed_diag,
            jitter: parts.jitter,
        })
    }
}

/// The numeric side of a factorisation, with a handle on its [`SymbolicPoisson`]'s analysis.
enum Numeric {
    Auto {
        symbolic: SymbolicLlt<usize>,
        /// None only until the first factorisation.
        llt: Option<Llt<usize, f64>>,
    },
    Supernodal {
        symbolic: Arc<SymbolicCholesky<usize>>,
        values: Vec<f64>,
        /// Work space of the numeric factorisation and of a 3-column solve.
        stack: std::sync::Mutex<MemBuffer>,
    },
}

/// A factorised Poisson system with Dirichlet vertices, reusable across right-hand sides.
pub struct PoissonSolver {
    symbolic: SymbolicPoisson,
    numeric: Numeric,
    fixed: Vec<usize>,
    /// (free row, fixed slot, L value): the `L_FC x_C` coupling moved to the right-hand side.
    coupling: Vec<(usize, usize, f64)>,
    fixed_diag: Vec<f64>,
    jitter: f64,
}

impl PoissonSolver {
    /// Factorises `laplacian` (PSD cotangent form, all diagonal entries in the pattern) with
    /// the vertices `fixed` held. Sets faer to sequential mode (faster on 2 cores).
    pub fn new(laplacian: &SparseColMat<usize, f64>, fixed: &[usize]) -> Result<Self> {
        Self::with_factorisation(laplacian, fixed, Factorisation::Auto)
    }

    /// [`PoissonSolver::new`] with a chosen factorisation; [`PoissonSolver::refactor`] keeps it.
    pub fn with_factorisation(
        laplacian: &SparseColMat<usize, f64>,
        fixed: &[usize],
        how: Factorisation,
    ) -> Result<Self> {
        SymbolicPoisson::new(laplacian, how)?.factorise(laplacian, fixed)
    }

    /// The symbolic analysis this solver's factorisation reuses.
    pub fn symbolic(&self) -> &SymbolicPoisson {
        &self.symbolic
    }

    /// The factorisation this solver runs.
    pub fn factorisation(&self) -> Factorisation {
        self.symbolic.factorisation()
    }

    /// Refactorises for new values and/or a new fixed set. The symbolic factorisation is
    /// reused when the sparsity pattern is unchanged (same topology), recomputed otherwise.
    pub fn refactor(
        &mut self,
        laplacian: &SparseColMat<usize, f64>,
        fixed: &[usize],
    ) -> Result<()> {
        if !self.symbolic.matches(laplacian) {
            *self = PoissonSolver::with_factorisation(laplacian, fixed, self.factorisation())?;
            return Ok(());
        }
        self.refactor_in_place(&mut laplacian.clone(), fixed)
    }

    /// [`PoissonSolver::refactor`] that applies the Dirichlet rows and columns to `laplacian`'s
    /// values in place instead of to a copy (the caller refills it before the next use): the
    /// same factorisation without copying the matrix.
    pub fn refactor_in_place(
        &mut self,
        laplacian: &mut SparseColMat<usize, f64>,
        fixed: &[usize],
    ) -> Result<()> {
        if !self.symbolic.matches(laplacian) {
            *self = PoissonSolver::with_factorisation(laplacian, fixed, self.factorisation())?;
            return Ok(());
        }
        let parts = factor(&self.symbolic.pattern, &mut self.numeric, laplacian, fixed)?;
        self.fixed = fixed.to_vec();
        self.coupling = parts.coupling;
        self.fixed_diag = parts.fixed_diag;
        self.jitter = parts.jitter;
        Ok(())
    }

    /// Number of unknowns (vertices).
    pub fn n(&self) -> usize {
        self.symbolic.pattern.n
    }
    /// The bytes this solver holds of its own (its factor's values and the coupling to the
    /// fixed vertices; the shared analysis not counted), an estimate to bound caches by.
    pub fn bytes(&self) -> usize {
        self.symbolic.pattern.factor_values * 8
            + self.coupling.len() * std::mem::size_of::<(usize, usize, f64)>()
            + self.fixed.len() * 16
    }
    /// The Dirichlet vertices.
    pub fn fixed(&self) -> &[usize] {
        &self.fixed
    }
    /// Diagonal jitter that had to be added to factorise (0 when none was needed).
    pub fn jitter(&self) -> f64 {
        self.jitter
    }

    /// Solves `L x = rhs` on the free vertices with `x[fixed[k]] = values[k]`, for the three
    /// coordinates at once.
    pub fn solve(
        &self,
        rhs: &[Vector3<f64>],
        values: &[Vector3<f64>],
    ) -> Result<Vec<Vector3<f64>>> {
        let n = self.n();
        if rhs.len() != n || values.len() != self.fixed.len() {
            return Err(Error::invalid(format!(
                "poisson: right-hand side has {} rows and {} fixed values, expected {} and {}",
                rhs.len(),
                values.len(),
                n,
                self.fixed.len()
            )));
        }
        let mut b = Mat::<f64>::zeros(n, 3);
        for (i, r) in rhs.iter().enumerate() {
            for d in 0..3 {
                b[(i, d)] = r[d];
            }
        }
        for &(row, k, l) in &self.coupling {
            for d in 0..3 {
                b[(row, d)] -= l * values[k][d];
            }
        }
        for (k, &v) in self.fixed.iter().enumerate() {
            for d in 0..3 {
                b[(v, d)] = self.fixed_diag[k] * values[k][d];
            }
        }
        match &self.numeric {
            Numeric::Auto { llt, .. } => llt
                .as_ref()
                .expect("factorised on construction")
                .solve_in_place(b.as_mut()),
            Numeric::Supernodal {
                symbolic,
                values,
                stack,
            } => {
                let mut stack = stack.lock().unwrap_or_else(|e| e.into_inner());
                LltRef::new(symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    b.as_mut(),
                    Par::Seq,
                    MemStack::new(&mut stack),
                );
            }
        }
        let x: Vec<Vector3<f64>> = (0..n)
            .map(|i| Vector3::new(b[(i, 0)], b[(i, 1)], b[(i, 2)]))
            .collect();
        if x.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(Error::invalid("poisson: solution is not finite"));
        }
        Ok(x)
    }
}

struct Parts {
    coupling: Vec<(usize, usize, f64)>,
    fixed_diag: Vec<f64>,
    jitter: f64,
}

/// Turns `a` (the Laplacian) into the Dirichlet-modified matrix in place and factorises it,
/// retrying with a growing diagonal jitter (logged on stderr) if it is not numerically
/// positive definite. `a` has `pattern`'s sparsity pattern.
fn factor(
    pattern: &Pattern,
    numeric: &mut Numeric,
    a: &mut SparseColMat<usize, f64>,
    fixed: &[usize],
) -> Result<Parts> {
    let component = &pattern.component;
    let n = a.nrows();
    let mut slot = vec![usize::MAX; n];
    for (k, &v) in fixed.iter().enumerate() {
        if v >= n {
            return Err(Error::invalid(format!(
                "poisson: fixed vertex {v} out of range ({n} vertices)"
            )));
        }
        if slot[v] != usize::MAX {
            return Err(Error::invalid(format!("poisson: vertex {v} fixed twice")));
        }
        slot[v] = k;
    }
    let (symbolic, vals) = a.parts_mut();
    let (cp, ri) = (symbolic.col_ptr(), symbolic.row_idx());
    let mut diag_pos = vec![usize::MAX; n];
    let mut coupling = Vec::new();
    let mut fixed_diag = vec![1.0; fixed.len()];
    let mut max_diag = 0.0f64;
    for j in 0..n {
        for p in cp[j]..cp[j + 1] {
            let i = ri[p];
            if i == j {
                diag_pos[j] = p;
                max_diag = max_diag.max(vals[p].abs());
            }
            if slot[i] == usize::MAX && slot[j] == usize::MAX {
                continue;
            }
            if i == j {
                let d = if vals[p] > 0.0 { vals[p] } else { 1.0 };
                fixed_diag[slot[j]] = d;
                vals[p] = d;
            } else {
                if slot[i] == usize::MAX {
                    coupling.push((i, slot[j], vals[p]));
                }
                vals[p] = 0.0;
            }
        }
    }
    check_anchored(component, &slot)?;
    if let Some(j) = diag_pos.iter().position(|&p| p == usize::MAX) {
        return Err(Error::invalid(format!(
            "poisson: diagonal entry {j} missing from the sparsity pattern"
        )));
    }
    let mut jitter = 0.0;
    for attempt in 0..6 {
        let done = match numeric {
            Numeric::Auto { symbolic, llt } => {
                match Llt::try_new_with_symbolic(symbolic.clone(), a.as_ref(), Side::Lower) {
                    Ok(new) => {
                        *llt = Some(new);
                        true
                    }
                    Err(_) => false,
                }
            }
            Numeric::Supernodal {
                symbolic,
                values,
                stack,
            } => {
                let stack = stack.get_mut().unwrap_or_else(|e| e.into_inner());
                symbolic
                    .factorize_numeric_llt(
                        values,
                        a.as_ref(),
                        Side::Lower,
                        Default::default(),
                        Par::Seq,
                        MemStack::new(stack),
                        Default::default(),
                    )
                    .is_ok()
            }
        };
        match done {
            true => {
                if attempt > 0 {
                    eprintln!(
                        "surface: poisson: system not positive definite, factorised with diagonal jitter {jitter:.3e}"
                    );
                }
                return Ok(Parts {
                    coupling,
                    fixed_diag,
                    jitter,
                });
            }
            false => {
                let add = max_diag.max(1.0) * 1e-12 * 100f64.powi(attempt);
                let vals = a.val_mut();
                for j in 0..n {
                    if slot[j] == usize::MAX {
                        vals[diag_pos[j]] += add - jitter;
                    }
                }
                jitter = add;
            }
        }
    }
    Err(Error::invalid(format!(
        "poisson: system is singular even with diagonal jitter {jitter:.1e} (a part without a fixed vertex?)"
    )))
}

/// The connected components of the matrix graph given by its pattern: a representative
/// vertex of every vertex's component.
fn components(n: usize, cp: &[usize], ri: &[usize]) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for j in 0..n {
        for &i in &ri[cp[j]..cp[j + 1]] {
            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
            if a != b {
                parent[a] = b;
            }
        }
    }
    (0..n).map(|v| find(&mut parent, v)).collect()
}

/// Every connected component of the matrix graph needs a fixed vertex: the Laplacian is
/// singular (constants) on a component without one.
fn check_anchored(component: &[usize], slot: &[usize]) -> Result<()> {
    let n = component.len();
    let mut anchored = vec![false; n];
    for v in 0..n {
        if slot[v] != usize::MAX {
            anchored[component[v]] = true;
        }
    }
    for v in 0..n {
        if !anchored[component[v]] {
            return Err(Error::invalid(format!(
                "poisson: no fixed vertex in the connected part containing vertex {v} (the system would be singular)"
            )));
        }
    }
    Ok(())
}

/// One-shot reconstruction: solves `Gᵀ A G x = Gᵀ A J` with `x[fixed[k]] = values[k]`.
pub fn reconstruct(
    op: &GradientOperator,
    field: &[Matrix3<f64>],
    fixed: &[usize],
    values: &[Vector3<f64>],
) -> Result<Vec<Vector3<f64>>> {
    let solver = PoissonSolver::new(&op.stiffness(), fixed)?;
    solver.solve(&op.divergence(field), values)
}

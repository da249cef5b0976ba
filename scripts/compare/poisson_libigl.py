#!/usr/bin/env python3
"""Compare the `surface` crate's Poisson solve with libigl (Python bindings) and scipy.

Usage: poisson_libigl.py DIR
  e.g.: OPENBLAS_NUM_THREADS=1 cargo build --release -p studies --bin poisson_export
        target/release/poisson_export /tmp/poisson13k
        python3 scripts/compare/poisson_libigl.py /tmp/poisson13k

DIR holds V.txt, F.txt (rest mesh), X.txt (deformed pose), fixed.txt (Dirichlet vertices),
solution.txt and timing.json written by crates/studies/src/bin/poisson_export.rs.
The problem: minimise sum_f A_f |grad x - grad X|^2 on the rest mesh with x = X on the fixed
vertices, i.e. L x = G^T A G X on the free vertices (L = G^T A G, cotangent Laplacian).
Here L = -igl.cotmatrix (libigl's is negative semi-definite), G = igl.grad, A from
igl.doublearea. Solved twice: igl.min_quad_with_fixed (min 1/2 x^T L x - x^T b, known = fixed)
and scipy.sparse.linalg.splu on the reduced system L_FF x_F = b_F - L_FC X_C.
Checks agreement with the Rust solution to 1e-8 relative (max-norm) and prints the time ratio
(Rust: faer sparse Cholesky, symbolic + numeric factorisation + 3-column solve).
Requires: pip install libigl scipy numpy   (tested: libigl 2.6.3, scipy 1.17.1, numpy 2.4.6)
"""
import json
import sys
import time

import numpy as np

try:
    import igl
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
except ImportError:
    sys.exit("poisson_libigl.py: needs libigl, scipy and numpy (pip install libigl scipy numpy)")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.splitlines()[2])
    d = sys.argv[1].rstrip("/")
    V = np.loadtxt(f"{d}/V.txt")
    F = np.loadtxt(f"{d}/F.txt", dtype=np.int64)
    X = np.loadtxt(f"{d}/X.txt")
    fixed = np.atleast_1d(np.loadtxt(f"{d}/fixed.txt", dtype=np.int64))
    rust = np.loadtxt(f"{d}/solution.txt")
    timing = json.load(open(f"{d}/timing.json"))

    L = (-igl.cotmatrix(V, F)).tocsc()
    G = igl.grad(V, F)
    area = np.tile(igl.doublearea(V, F) / 2.0, 3)
    b = G.T @ (area[:, None] * (G @ X))

    t0 = time.perf_counter()
    z_igl = np.asarray(igl.min_quad_with_fixed(A=L, B=-b, known=fixed, Y=X[fixed], pd=True))
    t_igl = time.perf_counter() - t0
    ok = z_igl.shape == X.shape and np.isfinite(z_igl).all()

    free = np.setdiff1d(np.arange(V.shape[0]), fixed)
    t0 = time.perf_counter()
    lu = spla.splu(L[free][:, free].tocsc())
    z_sp = X.copy()
    z_sp[free] = lu.solve(b[free] - L[free][:, fixed] @ X[fixed])
    t_sp = time.perf_counter() - t0

    scale = np.abs(z_sp).max()
    rel = lambda a, c: float(np.abs(a - c).max() / scale)
    t_rust = timing["factor_s"] + timing["solve_s"]
    report = {
        "n_vertices": int(V.shape[0]),
        "rel_err_rust_vs_scipy": rel(rust, z_sp),
        "rel_err_rust_vs_libigl": rel(rust, z_igl),
        "rel_err_libigl_vs_scipy": rel(z_igl, z_sp),
        "rel_err_solution_vs_pose": rel(rust, X),
        "time_rust_s": t_rust,
        "time_libigl_s": t_igl,
        "time_scipy_splu_s": t_sp,
        "libigl_over_rust": t_igl / t_rust,
        "scipy_over_rust": t_sp / t_rust,
    }
    print(json.dumps(report, indent=2))
    bad = [k for k in report if k.startswith("rel_err_r") and k != "rel_err_solution_vs_pose" and report[k] > 1e-8]
    if bad or not ok:
        sys.exit(f"poisson_libigl.py: disagreement above 1e-8 relative: {bad}")


if __name__ == "__main__":
    main()

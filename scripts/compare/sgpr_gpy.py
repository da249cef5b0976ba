#!/usr/bin/env python3
"""Compare the `gp` crate's sparse GP (Titsias' bound) with GPy's SparseGPRegression.

Usage: sgpr_gpy.py DIR [--models 0,1,...]
  e.g.: OPENBLAS_NUM_THREADS=1 cargo run --release -p gp --example sgpr_compare -- --pairs 1100 --inducing 256 --dump /tmp/sgpr1100
        OPENBLAS_NUM_THREADS=1 python3 scripts/compare/sgpr_gpy.py /tmp/sgpr1100

DIR holds problem_XX_{x,y,z}.csv and rust.json written by the `sgpr_compare` example (z: the
inducing inputs our greedy variance selection chose). For each problem GPy builds
SparseGPRegression with the MLP kernel, the same inducing inputs (fixed), the same fixed noise
variance and the same K_uu jitter (ours is 1e-6 * mean(diag K_uu), set as GPy's absolute
`const_jitter` at the starting point of each model: GPy keeps it fixed while optimising, ours
follows the hyperparameters, a difference of order 1e-6 in the objective), then:
  1. evaluates its bound at our optimum: must equal ours to 1e-6 relative (the known answer);
  2. optimises from our starting hyperparameters (the data-driven start, no warm start) with
     GPy's default (L-BFGS-B), timed, and prints its optimum beside ours from the same start
     and Z (`rust from l0`, single-threaded), and the time ratio.
Kernel mapping as in gpr_gpy.py: w = 1/(2 l^2), b = 0, var = sigma_f^2 * pi / 2.
Requires: pip install GPy==1.15.0 numpy scipy
"""
import json
import math
import sys
import time

import numpy as np

try:
    import GPy
except ImportError:
    sys.exit("sgpr_gpy.py: GPy not installed (pip install GPy==1.15.0 numpy scipy)")

from gpr_gpy import from_gpy, mlp_kernel  # the same kernel mapping (this script's folder)

KUU_JITTER = 1e-6  # crates/gp/src/sparse_gpr.rs, relative to mean(diag K_uu)


def model_for(x, y, z, noise, l, sf):
    k = mlp_kernel(x.shape[1], l, sf)
    m = GPy.models.SparseGPRegression(x, y, kernel=k, Z=z.copy())
    m.inducing_inputs.fix()
    m.Gaussian_noise.variance = noise
    m.Gaussian_noise.variance.fix()
    m.inference_method.const_jitter = KUU_JITTER * float(np.mean(np.diag(k.K(z))))
    m.parameters_changed()
    return m


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        sys.exit(__doc__)
    d = sys.argv[1]
    meta = json.load(open(f"{d}/rust.json"))
    sel = None
    if "--models" in sys.argv:
        sel = {int(v) for v in sys.argv[sys.argv.index("--models") + 1].split(",")}
    noise = meta["noise_var"]
    print(f"pairs {meta['pairs']}, inducing {meta['inducing']}, noise variance {noise}")
    print(f"{'model':>5} {'rust bound':>14} {'gpy@rust':>14} {'rel diff':>9} {'rust from l0':>14}"
          f" {'gpy from l0':>14} {'rust l':>9} {'gpy l':>9} {'rust s':>8} {'gpy s':>8} {'ratio':>6}")
    worst = 0.0
    rust_total = gpy_total = 0.0
    for rec in meta["models"]:
        i = rec["index"]
        if sel is not None and i not in sel:
            continue
        x = np.loadtxt(f"{d}/problem_{i:02d}_x.csv", delimiter=",", ndmin=2)
        y = np.loadtxt(f"{d}/problem_{i:02d}_y.csv", delimiter=",", ndmin=2)
        z = np.loadtxt(f"{d}/problem_{i:02d}_z.csv", delimiter=",", ndmin=2)
        at_rust = -float(model_for(x, y, z, noise, rec["l"], rec["sigma_f"]).objective_function())
        rel = abs(at_rust - rec["bound"]) / abs(rec["bound"])
        worst = max(worst, rel)
        m = model_for(x, y, z, noise, rec["l0"], rec["sigma_f0"])
        t = time.perf_counter()
        m.optimize()
        secs = time.perf_counter() - t
        gl, _ = from_gpy(float(m.mlp.weight_variance.values[0]), float(m.mlp.variance.values[0]))
        rust_total += rec["train_s"]
        gpy_total += secs
        print(f"{i:>5} {rec['bound']:>14.4f} {at_rust:>14.4f} {rel:>9.1e} {rec['train_bound']:>14.4f}"
              f" {-float(m.objective_function()):>14.4f} {rec['l']:>9.3f} {gl:>9.3f} {rec['train_s']:>8.3f} {secs:>8.3f}"
              f" {secs / rec['train_s']:>6.1f}")
    print(f"worst relative bound difference at our optimum: {worst:.2e}")
    print(f"total single-thread time: rust {rust_total:.3f} s, GPy {gpy_total:.3f} s, ratio {gpy_total / rust_total:.1f}x")
    if worst > 1e-6:
        sys.exit("sgpr_gpy.py: bounds differ by more than 1e-6 relative")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Compare the `gp` crate's GP regression with GPy's MLP-kernel GP regression.

Usage: gpr_gpy.py DIR [--models 0,1,...]
  e.g.: OPENBLAS_NUM_THREADS=1 cargo run --release -p studies --bin gpr_compare -- --pairs 1100 --dump /tmp/gpr1100
        python3 scripts/compare/gpr_gpy.py /tmp/gpr1100

DIR holds problem_XX_{x,y}.csv and rust.json written by the `gpr_compare` binary (crates/studies). For each
problem GPy fits GPRegression with the MLP kernel and the same fixed noise variance
(sigma_n^2 = 0.1), starting from the same hyperparameters as the Rust run, optimised with
GPy's default (L-BFGS-B). Prints both log marginal likelihoods, GPy's optimum converted to
eq. 10's parametrisation, GPy's likelihood evaluated at the Rust optimum (a check that both
compute the same objective), and the time ratio.

Kernel mapping (eq. 10 <-> GPy MLP, see crates/gp/src/kernel.rs):
  GPy: var * (2/pi) * asin((w x.x' + b) / sqrt((w x.x + b + 1)(w x'.x' + b + 1)))
  eq. 10 with a = 1/(2 l^2):  w = a, b = 0, var = sigma_f^2 * pi / 2.
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
    sys.exit("gpr_gpy.py: GPy not installed (pip install GPy==1.15.0 numpy scipy)")


def to_gpy(l, sf):
    return 1.0 / (2.0 * l * l), sf * sf * math.pi / 2.0


def from_gpy(w, var):
    return math.sqrt(1.0 / (2.0 * w)), math.sqrt(2.0 * var / math.pi)


def mlp_kernel(dim, l, sf):
    """GPy's MLP kernel equal to eq. 10 with length scale l and signal sigma_f = sf."""
    w, var = to_gpy(l, sf)
    k = GPy.kern.MLP(input_dim=dim, variance=var, weight_variance=w, bias_variance=1e-300)
    with np.errstate(divide="ignore"):
        k.bias_variance.fix(0.0)  # CVPR eq. 10 has no bias
    return k


def model_for(x, y, noise, l, sf):
    k = mlp_kernel(x.shape[1], l, sf)
    m = GPy.models.GPRegression(x, y, kernel=k, noise_var=noise)
    m.Gaussian_noise.variance.fix(noise)
    return m


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        sys.exit(__doc__)
    d = sys.argv[1]
    meta = json.load(open(f"{d}/rust.json"))
    if meta["kernel"] != "nn":
        sys.exit("gpr_gpy.py: only the neural-network (MLP) kernel is compared")
    sel = None
    if "--models" in sys.argv:
        sel = {int(v) for v in sys.argv[sys.argv.index("--models") + 1].split(",")}
    noise = meta["noise_var"]
    gpy_total = rust_total = 0.0
    print(f"pairs {meta['pairs']}, noise variance {noise}")
    print(f"{'model':>5} {'rust lml':>14} {'gpy lml':>14} {'gpy@rust':>14} {'rust l':>10} {'gpy l':>10}"
          f" {'rust sf':>10} {'gpy sf':>10} {'rust s':>8} {'gpy s':>8}")
    worse = 0
    for rec in meta["models"]:
        i = rec["index"]
        if sel is not None and i not in sel:
            continue
        x = np.loadtxt(f"{d}/problem_{i:02d}_x.csv", delimiter=",", ndmin=2)
        y = np.loadtxt(f"{d}/problem_{i:02d}_y.csv", delimiter=",", ndmin=2)
        m = model_for(x, y, noise, rec["l0"], rec["sigma_f0"])
        t = time.perf_counter()
        m.optimize()
        secs = time.perf_counter() - t
        gl, gsf = from_gpy(float(m.mlp.weight_variance.values[0]), float(m.mlp.variance.values[0]))
        at_rust = model_for(x, y, noise, rec["l"], rec["sigma_f"]).log_likelihood()
        gpy_total += secs
        rust_total += rec["train_s"]
        if rec["lml"] < m.log_likelihood() - 1e-3 * max(1.0, abs(m.log_likelihood())) * 1e-3:
            worse += 1
        print(f"{i:5d} {rec['lml']:14.4f} {m.log_likelihood():14.4f} {at_rust:14.4f} {rec['l']:10.4g} {gl:10.4g}"
              f" {rec['sigma_f']:10.4g} {gsf:10.4g} {rec['train_s']:8.3f} {secs:8.3f}")
    print(f"total training time: rust {rust_total:.3f} s (one thread, sequential), GPy {gpy_total:.3f} s;"
          f" ratio GPy/rust = {gpy_total / max(rust_total, 1e-9):.1f}")
    print(f"rust with rayon over models ({meta['models'].__len__()} models): {meta['parallel_train_s']:.3f} s")
    print(f"models where rust's optimum is below GPy's by more than 1e-6 relative: {worse}")


if __name__ == "__main__":
    main()

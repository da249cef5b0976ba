#!/usr/bin/env python3
"""Compare gpdm-train's optimiser (Rust, crates/gpdm) with numpy/scipy L-BFGS-B on the same
GPDM objective (paper eqs. 3-7, same log/noise-floor parametrisation) from the same start.

Usage: gpdm_scipy.py [--dim D] [--maxiter K] [--workdir DIR] [--bin PATH] [--raw]
e.g.:  OPENBLAS_NUM_THREADS=1 python3 scripts/compare/gpdm_scipy.py --dim 15000

Runs `fit_compare D DIR` (built by `cargo test --release -p gpdm`), which exports Y, theta0
and meta.json and writes the Rust traces; then minimises with scipy and reports both optima
and the time each needs to reach the scipy optimum. Needs numpy and scipy.
--raw: scipy optimises the raw hyperparameters (α, β > 0 and 1/α3 >= floor as L-BFGS-B
bounds), as a plain numpy GPDM would, instead of the Rust log/floor coordinates.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.optimize import minimize


def load(workdir):
    meta = json.load(open(os.path.join(workdir, "meta.json")))
    n, dobs = meta["n"], meta["d_obs"]
    y = np.fromfile(os.path.join(workdir, "y.f64"), dtype="<f8").reshape(n, dobs)
    theta0 = np.fromfile(os.path.join(workdir, "theta0.f64"), dtype="<f8")
    return meta, y, theta0


def make_objective(meta, y):
    n, dobs, d = meta["n"], meta["d_obs"], meta["latent_dim"]
    floor, s0 = meta["pose_noise_floor"], meta["first_point_var"]
    lens = meta["seq_lens"]
    starts = np.cumsum([0] + lens[:-1])
    xin = np.concatenate([np.arange(s, s + l - 1) for s, l in zip(starts, lens)])
    xout = xin + 1
    firsts = starts
    S = y @ y.T  # N x N, formed once
    eye_n, eye_m = np.eye(n), np.eye(len(xin))

    def sqdist(a):
        q = (a * a).sum(1)
        return np.maximum(q[:, None] + q[None, :] - 2 * a @ a.T, 0.0)

    def f(theta):
        X = theta[: n * d].reshape(d, n).T  # column-major in theta
        ta, tb = theta[n * d : n * d + 3], theta[n * d + 3 :]
        a1, a2, a3 = np.exp(ta[0]), np.exp(ta[1]), 1.0 / (floor + np.exp(ta[2]))
        b1, b2, b3, b4 = np.exp(tb[0]), np.exp(tb[1]), np.exp(tb[2]), 1.0 / np.exp(tb[3])
        # pose term
        D2 = sqdist(X)
        R = a1 * np.exp(-0.5 * a2 * D2)
        K = R + eye_n / a3
        c = cho_factor(K, lower=True)
        Kinv = cho_solve(c, eye_n)
        KiS = Kinv @ S
        logdet = 2 * np.log(np.diag(c[0])).sum()
        val = 0.5 * dobs * logdet + 0.5 * np.trace(KiS)
        G = 0.5 * (dobs * Kinv - KiS @ Kinv)
        P = G * R
        gX = -2 * a2 * (P.sum(1)[:, None] * X - P @ X)
        ga = np.array([(G * R).sum(), (G * R * -0.5 * D2).sum() * a2, 0.0])
        ga[2] = (-np.trace(G) / a3**2 + 1 / a3) * (-(a3**2) * np.exp(ta[2]))
        ga[:2] += 1.0
        # dynamics term
        Xi, Xo = X[xin], X[xout]
        D2x = sqdist(Xi)
        Rx = b1 * np.exp(-0.5 * b2 * D2x)
        Lin = Xi @ Xi.T
        Kx = Rx + b3 * Lin + eye_m / b4
        cx = cho_factor(Kx, lower=True)
        Kxinv = cho_solve(cx, eye_m)
        Z = Kxinv @ Xo
        val += 0.5 * d * 2 * np.log(np.diag(cx[0])).sum() + 0.5 * (Xo * Z).sum()
        val += 0.5 * (X[firsts] ** 2).sum() / s0
        Gx = 0.5 * (d * Kxinv - Z @ Z.T)
        Px = Gx * Rx
        gXi = -2 * b2 * (Px.sum(1)[:, None] * Xi - Px @ Xi) + 2 * b3 * Gx @ Xi
        np.add.at(gX, xin, gXi)
        np.add.at(gX, xout, Z)
        gX[firsts] += X[firsts] / s0
        gb = np.array([(Gx * Rx).sum() + 1, (Gx * Rx * -0.5 * D2x).sum() * b2 + 1,
                       (Gx * Lin).sum() * b3 + 1,
                       (-np.trace(Gx) / b4**2 + 1 / b4) * (-(b4**2) * np.exp(tb[3]))])
        # priors: sum ln alpha + sum ln beta
        val += np.log([a1, a2, a3, b1, b2, b3, b4]).sum()
        return val, np.concatenate([gX.T.ravel(), ga, gb])

    def to_raw(theta):
        ta, tb = theta[n * d : n * d + 3], theta[n * d + 3 :]
        a = [np.exp(ta[0]), np.exp(ta[1]), 1.0 / (floor + np.exp(ta[2]))]
        b = [np.exp(tb[0]), np.exp(tb[1]), np.exp(tb[2]), 1.0 / np.exp(tb[3])]
        return np.concatenate([theta[: n * d], a, b])

    def from_raw(r):
        a, b = r[n * d : n * d + 3], r[n * d + 3 :]
        ta = [np.log(a[0]), np.log(a[1]), np.log(max(1.0 / a[2] - floor, 1e-300))]
        tb = [np.log(b[0]), np.log(b[1]), np.log(b[2]), np.log(1.0 / b[3])]
        return np.concatenate([r[: n * d], ta, tb])

    def f_raw(r):
        # Chain rule from the theta gradient: d theta / d raw, per hyperparameter.
        th = from_raw(r)
        v, g = f(th)
        a, b = r[n * d : n * d + 3], r[n * d + 3 :]
        gr = g.copy()
        k = n * d
        gr[k] = g[k] / a[0]
        gr[k + 1] = g[k + 1] / a[1]
        gr[k + 2] = g[k + 2] * (-1.0 / a[2] ** 2) / (1.0 / a[2] - floor)
        gr[k + 3] = g[k + 3] / b[0]
        gr[k + 4] = g[k + 4] / b[1]
        gr[k + 5] = g[k + 5] / b[2]
        gr[k + 6] = g[k + 6] * (-1.0 / b[3])
        return v, gr

    bounds = [(None, None)] * (n * d) + [(1e-12, None), (1e-12, None), (1e-12, 1.0 / floor if floor > 0 else None)] \
        + [(1e-12, None)] * 4
    return f, f_raw, to_raw, bounds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dim", type=int, default=15000)
    ap.add_argument("--maxiter", type=int, default=1000)
    ap.add_argument("--workdir", default="/tmp/gpdm_compare")
    ap.add_argument("--raw", action="store_true")
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "../../target/release/examples/fit_compare"))
    a = ap.parse_args()
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([a.bin, str(a.dim), a.workdir], env=env, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"gpdm_scipy: {a.bin}: {out.stderr.strip()}")
    print(out.stdout, end="")
    meta, y, theta0 = load(a.workdir)
    f, f_raw, to_raw, bounds = make_objective(meta, y)
    # Same objective at the start (independent implementation check).
    f0, g0 = f(theta0)
    reps = 5
    t = time.perf_counter()
    for _ in range(reps):
        f(theta0)
    per_eval = (time.perf_counter() - t) / reps
    trace = []
    t0 = time.perf_counter()

    obj, start, bnds = (f_raw, to_raw(theta0), bounds) if a.raw else (f, theta0, None)

    def wrapped(th):
        v, g = obj(th)
        trace.append((time.perf_counter() - t0, v))
        return v, g

    res = minimize(wrapped, start, jac=True, method="L-BFGS-B", bounds=bnds,
                   options={"maxiter": a.maxiter, "maxfun": 3 * a.maxiter, "gtol": 1e-6, "ftol": 1e-12})
    t_scipy = trace[-1][0]
    f_scipy = min(v for _, v in trace)
    print(f"scipy ({'raw' if a.raw else 'log'} hyperparameters): f0 = {f0:.6f}, {per_eval*1e3:.1f} ms per objective+gradient, "
          f"{res.nfev} evals, {t_scipy:.2f} s, optimum {f_scipy:.6f} ({res.message})")
    target = f_scipy + 1e-6 * abs(f_scipy)
    t_scipy_hit = next(t for t, v in trace if v <= target)
    for name in ("joint", "alternate"):
        p = os.path.join(a.workdir, f"rust_trace_{name}.json")
        if not os.path.exists(p):
            continue
        rt = json.load(open(p))
        best = min(v for _, v in rt)
        hit = next((t for t, v in rt if v <= target), None)
        if hit is None:
            print(f"rust {name}: optimum {best:.6f}, never reached the scipy optimum")
        else:
            print(f"rust {name}: optimum {best:.6f}; reached scipy optimum in {hit:.2f} s "
                  f"vs scipy {t_scipy_hit:.2f} s: {t_scipy_hit / max(hit, 1e-9):.1f}x sooner")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Compare gpdm-train's optimiser (Rust, crates/gpdm) with numpy/scipy L-BFGS-B on the same
GPDM objective (paper eqs. 3-7 with gpdm-train's noise floors and weak log-normal factor on
beta1..beta3, same log/noise-floor parametrisation) from the same start, both stopping by
convergence (the value/gradient tolerances in meta.json).

Usage: gpdm_scipy.py [--dim D | --problem DIR] [--maxiter K] [--workdir DIR] [--bin PATH]
                     [--skip-rust] [--raw]
e.g.:  OPENBLAS_NUM_THREADS=1 python3 scripts/compare/gpdm_scipy.py --dim 15000

Runs `fit_compare D DIR` (built by `cargo build --release -p studies --bin fit_compare`), which exports Y, theta0
and meta.json and writes the Rust traces; then minimises with scipy and reports both optima,
iterations, evaluations and the time each needs to reach the scipy optimum. Needs numpy and
scipy. --problem DIR: fit a problem exported as y.f64 + meta.json (a real body part, see
fit_compare) instead of the synthetic one. --skip-rust: reuse the workdir's export and traces.
--raw: scipy optimises the raw hyperparameters (α, β > 0 and 1/α3 >= floor as L-BFGS-B
bounds), as a plain numpy GPDM would, instead of the Rust log/floor coordinates.
"""
import argparse
import glob
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
    dfloor = meta.get("dyn_noise_floor", 0.0)
    sd = meta.get("beta_log_sd", 0.0)
    inv_s2 = 1.0 / sd**2 if sd > 0 else 0.0
    fixed_scale = meta.get("fixed_latent_scale", False)
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
        Xt = theta[: n * d].reshape(d, n).T  # column-major in theta
        norm = np.sqrt((Xt * Xt).sum())
        sc = np.sqrt(n * d) / norm if fixed_scale else 1.0
        X = sc * Xt  # unit mean square when the latent scale is fixed
        ta, tb = theta[n * d : n * d + 3], theta[n * d + 3 :]
        a1, a2, a3 = np.exp(ta[0]), np.exp(ta[1]), 1.0 / (floor + np.exp(ta[2]))
        b1, b2, b3, b4 = np.exp(tb[0]), np.exp(tb[1]), np.exp(tb[2]), 1.0 / (dfloor + np.exp(tb[3]))
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
        if fixed_scale:  # chain rule through X = sqrt(N d) Xt / |Xt|
            gX = sc * (gX - Xt * (gX * Xt).sum() / norm**2)
        gb = np.array([(Gx * Rx).sum() + 1, (Gx * Rx * -0.5 * D2x).sum() * b2 + 1,
                       (Gx * Lin).sum() * b3 + 1,
                       (-np.trace(Gx) / b4**2 + 1 / b4) * (-(b4**2) * np.exp(tb[3]))])
        gb[:3] += inv_s2 * tb[:3]
        # priors: sum ln alpha + sum ln beta, log-normal factor on beta1..beta3
        val += np.log([a1, a2, a3, b1, b2, b3, b4]).sum() + 0.5 * inv_s2 * (tb[:3] ** 2).sum()
        return val, np.concatenate([gX.T.ravel(), ga, gb])

    def to_raw(theta):
        ta, tb = theta[n * d : n * d + 3], theta[n * d + 3 :]
        a = [np.exp(ta[0]), np.exp(ta[1]), 1.0 / (floor + np.exp(ta[2]))]
        b = [np.exp(tb[0]), np.exp(tb[1]), np.exp(tb[2]), 1.0 / (dfloor + np.exp(tb[3]))]
        return np.concatenate([theta[: n * d], a, b])

    def from_raw(r):
        a, b = r[n * d : n * d + 3], r[n * d + 3 :]
        ta = [np.log(a[0]), np.log(a[1]), np.log(max(1.0 / a[2] - floor, 1e-300))]
        tb = [np.log(b[0]), np.log(b[1]), np.log(b[2]), np.log(max(1.0 / b[3] - dfloor, 1e-300))]
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
        gr[k + 6] = g[k + 6] * (-1.0 / b[3] ** 2) / (1.0 / b[3] - dfloor)
        return v, gr

    bounds = [(None, None)] * (n * d) + [(1e-12, None), (1e-12, None), (1e-12, 1.0 / floor if floor > 0 else None)] \
        + [(1e-12, None)] * 3 + [(1e-12, 1.0 / dfloor if dfloor > 0 else None)]
    return f, f_raw, to_raw, bounds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dim", type=int, default=15000)
    ap.add_argument("--problem", help="exported problem directory (y.f64 + meta.json)")
    ap.add_argument("--maxiter", type=int, default=20000)
    ap.add_argument("--workdir", default="/tmp/gpdm_compare")
    ap.add_argument("--skip-rust", action="store_true")
    ap.add_argument("--raw", action="store_true")
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "../../target/release/fit_compare"))
    a = ap.parse_args()
    if not a.skip_rust:
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
        src = a.problem if a.problem else str(a.dim)
        out = subprocess.run([a.bin, src, a.workdir], env=env, capture_output=True, text=True)
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
    print(f"numpy objective+gradient: {per_eval*1e3:.1f} ms "
          f"(OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}), f0 = {f0:.6f}")
    trace = []
    t0 = time.perf_counter()

    obj, start, bnds = (f_raw, to_raw(theta0), bounds) if a.raw else (f, theta0, None)

    def wrapped(th):
        v, g = obj(th)
        trace.append((time.perf_counter() - t0, v))
        return v, g

    res = minimize(wrapped, start, jac=True, method="L-BFGS-B", bounds=bnds,
                   options={"maxiter": a.maxiter, "maxfun": 3 * a.maxiter,
                            "gtol": meta["grad_tol"], "ftol": meta["value_tol"]})
    t_scipy = trace[-1][0]
    f_scipy = min(v for _, v in trace)
    print(f"scipy ({'raw' if a.raw else 'log'} hyperparameters): {res.nit} iterations, "
          f"{res.nfev} evals, {t_scipy:.2f} s, optimum {f_scipy:.6f} ({res.message})")
    if not a.raw:
        th = res.x
        k = meta["n"] * meta["latent_dim"]
        print(f"  scipy ln alpha, ln beta coordinates: {np.round(th[k:], 4).tolist()}")
    for rel in (1e-5, 1e-6, 0.0):
        target = f_scipy + rel * abs(f_scipy)
        t_scipy_hit = next(t for t, v in trace if v <= target)
        n_scipy_hit = next(i for i, (t, v) in enumerate(trace) if v <= target) + 1
        for p in sorted(glob.glob(os.path.join(a.workdir, "rust_trace_*.json"))):
            name = os.path.basename(p)[len("rust_trace_"):-len(".json")]
            rt = json.load(open(p))
            best = min(v for _, v in rt)
            hit = next((i for i, (t, v) in enumerate(rt) if v <= target), None)
            if hit is None:
                print(f"target f_scipy + {rel:g}|f|: rust {name}: optimum {best:.6f}, never reached it")
            else:
                print(f"target f_scipy + {rel:g}|f|: rust {name}: optimum {best:.6f}; reached in "
                      f"{rt[hit][0]:.2f} s ({hit + 1} evals) vs scipy {t_scipy_hit:.2f} s ({n_scipy_hit} evals): "
                      f"{t_scipy_hit / max(rt[hit][0], 1e-9):.1f}x sooner")


if __name__ == "__main__":
    main()

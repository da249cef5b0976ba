#!/usr/bin/env python3
"""Compare the `gp` crate's sparse GP (Titsias' bound) with GPy's SparseGPRegression.

Usage: sgpr_gpy.py DIR [--models 0,1,...] [--tol REL] [--out FILE]
  Run through scripts/compare/sgpr-vs-gpy, which installs GPy in a venv, builds the binary,
  dumps the problems and runs this script with the thread settings stated; by hand:
        OPENBLAS_NUM_THREADS=1 RAYON_NUM_THREADS=1 target/release/sgpr_compare --pairs 1100 --inducing 256 --dump /tmp/sgpr1100
        OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 python3 scripts/compare/sgpr_gpy.py /tmp/sgpr1100

DIR holds problem_XX_{x,y,z}.csv and rust.json written by the `sgpr_compare` binary (crates/studies) (z: the
inducing inputs our greedy variance selection chose). For each problem GPy builds
SparseGPRegression with the MLP kernel, the same inducing inputs (fixed), the same fixed noise
variance and the same K_uu jitter (ours is 1e-6 * mean(diag K_uu), set as GPy's absolute
`const_jitter` at the starting point of each model: GPy keeps it fixed while optimising, ours
follows the hyperparameters, a difference of order 1e-6 in the objective), then:
  1. evaluates its bound at our optimum: must equal ours to 1e-6 relative (the known answer;
     exit 1 otherwise);
  2. optimises from our starting hyperparameters (the data-driven start, no warm start) with
     GPy's default (L-BFGS-B), recording the bound, wall and CPU time of every evaluation.
Equal bound: per model the target is the lower of the two optima (ours from the same start and
Z, GPy's) minus `--tol` (default 1e-6) relative; each side's time is the CPU time at which its
first evaluation at or above the target was known (GPy: that value-and-gradient call returned;
ours: the *next* evaluation's value was known, or the run ended -- conservative for us by one
evaluation). The ratio is GPy's CPU time to the target over ours, one thread each (our
thread-CPU time, fastest of the binary's --repeat runs; GPy's process CPU time); the ratio of
the whole optimisations (each to its own stop) is printed too. The whole record is written
to DIR/gpy.json (or --out).
Kernel mapping as in gpr_gpy.py: w = 1/(2 l^2), b = 0, var = sigma_f^2 * pi / 2.
Requires: scripts/compare/requirements-gpy.txt (GPy 1.15.0, numpy, scipy).
"""
import json
import os
import sys
import time

import numpy as np

try:
    import GPy
except ImportError:
    sys.exit("sgpr_gpy.py: GPy not installed (pip install -r scripts/compare/requirements-gpy.txt)")

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


def optimise_traced(m):
    """GPy's default optimiser (L-BFGS-B); returns wall, CPU and the per-evaluation trace
    [(wall, cpu, bound)] (bound = -objective; failed evaluations give a huge objective)."""
    trace = []
    inner = m._objective_grads
    t0, c0 = time.perf_counter(), time.process_time()

    def traced(x):
        o, g = inner(x)
        trace.append((time.perf_counter() - t0, time.process_time() - c0, -float(o)))
        return o, g

    m._objective_grads = traced
    m.optimize()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    del m._objective_grads
    return wall, cpu, trace


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        sys.exit(__doc__)
    d = sys.argv[1]
    arg = lambda flag, default: sys.argv[sys.argv.index(flag) + 1] if flag in sys.argv else default
    meta = json.load(open(f"{d}/rust.json"))
    sel = arg("--models", None)
    sel = None if sel is None else {int(v) for v in sel.split(",")}
    tol = float(arg("--tol", "1e-6"))
    out = arg("--out", f"{d}/gpy.json")
    noise = meta["noise_var"]
    threads = {k: os.environ.get(k, "unset") for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    print(f"pairs {meta['pairs']}, inducing {meta['inducing']}, noise variance {noise}; GPy {GPy.__version__},"
          f" numpy {np.__version__}; {threads}; load average {os.getloadavg()[0]:.2f}")
    print(f"{'model':>5} {'ours@opt':>12} {'gpy@ours':>12} {'rel diff':>8} {'ours':>12} {'gpy':>12} {'target':>12}"
          f" {'our ev/gr':>9} {'our wall':>8} {'our cpu':>8} {'gpy ev':>6} {'to tgt':>6} {'gpy cpu':>8}"
          f" {'cpu@tgt':>8} {'ours@tgt':>8} {'ratio':>6}")
    worst = 0.0
    rows = []
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
        wall, cpu, trace = optimise_traced(m)
        gpy_bound = -float(m.objective_function())
        ours = rec["train_bound"]
        target = min(ours, gpy_bound) - tol * abs(min(ours, gpy_bound))
        k = next(j for j, t in enumerate(trace) if t[2] >= target)
        ours_to_target = next(t for t, v in rec["trace"] if v >= target)
        gl, _ = from_gpy(float(m.mlp.weight_variance.values[0]), float(m.mlp.variance.values[0]))
        row = {
            "index": i, "ours_at_optimum": rec["bound"], "gpy_at_ours": at_rust, "rel_diff": rel,
            "ours_bound": ours, "gpy_bound": gpy_bound, "target": target,
            "ours_evaluations": rec["evaluations"], "ours_gradients": rec["gradients"],
            "ours_wall_s": rec["train_s"], "ours_cpu_s": rec["train_cpu_s"], "ours_l": rec["l"],
            "gpy_evaluations": len(trace), "gpy_evaluations_to_target": k + 1,
            "gpy_wall_s": wall, "gpy_cpu_s": cpu, "gpy_wall_to_target_s": trace[k][0],
            "gpy_cpu_to_target_s": trace[k][1], "gpy_l": gl, "ours_cpu_to_target_s": ours_to_target,
        }
        rows.append(row)
        print(f"{i:>5} {rec['bound']:>12.4f} {at_rust:>12.4f} {rel:>8.1e} {ours:>12.4f} {gpy_bound:>12.4f}"
              f" {target:>12.4f} {rec['evaluations']:>4}/{rec['gradients']:<4} {rec['train_s']:>8.3f}"
              f" {rec['train_cpu_s']:>8.3f} {len(trace):>6} {k + 1:>6} {cpu:>8.3f} {trace[k][1]:>8.3f}"
              f" {ours_to_target:>8.3f} {trace[k][1] / ours_to_target:>6.1f}")
    tot = lambda key: sum(r[key] for r in rows)
    summary = {
        "pairs": meta["pairs"], "inducing": meta["inducing"], "tol": tol, "threads": threads,
        "gpy": GPy.__version__, "numpy": np.__version__, "load_average_end": os.getloadavg()[0],
        "worst_rel_diff_at_our_optimum": worst,
        "ours_wall_s": tot("ours_wall_s"), "ours_cpu_s": tot("ours_cpu_s"),
        "gpy_wall_s": tot("gpy_wall_s"), "gpy_cpu_s": tot("gpy_cpu_s"),
        "gpy_wall_to_target_s": tot("gpy_wall_to_target_s"), "gpy_cpu_to_target_s": tot("gpy_cpu_to_target_s"),
        "ours_cpu_to_target_s": tot("ours_cpu_to_target_s"),
    }
    summary["cpu_ratio_to_target"] = summary["gpy_cpu_to_target_s"] / summary["ours_cpu_to_target_s"]
    summary["cpu_ratio_full"] = summary["gpy_cpu_s"] / summary["ours_cpu_s"]
    print(f"worst relative bound difference at our optimum: {worst:.2e}")
    print(f"ours on one thread, GPy on OPENBLAS_NUM_THREADS={threads['OPENBLAS_NUM_THREADS']}, {len(rows)} models: ours to the equal bound {summary['ours_cpu_to_target_s']:.3f} s CPU,"
          f" to its stop {summary['ours_cpu_s']:.3f} s CPU ({summary['ours_wall_s']:.3f} s wall); GPy to the equal bound {summary['gpy_cpu_to_target_s']:.3f} s CPU ({summary['gpy_wall_to_target_s']:.3f} s wall),"
          f" to its own stop {summary['gpy_cpu_s']:.3f} s CPU ({summary['gpy_wall_s']:.3f} s wall)")
    print(f"CPU ratio GPy / ours, to the equal bound: {summary['cpu_ratio_to_target']:.1f}x;"
          f" each to its own stop: {summary['cpu_ratio_full']:.1f}x")
    json.dump({"summary": summary, "models": rows}, open(out, "w"), indent=1)
    if worst > 1e-6:
        sys.exit("sgpr_gpy.py: bounds differ by more than 1e-6 relative")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Recompute `transfer-eval`'s errors of one transferred sequence with pymeshlab.

    python3 scripts/compare/evaluate_pymeshlab.py PRED_DIR TRUTH_DIR [--record EVAL.json]

Frames (000000.ply, ...) are loaded with pymeshlab (the user's comparison tool), then
  rms_placed_m: RMS per-vertex distance, no alignment;
  rms_pose_m:   each predicted frame rigidly aligned to its truth frame first (Kabsch /
                Procrustes, rotation + translation, no scale, reflection guarded; numpy SVD);
  hausdorff:    pymeshlab's `get_hausdorff_distance` (predicted vertices to the closest point of the
                truth surface, as placed): RMS and max, a correspondence-free lower bound.
With --record, compares with the `transfer-eval` record (rms_pose_m, rms_placed_m) and exits 1 when
they differ by more than 1e-6 relative. Needs `pip install pymeshlab numpy`.
"""
import argparse, json, os, sys

import numpy as np
import pymeshlab


def frames(d):
    return sorted(f for f in os.listdir(d) if f.endswith(".ply") and f.split(".")[0].isdigit())


def load(ms, path):
    ms.load_new_mesh(path)
    m = ms.current_mesh()
    return m.vertex_matrix().astype(np.float64), m.face_matrix()


def kabsch(p, t):
    cp, ct = p.mean(0), t.mean(0)
    u, _, vt = np.linalg.svd((p - cp).T @ (t - ct))
    d = np.sign(np.linalg.det(u @ vt))
    r = u @ np.diag([1.0, 1.0, d]) @ vt
    return (p - cp) @ r + ct


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pred")
    ap.add_argument("truth")
    ap.add_argument("--record", help="evaluate's JSON record to compare with")
    a = ap.parse_args()
    fp, ft = frames(a.pred), frames(a.truth)
    if len(fp) != len(ft) or not fp:
        sys.exit(f"evaluate_pymeshlab: {a.pred}: {len(fp)} frames, truth {len(ft)}")
    ms = pymeshlab.MeshSet()
    pose = placed = 0.0
    n = 0
    h_sq, h_n, h_max = 0.0, 0, 0.0
    for i, (p, t) in enumerate(zip(fp, ft)):
        vp, _ = load(ms, os.path.join(a.pred, p))
        vt, _ = load(ms, os.path.join(a.truth, t))
        if vp.shape != vt.shape:
            sys.exit(f"evaluate_pymeshlab: {p}: {vp.shape[0]} vertices, truth {vt.shape[0]}")
        placed += ((vp - vt) ** 2).sum()
        pose += ((kabsch(vp, vt) - vt) ** 2).sum()
        n += vp.shape[0]
        # Mesh 2*i is the prediction, 2*i+1 the truth.
        h = ms.get_hausdorff_distance(sampledmesh=2 * i, targetmesh=2 * i + 1, samplevert=True,
                                      sampleface=False, sampleedge=False, samplenum=vp.shape[0])
        h_sq += h["RMS"] ** 2 * h["n_samples"]
        h_n += h["n_samples"]
        h_max = max(h_max, h["max"])
    out = {"frames": len(fp), "rms_pose_m": (pose / n) ** 0.5, "rms_placed_m": (placed / n) ** 0.5,
           "hausdorff_rms_m": (h_sq / max(h_n, 1)) ** 0.5, "hausdorff_max_m": h_max,
           "pymeshlab": pymeshlab.__version__ if hasattr(pymeshlab, "__version__") else "?"}
    ok = True
    if a.record:
        rec = json.load(open(a.record))
        for k in ("rms_pose_m", "rms_placed_m"):
            rel = abs(out[k] - rec[k]) / max(abs(rec[k]), 1e-300)
            out["evaluate_" + k] = rec[k]
            out["rel_diff_" + k] = rel
            ok &= rel <= 1e-6
    print(json.dumps(out, indent=1))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()

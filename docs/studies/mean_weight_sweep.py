#!/usr/bin/env python3
"""Pose error of the weighted average of two transfer runs' raw gpr-nn frames, per weight.

Study: 47-mean-ensemble.md. The runs are `make transfer-results` of one set with two
configurations (e.g. CONFIG=affine-mean and CONFIG=zero-mean, TRANSFER_METHODS=gpr-nn). Each
frame's vertices are averaged, `w * first + (1 - w) * second`, and scored with `transfer-eval`
against the set's truth; the pooled pose RMS (cm) per direction is printed per weight.

    docs/studies/mean_weight_sweep.py SET FIRST_RUN SECOND_RUN
    e.g. docs/studies/mean_weight_sweep.py out/holdout/set /tmp/me/h-affine-mean /tmp/me/h-zero-mean
"""
import json
import math
import os
import subprocess
import sys
import tempfile

WEIGHTS = [1.0, 0.75, 0.5, 0.25, 0.0]


def vertices_block(data):
    """(header length, vertex count) of a binary little-endian PLY with double x, y, z first."""
    end = data.index(b"end_header\n") + len(b"end_header\n")
    line = next(l for l in data[:end].split(b"\n") if l.startswith(b"element vertex"))
    return end, int(line.split()[2])


def average(first, second, w, out):
    import struct
    for name in sorted(os.listdir(first)):
        if not name.endswith(".ply"):
            continue
        a = open(os.path.join(first, name), "rb").read()
        b = open(os.path.join(second, name), "rb").read()
        h, n = vertices_block(a)
        va = struct.unpack_from(f"<{3 * n}d", a, h)
        vb = struct.unpack_from(f"<{3 * n}d", b, h)
        mixed = struct.pack(f"<{3 * n}d", *(w * x + (1 - w) * y for x, y in zip(va, vb)))
        open(os.path.join(out, name), "wb").write(a[:h] + mixed + a[h + 24 * n:])


def main():
    set_dir, first, second = sys.argv[1:4]
    for direction in sorted(os.listdir(os.path.join(first, "transfer"))):
        src, tgt = direction.split("-to-")
        for w in WEIGHTS:
            sq, frames = 0.0, 0
            for motion in sorted(os.listdir(os.path.join(first, "transfer", direction))):
                with tempfile.TemporaryDirectory() as tmp:
                    frames_dir = os.path.join(tmp, "frames")
                    os.mkdir(frames_dir)
                    average(*(os.path.join(r, "transfer", direction, motion, "gpr-nn") for r in (first, second)), w, frames_dir)
                    report = os.path.join(tmp, "eval.json")
                    subprocess.run(
                        ["target/release/transfer-eval", "-q", frames_dir, os.path.join(set_dir, "truth", tgt, motion),
                         "--source-motion", os.path.join(first, "work", src, f"{motion}.aligned"),
                         "--source-pca", os.path.join(first, "work", src, "pca.model"),
                         "--target-pca", os.path.join(first, "work", tgt, "pca.model"),
                         "--direction", f"{src}->{tgt}", "--motion", motion, "--method", "average",
                         "--placement", "scaled-source", "--correspondences", "dense", "--out", report],
                        check=True)
                    r = json.load(open(report))
                sq += r["frames"] * r["rms_pose_m"] ** 2
                frames += r["frames"]
            print(f"{direction} w={w}: {100 * math.sqrt(sq / frames):.3f} cm over {frames} frames")


if __name__ == "__main__":
    main()

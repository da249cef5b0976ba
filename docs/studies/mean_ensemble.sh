#!/bin/bash
# The transfer model's configurations on capture sets: `make transfer-results` (gpr-nn rows only)
# per configuration, then the pooled pose error of the raw transfer and of the full pipeline
# (gpr-nn+correct+stitch) per direction and per set, and for `auto` the cross-validated error of
# every candidate with the configuration kept. Study: 47-mean-ensemble.md.
#   docs/studies/mean_ensemble.sh OUT SET...   e.g. docs/studies/mean_ensemble.sh /tmp/me out/holdout/set
# CONFIGS (default "default affine-mean no-prior affine-only zero-mean paper auto") names the
# configurations, each passed as gpr-train --config.
# Writes OUT/<set>-<config>/ (the runs; delete them when done) and prints one line per run.
set -euo pipefail
out=$1; shift
configs=${CONFIGS:-default affine-mean no-prior affine-only zero-mean paper auto}
mkdir -p "$out"
for set in "$@"; do
  name=$(basename "$(dirname "$set")")-$(basename "$set")
  for config in $configs; do
    # gpr-train --config alone: CONFIG=paper would also change the alignment and placement.
    make -s NO_BUILD=1 transfer-results SET="$set" OUT="$out/$name-$config" GPR_TRAIN_FLAGS="--config=$config" \
      TRANSFER_METHODS=gpr-nn > "$out/$name-$config.log" 2>&1
  done
done
python3 - "$out" <<'PY'
import glob, json, math, os, subprocess, sys
out = sys.argv[1]
def pooled(rows, method):
    acc = {}
    for r in rows:
        if r["method"] == method and r["placement"] == "scaled-source" and r["training"] == "dense":
            a = acc.setdefault(r["direction"], [0.0, 0])
            a[0] += r["frames"] * r["rms_pose_m"] ** 2
            a[1] += r["frames"]
    cm = lambda s, f: 100 * math.sqrt(s / f)
    per = " ".join(f"{d} {cm(*a):.3f}" for d, a in sorted(acc.items()))
    return f"{per}, pooled {cm(sum(a[0] for a in acc.values()), sum(a[1] for a in acc.values())):.3f}"
for run in sorted(glob.glob(f"{out}/*/results.json")):
    rows = json.load(open(run))
    d = os.path.dirname(run)
    print(f"{os.path.basename(d)}: raw {pooled(rows, 'gpr-nn')} | full {pooled(rows, 'gpr-nn+correct+stitch')}")
    if d.endswith("-auto"):
        for model in sorted(glob.glob(f"{d}/work/models/*/gpr-nn.model")):
            h = json.loads(subprocess.run(["target/release/inspect", model], capture_output=True, text=True, check=True).stdout)
            cv = h["header"]["params"]["cross_validation"]
            tried = " ".join(f"{c['config']} {100 * c['cv_rms_pose_m']:.2f}" for c in cv["candidates"])
            print(f"  {model.split('/')[-2]}: kept {cv['config']}; estimates (cm) {tried}")
PY

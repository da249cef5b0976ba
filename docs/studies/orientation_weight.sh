#!/bin/bash
# The limb orientation weight against the training size: `make transfer-results` (gpr-nn rows only)
# per weight, the pooled pose error of the full pipeline (gpr-nn+correct+stitch, scaled-source
# placement) per run, then per direction the cross-validated error of each weight with whole
# motions held out and with halves of motions held out (`gpr-train --cross-validate --cv-folds`,
# the pipeline's own pairs). Study: 48-orientation-weight.md.
#   docs/studies/orientation_weight.sh OUT SET...   e.g. docs/studies/orientation_weight.sh /tmp/ow out/holdout/set
# WEIGHTS (default "0.5 0.3 0") are the `gpr-train --orientation-weight` values.
# Writes OUT/<set>-<weight>/ (the runs; delete them when done) and prints one line per run and per
# direction and fold kind.
set -euo pipefail
out=$1; shift
weights=${WEIGHTS:-0.5 0.3 0}
mkdir -p "$out"
pooled() {
  python3 - "$1" <<'PY'
import json, math, sys
s = f = 0
for r in json.load(open(sys.argv[1])):
    if r["method"] == "gpr-nn+correct+stitch" and r["placement"] == "scaled-source" and r["training"] == "dense":
        s += r["frames"] * r["rms_pose_m"] ** 2
        f += r["frames"]
print(f"{100 * math.sqrt(s / f):.2f}")
PY
}
for set in "$@"; do
  name=$(basename "$(dirname "$set")")-$(basename "$set")
  for w in $weights; do
    run=$out/$name-$w
    make -s NO_BUILD=1 transfer-results SET="$set" OUT="$run" GPR_TRAIN_FLAGS="--orientation-weight=$w" \
      TRANSFER_METHODS=gpr-nn > "$run.log" 2>&1
    echo "$name weight $w: full pipeline $(pooled "$run/results.json") cm"
  done
  # The cross-validation reruns the pipeline's gpr-train step of each direction (its pairs).
  first=$out/$name-$(set -- $weights; echo "$1")
  grep -E "label 'gpr-train models/[^/]+/gpr-nn' " "$first/work/plan.mk" | while read -r line; do
    dir=$(grep -oE "label 'gpr-train models/[^/]+" <<< "$line" | cut -d/ -f2)
    cmd=${line#*-- }
    cmd=${cmd//\$(BIN)/target/release}
    cmd=$(sed -E 's/ --orientation-weight=[0-9.]+//; s/ --out .*//' <<< "$cmd")
    for folds in motions halves; do
      line="$name $dir folds $folds:"
      for w in $weights; do
        report=$out/$name-$dir-$folds-$w.json
        eval "$cmd --cross-validate --cv-folds $folds --orientation-weight $w --report $report --out $out/cv.model"
        line="$line weight $w $(python3 -c "import json, sys; print(f\"{100 * json.load(open(sys.argv[1]))['cv_rms_pose_m']:.2f}\")" "$report")"
      done
      echo "$line cm"
    done
  done
done

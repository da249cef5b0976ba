#!/bin/bash
# Spinning, torn and slowed frames of every variation of `make variation`'s groups, with and
# without the turn limit, under ancestral draws (seeds 0-2), from the plan's own hmc-sample
# command lines. Study: 46-turn-limit.md.
#   docs/studies/turn_limit.sh OUT SET...   e.g. docs/studies/turn_limit.sh /tmp/tl out/demo/set
# Writes OUT/<set>/ (make variation: HMC at the defaults) and OUT/ancestral/<set>-<seed>-<on|off>/
# (reports only), then prints the counts per set.
set -euo pipefail
out=$1; shift
mkdir -p "$out"
for set in "$@"; do
  name=$(basename "$(dirname "$set")")
  make -s NO_BUILD=1 variation SET="$set" OUT="$out/$name" > "$out/$name.log" 2>&1
  grep -h -- '-- $(BIN)/hmc-sample -q' "$out/$name/work/plan.mk" | sed 's/.*-- \$(BIN)\/hmc-sample/target\/release\/hmc-sample/' |
  while read -r line; do
    group=$(echo "$line" | sed 's/.*--model [^ ]*\/\([^/ ]*\)\.model.*/\1/')
    for seed in 0 1 2; do
      for limit in on off; do
        flag=""; [ $limit = off ] && flag="--no-turn-limit"
        dir="$out/ancestral/$name-$seed-$limit"; mkdir -p "$dir"
        eval "$(echo "$line" | sed "s# --seed 0# --seed $seed --sampler ancestral $flag#; s#--out [^ ]*#--out $dir/meshes#; s#--report [^ ]*#--report $dir/$group.json#")"
        rm -rf "$dir/meshes"
      done
    done
  done
done
python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
def counts(files):
    c = dict(spinning=0, about_vertical=0, torn=0, slowed=0)
    for f in files:
        for s in json.load(open(f))["sequences"]:
            for t in s["turns_and_tears"]:
                c["spinning"] += len(t["spinning_frames"]); c["about_vertical"] += len(t["heading_spinning_frames"])
                c["torn"] += len(t["torn_frames"]); c["slowed"] += t.get("slowed_steps", 0)
    return c
for d in sorted(glob.glob(f"{out}/*/work/variation")):
    name = d.split("/")[-3]
    print(name, "hmc, seed 0:", counts(glob.glob(f"{d}/*-samples.json")))
    for limit in ("on", "off"):
        print(name, f"ancestral, seeds 0-2, limit {limit}:", counts(glob.glob(f"{out}/ancestral/{name}-*-{limit}/*.json")))
PY

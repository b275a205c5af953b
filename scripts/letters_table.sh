#!/usr/bin/env bash
# Paper Table 3 on this machine: for each letter of "SIGGRAPH" and each optimiser, the
# evaluations (= NLopt iterations; Ceres and Ipopt report theirs in DIR/*.log) needed to reach
# a normalised loss of 1e-3 (capped at the scene's 100), and the wall time to get there.
#   scripts/letters_table.sh [BUILD_DIR] [OUT_DIR]   (default build, /tmp/liedyn-letters)
# Prints a Markdown table; per-run outputs stay in OUT_DIR/<letter>-<optimizer>/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
out=${2:-/tmp/liedyn-letters}
mkdir -p "$out"
echo "| letter | DOF | parameters | optimizer | evaluations to 1e-3 | seconds to 1e-3 | final normalised loss | status |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for letter in S I G R A P H; do
  scene=$root/problems/scenes/letters/letter_$letter.json
  nodes=$(python3 -c "import json;print(json.load(open('$scene'))['rods'][0]['shape']['edges']+1)")
  for optimizer in nlopt-lbfgs ceres-lbfgs ipopt-lbfgs; do
    dir=$out/$letter-$optimizer
    status=0
    "$build/liedyn" optimize "$scene" --out "$dir" --optimizer "$optimizer" > "$dir.log" 2>&1 || status=$?
    python3 - "$dir/history.csv" "$letter" "$nodes" "$optimizer" "$status" "$dir.log" <<'PY'
import csv, sys
path, letter, nodes, optimizer, status, log = sys.argv[1:]
nodes = int(nodes)
rows = list(csv.DictReader(open(path)))
hit = next((r for r in rows if float(r["normalized_loss"]) <= 1e-3), None)
best = min(float(r["normalized_loss"]) for r in rows)
first = open(log).readline().strip().split(": ", 1)[-1]
print(f"| {letter} | {3 * (2 * nodes - 1)} | {3 * nodes} | {optimizer} | "
      f"{int(hit['iteration']) + 1 if hit else '> ' + str(len(rows))} | "
      f"{float(hit['seconds']):.2f} | {best:.2e} | {first} |" if hit else
      f"| {letter} | {3 * (2 * nodes - 1)} | {3 * nodes} | {optimizer} | > {len(rows)} | "
      f"— ({float(rows[-1]['seconds']):.2f} s in all) | {best:.2e} | {first} |")
PY
  done
done

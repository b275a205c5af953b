#!/usr/bin/env bash
# Reproduces the paper's Fig. 3 (singular values of d vec(exp(r))/dr), Fig. 4 (butterfly bolt:
# residual reduction and Hessian condition number, Lie vs rotation vectors) and Table 1
# (helical perversion timings) from an existing Release build, then plots them with
# scripts/plot_paper_figures.py.
#   bash scripts/paper_figures.sh OUT_DIR
# The build is $LIEDYN_BUILD (default: build/ in the repository); make it with scripts/test.sh.
set -euo pipefail
if [ $# -ne 1 ]; then
  echo "usage: bash scripts/paper_figures.sh OUT_DIR" >&2
  exit 2
fi
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# OUT_DIR and LIEDYN_BUILD are relative to the caller's directory; the runs use the repository's.
B=$(realpath -m "${LIEDYN_BUILD:-$root/build}")
if [ ! -x "$B/liedyn" ]; then
  echo "error: $B/liedyn not found: build liedyn first with 'bash scripts/test.sh'" \
    "(or point LIEDYN_BUILD at a Release build folder)" >&2
  exit 1
fi
build_type=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$B/CMakeCache.txt" 2>/dev/null || true)
if [ "$build_type" != "Release" ]; then
  echo "warning: $B is a '${build_type:-unknown}' build, not Release: the timings mean little" >&2
fi
mkdir -p "$1"
out=$(cd "$1" && pwd)
cd "$root"

# Provenance: where and from what the numbers come.
{
  echo "uname: $(uname -a)"
  echo "nproc: $(nproc)"
  echo "cpu: $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n1)"
  echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "date: $(date -u '+%Y-%m-%d %H:%M:%S UTC')"
  echo "git: $(git rev-parse HEAD 2>/dev/null || echo unknown)"
  echo "uncommitted changes: $(git status --porcelain 2>/dev/null | wc -l) files"
  echo "build: $B (${build_type:-unknown})"
} > "$out/machine.txt"

echo "Fig. 3: exp Jacobian singular values" >&2
"$B/liedyn" exp-jacobian --out "$out/fig3_exp_jacobian.csv" --samples 721

echo "Fig. 4: butterfly bolt" >&2
"$B/liedyn" compare problems/scenes/butterfly_bolt.json --rotations lie,rotvec,quat --csv \
  --repeat 5 --frames-csv "$out/fig4_bolt_frames.csv" > "$out/fig4_bolt_compare.csv"

echo "Table 1: helical perversion" >&2
"$B/liedyn" compare problems/scenes/helix_perversion.json --rotations lie,rotvec,quat --csv \
  --repeat 3 --frames-csv "$out/table1_helix_frames.csv" > "$out/table1_helix_compare.csv"

/usr/bin/python3 scripts/plot_paper_figures.py "$out"

echo "Wrote:"
ls -1 "$out"/{machine.txt,fig3_exp_jacobian.csv,fig3_exp_jacobian.png,fig4_bolt_frames.csv} \
  "$out"/{fig4_bolt_compare.csv,fig4_bolt.png,fig4_bolt_summary.md} \
  "$out"/{table1_helix_frames.csv,table1_helix_compare.csv,table1_helix.md}

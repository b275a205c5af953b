#!/usr/bin/env bash
# Runs scripts/slurm/sweep.sbatch on a single-node Slurm cluster started here
# (local_cluster.sh: slurmctld, slurmd and munged on localhost, as root), merges the shards
# with `liedyn sweep-merge`, and checks the result against the same sweep run serially:
# every column but the timings equal.
#
#   test_sweep.sh LIEDYN_EXECUTABLE
#
# Slurm's packages are installed only where asked to (LIEDYN_TEST_SLURM=install, set by
# .ci/run): installing slurm-wlm on a machine with systemd enables its daemons. Otherwise,
# without slurmctld/slurmd/munged/sbatch, the test is skipped (exit 77) and says why.
set -euo pipefail

liedyn=$(realpath "$1")
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
cluster="$here/local_cluster.sh"

if [[ $(id -u) -ne 0 ]]; then
    echo "test_sweep: skipped: the local cluster's daemons run as root" >&2
    exit 77
fi
for tool in slurmctld slurmd munged sbatch; do
    if ! command -v "$tool" >/dev/null && [[ ${LIEDYN_TEST_SLURM:-} != install ]]; then
        echo "test_sweep: skipped: $tool is not installed (LIEDYN_TEST_SLURM=install installs" \
            "slurm-wlm and munge)" >&2
        exit 77
    fi
done

dir=$(mktemp -d /tmp/liedyn-slurm.XXXXXX)
cleanup() {
    local rc=$? f
    if [[ $rc -ne 0 ]]; then
        for f in "$dir"/slurmctld.log "$dir"/slurmd.log "$dir"/out/liedyn-sweep-*.out; do
            [[ -f $f ]] && { echo "===== $f =====" >&2; tail -n 30 "$f" >&2; }
        done
    fi
    "$cluster" stop "$dir" || true
    if [[ $rc -eq 0 ]]; then rm -rf "$dir"; else echo "kept $dir for inspection" >&2; fi
}
trap cleanup EXIT

env_line=$("$cluster" start "$dir")  # assigned first: a failed start stops the script
eval "$env_line"

scene="$root/problems/scenes/butterfly_bolt.json"
grid=(--set "time_step=0.02,0.01,0.005" --set "integrator=backward_euler,bdf2")
mkdir -p "$dir/out"
cd "$dir/out"
# Three array tasks over six grid points; --wait returns when all have ended (non-zero if
# one failed); timeout: a wedged cluster fails the test instead of hanging it.
LIEDYN="$liedyn" timeout 300 sbatch --wait --array=0-2 "$here/sweep.sbatch" "$scene" "$dir/sweep" "${grid[@]}"
"$liedyn" sweep-merge "$dir"/sweep/shard-*-of-3 --out "$dir/merged" > /dev/null
"$liedyn" sweep "$scene" "${grid[@]}" -j 1 --quiet --out "$dir/serial" > /dev/null

# The columns that are not timings, row by row.
results() {
    python3 - "$1" <<'PY'
import csv, sys
timing = {"wall_seconds", "parallel_runs", "gradient_seconds", "pareto"}
for row in csv.DictReader(open(sys.argv[1])):
    print(",".join(v for k, v in row.items() if k not in timing))
PY
}
if ! diff <(results "$dir/serial/sweep.csv") <(results "$dir/merged/sweep.csv"); then
    echo "test_sweep: the merged shards differ from the serial sweep" >&2
    exit 1
fi
rows=$(results "$dir/merged/sweep.csv" | wc -l)
[[ $rows -eq 6 ]] || { echo "test_sweep: $rows rows, expected 6" >&2; exit 1; }
echo "test_sweep: 3 Slurm array tasks, merged: the serial sweep's 6 runs"

#!/usr/bin/env bash
# Smoke test for local_cluster.sh: start a throw-away cluster, run a 3-task job array
# through sbatch, check each task wrote its own output, stop the cluster.
# Exits 0 on success. Must run as root (local_cluster.sh needs it).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cluster="$here/local_cluster.sh"
t0=$EPOCHREALTIME
# Seconds from $1 to $2 (default: now), both $EPOCHREALTIME values; awk, as bc may be absent.
elapsed() { awk -v a="$1" -v b="${2:-$EPOCHREALTIME}" 'BEGIN { printf "%.1f", b - a }'; }

dir=$(mktemp -d /tmp/slurm-check.XXXXXX)
cleanup() {
    local rc=$?
    "$cluster" stop "$dir" || true
    # Keep the state dir (logs) when something failed, to make CI failures debuggable.
    if [[ $rc -eq 0 ]]; then rm -rf "$dir"; else echo "kept $dir for inspection" >&2; fi
    echo "check_local_cluster: $([[ $rc -eq 0 ]] && echo OK || echo FAILED)," \
        "total wall time $(elapsed "$t0") s" >&2
}
trap cleanup EXIT

# `start` prints "export SLURM_CONF=..." on stdout (its log goes to stderr). Assign
# before eval: `eval "$(cmd)"` would hide a failing start from set -e.
env_line=$("$cluster" start "$dir")
eval "$env_line"
t_up=$EPOCHREALTIME

# --wait makes sbatch return only when every array task has finished, and its exit code
# is non-zero if any task failed. Single quotes: the variables expand inside the job.
# shellcheck disable=SC2016
sbatch --wait --array=0-2 --job-name=check --output="$dir/out_%a.txt" \
    --wrap 'echo task $SLURM_ARRAY_TASK_ID of $SLURM_ARRAY_TASK_COUNT'
echo "cluster up after $(elapsed "$t0" "$t_up") s;" \
    "job array took $(elapsed "$t_up") s" >&2

for i in 0 1 2; do
    f="$dir/out_$i.txt"
    [[ -f $f ]] || { echo "missing $f" >&2; exit 1; }
    got=$(<"$f")
    [[ $got == "task $i of 3" ]] || { echo "unexpected $f: '$got'" >&2; exit 1; }
    echo "$f: $got"
done

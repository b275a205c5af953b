#!/usr/bin/env python3
"""Measures many runs at once (README, "Many runs"): a sweep on threads and on MPI ranks
against the same sweep run serially, and multi-start optimisation against the single start.

    /usr/bin/python3 scripts/many_runs.py [--liedyn build/liedyn] [--repeat 3] [--part sweep|starts|all]

Sweep: wall time of the whole `liedyn sweep` command (median of --repeat runs each), on
  * the Timoshenko beam (3000 steps of 2 ms) over 8 values of its mass: 8 runs and their
    8 references (a model axis: every run has its own), 16 tasks of ~0.2 s;
  * the butterfly bolt over 4 time steps x 2 integrators: 8 runs sharing one reference at
    h/4, which runs first and alone (it bounds the speed-up: Amdahl).
  -j 1 against -j 2, and mpirun -np 2 (when liedyn was built with MPI).
Multi-start: the best normalised loss of K = 8 starts (-j 2) against start 0 (the scene's
own γ0, i.e. the single run), on letter S with ceres-lbfgs, letter R with nlopt-lbfgs, and
the share of starts that reach the target on the die thrown through contact.
"""

import argparse
import csv
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "problems", "scenes")


def run(cmd, cwd):
    start = time.perf_counter()
    result = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seconds = time.perf_counter() - start
    if result.returncode not in (0, 3):
        sys.exit(f"{' '.join(cmd)}: exit {result.returncode}\n{result.stderr}")
    return seconds, result


def timed(cmd, repeat, work):
    times = []
    for i in range(repeat):
        out = os.path.join(work, f"out{i}")
        shutil.rmtree(out, ignore_errors=True)
        seconds, _ = run(cmd + ["--out", out], work)
        times.append(seconds)
    return statistics.median(times), times


def sweep_part(liedyn, repeat, work):
    masses = ",".join(str(2900 + 10 * i) for i in range(8))
    grids = {
        "Timoshenko beam, 8 masses (8 runs + 8 references)": [
            "sweep", os.path.join(SCENES, "timoshenko_beam.json"), "--set", "frames=3000",
            "--set", f"rods.0.mass={masses}", "--quiet"],
        "butterfly bolt, 4 h x 2 integrators (8 runs + 1 reference at h/4)": [
            "sweep", os.path.join(SCENES, "butterfly_bolt.json"), "--set",
            "time_step=0.02,0.01,0.005,0.0025", "--set", "integrator=backward_euler,bdf2", "--quiet"],
    }
    mpirun = shutil.which("mpirun")
    print("| grid | -j 1 [s] | -j 2 [s] | speed-up | mpirun -np 2 [s] | speed-up |")
    print("|---|---|---|---|---|---|")
    for name, cmd in grids.items():
        serial, _ = timed([liedyn] + cmd + ["-j", "1"], repeat, work)
        threads, _ = timed([liedyn] + cmd + ["-j", "2"], repeat, work)
        mpi = "-"
        mpi_ratio = "-"
        if mpirun:
            ranks, _ = timed([mpirun, "--allow-run-as-root", "--oversubscribe", "-np", "2", liedyn] + cmd
                             + ["-j", "1"], repeat, work)
            mpi = f"{ranks:.2f}"
            mpi_ratio = f"{serial / ranks:.2f}x"
        print(f"| {name} | {serial:.2f} | {threads:.2f} | {serial / threads:.2f}x | {mpi} | {mpi_ratio} |",
              flush=True)


def read_starts(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def starts_part(liedyn, work):
    cases = [
        ("letter S, ceres-lbfgs", os.path.join(SCENES, "letters", "letter_S.json"), ["--optimizer", "ceres-lbfgs"]),
        ("letter R, nlopt-lbfgs", os.path.join(SCENES, "letters", "letter_R.json"), ["--optimizer", "nlopt-lbfgs"]),
        ("die through contact, scene's optimiser", os.path.join(SCENES, "optimization", "die_throw_contact.json"), []),
    ]
    print("| problem | K | spread | start 0 (single run) | best of K | starts reaching the target | wall time -j 2 [s] |")
    print("|---|---|---|---|---|---|---|")
    for name, scene, extra in cases:
        out = os.path.join(work, "starts")
        shutil.rmtree(out, ignore_errors=True)
        cmd = [liedyn, "optimize", scene, "--starts", "8", "-j", "2", "--out", out] + extra
        seconds, _ = run(cmd, work)
        rows = read_starts(os.path.join(out, "starts.csv"))
        losses = [float(r["best_normalized_loss"]) for r in rows]
        reached = sum(int(r["reached_target"]) for r in rows)
        print(f"| {name} | 8 | 0.1 | {losses[0]:.3g} | {min(losses):.3g} (start {losses.index(min(losses))}) "
              f"| {reached} of 8 | {seconds:.1f} |", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--liedyn", default=os.path.join(ROOT, "build", "liedyn"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--part", choices=["sweep", "starts", "all"], default="all")
    args = parser.parse_args()
    liedyn = os.path.abspath(args.liedyn)
    print(f"machine: {os.cpu_count()} cores; {time.strftime('%Y-%m-%d')}; {liedyn}\n")
    with tempfile.TemporaryDirectory() as work:
        if args.part in ("sweep", "all"):
            sweep_part(liedyn, args.repeat, work)
            print()
        if args.part in ("starts", "all"):
            starts_part(liedyn, work)


if __name__ == "__main__":
    main()

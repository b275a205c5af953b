#!/usr/bin/env python3
"""Paper Table 3 on this machine (README "Differentiable simulation").

  python3 scripts/letters_table.py [--build DIR] [--out DIR] [--letters SIGRAPH] [--no-sweep]

Runs `liedyn optimize` on problems/scenes/letters/letter_<L>.json and prints three Markdown
tables:
 1. per letter and back-end (rotation "lie"): iterations and evaluations to the scenes' stop
    (normalised loss <= 1e-3, or 100 iterations), wall time, best normalised loss, status;
 2. per letter, NLopt under the three rotation parameterisations (lie, rotvec, quat) run
    side by side: evaluations, seconds and time per evaluation, with the rotvec/lie ratio
    (paper Table 3 compares rotation vectors with Lie derivatives);
 3. the horizon sweep on S (NLopt): time step and frame count against the best normalised
    loss, which is why the scenes use 100 frames of 1 ms and not Table 2's 10 ms.
Variants of a scene are written to OUT as JSON; each run's outputs stay in OUT/<run>/ and its
console output in OUT/<run>.log. A run whose optimiser fails is reported as
such, not skipped (exit status 3: short of the target, 4: failed); any other non-zero
status stops the script.
"""
import argparse
import csv
import json
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
OPTIMIZERS = ["nlopt-lbfgs", "ceres-lbfgs", "ipopt-lbfgs"]
ROTATIONS = ["lie", "rotvec", "quat"]
# (time step in s, frames) for the sweep on S; the scenes' own setting is (1e-3, 100).
SWEEP = [(1e-2, 100), (1e-2, 10), (2.5e-3, 40), (1e-3, 100), (1e-3, 300)]


def run(build, out, letter, name, optimizer, rotation="lie", time_step=None, frames=None):
    scene = json.loads((ROOT / f"problems/scenes/letters/letter_{letter}.json").read_text())
    scene["solver"]["rotation"] = rotation
    if time_step is not None:
        scene["time_step"] = time_step
    if frames is not None:
        scene["frames"] = frames
    path = out / f"{name}.json"
    path.write_text(json.dumps(scene, indent=2))
    result = subprocess.run([str(build / "liedyn"), "optimize", str(path), "--out",
                             str(out / name), "--optimizer", optimizer],
                            capture_output=True, text=True)
    (out / f"{name}.log").write_text(result.stdout + result.stderr)
    if result.returncode not in (0, 3, 4):
        sys.exit(f"{name}: liedyn optimize exited with {result.returncode}:\n{result.stderr}")
    # "iterations N, evaluations M, T s" (problems/optimization.cpp)
    counts = re.search(r"iterations (\d+), evaluations (\d+), ([0-9.e+-]+) s", result.stdout)
    if counts is None:
        sys.exit(f"{name}: no iteration count in the output:\n{result.stdout}")
    rows = list(csv.DictReader(open(out / name / "history.csv")))
    status = result.stdout.splitlines()[0].split(": ", 1)[1].split(" ")[0]
    rod = scene["rods"][0]
    nodes = rod["shape"]["edges"] + 1
    return {
        "dof": 3 * (2 * nodes - 1), "parameters": 3 * nodes,
        "iterations": int(counts[1]), "evaluations": int(counts[2]),
        "seconds": float(counts[3]),
        "best": min(float(r["normalized_loss"]) for r in rows),
        "status": status,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(ROOT / "build"))
    parser.add_argument("--out", default="/tmp/liedyn-letters")
    parser.add_argument("--letters", default="SIGRAPH")
    parser.add_argument("--no-sweep", action="store_true")
    args = parser.parse_args()
    build, out = pathlib.Path(args.build), pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    print("| letter | #q | #γ | optimizer | iterations (evaluations) | seconds | best normalised loss | status |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for letter in args.letters:
        for optimizer in OPTIMIZERS:
            r = run(build, out, letter, f"{letter}-{optimizer}", optimizer)
            print(f"| {letter} | {r['dof']} | {r['parameters']} | {optimizer} | "
                  f"{r['iterations']} ({r['evaluations']}) | {r['seconds']:.2f} | "
                  f"{r['best']:.2e} | {r['status']} |", flush=True)

    print()
    print("| letter | rotation | evaluations | seconds | ms per evaluation | best normalised loss | status |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for letter in args.letters:
        per_evaluation = {}
        for rotation in ROTATIONS:
            r = run(build, out, letter, f"{letter}-nlopt-{rotation}", "nlopt-lbfgs", rotation)
            per_evaluation[rotation] = r["seconds"] / r["evaluations"]
            ratio = (f" ({per_evaluation['rotvec'] / per_evaluation['lie']:.2f}× lie)"
                     if rotation == "rotvec" else "")
            print(f"| {letter} | {rotation} | {r['evaluations']} | {r['seconds']:.2f} | "
                  f"{1e3 * per_evaluation[rotation]:.1f}{ratio} | {r['best']:.2e} | "
                  f"{r['status']} |", flush=True)

    if args.no_sweep:
        return
    print()
    print("| S: time step | frames | simulated time | evaluations | seconds | best normalised loss | status |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for time_step, frames in SWEEP:
        r = run(build, out, "S", f"S-sweep-{time_step:g}-{frames}", "nlopt-lbfgs",
                time_step=time_step, frames=frames)
        print(f"| {1e3 * time_step:g} ms | {frames} | {time_step * frames:g} s | "
              f"{r['evaluations']} | {r['seconds']:.2f} | {r['best']:.2e} | {r['status']} |",
              flush=True)


if __name__ == "__main__":
    main()

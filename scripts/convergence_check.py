#!/usr/bin/python3
"""Newton's two convergence checks side by side (SolverOptions::convergence_check): the same
scenes timed by `liedyn bench` under "assembled" and "estimated", interleaved, Release.

    /usr/bin/python3 scripts/convergence_check.py [build/liedyn]

Per scene: µs per step, Newton iterations, assemblies and factorisations per step, unconverged
steps, under each check, and the ratio of the step times.
"""
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENES = [
    ("butterfly_bolt.json", []),
    ("timoshenko_beam.json", ["integrator=backward_euler"]),
    ("timoshenko_beam.json", ["integrator=bdf2"]),
    ("timoshenko_beam.json", []),  # trapezoidal
    ("helix_pull.json", []),
    ("helix_perversion.json", []),
    ("contact/die_throw.json", []),
    ("contact/tube_insertion.json", ["frames=400"]),
]


def bench(liedyn, scene, settings, check):
    args = [liedyn, "bench", str(ROOT / "problems/scenes" / scene), "--repeat", "5", "--json",
            "--set", f"solver.convergence_check={check}"]
    for s in settings:
        args += ["--set", s]
    return json.loads(subprocess.run(args, capture_output=True, text=True, check=True).stdout)


def main(liedyn):
    print("| scene | check | µs per step | iterations | assemblies | factorisations | unconverged | assembled / estimated |")
    print("|---|---|---|---|---|---|---|---|")
    for scene, settings in SCENES:
        label = scene + "".join(f" {s}" for s in settings)
        runs = {check: bench(liedyn, scene, settings, check) for check in ("assembled", "estimated")}
        per_step = {c: 1e6 * r["total_seconds"] / r["frames"] for c, r in runs.items()}
        for check, r in runs.items():
            ratio = f"{per_step['assembled'] / per_step['estimated']:.2f}×" if check == "estimated" else ""
            print(f"| {label} | {check} | {per_step[check]:.1f} | {r['iterations_per_frame']:.3g} | "
                  f"{r['assemblies_per_frame']:.3g} | {r['factorizations_per_frame']:.3g} | "
                  f"{r['unconverged_steps']} | {ratio} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "build/liedyn"))

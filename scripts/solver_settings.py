#!/usr/bin/python3
"""Two or more values of one solver setting side by side: the same scenes timed by
`liedyn bench` under each value, interleaved, Release.

    /usr/bin/python3 scripts/solver_settings.py [--liedyn build/liedyn] [PATH=A,B,...]

PATH=A,B defaults to solver.convergence_check=assembled,estimated (Newton's two convergence
checks); solver.hessian_reuse=1,10 compares a new factorisation at every step with one per
ten steps. Per scene: µs per step, Newton iterations, assemblies and factorisations per step,
solves ended on a reused factorisation and the largest measured error of their steps,
unconverged steps, under each value, and how many times faster a step is than under the first
value.
"""
import argparse
import json
import pathlib
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENES = [
    ("butterfly_bolt.json", []),
    ("timoshenko_beam.json", ["integrator=backward_euler"]),
    ("timoshenko_beam.json", ["integrator=bdf2"]),
    ("timoshenko_beam.json", []),  # trapezoidal
    ("timoshenko_beam.json", ["integrator=backward_euler", "solver.tolerance=1e-5"]),
    ("timoshenko_beam.json", ["solver.tolerance=1e-5"]),
    ("helix_pull.json", []),
    ("helix_perversion.json", []),
    ("contact/die_throw.json", []),
    ("contact/tube_insertion.json", ["frames=400"]),
]


def bench(liedyn, scene, settings):
    args = [liedyn, "bench", str(ROOT / "problems/scenes" / scene), "--repeat", "5", "--json"]
    for s in settings:
        args += ["--set", s]
    return json.loads(subprocess.run(args, capture_output=True, text=True, check=True).stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--liedyn", default=str(ROOT / "build/liedyn"))
    parser.add_argument("setting", nargs="?", default="solver.convergence_check=assembled,estimated")
    args = parser.parse_args()
    path, _, values = args.setting.partition("=")
    values = values.split(",")
    if not path or len(values) < 2:
        parser.error("expected PATH=A,B[,...]")
    print(f"| scene | {path} | µs per step | iterations | assemblies | factorisations | reused | "
          "reuse error | unconverged | speed-up |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for scene, settings in SCENES:
        label = scene + "".join(f" {s}" for s in settings)
        runs = {v: bench(args.liedyn, scene, settings + [f"{path}={v}"]) for v in values}
        per_step = {v: 1e6 * r["total_seconds"] / r["frames"] for v, r in runs.items()}
        for v, r in runs.items():
            ratio = f"{per_step[values[0]] / per_step[v]:.2f}×" if v != values[0] else ""
            print(f"| {label} | {v} | {per_step[v]:.1f} | {r['iterations_per_frame']:.3g} | "
                  f"{r['assemblies_per_frame']:.3g} | {r['factorizations_per_frame']:.3g} | "
                  f"{r['reused_per_frame']:.3g} | {r['reuse_error']:.2g} | {r['unconverged_steps']} | {ratio} |")


if __name__ == "__main__":
    main()

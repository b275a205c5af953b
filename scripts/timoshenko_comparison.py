#!/usr/bin/python3
"""liedyn against PyElastica on PyElastica's Timoshenko beam (problems/scenes/timoshenko_beam.json):
a thick, shearable rod of 100 elements, clamped, a 15 N step load at its tip, no damping, 10 s.

PyElastica's example (examples/TimoshenkoBeamCase) ramps its load over 250 s and damps; both are
left out here on both sides, so that the two codes integrate the same undamped step response.
PyElastica is not a Debian package: give a checkout of its source (it needs Debian's
python3-numba, python3-numpy, python3-scipy, python3-tqdm, python3-typing-extensions):

  git clone --depth 1 https://github.com/GazzolaLab/PyElastica /tmp/pyelastica
  /usr/bin/python3 scripts/timoshenko_comparison.py --pyelastica /tmp/pyelastica [--liedyn build/liedyn]

Reports, for PyElastica (position Verlet at its example's dt = 0.07 L/100, at dt/4 and dt/16)
and liedyn (each integrator at several h and Newton tolerances: the scene's 1e-9, and 1e-5, at
which its steps converge at their first Newton step — one assembly and one factorisation,
without the trial gradient of a line search — and whose tip errors are the same; a converged
step errs by about the square of its last Newton step; and with a factorisation at every step
or one per ten, solver.hessian_reuse), the tip at t = 10 s, its distance from each code's
finest run, the largest tip distance from each code's finest run over the whole 10 s (at the
run's own steps, PyElastica's recorded in a second, untimed run),
and wall times: PyElastica's loop alone (after numba's compilation; median of 3), liedyn's `bench` (its
time steps alone, no outputs).
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "problems", "scenes", "timoshenko_beam.json")
FINAL_TIME = 10.0
# The example's parameters (examples/TimoshenkoBeamCase/run_timoshenko.py).
N_ELEM, LENGTH, RADIUS, DENSITY, E, G = 100, 3.0, 0.25, 5000.0, 1e6, 1e4
EXAMPLE_DT = 0.07 * LENGTH / N_ELEM


def pyelastica_run(dt):
    """PyElastica's tip series (time, x, y, z; in liedyn's axes: rod along x, load along −z)
    and its loop's wall time (the median of three runs without the recording). Its rod lies along +z
    with the load along −x: x and z swap."""
    import numpy as np
    import elastica as ea

    class Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing):
        pass

    def run(steps, dt, record):
        sim = Sim()
        rod = ea.CosseratRod.straight_rod(
            N_ELEM, np.zeros(3), np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0]), LENGTH,
            RADIUS, DENSITY, youngs_modulus=E, shear_modulus=G)
        sim.append(rod)
        sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                                 constrained_director_idx=(0,))
        # A step: EndpointForces scales by min(1, t/ramp_up_time), and position Verlet
        # evaluates forces at t + dt/2 > 0.
        force = np.array([-15.0, 0.0, 0.0])
        sim.add_forcing_to(rod).using(ea.EndpointForces, 0.0 * force, force, ramp_up_time=1e-12)
        sim.finalize()
        stepper, t = ea.PositionVerlet(), np.float64(0.0)
        series = []
        start = time.perf_counter()
        for _ in range(steps):
            t = stepper.step(sim, t, np.float64(dt))
            if record:
                tip = rod.position_collection[:, -1]
                series.append((float(t), tip[2], tip[1], tip[0]))
        return series, time.perf_counter() - start

    steps = int(math.ceil(FINAL_TIME / dt - 1e-9))
    dt = FINAL_TIME / steps
    run(20, dt, record=False)  # numba compiles here
    # Timed without recording, the median of three runs (as liedyn's bench --repeat 3).
    seconds = sorted(run(steps, dt, record=False)[1] for _ in range(3))[1]
    series, _ = run(steps, dt, record=True)
    return dt, series, seconds


def liedyn_run(liedyn, integrator, h, tolerance, reuse=1):
    """liedyn's tip series (time, x, y, z) and its `bench` time for one integrator, h, Newton
    tolerance and solver.hessian_reuse, and its Newton iterations over the run; for a step the
    integrator refuses as unstable, no series and the refusal in place of the time."""
    frames = int(round(FINAL_TIME / h))
    h = FINAL_TIME / frames
    settings = ["--set", f"integrator={integrator}", "--set", f"time_step={h!r}",
                "--set", f"frames={frames}", "--set", f"solver.tolerance={tolerance}",
                "--set", f"solver.hessian_reuse={reuse}"]
    with tempfile.TemporaryDirectory() as out:
        run = subprocess.run([liedyn, "simulate", SCENE, "--out", out, "--quiet", *settings],
                             capture_output=True, text=True)
        if run.returncode != 0:
            # fox_goodwin beyond its stable step: the scene is refused, naming the bound.
            if "time_step: is too large" in run.stderr:
                return h, None, run.stderr.strip().splitlines()[-1], None
            raise subprocess.CalledProcessError(run.returncode, run.args, run.stdout, run.stderr)
        series = []
        with open(os.path.join(out, "trajectory.csv"), newline="") as f:
            for r in csv.DictReader(f):
                if r["object"] == "beam" and r["kind"] == "node" and r["index"] == str(N_ELEM):
                    series.append((float(r["time"]), float(r["x"]), float(r["y"]), float(r["z"])))
        with open(os.path.join(out, "frames.csv"), newline="") as f:
            iterations = sum(int(r["newton_iterations"]) for r in csv.DictReader(f))
    bench = subprocess.run([liedyn, "bench", SCENE, "--repeat", "3", "--json", *settings],
                           check=True, capture_output=True, text=True)
    return h, series, json.loads(bench.stdout)["total_seconds"], iterations


def distance(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def largest_deviation(series, reference):
    """The largest tip distance from the reference over the run, at the run's frame times (the
    reference, a finer run, interpolated linearly between its frames)."""
    worst, j = 0.0, 0
    for t, *p in series:
        while j + 2 < len(reference) and reference[j + 1][0] < t:
            j += 1
        (t0, *p0), (t1, *p1) = reference[j], reference[j + 1]
        w = 0.0 if t1 == t0 else min(1.0, max(0.0, (t - t0) / (t1 - t0)))
        worst = max(worst, distance(p, [u + w * (v - u) for u, v in zip(p0, p1)]))
    return worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--pyelastica", required=True, help="a checkout of PyElastica's source")
    parser.add_argument("--liedyn", default=os.path.join(ROOT, "build", "liedyn"))
    parser.add_argument("--steps", default="8e-3,4e-3,2.4e-3,2e-3,1e-3,5e-4",
                        help="liedyn's time steps (and the finest / 2 as its reference)")
    parser.add_argument("--tolerances", default="1e-9,1e-5",
                        help="liedyn's Newton tolerances (‖δ‖∞, m and rad); the reference runs at 1e-10")
    parser.add_argument("--integrators", default="backward_euler,trapezoidal,fox_goodwin,bdf2",
                        help="liedyn's integrators")
    parser.add_argument("--hessian-reuse", default="1,10",
                        help="liedyn's solver.hessian_reuse values (steps one factorisation may serve)")
    args = parser.parse_args()
    sys.path.insert(0, args.pyelastica)

    pyelastica = [pyelastica_run(EXAMPLE_DT / k) for k in (1, 4, 16)]
    hs = sorted((float(h) for h in args.steps.split(",")), reverse=True)
    tolerances = [float(t) for t in args.tolerances.split(",")]
    reuses = [int(n) for n in args.hessian_reuse.split(",")]
    # The most accurate integrator here (fourth order in the phase of points, stable below
    # h = 2.6 ms on this beam) at the finest step / 2.
    reference_h, reference, _, _ = liedyn_run(args.liedyn, "fox_goodwin", hs[-1] / 2, 1e-10)
    print(f"liedyn reference: fox_goodwin, h = {reference_h:.4g} s, tip at {FINAL_TIME:g} s: "
          + ", ".join(f"{c:.8f}" for c in reference[-1][1:]))
    pyelastica_reference = pyelastica[-1][1]
    print(f"PyElastica reference: position Verlet, dt = {pyelastica[-1][0]:.4g} s, tip: "
          + ", ".join(f"{c:.8f}" for c in pyelastica_reference[-1][1:]))
    print(f"the two references differ by "
          f"{distance(reference[-1][1:], pyelastica_reference[-1][1:]):.3e} m\n")
    print("| code | integrator | h [s] | tolerance | hessian_reuse | Newton iterations per step | "
          "tip z at 10 s [m] | tip error at 10 s [m] | largest error over 10 s [m] | wall time [s] | "
          "µs per step |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for dt, series, seconds in pyelastica:
        steps = round(FINAL_TIME / dt)
        tip = series[-1][1:]
        print(f"| PyElastica | position Verlet | {dt:.4g} | – | – | – | {tip[2]:.8f} | "
              f"{distance(tip, pyelastica_reference[-1][1:]):.2e} (its own finest) | "
              f"{largest_deviation(series, pyelastica_reference):.2e} (its own finest) | "
              f"{seconds:.3f} | {1e6 * seconds / steps:.0f} |")
    for integrator in args.integrators.split(","):
        for tolerance, reuse, h in ((t, n, h) for t in tolerances for n in reuses for h in hs):
            h, series, seconds, iterations = liedyn_run(args.liedyn, integrator, h, tolerance, reuse)
            if series is None:
                print(f"| liedyn | {integrator} | {h:.4g} | {tolerance:g} | {reuse} | refused: {seconds} |")
                continue
            tip = series[-1][1:]
            steps = round(FINAL_TIME / h)
            print(f"| liedyn | {integrator} | {h:.4g} | {tolerance:g} | {reuse} | {iterations / steps:.2f} | "
                  f"{tip[2]:.8f} | "
                  f"{distance(tip, reference[-1][1:]):.2e} | {largest_deviation(series, reference):.2e} | "
                  f"{seconds:.3f} | {1e6 * seconds / steps:.0f} |")
            sys.stdout.flush()


if __name__ == "__main__":
    main()

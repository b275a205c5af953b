#!/usr/bin/python3
"""What calling liedyn from Python costs, side by side with the same work in C++ (Release).

    PYTHONPATH=build/python /usr/bin/python3 scripts/python_overhead.py [build/liedyn]

1. Simulator.run(1000) on the butterfly bolt against `liedyn bench` (the command line's steps,
   no outputs): their ratio.
2. Simulator.step() called 1000 times from Python against run(1000): the overhead per call.
3. DifferentiableProblem.loss_and_gradient on letter S (at γ₀ and at γ₀ + 0.01) against the
   same C++ call timed in C++: their ratio.
Medians over repeats; the ratios are what to compare across machines.
"""

import json
import pathlib
import statistics
import subprocess
import sys
import time

import numpy as np

import liedyn

ROOT = pathlib.Path(__file__).resolve().parents[1]
BOLT = ROOT / "problems/scenes/butterfly_bolt.json"
LETTER_S = ROOT / "problems/scenes/letters/letter_S.json"
REPEAT = 21


def median_seconds(f, repeat=REPEAT):
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        f()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def main(cli):
    bolt = liedyn.Scene.from_file(BOLT).with_settings({"frames": 1000})
    bench = json.loads(subprocess.run([cli, "bench", str(BOLT), "--set", "frames=1000",
                                       "--repeat", str(REPEAT), "--json"],
                                      capture_output=True, text=True, check=True).stdout)
    cli_seconds = bench["total_seconds"]

    simulators = []

    def fresh():
        simulators.append(liedyn.Simulator(bolt))
        return simulators[-1]

    def run():
        sim = fresh()
        start = time.perf_counter()
        sim.run(1000)
        return time.perf_counter() - start

    def steps():
        sim = fresh()
        step = sim.step
        start = time.perf_counter()
        for _ in range(1000):
            step()
        return time.perf_counter() - start

    run_seconds = statistics.median(run() for _ in range(REPEAT))
    step_seconds = statistics.median(steps() for _ in range(REPEAT))
    print(f"butterfly bolt, 1000 steps: liedyn bench {1e3 * cli_seconds:.3f} ms, "
          f"Simulator.run {1e3 * run_seconds:.3f} ms ({run_seconds / cli_seconds:.3f}x)")
    print(f"Simulator.step() x 1000: {1e3 * step_seconds:.3f} ms, "
          f"{1e6 * (step_seconds - run_seconds) / 1000:.3f} us per call over run()")

    problem = liedyn.DifferentiableProblem(liedyn.Scene.from_file(LETTER_S))
    for label, gamma in [("gamma0", problem.gamma0), ("gamma0 + 0.01", problem.gamma0 + 0.01)]:
        python = median_seconds(lambda: problem.loss_and_gradient(gamma))
        cpp = statistics.median(problem._cpp_seconds(gamma, REPEAT))
        print(f"letter S ({problem.size} parameters) at {label}: loss_and_gradient "
              f"{1e3 * python:.3f} ms, C++ {1e3 * cpp:.3f} ms ({python / cpp:.3f}x)")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "build/liedyn"))

"""Many rollouts at once: liedyn releases the GIL while it simulates, so Python threads run
simulations in parallel.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/thread_pool.py [rollouts]

Throws the butterfly bolt (problems/scenes/butterfly_bolt.json) with `rollouts` different spin
rates, once on one thread and once on as many threads as the machine has cores, checks that
both give the same final orientations, and prints the two wall times and their ratio. One
Simulator (here: one liedyn.simulate call) per thread.
"""

import concurrent.futures
import os
import pathlib
import sys
import time

import numpy as np

import liedyn

SCENE = pathlib.Path(__file__).resolve().parents[2] / "problems" / "scenes" / "butterfly_bolt.json"


def rollout(scene, spin):
    run = liedyn.simulate(scene.with_settings({"bodies.0.angular_velocity": [0.1, spin, 0.0]}))
    return run.quaternions[-1]


def timed(scene, spins, threads):
    start = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(max_workers=threads) as pool:
        finals = list(pool.map(lambda s: rollout(scene, s), spins))
    return time.perf_counter() - start, finals


def main(rollouts=16):
    scene = liedyn.Scene.from_file(SCENE).with_settings({"frames": 4000})
    spins = np.linspace(4.0, 6.0, rollouts)
    threads = os.cpu_count() or 1
    timed(scene, spins[:threads], threads)  # warm-up
    serial, a = timed(scene, spins, 1)
    parallel, b = timed(scene, spins, threads)
    assert all(np.array_equal(x, y) for x, y in zip(a, b)), "threads changed a result"
    print(f"{rollouts} rollouts of {scene.frames} steps: 1 thread {serial:.3f} s, "
          f"{threads} threads {parallel:.3f} s: {serial / parallel:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main(*map(int, sys.argv[1:])))

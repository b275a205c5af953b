"""Trajectory optimisation with SciPy: L-BFGS-B on liedyn's exact adjoint gradient.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/scipy_minimize.py \
        problems/scenes/optimization/die_throw.json

Minimises the scene's objective over its parameters γ (within their bounds) and prints the
normalised loss it reaches, the number `liedyn optimize` reports (loss / loss_scale).
Exits 1 if it does not reach the scene's target.
"""

import sys
import time

import scipy.optimize

import liedyn


def minimize(path):
    problem = liedyn.DifferentiableProblem(liedyn.Scene.from_file(path))
    scale = problem.loss_scale
    start = time.perf_counter()
    result = scipy.optimize.minimize(problem.loss_and_gradient, problem.gamma0, jac=True,
                                     method="L-BFGS-B", bounds=problem.bounds,
                                     options={"maxiter": 200})
    seconds = time.perf_counter() - start
    return problem, result, result.fun / scale, seconds


def main(paths):
    ok = True
    for path in paths:
        problem, result, normalized, seconds = minimize(path)
        reached = normalized <= problem.target_normalized_loss
        ok &= reached
        print(f"{path}: {problem.size} parameters, normalized loss {normalized:.3e} "
              f"(target {problem.target_normalized_loss:g}: {'reached' if reached else 'NOT reached'}) "
              f"after {result.nfev} evaluations in {seconds:.2f} s; scipy: {result.message}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

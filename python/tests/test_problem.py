"""liedyn.DifferentiableProblem: the adjoint gradient from Python against central differences."""

import pickle

from conftest import read_csv

import numpy as np
import pytest

import liedyn


def central_differences(problem, gamma, indices, step=1e-6):
    out = []
    for i in indices:
        h = step * max(1.0, abs(gamma[i]))
        plus, minus = gamma.copy(), gamma.copy()
        plus[i] += h
        minus[i] -= h
        out.append((problem.loss(plus) - problem.loss(minus)) / (2 * h))
    return np.array(out)


@pytest.fixture
def die(scenes):
    scene = liedyn.Scene.from_file(scenes / "optimization" / "die_throw.json")
    return liedyn.DifferentiableProblem(scene.with_settings({"solver.tolerance": 1e-13}))


def test_problem_describes_its_parameters(die, cli, scenes, tmp_path):
    assert die.size == 6 and die.gamma0.shape == (6,) and die.gamma0.dtype == np.float64
    assert die.names[0] == "bodies[0].angular_velocity[0]"
    assert die.bounds == [(None, None)] * 6
    assert die.loss_scale == pytest.approx(die.loss(die.gamma0))


@pytest.mark.parametrize("integrator", ["backward_euler", "trapezoidal", "fox_goodwin", "bdf2"])
def test_gradient_matches_central_differences(scenes, integrator):
    scene = liedyn.Scene.from_file(scenes / "optimization" / "die_throw.json").with_settings(
        {"solver.tolerance": 1e-13, "integrator": integrator})
    problem = liedyn.DifferentiableProblem(scene)
    gamma = problem.gamma0 + 0.1
    loss, gradient = problem.loss_and_gradient(gamma)
    assert loss == problem.loss(gamma)
    assert gradient.shape == (6,) and gradient.dtype == np.float64
    differences = central_differences(problem, gamma, range(6))
    scale = np.abs(differences).max()
    assert scale > 1.0
    np.testing.assert_allclose(gradient, differences, rtol=0, atol=1e-6 * scale)


def test_rod_gradient_matches_central_differences(scenes):
    scene = liedyn.Scene.from_file(scenes / "optimization" / "rest_shape_tip_curve.json")
    problem = liedyn.DifferentiableProblem(scene.with_settings({"solver.tolerance": 1e-15}))
    gamma = problem.gamma0
    loss, gradient = problem.loss_and_gradient(gamma)
    indices = np.argsort(-np.abs(gradient))[:5]  # the entries that carry the gradient
    differences = central_differences(problem, gamma, indices, step=1e-5)
    np.testing.assert_allclose(gradient[indices], differences, rtol=1e-5)


def test_wrong_gamma_size_is_a_value_error(die):
    with pytest.raises(ValueError, match="gamma has 3 entries"):
        die.loss(np.zeros(3))


def test_a_scene_without_an_optimization_block_is_refused(scenes):
    with pytest.raises(liedyn.SceneError) as error:
        liedyn.DifferentiableProblem(liedyn.Scene.from_file(scenes / "pendulum.json"))
    assert error.value.field == "optimization"


def test_a_forward_step_that_does_not_converge_raises(scenes):
    scene = liedyn.Scene.from_file(scenes / "optimization" / "die_throw.json").with_settings(
        {"solver.max_iterations": 1, "solver.tolerance": 1e-300})
    problem = liedyn.DifferentiableProblem(scene)
    with pytest.raises(liedyn.SimulationFailed) as error:
        problem.loss_and_gradient(problem.gamma0)
    assert error.value.frame == 1


def test_trajectory_is_the_forward_run(die):
    t = die.trajectory(die.gamma0)
    run = liedyn.simulate(die.scene)
    np.testing.assert_array_equal(t.positions, run.positions)
    np.testing.assert_array_equal(t.quaternions, run.quaternions)


def test_problem_pickles(die):
    copy = pickle.loads(pickle.dumps(die))
    assert copy.loss(die.gamma0) == die.loss(die.gamma0)


def test_loss_is_the_command_lines(die, cli, scenes, tmp_path):
    # gradcheck prints "loss L; ..." at γ₀ (the raw objective).
    result = cli("gradcheck", scenes / "optimization" / "die_throw.json", "--set",
                 "solver.tolerance=1e-13", "--sample", "1")
    line = next(l for l in result.stdout.splitlines() if l.startswith("loss "))
    assert float(line.split()[1].rstrip(";")) == pytest.approx(die.loss(die.gamma0), rel=1e-5)


def test_minimize_is_the_command_lines_optimisation(scenes, cli, tmp_path):
    path = scenes / "optimization" / "die_throw.json"
    result = liedyn.optimize(liedyn.Scene.from_file(path))
    assert result.status == "target_reached" and result.reached_target
    assert result.optimizer == "nlopt-lbfgs"
    assert result.loss.shape == (result.evaluations,) and result.seconds.dtype == np.float64
    assert result.best_loss == result.loss.min()
    np.testing.assert_array_equal(result.normalized_loss, result.loss / result.loss_scale)
    cli_run = cli("optimize", path, "--out", tmp_path / "die")
    assert cli_run.returncode == 0, cli_run.stderr
    rows = read_csv(tmp_path / "die" / "parameters.csv")
    np.testing.assert_array_equal(result.best_gamma, [float(r["value"]) for r in rows])
    history = read_csv(tmp_path / "die" / "history.csv")
    np.testing.assert_array_equal(result.loss, [float(r["loss"]) for r in history])


def test_minimize_options_are_checked(die):
    with pytest.raises(liedyn.SceneError) as error:
        die.minimize(optimizer="adam")
    assert error.value.field == "optimizer"
    with pytest.raises(liedyn.ModelError):
        die.minimize(max_iterations=0)
    result = die.minimize(optimizer="ipopt-lbfgs", max_iterations=2, start=die.gamma0 + 0.1)
    assert result.optimizer == "ipopt-lbfgs" and result.iterations <= 2


def test_problems_travel_to_other_processes(die):
    import concurrent.futures
    gammas = [die.gamma0 + 0.01 * i for i in range(3)]
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
        losses = list(pool.map(die.loss, gammas))
    assert losses == [die.loss(g) for g in gammas]

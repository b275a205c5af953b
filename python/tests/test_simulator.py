"""liedyn.Simulator and liedyn.simulate: shapes, copies, errors, and the command line's results."""

import pickle
import threading
import warnings

import numpy as np
import pytest

from conftest import read_csv
import liedyn


@pytest.fixture
def bolt(scenes):
    return liedyn.Scene.from_file(scenes / "butterfly_bolt.json").with_settings({"frames": 40})


@pytest.fixture
def rod_scene(scenes):
    return liedyn.Scene.from_file(scenes / "rod_pendulum.json").with_settings({"frames": 5})


def test_state_arrays_have_the_documented_shapes_and_dtypes(rod_scene):
    sim = liedyn.Simulator(rod_scene)
    report = sim.step()
    assert report.converged and report.state_updated and report.status == "converged"
    assert report.iterations >= 1 and report.gradient_norm >= 0.0
    points = sim.positions()
    rotations = sim.rotations()
    n, m = points.shape[0], rotations.shape[0]
    for array, shape in [(points, (n, 3)), (rotations, (m, 3, 3)), (sim.quaternions(), (m, 4)),
                         (sim.velocities(), (n, 3)), (sim.angular_velocities(), (m, 3)),
                         (sim.angular_momentum(), (3,))]:
        assert array.shape == shape and array.dtype == np.float64
        assert array.flags.c_contiguous and array.flags.owndata is False  # held by a capsule
        assert np.all(np.isfinite(array))
    np.testing.assert_allclose(np.einsum("mij,mkj->mik", rotations, rotations),
                               np.broadcast_to(np.eye(3), (m, 3, 3)), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(sim.quaternions(), axis=1), 1.0, atol=1e-12)
    rod = rod_scene.rods[0]
    assert sim.rod_points(rod) == sim.rod_points(0)
    assert len(sim.rod_rotations(rod)) == len(sim.rod_points(rod)) - 1
    with pytest.raises(KeyError):
        sim.rod_points("no such rod")
    with pytest.raises(IndexError):
        sim.rod_points(5)
    assert sim.frame == 1 and sim.time == pytest.approx(rod_scene.time_step)


def test_arrays_are_copies_that_outlive_the_simulator(bolt):
    sim = liedyn.Simulator(bolt)
    x = sim.positions()
    q = sim.quaternions()
    x[:] = 42.0
    assert not np.any(sim.positions() == 42.0)
    sim.step()
    assert not np.array_equal(sim.quaternions(), q)  # the old array kept the old state
    del sim
    assert np.all(np.isfinite(q))


def test_run_steps_to_the_scene_end_and_a_callback_can_stop_it(bolt):
    sim = liedyn.Simulator(bolt)
    reports = sim.run()
    assert len(reports) == 40 and sim.frame == 40
    assert all(isinstance(r, liedyn.StepReport) for r in reports)
    sim = liedyn.Simulator(bolt)
    seen = []
    reports = sim.run(10, callback=lambda s, r: seen.append(s.frame) or s.frame < 3)
    assert seen == [1, 2, 3] and len(reports) == 3 and sim.frame == 3


def test_a_failed_step_raises_and_leaves_the_state(scenes):
    scene = liedyn.Scene.from_file(scenes / "pendulum.json").with_settings(
        {"springs.0.stiffness": 1e300, "frames": 20})
    sim = liedyn.Simulator(scene)
    before = sim.positions()
    with pytest.raises(liedyn.SimulationFailed) as error:
        sim.run()
    assert error.value.frame == sim.frame + 1
    assert "non_finite" in str(error.value)
    if sim.frame == 0:
        np.testing.assert_array_equal(sim.positions(), before)
    with pytest.raises(liedyn.SimulationFailed) as failed:
        liedyn.simulate(scene)
    assert failed.value.trajectory.frames == failed.value.frame - 1


def test_simulate_matches_the_command_line_to_the_last_digit(scenes, cli, tmp_path):
    for name, frames in [("butterfly_bolt.json", 60), ("rod_pendulum.json", 30)]:
        scene = liedyn.Scene.from_file(scenes / name).with_settings({"frames": frames})
        run = liedyn.simulate(scene, out=tmp_path / "py")
        result = cli("simulate", scenes / name, "--set", f"frames={frames}", "--out",
                     tmp_path / "cli", "--quiet")
        assert result.returncode == 0, result.stderr
        run.to_csv(tmp_path / "to_csv")
        for file in ["trajectory.csv", "frames.csv"]:
            assert (tmp_path / "py" / file).read_text() == (tmp_path / "cli" / file).read_text()
            assert (tmp_path / "to_csv" / file).read_text() == (tmp_path / "cli" / file).read_text()
        rows = read_csv(tmp_path / "cli" / "trajectory.csv")
        # Parsed back (17 significant digits: exact) against the arrays.
        sim = liedyn.Simulator(scene)
        n_rows = len(rows) // (frames + 1)
        for k in [0, frames // 2, frames]:
            frame_rows = rows[k * n_rows:(k + 1) * n_rows]
            bodies = [r for r in frame_rows if r["kind"] == "body"]
            nodes = [r for r in frame_rows if r["kind"] == "node"]
            expected = np.array([[float(r[c]) for c in "xyz"] for r in bodies + nodes])
            np.testing.assert_array_equal(run.positions[k], expected)
            quats = [r for r in frame_rows if r["kind"] in ("body", "edge")]
            expected_q = np.array([[float(r[c]) for c in ("qw", "qx", "qy", "qz")] for r in quats])
            np.testing.assert_array_equal(run.quaternions[k], expected_q)
        frames_csv = read_csv(tmp_path / "cli" / "frames.csv")
        np.testing.assert_array_equal(run.kinetic_energy,
                                      [float(r["kinetic_energy"]) for r in frames_csv])
        np.testing.assert_array_equal(run.iterations,
                                      [int(r["newton_iterations"]) for r in frames_csv])
        # Simulator.run takes the same steps.
        sim.run()
        np.testing.assert_array_equal(sim.positions(), run.positions[-1])
        np.testing.assert_array_equal(sim.quaternions(), run.quaternions[-1])


def test_every_writes_the_command_lines_files_and_the_viewer_reads_them(scenes, cli, tmp_path):
    scene = liedyn.Scene.from_file(scenes / "rod_pendulum.json").with_settings({"frames": 23})
    run = liedyn.simulate(scene, out=tmp_path / "py", every=5)
    run.to_csv(tmp_path / "to_csv", every=5)
    result = cli("simulate", scenes / "rod_pendulum.json", "--set", "frames=23", "--every", "5",
                 "--out", tmp_path / "cli", "--quiet")
    assert result.returncode == 0, result.stderr
    for file in ["trajectory.csv", "frames.csv", "shapes.json"]:
        assert (tmp_path / "py" / file).read_text() == (tmp_path / "cli" / file).read_text()
        assert (tmp_path / "to_csv" / file).read_text() == (tmp_path / "cli" / file).read_text()
    # Frames 0, 5, …, 20 and the last; the arrays keep every frame.
    written = sorted({int(r["frame"]) for r in read_csv(tmp_path / "py" / "trajectory.csv")})
    assert written == [0, 5, 10, 15, 20, 23]
    assert run.positions.shape[0] == 24
    view = cli("view", tmp_path / "py")
    assert view.returncode == 0, view.stderr
    assert "6 frames" in view.stdout
    for bad in [0, -3]:
        with pytest.raises(ValueError, match="every must be >= 1"):
            liedyn.simulate(scene, out=tmp_path / "bad", every=bad)
        with pytest.raises(ValueError, match="every must be >= 1"):
            run.to_csv(tmp_path / "bad", every=bad)
    assert not (tmp_path / "bad").exists()


def test_to_csv_writes_every_column_of_a_contact_run_and_refuses_a_problem_run(scenes, cli, tmp_path):
    # Rods that touch each other: frames.csv's min_rod_separation column is filled.
    name = "contact/rod_coil.json"
    scene = liedyn.Scene.from_file(scenes / name).with_settings({"frames": 20})
    liedyn.simulate(scene).to_csv(tmp_path / "py")
    result = cli("simulate", scenes / name, "--set", "frames=20", "--out", tmp_path / "cli", "--quiet")
    assert result.returncode == 0, result.stderr
    frames_csv = read_csv(tmp_path / "cli" / "frames.csv")
    assert frames_csv[-1]["min_rod_separation"] != ""
    for file in ["trajectory.csv", "frames.csv", "run.json"]:
        assert (tmp_path / "py" / file).exists()
    for file in ["trajectory.csv", "frames.csv"]:
        assert (tmp_path / "py" / file).read_text() == (tmp_path / "cli" / file).read_text()
    # A second to_csv replaces the unit (no stale temporaries left beside it).
    liedyn.simulate(scene.with_settings({"frames": 5})).to_csv(tmp_path / "py")
    assert len(read_csv(tmp_path / "py" / "frames.csv")) == 6
    assert not [p for p in (tmp_path / "py").iterdir() if p.name.startswith(".")]

    problem = liedyn.DifferentiableProblem(
        liedyn.Scene.from_file(scenes / "optimization" / "die_throw.json"))
    with pytest.raises(ValueError, match="DifferentiableProblem"):
        problem.trajectory(problem.gamma0).to_csv(tmp_path / "problem")
    assert not (tmp_path / "problem").exists()


def test_trajectory_columns(bolt):
    run = liedyn.simulate(bolt, frames=10)
    assert run.frames == 10
    assert run.positions.shape == (11, 1, 3) and run.quaternions.shape == (11, 1, 4)
    for column in [run.time, run.kinetic_energy, run.potential_energy, run.max_penetration,
                   run.gradient_norm, run.step_norm]:
        assert column.shape == (11,) and column.dtype == np.float64
    assert run.iterations.dtype == np.int32 and run.converged.dtype == np.bool_
    assert run.status[0] == "initial" and run.status[1] == "converged"
    np.testing.assert_allclose(run.time, 0.01 * np.arange(11))


def test_unconverged_steps_warn(bolt):
    scene = bolt.with_settings({"solver.max_iterations": 1, "solver.tolerance": 1e-300})
    with pytest.warns(RuntimeWarning, match="did not meet the solver's tolerance"):
        run = liedyn.simulate(scene, frames=3)
    assert run.unconverged_steps == 3
    assert not run.converged[1:].any()


def test_simulator_pickles_by_replaying_its_steps(rod_scene):
    sim = liedyn.Simulator(rod_scene)
    sim.run(3)
    copy = pickle.loads(pickle.dumps(sim))
    assert copy.frame == 3
    np.testing.assert_array_equal(copy.positions(), sim.positions())
    np.testing.assert_array_equal(copy.rotations(), sim.rotations())
    copy.step()
    sim.step()
    np.testing.assert_array_equal(copy.positions(), sim.positions())


def test_threads_give_the_serial_results(bolt):
    serial = [liedyn.simulate(bolt).positions for _ in range(2)]
    results = [None, None]

    def work(i):
        results[i] = liedyn.simulate(bolt).positions

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        np.testing.assert_array_equal(r, serial[0])


def test_set_state_restarts_the_run_from_a_state(rod_scene):
    fresh = liedyn.Simulator(rod_scene)
    fresh.step()
    x, R, v, w = fresh.positions(), fresh.rotations(), fresh.velocities(), fresh.angular_velocities()
    fresh.run(3)
    reference = fresh.positions()
    sim = liedyn.Simulator(rod_scene)
    sim.run(4)
    sim.set_state(x, R, v, w)
    assert sim.frame == 4
    np.testing.assert_array_equal(sim.positions(), x)
    np.testing.assert_allclose(sim.velocities(), v, rtol=1e-12, atol=1e-15)
    sim.run(3)
    # Backward Euler reads only (q, Δq): the same steps as the run it was taken from.
    np.testing.assert_allclose(sim.positions(), reference, rtol=0, atol=1e-12)
    at_rest = liedyn.Simulator(rod_scene)
    at_rest.set_state(x, R)
    np.testing.assert_array_equal(at_rest.velocities(), np.zeros_like(x))


def test_set_state_refuses_what_is_not_a_state(rod_scene):
    sim = liedyn.Simulator(rod_scene)
    x, R = sim.positions(), sim.rotations()
    with pytest.raises(ValueError, match="positions: expected an array of shape"):
        sim.set_state(x[1:], R)
    bad = R.copy()
    bad[0] *= 2.0
    with pytest.raises(ValueError, match="rotations: 0 is not a rotation matrix"):
        sim.set_state(x, bad)
    with pytest.raises(ValueError, match="not finite"):
        sim.set_state(x * np.nan, R)
    with pytest.raises(ValueError, match="turns by π or more per step"):
        sim.set_state(x, R, angular_velocities=np.full((len(R), 3), 1e6))
    np.testing.assert_array_equal(sim.positions(), x)


def test_a_restarted_simulator_pickles(bolt):
    sim = liedyn.Simulator(bolt.with_settings({"integrator": "bdf2"}))
    sim.run(3)
    sim.set_state(sim.positions() + 0.1, sim.rotations(), angular_velocities=np.array([[0.0, 5.0, 0.1]]))
    sim.run(2)
    copy = pickle.loads(pickle.dumps(sim))
    assert copy.frame == 5
    np.testing.assert_array_equal(copy.quaternions(), sim.quaternions())
    copy.step()
    sim.step()
    np.testing.assert_array_equal(copy.quaternions(), sim.quaternions())


def test_steps_on_a_reused_factorisation_are_reported(scenes, tmp_path):
    # solver.hessian_reuse = 4 on the beam, whose solves end on chord steps: a factorisation
    # at steps 1, 5, 9, the others on it; the error is measured where a new one is made.
    scene = liedyn.Scene.from_file(scenes / "timoshenko_beam.json").with_settings(
        {"frames": 12, "integrator": "backward_euler", "solver.tolerance": 1e-5, "solver.hessian_reuse": 4})
    sim = liedyn.Simulator(scene)
    reports = [sim.step() for _ in range(12)]
    assert [r.factorizations for r in reports] == [1, 0, 0, 0] * 3
    assert [r.reused_factorizations for r in reports] == [0, 1, 1, 1] * 3
    assert reports[0].reuse_error == 0.0 and 0.0 < reports[4].reuse_error < 0.05
    # frames.csv says the same, frame 0 (the initial state) first.
    run = liedyn.simulate(scene, out=tmp_path / "run")
    np.testing.assert_array_equal(run.factorizations[1:], [r.factorizations for r in reports])
    np.testing.assert_array_equal(run.assemblies[1:], [r.assemblies for r in reports])
    np.testing.assert_array_equal(run.reused_factorizations[1:], [r.reused_factorizations for r in reports])
    np.testing.assert_array_equal(run.reuse_error[1:], [r.reuse_error for r in reports])
    assert run.factorizations[0] == 0 and run.reuse_error[0] == 0.0
    rows = read_csv(tmp_path / "run" / "frames.csv")[1:]
    assert [int(r["factorizations"]) for r in rows] == [r.factorizations for r in reports]
    assert [int(r["assemblies"]) for r in rows] == [r.assemblies for r in reports]
    assert [int(r["reused_factorizations"]) for r in rows] == [1 - r.factorizations for r in reports]
    assert [float(r["reuse_error"]) for r in rows] == pytest.approx([r.reuse_error for r in reports], rel=1e-5)

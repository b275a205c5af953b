"""liedyn.compare and liedyn.sweep: the command line's runs, as record arrays."""

import csv
import io

import numpy as np
import pytest

from conftest import read_csv
import liedyn


def scene_file(scene, tmp_path):
    """The scene's JSON as a file, for the command line to run the same scene."""
    path = tmp_path / "scene.json"
    path.write_text(scene.to_json())
    return path


def test_compare_runs_the_parameterisations_as_the_command_line(scenes, cli, tmp_path):
    scene = liedyn.Scene.from_file(scenes / "free_body.json").with_settings({"frames": 50})
    rows = liedyn.compare(scene, repeats=1)
    assert list(rows.backend) == ["newton"] * 3
    assert list(rows.rotation) == ["lie", "rotvec", "quat"]
    assert rows.reference.tolist() == [True, False, False]
    assert rows.frames.dtype.kind == "i" and rows.step_us.dtype == np.float64
    assert rows.max_rotation_deviation[0] == 0.0 and not rows.failed.any()
    result = cli("compare", scene_file(scene, tmp_path), "--repeat", "1", "--csv")
    assert result.returncode == 0, result.stderr
    csv_rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert [r["rotation"] for r in csv_rows] == list(rows.rotation)
    # The same runs: equal to the CSV's 9 significant digits.
    np.testing.assert_allclose(rows.max_rotation_deviation,
                               [float(r["max_rotation_deviation"]) for r in csv_rows], rtol=1e-8)
    with pytest.raises(liedyn.SceneError):
        liedyn.compare(scene, backends=["newtonian"])


def test_sweep_runs_the_grid_as_the_command_line(scenes, cli, tmp_path):
    scene = liedyn.Scene.from_file(scenes / "free_body.json").with_settings({"frames": 50})
    result = liedyn.sweep(scene, {"integrator": ["backward_euler", "bdf2"], "time_step": [0.02, 0.01]})
    runs = result.runs
    assert len(runs) == 4 and result.notes
    assert list(runs.integrator) == ["backward_euler", "backward_euler", "bdf2", "bdf2"]
    assert list(runs.time_step) == ["0.02", "0.01", "0.02", "0.01"]
    # Second order: BDF2's orientation error falls ~4x per halving, backward Euler's ~2x.
    assert runs.orientation_error[3] < runs.orientation_error[2] / 3
    cli_run = cli("sweep", scene_file(scene, tmp_path), "--set", "integrator=backward_euler,bdf2",
                  "--set", "time_step=0.02,0.01", "--out", tmp_path / "s", "--quiet")
    assert cli_run.returncode == 0, cli_run.stderr
    csv_rows = read_csv(tmp_path / "s" / "sweep.csv")
    assert [r["integrator"] for r in csv_rows] == list(runs.integrator)
    np.testing.assert_allclose(runs.orientation_error,  # the CSV's 9 significant digits
                               [float(r["orientation_error"]) for r in csv_rows], rtol=1e-8)
    with pytest.raises(liedyn.SceneError):
        liedyn.sweep(scene, {"integrator": ["midpoint"]})
    # On two threads: the same numbers, the timings aside.
    threads = liedyn.sweep(scene, {"integrator": ["backward_euler", "bdf2"], "time_step": [0.02, 0.01]},
                           jobs=2).runs
    np.testing.assert_array_equal(threads.orientation_error, runs.orientation_error)
    np.testing.assert_array_equal(threads.newton_iterations, runs.newton_iterations)
    assert list(threads.parallel_runs) == [2] * 4 and list(runs.parallel_runs) == [1] * 4

"""liedyn.Scene: parsing, validation errors as the command line gives them, settings, pickling."""

import json
import pickle

import numpy as np
import pytest

import liedyn


def test_from_file_reads_the_scene(scenes):
    scene = liedyn.Scene.from_file(scenes / "butterfly_bolt.json")
    assert scene.source == str(scenes / "butterfly_bolt.json")
    assert scene.bodies == ["bolt"] and scene.rods == []
    assert scene.frames == 1000 and scene.time_step == pytest.approx(0.01)
    assert scene.integrator == "backward_euler" and not scene.static_equilibrium
    assert not scene.has_optimization
    assert scene.to_json() == (scenes / "butterfly_bolt.json").read_text()


def test_from_json_and_from_dict_are_the_same_scene(scenes):
    text = (scenes / "pendulum.json").read_text()
    a = liedyn.Scene.from_json(text)
    b = liedyn.Scene.from_dict(json.loads(text))
    assert a.identity == b.identity
    assert a.to_dict() == json.loads(text)
    assert a.source == "<json>" and b.source == "<dict>"


def test_from_dict_takes_numpy_arrays():
    d = {"time_step": 0.01, "frames": 2,
         "bodies": [{"name": "b", "mass": np.float64(2.0), "inertia": np.array([1.0, 2.0, 3.0]),
                     "linear_velocity": np.array([0.0, 0.0, 1.0])}]}
    scene = liedyn.Scene.from_dict(d)
    assert scene.to_dict()["bodies"][0]["inertia"] == [1.0, 2.0, 3.0]


def test_to_dict_is_a_copy(scenes):
    scene = liedyn.Scene.from_file(scenes / "pendulum.json")
    d = scene.to_dict()
    d["frames"] = 1
    assert scene.frames == 2500


def test_bad_input_names_the_file_the_field_and_the_reason(scenes, cli, tmp_path):
    bad = json.loads((scenes / "pendulum.json").read_text())
    bad["time_step"] = -0.01
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad))
    with pytest.raises(liedyn.SceneError) as error:
        liedyn.Scene.from_file(path)
    assert error.value.file == str(path)
    assert error.value.field == "time_step"
    assert error.value.reason
    assert isinstance(error.value, ValueError)
    # The same message as the command line's (its stderr line, exit 2).
    result = cli("simulate", path, "--out", tmp_path / "out")
    assert result.returncode == 2
    assert str(error.value) in result.stderr


def test_a_missing_file_is_a_scene_error(tmp_path):
    with pytest.raises(liedyn.SceneError) as error:
        liedyn.Scene.from_file(tmp_path / "nowhere.json")
    assert error.value.file == str(tmp_path / "nowhere.json")


def test_malformed_json_is_a_scene_error():
    with pytest.raises(liedyn.SceneError):
        liedyn.Scene.from_json("{ not json")


def test_an_unknown_key_is_named():
    with pytest.raises(liedyn.SceneError) as error:
        liedyn.Scene.from_dict({"time_step": 0.01, "frames": 1, "bodeis": []})
    assert "bodeis" in error.value.field + error.value.reason


def test_with_settings_sets_dotted_paths_and_validates(scenes):
    scene = liedyn.Scene.from_file(scenes / "butterfly_bolt.json")
    changed = scene.with_settings({"integrator": "bdf2", "solver.tolerance": 1e-12, "frames": 7})
    assert changed.integrator == "bdf2" and changed.frames == 7
    assert changed.to_dict()["solver"]["tolerance"] == 1e-12
    assert scene.frames == 1000  # the original is unchanged
    assert "integrator=" in changed.source
    with pytest.raises(liedyn.SceneError) as error:
        scene.with_settings({"integrator": "midpoint"})
    assert error.value.field == "integrator"
    with pytest.raises(liedyn.SceneError):
        scene.with_settings({"bodies.5.mass": 1.0})  # a path that leads nowhere


def test_a_step_beyond_fox_goodwins_stable_step_is_named(scenes):
    beam = liedyn.Scene.from_file(scenes / "timoshenko_beam.json")
    assert beam.with_settings({"integrator": "fox_goodwin", "time_step": 0.0025}).integrator == "fox_goodwin"
    with pytest.raises(liedyn.SceneError) as error:
        beam.with_settings({"integrator": "fox_goodwin", "time_step": 0.0027})
    assert error.value.field == "time_step"
    assert "fox_goodwin" in error.value.reason and "0.0026" in error.value.reason


def test_scene_pickles_through_its_json(scenes):
    scene = liedyn.Scene.from_file(scenes / "optimization" / "die_throw.json")
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.identity == scene.identity
    assert copy.source == scene.source
    assert copy.has_optimization


def test_relative_mesh_paths_follow_the_scene_file_through_settings_and_pickles(scenes):
    scene = liedyn.Scene.from_file(scenes / "contact" / "mesh_slab.json")
    # A setting whose value has a '/' labels the scene; the mesh is still read beside the file.
    moved = scene.with_settings({"colliders.0.file": "meshes/slab.obj", "frames": 2})
    again = pickle.loads(pickle.dumps(moved)).with_settings({"frames": 3})
    assert again.frames == 3
    with pytest.raises(liedyn.SceneError, match="meshes/none.obj"):
        moved.with_settings({"colliders.0.file": "meshes/none.obj"})

"""The examples under examples/python run and do what they say."""

import os
import subprocess
import sys

import pytest

from conftest import SOURCE

EXAMPLES = SOURCE / "examples" / "python"
OPTIMIZATION = SOURCE / "problems" / "scenes" / "optimization"


def run(script, *args):
    result = subprocess.run([sys.executable, str(EXAMPLES / script), *map(str, args)],
                            capture_output=True, text=True, env=os.environ.copy())
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_scipy_reaches_the_targets_on_the_die_and_the_cable_rod():
    out = run("scipy_minimize.py", OPTIMIZATION / "die_throw.json", OPTIMIZATION / "cable_tip_curve.json")
    assert out.count("reached") == 2 and "NOT reached" not in out


def test_torch_adam_on_a_rod():
    pytest.importorskip("torch", reason="Debian's python3-torch (scripts/install-deps.sh)")
    out = run("torch_adam.py", OPTIMIZATION / "rod_throw_friction.json")
    assert "(target 0.001: reached)" in out


def test_thread_pool_gives_the_serial_results():
    out = run("thread_pool.py", "4")  # it asserts the results equal; the timing is for reading
    assert "4 rollouts" in out

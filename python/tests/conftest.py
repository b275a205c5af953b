"""Shared fixtures: the repository's scenes and the command line built beside the module."""

import csv
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("LIEDYN_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
SCENES = SOURCE / "problems" / "scenes"


@pytest.fixture
def scenes():
    return SCENES


@pytest.fixture
def cli():
    """Runs the `liedyn` executable (LIEDYN_CLI, set by CTest) and returns the CompletedProcess."""
    executable = os.environ.get("LIEDYN_CLI")
    if executable is None:
        pytest.skip("LIEDYN_CLI is not set (run through ctest)")

    def run(*args):
        return subprocess.run([executable, *map(str, args)], capture_output=True, text=True)

    return run


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))

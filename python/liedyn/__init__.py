"""liedyn from Python: scenes, forward simulation and exact adjoint gradients.

    import liedyn
    scene = liedyn.Scene.from_file("problems/scenes/butterfly_bolt.json")
    run = liedyn.simulate(scene)                     # a Trajectory of NumPy arrays
    sim = liedyn.Simulator(scene); sim.step()        # or one step at a time
    prob = liedyn.DifferentiableProblem(liedyn.Scene.from_file(
        "problems/scenes/optimization/die_throw.json"))
    loss, gradient = prob.loss_and_gradient(prob.gamma0)

Arrays are copies that own their memory. Calls that simulate release the GIL: use one
Simulator or DifferentiableProblem per thread. Scenes, simulators and problems pickle.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from os import PathLike
from typing import Optional, Union

import numpy as np

from ._liedyn import (  # noqa: F401  (re-exported)
    DifferentiableProblem,
    ModelError,
    Scene,
    SceneError,
    SimulationFailed,
    Simulator,
    StepReport,
    _compare,
    _Recording,
    _simulate,
    _sweep,
)

__all__ = [
    "DifferentiableProblem",
    "ModelError",
    "Scene",
    "SceneError",
    "SimulationFailed",
    "Simulator",
    "StepReport",
    "OptimizationFailed",
    "OptimizationResult",
    "Trajectory",
    "compare",
    "optimize",
    "simulate",
    "sweep",
]


@dataclass
class Trajectory:
    """A run's frames as arrays (frame 0 is the initial state).

    positions: F×N×3 (bodies' centres of mass, then every rod's nodes), m.
    quaternions: F×M×4, w first (bodies, then every rod's edges).
    time, kinetic_energy, potential_energy, max_penetration, gradient_norm, step_norm,
    iterations, converged, status, assemblies, factorizations, reused_factorizations,
    reuse_error: one entry per frame (frame 0: the initial state, no solve), as in frames.csv.
    """

    scene: Scene
    time: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray
    kinetic_energy: np.ndarray
    potential_energy: np.ndarray
    max_penetration: np.ndarray
    gradient_norm: np.ndarray
    step_norm: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    status: list
    assemblies: np.ndarray
    factorizations: np.ndarray
    reused_factorizations: np.ndarray
    reuse_error: np.ndarray
    _recording: Optional[_Recording] = None  # what to_csv writes (simulate's runs only)

    @property
    def frames(self) -> int:
        """Steps taken (the arrays hold frames + 1 states)."""
        return len(self.time) - 1

    @property
    def unconverged_steps(self) -> int:
        """Steps whose solve stopped short of the tolerance (their state was still updated)."""
        return int(np.count_nonzero(~self.converged))

    def to_csv(self, out: Union[str, PathLike], every: int = 1) -> None:
        """Writes trajectory.csv, frames.csv and shapes.json into the folder `out` (created if
        missing), as one unit and exactly as `liedyn simulate --every` writes them (the same
        writer): trajectory.csv holds frames 0, every, 2·every, … and the last. Only
        simulate's trajectories have every column: a DifferentiableProblem's trajectory
        raises ValueError."""
        if self._recording is None:
            raise ValueError("to_csv: this trajectory records positions and rotations only (a "
                             "DifferentiableProblem's run); use liedyn.simulate for the files")
        self._recording.write_csv(self.scene, str(out), int(every))


def _trajectory(scene: Scene, arrays: dict) -> Trajectory:
    fields = {k: arrays[k] for k in Trajectory.__dataclass_fields__ if k not in ("scene", "_recording")}
    return Trajectory(scene=scene, _recording=arrays["recording"], **fields)


def simulate(scene: Scene, frames: Optional[int] = None,
             out: Union[str, PathLike, None] = None, every: int = 1) -> Trajectory:
    """Runs a scene as `liedyn simulate` does and returns its Trajectory.

    frames: how many steps (default: the scene's own `frames`).
    out: a folder to write trajectory.csv, frames.csv and shapes.json into as well, as one
        unit, exactly as the command line writes them (`liedyn view out` then draws the run).
    every: trajectory.csv holds every `every`-th frame and the last (`--every`); frames.csv and
        the returned arrays hold every frame.

    A step that cannot update the state raises SimulationFailed, whose `trajectory` holds the
    frames before it (and `out`, if given, has them too). Steps that stop short of the
    tolerance are kept and counted: a RuntimeWarning says how many.
    """
    if frames is not None:
        scene = scene.with_settings({"frames": int(frames)})
    arrays = _simulate(scene, None if out is None else str(out), int(every))
    trajectory = _trajectory(scene, arrays)
    if arrays["failure"] is not None:
        error = SimulationFailed(arrays["failure"])
        error.frame = arrays["failed_frame"]
        error.trajectory = trajectory
        raise error
    if trajectory.unconverged_steps:
        warnings.warn(f"{scene.source}: {trajectory.unconverged_steps} of {trajectory.frames} "
                      "steps did not meet the solver's tolerance (see Trajectory.status)",
                      RuntimeWarning, stacklevel=2)
    return trajectory


def _problem_trajectory(self: DifferentiableProblem, gamma) -> Trajectory:
    """The forward run at γ (positions and quaternions; the other columns are not recorded
    by the adjoint's run: NaN, and zeros for the counts)."""
    arrays = self._trajectory(np.asarray(gamma, dtype=float))
    frames = len(arrays["time"])
    nan = np.full(frames, np.nan)
    zeros = np.zeros(frames, dtype=np.int32)
    return Trajectory(scene=self.scene, time=arrays["time"], positions=arrays["positions"],
                      quaternions=arrays["quaternions"], kinetic_energy=nan,
                      potential_energy=nan.copy(), max_penetration=nan.copy(),
                      gradient_norm=nan.copy(), step_norm=nan.copy(), iterations=zeros,
                      converged=np.ones(frames, dtype=bool), status=["converged"] * frames,
                      assemblies=zeros.copy(), factorizations=zeros.copy(),
                      reused_factorizations=zeros.copy(), reuse_error=nan.copy())


DifferentiableProblem.trajectory = _problem_trajectory


@dataclass
class OptimizationResult:
    """What `liedyn optimize` reports, and its history (one entry per evaluation of the loss
    and gradient, as history.csv)."""

    best_gamma: np.ndarray
    best_loss: float
    best_normalized_loss: float  # best_loss / loss_scale
    loss_scale: float
    iterations: int
    evaluations: int
    reached_target: bool
    status: str  # target_reached, max_iterations, converged, roundoff_limited (or failed)
    message: str  # the back-end's own status and message
    optimizer: str
    loss: np.ndarray
    normalized_loss: np.ndarray
    gradient_norm: np.ndarray
    seconds: np.ndarray


class OptimizationFailed(RuntimeError):
    """The optimiser stopped on an error (`.result` holds the best point before it)."""


def _problem_minimize(self: DifferentiableProblem, optimizer: Optional[str] = None,
                      max_iterations: Optional[int] = None, start=None) -> OptimizationResult:
    """Minimises the loss as `liedyn optimize` does (its optimiser settings from the scene,
    unless `optimizer` ("nlopt-lbfgs", "ceres-lbfgs", "ipopt-lbfgs") or `max_iterations` say
    otherwise; from `start`, default γ₀), without writing files. Raises OptimizationFailed if
    the optimiser stopped on an error (status "failed")."""
    start = None if start is None else np.asarray(start, dtype=float)
    result = OptimizationResult(**self._minimize(optimizer, max_iterations, start))
    if result.status == "failed":
        error = OptimizationFailed(f"{self.scene.source}: {result.optimizer} failed: {result.message}")
        error.result = result
        raise error
    return result


DifferentiableProblem.minimize = _problem_minimize


def optimize(scene: Scene, optimizer: Optional[str] = None,
             max_iterations: Optional[int] = None) -> OptimizationResult:
    """`liedyn optimize` without files: DifferentiableProblem(scene).minimize(...)."""
    return DifferentiableProblem(scene).minimize(optimizer, max_iterations)


def _records(columns: dict) -> np.recarray:
    return np.rec.fromarrays(list(columns.values()), names=list(columns.keys()))


def compare(scene: Scene, backends=None, rotations=None, repeats: int = 3) -> np.recarray:
    """`liedyn compare` without files: the scene run under each back-end ("newton", "ceres",
    "ipopt") and rotation parameterisation ("lie", "rotvec", "quat"), one record per run with
    its iterations, µs per step, deviations from the first (reference) run, unconverged steps
    and failure (problems/compare.hpp). Defaults as on the command line: the scene's back-end,
    and all three parameterisations when no back-end is given."""
    return _records(_compare(scene, list(backends or []), list(rotations or []), int(repeats)))


@dataclass
class SweepResult:
    """liedyn.sweep's runs, one record per grid point, and what the reader should know of
    them (the command line prints these notes under its table)."""

    runs: np.recarray
    notes: list


def sweep(scene: Scene, axes: dict, reference_refinement: int = 4, gradient_sample: int = 8,
          repeats: int = 1, jobs: int = 1) -> SweepResult:
    """`liedyn sweep` without files: the scene run at every point of the grid
    {path: [values]} (e.g. {"integrator": ["backward_euler", "bdf2"], "time_step": [0.01,
    0.005]}; strings as typed on the command line, other values as JSON), errors measured
    against a reference run at the smallest h / reference_refinement or a declared closed form
    (problems/sweep.hpp). One record per run, in the command line's order; its settings as the
    command line prints them. jobs: runs at once on threads (`liedyn sweep -j`; the results
    are the serial run's but for the timings, whose `parallel_runs` column says how many runs
    shared the machine)."""
    columns, notes = _sweep(scene, dict(axes), int(reference_refinement), int(gradient_sample),
                            int(repeats), int(jobs))
    return SweepResult(runs=_records(columns), notes=list(notes))

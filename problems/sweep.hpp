#pragma once
// `liedyn sweep`: one scene run over a grid of settings, each run measured for its cost and
// its accuracy, so that a user can see what a larger time step, a looser tolerance, another
// parameterisation or back-end costs and buys on their own scene (issue 7).
//
// The grid. Each `--set PATH=v1,v2,…` is an axis: PATH is a dotted path into the scene's JSON
// (`time_step`, `solver.tolerance`, `rods.0.bending_stiffness`; numbers index arrays, missing
// object keys are created), each value is JSON (`1e-4`, `[1, 1, 2]`) or else a bare string
// (`lie`). `--rotations` and `--backends` are the axes `solver.rotation` and `solver.backend`.
// The runs are every combination, the first axis outermost. Every grid point is parsed
// (parse_scene) before anything runs: a bad value is a SceneError naming the point.
// When `time_step` is an axis of a dynamic scene and `frames` is not, each run's frames are
// round(T/h) for the scene's duration T = frames · h, so that every run covers the same time.
//
// Cost, per run: wall time of the time steps (not of the bookkeeping around them; the median
// of `repeats` runs); iterations (Newton updates, or Ceres/Ipopt iterations) and linear solves
// summed over frames — Newton's Cholesky factorisations, one per solve plus retries with a
// shift; for Ceres and Ipopt only those of our final convergence check (their own solves are
// not counted) — and unconverged steps.
//
// Accuracy, per run, against a reference:
//   * the scene's analytic solution when it declares one ("analytic", problems/analytic.hpp),
//     over the points and rotations the solution describes, at every frame; or else
//   * a reference run that the sweep makes itself at the finest settings of the grid: time
//     step = the smallest on the grid / `reference_refinement` (only if `time_step` is an axis),
//     tolerance = the smallest on the grid / 100 (only if `solver.tolerance` is an axis), the
//     largest `solver.max_iterations`, Newton with `lie` whatever the back-end and rotation
//     axes say, and the trapezoidal integrator when `integrator` is an axis (second order: a
//     better reference for either). Static scenes: the most load steps (`frames`) on the grid. Every other axis
//     changes the physics (stiffness, mass, frames of a dynamic scene, …): each combination of
//     their values gets its own reference. The reference's own error is not known: the errors
//     of the finest runs are measured against something only `reference_refinement` times
//     finer (first order in h: they read ~1/refinement low).
//   Runs are compared with the reference at the run's frame times t = k h (static: load
//   fraction k/frames); the reference's state at t is interpolated between its two nearest
//   frames (linearly for positions, along the geodesic for rotations) when t is not one of
//   its own frame times.
// Metrics (NaN when not defined):
//   position_error     max over frames and points of ‖x − x_ref‖∞, m
//   orientation_error  max over frames and rotations of the geodesic angle, rad
//   energy_drift       max_k |E_k − E_0|, J (kinetic + potential; dynamic scenes; backward
//                      Euler dissipates, so this is the run's own loss, not an error)
//   momentum_drift     max_k ‖L_k − L_0‖, kg m²/s (angular momentum about the origin)
//   gradient_error     optimisation scenes: the run's adjoint gradient at the initial
//                      parameters against central differences of the reference run's loss,
//                      over `gradient_sample` random parameters: max_j |a_j − d_j| /
//                      max(|a_j|, |d_j|, 1e-3 max_i |d_i|) (solvers/gradient_check.hpp);
//                      NaN when the run's parameter count differs from the reference's.
// A run whose step fails is kept, marked failed, with the errors of the frames it completed
// (NaN when it completed none).
//
// Many runs at once (issue 23's `-j`, `--shard`, MPI, `--resume`). Grid points are numbered
// in grid order (SweepRun::index). `jobs` threads run them (problems/parallel.hpp): first
// the references, then the runs; the outputs are ordered by index, so they are those of a
// serial run except for the timing columns (wall_seconds, gradient_seconds, and the pareto
// marks that follow from them) and `parallel_runs`, the number of runs that shared the
// machine — keep -j 1 for timings meant for comparison. A share {index, count} runs only
// the grid points i with i mod count = index, and the references those need (a reference
// needed by two shares is computed by each); merge_sweeps joins the shares' results into the
// result of the whole grid. A resumed sweep keeps the runs and references its checkpoint
// holds and runs the rest (a reference is recomputed when a run left still needs it).
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "output_folder.hpp"
#include "scene.hpp"

namespace liedyn {

struct SweepAxis {
  std::string path;                 // dotted path, e.g. "solver.tolerance"
  std::vector<std::string> values;  // as given on the command line
};

// Parses "PATH=v1,v2,…"; commas inside [] or {} do not split. Throws std::invalid_argument
// naming the text when the path or the values are missing.
SweepAxis parse_sweep_axis(const std::string& text);

struct SweepRun;
struct SweepResult;

// Which grid points a process runs: i mod count = index (a Slurm array task, an MPI rank).
struct SweepShare {
  int index = 0;
  int count = 1;
};

struct SweepOptions {
  std::vector<SweepAxis> axes;
  int reference_refinement = 4;      // reference h = smallest h on the grid / this, ≥ 1
  int gradient_sample = 8;           // parameters checked for gradient_error (0: all)
  int repeats = 1;                   // timed runs per grid point; wall_seconds is their median
  // Called once every grid point has parsed, before the first run (the driver locks its
  // output folder there: bad input creates nothing, a busy folder fails before the runs).
  std::function<void()> before_runs;
  std::ostream* progress = nullptr;  // progress reports, if set:
  bool progress_bar = false;         //   a bar redrawn in place (a terminal), else a line per run
  int jobs = 1;                      // runs at once (threads), ≥ 1
  SweepShare share;                  // the grid points to run (all by default)
  // Another process's runs on the same machine (MPI ranks), for SweepRun::parallel_runs.
  int other_processes = 0;
  // A checkpoint of this sweep (same identity, else SceneError naming `resume_source` and
  // the field): its runs of this share and the references they need are kept, not rerun.
  const SweepResult* resume = nullptr;
  std::string resume_source;
  // Called after every finished reference and run with the result so far (runs in index
  // order), one call at a time: checkpoints.
  std::function<void(const SweepResult&)> on_finished;
};

struct SweepRun {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  int index = 0;                      // grid point (references: their group, in grid order)
  std::vector<std::string> settings;  // one value per axis
  int frames = 0;                     // requested
  int frames_completed = 0;
  double wall_seconds = 0.0;
  long newton_iterations = 0;
  long factorizations = 0;
  int unconverged_steps = 0;
  double position_error = kNaN, orientation_error = kNaN;
  double energy_drift = kNaN, momentum_drift = kNaN;
  double gradient_error = kNaN;
  double gradient_seconds = kNaN;  // the adjoint evaluation (forward + backward pass)
  std::string reference;           // "analytic free_body", or the reference run's settings
  int parallel_runs = 1;           // runs sharing the machine while it ran (threads × processes)
  bool failed = false;
  std::string failure;
};

struct SweepResult {
  std::string scene;
  // What makes two results parts of one sweep: the scene's content, the axes and the options
  // that change the numbers (refinement, gradient sample, repeats), as compact JSON ("null":
  // not a run_sweep result).
  std::string identity = "null";
  int grid_size = 0;  // grid points of the whole sweep
  SweepShare share;   // the points this result holds (merged: {0, 1})
  std::vector<std::string> axis_names;
  std::vector<SweepRun> runs;
  std::vector<SweepRun> references;  // the reference runs (settings: their overrides)
  std::vector<std::string> notes;    // what the reader should know (e.g. frames rescaled)
};

// Runs the grid. Throws SceneError for a bad axis or grid point (before anything runs);
// numerical failures are reported in the runs, never thrown.
SweepResult run_sweep(const std::string& scene_text, const std::string& source,
                      const SweepOptions& options);

// A result as JSON (sweep.json, the checkpoint; NaN as null, numbers to the last digit) and
// back: sweep_from_json throws SceneError naming `source` and the field that is wrong.
nlohmann::ordered_json sweep_to_json(const SweepResult& result);
SweepResult sweep_from_json(const nlohmann::ordered_json& value, const std::string& source);

// The shares of one sweep joined (`liedyn sweep-merge`): SceneError naming the part's source
// when the parts are not one sweep's (other identity or share count) or a share is repeated,
// or (`complete`) missing. References that several shares computed appear once. The result's
// share is {0, 1}: it can resume any share.
SweepResult merge_sweeps(const std::vector<SweepResult>& parts,
                         const std::vector<std::string>& sources, bool complete = true);

// One row per run: the axes, then the cost and accuracy fields above, `pareto` (1 if no other
// run is both cheaper and more accurate, else 0), reference, failure. "More accurate" is in
// the primary error: position_error, or orientation_error if no run has a positive position
// error (a body spinning in place), or gradient_error if neither has.
std::string sweep_csv(const SweepResult& result);
// A table for the terminal.
std::string format_sweep(const SweepResult& result);
// DIR/sweep.csv, DIR/sweep.json (sweep_to_json: for sweep-merge), and DIR/<metric>_vs_time.png for every metric with a positive finite value
// (the plots are log-log; a body spinning in place has no position error to show).
// Added to `out`'s current unit and committed: they replace the folder's earlier sweep
// outputs together.
void write_sweep(const SweepResult& result, OutputFolder& out);

}  // namespace liedyn

#pragma once
// `liedyn simulate`: runs a scene and writes trajectory.csv and frames.csv into an output
// folder as one unit (output_folder.hpp): they are replaced together or not at all.

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "../solvers/simulator.hpp"
#include "output_folder.hpp"
#include "scene.hpp"

namespace liedyn {

struct SimulationSummary {
  int frames_requested = 0;
  int frames_completed = 0;     // steps taken successfully
  int unconverged_steps = 0;    // steps that did not meet the tolerance (state updated)
  int stalled_steps = 0;        // of those, the ones that stopped with iterations left
  int regularized_steps = 0;    // steps in which the Hessian needed a shift
  int total_iterations = 0;
  int max_iterations_in_step = 0;
  double max_gradient_norm = 0.0;
  double solve_seconds = 0.0;   // wall time of the time steps alone
  double output_seconds = 0.0;  // wall time of formatting and writing the outputs
  double initial_energy = 0.0, final_energy = 0.0;  // kinetic + potential
  // Static mode with unconverged steps: the directions nothing holds at the last state
  // (Simulator::free_directions, described), the likely cause; empty otherwise.
  std::vector<std::string> free_directions;
  bool failed = false;          // a step failed (NaN, no descent): the run stopped early
  std::string failure;          // message when failed
};

// One frame of a run as trajectory.csv and frames.csv show it: the state, and what the step
// that reached it did (none at frame 0, the initial state).
struct FrameRecord {
  int frame = 0;
  double time = 0.0;
  State state;
  std::optional<StepReport> report;
  double kinetic_energy = 0.0, potential_energy = 0.0;
  Vector3 angular_momentum = Vector3::Zero();  // about the world origin
  double max_penetration = 0.0;
  double constraint_violation = 0.0;  // the step's, or the state's at frame 0
  int contact_pairs = 0;
  std::optional<double> min_rod_separation;  // only where rods can touch

  // Fills this record from the simulator's current frame (reusing its storage).
  void capture(const Simulator& sim, const StepReport* step_report);
};

// trajectory.csv, frames.csv and shapes.json (problems/shapes.hpp) of one run, added to an
// OutputFolder's current unit; then a row (or a block of rows) per frame. trajectory.csv
// holds frames 0, every, 2·every, … and the last one (finish); frames.csv every frame. The
// one writer of these files, for `liedyn simulate`, `optimize`'s final run and Python's
// Trajectory.to_csv.
class RunFiles {
 public:
  RunFiles(OutputFolder& out, const Scene& scene, int every = 1);
  void add(const FrameRecord& record);
  // The last frame's trajectory rows, if `every` skipped them.
  void finish(const FrameRecord& last);

 private:
  void add_trajectory(const FrameRecord& record);
  const Model& model_;
  int every_;
  int last_trajectory_frame_ = -1;
  std::ostream& trajectory_;
  std::ostream& frames_;
};

// Called with the record of frame 0 and of every step that updated the state: what a caller
// collects of a run besides the files (the Python module's arrays).
using FrameObserver = std::function<void(const FrameRecord&)>;

// Simulates the scene, adding its RunFiles to `out`'s current unit (the caller commits it,
// with whatever else belongs to the run; null: no files), the trajectory every
// `trajectory_every` frames. Progress goes to `progress` (if non-null) for runs longer than a
// second. The frames up to a failed step are written (and observed).
SimulationSummary simulate_into(const Scene& scene, OutputFolder* out, std::ostream* progress,
                                const FrameObserver& observer = nullptr, int trajectory_every = 1);

// simulate_into a locked OutputFolder at `out_dir` (created if missing), committed at the
// end. Throws std::runtime_error on I/O errors (the folder's previous outputs then stay).
SimulationSummary simulate_scene(const Scene& scene, const std::filesystem::path& out_dir,
                                 std::ostream* progress, int trajectory_every = 1);

// "step k (t = … s) failed: <status> after n <backend> iterations, gradient norm g (message)":
// why step k did not update the state (every command that runs a scene says it this way).
std::string step_failure_message(int k, double time_step, Backend backend,
                                 const StepReport& report);

// One-screen text summary.
std::string format_summary(const Scene& scene, const SimulationSummary& summary);

}  // namespace liedyn

#pragma once
// `liedyn simulate`: runs a scene and writes trajectory.csv and frames.csv atomically
// (each is written to a temporary file in the output directory, then renamed).

#include <filesystem>
#include <iosfwd>
#include <string>

#include "scene.hpp"

namespace liedyn {

struct SimulationSummary {
  int frames_requested = 0;
  int frames_completed = 0;     // steps taken successfully
  int unconverged_steps = 0;    // steps that ended at max_iterations
  int regularized_steps = 0;    // steps in which the Hessian needed a shift
  int total_iterations = 0;
  int max_iterations_in_step = 0;
  double max_gradient_norm = 0.0;
  double wall_seconds = 0.0;
  double initial_energy = 0.0, final_energy = 0.0;  // kinetic + potential
  bool failed = false;          // a step failed (NaN, no descent): the run stopped early
  std::string failure;          // message when failed
};

// Simulates the scene, writing outputs into out_dir (created if missing). Progress goes to
// `progress` (if non-null) for runs longer than a second. Files written up to a failed step
// are kept. Throws std::runtime_error on I/O errors.
SimulationSummary simulate_scene(const Scene& scene, const std::filesystem::path& out_dir,
                                 std::ostream* progress);

// "step k (t = … s) failed: <status> after n <backend> iterations, gradient norm g (message)":
// why step k did not update the state (every command that runs a scene says it this way).
std::string step_failure_message(int k, double time_step, Backend backend,
                                 const StepReport& report);

// One-screen text summary.
std::string format_summary(const Scene& scene, const SimulationSummary& summary);

}  // namespace liedyn

#pragma once
// `liedyn bench`: runs a scene (no output files) several times and reports the cost of its
// Newton iterations, split into assembly and linear solve, as paper Table 1 does.

#include <functional>
#include <string>
#include <vector>

#include "../solvers/simulator.hpp"
#include "scene.hpp"

namespace liedyn {

struct BenchResult {
  std::string scene;
  int dofs = 0;                        // free DOFs over all components
  int frames = 0;
  double time_step = 0.0;
  int repeats = 0;
  // Medians over the repeats:
  double total_seconds = 0.0;          // whole simulation
  double assembly_us = 0.0;            // per assembly of g and H (one per Newton iteration,
  double solve_us = 0.0;               //   plus the final convergence check of each step);
                                       //   factorisation + triangular solves per assembly
  double iterations_per_frame = 0.0;   // Newton updates
  double assemblies_per_frame = 0.0;
  double factorizations_per_frame = 0.0;  // including regularisation retries
  // solver.hessian_reuse > 1: solves ended by a chord step on a reused factorisation, and the
  // largest measured error of such a step (StepReport::reuse_error; last repeat).
  double reused_per_frame = 0.0;
  double reuse_error = 0.0;
  int max_iterations_in_frame = 0;
  int unconverged_steps = 0;           // in the last repeat
  bool failed = false;                 // a step failed; figures cover the frames before it
  std::string failure;
};

// The median of a non-empty list.
double median(std::vector<double> values);

// One timed run of a scene with the given solver options (measure_time is forced on).
// `observe`, if set, is called after every completed frame; its time is not counted.
struct TimedRun {
  double total_seconds = 0.0;  // in the time steps
  int frames = 0;  // completed
  StepReport sum;  // iterations, factorisations, assemblies and seconds summed over frames
  int max_iterations_in_frame = 0;
  int unconverged_steps = 0;
  bool failed = false;
  std::string failure;
  double assembly_us() const;  // per assembly
  double solve_us() const;     // per factorisation + solve
};
TimedRun time_scene(const Scene& scene, SolverOptions options,
                    const std::function<void(const Simulator&)>& observe = {});

// Runs the scene `repeats` times (≥ 1), with timing on.
BenchResult bench_scene(const Scene& scene, int repeats);

std::string format_bench(const BenchResult& result);
std::string bench_json(const BenchResult& result);

}  // namespace liedyn

#pragma once
// `liedyn compare`: one scene under several rotation parameterisations (Lie, rotation vectors,
// quaternions; solvers/newton.hpp), same potential, Newton solver and tolerances, side by side
// (paper §4.4, Fig. 4, Table 1).
//
// Each parameterisation is run `repeats` times timed (SolverOptions::measure_time; medians,
// the first run's trajectory), then once more for the diagnostics, with the condition number of the first Hessian of
// every sampled frame (a dense eigendecomposition, which would distort the timing).

#include <filesystem>
#include <string>
#include <vector>

#include "../solvers/newton.hpp"
#include "scene.hpp"

namespace liedyn {

struct CompareOptions {
  std::vector<RotationParameterization> rotations;
  int repeats = 3;  // timed runs per parameterisation; timings are their medians
  // The condition number is measured at frames 1, 1 + every, 1 + 2·every, …; 0 picks every
  // frame up to kDenseConditionDofs DOFs and about 20 frames beyond.
  int condition_every = 0;
  static constexpr int kDenseConditionDofs = 300;
};

// Per frame, for paper Fig. 4.
struct CompareFrame {
  int frame = 0;
  int iterations = 0;
  double first_gradient_norm = 0.0;   // ‖g‖ at the first assembly
  double second_gradient_norm = 0.0;  // after the first update (NaN if none)
  double condition = 0.0;             // of the first Hessian (NaN if not sampled)
};

struct CompareRow {
  RotationParameterization rotation = RotationParameterization::kLie;
  int frames = 0;                      // completed
  double iterations_mean = 0.0;        // Newton updates per frame
  int iterations_max = 0;
  double assembly_us = 0.0;            // per assembly (as liedyn bench)
  double solve_us = 0.0;               // per factorisation + solve
  double total_seconds = 0.0;          // whole run
  double condition_mean = 0.0;         // over the sampled frames (NaN if none)
  int condition_frames = 0;
  // Largest difference from the reference (the first parameterisation listed) over all
  // frames: positions in m, rotations as geodesic angle in rad.
  double max_position_deviation = 0.0;
  double max_rotation_deviation = 0.0;
  int unconverged_steps = 0;
  bool failed = false;
  std::string failure;
  std::vector<CompareFrame> per_frame;
};

// Runs the comparison; throws SceneError if `rotations` is empty.
std::vector<CompareRow> compare_rotations(const Scene& scene, const CompareOptions& options);

std::string format_compare(const Scene& scene, const std::vector<CompareRow>& rows);
std::string compare_csv(const std::vector<CompareRow>& rows);
std::string compare_json(const Scene& scene, const std::vector<CompareRow>& rows);
// The per-frame series, one row per (rotation, frame):
// rotation,frame,iterations,first_gradient_norm,second_gradient_norm,residual_reduction,condition
std::string compare_frames_csv(const std::vector<CompareRow>& rows);

}  // namespace liedyn

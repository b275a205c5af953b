#pragma once
// `liedyn compare`: one scene, same potential and tolerance, solved by several back-ends
// (newton, ceres, ipopt; solvers/step_solver.hpp) under several rotation parameterisations
// (lie, rotvec, quat; solvers/newton.hpp), side by side (paper §4.4, Fig. 4, Table 1).
//
// The rows are the (backend, rotation) pairs of the two lists, backends outer. The first row
// is the reference: every row's deviations are measured from its trajectory. Every back-end
// takes every parameterisation; a row whose step fails is marked failed with the step's
// message, and the other rows still run.
//
// Each row is run `repeats` times timed (SolverOptions::measure_time; medians, the first
// run's trajectory), then once more for the diagnostics: per-frame iterations and gradient
// norms and, for Newton, the condition number of the first Hessian of every sampled frame (a
// dense eigendecomposition, which would distort the timing).
//
// Newton-only figures: assembly µs and solve µs per assembly, and the condition number. Ceres
// fills StepReport::assembly_seconds / solve_seconds only approximately (its residual and
// Jacobian evaluation and linear-solver times, plus the final check), Ipopt differently again
// (its evaluations; the rest of its time as "solve"), and neither measures the condition
// number; so for them these fields are NaN ("-" in the table, null in JSON). Iterations are each back-end's own (Newton updates, Ceres or Ipopt
// iterations). The gradient norm is comparable across back-ends: StepReport::gradient_norm,
// the Lie gradient at the end of each step, which every back-end reports.

#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

#include "scene.hpp"

namespace liedyn {

struct CompareOptions {
  // Back-ends, the outer loop of the rows; empty: the scene's own.
  std::vector<Backend> backends;
  // Parameterisations, the inner loop; empty: the scene's own if `backends` is given, else
  // all three (lie, rotvec, quat), so that `liedyn compare SCENE` compares parameterisations.
  std::vector<RotationParameterization> rotations;
  int repeats = 3;  // timed runs per row; timings are their medians
  // The condition number is measured at frames 1, 1 + every, 1 + 2·every, …; 0 picks every
  // frame up to kDenseConditionDofs DOFs and about 20 frames beyond.
  int condition_every = 0;
  static constexpr int kDenseConditionDofs = 300;
  std::ostream* progress = nullptr;  // a line per row as it finishes (the driver: a terminal)
};

// Per frame, for paper Fig. 4.
struct CompareFrame {
  int frame = 0;
  int iterations = 0;
  double first_gradient_norm = 0.0;   // ‖g‖ at the first assembly
  double second_gradient_norm = 0.0;  // after the first update (NaN if none)
  double final_gradient_norm = 0.0;   // StepReport::gradient_norm: Lie gradient, end of step
  double condition = 0.0;             // of the first Hessian (NaN if not sampled or not Newton)
};

// One (backend, rotation) pair. A figure that was not measured is NaN: everything of a pair
// that did not run, and the Newton-only figures of the other back-ends (see above).
struct CompareRow {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  Backend backend = Backend::kNewton;
  RotationParameterization rotation = RotationParameterization::kLie;
  bool reference = false;         // the first row, which deviations are measured from
  int frames = 0;                 // completed
  double iterations_mean = kNaN;  // back-end iterations per frame
  int iterations_max = 0;
  double step_us = kNaN;                  // wall time per completed step (total / frames)
  double total_seconds = kNaN;            // whole run
  double max_final_gradient_norm = kNaN;  // largest StepReport::gradient_norm over the frames
  // Largest difference from the reference row over their common frames: positions in m,
  // rotations as geodesic angle in rad (0 for the reference itself).
  double max_position_deviation = kNaN;
  double max_rotation_deviation = kNaN;
  int unconverged_steps = 0;
  double assembly_us = kNaN;     // Newton: per assembly (as liedyn bench)
  double solve_us = kNaN;        // Newton: per factorisation + solve
  double condition_mean = kNaN;  // Newton: over the sampled frames
  int condition_frames = 0;
  bool failed = false;  // a step failed, or the pair is not supported
  std::string failure;  // why (empty if not failed)
  std::vector<CompareFrame> per_frame;

  std::string label() const;  // "backend/rotation", e.g. "newton/lie"
};

// Runs the comparison: one row per (backend, rotation) pair, in the order above. Numerical
// failures are reported in their rows, never thrown.
std::vector<CompareRow> compare_solvers(const Scene& scene, const CompareOptions& options);

// The same fields three ways: a table for reading, one CSV row per pair, one JSON object.
std::string format_compare(const Scene& scene, const std::vector<CompareRow>& rows);
std::string compare_csv(const std::vector<CompareRow>& rows);
std::string compare_json(const Scene& scene, const std::vector<CompareRow>& rows);
// The per-frame series, one row per (backend, rotation, frame):
// backend,rotation,frame,iterations,first_gradient_norm,second_gradient_norm,
// residual_reduction,final_gradient_norm,condition
std::string compare_frames_csv(const std::vector<CompareRow>& rows);

}  // namespace liedyn

#include "compare.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "../lib/so3.hpp"
#include "../solvers/simulator.hpp"
#include "bench.hpp"
#include "output.hpp"

namespace liedyn {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The diagnostics run: per-frame iterations and gradient norms, and the condition number of
// the first Hessian at the sampled frames.
void diagnose(const Scene& scene, SolverOptions options, int condition_every, CompareRow& row) {
  Simulator sim(scene.model, options);
  double condition_sum = 0.0;
  for (int k = 1; k <= row.frames; ++k) {
    const bool sampled = condition_every > 0 && (k - 1) % condition_every == 0;
    sim.set_measure_condition(sampled);
    const StepReport report = sim.step();
    if (!report.state_updated()) break;  // the timed run stopped at the same step
    CompareFrame f;
    f.frame = k;
    f.iterations = report.iterations;
    f.first_gradient_norm = report.first_gradient_norm;
    f.second_gradient_norm = report.second_gradient_norm;
    f.condition = sampled ? report.first_hessian_condition : kNaN;
    if (sampled && std::isfinite(f.condition)) {
      condition_sum += f.condition;
      ++row.condition_frames;
    }
    row.per_frame.push_back(f);
  }
  row.condition_mean = row.condition_frames > 0 ? condition_sum / row.condition_frames : kNaN;
}

void deviation(const std::vector<State>& reference, const std::vector<State>& states,
               CompareRow& row) {
  for (std::size_t k = 0; k < std::min(reference.size(), states.size()); ++k) {
    for (std::size_t i = 0; i < states[k].points.size(); ++i) {
      row.max_position_deviation =
          std::max(row.max_position_deviation,
                   (states[k].points[i] - reference[k].points[i]).cwiseAbs().maxCoeff());
    }
    for (std::size_t i = 0; i < states[k].rotations.size(); ++i) {
      row.max_rotation_deviation =
          std::max(row.max_rotation_deviation,
                   so3::distance(states[k].rotations[i], reference[k].rotations[i]));
    }
  }
}

std::string number(double v) {
  if (std::isnan(v)) return "nan";
  std::ostringstream os;
  os << std::setprecision(6) << v;
  return os.str();
}

}  // namespace

std::vector<CompareRow> compare_rotations(const Scene& scene, const CompareOptions& options) {
  if (options.rotations.empty()) {
    throw SceneError(scene.source, "--rotations", "lists no parameterisation");
  }
  int dofs = 0;
  for (const Component& c : build_components(scene.model)) dofs = std::max(dofs, c.dofs);
  int every = options.condition_every;
  if (every == 0) {
    every = dofs <= CompareOptions::kDenseConditionDofs ? 1 : std::max(1, scene.frames / 20);
  }
  std::vector<CompareRow> rows;
  std::vector<State> reference;
  for (const RotationParameterization rotation : options.rotations) {
    SolverOptions solver = scene.solver;
    solver.rotation = rotation;
    std::vector<State> trajectory;
    const TimedRun run = time_scene(scene, solver, &trajectory);
    std::vector<double> assembly{run.assembly_us()}, solve{run.solve_us()},
        total{run.total_seconds};
    for (int r = 1; r < options.repeats && !run.failed; ++r) {
      const TimedRun again = time_scene(scene, solver, nullptr);
      assembly.push_back(again.assembly_us());
      solve.push_back(again.solve_us());
      total.push_back(again.total_seconds);
    }
    CompareRow row;
    row.rotation = rotation;
    row.frames = run.frames;
    row.iterations_mean = run.frames > 0 ? double(run.sum.iterations) / run.frames : 0.0;
    row.iterations_max = run.max_iterations_in_frame;
    row.assembly_us = median(assembly);
    row.solve_us = median(solve);
    row.total_seconds = median(total);
    row.unconverged_steps = run.unconverged_steps;
    row.failed = run.failed;
    row.failure = run.failure;
    solver.measure_time = false;
    diagnose(scene, solver, every, row);
    if (rows.empty()) {
      reference = std::move(trajectory);
    } else {
      deviation(reference, trajectory, row);
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string format_compare(const Scene& scene, const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  os << "scene " << scene.source << ", " << scene.frames << " frames, h = "
     << scene.model.time_step << " s; deviations from " << to_string(rows.front().rotation)
     << "\n";
  os << std::left << std::setw(8) << "rotation" << std::right << std::setw(11) << "iter/frame"
     << std::setw(9) << "max iter" << std::setw(13) << "assembly µs" << std::setw(11)
     << "solve µs" << std::setw(10) << "total s" << std::setw(13) << "cond(H₁) mean"
     << std::setw(13) << "Δx max [m]" << std::setw(14) << "ΔR max [rad]" << "\n";
  for (const CompareRow& r : rows) {
    os << std::left << std::setw(8) << to_string(r.rotation) << std::right << std::setprecision(4)
       << std::setw(11) << r.iterations_mean << std::setw(9) << r.iterations_max << std::setw(12)
       << r.assembly_us << std::setw(11) << r.solve_us << std::setw(10) << r.total_seconds
       << std::setw(12) << number(r.condition_mean) << std::setw(12)
       << r.max_position_deviation << std::setw(13) << r.max_rotation_deviation;
    if (r.failed) os << "  FAILED: " << r.failure;
    if (r.unconverged_steps > 0) os << "  (" << r.unconverged_steps << " unconverged steps)";
    os << "\n";
  }
  return os.str();
}

std::string compare_csv(const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  os << std::setprecision(9);
  os << "rotation,frames,iterations_mean,iterations_max,assembly_us,solve_us,total_seconds,"
        "condition_mean,condition_frames,max_position_deviation,max_rotation_deviation,"
        "unconverged_steps,failed\n";
  for (const CompareRow& r : rows) {
    os << to_string(r.rotation) << "," << r.frames << "," << r.iterations_mean << ","
       << r.iterations_max << "," << r.assembly_us << "," << r.solve_us << ","
       << r.total_seconds << "," << number(r.condition_mean) << "," << r.condition_frames << ","
       << r.max_position_deviation << "," << r.max_rotation_deviation << ","
       << r.unconverged_steps << "," << (r.failed ? 1 : 0) << "\n";
  }
  return os.str();
}

std::string compare_json(const Scene& scene, const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  os << std::setprecision(9);
  // JSON has no NaN: a missing condition number is null.
  auto json_number = [](double v) { return std::isnan(v) ? std::string("null") : number(v); };
  os << "{\"scene\": " << json_quoted(scene.source) << ", \"frames\": " << scene.frames
     << ", \"time_step\": " << scene.model.time_step << ", \"reference\": \""
     << to_string(rows.front().rotation) << "\", \"rows\": [";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const CompareRow& r = rows[i];
    os << (i > 0 ? ", " : "") << "{\"rotation\": \"" << to_string(r.rotation)
       << "\", \"frames\": " << r.frames << ", \"iterations_mean\": " << r.iterations_mean
       << ", \"iterations_max\": " << r.iterations_max << ", \"assembly_us\": " << r.assembly_us
       << ", \"solve_us\": " << r.solve_us << ", \"total_seconds\": " << r.total_seconds
       << ", \"condition_mean\": " << json_number(r.condition_mean)
       << ", \"condition_frames\": " << r.condition_frames
       << ", \"max_position_deviation\": " << r.max_position_deviation
       << ", \"max_rotation_deviation\": " << r.max_rotation_deviation
       << ", \"unconverged_steps\": " << r.unconverged_steps
       << ", \"failed\": " << (r.failed ? "true" : "false") << "}";
  }
  os << "]}\n";
  return os.str();
}

std::string compare_frames_csv(const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  os << std::setprecision(9);
  os << "rotation,frame,iterations,first_gradient_norm,second_gradient_norm,"
        "residual_reduction,condition\n";
  for (const CompareRow& r : rows) {
    for (const CompareFrame& f : r.per_frame) {
      os << to_string(r.rotation) << "," << f.frame << "," << f.iterations << ","
         << number(f.first_gradient_norm) << "," << number(f.second_gradient_norm) << ","
         << number(f.second_gradient_norm / f.first_gradient_norm) << ","
         << number(f.condition) << "\n";
    }
  }
  return os.str();
}

}  // namespace liedyn

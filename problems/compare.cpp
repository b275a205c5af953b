#include "compare.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>
#include <variant>

#include "../lib/so3.hpp"
#include "../solvers/simulator.hpp"
#include "bench.hpp"
#include "output.hpp"

namespace liedyn {
namespace {

// The diagnostics run: per-frame iterations and gradient norms, and the condition number of
// the first Hessian at the sampled frames (Newton; the other back-ends leave it NaN).
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
    f.final_gradient_norm = report.gradient_norm;
    f.condition = sampled ? report.first_hessian_condition : CompareRow::kNaN;
    if (sampled && std::isfinite(f.condition)) {
      condition_sum += f.condition;
      ++row.condition_frames;
    }
    // std::fmax ignores the initial NaN.
    row.max_final_gradient_norm = std::fmax(row.max_final_gradient_norm, f.final_gradient_norm);
    row.per_frame.push_back(f);
  }
  row.condition_mean = row.condition_frames > 0 ? condition_sum / row.condition_frames : CompareRow::kNaN;
}

// Largest differences over the frames both trajectories have; left NaN if there are none.
void deviation(const std::vector<State>& reference, const std::vector<State>& states,
               CompareRow& row) {
  const std::size_t frames = std::min(reference.size(), states.size());
  if (frames == 0) return;
  row.max_position_deviation = row.max_rotation_deviation = 0.0;
  for (std::size_t k = 0; k < frames; ++k) {
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

// One row: the timed runs and the diagnostics run of `solver` (a failed row if a step fails).
// `trajectory` receives the first timed run's states.
CompareRow run_row(const Scene& scene, SolverOptions solver, int repeats, int condition_every,
                   std::vector<State>& trajectory) {
  CompareRow row;
  row.backend = solver.backend;
  row.rotation = solver.rotation;
  const TimedRun run =
      time_scene(scene, solver, [&](const Simulator& sim) { trajectory.push_back(sim.state()); });
  std::vector<double> assembly{run.assembly_us()}, solve{run.solve_us()},
      total{run.total_seconds};
  for (int r = 1; r < repeats && !run.failed; ++r) {
    const TimedRun again = time_scene(scene, solver);
    assembly.push_back(again.assembly_us());
    solve.push_back(again.solve_us());
    total.push_back(again.total_seconds);
  }
  row.frames = run.frames;
  row.iterations_max = run.max_iterations_in_frame;
  row.total_seconds = median(total);
  if (run.frames > 0) {
    row.iterations_mean = double(run.sum.iterations) / run.frames;
    row.step_us = 1e6 * row.total_seconds / run.frames;
  }
  if (solver.backend == Backend::kNewton) {
    row.assembly_us = median(assembly);
    row.solve_us = median(solve);
  }
  row.unconverged_steps = run.unconverged_steps;
  row.failed = run.failed;
  row.failure = run.failure;
  solver.measure_time = false;
  diagnose(scene, solver, condition_every, row);
  return row;
}

// One output field of a row: its CSV column and JSON key, its table heading and its value.
// The table, CSV and JSON are all written from this one list.
struct Field {
  const char* key;
  const char* heading;
  std::variant<bool, int, double, std::string> value;
};

std::vector<Field> fields(const CompareRow& r) {
  return {
      {"backend", "backend", std::string(to_string(r.backend))},
      {"rotation", "rotation", std::string(to_string(r.rotation))},
      {"reference", "ref", r.reference},
      {"frames", "frames", r.frames},
      {"iterations_mean", "iter/frame", r.iterations_mean},
      {"iterations_max", "max iter", r.iterations_max},
      {"step_us", "step µs", r.step_us},
      {"total_seconds", "total s", r.total_seconds},
      {"max_final_gradient_norm", "max ‖g‖", r.max_final_gradient_norm},
      {"max_position_deviation", "Δx max [m]", r.max_position_deviation},
      {"max_rotation_deviation", "ΔR max [rad]", r.max_rotation_deviation},
      {"unconverged_steps", "unconv.", r.unconverged_steps},
      {"assembly_us", "assembly µs", r.assembly_us},
      {"solve_us", "solve µs", r.solve_us},
      {"condition_mean", "cond(H₁) mean", r.condition_mean},
      {"condition_frames", "cond frames", r.condition_frames},
      {"failed", "failed", r.failed},
      {"failure", "failure", r.failure},
  };
}

// How each output writes a value: table (4 digits, "-" for NaN or empty text, yes/no), CSV
// (9 digits, nan, 1/0, quoted text) and JSON (9 digits, null for NaN, true/false).
enum class Format { kTable, kCsv, kJson };

std::string format_value(const Field& field, Format format) {
  if (const bool* b = std::get_if<bool>(&field.value)) {
    switch (format) {
      case Format::kTable: return *b ? "yes" : "no";
      case Format::kCsv: return *b ? "1" : "0";
      case Format::kJson: return *b ? "true" : "false";
    }
  }
  if (const int* i = std::get_if<int>(&field.value)) return std::to_string(*i);
  if (const double* d = std::get_if<double>(&field.value)) {
    if (!std::isfinite(*d)) {
      if (format == Format::kTable) return "-";
      if (format == Format::kJson) return "null";  // JSON has no NaN
    }
    return format_number(*d, format == Format::kTable ? 4 : 9);
  }
  const std::string& text = std::get<std::string>(field.value);
  switch (format) {
    case Format::kTable: return text.empty() ? "-" : text;
    case Format::kCsv: return csv_field(text);
    case Format::kJson: return json_quoted(text);
  }
  return text;
}

// Columns of UTF-8 text: one per code point (the headings' µ, Δ, ‖, ₁ are one column each).
std::size_t display_width(const std::string& text) {
  return std::count_if(text.begin(), text.end(),
                       [](char ch) { return (static_cast<unsigned char>(ch) & 0xC0) != 0x80; });
}

const CompareRow* reference_row(const std::vector<CompareRow>& rows) {
  const auto it = std::find_if(rows.begin(), rows.end(), [](const auto& r) { return r.reference; });
  return it == rows.end() ? nullptr : &*it;
}

}  // namespace

std::string CompareRow::label() const {
  return std::string(to_string(backend)) + "/" + to_string(rotation);
}

std::vector<CompareRow> compare_solvers(const Scene& scene, const CompareOptions& options) {
  const std::vector<Backend> backends =
      options.backends.empty() ? std::vector<Backend>{scene.solver.backend} : options.backends;
  std::vector<RotationParameterization> rotations = options.rotations;
  if (rotations.empty() && !options.backends.empty()) {
    rotations = {scene.solver.rotation};
  } else if (rotations.empty()) {
    rotations = {RotationParameterization::kLie, RotationParameterization::kRotationVector,
                 RotationParameterization::kQuaternion};
  }
  int dofs = 0;
  for (const Component& c : build_components(scene.model)) dofs = std::max(dofs, c.dofs);
  int every = options.condition_every;
  if (every == 0) {
    every = dofs <= CompareOptions::kDenseConditionDofs ? 1 : std::max(1, scene.frames / 20);
  }
  std::vector<CompareRow> rows;
  std::vector<State> reference;
  for (const Backend backend : backends) {
    for (const RotationParameterization rotation : rotations) {
      SolverOptions solver = scene.solver;
      solver.backend = backend;
      solver.rotation = rotation;
      std::vector<State> trajectory;
      CompareRow row = run_row(scene, solver, options.repeats, every, trajectory);
      if (options.progress != nullptr) {
        std::ostringstream line;  // formatted apart so the caller's stream keeps its settings
        line << "row " << rows.size() + 1 << "/" << backends.size() * rotations.size() << " "
             << row.label() << ": "
             << (row.failed ? "failed" : format_number(row.total_seconds, 3) + " s") << "\n";
        *options.progress << line.str() << std::flush;
      }
      if (rows.empty()) {
        row.reference = true;
        reference = std::move(trajectory);
        // Exactly 0 for the reference itself (NaN if it has no frames).
        if (!reference.empty()) row.max_position_deviation = row.max_rotation_deviation = 0.0;
      } else {
        deviation(reference, trajectory, row);
      }
      rows.push_back(std::move(row));
    }
  }
  return rows;
}

std::string format_compare(const Scene& scene, const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  os << "scene " << scene.source << ", " << scene.frames << " frames, h = "
     << scene.model.time_step << " s";
  if (const CompareRow* reference = reference_row(rows)) {
    os << "; deviations from " << reference->label() << " (the reference: the first row)";
  }
  os << "\nstep µs: wall time per step, median over the timed runs; max ‖g‖: largest final "
        "Lie gradient norm of a step;\nassembly µs, solve µs, cond(H₁): Newton only (\"-\" for "
        "other back-ends and for rows that did not run)\n";
  // Cells: the headings, then one line per row.
  std::vector<std::vector<std::string>> lines(1);
  std::vector<bool> text_column;
  for (const Field& f : fields(CompareRow{})) {
    lines[0].push_back(f.heading);
    text_column.push_back(std::holds_alternative<std::string>(f.value));
  }
  for (const CompareRow& r : rows) {
    lines.emplace_back();
    for (const Field& f : fields(r)) lines.back().push_back(format_value(f, Format::kTable));
  }
  std::vector<std::size_t> widths(text_column.size(), 0);
  for (const auto& line : lines) {
    for (std::size_t c = 0; c < line.size(); ++c) {
      widths[c] = std::max(widths[c], display_width(line[c]));
    }
  }
  // Text left-aligned, numbers right-aligned; the last column (the failure) is not padded.
  for (const auto& line : lines) {
    for (std::size_t c = 0; c < line.size(); ++c) {
      const std::string padding(widths[c] - display_width(line[c]), ' ');
      const bool last = c + 1 == line.size();
      if (c > 0) os << "  ";
      os << (text_column[c] ? line[c] + (last ? "" : padding) : padding + line[c]);
    }
    os << "\n";
  }
  return os.str();
}

std::string compare_csv(const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  const char* separator = "";
  for (const Field& f : fields(CompareRow{})) os << std::exchange(separator, ",") << f.key;
  os << "\n";
  for (const CompareRow& r : rows) {
    separator = "";
    for (const Field& f : fields(r)) {
      os << std::exchange(separator, ",") << format_value(f, Format::kCsv);
    }
    os << "\n";
  }
  return os.str();
}

std::string compare_json(const Scene& scene, const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  os << std::setprecision(9);
  os << "{\"scene\": " << json_quoted(scene.source) << ", \"frames\": " << scene.frames
     << ", \"time_step\": " << scene.model.time_step << ", \"reference\": ";
  if (const CompareRow* reference = reference_row(rows)) {
    os << "{\"backend\": \"" << to_string(reference->backend) << "\", \"rotation\": \""
       << to_string(reference->rotation) << "\"}";
  } else {
    os << "null";
  }
  os << ", \"rows\": [";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    os << (i > 0 ? ", " : "") << "{";
    const char* separator = "";
    for (const Field& f : fields(rows[i])) {
      os << std::exchange(separator, ", ") << "\"" << f.key
         << "\": " << format_value(f, Format::kJson);
    }
    os << "}";
  }
  os << "]}\n";
  return os.str();
}

std::string compare_frames_csv(const std::vector<CompareRow>& rows) {
  std::ostringstream os;
  os << "backend,rotation,frame,iterations,first_gradient_norm,second_gradient_norm,"
        "residual_reduction,final_gradient_norm,condition\n";
  for (const CompareRow& r : rows) {
    for (const CompareFrame& f : r.per_frame) {
      os << to_string(r.backend) << "," << to_string(r.rotation) << "," << f.frame << ","
         << f.iterations << "," << format_number(f.first_gradient_norm, 9) << ","
         << format_number(f.second_gradient_norm, 9) << ","
         << format_number(f.second_gradient_norm / f.first_gradient_norm, 9) << ","
         << format_number(f.final_gradient_norm, 9) << "," << format_number(f.condition, 9) << "\n";
    }
  }
  return os.str();
}

}  // namespace liedyn

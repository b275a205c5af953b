// liedyn.compare and liedyn.sweep: the command line's `compare` (problems/compare.hpp) and
// `sweep` (problems/sweep.hpp) without files, their rows as columns (the package turns them
// into NumPy record arrays).

#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "problems/compare.hpp"
#include "problems/sweep.hpp"

namespace liedyn::python {

namespace {

// Columns of `rows`: name → one value per row, from `value_of(row)`.
template <class Row, class Value>
py::list column(const std::vector<Row>& rows, Value value_of) {
  py::list out;
  for (const Row& r : rows) out.append(value_of(r));
  return out;
}

// A value as the command line takes it (parse_setting_value): a string as typed, anything
// else as its JSON text.
std::string setting_text(const py::handle& value) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  return py::module_::import("json").attr("dumps")(value).cast<std::string>();
}

}  // namespace

void bind_studies(py::module_& m) {
  m.def(
      "_compare",
      [](const SceneHandle& scene, const std::vector<std::string>& backends,
         const std::vector<std::string>& rotations, int repeats) {
        CompareOptions options;
        for (const std::string& b : backends) {
          const auto parsed = parse_backend(b);
          if (!parsed) throw SceneError(scene.scene.source, "backends", "unknown backend '" + b + "'");
          options.backends.push_back(*parsed);
        }
        for (const std::string& r : rotations) {
          const auto parsed = parse_rotation(r);
          if (!parsed) throw SceneError(scene.scene.source, "rotations", "unknown rotation '" + r + "'");
          options.rotations.push_back(*parsed);
        }
        if (repeats < 1) throw py::value_error("repeats must be >= 1");
        options.repeats = repeats;
        std::vector<CompareRow> rows;
        {
          py::gil_scoped_release release;
          rows = compare_solvers(scene.scene, options);
        }
        py::dict d;
        d["backend"] = column(rows, [](const CompareRow& r) { return std::string(to_string(r.backend)); });
        d["rotation"] = column(rows, [](const CompareRow& r) { return std::string(to_string(r.rotation)); });
        d["reference"] = column(rows, [](const CompareRow& r) { return r.reference; });
        d["frames"] = column(rows, [](const CompareRow& r) { return r.frames; });
        d["iterations_mean"] = column(rows, [](const CompareRow& r) { return r.iterations_mean; });
        d["iterations_max"] = column(rows, [](const CompareRow& r) { return r.iterations_max; });
        d["step_us"] = column(rows, [](const CompareRow& r) { return r.step_us; });
        d["total_seconds"] = column(rows, [](const CompareRow& r) { return r.total_seconds; });
        d["max_final_gradient_norm"] = column(rows, [](const CompareRow& r) { return r.max_final_gradient_norm; });
        d["max_position_deviation"] = column(rows, [](const CompareRow& r) { return r.max_position_deviation; });
        d["max_rotation_deviation"] = column(rows, [](const CompareRow& r) { return r.max_rotation_deviation; });
        d["unconverged_steps"] = column(rows, [](const CompareRow& r) { return r.unconverged_steps; });
        d["assembly_us"] = column(rows, [](const CompareRow& r) { return r.assembly_us; });
        d["solve_us"] = column(rows, [](const CompareRow& r) { return r.solve_us; });
        d["failed"] = column(rows, [](const CompareRow& r) { return r.failed; });
        d["failure"] = column(rows, [](const CompareRow& r) { return r.failure; });
        return d;
      },
      py::arg("scene"), py::arg("backends"), py::arg("rotations"), py::arg("repeats"),
      "Use liedyn.compare.");

  m.def(
      "_sweep",
      [](const SceneHandle& scene, const py::dict& axes, int reference_refinement,
         int gradient_sample, int repeats, int jobs) {
        SweepOptions options;
        for (const auto& [path, values] : axes) {
          SweepAxis axis;
          axis.path = py::str(path);
          for (const py::handle v : values) axis.values.push_back(setting_text(v));
          options.axes.push_back(std::move(axis));
        }
        options.reference_refinement = reference_refinement;
        options.gradient_sample = gradient_sample;
        options.repeats = repeats;
        options.jobs = jobs;
        SweepResult result;
        {
          py::gil_scoped_release release;
          result = run_sweep(scene.json, scene.scene.source, options);
        }
        const std::vector<SweepRun>& runs = result.runs;
        py::dict d;
        for (std::size_t a = 0; a < result.axis_names.size(); ++a) {
          d[py::str(result.axis_names[a])] = column(runs, [&](const SweepRun& r) { return r.settings[a]; });
        }
        d["frames"] = column(runs, [](const SweepRun& r) { return r.frames; });
        d["frames_completed"] = column(runs, [](const SweepRun& r) { return r.frames_completed; });
        d["wall_seconds"] = column(runs, [](const SweepRun& r) { return r.wall_seconds; });
        d["parallel_runs"] = column(runs, [](const SweepRun& r) { return r.parallel_runs; });
        d["newton_iterations"] = column(runs, [](const SweepRun& r) { return r.newton_iterations; });
        d["factorizations"] = column(runs, [](const SweepRun& r) { return r.factorizations; });
        d["unconverged_steps"] = column(runs, [](const SweepRun& r) { return r.unconverged_steps; });
        d["position_error"] = column(runs, [](const SweepRun& r) { return r.position_error; });
        d["orientation_error"] = column(runs, [](const SweepRun& r) { return r.orientation_error; });
        d["energy_drift"] = column(runs, [](const SweepRun& r) { return r.energy_drift; });
        d["momentum_drift"] = column(runs, [](const SweepRun& r) { return r.momentum_drift; });
        d["gradient_error"] = column(runs, [](const SweepRun& r) { return r.gradient_error; });
        d["failed"] = column(runs, [](const SweepRun& r) { return r.failed; });
        d["failure"] = column(runs, [](const SweepRun& r) { return r.failure; });
        return py::make_tuple(d, result.notes);
      },
      py::arg("scene"), py::arg("axes"), py::arg("reference_refinement"),
      py::arg("gradient_sample"), py::arg("repeats"), py::arg("jobs"), "Use liedyn.sweep.");
}

}  // namespace liedyn::python

// liedyn.DifferentiableProblem: a scene's optimisation problem as a loss of γ and its exact
// adjoint gradient (solvers/adjoint.hpp), for SciPy, PyTorch and other optimisers.

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <optional>

#include "arrays.hpp"
#include "bindings.hpp"
#include "problems/optimization.hpp"

namespace liedyn::python {

namespace {

class ProblemHandle {
 public:
  explicit ProblemHandle(SceneHandle scene)
      : scene_(std::move(scene)), simulation_(make_differentiable_simulation(scene_.scene)) {}

  const SceneHandle& scene() const { return scene_; }
  const DifferentiableSimulation& simulation() const { return simulation_; }

  Eigen::VectorXd checked(const Eigen::VectorXd& gamma) const {
    if (gamma.size() != simulation_.parameters().size()) {
      throw py::value_error("gamma has " + std::to_string(gamma.size()) + " entries, the problem " +
                            std::to_string(simulation_.parameters().size()));
    }
    return gamma;
  }

 private:
  SceneHandle scene_;
  DifferentiableSimulation simulation_;
};

}  // namespace

void bind_problem(py::module_& m) {
  py::class_<ProblemHandle>(m, "DifferentiableProblem", R"doc(
The optimisation problem of a scene's "optimization" block: the loss g(γ) of a forward
simulation and its exact gradient dg/dγ by the adjoint method (one backward pass).

    prob = liedyn.DifferentiableProblem(scene)
    scipy.optimize.minimize(prob.loss_and_gradient, prob.gamma0, jac=True,
                            method="L-BFGS-B", bounds=prob.bounds)

The loss is the objective's raw value; `liedyn optimize` reports it divided by loss_scale.
A forward step that does not converge raises SimulationFailed (the gradient would not be
exact). Calls release the GIL; one problem per thread.)doc")
      .def(py::init([](const SceneHandle& scene) { return ProblemHandle(scene); }), py::arg("scene"))
      .def_property_readonly("scene", &ProblemHandle::scene)
      .def_property_readonly("gamma0", [](const ProblemHandle& p) {
             return Eigen::VectorXd(p.simulation().initial_parameters());
           }, "The parameters' values in the scene, γ₀.")
      .def_property_readonly("size", [](const ProblemHandle& p) { return p.simulation().parameters().size(); })
      .def_property_readonly("names", [](const ProblemHandle& p) {
             std::vector<std::string> names;
             const ParameterSet& set = p.simulation().parameters();
             for (int i = 0; i < set.size(); ++i) names.push_back(set.describe(p.simulation().base_model(), i));
             return names;
           }, "One name per entry of γ, as parameters.csv names them.")
      .def_property_readonly("bounds", [](const ProblemHandle& p) {
             const ParameterSet& set = p.simulation().parameters();
             const Eigen::VectorXd lower = set.lower_bounds(), upper = set.upper_bounds();
             const auto bound = [](double b) -> py::object {
               return std::isfinite(b) ? py::object(py::float_(b)) : py::object(py::none());
             };
             std::vector<py::tuple> pairs;
             for (int i = 0; i < set.size(); ++i) pairs.push_back(py::make_tuple(bound(lower(i)), bound(upper(i))));
             return pairs;
           }, "(lower, upper) per entry, None where unbounded: SciPy's bounds format.")
      .def_property_readonly("loss_scale", [](const ProblemHandle& p) {
             const double scale = p.scene().scene.optimization->loss_scale;
             if (scale > 0.0) return scale;
             py::gil_scoped_release release;
             return p.simulation().evaluate(p.simulation().initial_parameters(), nullptr).loss;
           }, "What `liedyn optimize` divides the loss by: the scene's loss_scale, else the loss at γ₀.")
      .def_property_readonly("target_normalized_loss", [](const ProblemHandle& p) {
             return p.scene().scene.optimization->optimizer.target_normalized_loss;
           }, "The scene's target for loss / loss_scale (`liedyn optimize` stops there).")
      .def("loss", [](const ProblemHandle& p, const Eigen::VectorXd& gamma) {
             const Eigen::VectorXd g = p.checked(gamma);
             py::gil_scoped_release release;
             return p.simulation().evaluate(g, nullptr).loss;
           }, py::arg("gamma"), "g(γ): one forward simulation.")
      .def("loss_and_gradient", [](const ProblemHandle& p, const Eigen::VectorXd& gamma) {
             const Eigen::VectorXd g = p.checked(gamma);
             Eigen::VectorXd gradient;
             double loss = 0.0;
             {
               py::gil_scoped_release release;
               loss = p.simulation().evaluate(g, &gradient).loss;
             }
             return py::make_tuple(loss, gradient);
           }, py::arg("gamma"),
           "(g(γ), dg/dγ): one forward simulation and one adjoint (backward) pass.")
      .def("_trajectory", [](const ProblemHandle& p, const Eigen::VectorXd& gamma) {
             const Eigen::VectorXd g = p.checked(gamma);
             DifferentiableSimulation::Result result;
             {
               py::gil_scoped_release release;
               result = p.simulation().evaluate(g, nullptr);
             }
             const Trajectory& t = result.trajectory;
             std::vector<double> time, positions, quaternions;
             for (int k = 0; k <= t.frames(); ++k) {
               time.push_back(k * t.time_step);
               append_points(t.states[k], positions);
               append_quaternions(t.states[k], quaternions);
             }
             const py::ssize_t f = t.frames() + 1;
             const py::ssize_t n = static_cast<py::ssize_t>(t.states[0].points.size());
             const py::ssize_t r = static_cast<py::ssize_t>(t.states[0].rotations.size());
             py::dict d;
             d["time"] = owned_array(std::move(time), {f});
             d["positions"] = owned_array(std::move(positions), {f, n, 3});
             d["quaternions"] = owned_array(std::move(quaternions), {f, r, 4});
             d["loss"] = result.loss;
             return d;
           }, py::arg("gamma"), "The forward run at γ as arrays (use trajectory()).")
      .def("_minimize", [](const ProblemHandle& p, std::optional<std::string> optimizer,
                           std::optional<int> max_iterations, std::optional<Eigen::VectorXd> start) {
             // `liedyn optimize`'s minimisation (problems/optimization.cpp): the scene's
             // optimiser settings, its loss scale rule and bounds; no files.
             const Scene& scene = p.scene().scene;
             OptimizerOptions options = scene.optimization->optimizer;
             if (optimizer) {
               const auto parsed = parse_optimizer(*optimizer);
               if (!parsed) {
                 throw SceneError(scene.source, "optimizer", "unknown optimizer '" + *optimizer +
                                  "' (nlopt-lbfgs, ceres-lbfgs or ipopt-lbfgs)");
               }
               options.optimizer = *parsed;
             }
             if (max_iterations) options.max_iterations = *max_iterations;
             options.validate();
             const Bounds bounds = optimizer_bounds(scene, p.simulation(), options.optimizer,
                                                    optimizer ? "optimizer" : "optimization.optimizer");
             const Eigen::VectorXd x0 = p.checked(start.value_or(p.simulation().initial_parameters()));
             std::vector<double> loss, normalized, gradient_norm, seconds;
             OptimizationResult result;
             double scale = scene.optimization->loss_scale;
             {
               py::gil_scoped_release release;
               if (scale == 0.0) scale = p.simulation().evaluate(x0, nullptr).loss;
               if (scale > 0.0) {
                 const EvaluationCallback record = [&](const Evaluation& e, const Eigen::VectorXd&,
                                                       const Eigen::VectorXd&) {
                   loss.push_back(e.loss);
                   normalized.push_back(e.normalized_loss);
                   gradient_norm.push_back(e.gradient_norm);
                   seconds.push_back(e.seconds);
                 };
                 result = minimize(objective_of(p.simulation()), x0, scale, options, record, bounds);
               }
             }
             if (!(scale > 0.0)) {
               throw py::value_error("the initial loss is " + std::to_string(scale) +
                                     ": nothing to minimise (set optimization.loss_scale)");
             }
             const py::ssize_t n = static_cast<py::ssize_t>(loss.size());
             py::dict d;
             d["best_gamma"] = result.best_x;
             d["best_loss"] = result.best_loss;
             d["best_normalized_loss"] = result.best_normalized_loss;
             d["loss_scale"] = scale;
             d["iterations"] = result.iterations;
             d["evaluations"] = result.evaluations;
             d["reached_target"] = result.reached_target;
             d["status"] = result.status;
             d["message"] = result.message;
             d["optimizer"] = std::string(to_string(options.optimizer));
             d["loss"] = owned_array(std::move(loss), {n});
             d["normalized_loss"] = owned_array(std::move(normalized), {n});
             d["gradient_norm"] = owned_array(std::move(gradient_norm), {n});
             d["seconds"] = owned_array(std::move(seconds), {n});
             return d;
           }, py::arg("optimizer") = py::none(), py::arg("max_iterations") = py::none(),
           py::arg("start") = py::none(), "Use minimize().")
      .def("_cpp_seconds", [](const ProblemHandle& p, const Eigen::VectorXd& gamma, int repeat) {
             // For scripts/python_overhead.py: the C++ call loss_and_gradient makes, timed in
             // C++ (`repeat` times), to set the Python call's overhead against.
             const Eigen::VectorXd g = p.checked(gamma);
             std::vector<double> seconds;
             Eigen::VectorXd gradient;
             py::gil_scoped_release release;
             for (int i = 0; i < repeat; ++i) {
               const auto start = std::chrono::steady_clock::now();
               p.simulation().evaluate(g, &gradient);
               seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
             }
             return seconds;
           }, py::arg("gamma"), py::arg("repeat"))
      .def(py::pickle([](const ProblemHandle& p) { return py::make_tuple(p.scene()); },
                      [](const py::tuple& t) { return ProblemHandle(t[0].cast<SceneHandle>()); }));
}

}  // namespace liedyn::python

// liedyn.Simulator (one step at a time, for control loops) and liedyn._simulate (a whole run,
// through the command line's own loop, problems/run.hpp).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <memory>
#include <optional>

#include "arrays.hpp"
#include "bindings.hpp"
#include "problems/run.hpp"
#include "solvers/adjoint.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::python {

namespace {

// A Simulator with the scene it runs (for pickling and for the step failure messages).
class SimulatorHandle {
 public:
  explicit SimulatorHandle(SceneHandle scene)
      : scene_(std::move(scene)),
        simulator_(std::make_unique<Simulator>(scene_.scene.model, scene_.scene.solver)) {}

  const SceneHandle& scene() const { return scene_; }
  Simulator& simulator() { return *simulator_; }
  const Simulator& simulator() const { return *simulator_; }

  // One step; SimulationFailed if it did not update the state (the simulator is then as
  // before the call).
  StepReport step_or_throw() {
    StepReport report = simulator_->step();
    if (!report.state_updated()) {
      const int k = simulator_->frame() + 1;
      throw SimulationFailed(k, step_failure_message(k, scene_.scene.model.time_step,
                                                     scene_.scene.solver.backend, report));
    }
    return report;
  }

 private:
  SceneHandle scene_;
  std::unique_ptr<Simulator> simulator_;
};

// The index of a rod given by index or name (IndexError / KeyError otherwise).
int rod_index(const Model& model, const py::object& rod) {
  const int n = static_cast<int>(model.rods.size());
  if (py::isinstance<py::int_>(rod)) {
    const int r = rod.cast<int>();
    if (r < 0 || r >= n) throw py::index_error("rod " + std::to_string(r) + " of " + std::to_string(n));
    return r;
  }
  const std::string name = py::str(rod);
  for (int r = 0; r < n; ++r) {
    if (model.rods[r].name == name) return r;
  }
  throw py::key_error("no rod named '" + name + "'");
}

py::array_t<double> vectors(int count, const auto& value_of) {
  std::vector<double> data;
  data.reserve(3 * count);
  for (int i = 0; i < count; ++i) {
    const Vector3 v = value_of(i);
    data.insert(data.end(), {v.x(), v.y(), v.z()});
  }
  return owned_array(std::move(data), {count, 3});
}

// What _simulate collects per frame, turned into arrays once the run is over.
struct Recording {
  std::vector<double> time, positions, quaternions, kinetic, potential, gradient_norm, step_norm,
      penetration;
  std::vector<int> iterations;
  std::vector<bool> converged;
  std::vector<std::string> status;
  int frames = 0;

  void observe(const Simulator& sim, const StepReport* report) {
    ++frames;
    time.push_back(sim.time());
    append_points(sim.state(), positions);
    append_quaternions(sim.state(), quaternions);
    kinetic.push_back(sim.kinetic_energy());
    potential.push_back(sim.potential_energy());
    penetration.push_back(sim.max_penetration());
    iterations.push_back(report ? report->iterations : 0);
    gradient_norm.push_back(report ? report->gradient_norm : 0.0);
    step_norm.push_back(report ? report->step_norm : 0.0);
    converged.push_back(report ? report->converged() : true);
    status.push_back(report ? to_string(report->status) : "initial");
  }
};

}  // namespace

void bind_simulator(py::module_& m) {
  py::class_<StepReport>(m, "StepReport", "What one time step did (the columns of frames.csv).")
      .def_property_readonly("status", [](const StepReport& r) { return std::string(to_string(r.status)); },
                             "'converged', 'max_iterations', 'stalled' (state updated), or "
                             "'line_search_failed', 'non_finite', 'solver_failed' (not updated).")
      .def_property_readonly("converged", &StepReport::converged)
      .def_property_readonly("state_updated", &StepReport::state_updated)
      .def_readonly("iterations", &StepReport::iterations, "Newton (or Ceres, Ipopt) iterations.")
      .def_readonly("gradient_norm", &StepReport::gradient_norm, "‖g‖₂ at the final iterate.")
      .def_readonly("step_norm", &StepReport::step_norm, "‖δ‖∞ of the last Newton step.")
      .def_readonly("assemblies", &StepReport::assemblies)
      .def_readonly("factorizations", &StepReport::factorizations)
      .def_readonly("regularized_iterations", &StepReport::regularized_iterations)
      .def_readonly("constraint_violation", &StepReport::constraint_violation)
      .def_readonly("message", &StepReport::message, "Why it did not converge, if there is more to say.")
      .def("__repr__", [](const StepReport& r) {
        return "<StepReport " + std::string(to_string(r.status)) + ", " +
               std::to_string(r.iterations) + " iterations, |g| " + std::to_string(r.gradient_norm) + ">";
      });

  py::class_<SimulatorHandle>(m, "Simulator", R"doc(
Steps a scene forward in time, one step at a time (for control loops and inspection).

The state is read as NumPy arrays (copies): positions() holds the bodies' centres of mass in
scene order, then every rod's nodes; rotations() / quaternions() the bodies', then every rod's
edges (rod_points / rod_rotations give a rod's rows). One Simulator per thread.)doc")
      .def(py::init<SceneHandle>(), py::arg("scene"))
      .def("step", &SimulatorHandle::step_or_throw, py::call_guard<py::gil_scoped_release>(),
           "Advances one time step and returns its StepReport (which says whether it met the "
           "tolerance). Raises SimulationFailed if the step could not update the state (the "
           "simulator is then left as it was).")
      .def(
          "run",
          [](const py::object& self, std::optional<int> frames, const py::object& callback) {
            SimulatorHandle& h = self.cast<SimulatorHandle&>();
            const int n = frames.value_or(h.scene().scene.frames - h.simulator().frame());
            if (n < 0) throw py::value_error("frames must be >= 0, got " + std::to_string(n));
            std::vector<StepReport> reports;
            reports.reserve(n);
            {
              py::gil_scoped_release release;
              for (int k = 0; k < n; ++k) {
                reports.push_back(h.step_or_throw());
                if (!callback.is_none()) {
                  py::gil_scoped_acquire acquire;
                  const py::object go_on = callback(self, reports.back());
                  if (!go_on.is_none() && !go_on.cast<bool>()) break;
                }
              }
            }
            return reports;
          },
          py::arg("frames") = py::none(), py::arg("callback") = py::none(),
          "Takes `frames` steps (default: the rest of the scene's frames) and returns their "
          "StepReports. callback(simulator, report), if given, runs after each step; returning "
          "False stops the run. Raises SimulationFailed at a step that cannot update the state. "
          "Releases the GIL while it steps.")
      .def_property_readonly("scene", &SimulatorHandle::scene)
      .def_property_readonly("frame", [](const SimulatorHandle& h) { return h.simulator().frame(); })
      .def_property_readonly("time", [](const SimulatorHandle& h) { return h.simulator().time(); })
      .def("positions", [](const SimulatorHandle& h) {
             const State& q = h.simulator().state();
             std::vector<double> data;
             append_points(q, data);
             return owned_array(std::move(data), {static_cast<py::ssize_t>(q.points.size()), 3});
           }, "Every point's position, N×3 (bodies, then rod nodes), m.")
      .def("rotations", [](const SimulatorHandle& h) {
             const State& q = h.simulator().state();
             std::vector<double> data;
             append_rotations(q, data);
             return owned_array(std::move(data), {static_cast<py::ssize_t>(q.rotations.size()), 3, 3});
           }, "Every rotation matrix, M×3×3 (bodies, then rod edges): body frame to world.")
      .def("quaternions", [](const SimulatorHandle& h) {
             const State& q = h.simulator().state();
             std::vector<double> data;
             append_quaternions(q, data);
             return owned_array(std::move(data), {static_cast<py::ssize_t>(q.rotations.size()), 4});
           }, "Every rotation as a unit quaternion, M×4, w first (as trajectory.csv).")
      .def("velocities", [](const SimulatorHandle& h) {
             const Simulator& s = h.simulator();
             return vectors(static_cast<int>(s.state().points.size()),
                            [&](int i) { return s.linear_velocity(i); });
           }, "Every point's velocity of the last step (Δx/h), N×3, m/s.")
      .def("angular_velocities", [](const SimulatorHandle& h) {
             const Simulator& s = h.simulator();
             return vectors(static_cast<int>(s.state().rotations.size()),
                            [&](int i) { return s.angular_velocity(i); });
           }, "Every rotation's angular velocity of the last step (log(ΔR)/h, world frame), M×3, rad/s.")
      .def("kinetic_energy", [](const SimulatorHandle& h) { return h.simulator().kinetic_energy(); })
      .def("potential_energy", [](const SimulatorHandle& h) { return h.simulator().potential_energy(); })
      .def("angular_momentum", [](const SimulatorHandle& h) {
             const Vector3 L = h.simulator().angular_momentum();
             return owned_array({L.x(), L.y(), L.z()}, {3});
           }, "About the world origin, kg m²/s.")
      .def("max_penetration", [](const SimulatorHandle& h) { return h.simulator().max_penetration(); })
      .def("contact_pairs", [](const SimulatorHandle& h) { return h.simulator().contact_pairs(); })
      .def("rod_points", [](const SimulatorHandle& h, const py::object& rod) {
             const Model& model = h.simulator().model();
             const int r = rod_index(model, rod);
             std::vector<int> rows;
             for (int i = 0; i < model.rods[r].node_count(); ++i) rows.push_back(model.rod_point(r, i));
             return rows;
           }, py::arg("rod"), "The rows of positions() that hold a rod's nodes (rod by index or name).")
      .def("rod_rotations", [](const SimulatorHandle& h, const py::object& rod) {
             const Model& model = h.simulator().model();
             const int r = rod_index(model, rod);
             std::vector<int> rows;
             for (int j = 0; j < model.rods[r].edge_count(); ++j) rows.push_back(model.rod_rotation(r, j));
             return rows;
           }, py::arg("rod"), "The rows of rotations() that hold a rod's edges.")
      .def(py::pickle(
          // A simulator pickles as its scene and frame; unpickling replays the steps (the
          // simulation is deterministic: the state is bit for bit the same).
          [](const SimulatorHandle& h) { return py::make_tuple(h.scene(), h.simulator().frame()); },
          [](const py::tuple& t) {
            SimulatorHandle h(t[0].cast<SceneHandle>());
            const int frame = t[1].cast<int>();
            py::gil_scoped_release release;
            for (int k = 0; k < frame; ++k) h.step_or_throw();
            return h;
          }));

  m.def(
      "_simulate",
      [](const SceneHandle& scene, std::optional<std::filesystem::path> out) {
        Recording recording;
        SimulationSummary summary;
        {
          py::gil_scoped_release release;
          const FrameObserver observe = [&](const Simulator& sim, const StepReport* report) {
            recording.observe(sim, report);
          };
          if (out) {
            OutputFolder folder(*out, "python simulate " + scene.scene.source, nullptr);
            summary = simulate_into(scene.scene, &folder, nullptr, observe);
            folder.commit();  // also after a failed step: its frames are valid
          } else {
            summary = simulate_into(scene.scene, nullptr, nullptr, observe);
          }
        }
        const py::ssize_t f = recording.frames;
        const py::ssize_t n = f > 0 ? static_cast<py::ssize_t>(recording.positions.size()) / (3 * f) : 0;
        const py::ssize_t r = f > 0 ? static_cast<py::ssize_t>(recording.quaternions.size()) / (4 * f) : 0;
        py::dict d;
        d["time"] = owned_array(std::move(recording.time), {f});
        d["positions"] = owned_array(std::move(recording.positions), {f, n, 3});
        d["quaternions"] = owned_array(std::move(recording.quaternions), {f, r, 4});
        d["kinetic_energy"] = owned_array(std::move(recording.kinetic), {f});
        d["potential_energy"] = owned_array(std::move(recording.potential), {f});
        d["max_penetration"] = owned_array(std::move(recording.penetration), {f});
        d["gradient_norm"] = owned_array(std::move(recording.gradient_norm), {f});
        d["step_norm"] = owned_array(std::move(recording.step_norm), {f});
        d["iterations"] = py::array_t<int>(f, recording.iterations.data());
        py::array_t<bool> converged(f);
        for (py::ssize_t i = 0; i < f; ++i) converged.mutable_at(i) = recording.converged[i];
        d["converged"] = converged;
        d["status"] = recording.status;
        d["failure"] = summary.failed ? py::object(py::str(summary.failure)) : py::object(py::none());
        d["failed_frame"] = summary.failed ? summary.frames_completed + 1 : -1;
        d["solve_seconds"] = summary.solve_seconds;
        return d;
      },
      py::arg("scene"), py::arg("out") = py::none(),
      "The command line's run (problems/run.hpp) with every frame recorded as arrays; with "
      "`out`, trajectory.csv and frames.csv written there as one unit, as `liedyn simulate` "
      "writes them. Use liedyn.simulate.");
}

}  // namespace liedyn::python

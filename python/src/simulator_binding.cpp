// liedyn.Simulator (one step at a time, for control loops) and liedyn._simulate (a whole run,
// through the command line's own loop, problems/run.hpp).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "arrays.hpp"
#include "bindings.hpp"
#include "problems/run.hpp"
#include "solvers/adjoint.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::python {

namespace {

// --every's range, as ValueError.
void checked_every(int every) {
  if (every < 1) throw py::value_error("every must be >= 1, got " + std::to_string(every));
}

// A Simulator with the scene it runs (for pickling and for the step failure messages).
class SimulatorHandle {
 public:
  explicit SimulatorHandle(SceneHandle scene)
      : scene_(std::move(scene)),
        simulator_(std::make_unique<Simulator>(scene_.scene.model, scene_.scene.solver)) {}

  const SceneHandle& scene() const { return scene_; }
  Simulator& simulator() { return *simulator_; }
  const Simulator& simulator() const { return *simulator_; }

  // Simulator::set_state, remembered for pickling.
  struct Restart {
    int frame;
    State state;
    Step step;
  };
  void set_state(const State& q, const Step& dq) {
    simulator_->set_state(q, dq);
    restarts_.push_back({simulator_->frame(), q, dq});
  }
  const std::vector<Restart>& restarts() const { return restarts_; }

  // Steps (and restarts) up to `frame`, as the pickled simulator did: the simulation is
  // deterministic, so the state is bit for bit the same.
  void replay(int frame, const std::vector<Restart>& restarts) {
    std::size_t next = 0;
    for (;;) {
      while (next < restarts.size() && restarts[next].frame == simulator_->frame()) {
        set_state(restarts[next].state, restarts[next].step);
        ++next;
      }
      if (simulator_->frame() >= frame) break;
      step_or_throw();
    }
  }

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
  std::vector<Restart> restarts_;
};

// A state and step as flat lists of numbers (exact: the pickled simulator's restarts).
py::tuple to_numbers(const State& q, const Step& dq) {
  std::vector<double> x, R, dx, dR;
  append_points(q, x);
  append_rotations(q, R);
  for (const Vector3& v : dq.points) dx.insert(dx.end(), {v.x(), v.y(), v.z()});
  for (const Matrix3& M : dq.rotations) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) dR.push_back(M(i, j));
    }
  }
  return py::make_tuple(x, R, dx, dR);
}

void from_numbers(const py::tuple& t, State& q, Step& dq) {
  const auto x = t[0].cast<std::vector<double>>(), R = t[1].cast<std::vector<double>>(),
             dx = t[2].cast<std::vector<double>>(), dR = t[3].cast<std::vector<double>>();
  if (x.size() != 3 * q.points.size() || R.size() != 9 * q.rotations.size() ||
      dx.size() != x.size() || dR.size() != R.size()) {
    throw py::value_error("a pickled simulator's restart does not fit its scene");
  }
  for (std::size_t i = 0; i < q.points.size(); ++i) {
    q.points[i] = Vector3(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
    dq.points[i] = Vector3(dx[3 * i], dx[3 * i + 1], dx[3 * i + 2]);
  }
  for (std::size_t j = 0; j < q.rotations.size(); ++j) {
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        q.rotations[j](a, b) = R[9 * j + 3 * a + b];
        dq.rotations[j](a, b) = dR[9 * j + 3 * a + b];
      }
    }
  }
}

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

// The simulator's state as an array, one row per point (`append` = append_points) or per
// rotation, each row of shape `row` (arrays.hpp).
py::array_t<double> state_array(const SimulatorHandle& h,
                                void (*append)(const State&, std::vector<double>&),
                                std::vector<py::ssize_t> row) {
  const State& q = h.simulator().state();
  std::vector<double> data;
  append(q, data);
  const std::size_t rows = append == &append_points ? q.points.size() : q.rotations.size();
  row.insert(row.begin(), static_cast<py::ssize_t>(rows));
  return owned_array(std::move(data), std::move(row));
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

// A run's frames as _simulate recorded them: the arrays of a Trajectory are built from them,
// and Trajectory.to_csv writes them through the command line's own writer.
struct Recording {
  std::vector<FrameRecord> frames;

  py::dict arrays() const {
    const py::ssize_t f = static_cast<py::ssize_t>(frames.size());
    const py::ssize_t n = f > 0 ? static_cast<py::ssize_t>(frames[0].state.points.size()) : 0;
    const py::ssize_t r = f > 0 ? static_cast<py::ssize_t>(frames[0].state.rotations.size()) : 0;
    std::vector<double> time, positions, quaternions, kinetic, potential, gradient_norm, step_norm,
        penetration;
    py::array_t<int> iterations(f), assemblies(f), factorizations(f), reused(f);
    std::vector<double> reuse_error;
    py::array_t<bool> converged(f);
    py::list status;
    for (py::ssize_t k = 0; k < f; ++k) {
      const FrameRecord& record = frames[k];
      const StepReport* report = record.report ? &*record.report : nullptr;
      time.push_back(record.time);
      append_points(record.state, positions);
      append_quaternions(record.state, quaternions);
      kinetic.push_back(record.kinetic_energy);
      potential.push_back(record.potential_energy);
      penetration.push_back(record.max_penetration);
      gradient_norm.push_back(report ? report->gradient_norm : 0.0);
      step_norm.push_back(report ? report->step_norm : 0.0);
      iterations.mutable_at(k) = report ? report->iterations : 0;
      assemblies.mutable_at(k) = report ? report->assemblies : 0;
      factorizations.mutable_at(k) = report ? report->factorizations : 0;
      reused.mutable_at(k) = report ? report->reused_factorizations : 0;
      reuse_error.push_back(report ? report->reuse_error : 0.0);
      converged.mutable_at(k) = report ? report->converged() : true;
      status.append(report ? to_string(report->status) : "initial");
    }
    py::dict d;
    d["time"] = owned_array(std::move(time), {f});
    d["positions"] = owned_array(std::move(positions), {f, n, 3});
    d["quaternions"] = owned_array(std::move(quaternions), {f, r, 4});
    d["kinetic_energy"] = owned_array(std::move(kinetic), {f});
    d["potential_energy"] = owned_array(std::move(potential), {f});
    d["max_penetration"] = owned_array(std::move(penetration), {f});
    d["gradient_norm"] = owned_array(std::move(gradient_norm), {f});
    d["step_norm"] = owned_array(std::move(step_norm), {f});
    d["iterations"] = iterations;
    d["assemblies"] = assemblies;
    d["factorizations"] = factorizations;
    d["reused_factorizations"] = reused;
    d["reuse_error"] = owned_array(std::move(reuse_error), {f});
    d["converged"] = converged;
    d["status"] = status;
    return d;
  }

  // trajectory.csv (every `every`-th frame and the last), frames.csv and shapes.json in `out`,
  // one unit (as `liedyn simulate --every` writes them).
  void write_csv(const SceneHandle& scene, const std::filesystem::path& out, int every) const {
    checked_every(every);
    const Model& model = scene.scene.model;
    for (const FrameRecord& record : frames) {
      const auto rods = static_cast<int>(model.rods.size());
      if (static_cast<int>(record.state.points.size()) != model.point_count() ||
          static_cast<int>(record.state.rotations.size()) != model.rod_rotation(rods, 0)) {
        throw py::value_error("to_csv: the trajectory's states do not fit the scene " + scene.scene.source);
      }
    }
    OutputFolder folder(out, "python Trajectory.to_csv " + scene.scene.source, nullptr);
    RunFiles files(folder, scene.scene, every);
    for (const FrameRecord& record : frames) files.add(record);
    if (!frames.empty()) files.finish(frames.back());
    folder.commit();
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
      .def_readonly("reused_factorizations", &StepReport::reused_factorizations,
                    "Solves ended by chord steps on a reused factorisation (solver.hessian_reuse).")
      .def_readonly("reuse_error", &StepReport::reuse_error,
                    "Largest measured relative error of those steps where a new factorisation "
                    "was made (0 if none was measured).")
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
      .def(
          "set_state",
          [](SimulatorHandle& h, const py::array_t<double, py::array::c_style | py::array::forcecast>& positions,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& rotations,
             const std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>>& velocities,
             const std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>>& angular_velocities) {
            Simulator& sim = h.simulator();
            const py::ssize_t n = static_cast<py::ssize_t>(sim.state().points.size());
            const py::ssize_t m = static_cast<py::ssize_t>(sim.state().rotations.size());
            const double step = h.scene().scene.model.time_step;
            const auto shaped = [](const auto& a, std::vector<py::ssize_t> shape, const char* name) {
              if (a.ndim() != static_cast<py::ssize_t>(shape.size()) ||
                  !std::equal(shape.begin(), shape.end(), a.shape())) {
                std::string expected;
                for (const py::ssize_t d : shape) expected += (expected.empty() ? "" : "×") + std::to_string(d);
                throw py::value_error(std::string(name) + ": expected an array of shape " + expected);
              }
            };
            shaped(positions, {n, 3}, "positions");
            shaped(rotations, {m, 3, 3}, "rotations");
            if (velocities) shaped(*velocities, {n, 3}, "velocities");
            if (angular_velocities) shaped(*angular_velocities, {m, 3}, "angular_velocities");
            if (h.scene().scene.model.static_equilibrium && (velocities || angular_velocities)) {
              throw py::value_error("velocities: a static scene has none (its states are equilibria)");
            }
            State q = sim.state();
            Step dq = sim.last_step();
            for (py::ssize_t i = 0; i < n; ++i) {
              q.points[i] = Vector3(positions.at(i, 0), positions.at(i, 1), positions.at(i, 2));
              dq.points[i] = velocities ? Vector3(step * Vector3(velocities->at(i, 0), velocities->at(i, 1),
                                                                  velocities->at(i, 2)))
                                        : Vector3::Zero();
              if (!q.points[i].allFinite() || !dq.points[i].allFinite()) {
                throw py::value_error("positions/velocities: row " + std::to_string(i) + " is not finite");
              }
            }
            for (py::ssize_t j = 0; j < m; ++j) {
              Matrix3 R;
              for (int a = 0; a < 3; ++a) {
                for (int b = 0; b < 3; ++b) R(a, b) = rotations.at(j, a, b);
              }
              // The scene's rule for orientations: within 1e-6 of a rotation it is made one,
              // beyond it is refused.
              if (!R.allFinite() || (R.transpose() * R - Matrix3::Identity()).norm() > kQuaternionNormTolerance ||
                  R.determinant() <= 0.0) {
                throw py::value_error("rotations: " + std::to_string(j) +
                                      " is not a rotation matrix (RᵀR = I and det R = 1 within 1e-6)");
              }
              q.rotations[j] = so3::orthonormalize(R);
              Vector3 omega = Vector3::Zero();
              if (angular_velocities) {
                omega = Vector3(angular_velocities->at(j, 0), angular_velocities->at(j, 1),
                                angular_velocities->at(j, 2));
              }
              if (!omega.allFinite() || !(omega.norm() * step < M_PI)) {
                throw py::value_error("angular_velocities: row " + std::to_string(j) +
                                      " turns by π or more per step (|ω| h ≥ π), or is not finite");
              }
              dq.rotations[j] = so3::exp(step * omega);
            }
            h.set_state(q, dq);
          },
          py::arg("positions"), py::arg("rotations"), py::arg("velocities") = py::none(),
          py::arg("angular_velocities") = py::none(),
          "Restarts the run from this state (arrays as positions(), rotations(), velocities(), "
          "angular_velocities(); velocities default to rest) at the current frame: the time "
          "integrator's history starts again from it, as at frame 0, while time and the scene's "
          "schedules go on. Raises ValueError for wrong shapes, non-finite entries, matrices "
          "that are not rotations (within 1e-6) or |ω| h ≥ π.")
      .def_property_readonly("scene", &SimulatorHandle::scene)
      .def_property_readonly("frame", [](const SimulatorHandle& h) { return h.simulator().frame(); })
      .def_property_readonly("time", [](const SimulatorHandle& h) { return h.simulator().time(); })
      .def("positions", [](const SimulatorHandle& h) { return state_array(h, &append_points, {3}); },
           "Every point's position, N×3 (bodies, then rod nodes), m.")
      .def("rotations", [](const SimulatorHandle& h) { return state_array(h, &append_rotations, {3, 3}); },
           "Every rotation matrix, M×3×3 (bodies, then rod edges): body frame to world.")
      .def("quaternions", [](const SimulatorHandle& h) { return state_array(h, &append_quaternions, {4}); },
           "Every rotation as a unit quaternion, M×4, w first (as trajectory.csv).")
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
          // A simulator pickles as its scene, frame and restarts (set_state); unpickling
          // replays them (the simulation is deterministic: the state is bit for bit the same).
          [](const SimulatorHandle& h) {
            py::list restarts;
            for (const auto& r : h.restarts()) restarts.append(py::make_tuple(r.frame, to_numbers(r.state, r.step)));
            return py::make_tuple(h.scene(), h.simulator().frame(), restarts);
          },
          [](const py::tuple& t) {
            SimulatorHandle h(t[0].cast<SceneHandle>());
            std::vector<SimulatorHandle::Restart> restarts;
            for (const py::handle r : t[2].cast<py::list>()) {
              const py::tuple entry = r.cast<py::tuple>();
              SimulatorHandle::Restart restart{entry[0].cast<int>(), h.simulator().state(),
                                               h.simulator().last_step()};
              from_numbers(entry[1].cast<py::tuple>(), restart.state, restart.step);
              restarts.push_back(std::move(restart));
            }
            const int frame = t[1].cast<int>();
            py::gil_scoped_release release;
            h.replay(frame, restarts);
            return h;
          }));

  py::class_<Recording, std::shared_ptr<Recording>>(m, "_Recording",
                                                     "A run's frames as recorded (Trajectory.to_csv).")
      .def("write_csv", &Recording::write_csv, py::arg("scene"), py::arg("out"), py::arg("every") = 1,
           py::call_guard<py::gil_scoped_release>());

  m.def(
      "_simulate",
      [](const SceneHandle& scene, std::optional<std::filesystem::path> out, int every) {
        checked_every(every);
        auto recording = std::make_shared<Recording>();
        SimulationSummary summary;
        {
          py::gil_scoped_release release;
          const FrameObserver observe = [&](const FrameRecord& record) {
            recording->frames.push_back(record);
          };
          if (out) {
            OutputFolder folder(*out, "python simulate " + scene.scene.source, nullptr);
            summary = simulate_into(scene.scene, &folder, nullptr, observe, every);
            folder.commit();  // also after a failed step: its frames are valid
          } else {
            summary = simulate_into(scene.scene, nullptr, nullptr, observe);
          }
        }
        py::dict d = recording->arrays();
        d["recording"] = recording;
        d["failure"] = summary.failed ? py::object(py::str(summary.failure)) : py::object(py::none());
        d["failed_frame"] = summary.failed ? summary.frames_completed + 1 : -1;
        d["solve_seconds"] = summary.solve_seconds;
        return d;
      },
      py::arg("scene"), py::arg("out") = py::none(), py::arg("every") = 1,
      "The command line's run (problems/run.hpp) with every frame recorded (arrays, and the "
      "recording for Trajectory.to_csv); with `out`, trajectory.csv and frames.csv written "
      "there as one unit, as `liedyn simulate --every` writes them. Use liedyn.simulate.");
}

}  // namespace liedyn::python

#include "run.hpp"

#include <chrono>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "../lib/so3.hpp"
#include "shapes.hpp"

namespace liedyn {

void FrameRecord::capture(const Simulator& sim, const StepReport* step_report) {
  frame = sim.frame();
  time = sim.time();
  state.points = sim.state().points;  // assignment keeps the vectors' capacity
  state.rotations = sim.state().rotations;
  if (step_report != nullptr) {
    report = *step_report;
  } else {
    report.reset();
  }
  kinetic_energy = sim.kinetic_energy();
  potential_energy = sim.potential_energy();
  angular_momentum = sim.angular_momentum();
  max_penetration = sim.max_penetration();
  constraint_violation = step_report ? step_report->constraint_violation : sim.constraint_violation();
  contact_pairs = sim.contact_pairs();
  min_rod_separation = sim.has_rod_contact() ? std::optional<double>(sim.min_rod_separation())
                                             : std::nullopt;
}

namespace {
int checked_every(int every) {
  if (every < 1) throw std::invalid_argument("RunFiles: every must be ≥ 1");
  return every;
}
}  // namespace

RunFiles::RunFiles(OutputFolder& out, const Scene& scene, int every)
    : model_(scene.model),
      every_(checked_every(every)),  // before any file is added
      trajectory_(out.add("trajectory.csv")),
      frames_(out.add("frames.csv")) {
  out.add("shapes.json") << scene_shapes(scene, every).dump(1) << '\n';
  trajectory_ << "frame,time,object,kind,index,x,y,z,qw,qx,qy,qz\n";
  frames_ << "frame,time,newton_iterations,gradient_norm,converged,kinetic_energy,"
             "potential_energy,angular_momentum_x,angular_momentum_y,angular_momentum_z,"
             "step_norm,regularized_iterations,status,max_penetration,constraint_violation,"
             "multiplier_updates,contact_pairs,min_rod_separation,assemblies,factorizations,"
             "reused_factorizations,reuse_error\n";
}

void RunFiles::finish(const FrameRecord& last) {
  if (last.frame != last_trajectory_frame_) add_trajectory(last);
}

void RunFiles::add_trajectory(const FrameRecord& r) {
  const Model& model = model_;
  last_trajectory_frame_ = r.frame;
  const std::vector<Vector3>& x = r.state.points;
  const std::vector<Matrix3>& R = r.state.rotations;
  std::ostream& out = trajectory_;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const Eigen::Quaterniond q = so3::to_quaternion(R[i]);
    out << r.frame << ',' << r.time << ',' << csv_field(model.bodies[i].name) << ",body,0," << x[i].x()
        << ',' << x[i].y() << ',' << x[i].z() << ',' << q.w() << ',' << q.x() << ',' << q.y() << ','
        << q.z() << '\n';
  }
  // Rods: one row per node (position only, orientation columns empty), then one row per
  // edge (midpoint and edge frame).
  for (std::size_t r_index = 0; r_index < model.rods.size(); ++r_index) {
    const RodSpec& rod = model.rods[r_index];
    const int k = static_cast<int>(r_index);
    for (int i = 0; i < rod.node_count(); ++i) {
      const Vector3& p = x[model.rod_point(k, i)];
      out << r.frame << ',' << r.time << ',' << csv_field(rod.name) << ",node," << i << ',' << p.x()
          << ',' << p.y() << ',' << p.z() << ",,,,\n";
    }
    for (int j = 0; j < rod.edge_count(); ++j) {
      const Vector3 p = 0.5 * (x[model.rod_point(k, j)] + x[model.rod_point(k, j + 1)]);
      const Eigen::Quaterniond q = so3::to_quaternion(R[model.rod_rotation(k, j)]);
      out << r.frame << ',' << r.time << ',' << csv_field(rod.name) << ",edge," << j << ',' << p.x()
          << ',' << p.y() << ',' << p.z() << ',' << q.w() << ',' << q.x() << ',' << q.y() << ','
          << q.z() << '\n';
    }
  }
}

void RunFiles::add(const FrameRecord& r) {
  if (r.frame % every_ == 0) add_trajectory(r);
  const StepReport* report = r.report ? &*r.report : nullptr;
  const Vector3& L = r.angular_momentum;
  frames_ << r.frame << ',' << r.time << ',';
  if (report != nullptr) {
    frames_ << report->iterations << ',' << report->gradient_norm << ','
            << (report->converged() ? 1 : 0) << ',';
  } else {
    frames_ << "0,0,1,";  // frame 0: the initial state, not a solve
  }
  frames_ << r.kinetic_energy << ',' << r.potential_energy << ',' << L.x() << ',' << L.y() << ','
          << L.z() << ',' << (report ? report->step_norm : 0.0) << ','
          << (report ? report->regularized_iterations : 0) << ','
          << (report ? to_string(report->status) : "initial") << ',' << r.max_penetration << ','
          << r.constraint_violation << ',' << (report ? report->multiplier_updates : 0) << ','
          << r.contact_pairs << ',';
  if (r.min_rod_separation) frames_ << *r.min_rod_separation;  // empty without
  // What the solver spent on the step (solver.hessian_reuse: solves ended on an old
  // factorisation and the measured error of its steps).
  if (report != nullptr) {
    frames_ << ',' << report->assemblies << ',' << report->factorizations << ','
            << report->reused_factorizations << ',' << report->reuse_error << '\n';
  } else {
    frames_ << ",0,0,0,0\n";
  }
}

SimulationSummary simulate_into(const Scene& scene, OutputFolder* out, std::ostream* progress,
                                const FrameObserver& observer, int trajectory_every) {
  using Clock = std::chrono::steady_clock;
  std::optional<RunFiles> files;
  if (out) files.emplace(*out, scene, trajectory_every);
  FrameRecord frame_record;
  const auto record = [&](const Simulator& sim, const StepReport* report) {
    if (!files && !observer) return;
    frame_record.capture(sim, report);
    if (files) files->add(frame_record);
    if (observer) observer(frame_record);
  };

  Simulator sim(scene.model, scene.solver);
  SimulationSummary summary;
  summary.frames_requested = scene.frames;
  summary.initial_energy = sim.kinetic_energy() + sim.potential_energy();
  record(sim, nullptr);

  const auto start = Clock::now();
  auto last_progress = start;
  Clock::duration solving{}, writing{};
  bool progress_shown = false;
  for (int k = 1; k <= scene.frames; ++k) {
    const auto before = Clock::now();
    const StepReport report = sim.step();
    const auto solved = Clock::now();
    solving += solved - before;
    if (!report.state_updated()) {
      summary.failed = true;
      summary.failure =
          step_failure_message(k, scene.model.time_step, scene.solver.backend, report);
      break;
    }
    ++summary.frames_completed;
    summary.total_iterations += report.iterations;
    summary.max_iterations_in_step = std::max(summary.max_iterations_in_step, report.iterations);
    summary.max_gradient_norm = std::max(summary.max_gradient_norm, report.gradient_norm);
    if (!report.converged()) ++summary.unconverged_steps;
    if (report.status == StepStatus::kStalled) ++summary.stalled_steps;
    if (report.regularized_iterations > 0) ++summary.regularized_steps;
    record(sim, &report);

    const auto now = Clock::now();
    writing += now - solved;
    if (progress != nullptr && now - start > std::chrono::seconds(1) &&
        now - last_progress > std::chrono::milliseconds(250)) {
      std::ostringstream line;  // formatted apart so the caller's stream keeps its settings
      line << "\rframe " << k << "/" << scene.frames << " (" << (100LL * k) / scene.frames << "%)";
      *progress << line.str() << std::flush;
      last_progress = now;
      progress_shown = true;
    }
  }
  if (progress_shown) *progress << "\n";
  if (scene.model.static_equilibrium && summary.unconverged_steps > 0) {
    for (const FreeDirection& d : sim.free_directions()) {
      summary.free_directions.push_back(d.describe());
    }
  }
  summary.solve_seconds = std::chrono::duration<double>(solving).count();
  summary.output_seconds = std::chrono::duration<double>(writing).count();
  summary.final_energy = sim.kinetic_energy() + sim.potential_energy();
  if (files) files->finish(frame_record);  // the last frame recorded (the failed step's: none)
  return summary;
}

SimulationSummary simulate_scene(const Scene& scene, const std::filesystem::path& out_dir,
                                 std::ostream* progress, int trajectory_every) {
  OutputFolder out(out_dir, "simulate " + scene.source, progress);
  SimulationSummary summary = simulate_into(scene, &out, progress, nullptr, trajectory_every);
  // Committed even after a failed step: the frames up to it are valid and are kept.
  const auto start = std::chrono::steady_clock::now();
  out.commit();
  summary.output_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

std::string step_failure_message(int k, double time_step, Backend backend,
                                 const StepReport& report) {
  std::ostringstream os;
  os << "step " << k << " (t = " << k * time_step << " s) failed: " << to_string(report.status)
     << " after " << report.iterations << " " << to_string(backend)
     << " iterations, gradient norm " << report.gradient_norm;
  if (!report.message.empty()) os << " (" << report.message << ")";
  return os.str();
}

std::string format_summary(const Scene& scene, const SimulationSummary& s) {
  std::ostringstream os;
  os << "scene        " << scene.source << "\n";
  if (!scene.description.empty()) os << "             " << scene.description << "\n";
  int nodes = 0;
  for (const RodSpec& rod : scene.model.rods) nodes += rod.node_count();
  os << "bodies       " << scene.model.bodies.size() << ", rods " << scene.model.rods.size();
  if (!scene.model.rods.empty()) os << " (" << nodes << " nodes)";
  os << ", h = " << scene.model.time_step
     << " s, " << to_string(scene.solver.backend) << "/" << to_string(scene.solver.rotation)
     << ", tolerance " << scene.solver.tolerance << ", max_iterations "
     << scene.solver.max_iterations << "\n";
  os << "frames       " << s.frames_completed << " of " << s.frames_requested << " solved in "
     << std::setprecision(3) << s.solve_seconds << " s";
  if (s.frames_completed > 0) {
    os << " (" << 1e6 * s.solve_seconds / s.frames_completed << " µs/step)";
  }
  os << "; outputs written in " << s.output_seconds << " s\n";
  os << "iterations   " << s.total_iterations << " (" << to_string(scene.solver.backend)
     << "), "
     << (s.frames_completed ? double(s.total_iterations) / s.frames_completed : 0.0)
     << " per step (max " << s.max_iterations_in_step << ")\n";
  os << "unconverged  " << s.unconverged_steps << " steps did not meet the tolerance";
  if (s.unconverged_steps > 0) {
    os << " (" << s.unconverged_steps - s.stalled_steps << " used up max_iterations, "
       << s.stalled_steps << " stalled with iterations left)";
  }
  os << "\n";
  for (const std::string& d : s.free_directions) os << "cause        " << d << "\n";
  os << "regularized  " << s.regularized_steps << " steps needed a Hessian shift\n";
  os << "energy       " << std::setprecision(6) << s.initial_energy << " -> " << s.final_energy
     << " J\n";
  if (s.failed) os << "FAILED       " << s.failure << "\n";
  return os.str();
}

}  // namespace liedyn

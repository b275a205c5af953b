#include "simulator.hpp"

#include <omp.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include "../lib/so3.hpp"
#include "../lib/stability.hpp"
#include "../lib/trajectory.hpp"

namespace liedyn {

Simulator::Simulator(Model model, const SolverOptions& options)
    : model_(std::move(model)), options_(options) {
  model_.validate();
  options_.validate();
  for (const RodSpec& rod : model_.rods) rods_.push_back(discretize(rod));
  state_ = model_.initial_state();
  initial_ = state_;
  step_ = model_.initial_step();
  if (model_.static_equilibrium) {  // equilibria have no velocities
    for (Vector3& dx : step_.points) dx.setZero();
    for (Matrix3& dR : step_.rotations) dR.setIdentity();
  }
  previous_ = state_;
  previous_step_ = step_;
  step_before_ = step_;
  search_ = ContactSearch(model_);
  touching_.assign(search_.size(), false);
  search_.find(state_, Step{}, touching_);  // nothing has moved yet: no margins
  model_.coupling_key(1, touching_, key_);
  current_ = &islands_at(key_);
}

Simulator::StepIslands& Simulator::islands_at(const std::vector<bool>& key) {
  return islands_.at(key, [&] {
    std::vector<Component> components = build_components(model_, key);
    check_stable_step(model_, components, state_, frame_);
    StepIslands islands;
    for (Component& c : components) islands.solvers.push_back(make_step_solver(std::move(c), options_));
    islands.reports.resize(islands.solvers.size());
    const int count = static_cast<int>(islands.solvers.size());
    int threads = options_.island_threads == 0 ? omp_get_max_threads() : options_.island_threads;
    islands.threads = std::max(1, std::min(threads, count));
    if (options_.backend == Backend::kIpopt) islands.threads = 1;  // see SolverOptions
    return islands;
  });
}

void Simulator::set_state(const State& q, const Step& dq) {
  if (q.points.size() != state_.points.size() || q.rotations.size() != state_.rotations.size() ||
      dq.points.size() != state_.points.size() || dq.rotations.size() != state_.rotations.size()) {
    throw std::invalid_argument("Simulator::set_state: the state or step has other sizes than the model's");
  }
  for (std::size_t i = 0; i < q.points.size(); ++i) {
    if (!q.points[i].allFinite() || !dq.points[i].allFinite()) {
      throw std::invalid_argument("Simulator::set_state: point " + std::to_string(i) + " is not finite");
    }
  }
  for (std::size_t j = 0; j < q.rotations.size(); ++j) {
    for (const Matrix3* R : {&q.rotations[j], &dq.rotations[j]}) {
      if (!R->allFinite() || (R->transpose() * *R - Matrix3::Identity()).norm() > 1e-9 ||
          R->determinant() < 0.0) {
        throw std::invalid_argument("Simulator::set_state: rotation " + std::to_string(j) +
                                    " is not a rotation matrix");
      }
    }
  }
  state_ = q;
  step_ = dq;
  if (model_.static_equilibrium) {
    for (Vector3& x : step_.points) x.setZero();
    for (Matrix3& R : step_.rotations) R.setIdentity();
  }
  step_before_ = step_;
  start_frame_ = frame_;
  // The couplings at the new state, as at the start of a run.
  touching_.assign(search_.size(), false);
  search_.find(state_, Step{}, touching_);
  model_.coupling_key(frame_ + 1, touching_, key_);
  current_ = &islands_at(key_);
}

void Simulator::set_measure_condition(bool on) {
  options_.measure_condition = on;  // for islands built later
  islands_.for_each([&](StepIslands& islands) {
    for (auto& s : islands.solvers) s->set_measure_condition(on);
  });
}

StepReport Simulator::step() {
  previous_ = state_;  // same sizes: copies without allocating
  previous_step_ = step_;
  // Dynamics starts Newton from the extrapolation (x + Δx, ΔR R); a static load step from
  // the previous equilibrium, with the loads of this step.
  const bool dynamic = !model_.static_equilibrium;
  if (dynamic) {
    for (std::size_t i = 0; i < state_.points.size(); ++i) {
      state_.points[i] = previous_.points[i] + step_.points[i];
    }
    for (std::size_t i = 0; i < state_.rotations.size(); ++i) {
      state_.rotations[i] = so3::orthonormalize(step_.rotations[i] * previous_.rotations[i]);
    }
  }
  const double load_scale =
      dynamic ? 1.0 : std::min(1.0, double(frame_ + 1) / double(model_.load_steps));
  apply_prescribed_motions(load_scale);

  // The step's couplings: the joints active at it and the pairs of objects within reach of
  // each other at its start, with margins from the last step (none in static mode: Δq = 0).
  search_.find(state_, step_, touching_);
  saved_key_ = key_;  // same size: no allocation
  StepIslands* const before = current_;
  start_ = state_;
  StepReport report;
  for (int round = 0;; ++round) {
    model_.coupling_key(frame_ + 1, touching_, key_);
    StepIslands& now = islands_at(key_);
    current_ = &now;
    // The islands write disjoint entries of state_ and read previous_ and the model only.
    const auto solve_island = [&](int i) {
      IncrementalPotential& potential = now.solvers[i]->component().potential;
      potential.begin_step(previous_, previous_step_, frame_ + 1, &step_before_, start_frame_);
      if (!dynamic) potential.set_load_scale(load_scale);
      now.reports[i] = now.solvers[i]->solve(state_);
    };
    const int islands = static_cast<int>(now.solvers.size());
    if (now.threads > 1) {
#pragma omp parallel for num_threads(now.threads) schedule(dynamic)
      for (int i = 0; i < islands; ++i) solve_island(i);
    } else {  // no parallel region at all: even an inactive one allocates in libgomp
      for (int i = 0; i < islands; ++i) solve_island(i);
    }
    // A round's report, added to the earlier rounds' (their states are discarded, their work
    // is not).
    StepReport solved;
    for (const StepReport& r : now.reports) solved.merge(r);
    report.accumulate(std::move(solved));
    if (!report.state_updated()) break;
    // Two bodies that reached each other only within the step: solve it again with them
    // coupled, from the same start (a few rounds at most: each adds pairs).
    if (round == kMaxContactRounds || !search_.add_penetrating(state_, touching_)) break;
    state_ = start_;
  }

  if (!report.state_updated()) {
    state_ = previous_;
    key_ = saved_key_;
    current_ = before;  // the islands of the state kept
    return report;
  }
  // The step; a static sequence of equilibria has none (zero velocities and kinetic energy).
  // Δq_{k−1} becomes the step before the next one's previous step (previous_step_ is set
  // again at the next step's start: a swap, not a copy).
  std::swap(step_before_, previous_step_);
  for (std::size_t i = 0; i < state_.points.size(); ++i) {
    step_.points[i] = dynamic ? Vector3(state_.points[i] - previous_.points[i]) : Vector3::Zero();
  }
  for (std::size_t i = 0; i < state_.rotations.size(); ++i) {
    step_.rotations[i] =
        dynamic ? rotation_step(state_.rotations[i], previous_.rotations[i]) : Matrix3::Identity();
  }
  ++frame_;
  return report;
}

void Simulator::apply_prescribed_motions(double load_scale) {
  for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
    const RigidBody& b = model_.bodies[i];
    if (!b.kinematic) continue;
    const double time = model_.static_equilibrium ? load_scale * b.kinematic->duration() : (frame_ + 1) * model_.time_step;
    b.kinematic->pose(time, initial_.points[i], initial_.rotations[i], state_.points[i], state_.rotations[i]);
  }
  for (std::size_t r = 0; r < model_.rods.size(); ++r) {
    const int rod = static_cast<int>(r);
    for (const PrescribedMotion& motion : model_.rods[r].prescribed_motions) {
      const double time = model_.static_equilibrium ? load_scale * motion.duration()
                                                    : (frame_ + 1) * model_.time_step;
      const RigidTransform T = motion.at(time);
      for (int node : motion.nodes) {
        const int i = model_.rod_point(rod, node);
        state_.points[i] = motion.move_point(T, initial_.points[i]);
      }
      for (int edge : motion.edges) {
        const int j = model_.rod_rotation(rod, edge);
        state_.rotations[j] = so3::orthonormalize(T.rotation * initial_.rotations[j]);
      }
    }
  }
}

Vector3 Simulator::linear_velocity(int point) const {
  return step_.points[point] / model_.time_step;
}

Vector3 Simulator::angular_velocity(int rotation) const {
  return so3::log(step_.rotations[rotation]) / model_.time_step;
}

double Simulator::kinetic_energy() const {
  double energy = 0.0;
  for_each_mass([&](int point, double mass, int rotation, const Matrix3& inertia) {
    if (point >= 0) energy += 0.5 * mass * linear_velocity(point).squaredNorm();
    if (rotation >= 0) {
      const Matrix3& R = state_.rotations[rotation];
      const Vector3 w = angular_velocity(rotation);
      energy += 0.5 * w.dot(R * inertia * R.transpose() * w);
    }
  });
  return energy;
}

double Simulator::potential_energy() const {
  double energy = 0.0;
  for (const auto& s : current_->solvers) energy += s->component().potential.potential_energy(state_);
  return energy;
}

double Simulator::max_penetration() const {
  double deepest = 0.0;
  for (const auto& s : current_->solvers) {
    deepest = std::max(deepest, s->component().potential.max_penetration(state_));
  }
  return deepest;
}

int Simulator::contact_pairs() const {
  int pairs = search_.penetrating(state_);
  // A point at p touches collider c when it is within ρ of it.
  const auto inside = [&](const Collider& c, const ContactMaterial& m, const Vector3& p) {
    return m.touches(c.name) && m.radius - c.evaluate(p, false).distance > 0.0;
  };
  for (const Collider& c : model_.colliders) {
    for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
      const RigidBody& b = model_.bodies[i];
      if (!b.contact.enabled() || b.kinematic) continue;  // no terms: it moves nothing
      pairs += std::any_of(b.contact_points.begin(), b.contact_points.end(), [&](const Vector3& s) {
        return inside(c, b.contact, state_.points[i] + state_.rotations[i] * s);
      });
    }
    for (std::size_t r = 0; r < model_.rods.size(); ++r) {
      const RodSpec& rod = model_.rods[r];
      if (!rod.contact.enabled()) continue;
      bool touching = false;
      for (int n = 0; n < rod.node_count() && !touching; ++n) {
        const bool clamped = std::find(rod.fixed_nodes.begin(), rod.fixed_nodes.end(), n) != rod.fixed_nodes.end();
        touching = !clamped && inside(c, rod.contact, state_.points[model_.rod_point(static_cast<int>(r), n)]);
      }
      pairs += touching;
    }
  }
  return pairs;
}

double Simulator::constraint_violation() const {
  double violation = 0.0;
  for (const auto& s : current_->solvers) {
    violation = std::max(violation, s->component().potential.constraint_violation(state_));
  }
  return violation;
}

void Simulator::exact_forces(std::vector<Vector3>& out) const {
  out.clear();
  for (const auto& s : current_->solvers) s->component().potential.exact_forces(state_, out);
}

std::vector<FreeDirection> Simulator::free_directions() const {
  std::vector<FreeDirection> out;
  for (const auto& s : current_->solvers) {
    const std::vector<FreeDirection> free = liedyn::free_directions(model_, s->component(), state_);
    out.insert(out.end(), free.begin(), free.end());
  }
  return out;
}

Vector3 Simulator::angular_momentum() const {
  Vector3 L = Vector3::Zero();
  for_each_mass([&](int point, double mass, int rotation, const Matrix3& inertia) {
    if (point >= 0) L += mass * state_.points[point].cross(linear_velocity(point));
    if (rotation >= 0) {
      const Matrix3& R = state_.rotations[rotation];
      L += R * inertia * R.transpose() * angular_velocity(rotation);
    }
  });
  return L;
}

template <class Function>
void Simulator::for_each_mass(Function&& f) const {
  const Matrix3 none = Matrix3::Zero();
  for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
    if (model_.bodies[i].kinematic) continue;  // driven: not part of the system's energy or momentum
    const int index = static_cast<int>(i);
    f(index, model_.bodies[i].mass, index, model_.bodies[i].inertia);
  }
  for (std::size_t r = 0; r < model_.rods.size(); ++r) {
    const RodDiscretization& d = rods_[r];
    const int rod = static_cast<int>(r);
    for (std::size_t i = 0; i < d.node_mass.size(); ++i) {
      f(model_.rod_point(rod, static_cast<int>(i)), d.node_mass[i], -1, none);
    }
    for (std::size_t j = 0; j < d.edge_inertia.size(); ++j) {
      f(-1, 0.0, model_.rod_rotation(rod, static_cast<int>(j)), d.edge_inertia[j]);
    }
  }
}

}  // namespace liedyn

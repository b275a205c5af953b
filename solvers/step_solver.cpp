#include "step_solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <initializer_list>
#include <numbers>
#include <string>

#include "../lib/so3.hpp"
#include "ceres_step.hpp"
#include "ipopt_step.hpp"
#include "newton.hpp"

namespace liedyn {

void SolverOptions::validate() const {
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) {
    throw ModelError("solver.tolerance", "must be a finite positive number");
  }
  if (max_iterations < 1) throw ModelError("solver.max_iterations", "must be at least 1");
  if (hessian_reuse < 1) {
    throw ModelError("solver.hessian_reuse", "must be at least 1 (1: a new factorisation at every step)");
  }
  // Chord steps end a solve on an old factorisation's step; "assembled" asks that every verdict
  // be made on a new one. Honouring both would factorise at every solve and gain nothing.
  if (hessian_reuse > 1 && convergence_check == ConvergenceCheck::kAssembled) {
    throw ModelError("solver.hessian_reuse",
                     "must be 1 with convergence_check \"assembled\" (chord steps end solves on "
                     "an old factorisation, which that check rules out)");
  }
  if (!(armijo > 0.0 && armijo < 0.5)) throw ModelError("solver.armijo", "must be in (0, 0.5)");
  if (!(min_step_length > 0.0 && min_step_length < 1.0)) {
    throw ModelError("solver.min_step_length", "must be in (0, 1)");
  }
  if (assembly_threads < 0 || assembly_threads > kMaxAssemblyThreads) {
    throw ModelError("solver.assembly_threads",
                     "must be in [0, " + std::to_string(kMaxAssemblyThreads) + "] (0: automatic)");
  }
  if (island_threads < 0 || island_threads > kMaxAssemblyThreads) {
    throw ModelError("solver.island_threads",
                     "must be in [0, " + std::to_string(kMaxAssemblyThreads) + "] (0: automatic)");
  }
  const auto one_of = [](const std::string& value, std::initializer_list<const char*> names) {
    for (const char* name : names) {
      if (value == name) return true;
    }
    return false;
  };
  if (!one_of(ceres.linear_solver,
              {"auto", "dense_qr", "dense_normal_cholesky", "sparse_normal_cholesky"})) {
    throw ModelError("solver.ceres.linear_solver",
                     "unknown linear solver \"" + ceres.linear_solver +
                         "\" (expected auto, dense_qr, dense_normal_cholesky or "
                         "sparse_normal_cholesky)");
  }
  if (!one_of(ceres.trust_region_strategy, {"levenberg_marquardt", "dogleg"})) {
    throw ModelError("solver.ceres.trust_region_strategy",
                     "unknown strategy \"" + ceres.trust_region_strategy +
                         "\" (expected levenberg_marquardt or dogleg)");
  }
  if (!one_of(ceres.lie_blocks, {"chart", "manifold"})) {
    throw ModelError("solver.ceres.lie_blocks",
                     "unknown rotation blocks \"" + ceres.lie_blocks + "\" (expected chart or manifold)");
  }
  if (!one_of(ipopt.hessian_approximation, {"exact", "limited-memory"})) {
    throw ModelError("solver.ipopt.hessian_approximation",
                     "unknown approximation \"" + ipopt.hessian_approximation +
                         "\" (expected exact or limited-memory)");
  }
  if (ipopt.print_level < 0 || ipopt.print_level > 12) {
    throw ModelError("solver.ipopt.print_level", "must be in [0, 12]");
  }
  if (!one_of(ipopt.derivative_test, {"none", "first-order", "second-order"})) {
    throw ModelError("solver.ipopt.derivative_test",
                     "unknown test \"" + ipopt.derivative_test +
                         "\" (expected none, first-order or second-order)");
  }
  if (ipopt.max_recentrings < 0) {
    throw ModelError("solver.ipopt.max_recentrings", "must be at least 0");
  }
}

const char* to_string(Backend backend) {
  switch (backend) {
    case Backend::kNewton: return "newton";
    case Backend::kCeres: return "ceres";
    case Backend::kIpopt: return "ipopt";
  }
  return "unknown";
}

std::optional<Backend> parse_backend(std::string_view name) {
  for (const auto b : {Backend::kNewton, Backend::kCeres, Backend::kIpopt}) {
    if (name == to_string(b)) return b;
  }
  return std::nullopt;
}

const char* to_string(RotationParameterization rotation) {
  switch (rotation) {
    case RotationParameterization::kLie: return "lie";
    case RotationParameterization::kRotationVector: return "rotvec";
    case RotationParameterization::kQuaternion: return "quat";
  }
  return "unknown";
}

std::optional<RotationParameterization> parse_rotation(std::string_view name) {
  for (const auto r : {RotationParameterization::kLie, RotationParameterization::kRotationVector,
                       RotationParameterization::kQuaternion}) {
    if (name == to_string(r)) return r;
  }
  return std::nullopt;
}

const char* to_string(ConvergenceCheck check) {
  switch (check) {
    case ConvergenceCheck::kEstimated: return "estimated";
    case ConvergenceCheck::kAssembled: return "assembled";
  }
  return "unknown";
}

std::optional<ConvergenceCheck> parse_convergence_check(std::string_view name) {
  for (const auto c : {ConvergenceCheck::kEstimated, ConvergenceCheck::kAssembled}) {
    if (name == to_string(c)) return c;
  }
  return std::nullopt;
}

const char* to_string(StepStatus status) {
  switch (status) {
    case StepStatus::kConverged: return "converged";
    case StepStatus::kMaxIterations: return "max_iterations";
    case StepStatus::kStalled: return "stalled";
    case StepStatus::kLineSearchFailed: return "line_search_failed";
    case StepStatus::kNonFinite: return "non_finite";
    case StepStatus::kSolverFailed: return "solver_failed";
  }
  return "unknown";
}

void StepReport::merge(const StepReport& other) {
  // The worst status wins; iterations are the slowest component's (they are independent).
  if (static_cast<int>(other.status) > static_cast<int>(status)) status = other.status;
  iterations = std::max(iterations, other.iterations);
  regularized_iterations = std::max(regularized_iterations, other.regularized_iterations);
  factorizations += other.factorizations;
  assemblies += other.assemblies;
  assembly_seconds += other.assembly_seconds;
  solve_seconds += other.solve_seconds;
  gradient_norm = std::hypot(gradient_norm, other.gradient_norm);
  step_norm = std::max(step_norm, other.step_norm);
  // std::fmax ignores a NaN operand: a component without the figure does not erase another's.
  first_gradient_norm = std::fmax(first_gradient_norm, other.first_gradient_norm);
  second_gradient_norm = std::fmax(second_gradient_norm, other.second_gradient_norm);
  first_hessian_condition = std::fmax(first_hessian_condition, other.first_hessian_condition);
  psi += other.psi;
  constraint_violation = std::max(constraint_violation, other.constraint_violation);
  multiplier_updates = std::max(multiplier_updates, other.multiplier_updates);
  history_updates = std::max(history_updates, other.history_updates);
  history_moved = std::max(history_moved, other.history_moved);
  reused_factorizations += other.reused_factorizations;
  reuse_error = std::max(reuse_error, other.reuse_error);
  if (!other.message.empty()) message += (message.empty() ? "" : "; ") + other.message;
}

void StepReport::accumulate(StepReport next) {
  next.iterations += iterations;
  next.regularized_iterations += regularized_iterations;
  next.factorizations += factorizations;
  next.assemblies += assemblies;
  next.assembly_seconds += assembly_seconds;
  next.solve_seconds += solve_seconds;
  const auto earliest = [](double mine, double theirs) { return std::isnan(mine) ? theirs : mine; };
  next.first_gradient_norm = earliest(first_gradient_norm, next.first_gradient_norm);
  next.second_gradient_norm = earliest(second_gradient_norm, next.second_gradient_norm);
  next.first_hessian_condition = earliest(first_hessian_condition, next.first_hessian_condition);
  // The loops' counters (StepSolver::solve counts its updates into the step's report).
  next.multiplier_updates += multiplier_updates;
  next.history_updates += history_updates;
  next.history_moved = std::max(next.history_moved, history_moved);
  next.reused_factorizations += reused_factorizations;
  next.reuse_error = std::max(next.reuse_error, reuse_error);
  *this = std::move(next);
}

std::string short_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

StepReport StepSolver::solve(State& q) {
  const Component& c = component();
  if (!sized_) {
    entry_ = ComponentSnapshot(c);
    returned_ = ComponentSnapshot(c);
    // The component's block of each inertia term (−1 if none: nothing to test).
    const auto block_of = [](const std::vector<DofBlock>& blocks, int index) {
      for (std::size_t i = 0; i < blocks.size(); ++i) {
        if (blocks[i].index == index) return static_cast<int>(i);
      }
      return -1;
    };
    for (const TranslationalInertia& t : c.potential.terms<TranslationalInertia>()) {
      inertia_point_.push_back(block_of(c.points, t.point));
    }
    for (const RotationalInertia& t : c.potential.terms<RotationalInertia>()) {
      inertia_rotation_.push_back(block_of(c.rotations, t.rotation));
      // A rotation's step angle is at most π, so its kinetic energy ½ θᵀ I_b θ/h² is at most
      // π² tr(J/h²) (I_b/h² is PSD with trace 2 tr(J/h²)); J/h² is fixed with the terms.
      if (inertia_rotation_.back() >= 0) {
        rotation_energy_bound_ += std::numbers::pi * std::numbers::pi * t.J_over_h2.trace();
      }
    }
    has_exact_constraints_ = c.potential.exact_constraints() > 0;  // fixed with the terms
    sized_ = true;
  }
  entry_.save(c, q);
  StepReport report = minimize(q);
  IncrementalPotential& P = component().potential;
  for (;;) {
    if (report.state_updated() && has_exact_constraints_) enforce_exact_constraints(q, report);
    if (!report.state_updated() || !P.has_rotation_history()) break;
    // The trapezoidal integrator's torque fields are exact where their reference is
    // (lib/history.hpp): solve again from the new reference until it no longer moves.
    const double moved = P.history_reference_distance(q);
    P.rereference_history(q);
    report.history_moved = moved;
    if (moved <= tolerance_) break;
    if (report.history_updates == kMaxHistoryUpdates) {
      if (report.converged()) report.status = StepStatus::kMaxIterations;
      const std::string message = "trapezoidal history: the torque fields' reference still moved " +
                                  short_number(moved) + " rad > tolerance after " +
                                  std::to_string(kMaxHistoryUpdates) + " updates";
      report.message = report.message.empty() ? message : message + "; " + report.message;
      break;
    }
    report.accumulate(minimize(q));
    ++report.history_updates;
  }
  if (!report.state_updated()) {
    entry_.restore(c, q);
    return report;
  }
  if (const char* what = non_finite_value(report, q)) {
    entry_.restore(c, q);
    std::string message = std::string("not finite at the end of the step: ") + what +
                          " (the back-end reported " + to_string(report.status) + ")";
    if (!report.message.empty()) message += "; " + report.message;
    report.message = std::move(message);
    report.status = StepStatus::kNonFinite;
    return report;
  }
  returned_.save(c, q);
  has_returned_ = true;
  return report;
}

void StepSolver::enforce_exact_constraints(State& q, StepReport& report) {
  IncrementalPotential& P = component().potential;
  double violation = P.constraint_violation(q);
  double previous = std::numeric_limits<double>::infinity();
  while (violation > tolerance_ && report.multiplier_updates < kMaxMultiplierUpdates) {
    if (!(violation <= 0.1 * previous) && penalty_growth_ < kMaxPenaltyGrowth) {
      P.scale_penalties(10.0);
      penalty_growth_ *= 10.0;
    }
    previous = violation;
    P.update_multipliers(q);
    report.accumulate(minimize(q));
    ++report.multiplier_updates;
    if (!report.state_updated()) return;
    violation = P.constraint_violation(q);
  }
  report.constraint_violation = violation;
  if (violation > tolerance_) {
    if (report.converged()) report.status = StepStatus::kMaxIterations;
    const std::string message = "exact joints: largest violation " + short_number(violation) +
                                " > tolerance after " + std::to_string(report.multiplier_updates) +
                                " multiplier updates";
    report.message = report.message.empty() ? message : message + "; " + report.message;
  }
}

const char* StepSolver::non_finite_value(const StepReport& report, const State& q) const {
  const Component& c = component();
  // A NaN or Inf entry makes a sum non-finite (so does an overflow of the sum, whose
  // entries are then too large to be of use); one sum per block is cheaper than a test of
  // every entry.
  for (const DofBlock& b : c.points) {
    if (!std::isfinite(q.points[b.index].sum())) return "position";
  }
  for (const DofBlock& b : c.rotations) {
    if (!std::isfinite(q.rotations[b.index].sum())) return "rotation";
  }
  if (!std::isfinite(report.psi)) return "Psi (the incremental potential)";
  if (!std::isfinite(report.gradient_norm)) return "gradient norm";
  if (!std::isfinite(report.step_norm)) return "Newton step";
  if (!has_returned_) return nullptr;
  double kinetic = 0.0;
  const IncrementalPotential& P = c.potential;
  const auto& translational = P.terms<TranslationalInertia>();
  const auto& rotational = P.terms<RotationalInertia>();
  for (std::size_t t = 0; t < translational.size(); ++t) {
    const int i = inertia_point_[t];
    if (i < 0) continue;
    const Vector3 dx = q.points[c.points[i].index] - returned_.point(i);
    kinetic += 0.5 * translational[t].mass_over_h2 * dx.squaredNorm();
  }
  // Where the rotations' bound (rotation_energy_bound_, set with the blocks) leaves the sum
  // finite, so is the sum, and the logarithms below (the check's main cost) are not needed.
  if (std::isfinite(kinetic + rotation_energy_bound_)) return nullptr;
  for (std::size_t t = 0; t < rotational.size(); ++t) {
    const int i = inertia_rotation_[t];
    if (i < 0) continue;
    const Matrix3& R = q.rotations[c.rotations[i].index];
    // Body-frame rotation of the step: θ_b = log(Rₚᵀ R), and I_b/h² = tr(J/h²) 1 − J/h²
    // from J = ½ tr(I_b) 1 − I_b (lib/inertia.hpp).
    const Vector3 theta = so3::log(returned_.rotation(i).transpose() * R);
    const Matrix3& J = rotational[t].J_over_h2;
    const Matrix3 I = J.trace() * Matrix3::Identity() - J;
    kinetic += 0.5 * theta.dot(I * theta);
  }
  if (!std::isfinite(kinetic)) return "kinetic energy of the step";
  return nullptr;
}

std::unique_ptr<StepSolver> make_step_solver(Component component, const SolverOptions& options) {
  switch (options.backend) {
    case Backend::kNewton: return make_newton(std::move(component), options);
    case Backend::kCeres: return make_ceres_step_solver(std::move(component), options);
    case Backend::kIpopt: return make_ipopt_step_solver(std::move(component), options);
  }
  throw std::logic_error("make_step_solver: unknown back-end");
}

}  // namespace liedyn

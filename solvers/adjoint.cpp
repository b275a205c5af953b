#include "adjoint.hpp"

#include <Eigen/QR>
#include <chrono>
#include <cmath>
#include <memory>
#include <utility>

#include "linear_system.hpp"
#include "simulator.hpp"

namespace liedyn {

namespace {

using Clock = std::chrono::steady_clock;

// The trapezoidal adjoint's fixed point (backward, on CHOLMOD's symmetric factorisation):
// relative change at which it stops, and the rounds it may take (each one solve with H's
// factorisation).
constexpr double kSkewTolerance = 1e-13;
constexpr int kMaxSkewIterations = 200;

// The step's Jacobian of one component, factorised, and solves with its transpose (the linear
// system the forward Newton solver would pick for the component's size): H_k, or under the
// trapezoidal integrator H_k + K where the system factorises it (linear_system.hpp).
class HessianSolve {
 public:
  virtual ~HessianSolve() = default;
  // Assembles the exact Lie Hessian at q and factorises it, with K if the potential has one
  // and the system can (includes_skew()); false if not positive definite (with K: a pivot
  // that is not positive).
  virtual bool factorize(const IncrementalPotential& potential, const State& q) = 0;
  virtual bool includes_skew() const = 0;
  // x = H⁻¹ b, or (H + K)⁻ᵀ b = (H − K)⁻¹ b.
  virtual void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) = 0;
};

template <class System>
class SystemSolve final : public HessianSolve {
 public:
  explicit SystemSolve(const Component& c) : system_(c) {}
  bool factorize(const IncrementalPotential& potential, const State& q) override {
    system_.assemble(potential, q, nullptr);
    skew_ = potential.has_rotation_history() && system_.can_factorize_skew();
    if (skew_) system_.set_history_skew(&potential);
    return system_.hessian_finite() && system_.factorize(0.0);
  }
  bool includes_skew() const override { return skew_; }
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) override {
    b_ = b;
    system_.solve_linear_transposed(b_, x_);
    x = x_;
  }

 private:
  System system_;
  typename System::Vector b_, x_;
  bool skew_ = false;
};

std::unique_ptr<HessianSolve> make_hessian_solve(const Component& c) {
  if (c.dofs == 6) return std::make_unique<SystemSolve<DenseSystem<6>>>(c);
  if (c.dofs <= kDenseLimit) return std::make_unique<SystemSolve<DenseSystem<Eigen::Dynamic>>>(c);
  return std::make_unique<SystemSolve<SparseSystem>>(c);
}

}  // namespace

SimulationFailed::SimulationFailed(int frame, const std::string& reason)
    : std::runtime_error("frame " + std::to_string(frame) + ": " + reason), frame_(frame) {}

DifferentiableSimulation::DifferentiableSimulation(Model base, ParameterSet parameters,
                                                   Objective objective, SolverOptions options)
    : base_(std::move(base)),
      parameters_(std::move(parameters)),
      objective_(std::move(objective)),
      options_(options) {
  options_.validate();
  parameters_.apply(base_, initial_parameters()).validate();
}

Trajectory DifferentiableSimulation::simulate(const Model& model, Result& result) const {
  Simulator simulator(model, options_);
  Trajectory t;
  t.time_step = model.time_step;
  t.static_equilibrium = model.static_equilibrium;
  t.initial_step = simulator.last_step();
  t.states.reserve(frames() + 1);
  t.states.push_back(simulator.state());
  for (int k = 1; k <= frames(); ++k) {
    const StepReport report = simulator.step();
    result.iterations += report.iterations;
    if (!report.converged()) {
      throw SimulationFailed(k, std::string("the forward step did not converge (") +
                                    to_string(report.status) +
                                    (report.message.empty() ? "" : ": " + report.message) +
                                    "), so the adjoint gradient would not be exact");
    }
    t.states.push_back(simulator.state());
    if (k == 1) t.multipliers.resize(static_cast<std::size_t>(frames()) + 1);
    simulator.exact_forces(t.multipliers[k]);
    if (k == 1) t.couplings.resize(static_cast<std::size_t>(frames()) + 1);
    t.couplings[k] = simulator.coupling_key();
  }
  return t;
}

DifferentiableSimulation::Result DifferentiableSimulation::evaluate(const Eigen::VectorXd& gamma,
                                                                    Eigen::VectorXd* gradient) const {
  if (gamma.size() != parameters_.size()) {
    throw std::invalid_argument("DifferentiableSimulation::evaluate: γ has " +
                                std::to_string(gamma.size()) + " entries, the parameters " +
                                std::to_string(parameters_.size()));
  }
  const Model model = parameters_.apply(base_, gamma);
  Result result;
  const Clock::time_point start = Clock::now();
  result.trajectory = simulate(model, result);
  result.loss = objective_.value(result.trajectory, gamma);
  result.forward_seconds = seconds_since(start);
  if (gradient != nullptr) {
    const Clock::time_point backward_start = Clock::now();
    backward(model, gamma, result.trajectory, *gradient);
    result.backward_seconds = seconds_since(backward_start);
  }
  return result;
}

void DifferentiableSimulation::backward(const Model& model, const Eigen::VectorXd& gamma,
                                        const Trajectory& trajectory,
                                        Eigen::VectorXd& gradient) const {
  // Per set of islands (solvers/islands.hpp; the forward run's, step by step, from the
  // couplings it recorded — its joints and its bodies in contact): a Hessian
  // solve per component, and its exact joint terms with the first one's place in a frame's
  // multipliers (Trajectory::multipliers, in the same component order).
  struct Islands {
    std::vector<Component> components;
    std::vector<std::unique_ptr<HessianSolve>> solves;
    std::vector<int> exact_terms, first_exact;
  };
  IslandCache<Islands> cache;
  const auto make = [](std::vector<Component> components) {
    Islands islands;
    int exact_total = 0;
    for (const Component& c : components) {
      islands.solves.push_back(make_hessian_solve(c));
      islands.exact_terms.push_back(c.potential.exact_constraints());
      islands.first_exact.push_back(exact_total);
      exact_total += islands.exact_terms.back();
    }
    islands.components = std::move(components);
    return islands;
  };
  Eigen::MatrixXd J, Y;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> JY;
  Eigen::VectorXd column, z0, kz, dz;

  const int n = trajectory.frames();
  const int size = tangent_size(trajectory.states[0]);
  gradient = Eigen::VectorXd::Zero(parameters_.size());
  Eigen::VectorXd a = Eigen::VectorXd::Zero(size), da = Eigen::VectorXd::Zero(size);
  // da_before: (∂C_{k+1}/∂Δq_{k−1})ᵀ z_{k+1}, BDF2's read of the step before its previous one,
  // which joins Δa_{k−1} one step later.
  Eigen::VectorXd a_previous(size), da_previous(size), da_before = Eigen::VectorXd::Zero(size);
  Eigen::VectorXd rhs, b, z;
  objective_.add_state_gradient(trajectory, n, a, da);
  const bool dynamic = !trajectory.static_equilibrium;
  // Δq_k, Δq_{k−1} and Δq_{k−2} (BDF2's; frame 1: Δq_0), each built once and passed down.
  Step step = trajectory.step(n);
  Step previous_step = trajectory.step(n - 1);
  Step step_before;
  for (int k = n; k >= 1; --k) {
    const State& q = trajectory.states[k];
    const State& previous = trajectory.states[k - 1];
    step_before = trajectory.step(std::max(k - 2, 0));
    rhs = a + da;  // ∂f_k/∂q_k = I
    a_previous.setZero();
    da_previous.setZero();
    da_previous.swap(da_before);
    objective_.add_state_gradient(trajectory, k - 1, a_previous, da_previous);
    if (dynamic) {  // (∂f_k/∂q_{k−1})ᵀ Δa_k: −I for points, −ΔR_kᵀ for rotations
      for (std::size_t i = 0; i < q.points.size(); ++i) {
        const int o = tangent_point(static_cast<int>(i));
        a_previous.segment<3>(o) -= da.segment<3>(o);
      }
      for (std::size_t j = 0; j < q.rotations.size(); ++j) {
        const int o = tangent_rotation(q, static_cast<int>(j));
        a_previous.segment<3>(o) -= step.rotations[j].transpose() * da.segment<3>(o);
      }
    }
    const double load_scale =
        dynamic ? 1.0 : std::min(1.0, double(k) / double(model.load_steps));
    const std::vector<bool>& key = trajectory.couplings[k];
    Islands& islands = cache.at(key, [&] { return make(build_components(model, key)); });
    std::vector<Component>& components = islands.components;
    const std::vector<std::unique_ptr<HessianSolve>>& solves = islands.solves;
    const std::vector<int>& exact_terms = islands.exact_terms;
    const std::vector<int>& first_exact = islands.first_exact;
    for (std::size_t c = 0; c < components.size(); ++c) {
      IncrementalPotential& potential = components[c].potential;
      potential.begin_step(previous, previous_step, k, &step_before);
      // Trapezoidal: the history's Hessian vanishes at its reference (lib/history.hpp).
      potential.rereference_history(q);
      if (!dynamic) potential.set_load_scale(load_scale);
      const int exact = exact_terms[c];
      if (exact > 0) {
        potential.set_adjoint_multipliers(trajectory.multipliers[k].data() + first_exact[c]);
      }
      HessianSolve& solve = *solves[c];
      if (!solve.factorize(potential, q)) {
        throw SimulationFailed(k, "the Hessian of the converged step is not positive definite "
                                  "(not a strict minimum): the adjoint is not defined");
      }
      if (exact > 0) {
        // Exact joints: [M Jᵀ; J 0] [z; μ] = [b; 0] with M = K + ρJᵀJ the assembled
        // Lagrangian Hessian (docs/design.md §8.6; transposed with the trapezoidal history's
        // skew part where the factorisation holds it): z = z₀ − Y μ, Y = M⁻¹Jᵀ, (J Y) μ = J z₀.
        // J Y is singular for a hinge (its 3 rows hold 2 constraints): the least-squares μ
        // of a consistent system.
        J.resize(3 * exact, components[c].dofs);
        potential.constraint_jacobian(q, J);
        Y.resize(components[c].dofs, 3 * exact);
        for (int i = 0; i < 3 * exact; ++i) {
          solve.solve(J.row(i).transpose(), column);
          Y.col(i) = column;
        }
        JY.compute(J * Y);
      }
      // x = M⁻¹ b on the constraints' tangent space (the bordered solve above, or H⁻¹ b).
      const auto solve_step = [&](const Eigen::VectorXd& rhs_c, Eigen::VectorXd& x) {
        solve.solve(rhs_c, x);
        if (exact > 0) x -= Y * JY.solve(Eigen::VectorXd(J * x));
      };
      b.resize(components[c].dofs);
      for (const DofBlock& p : components[c].points) {
        b.segment<3>(p.offset) = -rhs.segment<3>(tangent_point(p.index));
      }
      for (const DofBlock& r : components[c].rotations) {
        b.segment<3>(r.offset) = -rhs.segment<3>(tangent_rotation(q, r.index));
      }
      // Trapezoidal: the step's Jacobian is H + K with K = ½ hat(c) skew
      // (IncrementalPotential::history_skew), so the adjoint solves (H + K)ᵀ z = (H − K) z = b:
      // directly where the factorisation holds K, else (CHOLMOD) by the fixed point below.
      solve_step(b, z);  // (H − K) z = −(a + Δa), or H z = −(a + Δa)
      if (potential.has_rotation_history() && !solve.includes_skew()) {
        // The fixed point z ← z₀ + H⁻¹ K z on H's factorisation. It contracts by ‖H⁻¹K‖, as
        // the forward step's re-solves did (design §14.1).
        z0 = z;
        double change = 0.0;
        for (int i = 0;; ++i) {
          potential.history_skew(z, kz);
          solve_step(kz, dz);
          change = (z0 + dz - z).lpNorm<Eigen::Infinity>();
          z = z0 + dz;
          if (change <= kSkewTolerance * z.lpNorm<Eigen::Infinity>()) break;
          if (i == kMaxSkewIterations || !std::isfinite(change)) {
            throw SimulationFailed(
                k, "the adjoint's fixed point on the history's skew part did not converge in " +
                       std::to_string(kMaxSkewIterations) + " rounds (last change " +
                       std::to_string(change) + "): ‖H⁻¹K‖ is not small at this step");
          }
        }
      }
      potential.add_parameter_adjoint(q, k, z, gradient);
      potential.add_step_adjoint(q, previous, previous_step, z, a_previous, da_previous);
      potential.add_history_adjoint(q, previous, previous_step, step_before, k, z, a_previous,
                                    da_previous, da_before, gradient);
    }
    a.swap(a_previous);
    da.swap(da_previous);
    std::swap(step, previous_step);
    std::swap(previous_step, step_before);
  }
  parameters_.add_initial_gradient(model, gamma, a, da, gradient);
  objective_.add_parameter_gradient(gamma, gradient);
}

}  // namespace liedyn

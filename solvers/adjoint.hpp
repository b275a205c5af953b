#pragma once
// Differentiable simulation: the loss g({q_k}, γ) of a forward simulation and its exact
// gradient dg/dγ by the adjoint method in the state + step formulation (paper §5, appendix
// D; docs/design.md §8). With C_k = ∇Ψ_k (the Lie gradient of step k's incremental potential):
//
//   a_n = ∂g/∂q_n,  Δa_n = ∂g/∂Δq_n
//   for k = n … 1:
//     H_k z_k = −(a_k + Δa_k)                       H_k: exact Lie Hessian at q_k  (paper §5.3)
//     dg/dγ   += (∂C_k/∂γ)ᵀ z_k                                                         (21)
//     a_{k−1}  = ∂g/∂q_{k−1} + (∂C_k/∂q_{k−1})ᵀ z_k + (∂f_k/∂q_{k−1})ᵀ Δa_k             (19)
//     Δa_{k−1} = ∂g/∂Δq_{k−1} + (∂C_k/∂Δq_{k−1})ᵀ z_k                                   (20)
//   dg/dγ += ∂g/∂γ + (∂q_0/∂γ)ᵀ a_0 + (∂Δq_0/∂γ)ᵀ Δa_0
//
// with the step Δq_k = f(q_k, q_{k−1}): ∂f/∂x_k = I, ∂f/∂x_{k−1} = −I, ∂f/∂R_k = I,
// ∂f/∂R_{k−1} = −ΔR_k (appendix C; in static mode there is no step and Δa is not propagated).
// Each component is solved on its own (H_k is block diagonal over components).
//
// Under the trapezoidal integrator (docs/design.md §14.1) the step's Jacobian is H_k + K, K the
// skew part of the rotations' history: z_k solves (H_k − K) z_k = −(a_k + Δa_k) by a fixed point
// on H_k's factorisation, and the history field adds its mixed blocks through q_{k−1}, Δq_{k−1}
// and γ (IncrementalPotential::add_history_adjoint). Under BDF2 (§15.1) C_k reads Δq_{k−2} too:
// (∂C_k/∂Δq_{k−2})ᵀ z_k joins Δa_{k−2} when the pass gets there.
//
// Exactness: H_k is the derivative of C_k only where C_k = 0 (the Lie Hessian differs from the
// derivative of the Lie gradient field by ½ hat(C_k)), so the gradient is exact at converged
// forward steps and its error grows with the Newton tolerance (measured in tests and the
// README). A forward step that does not converge makes evaluate() throw.
//
// Cost and memory: the backward pass re-assembles and refactorises H_k once per frame and
// component (the forward pass's factorisations are not kept: n of them would not fit for long
// runs), and the trajectory stores one State per frame (lib/trajectory.hpp). Both passes are
// timed by `liedyn gradcheck SCENE`, which prints "one forward pass … s, backward pass … s
// (…× forward)", and by the benchmark in tests/bench_adjoint.cpp (docs/design.md §8.7).

#include <Eigen/Core>
#include <stdexcept>
#include <string>

#include "../lib/objective.hpp"
#include "../lib/parameters.hpp"
#include "../lib/trajectory.hpp"
#include "step_solver.hpp"

namespace liedyn {

// A forward step did not converge, or a Hessian of the backward pass is not positive
// definite: the loss or its gradient is not defined. `frame` is the step k.
class SimulationFailed : public std::runtime_error {
 public:
  SimulationFailed(int frame, const std::string& reason);
  int frame() const { return frame_; }

 private:
  int frame_;
};

class DifferentiableSimulation {
 public:
  // Validates the model and options (ModelError) with γ at its initial values.
  DifferentiableSimulation(Model base, ParameterSet parameters, Objective objective,
                           SolverOptions options);

  const Model& base_model() const { return base_; }
  const ParameterSet& parameters() const { return parameters_; }
  const Objective& objective() const { return objective_; }
  const SolverOptions& options() const { return options_; }
  int frames() const { return parameters_.frames(); }
  Eigen::VectorXd initial_parameters() const { return parameters_.initial_values(base_); }

  struct Result {
    double loss = 0.0;
    Trajectory trajectory;
    double forward_seconds = 0.0;
    double backward_seconds = 0.0;  // 0 without a gradient
    int iterations = 0;             // forward solver iterations, all frames and components
  };
  // g(γ), and dg/dγ into *gradient if non-null (resized). Throws SimulationFailed.
  Result evaluate(const Eigen::VectorXd& gamma, Eigen::VectorXd* gradient) const;

 private:
  Trajectory simulate(const Model& model, Result& result) const;
  void backward(const Model& model, const Eigen::VectorXd& gamma, const Trajectory& trajectory,
                Eigen::VectorXd& gradient) const;

  Model base_;
  ParameterSet parameters_;
  Objective objective_;
  SolverOptions options_;
};

}  // namespace liedyn

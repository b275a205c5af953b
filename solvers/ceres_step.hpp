#pragma once
// The backward-Euler step as a manifold nonlinear least-squares problem for Ceres
// (docs/design.md §9.3): Ψ(q) = ½ Σ_t ‖r_t(q)‖² + const, minimised by Ceres's trust-region
// Gauss–Newton (Levenberg–Marquardt or dogleg).
//
// Residuals. Each term provides its least-squares form with a Lie Jacobian (lib/*.hpp,
// `residual`): inertia ‖(x − x̂)‖√m/h and vec((R − R̃)J^½)/h, springs, rod stretch, shear and
// bend–twist. Constant loads on a point with inertia (gravity, node forces) are folded into
// its inertia residual by completing the square, x̂ = x̃ + h² F/m. The remaining linear loads
// (static mode, forces with a lever arm, torques) have no least-squares form; each becomes
// r = √(2(V + c)) with c fixed per solve so that V + c = β ≫ the load's work over the step:
// exact value and gradient, and a spurious Gauss–Newton curvature g gᵀ/(2β) that a large β
// keeps small.
//
// Rotation blocks (SolverOptions::rotation):
//   lie    — CeresOptions::lie_blocks = "manifold" (default): SO3Manifold
//            (manifolds/so3_manifold.hpp), 4 doubles, Plus = exp(δ) ⊗ q exactly, the cost
//            returns J_Lie · 4Q(q)ᵀ; "chart": 3 doubles θ, R = exp(θ) R₀ with R₀ = R where the
//            solve (or round, below) starts, Jacobian J_Lie J_l(θ) (= J_Lie at θ = 0), no
//            manifold needed. Why the manifold is the default: docs/design.md §9.3;
//   rotvec — the chart with R₀ = I: global rotation vectors r = log R;
//   quat   — UnitQuaternionRetraction (manifolds/ceres_manifolds.hpp): 4 doubles,
//            Plus = normalize(q + Q(q) δ), the cost returns J_Lie · 4Q(q)ᵀ.
//
// Linear solver: DENSE_QR up to kDenseLimit DOFs, SPARSE_NORMAL_CHOLESKY with SuiteSparse
// beyond (CeresOptions::linear_solver). The problem (parameter blocks, residual blocks) is
// built once, at the first solve; later solves only reload the parameters (ceres::Solve still
// preprocesses it and analyses the sparsity anew every time).
//
// Stopping: Ceres stops once it computes a step no longer than `tolerance` (accepted or not;
// 2-norm ≥ the ∞-norm); then the shared convergence test (step_solver.hpp) runs with the
// exact Lie Hessian. If it fails (Gauss–Newton converges only linearly where residuals stay
// large at the minimum: inertia under load, stretched springs), another round starts where
// Ceres stopped, with a ten times smaller threshold (down to 1e-3 tolerance), until the
// iterations (max_iterations in all) are used up or a round accepts no step: Ceres's
// acceptance test compares cost values and cannot see decreases below their round-off, so it
// stalls there; the step is then reported unconverged ("ceres: stalled").
// Ceres FAILURE → StepStatus::kSolverFailed with Ceres's message, the state restored.
//
// Threads: the cost functions of a component share one scratch state, so Ceres runs them on
// one thread.

#include <memory>
#include <string>

#include "step_solver.hpp"

namespace liedyn {

std::unique_ptr<StepSolver> make_ceres_step_solver(Component component,
                                                   const SolverOptions& options);

// Initialises glog for Ceres once per process ("liedyn"), unless the program already has:
// Ceres logs through glog. Thread-safe; called by every Ceres-based solver here.
void initialize_ceres_logging();

// Ceres's check_gradients, done our way, on every residual block of the component's problem at
// q (which must have had begin_step): each analytic Jacobian as Ceres sees it in tangent
// space (J_amb · PlusJacobian) against central differences of the cost function along each
// tangent direction through the manifold's Plus (step 1e-6). The error of a parameter block
// is max|analytic − numeric| over its entries divided by its largest entry. Ceres's own
// check divides entry by entry, which flags the round-off of entries that are zero
// analytically (1e-19 against 1e-16), and its GradientChecker's Ridders differences start
// from a step of 1e-2·|x| (0.32 for a zero coordinate), as long as a rod edge: on rod terms
// they disagreed with the analytic Jacobian and with plain central differences (both of
// which agree to 1e-9) by a factor ~5 (Ceres 2.1).
struct CeresGradientCheck {
  int residual_blocks = 0;
  double worst_error = 0.0;  // over all blocks (∞ if a cost failed to evaluate)
  std::string worst_term;    // its term type
};
CeresGradientCheck check_ceres_gradients(Component component, const SolverOptions& options,
                                         const State& q);

}  // namespace liedyn

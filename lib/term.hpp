#pragma once
// What an energy term is (IPC-Toolkit style: each term owns its value, Lie gradient and Lie
// Hessian in one place; "Lie" as defined in so3.hpp), written as C++20 concepts: a required
// core, `Term`, and optional capabilities that the consumers detect with
// `if constexpr (Capability<T>)`. Terms are stored per type in contiguous vectors, one vector
// per type of the one list of term types (IncrementalPotential::TermTypes): no virtual call
// per element, and adding a term type means writing the type and adding it to that list and
// to the builder that creates it from the model — no consumer names a term type.
//
// Core (Term):
//   static constexpr int kBlocks;             // 3-DOF blocks in its stencil (points, rotations)
//   static constexpr const char* kName;       // for messages and Ceres's residual labels
//   std::array<int, kBlocks> offsets;         // tangent offset of each block, −1 if not a DOF
//   double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;
// evaluate returns the value and, when the pointers are non-null, writes (not adds) the
// local Lie gradient and Lie Hessian. Blocks whose offset is −1 are ignored by assembly.
//
// Capabilities:
//   HasResidual       — a sum of squares, with its least-squares form for Ceres (below).
//   BeginsStep        — fixes per-step data from q_{k−1}, Δq_{k−1} (inertia, lagged friction):
//                         void begin_step(const State& previous, const Step& previous_step);
//   Scheduled         — a quantity that changes per frame (ScheduledParameter below):
//                         void begin_frame(int k);
//                         bool scheduled() const;   (false: no schedule, the value is kept)
//   LoadScaled        — a load that static load stepping scales: member `double scale`,
//                         which multiplies value, gradient and Hessian.
//   EnergyOfState     — `static constexpr bool kEnergyOfState = true`: its value is a
//                         potential energy of the state (what frames.csv reports), unlike the
//                         inertia, torque, cable and friction terms.
//   EndOfStep         — `static constexpr bool kEndOfStep = true`: its force belongs to the
//                         step as a whole, not to a state (inertia, friction, motors, the
//                         trapezoidal integrator's history, lib/history.hpp). An integrator
//                         that weights the forces of states (Model::Integrator, trapezoidal)
//                         applies it once, at the step's end; the others — the conservative
//                         terms — and the elastic (not exact) Constraint terms it weights.
//   ReadsPreviousStep — C = ∇Ψ_t depends on q_{k−1} or Δq_{k−1}: the adjoint's mixed blocks
//                         (paper §5, docs/design.md §8), with z the term's part of the
//                         component's adjoint vector (zeros where a block is not a DOF):
//                         void add_step_adjoint(const State& q, const State& previous,
//                             const Step& previous_step, const LocalGradient<kBlocks>& z,
//                             Eigen::VectorXd& a_previous, Eigen::VectorXd& da_previous) const;
//                         adds (∂C/∂q_{k−1})ᵀ z and (∂C/∂Δq_{k−1})ᵀ z in the whole-state
//                         layout (tangent_point / tangent_rotation, state.hpp).
//   PointLoad         — a load V = −F·x on one point, with no lever arm (gravity, a force
//                         on a rod node), whose current F (times `scale`) it gives:
//                         bool point_load(int& point, Vector3& force) const;
//                         (false when this instance has a lever arm). The Ceres back-end
//                         folds such loads into the point's inertia residual.
//   HasParameters     — C depends on optimisation parameters γ of step `frame`:
//                         void add_parameter_adjoint(const State& q, int frame,
//                             const LocalGradient<kBlocks>& z, Eigen::VectorXd& dgamma) const;
//                         adds (∂C/∂γ)ᵀ z.
//   Constraint        — a joint part c(q) = 0 (joint_terms.hpp) that is elastic, value
//                         ½ k ‖c‖², or, with `exact` set, enforced to the step tolerance by
//                         the augmented Lagrangian of StepSolver::solve: the term is then
//                         ½ ρ ‖c + s‖² with ρ its `stiffness` and s its multiplier shift
//                         (λ = ρ s, the joint's force or torque):
//                           bool exact;  double stiffness;
//                           double violation(const State& q) const;   ‖c(q)‖∞ (m or rad)
//                           void update_multiplier(const State& q);   s ← s + c(q)
//                         and, for the adjoint (joint_terms.hpp): bool adjoint; Vector3
//                         multiplier; Vector3 force(q) (λ); Vector3 constraint(q, J*) (c, ∂c).
//                         An exact term is not an energy of the state (EnergyOfState is then
//                         ignored): a constraint does no work. With `adjoint` set the term is
//                         the Lagrangian λᵀc + ½ρ‖c‖² with λ = `multiplier` (the adjoint's
//                         backward solve, and the Ipopt back-end's equality constraints).
//                         `static constexpr int kConstraintRank` (optional, default 3): how
//                         many independent constraints c's 3 rows hold (a hinge's alignment
//                         and a slider's line: 2, c being perpendicular to an axis).
//   Inequality        — `static constexpr bool kInequality = true`: a Constraint that is one
//                         sided, c = g ≤ 0 in row 0 (joint_limits.hpp); the others are
//                         equalities c = 0 in all three rows.
//
// Least-squares form (HasResidual; inertia, springs, rod elasticity, contact; not the
// linear loads):
//   static constexpr int kResiduals;          // R, the length of its residual r
//   using Residual = LocalResidual<kResiduals>;
//   using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
//   void residual(const State& q, Residual& r, ResidualJacobian* J) const;
// with, for every q,
//   Ψ(q) = ½ ‖r(q)‖² + c,   c independent of q,
//   J = ∂r/∂(blocks) (written when non-null), rotation blocks by LEFT perturbation
//       (column 3b + j of J = ∂r(…, exp(ε e_j) R_b, …)/∂ε at ε = 0, see so3.hpp),
// so that Jᵀ r is the Lie gradient evaluate() returns and Jᵀ J is the Gauss–Newton model of
// the Lie Hessian (no residual curvature, not the exact Hessian). Blocks are in the order of
// `offsets`; columns of blocks whose offset is −1 are written but are not DOFs. J is
// column-major (Eigen's default): Ceres's row-major jacobians[i][r·n + c] = J(r, 3i + c)
// for a parameter block i of tangent size 3.
// Where r is not differentiable (a spring or edge of zero length with a positive rest
// length) a term documents the r and J it returns; Jᵀ r is still evaluate()'s gradient.

#include <Eigen/Core>
#include <array>
#include <concepts>
#include <vector>

#include "state.hpp"

namespace liedyn {

template <int B>
using LocalGradient = Eigen::Matrix<double, 3 * B, 1>;
template <int B>
using LocalHessian = Eigen::Matrix<double, 3 * B, 3 * B>;
template <int R>
using LocalResidual = Eigen::Matrix<double, R, 1>;
template <int R, int B>
using LocalResidualJacobian = Eigen::Matrix<double, R, 3 * B>;

template <class T>
concept Term = requires(const T& t, const State& q, LocalGradient<T::kBlocks>* g,
                        LocalHessian<T::kBlocks>* H) {
  { T::kName } -> std::convertible_to<const char*>;
  { t.offsets } -> std::convertible_to<std::array<int, T::kBlocks>>;
  { t.evaluate(q, g, H) } -> std::same_as<double>;
};

template <class T>
concept HasResidual = Term<T> && requires(const T& t, const State& q, typename T::Residual& r,
                                          typename T::ResidualJacobian* J) {
  { T::kResiduals } -> std::convertible_to<int>;
  t.residual(q, r, J);
};

template <class T>
concept BeginsStep = requires(T& t, const State& previous, const Step& previous_step) {
  t.begin_step(previous, previous_step);
};

template <class T>
concept Scheduled = requires(T& t, int frame) { t.begin_frame(frame); };
// Checked where it is used (IncrementalPotential::state_terms_change_per_step): a term that
// lacked begin_frame's companion would otherwise stop being Scheduled without a word.
template <class T>
concept SaysWhetherScheduled = requires(const T& t) { { t.scheduled() } -> std::same_as<bool>; };

template <class T>
concept LoadScaled = requires(T& t) { { t.scale } -> std::same_as<double&>; };

template <class T>
concept EnergyOfState = requires { requires T::kEnergyOfState; };

template <class T>
concept EndOfStep = requires { requires T::kEndOfStep; };

template <class T>
concept ReadsPreviousStep =
    requires(const T& t, const State& q, const State& previous, const Step& previous_step,
             const LocalGradient<T::kBlocks>& z, Eigen::VectorXd& a, Eigen::VectorXd& da) {
      t.add_step_adjoint(q, previous, previous_step, z, a, da);
    };

template <class T>
concept PointLoad = requires(const T& t, int& point, Vector3& force) {
  { t.point_load(point, force) } -> std::same_as<bool>;
};

template <class T>
concept HasParameters = requires(const T& t, const State& q, int frame,
                                 const LocalGradient<T::kBlocks>& z, Eigen::VectorXd& dgamma) {
  t.add_parameter_adjoint(q, frame, z, dgamma);
};

template <class T>
concept Constraint = requires(T& t, const T& ct, const State& q,
                              typename T::ConstraintJacobian* J) {
  { t.exact } -> std::same_as<bool&>;
  { t.stiffness } -> std::same_as<double&>;
  { ct.violation(q) } -> std::same_as<double>;
  t.update_multiplier(q);
  { t.adjoint } -> std::same_as<bool&>;
  { t.multiplier } -> std::same_as<Vector3&>;
  { ct.force(q) } -> std::same_as<Vector3>;
  { ct.constraint(q, J) } -> std::same_as<Vector3>;
};

template <class T>
concept Inequality = Constraint<T> && requires { requires T::kInequality; };

template <class T>
constexpr int constraint_rank() {
  if constexpr (requires { T::kConstraintRank; }) {
    return T::kConstraintRank;
  } else {
    return 3;
  }
}

// add_parameter_adjoint of a term whose value is proportional to its scalar `stiffness` k
// (Ψ_t = k φ(q), so C = k ∇φ): ∂C/∂k = ∇φ, the term's gradient at k = 1. Adds nothing when
// k is not a parameter (stiffness_slot < 0).
template <class T>
void add_stiffness_adjoint(const T& term, const State& q, const LocalGradient<T::kBlocks>& z,
                           Eigen::VectorXd& dgamma) {
  if (term.stiffness_slot < 0) return;
  T unit = term;
  unit.stiffness = 1.0;
  LocalGradient<T::kBlocks> g;
  unit.evaluate(q, &g, nullptr);
  dgamma(term.stiffness_slot) += g.dot(z);
}
// A term's quantity that may change from frame to frame and may be an optimisation parameter
// (a force, a torque, a cable tension, a rest Darboux vector; paper §5, docs/design.md §5.1, §8).
//   * schedule: its value during step k (the step that produces q_k, k ≥ 1) is schedule[k−1];
//     empty: the term's constant value is kept. IncrementalPotential::begin_step applies it.
//   * slot: index in the parameter vector γ of its value during step 1 (−1: not a
//     parameter), and stride: entries between the values of consecutive steps, so step k's
//     value is γ[slot + stride·(k−1) …] (stride 0: one value for all steps).
template <int P>
struct ScheduledParameter {
  using Value = Eigen::Matrix<double, P, 1>;
  std::vector<Value> schedule;
  int slot = -1;
  int stride = 0;

  // The value during step k, or `constant` without a schedule. Throws std::out_of_range past
  // the schedule's end (a schedule covers every frame it is run for).
  Value at(int k, const Value& constant) const {
    return schedule.empty() ? constant : schedule.at(static_cast<std::size_t>(k - 1));
  }
  // Index in γ of step k's value (−1: not a parameter).
  int slot_at(int k) const { return slot < 0 ? -1 : slot + stride * (k - 1); }
};

}  // namespace liedyn

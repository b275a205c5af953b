#pragma once
// What an energy term is, for the assembler (IPC-Toolkit style: each term owns its value,
// Lie gradient and Lie Hessian in one place; "Lie" as defined in so3.hpp).
//
// A term type T provides
//   static constexpr int kBlocks;             // 3-DOF blocks in its stencil (points, rotations)
//   std::array<int, kBlocks> offsets;         // tangent offset of each block, −1 if not a DOF
//   double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;
// evaluate returns the value and, when the pointers are non-null, writes (not adds) the
// local Lie gradient and Lie Hessian. Blocks whose offset is −1 are ignored by assembly.
// Terms are stored per type in contiguous vectors: no virtual call per element.
//
// A term that is a sum of squares (inertia, springs, rod elasticity; not the linear loads)
// also provides its least-squares form, for the Ceres back-end:
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
#include <vector>

namespace liedyn {

template <int B>
using LocalGradient = Eigen::Matrix<double, 3 * B, 1>;
template <int B>
using LocalHessian = Eigen::Matrix<double, 3 * B, 3 * B>;
template <int R>
using LocalResidual = Eigen::Matrix<double, R, 1>;
template <int R, int B>
using LocalResidualJacobian = Eigen::Matrix<double, R, 3 * B>;

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

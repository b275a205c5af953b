#pragma once
// Quaternion coordinates of a component for a solver that takes constraints (Ipopt): each
// rotation is 4 free numbers q = (x, y, z, s), each position its 3, and the solver is given
// qᵀq = 1 as an equality constraint (docs/design.md §9.4). Between iterates q need not be
// unit; a rotation is read from any q ≠ 0 as
//   R(q) = A.21(q) / qᵀq,
// the rotation of q/‖q‖ (eq. A.21 is homogeneous of degree 2). So Ψ(q) is invariant under
// q ↦ λq: the constraint fixes the scale that Ψ does not see, and Ψ never meets a matrix
// outside SO(3).
//
// Derivatives from the Lie gradient g and Hessian H of the terms (left, world-frame
// perturbations R ← exp(δ) R). Write q̂ = q/‖q‖ and u = dq q⁻¹/qᵀq for a change dq, so that
// (q + dq) q⁻¹/qᵀq = 1 + u; the rotation moves by exp(φ) with φ = log of the unit quaternion
// (1 + u)/‖1 + u‖:
//   φ = 2 atan2(‖u_v‖, 1 + u_s) u_v/‖u_v‖ = 2 u_v (1 − u_s) + O(‖dq‖³),
//   2 u_v = E(q) dq,   E(q) = 4 Q(q)ᵀ / qᵀq   (Q of eq. A.25: 2 (dq q⁻¹)_v = 4 Q(q)ᵀ dq),
//   u_s = qᵀdq / qᵀq.
// Hence, with G = E(q)ᵀ g,
//   ∂Ψ/∂q    = G,
//   ∂²Ψ/∂q²  = E(q)ᵀ H E(q) − (q Gᵀ + G qᵀ) / qᵀq,   ∂²Ψ/∂x∂q = H_xθ E(q),
// and E(q) q = 0, so G ⊥ q and ∂²Ψ/∂q² q = −G: the derivatives of a function of degree 0.
// A constraint λ(qᵀq − 1) adds 2λ I to the diagonal block. At a solution G ⊥ q already, so
// that λ is 0: the constraint only removes the Hessian's null direction q.

#include <Eigen/Core>
#include <vector>

#include "../lib/incremental_potential.hpp"
#include "quaternion.hpp"

namespace liedyn {

using Matrix34 = Eigen::Matrix<double, 3, 4>;

class QuaternionCoordinates {
 public:
  QuaternionCoordinates() = default;
  explicit QuaternionCoordinates(const Component& component);

  // Number of coordinates: 3 per position, 4 per rotation.
  int size() const { return size_; }
  // The coordinates of the component's tangent block at `offset` start at variable(offset),
  // and are 4 for a rotation, 3 for a position.
  int variable(int offset) const { return variable_[offset / 3]; }
  // E(q) of the rotation whose tangent DOFs start at `offset`, or null for a position.
  const Matrix34* jacobian_at(int offset) const {
    const int i = rotation_of_block_[offset / 3];
    return i < 0 ? nullptr : &E_[i];
  }
  // q of rotation i (component.rotations[i]), as last set.
  const quat::Vector4& quaternion(std::size_t i) const { return q_[i]; }
  // Rotation i's first coordinate.
  int rotation_variable(std::size_t i) const { return variable(rotation_offsets_[i]); }
  std::size_t rotations() const { return q_.size(); }

  // The coordinates of `state`: positions, and each rotation's unit quaternion (s ≥ 0).
  void get(const Component& component, const State& state, double* x);
  // Writes the coordinates x into `state` (R(q) above) and keeps E(q) of each rotation.
  void set(const Component& component, const double* x, State& state);

  // After the terms have assembled the Lie gradient `lie` (tangent order): writes ∂Ψ/∂x
  // (coordinate order) and adds each rotation's −(q Gᵀ + G qᵀ)/qᵀq + 2 μ_i I through `sink`
  // (μ_i = norm_multipliers[i], or none when null).
  template <class Sink>
  void finish(const Eigen::VectorXd& lie, Eigen::VectorXd& x_gradient, Sink& sink,
              const double* norm_multipliers) const;

 private:
  int size_ = 0;
  std::vector<int> variable_;            // per 3-DOF tangent block: its first coordinate
  std::vector<int> rotation_of_block_;   // per 3-DOF tangent block: its rotation, or −1
  std::vector<int> point_offsets_;       // per position: tangent offset
  std::vector<int> rotation_offsets_;    // per rotation: tangent offset
  std::vector<quat::Vector4> q_;         // per rotation
  std::vector<Matrix34> E_;              // per rotation: E(q)
};

// Passes each Lie Hessian block on as E_rowᵀ block E_column at the coordinates' offsets (E
// the identity for a position): 3×3, 4×3, 3×4 or 4×4 blocks.
template <class Sink>
struct QuaternionSink {
  Sink& sink;
  const QuaternionCoordinates& coordinates;
  void clear() { sink.clear(); }
  template <class Block>
  void add(int row, int column, const Block& block) {
    const Matrix34* E_row = coordinates.jacobian_at(row);
    const Matrix34* E_column = coordinates.jacobian_at(column);
    const int r = coordinates.variable(row), c = coordinates.variable(column);
    const Matrix3 b = block;
    if (E_row == nullptr && E_column == nullptr) {
      sink.add(r, c, b);
    } else if (E_column == nullptr) {
      sink.add(r, c, Eigen::Matrix<double, 4, 3>(E_row->transpose() * b));
    } else if (E_row == nullptr) {
      sink.add(r, c, Matrix34(b * *E_column));
    } else {
      sink.add(r, c, quat::Matrix4(E_row->transpose() * b * *E_column));
    }
  }
};

template <class Sink>
void QuaternionCoordinates::finish(const Eigen::VectorXd& lie, Eigen::VectorXd& x_gradient,
                                   Sink& sink, const double* norm_multipliers) const {
  for (const int o : point_offsets_) x_gradient.segment<3>(variable(o)) = lie.segment<3>(o);
  for (std::size_t i = 0; i < q_.size(); ++i) {
    const int o = rotation_offsets_[i];
    const int v = variable(o);
    const quat::Vector4& q = q_[i];
    const quat::Vector4 G = E_[i].transpose() * lie.segment<3>(o);
    x_gradient.segment<4>(v) = G;
    quat::Matrix4 C = -(q * G.transpose() + G * q.transpose()) / q.squaredNorm();
    if (norm_multipliers != nullptr) C.diagonal().array() += 2.0 * norm_multipliers[i];
    sink.add(v, v, C);
  }
}

// Ψ, ∂Ψ/∂x (in x_gradient, coordinate order; `lie` is the tangent-order work space) and the
// coordinates' Hessian blocks through `sink`, at the state the coordinates were last set to.
template <class Sink>
double assemble_in_quaternions(const IncrementalPotential& potential, const State& q,
                               const QuaternionCoordinates& coordinates, Eigen::VectorXd& lie,
                               Eigen::VectorXd& x_gradient, Sink& sink,
                               const double* norm_multipliers) {
  QuaternionSink<Sink> s{sink, coordinates};
  const double value = potential.assemble_into(q, lie, s, nullptr);
  coordinates.finish(lie, x_gradient, sink, norm_multipliers);
  return value;
}

}  // namespace liedyn

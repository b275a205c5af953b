#pragma once
// State and step of a simulation (paper §4.1).
//
// The state q_k gathers points x_i ∈ R³ (rigid-body centres of mass; later rod nodes) and
// rotations R_j ∈ SO(3) (rigid bodies; later rod edges). The step Δq_k is
//   Δx_k = x_k − x_{k−1},   ΔR_k = R_k R_{k−1}ᵀ   (eq. 6).
// Tangent vectors stack 3 entries per point and 3 per rotation (left perturbations, see
// so3.hpp); a term knows where its DOFs live in the tangent vector through offsets.

#include <Eigen/Core>
#include <vector>

namespace liedyn {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

struct State {
  std::vector<Vector3> points;
  std::vector<Matrix3> rotations;
};

// R of a joint's end: State::rotations[rotation], or the identity for the world (rotation = −1).
const Matrix3& rotation_or_identity(const State& q, int rotation);

struct Step {
  std::vector<Vector3> points;     // Δx
  std::vector<Matrix3> rotations;  // ΔR
};

// A point that is fixed in the world, or attached to a point x with or without a rotation:
//   p = x + R p̄   (rotation ≥ 0; p̄ = `local`, in the frame's coordinates),
//   p = x + p̄     (rotation = −1: a translating offset),
//   p = p̄         (point = −1: a world anchor).
// Its tangent Jacobian is [∂p/∂x, ∂p/∂θ] = [I, −hat(R p̄)] (paper eq. 22).
struct AttachedPoint {
  int point = -1;     // index into State::points, −1 for a world anchor
  int rotation = -1;  // index into State::rotations, −1 if the point does not rotate
  Vector3 local = Vector3::Zero();

  // World position.
  Vector3 position(const State& q) const;
  // Offset r = p − x: R p̄, or p̄ without a rotation (only R p̄ enters the Lie derivatives).
  Vector3 lever(const State& q) const;
};

// Second-order Lie term of a potential through a rotated point (paper eq. 23):
// with p = x + r, r = R p̄, and f = ∂Ψ/∂p,
//   D²Ψ/DR² ⊇ ½ (f rᵀ + r fᵀ) − (f·r) I   ( = D + Dᵀ, D = ½ hat(r) hat(f) ).
Matrix3 rotated_point_curvature(const Vector3& r, const Vector3& f);

// Index of point i and rotation j in a whole-state tangent vector (3 entries per point, then
// 3 per rotation), the layout of the adjoint vectors a_k, Δa_k.
inline int tangent_point(int i) { return 3 * i; }
inline int tangent_rotation(const State& q, int j) {
  return 3 * (static_cast<int>(q.points.size()) + j);
}
inline int tangent_size(const State& q) {
  return 3 * static_cast<int>(q.points.size() + q.rotations.size());
}

}  // namespace liedyn

#pragma once
// Unit quaternions q = (x, y, z, s) (vector part, then scalar part: the order and formulas of
// docs/design.md §10.3, eqs. A.13–A.25), as a rotation parameterisation
// for Newton's method beside the Lie one (solvers/newton.hpp).
//
// Unit norm is kept by the update, not by a constraint: a Newton step δ ∈ R³ moves q along
// the tangent of the unit sphere and renormalises,
//   q ← (q + Q(q) δ) / ‖q + Q(q) δ‖,      Q(q) of eq. A.25 (q̇ = Q(q) ω),
// which is the rotation exp(θ(δ)) R(q) with θ(δ) = 2 atan(‖δ‖/2) δ/‖δ‖ = δ − ‖δ‖² δ/12 + …
// Hence θ'(0) = I and θ''(0) = 0: the gradient and Hessian of δ ↦ Ψ(R(q(δ))) at δ = 0 are
// exactly the Lie gradient and Lie Hessian at R(q). The parameterisations differ in the
// retraction (a step δ turns by 2 atan(‖δ‖/2), not ‖δ‖) and in what is stored.

#include <Eigen/Core>

namespace liedyn::quat {

using Vector3 = Eigen::Vector3d;
using Vector4 = Eigen::Vector4d;  // (x, y, z, s)
using Matrix3 = Eigen::Matrix3d;
using Matrix4 = Eigen::Matrix4d;

// a b (eq. A.14).
Vector4 product(const Vector4& a, const Vector4& b);
// q⁻¹ = (−x, −y, −z, s) for a unit quaternion (eq. A.13).
Vector4 inverse(const Vector4& q);
// A(a) with a b = A(a) b (eq. A.15), and B(b) with a b = B(b) a (eq. A.16).
Matrix4 left_matrix(const Vector4& a);
Matrix4 right_matrix(const Vector4& b);
// R(q) (eq. A.21); q must be unit (A.21 is a homogeneous quadratic: R(λq) = λ² R(q)).
Matrix3 rotation(const Vector4& q);
// ∂R/∂x, ∂R/∂y, ∂R/∂z, ∂R/∂s (eq. A.23). Constant second derivatives follow from them.
void rotation_derivatives(const Vector4& q, Matrix3 dR[4]);
// Q(q), 4×3, with q̇ = Q(q) ω for a world-frame angular velocity ω (eq. A.25).
Eigen::Matrix<double, 4, 3> rate_matrix(const Vector4& q);
// The unit quaternion of a rotation matrix, with s ≥ 0 (Shepperd's method: numerically stable
// for every R, including rotations by π; R must be within round-off of SO(3)).
Vector4 from_rotation(const Matrix3& R);
// The update above: (q + Q(q) δ)/‖q + Q(q) δ‖.
Vector4 retract(const Vector4& q, const Vector3& delta);

}  // namespace liedyn::quat

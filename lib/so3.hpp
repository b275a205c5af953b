#pragma once
// SO(3) Lie group operations used everywhere in liedyn.
//
// Conventions (the one place they are stated; docs/conventions.md repeats them for users):
//   * R ∈ SO(3) maps body coordinates to world coordinates.
//   * Perturbations are LEFT, in the world frame:  R⁺ = exp(θ) R,  θ ∈ R³ (full angle).
//   * The Lie derivative of a scalar f at R is  Df/DR = ∂f(exp(θ)R)/∂θ |θ=0  (a 3-vector),
//     and the Lie Hessian is  ∂²f(exp(θ)R)/∂θ² |θ=0  (a symmetric 3×3 matrix).
//   * For a rotation-valued Q(R):  DQ/DR = ∂θ_Q/∂θ_R  with  Q(exp(θ_R)R) = exp(θ_Q) Q(R)
//     (paper eq. 2).
//   * hat(u) v = u × v, vee = hat⁻¹.
//
// Jacobians follow manif's naming, J_<output>_<input>, and are optional trailing outputs
// computed only when a non-null pointer is passed. Because perturbations are left, the
// Jacobian of exp is the LEFT Jacobian:  exp(θ + ε) = exp(J_l(θ) ε) exp(θ) + O(ε²),
// and that of log is its inverse.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace liedyn::so3 {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

// hat(u) = [u]×, the antisymmetric matrix with hat(u) v = u × v.
inline Matrix3 hat(const Vector3& u) {
  Matrix3 m;
  m << 0.0, -u.z(), u.y(),  //
      u.z(), 0.0, -u.x(),   //
      -u.y(), u.x(), 0.0;
  return m;
}

// vee(M) = hat⁻¹ of the antisymmetric part of M:  vee(M) = ½ (M₃₂−M₂₃, M₁₃−M₃₁, M₂₁−M₁₂).
// For an antisymmetric M this is the exact inverse of hat.
inline Vector3 vee(const Matrix3& M) {
  return 0.5 * Vector3(M(2, 1) - M(1, 2), M(0, 2) - M(2, 0), M(1, 0) - M(0, 1));
}

// exp(θ) = I + sin t/t [θ]× + (1−cos t)/t² [θ]×²,  t = ‖θ‖  (Rodrigues, paper eq. 4).
// Taylor branches near t = 0 keep full precision down to t = 0.
// J_R_theta (optional) = J_l(θ), the left Jacobian: exp(θ+ε) ≈ exp(J_l(θ)ε) exp(θ).
Matrix3 exp(const Vector3& theta, Matrix3* J_R_theta = nullptr);

// log(R) = θ with exp(θ) = R and ‖θ‖ ∈ [0, π]. Accurate near 0 (antisymmetric part) and
// near π (symmetric part): at ‖θ‖ = π the sign of θ is arbitrary, as it must be.
// J_theta_R (optional) = J_l⁻¹(θ):  log(exp(ε) R) ≈ θ + J_l⁻¹(θ) ε.
Vector3 log(const Matrix3& R, Matrix3* J_theta_R = nullptr);

// Left Jacobian  J_l(θ) = I + (1−cos t)/t² [θ]× + (t−sin t)/t³ [θ]×².
Matrix3 left_jacobian(const Vector3& theta);

// Inverse left Jacobian  J_l⁻¹(θ) = I − ½[θ]× + (1/t² − cot(t/2)/(2t)) [θ]×².
// Singular at t = 2π; finite (and accurate) for t ≤ π and beyond, up to near 2π.
Matrix3 left_jacobian_inverse(const Vector3& theta);

// Rotation matrix of a quaternion. The input need not be unit: it is normalised first
// (callers that must reject non-unit input check the norm themselves).
Matrix3 from_quaternion(const Eigen::Quaterniond& q);

// Unit quaternion of a rotation matrix, with w ≥ 0 (canonical sign).
Eigen::Quaterniond to_quaternion(const Matrix3& R);

// Nearest rotation, for a matrix within round-off of SO(3): one Newton step of the polar
// decomposition, R ← R (3I − RᵀR)/2, which squares the orthonormality error.
// Called after every update so that drift never accumulates (docs/design.md §2.3).
Matrix3 orthonormalize(const Matrix3& R);

// Geodesic distance ‖log(A Bᵀ)‖ ∈ [0, π].
double distance(const Matrix3& A, const Matrix3& B);

}  // namespace liedyn::so3

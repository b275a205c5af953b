#pragma once
// SO(3) as a Ceres manifold with Lie derivatives, for your own problems over rotations
// (attitude control, rotation averaging, calibration) and for liedyn's Ceres step back-end.
//
// Storage: a unit quaternion q = (x, y, z, w), 4 doubles, vector part first — the order of
// Eigen::Quaterniond::coeffs(), so `Eigen::Map<Eigen::Quaterniond>(block)` reads a block.
// (Ceres's own QuaternionManifold is w-first; EigenQuaternionManifold uses this order but a
// right, body-frame perturbation.)
//
// Tangent: the world-frame (left) rotation vector of lib/so3.hpp, so that
//   Plus(q, δ)  = exp(δ) ⊗ q                R⁺ = exp(δ) R,   the exact exponential,
//   Minus(p, q) = log(p ⊗ q⁻¹)               ∈ the ball ‖δ‖ ≤ π (the shorter way round),
// and Minus(Plus(q, δ), q) = δ for ‖δ‖ < π, Plus(q, Minus(p, q)) = ±p. exp(δ) as a quaternion
// is (sin(t/2) δ/t, cos(t/2)), t = ‖δ‖, with its Taylor series near t = 0; the product is
// normalised (round-off only, so that ‖q‖ = 1 never drifts over many Plus).
//
// Jacobians. With Q(q) the 4×3 rate matrix of manifolds/quaternion.hpp (q̇ = Q(q) ω for a
// world angular velocity ω):
//   PlusJacobian(q)  = ∂Plus(q, δ)/∂δ at δ = 0 = Q(q),                      4×3,
//   MinusJacobian(q) = ∂Minus(p, q)/∂p at p = q = 4 Q(q)ᵀ,                    3×4,
// the second a left inverse of the first (Q(q)ᵀ Q(q) = ¼ I for a unit q).
//
// Using Lie Jacobians in a cost function. Ceres asks a cost function for ∂r/∂q (ambient,
// n × 4) and multiplies it by PlusJacobian(q). A cost that knows its Lie Jacobian
// J = ∂r(exp(δ) R)/∂δ at δ = 0 (n × 3, the Jacobians of lib/so3.hpp and of every liedyn term)
// returns
//   ∂r/∂q := J · lie_to_ambient(q),   lie_to_ambient(q) = MinusJacobian(q) = 4 Q(q)ᵀ,
// and Ceres then works with J · 4Q(q)ᵀ Q(q) = J exactly — no derivative of R(q) is written,
// and numeric checks of the cost along Plus (ceres::GradientChecker) see the same Jacobian.
// (It is the ambient Jacobian of r(R(q/‖q‖)) restricted to the tangent space; the radial
// direction, which Ceres never uses, gets 0.)
//
// RightMultiplyByPlusJacobian is overridden: for the J · 4Q(q)ᵀ above it returns J to
// round-off, in 12 multiply–adds per row.
//
// Ownership: a ceres::Problem deletes its manifolds unless its options say
// manifold_ownership = DO_NOT_TAKE_OWNERSHIP; one SO3Manifold (stateless) may serve every block.
// Usage, with examples: docs/manifolds.md.

#include <ceres/manifold.h>

#include <Eigen/Core>

namespace liedyn {

class SO3Manifold final : public ceres::Manifold {
 public:
  using Vector3 = Eigen::Vector3d;
  using Vector4 = Eigen::Vector4d;  // (x, y, z, w)
  using Matrix3 = Eigen::Matrix3d;
  using PlusJacobianMatrix = Eigen::Matrix<double, 4, 3>;
  using LieToAmbient = Eigen::Matrix<double, 3, 4>;

  int AmbientSize() const override { return 4; }
  int TangentSize() const override { return 3; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool RightMultiplyByPlusJacobian(const double* x, int num_rows, const double* ambient_matrix,
                                   double* tangent_matrix) const override;
  // False only when p or q is not finite or zero.
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;

  // The conversions a user needs around a parameter block.
  static Vector4 quaternion(const Matrix3& R);  // of a rotation, w ≥ 0
  static Matrix3 rotation(const double* q);     // R(q/‖q‖)
  // 4 Q(q)ᵀ: a cost's Lie Jacobian J (n × 3) times this is the ambient Jacobian to return.
  static LieToAmbient lie_to_ambient(const double* q);
  // exp(δ) as a unit quaternion, and the inverse map (the rotation vector of a unit
  // quaternion, taking the shorter way: ‖result‖ ≤ π).
  static Vector4 exp(const Vector3& delta);
  static Vector3 log(const Vector4& q);
};

}  // namespace liedyn

#pragma once
// Unit quaternions as a Ceres manifold (ceres::Manifold, Ceres 2.1; docs/design.md §9.3), with Lie
// derivatives.
//
// Ceres's cost functions return Jacobians with respect to a parameter block's AMBIENT
// coordinates, and Ceres multiplies them by PlusJacobian(x) = ∂Plus(x, δ)/∂δ at δ = 0 to get
// the tangent Jacobian it works with. Our terms give Lie Jacobians J_Lie = ∂r/∂θ for the left
// perturbation R⁺ = exp(θ) R directly. With a manifold whose Plus moves along exactly that
// perturbation to first order, a cost function returns
//   J_amb = J_Lie · M(x),   M(x) = MinusJacobian(x) = ∂Minus(y, x)/∂y at y = x,
// and since M(x) · PlusJacobian(x) = I (Minus inverts Plus), Ceres sees
//   J_amb · PlusJacobian(x) = J_Lie,
// exactly the Lie Jacobian, without differentiating R(q) (A.23); and numeric checks through
// Plus pass (padding [J_Lie 0] with a fake PlusJacobian would not: docs/design.md §9.3).
//
// * UnitQuaternionRetraction — q = (x, y, z, s) (manifolds/quaternion.hpp), 4 doubles:
//     Plus(q, δ)  = (q + Q(q) δ)/‖q + Q(q) δ‖   (quat::retract: turns by 2 atan(‖δ‖/2)),
//     PlusJacobian(q) = Q(q) (its column space is tangent to the unit sphere: qᵀQ(q) = 0),
//     Minus(p, q) = 4 Q(q)ᵀ p / (qᵀp)   (p in q's hemisphere; solves Plus(q, δ) = p),
//     M(q) = 4 Q(q)ᵀ, since Q(q)ᵀQ(q) = ¼ I.
//   The derivatives of δ ↦ f(R(Plus(q, δ))) at δ = 0 are the Lie ones (quaternion.hpp), so
//   J_amb = J_Lie · 4 Q(q)ᵀ.
//
// (Ceres's own QuaternionManifold uses w-first order and δ = θ/2; not used here.)
//
// Lie and rotation-vector blocks need no manifold: they are charts, 3 doubles θ with
// R = exp(θ) R_ref and J = J_Lie J_l(θ) (solvers/ceres_step.hpp). A 9-double "lift" (the
// matrix R itself, Plus = exp(δ) R, MinusJacobian column (a, b) = ½ x_b × e_a) was measured
// against the chart and dropped: see ceres_step.hpp.

#include <ceres/manifold.h>

#include <Eigen/Core>

namespace liedyn {

class UnitQuaternionRetraction final : public ceres::Manifold {
 public:
  using LieToAmbient = Eigen::Matrix<double, 3, 4>;
  static LieToAmbient lie_to_ambient(const double* q);

  int AmbientSize() const override { return 4; }
  int TangentSize() const override { return 3; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

}  // namespace liedyn

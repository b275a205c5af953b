#include "history.hpp"

#include "loads.hpp"
#include "so3.hpp"

namespace liedyn {

double PointHistory::evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const {
  if (g != nullptr) *g = field;
  if (H != nullptr) H->setZero();
  return field.dot(q.points[point]);
}

double RotationHistory::evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const {
  // A world torque τ = −c about R_ref.
  return torque_potential(q.rotations[rotation] * reference.transpose(), -field, g, H);
}

Matrix3 RotationHistory::inertia_shift(const Matrix3& J_over_h2_inverse) const {
  return -0.5 * so3::hat(field) * reference * J_over_h2_inverse;
}

double RotationHistory::rereference(const State& q) {
  const Matrix3& R = q.rotations[rotation];
  const double angle = so3::log(R * reference.transpose()).norm();
  reference = R;
  return angle;
}

}  // namespace liedyn

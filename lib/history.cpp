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
  if (q.rotations[rotation] == reference) {
    if (g != nullptr) *g = field;
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  // A world torque τ = −c about R_ref.
  return torque_potential(q.rotations[rotation] * reference.transpose(), -field, g, H);
}

Matrix3 RotationHistory::inertia_shift(const Matrix3& J_over_h2_inverse) const {
  return -0.5 * so3::hat(field) * reference * J_over_h2_inverse;
}

double RotationHistory::reference_distance(const State& q) const {
  const Matrix3& R = q.rotations[rotation];
  return R == reference ? 0.0 : so3::log(R * reference.transpose()).norm();
}

}  // namespace liedyn

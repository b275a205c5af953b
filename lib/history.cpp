#include "history.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

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

double RotationHistory::chord_angle(double chord) {
  // Exact for rotations (‖R₁ − R₂‖² = 2(3 − tr(R₁R₂ᵀ)) = 4(1 − cos θ)) and accurate at the
  // small angles compared with the tolerance (no trace near 3 to cancel), without the
  // logarithm's atan2 — StepSolver::solve asks after every solve. Near π it loses digits
  // (asin's slope), where the test against the tolerance has long been decided.
  return 2.0 * std::asin(std::min(1.0, chord / (2.0 * std::numbers::sqrt2)));
}

}  // namespace liedyn

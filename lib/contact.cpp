#include "contact.hpp"

#include <algorithm>
#include <cmath>

#include "point_pair.hpp"

namespace liedyn {

bool ContactMaterial::touches(const std::string& name) const {
  const auto listed = [&](const std::vector<std::string>& names) {
    return std::find(names.begin(), names.end(), name) != names.end();
  };
  return (collides_with.empty() || listed(collides_with)) && !listed(ignores);
}

double ContactSample::penetration(const State& q) const {
  return radius - collider->evaluate(at.position(q), false).distance;
}

double Contact::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  const SdfValue s = collider->evaluate(at.position(q), H != nullptr);
  const double d = radius - s.distance;
  if (!(d > 0.0)) {
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  if (g != nullptr || H != nullptr) {
    const Vector3 f = -stiffness * d * s.gradient;  // ∂V/∂p = −k d ∇φ
    Matrix3 K = Matrix3::Zero();
    if (H != nullptr) {
      K = stiffness * (s.gradient * s.gradient.transpose() - d * s.hessian);  // k(n nᵀ − d N)
    }
    attached_point_derivatives(at.lever(q), f, K, g, H);
  }
  return 0.5 * stiffness * d * d;
}

void Contact::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const SdfValue s = collider->evaluate(at.position(q), false);
  const double d = radius - s.distance;
  const double root_k = std::sqrt(stiffness);
  if (!(d > 0.0)) {
    r(0) = 0.0;
    if (J != nullptr) J->setZero();
    return;
  }
  r(0) = root_k * d;
  if (J != nullptr) {
    J->leftCols<3>() = -root_k * s.gradient.transpose();                          // ∂d/∂x = −nᵀ
    J->rightCols<3>() = -root_k * at.lever(q).cross(s.gradient).transpose();  // −nᵀ(−hat(r))
  }
}

}  // namespace liedyn

#include "contact.hpp"

#include <algorithm>
#include <cmath>

#include "point_pair.hpp"
#include "so3.hpp"

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

ContactSample::Lagged ContactSample::lag(const State& previous) const {
  const Vector3 p = at.position(previous);
  const SdfValue s = collider->evaluate(p, false);
  const double length = s.gradient.norm();
  return {p, radius - s.distance, length > 0.0 ? Vector3(s.gradient / length) : Vector3::UnitZ()};
}

Matrix3 ContactSample::normal_jacobian(const Vector3& previous_position, const Vector3& normal,
                                       SdfValue& lagged) const {
  lagged = collider->evaluate(previous_position, true);
  const double g_norm = lagged.gradient.norm();
  if (!(g_norm > 0.0)) return Matrix3::Zero();
  return (Matrix3::Identity() - normal * normal.transpose()) * lagged.hessian / g_norm;
}

Eigen::Matrix<double, 6, 6> ContactSample::previous_block(const State& q, const State& previous,
                                                          const Matrix3& df_dprevious) const {
  Eigen::Matrix<double, 3, 6> dp_previous;  // ∂p̂/∂(x̂, θ̂)
  dp_previous << Matrix3::Identity(), -so3::hat(at.lever(previous));
  Eigen::Matrix<double, 6, 6> out;
  out.topRows<3>() = df_dprevious * dp_previous;
  out.bottomRows<3>() = so3::hat(at.lever(q)) * out.topRows<3>();  // rows θ: r × f
  return out;
}

void ContactSample::add_previous_adjoint(const State& q, const Eigen::Matrix<double, 6, 6>& block,
                                         const LocalGradient<2>& z, Eigen::VectorXd& a_previous) const {
  // Columns (x̂, θ̂) of the sample's frame: its point and, on a body, its rotation.
  const Eigen::Matrix<double, 6, 1> w = block.transpose() * z;
  if (at.point >= 0) a_previous.segment<3>(tangent_point(at.point)) += w.head<3>();
  if (at.rotation >= 0) a_previous.segment<3>(tangent_rotation(q, at.rotation)) += w.tail<3>();
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

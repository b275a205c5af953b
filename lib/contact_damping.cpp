#include "contact_damping.hpp"

#include <cmath>

#include "point_pair.hpp"

namespace liedyn {

void ContactDamping::begin_step(const State& previous, const Step&) {
  const Lagged lagged = lag(previous);
  previous_position = lagged.position;
  active = lagged.penetration > 0.0;
  normal = lagged.normal;
}

double ContactDamping::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  if (!active) {
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  const double rate = damping / time_step;  // c/h
  const double s = normal.dot(at.position(q) - previous_position);
  if (g != nullptr || H != nullptr) {
    const Matrix3 K = H != nullptr ? Matrix3(rate * normal * normal.transpose()) : Matrix3::Zero();
    attached_point_derivatives(at.lever(q), rate * s * normal, K, g, H);
  }
  return 0.5 * rate * s * s;
}

void ContactDamping::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  if (!active) {
    r.setZero();
    if (J != nullptr) J->setZero();
    return;
  }
  const double root = std::sqrt(damping / time_step);
  r(0) = root * normal.dot(at.position(q) - previous_position);
  if (J == nullptr) return;
  J->leftCols<3>() = root * normal.transpose();
  J->rightCols<3>() = root * at.lever(q).cross(normal).transpose();
}

Eigen::Matrix<double, 6, 6> ContactDamping::previous_jacobian(const State& q,
                                                              const State& previous) const {
  if (!active) return Eigen::Matrix<double, 6, 6>::Zero();
  const double rate = damping / time_step;
  const Vector3 w = at.position(q) - previous_position;
  const double s = normal.dot(w);
  SdfValue lagged;
  const Matrix3 dn = normal_jacobian(previous_position, normal, lagged);
  const Eigen::RowVector3d ds = -normal.transpose() + w.transpose() * dn;
  const Matrix3 df = rate * (normal * ds + s * dn);
  return previous_block(q, previous, df);
}

void ContactDamping::add_step_adjoint(const State& q, const State& previous, const Step&,
                                      const LocalGradient<2>& z, Eigen::VectorXd& a_previous,
                                      Eigen::VectorXd&) const {
  if (!active) return;
  add_previous_adjoint(q, previous_jacobian(q, previous), z, a_previous);
}

}  // namespace liedyn

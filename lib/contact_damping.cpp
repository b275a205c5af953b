#include "contact_damping.hpp"

#include <cmath>

#include "point_pair.hpp"
#include "so3.hpp"

namespace liedyn {

void ContactDamping::begin_step(const State& previous, const Step&) {
  const Lagged lagged = lag(previous);
  previous_position = lagged.position;
  active = lagged.penetration > 0.0;
  normal = lagged.normal;
}

const NormalDashpot& ContactDamping::law() const { return *this; }

double ContactDamping::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  if (!active) {
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  Vector3 f;
  Matrix3 K = Matrix3::Zero();
  const bool derivatives = g != nullptr || H != nullptr;
  const double D = law().evaluate(at.position(q) - previous_position, 0.0, normal, stiffness,
                                  derivatives ? &f : nullptr, H != nullptr ? &K : nullptr);
  if (derivatives) attached_point_derivatives(at.lever(q), f, K, g, H);
  return D;
}

void ContactDamping::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  if (!active) {
    r.setZero();
    if (J != nullptr) J->setZero();
    return;
  }
  Eigen::RowVector3d row;  // ∂r/∂p
  r(0) = law().residual(at.position(q) - previous_position, normal, stiffness, row);
  if (J == nullptr) return;
  J->leftCols<3>() = row;
  J->rightCols<3>() = row * so3::hat(at.lever(q)).transpose();  // ∂p/∂θ = −hat(r)
}

Eigen::Matrix<double, 6, 6> ContactDamping::previous_jacobian(const State& q,
                                                              const State& previous) const {
  if (!active) return Eigen::Matrix<double, 6, 6>::Zero();
  SdfValue lagged;
  const Matrix3 dn = normal_jacobian(previous_position, normal, lagged);
  // d = p − p̂: ∂d/∂p̂ = −I; λ enters only through the zone.
  const Vector3 d = at.position(q) - previous_position;
  const Matrix3 dd = -Matrix3::Identity();
  const Eigen::RowVector3d no_lambda = Eigen::RowVector3d::Zero();
  const Matrix3 df = law().force_jacobian(d, 0.0, normal, stiffness, dd, no_lambda, dn);
  return previous_block(q, previous, df);
}

void ContactDamping::add_step_adjoint(const State& q, const State& previous, const Step&,
                                      const LocalGradient<2>& z, Eigen::VectorXd& a_previous,
                                      Eigen::VectorXd&) const {
  if (!active) return;
  add_previous_adjoint(q, previous_jacobian(q, previous), z, a_previous);
}

}  // namespace liedyn

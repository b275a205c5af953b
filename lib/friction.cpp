#include "friction.hpp"

#include <cmath>

#include "dissipation_law.hpp"
#include "point_pair.hpp"
#include "so3.hpp"

namespace liedyn {

void Friction::begin_step(const State& previous, const Step&) {
  const Lagged lagged = lag(previous);
  previous_position = lagged.position;
  normal_force = stiffness * std::max(0.0, lagged.penetration);  // k max(0, penetration)
  normal = lagged.normal;
}

SmoothedSlip::SmoothedSlip(const Vector3& tangential, double epsilon)
    : u(tangential), y(tangential.norm()) {
  if (y < epsilon) {
    const double inv = 1.0 / epsilon;
    phi1 = 2.0 * inv - y * inv * inv;
    dphi1 = -inv * inv;
    f0 = y * y * inv * (1.0 - y * inv / 3.0) + epsilon / 3.0;
  } else {
    phi1 = 1.0 / y;
    dphi1 = -1.0 / (y * y);
    f0 = y;
  }
}

Matrix3 SmoothedSlip::curvature(const Matrix3& P) const {
  Matrix3 A = phi1 * P;
  if (y > 0.0) A += (dphi1 / y) * (u * u.transpose());
  return A;
}

// The law of dissipation_law.hpp on d = p − p̂ (the sample's displacement over the step).
double Friction::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  if (normal_force == 0.0) {
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  Vector3 f;
  Matrix3 K = Matrix3::Zero();
  const bool derivatives = g != nullptr || H != nullptr;
  const double D = SlipFriction{coefficient, epsilon}.evaluate(at.position(q) - previous_position, normal_force,
                                                               normal, stiffness, derivatives ? &f : nullptr,
                                                               H != nullptr ? &K : nullptr);
  if (derivatives) attached_point_derivatives(at.lever(q), f, K, g, H);
  return D;
}

void Friction::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  friction_residual(*this, q, r, J);
}

Eigen::Matrix<double, 6, 6> Friction::previous_jacobian(const State& q,
                                                        const State& previous) const {
  if (normal_force == 0.0) return Eigen::Matrix<double, 6, 6>::Zero();
  SdfValue lagged;
  const Matrix3 dn = normal_jacobian(previous_position, normal, lagged);
  // d = p − p̂: ∂d/∂p̂ = −I; λ = k(ρ − φ(p̂)) > 0 here, so ∂λ/∂p̂ = −k Gᵀ.
  const Matrix3 dd = -Matrix3::Identity();
  const Eigen::RowVector3d dlambda = -stiffness * lagged.gradient.transpose();
  const Matrix3 df = SlipFriction{coefficient, epsilon}.force_jacobian(at.position(q) - previous_position,
                                                                       normal_force, normal, stiffness, dd, dlambda, dn);
  return previous_block(q, previous, df);
}

void Friction::add_step_adjoint(const State& q, const State& previous, const Step&,
                                const LocalGradient<2>& z, Eigen::VectorXd& a_previous,
                                Eigen::VectorXd&) const {
  if (normal_force == 0.0) return;
  add_previous_adjoint(q, previous_jacobian(q, previous), z, a_previous);
}

}  // namespace liedyn

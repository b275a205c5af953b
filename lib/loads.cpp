#include "loads.hpp"

#include "point_pair.hpp"
#include "so3.hpp"

namespace liedyn {

double Gravity::evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const {
  const Vector3 w = scale * weight;
  if (g != nullptr) *g = -w;
  if (H != nullptr) H->setZero();
  return -w.dot(q.points[point]);
}

double ConstantForce::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  const Vector3 F = scale * force;
  // f = ∂V/∂p = −F and ∂²V/∂p² = 0, through p = x + R p̄ (eqs. 22, 23).
  if (g != nullptr || H != nullptr) attached_point_derivatives(at.lever(q), -F, Matrix3::Zero(), g, H);
  return -F.dot(at.position(q));
}

Eigen::Matrix<double, 6, 3> ConstantForce::force_jacobian(const State& q) const {
  Eigen::Matrix<double, 6, 3> J;
  J << -scale * Matrix3::Identity(), -scale * so3::hat(at.lever(q));  // ∂[f; r × f]/∂F, f = −F
  return J;
}

void ConstantTorque::begin_step(const State& previous, const Step&) {
  R_previous = previous.rotations[rotation];
}

double torque_potential(const Matrix3& P, const Vector3& tau, LocalGradient<1>* g,
                        LocalHessian<1>* H) {
  if (g != nullptr) *g = -0.5 * (P.trace() * tau - P.transpose() * tau);
  if (H != nullptr) {
    const Matrix3 T = so3::hat(tau);
    *H = 0.25 * (P * T - T * P.transpose()) - 0.5 * (T * P).trace() * Matrix3::Identity();
  }
  return -tau.dot(so3::vee(P));
}

double ConstantTorque::evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const {
  return torque_potential(q.rotations[rotation] * R_previous.transpose(), scale * torque, g, H);
}

Matrix3 ConstantTorque::torque_jacobian(const State& q) const {
  const Matrix3 P = q.rotations[rotation] * R_previous.transpose();
  return -0.5 * scale * (P.trace() * Matrix3::Identity() - P.transpose());
}

Matrix3 ConstantTorque::previous_jacobian(const State& q) const {
  const Matrix3 P = q.rotations[rotation] * R_previous.transpose();
  const Vector3 tau = scale * torque;
  return -(tau * so3::vee(P).transpose() + 0.5 * so3::hat(P.transpose() * tau));
}

void RegionForce::begin_step(const State& previous, const Step&) {
  active = (previous.points[point] - center).norm() <= radius;
}

double RegionForce::evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const {
  const Vector3 F = active ? Vector3(scale * force) : Vector3::Zero();
  if (g != nullptr) *g = -F;
  if (H != nullptr) H->setZero();
  return -F.dot(q.points[point]);
}

void ConstantForce::add_parameter_adjoint(const State& q, int frame, const LocalGradient<2>& z,
                                          Eigen::VectorXd& dgamma) const {
  const int slot = control.slot_at(frame);
  if (slot >= 0) dgamma.segment<3>(slot) += force_jacobian(q).transpose() * z;
}

void ConstantTorque::add_step_adjoint(const State& q, const State&, const Step&,
                                      const LocalGradient<1>& z, Eigen::VectorXd& a_previous,
                                      Eigen::VectorXd&) const {
  a_previous.segment<3>(tangent_rotation(q, rotation)) += previous_jacobian(q).transpose() * z;
}

void ConstantTorque::add_parameter_adjoint(const State& q, int frame, const LocalGradient<1>& z,
                                           Eigen::VectorXd& dgamma) const {
  const int slot = control.slot_at(frame);
  if (slot >= 0) dgamma.segment<3>(slot) += torque_jacobian(q).transpose() * z;
}

}  // namespace liedyn

#include "body_contact.hpp"

#include <cmath>

#include "so3.hpp"

namespace liedyn {

SdfValue BodyContact::field(const State& q, Vector3& w, bool with_hessian) const {
  const Matrix3& R_b = q.rotations[body_b];
  w = at.position(q) - q.points[body_b];
  SdfValue s = shape->evaluate(R_b.transpose() * w, with_hessian);  // in B's coordinates
  s.gradient = R_b * s.gradient;
  if (with_hessian) s.hessian = R_b * s.hessian * R_b.transpose();
  return s;
}

double BodyContact::penetration(const State& q) const {
  Vector3 w;
  return radius - field(q, w, false).distance;
}

double BodyContact::evaluate(const State& q, LocalGradient<kBlocks>* g,
                             LocalHessian<kBlocks>* H) const {
  Vector3 w;
  const SdfValue s = field(q, w, H != nullptr);
  const double d = radius - s.distance;
  if (!(d > 0.0)) {
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  if (g == nullptr && H == nullptr) return 0.5 * stiffness * d * d;
  const Vector3 r = at.lever(q);
  const Vector3 f = -stiffness * d * s.gradient;  // ∂V/∂p
  Eigen::Matrix<double, 3, 12> J;
  J << Matrix3::Identity(), -so3::hat(r), -Matrix3::Identity(), so3::hat(w);
  if (g != nullptr) *g = J.transpose() * f;
  if (H != nullptr) {
    const Matrix3 K = stiffness * (s.gradient * s.gradient.transpose() - d * s.hessian);
    const Eigen::Matrix<double, 12, 3> JtK = J.transpose() * K;
    H->noalias() = JtK.lazyProduct(J);
    const Matrix3 F = so3::hat(f);
    H->block<3, 3>(3, 3) += rotated_point_curvature(r, f);
    H->block<3, 3>(9, 9) += rotated_point_curvature(w, f);
    H->block<3, 3>(9, 0) += F;
    H->block<3, 3>(0, 9) -= F;  // (hat f)ᵀ
    H->block<3, 3>(9, 6) -= F;
    H->block<3, 3>(6, 9) += F;
    const Matrix3 FS = F * so3::hat(r);
    H->block<3, 3>(9, 3) -= FS;
    H->block<3, 3>(3, 9) -= FS.transpose();
  }
  return 0.5 * stiffness * d * d;
}

void BodyContact::residual(const State& q, Residual& res, ResidualJacobian* J) const {
  Vector3 w;
  const SdfValue s = field(q, w, false);
  const double d = radius - s.distance;
  if (!(d > 0.0)) {
    res(0) = 0.0;
    if (J != nullptr) J->setZero();
    return;
  }
  const double root_k = std::sqrt(stiffness);
  res(0) = root_k * d;
  if (J != nullptr) {
    const Vector3& n = s.gradient;
    const Vector3 r = at.lever(q);
    // −√k nᵀ [I, −hat(r), −I, hat(w)]: nᵀ(−hat(r)) = (r × n)ᵀ, nᵀ hat(w) = −(w × n)ᵀ.
    J->block<1, 3>(0, 0) = -root_k * n.transpose();
    J->block<1, 3>(0, 3) = -root_k * r.cross(n).transpose();
    J->block<1, 3>(0, 6) = root_k * n.transpose();
    J->block<1, 3>(0, 9) = root_k * w.cross(n).transpose();
  }
}

}  // namespace liedyn

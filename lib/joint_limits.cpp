#include "joint_limits.hpp"

#include <cmath>
#include <numbers>

#include "so3.hpp"

namespace liedyn {

void HingeAngle::begin_step(const State& previous_state) { previous = value(previous_state, nullptr, nullptr); }

double HingeAngle::value(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  const Matrix3& R_a = rotation_or_identity(q, rotation_a);
  const Vector3 n = R_a * axis_a, u = R_a * reference_a, v = u.cross(n);
  const Vector3 w = rotation_or_identity(q, rotation_b) * reference_b;
  const double x = u.dot(w), y = v.dot(w), rho2 = x * x + y * y;
  // The branch nearest the angle at the start of the step (header).
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  const double xi = previous + std::remainder(std::atan2(y, x) - previous, kTwoPi);
  if (g == nullptr && H == nullptr) return xi;
  const Vector3 t = (x * v - y * u) / rho2;  // ∂ξ/∂w
  const Vector3 gamma = w.cross(t);          // Dξ/Dθ_b
  if (g != nullptr) *g << -gamma, gamma;
  if (H != nullptr) {
    Eigen::Matrix<double, 3, 2> uv;
    uv << u, v;
    Eigen::Matrix2d S;
    S << 2.0 * x * y, y * y - x * x, y * y - x * x, -2.0 * x * y;
    const Matrix3 N = uv * S * uv.transpose() / (rho2 * rho2);
    const Matrix3 hat_w = so3::hat(w);
    const Matrix3 Hb = rotated_point_curvature(w, t) + hat_w.transpose() * N * hat_w;
    const Matrix3 mixed = -Hb + 0.5 * so3::hat(gamma);
    H->block<3, 3>(0, 0) = Hb;
    H->block<3, 3>(3, 3) = Hb;
    H->block<3, 3>(0, 3) = mixed;
    H->block<3, 3>(3, 0) = mixed.transpose();
  }
  return xi;
}

double SliderPosition::value(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
  const Vector3 n = q.rotations[a.rotation] * axis_a;
  const Vector3 d = b.position(q) - a.position(q);
  const Vector3 r_a = a.lever(q), r_b = b.lever(q);
  if (g != nullptr) *g << -n, n.cross(d + r_a), n, r_b.cross(n);
  if (H != nullptr) {
    H->setZero();
    H->block<3, 3>(3, 3) = rotated_point_curvature(n, d) + rotated_point_curvature(r_a, -n);
    H->block<3, 3>(9, 9) = rotated_point_curvature(r_b, n);
    Eigen::Matrix<double, 3, 12> D;
    D << -Matrix3::Identity(), so3::hat(r_a), Matrix3::Identity(), -so3::hat(r_b);
    const Eigen::Matrix<double, 3, 12> nD = so3::hat(n) * D;
    H->block<3, 12>(3, 0) += nD;
    H->block<12, 3>(0, 3) += nD.transpose();
    *H = -*H;
  }
  if (g != nullptr) *g = -*g;
  return -n.dot(d) - origin;
}

template <class Coordinate>
double JointLimit<Coordinate>::gap(const State& q, LocalGradient<kBlocks>* g,
                                   LocalHessian<kBlocks>* H) const {
  const double xi = coordinate.value(q, g, H);
  if (g != nullptr) *g *= side;
  if (H != nullptr) *H *= side;
  return side * (xi - bound);
}

template <class Coordinate>
double JointLimit<Coordinate>::evaluate(const State& q, LocalGradient<kBlocks>* g,
                                        LocalHessian<kBlocks>* H) const {
  const bool derivatives = g != nullptr || H != nullptr;
  LocalGradient<kBlocks> dg;
  LocalHessian<kBlocks> ddg;
  const double c = gap(q, derivatives ? &dg : nullptr, H != nullptr ? &ddg : nullptr);
  if (adjoint) {  // header: the Lagrangian of an active row, nothing of an inactive one
    const double lambda = multiplier(0);
    const bool active = lambda > 0.0;
    if (g != nullptr) *g = active ? ((lambda + stiffness * c) * dg).eval() : LocalGradient<kBlocks>::Zero().eval();
    if (H != nullptr) {
      *H = active ? (stiffness * dg * dg.transpose() + lambda * ddg).eval() : LocalHessian<kBlocks>::Zero().eval();
    }
    return active ? lambda * c + 0.5 * stiffness * c * c : 0.0;
  }
  const double m = penetration(c);
  if (g != nullptr) *g = stiffness * m * dg;
  if (H != nullptr) {
    *H = m > 0.0 ? (stiffness * (dg * dg.transpose() + m * ddg)).eval() : LocalHessian<kBlocks>::Zero().eval();
  }
  return 0.5 * stiffness * m * m;
}

template <class Coordinate>
void JointLimit<Coordinate>::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  LocalGradient<kBlocks> dg;
  const double m = penetration(gap(q, J != nullptr ? &dg : nullptr));
  const double s = std::sqrt(stiffness);
  r(0) = s * m;
  if (J != nullptr) {
    if (m > 0.0) {
      *J = s * dg.transpose();
    } else {
      J->setZero();
    }
  }
}

template <class Coordinate>
Vector3 JointLimit<Coordinate>::force(const State& q) const {
  return Vector3(stiffness * penetration(gap(q)), 0.0, 0.0);
}

template <class Coordinate>
Vector3 JointLimit<Coordinate>::constraint(const State& q, ConstraintJacobian* J) const {
  LocalGradient<kBlocks> dg;
  const double c = gap(q, J != nullptr ? &dg : nullptr);
  const bool active = adjoint ? multiplier(0) > 0.0 : penetration(c) > 0.0;
  if (J != nullptr) {
    J->setZero();
    if (active) J->row(0) = dg.transpose();
  }
  return Vector3(active ? c : 0.0, 0.0, 0.0);
}

template struct JointLimit<HingeAngle>;
template struct JointLimit<SliderPosition>;

}  // namespace liedyn

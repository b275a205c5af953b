#include "so3.hpp"

#include <cmath>

namespace liedyn::so3 {
namespace {

// Coefficients of Rodrigues-type series, accurate for every t ≥ 0.
//   a(t) = sin t / t,  b(t) = (1 − cos t)/t²,  c(t) = (t − sin t)/t³.
// Below t = 0.1 all three are their Taylor series in t², to the term below 2e-20 (the closed
// forms lose digits as t → 0, c badly; and the series cost less than the sines, which matters
// for the small steps every retraction takes). Above it: sin t, and b as 2 sin²(t/2)/t², which
// has no cancellation. c only where asked for (exp's Jacobian, J_l).
struct RodriguesCoefficients {
  double a, b, c;
};

RodriguesCoefficients rodrigues_coefficients(double t, bool with_c) {
  const double t2 = t * t;
  RodriguesCoefficients k{};
  if (t < 0.1) {
    k.a = 1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 + t2 * (-1.0 / 5040.0 + t2 * (1.0 / 362880.0 +
                                                                t2 * (-1.0 / 39916800.0)))));
    k.b = 0.5 + t2 * (-1.0 / 24.0 + t2 * (1.0 / 720.0 + t2 * (-1.0 / 40320.0 + t2 * (1.0 / 3628800.0 +
                                                                t2 * (-1.0 / 479001600.0)))));
    if (with_c) {
      k.c = 1.0 / 6.0 + t2 * (-1.0 / 120.0 + t2 * (1.0 / 5040.0 + t2 * (-1.0 / 362880.0 +
                                                                      t2 / 39916800.0)));
    }
  } else {
    const double sine = std::sin(t);
    const double half = std::sin(0.5 * t);
    k.a = sine / t;
    k.b = 2.0 * half * half / t2;
    if (with_c) k.c = (t - sine) / (t2 * t);
  }
  return k;
}

}  // namespace

Matrix3 exp(const Vector3& theta, Matrix3* J_R_theta) {
  const double t = theta.norm();
  const RodriguesCoefficients k = rodrigues_coefficients(t, J_R_theta != nullptr);
  const Matrix3 W = hat(theta);
  const Matrix3 W2 = W * W;
  if (J_R_theta != nullptr) *J_R_theta = Matrix3::Identity() + k.b * W + k.c * W2;
  return Matrix3::Identity() + k.a * W + k.b * W2;
}

Matrix3 left_jacobian(const Vector3& theta) {
  const RodriguesCoefficients k = rodrigues_coefficients(theta.norm(), true);
  const Matrix3 W = hat(theta);
  return Matrix3::Identity() + k.b * W + k.c * W * W;
}

Matrix3 left_jacobian_inverse(const Vector3& theta) {
  const double t = theta.norm();
  // d(t) = 1/t² − cot(t/2)/(2t) = 1/t² − (1 + cos t)/(2 t sin t); cot(t/2) stays finite at π.
  double d;
  if (t < 0.1) {
    const double t2 = t * t;
    // 1/12 + t²/720 + t⁴/30240 + t⁶/1209600; the next term is below 1e-14 · t⁸.
    d = 1.0 / 12.0 + t2 * (1.0 / 720.0 + t2 * (1.0 / 30240.0 + t2 / 1209600.0));
  } else {
    d = 1.0 / (t * t) - 0.5 / (t * std::tan(0.5 * t));
  }
  const Matrix3 W = hat(theta);
  return Matrix3::Identity() - 0.5 * W + d * W * W;
}

Vector3 log(const Matrix3& R, Matrix3* J_theta_R) {
  // sin t · n = vee(R) (antisymmetric part), cos t = (tr R − 1)/2; atan2 is accurate for all t.
  const Vector3 s_n = vee(R);
  const double s = s_n.norm();
  const double c = 0.5 * (R.trace() - 1.0);
  const double t = std::atan2(s, c);
  Vector3 theta;
  if (c > 0.0) {
    // t < π/2: θ = t/sin t · vee(R). t/sin t → 1 at 0 (series below 1e-4).
    const double t_over_s = (t < 1e-4) ? 1.0 + t * t / 6.0 : t / s;
    theta = t_over_s * s_n;
  } else {
    // t ≥ π/2: sin t may vanish, so take the axis from the symmetric part,
    // ½(R + Rᵀ) = cos t I + (1 − cos t) n nᵀ, using its largest diagonal entry.
    const Matrix3 B = (0.5 * (R + R.transpose()) - c * Matrix3::Identity()) / (1.0 - c);
    int i = 0;
    B.diagonal().maxCoeff(&i);
    Vector3 n = B.col(i) / std::sqrt(B(i, i));
    // The symmetric part fixes n up to sign; the antisymmetric part (sin t n) fixes the sign.
    if (n.dot(s_n) < 0.0) n = -n;
    theta = t * n;
  }
  if (J_theta_R != nullptr) *J_theta_R = left_jacobian_inverse(theta);
  return theta;
}

Matrix3 from_quaternion(const Eigen::Quaterniond& q) { return q.normalized().toRotationMatrix(); }

Eigen::Quaterniond to_quaternion(const Matrix3& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  return q;
}

Matrix3 orthonormalize(const Matrix3& R) {
  return 0.5 * R * (3.0 * Matrix3::Identity() - R.transpose() * R);
}

double distance(const Matrix3& A, const Matrix3& B) { return log(A * B.transpose()).norm(); }

}  // namespace liedyn::so3

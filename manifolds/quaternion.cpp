#include "quaternion.hpp"

#include <cmath>

#include "../lib/so3.hpp"

namespace liedyn::quat {

namespace {

Vector3 vec(const Vector4& q) { return q.head<3>(); }

}  // namespace

// (a_s b_u + b_s a_u + a_u × b_u, a_s b_s − a_u · b_u)  (eq. A.14).
Vector4 product(const Vector4& a, const Vector4& b) {
  Vector4 ab;
  ab << a(3) * vec(b) + b(3) * vec(a) + vec(a).cross(vec(b)), a(3) * b(3) - vec(a).dot(vec(b));
  return ab;
}

// (−u, s)  (eq. A.13).
Vector4 inverse(const Vector4& q) { return Vector4(-q(0), -q(1), -q(2), q(3)); }

// A = [a_u* + a_s I, a_u; −a_uᵀ, a_s]  (eq. A.15).
Matrix4 left_matrix(const Vector4& a) {
  Matrix4 A;
  A.topLeftCorner<3, 3>() = so3::hat(vec(a)) + a(3) * Matrix3::Identity();
  A.topRightCorner<3, 1>() = vec(a);
  A.bottomLeftCorner<1, 3>() = -vec(a).transpose();
  A(3, 3) = a(3);
  return A;
}

// B = [−b_u* + b_s I, b_u; −b_uᵀ, b_s]: the cross product changes sign because a b ≠ b a
// (eq. A.16).
Matrix4 right_matrix(const Vector4& b) {
  Matrix4 B;
  B.topLeftCorner<3, 3>() = -so3::hat(vec(b)) + b(3) * Matrix3::Identity();
  B.topRightCorner<3, 1>() = vec(b);
  B.bottomLeftCorner<1, 3>() = -vec(b).transpose();
  B(3, 3) = b(3);
  return B;
}

// Eq. A.21, entry by entry as printed (v ↦ q v q⁻¹ of eq. A.19, Hamilton's convention).
Matrix3 rotation(const Vector4& q) {
  const double x = q(0), y = q(1), z = q(2), s = q(3);
  Matrix3 R;
  R << x * x - y * y - z * z + s * s, 2 * y * x - 2 * z * s, 2 * z * x + 2 * y * s,  //
      2 * x * y + 2 * z * s, -x * x + y * y - z * z + s * s, 2 * z * y - 2 * x * s,  //
      2 * x * z - 2 * y * s, 2 * y * z + 2 * x * s, -x * x - y * y + z * z + s * s;
  return R;
}

// Eq. A.23: linear in q because A.21 is quadratic.
void rotation_derivatives(const Vector4& q, Matrix3 dR[4]) {
  const double x = q(0), y = q(1), z = q(2), s = q(3);
  dR[0] << x, y, z, y, -x, -s, z, s, -x;
  dR[1] << -y, x, s, x, y, z, -s, z, -y;
  dR[2] << -z, -s, x, s, -z, y, x, y, z;
  dR[3] << s, -z, y, z, s, -x, -y, x, s;
  for (int i = 0; i < 4; ++i) dR[i] *= 2.0;
}

// Q = ½ [−u* + sI; −uᵀ], the right matrix B(q) of eq. A.16 restricted to ω_q = (ω, 0):
// q̇ = ½ ω_q q (eq. A.24, A.25). ω_q multiplies from the left, so ω is in the world frame.
Eigen::Matrix<double, 4, 3> rate_matrix(const Vector4& q) {
  Eigen::Matrix<double, 4, 3> Q;
  Q.topRows<3>() = 0.5 * (-so3::hat(vec(q)) + q(3) * Matrix3::Identity());
  Q.bottomRows<1>() = -0.5 * vec(q).transpose();
  return Q;
}

// Shepperd's method. By eq. A.21 with ‖q‖ = 1,
//   4s² = 1 + R₀₀ + R₁₁ + R₂₂,   4x² = 1 + R₀₀ − R₁₁ − R₂₂   (likewise y², z²),
//   4xs = R₂₁ − R₁₂,  4ys = R₀₂ − R₂₀,  4zs = R₁₀ − R₀₁,
//   4xy = R₁₀ + R₀₁,  4xz = R₀₂ + R₂₀,  4yz = R₂₁ + R₁₂.
// The largest of the four squares is ≥ ¼, so taking its square root and dividing the three
// matching products by it never loses precision (the s-only formula fails near π, where s → 0).
Vector4 from_rotation(const Matrix3& R) {
  const Eigen::Vector4d squares(1.0 + R(0, 0) - R(1, 1) - R(2, 2),   // 4x²
                                1.0 - R(0, 0) + R(1, 1) - R(2, 2),   // 4y²
                                1.0 - R(0, 0) - R(1, 1) + R(2, 2),   // 4z²
                                1.0 + R(0, 0) + R(1, 1) + R(2, 2));  // 4s²
  Eigen::Index k;
  squares.maxCoeff(&k);
  const double c = 0.5 * std::sqrt(squares(k));  // |q_k|
  const double f = 0.25 / c;
  Vector4 q;
  switch (k) {
    case 0:
      q << c, f * (R(1, 0) + R(0, 1)), f * (R(0, 2) + R(2, 0)), f * (R(2, 1) - R(1, 2));
      break;
    case 1:
      q << f * (R(1, 0) + R(0, 1)), c, f * (R(2, 1) + R(1, 2)), f * (R(0, 2) - R(2, 0));
      break;
    case 2:
      q << f * (R(0, 2) + R(2, 0)), f * (R(2, 1) + R(1, 2)), c, f * (R(1, 0) - R(0, 1));
      break;
    default:
      q << f * (R(2, 1) - R(1, 2)), f * (R(0, 2) - R(2, 0)), f * (R(1, 0) - R(0, 1)), c;
      break;
  }
  // q and −q are the same rotation: pick s ≥ 0. Normalising absorbs the round-off of R.
  return (q(3) < 0.0 ? -q : q).normalized();
}

// Q(q) δ ⊥ q, so ‖q + Q(q) δ‖ = √(1 + ‖δ‖²/4) for unit q: the step never degenerates.
Vector4 retract(const Vector4& q, const Vector3& delta) {
  return (q + rate_matrix(q) * delta).normalized();
}

}  // namespace liedyn::quat

#pragma once
// Smooth test functions Ψ(R) of one rotation with hand-derived Lie gradient g and Lie Hessian
// H (lib/so3.hpp: ∂/∂θ and ∂²/∂θ² of Ψ(exp(θ)R) at θ = 0), shared by the parameterisation
// tests (tests/test_rotation_vector.cpp, tests/test_quaternion.cpp), which check them by
// finite differences before relying on them. Both use exp(θ) = I + hat(θ) + ½hat(θ)² + O(θ³),
// tr(M hat(θ)) = −2 vee(M)·θ and hat(θ)² = θθᵀ − |θ|² I.

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <string>

#include "lib/so3.hpp"

namespace liedyn::test_functions {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

struct TestFunction {
  std::string name;
  std::function<double(const Matrix3&)> value;
  std::function<Vector3(const Matrix3&)> gradient;
  std::function<Matrix3(const Matrix3&)> hessian;
};

inline Matrix3 sym(const Matrix3& M) { return 0.5 * (M + M.transpose()); }

// Ψ(R) = tr(A R) + ½‖R p − y‖². With M = R A, q = R p, d = q − y:
//   tr(A exp(θ)R) = tr(M) + tr(M hat(θ)) + ½tr(M hat(θ)²)  →  g = −2 vee(M),  H = sym(M) − tr(M) I;
//   q⁺ = q + θ × q + ½ hat(θ)² q  →  g = q × d,  H = |q|² I − q qᵀ + sym(d qᵀ) − (d·q) I.
inline TestFunction trace_and_point(const Matrix3& A, const Vector3& p, const Vector3& y) {
  return {"tr(AR) + ½|Rp − y|²",
          [=](const Matrix3& R) { return (A * R).trace() + 0.5 * (R * p - y).squaredNorm(); },
          [=](const Matrix3& R) {
            const Vector3 q = R * p;
            return Vector3(-2.0 * so3::vee(R * A) + q.cross(q - y));
          },
          [=](const Matrix3& R) {
            const Matrix3 M = R * A;
            const Vector3 q = R * p;
            const Vector3 d = q - y;
            return Matrix3(sym(M) - M.trace() * Matrix3::Identity() +
                           q.squaredNorm() * Matrix3::Identity() - q * q.transpose() +
                           sym(d * q.transpose()) - d.dot(q) * Matrix3::Identity());
          }};
}

// Ψ(R) = ½ (uᵀ R w)². With q = R w, s = u·q: s⁺ = s + θ·(q × u) + ½ uᵀ hat(θ)² q, so
//   g = s (q × u),  H = (q × u)(q × u)ᵀ + s (sym(u qᵀ) − (u·q) I).
inline TestFunction squared_bilinear(const Vector3& u, const Vector3& w) {
  return {
      "½(uᵀRw)²", [=](const Matrix3& R) { return 0.5 * std::pow(u.dot(R * w), 2); },
      [=](const Matrix3& R) {
        const Vector3 q = R * w;
        return Vector3(u.dot(q) * q.cross(u));
      },
      [=](const Matrix3& R) {
        const Vector3 q = R * w;
        const Vector3 c = q.cross(u);
        const double s = u.dot(q);
        return Matrix3(c * c.transpose() + s * (sym(u * q.transpose()) - s * Matrix3::Identity()));
      }};
}

}  // namespace liedyn::test_functions

#include "spring.hpp"

#include <cmath>

#include "point_pair.hpp"
#include "so3.hpp"

namespace liedyn {

double Spring::evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
  const Vector3 d = b.position(q) - a.position(q);
  if (g == nullptr && H == nullptr) {
    const double stretch = d.norm() - rest_length;
    return 0.5 * stiffness * stretch * stretch;
  }
  const auto [value, f, K] = length_spring(d, stiffness, rest_length);  // ∂V/∂d, ∂²V/∂d²

  point_pair_derivatives(a.lever(q), b.lever(q), f, K, g, H);  // eqs. (22), (23)
  return value;
}

void Spring::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const Vector3 d = b.position(q) - a.position(q);
  const double sqrt_k = std::sqrt(stiffness);
  Matrix3 A;  // ∂r/∂d
  if (rest_length == 0.0) {
    r = sqrt_k * d;  // √k d
    A = sqrt_k * Matrix3::Identity();
  } else {
    // Same branches as length_spring, so that Jᵀr is evaluate()'s gradient everywhere.
    const double l = d.norm();
    if (!(l > 0.0)) {
      r = Vector3(-sqrt_k * rest_length, 0.0, 0.0);  // d = 0: see spring.hpp
      if (J != nullptr) J->setZero();
      return;
    }
    const double inv_l = 1.0 / l;
    const Vector3 n = inv_l * d;
    const double stretch = l - rest_length;
    r = (sqrt_k * stretch) * n;  // √k (d − L n) = √k (l − L) n, without cancellation
    // √k [L/l n nᵀ + (l − L)/l I]: neither coefficient a difference (as in length_spring).
    A = (sqrt_k * rest_length * inv_l) * (n * n.transpose()) +
        (sqrt_k * stretch * inv_l) * Matrix3::Identity();
  }
  if (J != nullptr) {
    // A ∂d/∂(x_a, θ_a, x_b, θ_b) = [−A, A hat(r_a), A, −A hat(r_b)]
    const Matrix3 A_hat_ra = A * so3::hat(a.lever(q));
    const Matrix3 A_hat_rb = A * so3::hat(b.lever(q));
    *J << -A, A_hat_ra, A, -A_hat_rb;
  }
}

}  // namespace liedyn

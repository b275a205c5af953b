#include "spring.hpp"

#include "so3.hpp"

namespace liedyn {

double Spring::evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
  const Vector3 d = b.position(q) - a.position(q);
  if (g == nullptr && H == nullptr) {
    const double stretch = d.norm() - rest_length;
    return 0.5 * stiffness * stretch * stretch;
  }
  const auto [value, f, K] = length_spring(d, stiffness, rest_length);  // ∂V/∂d, ∂²V/∂d²

  const Vector3 r_a = a.lever(q);
  const Vector3 r_b = b.lever(q);
  Eigen::Matrix<double, 3, 12> Jd;  // ∂d/∂(x_a, θ_a, x_b, θ_b)
  Jd << -Matrix3::Identity(), so3::hat(r_a), Matrix3::Identity(), -so3::hat(r_b);
  if (g != nullptr) *g = Jd.transpose() * f;
  if (H != nullptr) {
    // Coefficient-based (lazy) product: a plain 12×3·3×12 product is large enough for Eigen
    // to dispatch it to its blocked GEMM kernel, whose packing costs more than the flops.
    const Eigen::Matrix<double, 12, 3> JtK = Jd.transpose() * K;
    H->noalias() = JtK.lazyProduct(Jd);
    H->block<3, 3>(3, 3) += rotated_point_curvature(r_a, -f);  // f_a = ∂V/∂p_a = −f
    H->block<3, 3>(9, 9) += rotated_point_curvature(r_b, f);
  }
  return value;
}

}  // namespace liedyn

#include "rotation_vector.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace liedyn::rotvec {
namespace {

using so3::hat;

// The scalar functions of eq. (4) and of J_l are members of one family,
//   f_n(t) = Σ_{k≥0} (−1)^k t^{2k} / (2k+n)!:
//   f_1 = sin t / t = σ(t) (sinc),  f_2 = (1 − cos t)/t² = ½σ²(t/2) = a,  f_3 = (t − sin t)/t³ = b,
// and f_0 = cos t. Since (tⁿ f_n)' = t^{n−1} f_{n−1}, their derivatives divided by t are
//   f_n'(t)/t = (f_{n−1} − n f_n)/t²,
// which is what every formula below needs (∂t/∂r_i = r_i/t).
struct Family {
  double f1, f2, f3;  // f_n(t)
  double d1, d2, d3;  // f_n'(t)/t
};

// Series below t = kSeriesBelow, terms k ≤ kLastTerm; closed forms above.
// Why 2: the closed forms of f_n'/t cancel (f_{n−1} ≈ n f_n near 0), with relative round-off
// ≈ c ε/t², c up to a few hundred for f_3'/t (whose f_3 already cancels in t − sin t).
// Why 12 terms: for t < 2 the first omitted term (k = 13) is below 2e-19 relative for every
// f_n and f_n'/t.
// Measured against quad precision on (0, 2π) (relative, or in units of the value at 0 near a
// zero): f_n within 2 ulps, f_1'/t and f_2'/t within 5, f_3'/t within 16 (just above the
// switch); switching at 1 instead would leave 80 ulps there.
constexpr double kSeriesBelow = 2.0;
constexpr int kLastTerm = 12;

// 1/m! for m ≤ 2·kLastTerm + 3.
constexpr auto kInverseFactorial = [] {
  std::array<double, 2 * kLastTerm + 4> inv{};
  double factorial = 1.0;
  for (std::size_t m = 0; m < inv.size(); ++m) {
    if (m > 0) factorial *= static_cast<double>(m);
    inv[m] = 1.0 / factorial;
  }
  return inv;
}();

// f_n(t) and f_n'(t)/t = Σ_{k≥1} (−1)^k 2k t^{2k−2}/(2k+n)!, by Horner in t², smallest term first.
void series(double t2, int n, double& value, double& slope) {
  value = 0.0;
  slope = 0.0;
  for (int k = kLastTerm; k >= 0; --k) {
    const double c = (k % 2 == 0 ? 1.0 : -1.0) * kInverseFactorial[2 * k + n];
    value = value * t2 + c;
    if (k > 0) slope = slope * t2 + 2.0 * k * c;
  }
}

Family family(double t) {
  const double t2 = t * t;
  Family f{};
  if (t < kSeriesBelow) {
    series(t2, 1, f.f1, f.d1);
    series(t2, 2, f.f2, f.d2);
    series(t2, 3, f.f3, f.d3);
    return f;
  }
  const double sin_t = std::sin(t);
  const double sin_half = std::sin(0.5 * t);
  f.f1 = sin_t / t;
  f.f2 = 2.0 * sin_half * sin_half / t2;  // 1 − cos t without cancellation
  f.f3 = (t - sin_t) / (t2 * t);
  f.d1 = (std::cos(t) - f.f1) / t2;
  f.d2 = (f.f1 - 2.0 * f.f2) / t2;
  f.d3 = (f.f2 - 3.0 * f.f3) / t2;
  return f;
}

}  // namespace

// With J_l = I + a hat(r) + b hat(r)², a = f_2, b = f_3, α = a'/t, β = b'/t:
//   ∂J_l/∂r_i = α r_i hat(r) + a hat(e_i) + β r_i hat(r)² + b (hat(e_i) hat(r) + hat(r) hat(e_i)).
// Contracted as gᵀ (∂J_l/∂r_i) e_j:
//   gᵀ hat(e_i) e_j = g·(e_i × e_j) and gᵀ hat(r) hat(e_i) e_j = (g × r)·(e_i × e_j) are
//     antisymmetric in (i, j): they drop out of C;
//   gᵀ hat(r) e_j = (g × r)_j,  gᵀ hat(r)² e_j = (hat(r)² g)_j,
//   gᵀ hat(e_i) hat(r) e_j = −(hat(g) hat(r))_ij = (g·r) δ_ij − r_i g_j.
// Hence gᵀ (∂J_l/∂r_i) e_j = r_i v_j + b (g·r) δ_ij + (antisymmetric), and
//   C = ½ (r vᵀ + v rᵀ) + b (g·r) I,   v = α (g × r) + β hat(r)² g − b g.
Matrix3 hessian_correction(const Vector3& r, const Vector3& g) {
  const Family f = family(r.norm());
  const Vector3 v = f.d2 * g.cross(r) + f.d3 * r.cross(r.cross(g)) - f.f3 * g;
  const Matrix3 rv = r * v.transpose();
  return 0.5 * (rv + rv.transpose()) + (f.f3 * g.dot(r)) * Matrix3::Identity();
}

// Eq. (5), with h = t/2 and W = hat(r), R = I + σ(t) W + ½σ²(h) W² (eq. 4):
//   ∂R/∂r_k = (σ'(t)/t) r_k W + σ(t) hat(e_k) + ¼ σ(h) (σ'(h)/h) r_k W²
//             + ½σ²(h) (hat(e_k) W + W hat(e_k)),
// using ∂t/∂r_k = r_k/t, ∂h/∂r_k = r_k/(2t). The last term is the product rule for W², which
// eq. (5) abbreviates as skew(r) skew'(r) (hat(e_k) and W do not commute).
Eigen::Matrix<double, 9, 3> exp_jacobian(const Vector3& r) {
  const double t = r.norm();
  const Family full = family(t);
  const Family half = family(0.5 * t);
  const double half_sigma_sq = 0.5 * half.f1 * half.f1;
  const Matrix3 W = hat(r);
  const Matrix3 W2 = W * W;
  Eigen::Matrix<double, 9, 3> J;
  for (int k = 0; k < 3; ++k) {
    const Matrix3 E = hat(Vector3::Unit(k));
    const Matrix3 dR = (full.d1 * r(k)) * W + full.f1 * E + (0.25 * half.f1 * half.d1 * r(k)) * W2 +
                       half_sigma_sq * (E * W + W * E);
    J.col(k) = dR.reshaped();  // column-major: vec stacks columns
  }
  return J;
}

// r (1 − 2πn/‖r‖) for the integer n that brings the angle into [−π, π]: the same as
// subtracting 2π r/‖r‖ while ‖r‖ > π, in one step (std::remainder is exact).
Vector3 wrap(const Vector3& r) {
  const double t = r.norm();
  if (t <= std::numbers::pi) return r;
  return (std::remainder(t, 2.0 * std::numbers::pi) / t) * r;
}

}  // namespace liedyn::rotvec

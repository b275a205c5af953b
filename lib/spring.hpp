#pragma once
// Linear spring between two attached points (bodies or world anchors), paper eqs. 22–23.
//
//   V = ½ k (‖d‖ − L)²,   d = p_b − p_a,   p = x + R p̄.
// With l = ‖d‖, n = d/l:
//   ∂V/∂d = k (l − L) n,
//   ∂²V/∂d² = k n nᵀ + k (l − L)/l (I − n nᵀ)    (L = 0: exactly k I).
// Blocks (x_a, θ_a, x_b, θ_b); ∂d/∂(blocks) = [−I, hat(r_a), I, −hat(r_b)], r = R p̄. Then
//   gradient = (∂d)ᵀ ∂V/∂d,   Hessian = (∂d)ᵀ ∂²V/∂d² (∂d) + eq. (23) curvature at each rotation.
// The Hessian is exact and indefinite for a compressed spring (l < L) and for some lever
// configurations; the Newton solver regularises the assembled matrix (see solvers/newton.hpp).

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// V(d) = ½ k (‖d‖ − L)² and its derivatives with respect to the vector d:
//   f = ∂V/∂d = k (l − L) n,   K = ∂²V/∂d² = k n nᵀ + k (l − L)/l (I − n nᵀ),   n = d/l.
// L = 0 gives exactly f = k d, K = k I. At d = 0 with L > 0 the direction is undefined and V
// is stationary along every direction at first order: f = 0 and the isotropic limit K = k I.
// Shared by Spring and the rod's stretch term (lib/rod_terms.hpp). Inline, so that the
// result stays in registers: returned through memory, its 3×3 block was stored in 2-wide
// pieces and read back in pieces straddling them, which store forwarding cannot serve (the
// rod's stretch term spent ~40 % of its time on that).
struct LengthSpringDerivatives {
  double value;
  Vector3 f;
  Matrix3 K;
};
inline LengthSpringDerivatives length_spring(const Vector3& d, double stiffness,
                                             double rest_length) {
  const double l = d.norm();
  const double stretch = l - rest_length;
  LengthSpringDerivatives out;
  out.value = 0.5 * stiffness * stretch * stretch;
  if (rest_length != 0.0 && l > 0.0) {
    const double inv_l = 1.0 / l;
    const Vector3 n = inv_l * d;
    out.f = (stiffness * stretch) * n;
    // k n nᵀ + k (l − L)/l (I − n nᵀ) = k L/l n nᵀ + k (l − L)/l I: the same matrix, with
    // neither coefficient a difference.
    out.K = (stiffness * rest_length * inv_l) * (n * n.transpose()) +
            (stiffness * stretch * inv_l) * Matrix3::Identity();
  } else {
    out.f = rest_length == 0.0 ? Vector3(stiffness * d) : Vector3::Zero();
    out.K = stiffness * Matrix3::Identity();
  }
  return out;
}

struct Spring {
  static constexpr int kBlocks = 4;
  std::array<int, kBlocks> offsets{-1, -1, -1, -1};  // x_a, θ_a, x_b, θ_b
  AttachedPoint a, b;
  double stiffness = 0.0;    // k  [N/m]
  double rest_length = 0.0;  // L  [m]

  double evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const;
};

}  // namespace liedyn

#pragma once
// Linear spring between two attached points (bodies or world anchors), paper eqs. 22–23.
//
//   V = ½ k (‖d‖ − L)²,   d = p_b − p_a,   p = x + R p̄.
// With l = ‖d‖, n = d/l:
//   ∂V/∂d = k (l − L) n,
//   ∂²V/∂d² = k n nᵀ + k (l − L)/l (I − n nᵀ)    (L = 0: exactly k I).
// Blocks (x_a, θ_a, x_b, θ_b); ∂d/∂(blocks) = [−I, hat(r_a), I, −hat(r_b)], r = R p̄. Then
//   gradient = (∂d)ᵀ ∂V/∂d,   Hessian = (∂d)ᵀ ∂²V/∂d² (∂d) + eq. (23) curvature at each rotation
// (point_pair_derivatives in point_pair.hpp, shared with the cable term).
// The Hessian is exact and indefinite for a compressed spring (l < L) and for some lever
// configurations; the Newton solver regularises the assembled matrix (see solvers/newton.hpp).
//
// Least-squares form (contract: term.hpp), 3 residuals:
//   r = √k (d − L n) = √k (l − L) n   (L = 0: r = √k d),   ½‖r‖² = ½ k (l − L)² = V.
// With ∂n/∂d = (I − n nᵀ)/l,
//   A = ∂r/∂d = √k [n nᵀ + (l − L)/l (I − n nᵀ)] = √k [L/l n nᵀ + (l − L)/l I]   (= K/√k),
//   J = A ∂d/∂(blocks) = [−A, A hat(r_a), A, −A hat(r_b)],
// and since A n = √k n, Jᵀr = (∂d)ᵀ k (l − L) n = (∂d)ᵀ f: the gradient above. Jᵀ J =
// (∂d)ᵀ A² (∂d) is Gauss–Newton: without the eq. (23) curvature and with A² ≠ K.
// At d = 0 with L > 0, r jumps (r → −√k L u as d = ε u → 0) and has no derivative; as for
// the gradient (f = 0, see length_spring) the residual is r = −√k L e_x with J = 0:
// ½‖r‖² = ½ k L² = V and Jᵀr = 0 = evaluate()'s gradient; the term then adds nothing to
// the Gauss–Newton model (evaluate()'s K = k I has no residual counterpart with Jᵀr = 0).

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// V(d) = ½ k (‖d‖ − L)² and its derivatives with respect to the vector d:
//   f = ∂V/∂d = k (l − L) n,   K = ∂²V/∂d² = k n nᵀ + k (l − L)/l (I − n nᵀ),   n = d/l.
// L = 0 gives exactly f = k d, K = k I. At d = 0 with L > 0 the direction is undefined and V
// is not differentiable: V(ε u) = ½ k L² − k L ε + O(ε²) along every unit u, a conical local
// maximum. We take f = 0 (the smallest element of its generalised gradient, the ball of
// radius k L) and K = k I (the value at L = 0, not a limit: K is unbounded as d → 0).
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
  static constexpr const char* kName = "spring";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1, -1, -1};  // x_a, θ_a, x_b, θ_b
  AttachedPoint a, b;
  double stiffness = 0.0;    // k  [N/m]
  double rest_length = 0.0;  // L  [m]
  int stiffness_slot = -1;   // γ index of k, −1: not a parameter (V ∝ k)

  double evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const;
  // HasParameters (term.hpp): the value is proportional to the stiffness.
  void add_parameter_adjoint(const State& q, int, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const {
    add_stiffness_adjoint(*this, q, z, dgamma);
  }

  static constexpr int kResiduals = 3;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  // r = √k (d − L d/‖d‖) and J = ∂r/∂(x_a, θ_a, x_b, θ_b) as derived at the top; ½‖r‖² equals
  // evaluate()'s value (constant 0). Needs k ≥ 0.
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

}  // namespace liedyn

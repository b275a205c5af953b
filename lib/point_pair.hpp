#pragma once
// Potentials of the vector between two attached points, V(d) with d = p_b − p_a, mapped to
// the four blocks (x_a, θ_a, x_b, θ_b) of the two points' frames (paper eqs. 22, 23;
// conventions: so3.hpp). Shared by the spring (spring.hpp) and cable (cable.hpp) terms, which
// differ only in V(d).
//
// With p = x + r, r = R p̄ (state.hpp, AttachedPoint), a left perturbation R ← exp(θ)R moves
// p by θ × r = −hat(r) θ, so
//   ∂d/∂(x_a, θ_a, x_b, θ_b) = Jd = [−I, hat(r_a), I, −hat(r_b)],
// and for f = ∂V/∂d, K = ∂²V/∂d² (symmetric),
//   gradient = Jdᵀ f                                         (eq. 22),
//   Hessian  = Jdᵀ K Jd + C(r_a, −f) at θ_aθ_a + C(r_b, f) at θ_bθ_b,
// where C(r, f_p) = ½ (f_p rᵀ + r f_pᵀ) − (f_p·r) I is the second-order term of a potential
// through a rotated point with f_p = ∂V/∂p (eq. 23, rotated_point_curvature in state.hpp):
// ∂V/∂p_a = −f, ∂V/∂p_b = f. C is indefinite in general, so the Hessian can be indefinite
// even where K is PSD. Points without a rotation have r = p̄ (or 0), and the θ blocks are then
// not DOFs (offset −1): they are written all the same and ignored by assembly.
// When both points share one rotation (or one node), the two blocks name the same DOF and
// assembly adds them: the mapping stays per block.

#include "so3.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// Writes (not adds) g = Jdᵀ f when g is non-null and H = Jdᵀ K Jd + eq. (23) terms when H is
// non-null; r_a, r_b are the levers p − x of the two points (AttachedPoint::lever).
// Inline, so that f and K can stay in registers between the caller's V(d) and this mapping.
inline void point_pair_derivatives(const Vector3& r_a, const Vector3& r_b, const Vector3& f,
                                   const Matrix3& K, LocalGradient<4>* g, LocalHessian<4>* H) {
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
}

// The same mapping for a potential of ONE attached point p = x + r, r = R p̄ (a force, a
// contact sample), with f = ∂V/∂p and K = ∂²V/∂p²: ∂p/∂(x, θ) = [I, −hat(r)], so
//   gradient = [f; r × f],
//   Hessian  = [[K, −K hat(r)], [hat(r) K, −hat(r) K hat(r) + C(r, f)]]   (eqs. 22, 23).
// Writes (not adds); g and H may be null. A point without a rotation still gets its θ block
// written, and assembly ignores it (offset −1).
inline void attached_point_derivatives(const Vector3& lever, const Vector3& f, const Matrix3& K,
                                       LocalGradient<2>* g, LocalHessian<2>* H) {
  if (g != nullptr) {
    g->head<3>() = f;
    g->tail<3>() = lever.cross(f);  // (22): −hat(r)ᵀ f = r × f
  }
  if (H != nullptr) {
    const Matrix3 S = so3::hat(lever);
    const Matrix3 KS = K * S;
    H->topLeftCorner<3, 3>() = K;
    H->topRightCorner<3, 3>() = -KS;               // K ∂p/∂θ
    H->bottomLeftCorner<3, 3>() = -KS.transpose();  // (K(−S))ᵀ = S K (K symmetric, S skew)
    H->bottomRightCorner<3, 3>() = -S * KS + rotated_point_curvature(lever, f);  // (23)
  }
}

}  // namespace liedyn

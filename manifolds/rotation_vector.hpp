#pragma once
// Rotation vectors r ∈ R³, R = exp(r) (paper §3.3, eq. 4), as a rotation parameterisation
// for Newton's method beside the Lie one (solvers/newton.hpp).
//
// With the Lie gradient g and Lie Hessian H of a function Ψ at R = exp(r) (lib/so3.hpp: left
// perturbations R⁺ = exp(θ) R), the derivatives of r ↦ Ψ(exp(r)) are
//   ∂Ψ/∂r   = J_l(r)ᵀ g,
//   ∂²Ψ/∂r² = J_l(r)ᵀ H J_l(r) + C(r, g),
// exactly: exp(r + ε) = exp(θ(ε)) exp(r) with θ'(0) = J_l(r) and θ''(0)[u, u] = (∂_u J_l(r)) u,
// so C(r, g) is the symmetric matrix of the quadratic form u ↦ gᵀ (∂_u J_l(r)) u. This is the
// chain rule through eq. (5), ∂R/∂r_k = hat(J_l(r) e_k) R, without the 9×3 and 9×9 detour
// through the matrix entries: the numbers are those of the paper's rotation-vector
// derivatives, the cost is a 3×3 transformation per Hessian block.

#include <Eigen/Core>

#include "../lib/so3.hpp"

namespace liedyn::rotvec {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

// C(r, g): the second-order term of ∂²Ψ/∂r² above, symmetric,
//   C_ij = ½ gᵀ (∂J_l/∂r_i e_j + ∂J_l/∂r_j e_i)
//        = ½ (r vᵀ + v rᵀ) + b (g·r) I,  v = α (g × r) + β hat(r)² g − b g,
// with J_l = I + a hat(r) + b hat(r)², α = a'(t)/t, β = b'(t)/t, t = ‖r‖ (derivation in the .cpp).
// Accurate (Taylor branches) from ‖r‖ = 0 up to near 2π.
Matrix3 hessian_correction(const Vector3& r, const Vector3& g);

// ∂vec(exp(r))/∂r, 9×3 (vec stacks columns), by eq. (5) with robust sinc and sinc'
// (Taylor near 0). Its singular values are paper Fig. 3.
Eigen::Matrix<double, 9, 3> exp_jacobian(const Vector3& r);

// The same rotation with ‖r‖ ≤ π: r − 2π r/‖r‖ while ‖r‖ > π.
Vector3 wrap(const Vector3& r);

}  // namespace liedyn::rotvec

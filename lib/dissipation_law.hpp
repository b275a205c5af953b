#pragma once
// The laws of the lagged dissipation terms between objects (body_contact.hpp, edge_contact.hpp):
// a dissipation potential D(d) of a contact sample's displacement d over the step relative to
// the point it touched, with the contact normal n and the normal force λ frozen at the start of
// the step (λ > 0: the sample was in contact; λ = 0: the law is not evaluated) and k the
// sample's penalty stiffness. The terms own the geometry (what d is, how it moves with the
// blocks, what was lagged); a law owns only D and its derivatives in d, so that friction and
// damping share every line of the terms' geometry and adjoints.
//
// SlipFriction: friction.hpp's smoothed Coulomb law on the tangential part of d,
//   u = P d,  P = I − n nᵀ,  y = ‖u‖,
//   D = μλ f₀(y),   f = ∂D/∂d = μλ φ₁ u,   K = ∂²D/∂d² = μλ (φ₁ P + (φ₁′/y) u uᵀ).
// NormalDashpot: contact_damping.hpp's dashpot on the normal part of d, s = n·d (the normal
// approach velocity times h). A material of damping c and stiffness k̄ damps a sample of
// stiffness k with c k/k̄: the samples that share a material's k (an edge's Gauss points, each
// with its weight's share) share its c in proportion, so that the damping ratio
// ζ = c/(2√(k̄ m)) of a contact is the material's however it is sampled. With τ = c/k̄ and
// r = τ k/h,
//   D = ½ r s²,   f = r s n,   K = r n nᵀ.
//
// For the adjoints, the derivative of f with respect to some variables (the previous state's
// blocks) through d, λ and n, given ∂d, ∂λ and ∂n:
//   friction:  ∂u = P ∂d − (n dᵀ + (n·d) I) ∂n,   ∂f = μ φ₁ u ∂λ + μλ (φ₁ I + (φ₁′/y) u uᵀ) ∂u;
//   dashpot:   ∂f = r (n nᵀ ∂d + (n dᵀ + s I) ∂n)   (λ enters only through the zone, whose
//              switch is a jump: the adjoint is that of the side the run is on).
//
// Least-squares forms: friction gives a term one residual, √(2 Σ D) over its samples
// (friction_residual: D > 0 wherever λ > 0); the dashpot one per sample, √r s, with the row
// √r nᵀ ∂d (½ r s² is a square already, and √(2D) = √r |s| would not be smooth at s = 0).

#include "friction.hpp"
#include "state.hpp"

namespace liedyn {

struct SlipFriction {
  static constexpr bool kResidualPerSample = false;
  double coefficient = 0.0;  // μ
  double epsilon = 0.0;      // ε = ε_v h, m, > 0

  // D at d; f = ∂D/∂d and K = ∂²D/∂d² written where non-null.
  double evaluate(const Vector3& d, double lambda, const Vector3& n, double k, Vector3* f,
                  Matrix3* K) const;
  // ∂f from ∂d, ∂λ and ∂n (formulas above).
  template <int M>
  Eigen::Matrix<double, 3, M> force_jacobian(const Vector3& d, double lambda, const Vector3& n,
                                             double, const Eigen::Matrix<double, 3, M>& dd,
                                             const Eigen::Matrix<double, 1, M>& dlambda,
                                             const Eigen::Matrix<double, 3, M>& dn) const {
    const Matrix3 P = Matrix3::Identity() - n * n.transpose();
    const SmoothedSlip slip(P * d, epsilon);
    const Eigen::Matrix<double, 3, M> du = P * dd - (n * d.transpose() + n.dot(d) * Matrix3::Identity()) * dn;
    return coefficient * (slip.phi1 * slip.u * dlambda + lambda * slip.jacobian() * du);
  }
};

struct NormalDashpot {
  static constexpr bool kResidualPerSample = true;
  double time_constant = 0.0;  // τ = c/k̄, s, > 0
  double time_step = 0.0;      // h, s, > 0

  double rate(double k) const { return time_constant * k / time_step; }  // r = τ k/h
  double evaluate(const Vector3& d, double lambda, const Vector3& n, double k, Vector3* f,
                  Matrix3* K) const;
  template <int M>
  Eigen::Matrix<double, 3, M> force_jacobian(const Vector3& d, double, const Vector3& n, double k,
                                             const Eigen::Matrix<double, 3, M>& dd,
                                             const Eigen::Matrix<double, 1, M>&,
                                             const Eigen::Matrix<double, 3, M>& dn) const {
    const Matrix3 turn = n * d.transpose() + n.dot(d) * Matrix3::Identity();
    return rate(k) * ((n * n.transpose()) * dd + turn * dn);
  }
  // The sample's residual √r s; `row` receives √r nᵀ (∂r/∂d).
  double residual(const Vector3& d, const Vector3& n, double k, Eigen::RowVector3d& row) const;
};

}  // namespace liedyn

#pragma once
// Inertial terms of the backward-Euler incremental potential (paper §4.2, eqs. 7, 9, 10).
//
// Backward Euler for  M ẍ = −∇V  is  x_k = argmin  m/(2h²)‖x − x̃‖² + V(x),
//   x̃ = x_{k−1} + Δx_{k−1}.
// For a rotation with body inertia I_b, Ferguson et al. / the paper use
//   Ψ_R = −tr(R J R̃ᵀ)/h²,   J = ½ tr(I_b) 1 − I_b,   R̃ = (2I − ΔR_{k−1}ᵀ) R_{k−1}   (9), (10).
// With M = R J R̃ᵀ/h² = S + A (symmetric + antisymmetric):
//   Lie gradient  2 vee(A)      (12)        Lie Hessian  tr(S) I − S   (13).
// The value is computed in the equivalent least-squares form
//   ‖(R − R̃) J^½‖²_F/(2h²) = tr((R − R̃) J (R − R̃)ᵀ)/(2h²)  = Ψ_R + const,
// because −tr(RJR̃ᵀ)/h² is a large constant plus a small variation and loses digits in the
// line search.
//
// Least-squares (residual) forms, for the Ceres back-end (contract: term.hpp):
//   translation  r = √(m/h²) (x − x̃) − load/√(m/h²)                       (3 residuals)
//   rotation     r = vec((R − R̃) J^½)/h, column-major                      (9 residuals)
// The rotation's Lie Jacobian: exp(θ)R J^½ has column k  c_k + θ × c_k + O(θ²) with
// c_k = (R J^½)_k, and θ × c_k = −hat(c_k) θ, so rows 3k…3k+2 of J are −hat(c_k)/h.
// Then Jᵀr = Σ_k c_k × (D J^½)_k/h² (D = R − R̃) = −Σ_k (RJ^½)_k × (R̃J^½)_k/h²
// = −2 vee(R̃ J Rᵀ)/h² = 2 vee(M), eq. (12), using Σ_k a_k × b_k = 2 vee(Σ_k b_k a_kᵀ).

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// J = ½ tr(I_b) 1 − I_b, the "mass matrix" of the rotation: J = ∫ρ x̄ x̄ᵀ (PSD iff I_b obeys
// the triangle inequality).
Matrix3 rotational_mass(const Matrix3& body_inertia);

// The symmetric PSD square root S of a symmetric PSD A (S = Sᵀ, S² = A up to round-off), by
// eigen-decomposition A = V Λ Vᵀ, S = V Λ^½ Vᵀ. A singular A (J of a rod of zero radius,
// diag(0, 0, m l²/12)) is fine. Eigenvalues in [−1e-9 λ_max, 0) are clamped to 0: they are
// round-off, or the 1e-12 triangle-inequality tolerance of Model::validate (which allows
// λ_min(J) ≥ −1e-12 tr(J)), not a lack of PSD-ness. Throws std::invalid_argument for an A
// with a more negative eigenvalue (no square root, no least-squares form) or non-finite
// entries.
Matrix3 psd_sqrt(const Matrix3& A);

struct TranslationalInertia {
  static constexpr int kBlocks = 1;
  static constexpr const char* kName = "translational_inertia";
  static constexpr bool kEndOfStep = true;  // term.hpp
  std::array<int, kBlocks> offsets{-1};
  int point = -1;
  double mass_over_h2 = 0.0;  // m/h²
  Vector3 x_tilde = Vector3::Zero();

  // x̃ = x_{k−1} + Δx_{k−1}
  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;
  // For the adjoint: the gradient m/h² (x − x_{k−1} − Δx_{k−1}) has
  //   ∂C/∂x_{k−1} = ∂C/∂Δx_{k−1} = −(m/h²) I.
  double step_jacobian() const { return -mass_over_h2; }
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z and (∂C/∂Δq_{k−1})ᵀ z.
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
  // (∂C/∂x̃)ᵀ z = −(m/h²) z: what z makes of x̃, for an integrator whose x̃ reads more of the
  // history than backward Euler's (BDF2, IncrementalPotential::add_history_adjoint).
  Vector3 x_tilde_adjoint(const Vector3& z) const { return -mass_over_h2 * z; }

  static constexpr int kResiduals = 3;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  // With a = m/h² and a constant world force `load` on the point (its potential −load·x;
  // e.g. gravity's scale·weight plus node forces, docs/design.md §9.3), completing the square:
  //   a/2 ‖x − x̃‖² − load·x = ½‖r‖² − load·x̃ − ‖load‖²/(2a),
  //   r = √a (x − x̃ − load/a) = √a (x − x̃) − load/√a,   J = √a I.
  // So ½‖r‖² = evaluate() − load·x + const, and Jᵀr = evaluate()'s gradient − load.
  // a = 0 (no mass) gives r = 0, J = 0 when load = 0, and throws std::invalid_argument
  // otherwise: a massless point under a load has no least-squares form.
  void residual(const State& q, Residual& r, ResidualJacobian* J,
                const Vector3& load = Vector3::Zero()) const;
};

struct RotationalInertia {
  static constexpr int kBlocks = 1;
  static constexpr const char* kName = "rotational_inertia";
  static constexpr bool kEndOfStep = true;  // term.hpp
  std::array<int, kBlocks> offsets{-1};
  int rotation = -1;
  Matrix3 J_over_h2 = Matrix3::Zero();  // J/h²
  Matrix3 R_tilde = Matrix3::Identity();
  // J^½/h = psd_sqrt(J/h²), for residual() only; set beside J_over_h2 (build_components).
  Matrix3 sqrt_J_over_h = Matrix3::Zero();

  // The trapezoidal integrator's discretisation (lib/history.hpp): R̃ = R_{k−1}, the momentum
  // of the previous step being in the rotation's history term. Set by
  // IncrementalPotential::set_integrator.
  bool variational = false;

  // R̃ = (2I − ΔR_{k−1}ᵀ) R_{k−1} = 2R_{k−1} − R_{k−2}   (10),  or R_{k−1} (variational)
  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;

  // For the adjoint: the Lie derivatives of the gradient C = 2 vee(M), M = R J R̃ᵀ/h², with
  // respect to the previous rotation R_p = R_{k−1} → exp(φ) R_p and the previous step
  // ΔR = ΔR_{k−1} → exp(ψ) ΔR (state + step formulation, paper §5; eqs. (33)–(34) of the
  // paper are checked by finite differences instead of trusted). With B = R J R_pᵀ/h²:
  //   R̃ → R̃ + (2I − ΔRᵀ) hat(φ) R_p,   M → M − B hat(φ) (2I − ΔR),
  //   R̃ → R̃ + ΔRᵀ hat(ψ) R_p,          M → M − B hat(ψ) ΔR,
  // so column j of each Jacobian is −2 vee(B hat(e_j) X), X = 2I − ΔR or ΔR. Variational
  // (R̃ = R_p): X = I for φ, and C does not read ΔR.
  void step_jacobians(const State& q, const Matrix3& R_previous, const Matrix3& dR_previous,
                      Matrix3& dC_dR_previous, Matrix3& dC_ddR_previous) const;
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z and (∂C/∂Δq_{k−1})ᵀ z.
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
  // The matrix Ḡ with zᵀ δC = ⟨Ḡ, δR̃⟩ (Frobenius) for any change δR̃ of R̃, for an integrator
  // whose R̃ reads more of the history than backward Euler's (BDF2,
  // IncrementalPotential::add_history_adjoint): C = 2 vee(R Ĵ R̃ᵀ), Ĵ = J/h², and
  // 2 z·vee(X) = ⟨hat(z), X⟩ give zᵀ δC = ⟨hat(z), R Ĵ δR̃ᵀ⟩ = ⟨−hat(z) R Ĵ, δR̃⟩.
  Matrix3 R_tilde_adjoint(const State& q, const Vector3& z) const;

  static constexpr int kResiduals = 9;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  // r = vec((R − R̃) J^½/h) column-major: r(3k + i) = ((R − R̃) sqrt_J_over_h)(i, k), and
  // ½‖r‖² = ½ tr(D J Dᵀ)/h² = evaluate()'s value (the constant is 0).
  // J rows 3k…3k+2 = −hat(c_k), c_k column k of R J^½/h (derivation at the top).
  // With `shift` S, R̃ + S in place of R̃: −tr(R J (R̃ + S)ᵀ)/h² adds −tr(R J Sᵀ)/h², how a
  // torque field folds in (RotationHistory::inertia_shift).
  void residual(const State& q, Residual& r, ResidualJacobian* J,
                const Matrix3& shift = Matrix3::Zero()) const;
};

}  // namespace liedyn

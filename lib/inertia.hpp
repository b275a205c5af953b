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

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// J = ½ tr(I_b) 1 − I_b, the "mass matrix" of the rotation: J = ∫ρ x̄ x̄ᵀ (PSD iff I_b obeys
// the triangle inequality).
Matrix3 rotational_mass(const Matrix3& body_inertia);

struct TranslationalInertia {
  static constexpr int kBlocks = 1;
  std::array<int, kBlocks> offsets{-1};
  int point = -1;
  double mass_over_h2 = 0.0;  // m/h²
  Vector3 x_tilde = Vector3::Zero();

  // x̃ = x_{k−1} + Δx_{k−1}
  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;
};

struct RotationalInertia {
  static constexpr int kBlocks = 1;
  std::array<int, kBlocks> offsets{-1};
  int rotation = -1;
  Matrix3 J_over_h2 = Matrix3::Zero();  // J/h²
  Matrix3 R_tilde = Matrix3::Identity();

  // R̃ = (2I − ΔR_{k−1}ᵀ) R_{k−1} = 2R_{k−1} − R_{k−2}   (10)
  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;
};

}  // namespace liedyn

#pragma once
// The rotational parts of elastic joints between two frames (bodies, or a body and the
// world). A joint's translational part, ½‖p_b − p_a‖²/compliance, is a zero-rest-length
// spring (spring.hpp) of stiffness 1/compliance; these terms hold the orientations.
// Conventions: so3.hpp (left perturbations R ← exp(θ) R, Lie gradient and symmetric Lie
// Hessian). Blocks (θ_a, θ_b); a world end has offset −1 and a constant frame.
//
// Hinge alignment. With the axes a = R_a â and b = R_b b̂ (unit; â, b̂ in body coordinates),
//   V = k (1 − a·b) = ½ k ‖a − b‖²,
// zero when the axes agree, ½ k θ² for a small angle θ between them, and smooth everywhere
// (one minimum: the flipped axis, θ = π, is a maximum, not a second rest state as it would
// be for ‖a × b‖²). With exp(θ) a = a + θ × a + ½ θ × (θ × a) + O(θ³):
//   DV/Dθ_a = −k a × b,   DV/Dθ_b = −k b × a,
//   D²V/Dθ_a² = −k [½ (a bᵀ + b aᵀ) − (a·b) I],   D²V/Dθ_b² = the same,
//   D²V/Dθ_a Dθ_b = k hat(a) hat(b)        ((θ_a × a)·(θ_b × b) = θ_aᵀ hat(a)ᵀ hat(b) θ_b).
// Residual form: r = √k (a − b), J = √k [−hat(a), hat(b)] (∂(exp(θ)a)/∂θ = −hat(a)).
//
// Weld. With the joint frames F_a = R_a A and F_b = R_b B (A, B constant, in body
// coordinates) and their relative rotation E = F_a F_bᵀ, φ = log E (‖φ‖ ≤ π),
//   V = ½ k ‖φ‖².
// A perturbation of both ends gives E ← exp(θ_a) exp(−E θ_b) E, i.e. exp(w) E with
// w = θ_a − E θ_b − ½ θ_a × (E θ_b) + O(3) (Baker–Campbell–Hausdorff). In the coordinates u
// of exp(u) E, V has the gradient J_l⁻¹(φ)ᵀ φ = φ and the Hessian
//   H_φ = I + c(t) hat(φ)²,   c(t) = 1/t² − cot(t/2)/(2t),  t = ‖φ‖   (c → 1/12 as t → 0),
// the symmetric part of J_l⁻¹(φ) (so3.hpp), because J_l(u)ᵀ φ = φ − ½ u × φ to first order.
// Since E φ = φ and E commutes with hat(φ):
//   DV/Dθ_a = k φ,   DV/Dθ_b = −k φ,
//   D²V/Dθ_a² = D²V/Dθ_b² = k H_φ,   D²V/Dθ_a Dθ_b = −k H_φ E + ½ k hat(φ) E.
// At t = π the log map's sign is arbitrary (the cut locus): V is continuous there, its
// gradient flips from k φ to −k φ, so V has a ridge, not a derivative (a welded body turned
// half a turn is pushed back either way).
// With one end the world the Hessian k H_φ has eigenvalues k {1, τ, τ}, τ = (t/2) cot(t/2) ≥ 0
// up to π. With both ends free the 6×6 Hessian is indefinite for every t > 0: its eigenvalues
// are k {0, 2, τ ± √(τ² + t²/4) (twice each)} — ½ dist(F_a, F_b)² is not jointly convex on
// SO(3) × SO(3), which is curved — so Newton regularises away from rest (solvers/newton.hpp).
// Residual form: r = √k φ, J = √k [J_l⁻¹(φ), −J_l⁻¹(φ) E] (Jᵀ r = k [φ, −φ]).

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

struct JointAlignment {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "joint_alignment";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1};  // θ_a, θ_b
  int rotation_a = -1, rotation_b = -1;      // State::rotations, −1: the world (identity)
  Vector3 axis_a = Vector3::UnitZ();         // â, b̂: unit, in each end's body coordinates
  Vector3 axis_b = Vector3::UnitZ();
  double stiffness = 0.0;                    // k = 1/compliance_rot, N·m/rad

  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  static constexpr int kResiduals = 3;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

struct JointWeld {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "joint_weld";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1};  // θ_a, θ_b
  int rotation_a = -1, rotation_b = -1;      // State::rotations, −1: the world (identity)
  Matrix3 frame_a = Matrix3::Identity();     // A, B: joint frames in body coordinates
  Matrix3 frame_b = Matrix3::Identity();
  double stiffness = 0.0;                    // k = 1/compliance_rot, N·m/rad

  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  static constexpr int kResiduals = 3;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // φ = log(R_a A Bᵀ R_bᵀ) and E, for the tests and the residual.
  Vector3 relative_rotation(const State& q, Matrix3* E = nullptr) const;
};

}  // namespace liedyn

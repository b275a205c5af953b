#pragma once
// The history terms of the trapezoidal and Fox–Goodwin integrators (Model::Integrator;
// derivation in docs/design.md §14 and §14.2): what a step needs of the states before it, as a
// constant force field on each point and a constant world torque field on each rotation.
//
// The step from q_{k−1} (and q_{k−2} = q_{k−1} ⊖ Δq_{k−1}) solves, with f = −∇V the forces of
// the conservative terms and β = newmark_beta (¼ trapezoidal, 1/12 Fox–Goodwin),
//   points     m (x_k − 2x_{k−1} + x_{k−2})/h² = β f_k + (1 − 2β) f_{k−1} + β f_{k−2},
//   rotations  (μ_{k−½} − μ_{k−3/2})/h = β τ_k + (1 − 2β) τ_{k−1} + β τ_{k−2},
// with μ_{k−½} = 2 vee(R_k J R_{k−1}ᵀ)/h the Lie group variational integrator's discrete
// (spatial) angular momentum. It is the stationary point of
//   Ψ = Σ m/(2h²)‖x − x̃‖² + Σ −tr(R J R_{k−1}ᵀ)/h² + β V(q) + Σ_t Ψ_t(q) + history,
// x̃ = x_{k−1} + Δx_{k−1} (the inertia terms' own), Ψ_t the terms that act at the step's end
// (term.hpp, EndOfStep), where the history's gradient is the constant
//   c = (1 − 2β) ∇V(q_{k−1}) + β ∇V(q_{k−2}) − μ_{k−3/2}/h      (μ only on rotations).
// The first step, from q_0 and the initial velocities, is Newmark's own first step:
// c = (½ − β) ∇V(q_0) − π_0/h with π_0 = R_0 I_b R_0ᵀ ω_0 the momentum of ω_0 = log(ΔR_0)/h.
//
// On a point the field is the gradient of a linear potential, c·x. On SO(3) no function has
// a constant world gradient (its Lie Hessian would have to be antisymmetric), so a rotation's
// field is the potential of a world torque −c about a reference R_ref (ConstantTorque's,
// lib/loads.hpp):
//   V(R) = c·vee(P),  P = R R_refᵀ,  gradient exactly c at R = R_ref, Hessian 0 there,
// whose gradient is c + ½ c × log(R R_refᵀ) + O(|log|²) elsewhere; RotationHistory says how
// R_ref is brought to where the step ends.

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// The history's force field on a point: V = c·x, gradient c, Hessian 0.
struct PointHistory {
  static constexpr int kBlocks = 1;
  static constexpr const char* kName = "point_history";
  static constexpr bool kEndOfStep = true;
  std::array<int, kBlocks> offsets{-1};
  int point = -1;
  Vector3 field = Vector3::Zero();  // c

  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;
  // PointLoad (term.hpp): the force −c (Ceres folds it into the point's inertia residual).
  bool point_load(int& on, Vector3& force) const {
    on = point;
    force = -field;
    return true;
  }
};

// The history's torque field on a rotation: V = c·vee(R R_refᵀ), gradient c at R = R_ref.
// StepSolver::solve moves R_ref to the solution and solves again until it no longer moves,
// so that the step satisfies its equations exactly (and the free body conserves its discrete
// momentum). Each such re-solve contracts the error by ‖H⁻¹ ½ hat(c)‖ — the skew part of the
// field's derivative that no potential has —, about ½θ (θ the step's rotation angle) where
// inertia dominates and 3× the elastic strain angle on a rod's edges; where it exceeds 1 (a
// rod ringing in its stiff modes) the step is reported unconverged.
struct RotationHistory {
  static constexpr int kBlocks = 1;
  static constexpr const char* kName = "rotation_history";
  static constexpr bool kEndOfStep = true;
  std::array<int, kBlocks> offsets{-1};
  int rotation = -1;
  Vector3 field = Vector3::Zero();          // c
  Matrix3 reference = Matrix3::Identity();  // R_ref

  // At R = R_ref (where Newton assembles, the reference moved to its iterate) exactly 0, c and
  // 0: P = I without the round-off of R R_refᵀ.
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;
  // Its potential folded into the rotational inertia −tr(R Ĵ R̃ᵀ) (Ĵ = J/h², invertible) of
  // the same rotation: c·vee(R R_refᵀ) = −½ tr(ĉ R R_refᵀ) = −tr(R Ĵ Sᵀ) with
  //   S = −½ ĉ R_ref Ĵ⁻¹,
  // so the two are −tr(R Ĵ (R̃ + S)ᵀ), one least-squares residual (RotationalInertia::residual;
  // the Ceres back-end, which would otherwise need a non-square residual for the field).
  Matrix3 inertia_shift(const Matrix3& J_over_h2_inverse) const;
  // Moves R_ref to the rotation in q.
  void rereference(const State& q) { reference = q.rotations[rotation]; }
  // The angle rereference(q) would move R_ref, |log(R R_refᵀ)| (0 where R is R_ref).
  double reference_distance(const State& q) const { return chord_angle(reference_chord(q)); }
  // ‖R − R_ref‖_F, which grows with that angle (the largest over many terms needs one chord_angle).
  double reference_chord(const State& q) const { return (q.rotations[rotation] - reference).norm(); }
  // The angle θ between two rotations from their chord ‖R₁ − R₂‖_F = 2√2 sin(θ/2).
  static double chord_angle(double chord);
};

}  // namespace liedyn

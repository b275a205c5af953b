#pragma once
// Joint limits: lo ≤ ξ(q) ≤ hi on a joint's coordinate ξ — a hinge's angle about its axis or a
// slider's position along its rail, both measured from the start of the run. Each bound is one
// term, JointLimit<Coordinate>, a one-sided constraint on the gap
//   g = σ (ξ − bound) ≤ 0,   σ = +1 for hi, −1 for lo,
// held elastically, V = ½ k max(0, g)² with k the joint's own stiffness (1/compliance,
// 1/compliance_rotation), or exactly by the augmented Lagrangian of StepSolver::solve:
// V = ½ ρ max(0, g + s)² with the shift s ≥ 0 updated s ← max(0, s + g), the inequality form
// of the joint parts' update (joint_terms.hpp): the multiplier λ = ρ max(0, g + s) ≥ 0 is the
// stop's torque or force, zero while the joint is inside its range. The loop runs until
// |max(g, −s)| ≤ tolerance: feasible (g ≤ 0) and complementary (no push, s = 0, from a
// distance, g < 0), the measure of an inequality's KKT conditions. Lie derivatives of V from
// those of ξ: ∇V = k m σ ∇ξ, ∇²V = k (∇ξ ∇ξᵀ + m σ ∇²ξ), m = max(0, g (+ s)); V is C¹ at the
// switch m = 0, where the Hessian jumps by k ∇ξ ∇ξᵀ (as the contact penalty's does).
// The adjoint (solvers/adjoint.cpp) sees an exact limit as an equality c = g where it is
// active at the converged step (λ > 0) and as nothing where it is not (c and J zero: the
// least-squares multiplier of that row is zero):
//   V_adj = λ g + ½ ρ g²,   ∇V_adj = (λ + ρ g) σ ∇ξ,   H_adj = ρ ∇ξ∇ξᵀ + λ σ ∇²ξ,
// the Lagrangian of joint_terms.hpp for one row. Conventions: so3.hpp (left perturbations).
//
// Hinge angle (HingeAngle). With a's axis n = R_a â, a reference u = R_a û (û ⟂ â) and
// v = u × n spanning a's plane, and b's reference w = R_b û_b (û_b: a's initial û in b's
// coordinates, so ξ = 0 at the start),
//   ξ = atan2(y, x),  x = u·w, y = v·w,
// the angle from w's projection on a's plane to u: positive when a turns positively about its
// axis relative to b (the sense of the hinge motor's torque on a). It depends on the relative rotation only, through
// w in a's frame. Varying b alone, δw = θ_b × w, so with t = ∂ξ/∂w = (x v − y u)/ρ², ρ² = x² + y²,
//   Dξ/Dθ_b = w × t,   D²ξ/Dθ_b² = C(w, t) + hat(w)ᵀ N hat(w),
// C the rotated-point curvature (state.hpp) and N = ∇²_w ξ = [u v] S [u v]ᵀ / ρ⁴,
// S = [[2xy, y² − x²], [y² − x², −2xy]] (the Hessian of atan2). A function of R_aᵀ R_b with
// b-side gradient γ and Hessian H has, by R_aᵀ exp(−θ_a) exp(θ_b) R_b and BCH
// (exp(−α) exp(β) = exp(β − α − ½ α × β + …)),
//   Dξ/Dθ_a = −γ,   D²/Dθ_a² = H,   D²/Dθ_a Dθ_b = −H + ½ hat(γ),
// as for the weld. atan2 returns (−π, π]; ξ is continued across ±π from the angle at the
// start of the step (begin_step), so limits may span several turns. Undefined where w ∥ n
// (ρ = 0: b's reference along a's axis, which an intact hinge never reaches).
//
// Slider position (SliderPosition). With n = R_a â (turning with a, not lagged) and
// d = p_b − p_a (AttachedPoint), ξ = −n·d − ξ₀ = n·(p_a − p_b) − ξ₀, a's place along the rail
// relative to b (positive where the slider motor pushes a), ξ₀ its value at the start. The
// derivatives of n·d: first variations δn = θ_a × n, δd = δx_b − δx_a + θ_b × r_b − θ_a × r_a
// give
//   ∇(n·d) = (−n, n × (d + r_a), n, r_b × n)   over (x_a, θ_a, x_b, θ_b),
// and the second variation: C(n, d) + C(r_a, −n) at θ_aθ_a, C(r_b, n) at θ_bθ_b (the rotated
// vectors' second order), plus the bilinear δn·δd = θ_aᵀ hat(n) D δq with
// D = [−I, hat(r_a), I, −hat(r_b)]: hat(n) D into the θ_a rows and its transpose into the θ_a
// columns.

#include <algorithm>
#include <array>

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

struct HingeAngle {
  static constexpr int kBlocks = 2;  // θ_a, θ_b
  static constexpr const char* kName = "joint_angle_limit";
  int rotation_a = -1, rotation_b = -1;  // State::rotations, −1: the world (identity)
  Vector3 axis_a = Vector3::UnitZ();     // â, unit, in a's coordinates
  Vector3 reference_a = Vector3::UnitX();  // û ⟂ â, unit, in a's coordinates
  Vector3 reference_b = Vector3::UnitX();  // û_b, in b's coordinates
  double previous = 0.0;                   // ξ at the start of the step (picks the turn)

  void begin_step(const State& previous_state);
  // ξ, and its Lie gradient and Hessian when non-null.
  double value(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;
};

struct SliderPosition {
  static constexpr int kBlocks = 4;  // x_a, θ_a, x_b, θ_b
  static constexpr const char* kName = "joint_slide_limit";
  AttachedPoint a, b;                 // a: a point with a rotation
  Vector3 axis_a = Vector3::UnitX();  // â, unit, in a's coordinates
  double origin = 0.0;                // ξ₀, m

  void begin_step(const State&) {}
  double value(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const;
};

template <class Coordinate>
struct JointLimit {
  static constexpr int kBlocks = Coordinate::kBlocks;
  static constexpr const char* kName = Coordinate::kName;
  static constexpr bool kEnergyOfState = true;
  static constexpr bool kInequality = true;
  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<1>;
  using ResidualJacobian = LocalResidualJacobian<1, kBlocks>;
  using ConstraintJacobian = LocalResidualJacobian<3, kBlocks>;  // row 0: g; rows 1, 2 zero

  std::array<int, kBlocks> offsets{};
  Coordinate coordinate;
  double bound = 0.0;      // lo or hi (rad or m)
  double side = 1.0;       // σ: +1 for the upper bound, −1 for the lower
  double stiffness = 0.0;  // k = 1/compliance, or ρ if exact
  // Constraint (term.hpp): the shift s ≥ 0, and λ in the adjoint (row 0 of `multiplier`).
  bool exact = false;
  double shift = 0.0;
  bool adjoint = false;
  Vector3 multiplier = Vector3::Zero();

  void begin_step(const State& previous, const Step&) { coordinate.begin_step(previous); }
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // |max(g, −s)|: the gap where the stop is passed, and where the stop pushes (s > 0) from a
  // distance (g < 0) the smaller of the two — zero only when g ≤ 0 = s or g = 0 ≤ s.
  double violation(const State& q) const { return std::abs(std::max(gap(q), exact ? -shift : 0.0)); }
  void update_multiplier(const State& q) { shift = std::max(0.0, shift + gap(q)); }
  Vector3 force(const State& q) const;                              // (λ, 0, 0)
  Vector3 constraint(const State& q, ConstraintJacobian* J) const;  // (g, 0, 0) where active

 private:
  // g, and σ∇ξ, σ∇²ξ when non-null.
  double gap(const State& q, LocalGradient<kBlocks>* g = nullptr,
             LocalHessian<kBlocks>* H = nullptr) const;
  // m = max(0, g + s) (s = 0 when elastic).
  double penetration(double gap) const { return std::max(0.0, gap + (exact ? shift : 0.0)); }
};

extern template struct JointLimit<HingeAngle>;
extern template struct JointLimit<SliderPosition>;

}  // namespace liedyn

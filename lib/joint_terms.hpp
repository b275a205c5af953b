#pragma once
// The parts of a joint between two frames (bodies, rod nodes and edges, the world): its
// translation (JointPoint) and, for hinges and welds, its rotation (JointAlignment,
// JointWeld). Each part is a constraint c(q) = 0 (term.hpp, Constraint) held either
// elastically, V = ½ k ‖c‖² with k = 1/compliance, or exactly (compliance 0) by the augmented
// Lagrangian of StepSolver::solve: V = ½ ρ ‖c + s‖², ρ the penalty (`stiffness`) and s the
// multiplier shift, updated s ← s + c between solves until ‖c‖∞ ≤ tolerance. Every shift is
// stored in end a's body coordinates (world coordinates for a point without rotation), so it
// turns with the body, and enters the term as a change of end a's geometry: its point, axis
// or frame. The derivatives below therefore hold for the shifted term unchanged.
// Conventions: so3.hpp (left perturbations R ← exp(θ) R, Lie gradient and symmetric Lie
// Hessian). A world end has offset −1 and a constant frame.
//
// The adjoint of an exact part (solvers/adjoint.cpp, docs/design.md §8.6) needs the
// constraint's Jacobian J = ∂c/∂(blocks), its multiplier λ at the converged step — the force
// or torque the penalty exerts, λ = ρ (c + s) in world coordinates, so that the term's
// gradient is Jᵀλ at c = 0 — and the Hessian of the Lagrangian. For that the adjoint sets
// `adjoint` with λ in `multiplier`; the term is then
//   V_adj = λᵀ c + ½ ρ ‖c‖²,   ∇V_adj = Jᵀ (λ + ρ c),   H_adj = ρ JᵀJ + ∇²(λᵀ c),
// with ρ its `stiffness`: H_adj is V_adj's Hessian at c = 0 (at the converged step c is at the
// tolerance), and the M = K + ρ JᵀJ the adjoint's bordered solve needs (any ρ > 0 that
// keeps M positive definite gives the same adjoint, docs/design.md §8.6). ∇²(λᵀc) is exact
// for the point, the hinge axis and the weld (below).
//
// Translation (JointPoint). c = p_b − p_a with p = x + R p̄ (AttachedPoint); shift s:
//   V = ½ k ‖p_b − (p_a − R_a s)‖²,   s ← s + R_aᵀ c,
// a zero-rest-length spring (spring.hpp, point_pair.hpp) whose point a is p̄_a − s.
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
// The formulas use only a·b (‖a‖, ‖b‖ are invariant), so they hold for the shifted axis
// a = R_a (â + s), c = R_a â − b, s ← s + R_aᵀ c, which is not a unit vector. c is 3 numbers
// for a 2-dimensional constraint: its part along a, 1 − a·b ≈ θ²/2, is second order.
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
// Adjoint (and Ipopt's Lagrangian): ∇²(λᵀφ), exact at every E. With w as above,
// log(exp(w) exp(φ)) = φ + J_l⁻¹(φ) w + ½ D(J_l⁻¹)(φ)[J_l⁻¹(φ) w] w + O(3) (the derivative of
// u ↦ log(exp(u) exp(φ)) is J_l⁻¹(L(u)) J_l(u), and J_l(u) = I + ½ hat(u) + …, whose part
// ½ hat(w) w vanishes), and
//   D(J_l⁻¹)(φ)[v] = −½ hat(v) + (c'(t)/t)(φ·v) hat(φ)² + c(t) (hat(v) hat(φ) + hat(φ) hat(v)).
// So with M = sym(M̃), M̃'s row i = λᵀ D(J_l⁻¹)(φ)[J_l⁻¹(φ) e_i], and μ = J_l⁻¹(φ)ᵀ λ:
//   D²/Dθ_a² = M,   D²/Dθ_b² = Eᵀ M E,   D²/Dθ_a Dθ_b = −M E + ½ hat(μ) E,
// the last term from the BCH part −½ θ_a × (E θ_b) of w. At E = I, M = 0 and μ = λ.
// (For λ = kφ this is k(H_φ − J_l⁻ᵀ J_l⁻¹) on the diagonal: V's Hessian less its Gauss–Newton
// part, a check.)
// Exact: the shift is a rotation S of frame a, E = R_a A S Bᵀ R_bᵀ (A S in place of A), and
// c = log(F_a F_bᵀ) with the joint's own A. The update S ← (F_bᵀ F_a) S is s ← s + c to first
// order: once the joint holds (F_a = F_b = F) the shifted E becomes F S' Fᵀ, which keeps the
// current F_a S F_bᵀ — the torque ρ log E — when S' = F_bᵀ F_a S.

#include <type_traits>

#include "loads.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// What every joint part holds for the augmented Lagrangian and the adjoint (above): whether it
// is exact, its multiplier shift s (a vector, or the weld's rotation S; none at first), and,
// in the adjoint, λ in place of the penalty.
// Also the least-squares and constraint forms' types, 3 rows each over the term's B blocks.
template <class Shift, int B>
struct JointConstraintState {
  static constexpr int kResiduals = 3;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, B>;
  using ConstraintJacobian = LocalResidualJacobian<3, B>;

  bool exact = false;
  Shift shift = no_shift();
  bool adjoint = false;
  Vector3 multiplier = Vector3::Zero();

 private:
  static Shift no_shift() {
    if constexpr (std::is_same_v<Shift, Matrix3>) {
      return Matrix3::Identity();
    } else {
      return Shift::Zero();
    }
  }
};

struct JointPoint : JointConstraintState<Vector3, 4> {
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "joint_point";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1, -1, -1};  // x_a, θ_a, x_b, θ_b
  AttachedPoint a, b;                                // a: not a world anchor
  double stiffness = 0.0;                            // k = 1/compliance (N/m), or ρ if exact

  double evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const;

  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // Constraint (term.hpp): c = p_b − p_a with the joint's own point a.
  double violation(const State& q) const;
  void update_multiplier(const State& q);

  // The adjoint (header): λ, and c with J.
  Vector3 force(const State& q) const;  // λ = ρ (c + s), world
  Vector3 constraint(const State& q, ConstraintJacobian* J) const;  // c, and J = ∂c/∂(blocks)

 private:
  AttachedPoint shifted_a() const;
};

// Slider line (JointLine): the points of a slider stay on the line through p_a along
// n = R_a â, c = n × d + R_a s, d = p_b − p_a (3 numbers for 2 constraints, zero exactly when
// d ∥ n); its rotation is a weld. With w = R_a s, first variations
//   δd = δx_b − δx_a + θ_b × r_b − θ_a × r_a,   δn = θ_a × n,   δw = θ_a × w,
// so J = ∂c/∂(x_a, θ_a, x_b, θ_b) = [−hat(n), hat(n) hat(r_a) + n dᵀ − (n·d) I − hat(w),
//                                    hat(n), −hat(n) hat(r_b)].
// Second variation of μᵀc (μ = k c in V = ½ k ‖c‖², or λ in the adjoint): from n₂, d₂, w₂
// the rotated-point curvatures C(n, d × μ) + C(r_a, −μ × n) + C(w, μ) at θ_aθ_a and
// C(r_b, μ × n) at θ_bθ_b; from n₁ × d₁ the bilinear −δdᵀ hat(μ) hat(n) θ_a, i.e. with
// δd = D δq (D = [−I, hat(r_a), I, −hat(r_b)]) and A = −hat(μ) hat(n) the blocks Dᵀ A at the
// θ_a column and their transpose at the θ_a row. H = k JᵀJ + that (exact).
struct JointLine : JointConstraintState<Vector3, 4> {
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "joint_line";
  static constexpr bool kEnergyOfState = true;
  static constexpr int kConstraintRank = 2;  // c ⊥ n to first order (term.hpp)
  std::array<int, kBlocks> offsets{-1, -1, -1, -1};  // x_a, θ_a, x_b, θ_b
  AttachedPoint a, b;                                // a: a point with a rotation
  Vector3 axis_a = Vector3::UnitX();                 // â, unit, in a's body coordinates
  double stiffness = 0.0;                            // k = 1/compliance (N/m), or ρ if exact

  double evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const;

  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // Constraint (term.hpp): c = n × d without the shift.
  double violation(const State& q) const;
  void update_multiplier(const State& q);

  // The adjoint (header): λ, and c with J.
  Vector3 force(const State& q) const;  // λ = ρ (c + R_a s), world
  Vector3 constraint(const State& q, ConstraintJacobian* J) const;

 private:
  // c (with w = R_a s), and J and the curvature of μᵀc (added into H) when non-null.
  Vector3 line(const State& q, const Vector3& w, ConstraintJacobian* J, const Vector3* mu,
               LocalHessian<4>* H) const;
};

struct JointAlignment : JointConstraintState<Vector3, 2> {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "joint_alignment";
  static constexpr bool kEnergyOfState = true;
  static constexpr int kConstraintRank = 2;  // c ⊥ a to first order (term.hpp)
  std::array<int, kBlocks> offsets{-1, -1};  // θ_a, θ_b
  int rotation_a = -1, rotation_b = -1;      // State::rotations, −1: the world (identity)
  Vector3 axis_a = Vector3::UnitZ();         // â, b̂: unit, in each end's body coordinates
  Vector3 axis_b = Vector3::UnitZ();
  double stiffness = 0.0;                    // k = 1/compliance_rot (N·m/rad), or ρ if exact

  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // Constraint (term.hpp): c = R_a â − R_b b̂.
  double violation(const State& q) const;
  void update_multiplier(const State& q);

  // The adjoint (header): λ, and c with J.
  Vector3 force(const State& q) const;  // λ = ρ (c + s), world
  Vector3 constraint(const State& q, ConstraintJacobian* J) const;  // c, and J = ∂c/∂(blocks)
};

struct JointWeld : JointConstraintState<Matrix3, 2> {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "joint_weld";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1};  // θ_a, θ_b
  int rotation_a = -1, rotation_b = -1;      // State::rotations, −1: the world (identity)
  Matrix3 frame_a = Matrix3::Identity();     // A, B: joint frames in body coordinates
  Matrix3 frame_b = Matrix3::Identity();
  double stiffness = 0.0;                    // k = 1/compliance_rot (N·m/rad), or ρ if exact

  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // φ = log(R_a A S Bᵀ R_bᵀ) and E, the term's relative rotation (shifted, but not in the
  // adjoint).
  Vector3 relative_rotation(const State& q, Matrix3* E = nullptr) const;

  // Constraint (term.hpp): c = log(R_a A Bᵀ R_bᵀ), without the shift.
  double violation(const State& q) const;
  void update_multiplier(const State& q);

  // The adjoint (header): λ, and c with J.
  Vector3 force(const State& q) const;  // λ = ρ (c + s), world
  Vector3 constraint(const State& q, ConstraintJacobian* J) const;  // c, and J = ∂c/∂(blocks)
};

// A hinge's motor: a torque τ about the hinge axis, τ ê on body a and −τ ê on body b (none
// on the world). ê = R_{a,k−1} â is the axis at the start of the step (lagged, first order like
// backward Euler: a motor's work over a step is τ times the turn about the axis it had). Each
// end's part is a ConstantTorque (loads.hpp) of that torque, whose incremental potential,
// derivatives and adjoint blocks it takes; the axis's own dependence on R_{a,k−1},
// ∂ê/∂φ_a = −hat(ê), adds to the previous-step block of a:
//   C_a = M_a τ ê,  C_b = −M_b τ ê  (M = ConstantTorque's ∂C/∂torque)
//   ⇒ ∂C_a/∂φ_a ⊇ −τ M_a hat(ê),  ∂C_b/∂φ_a ⊇ τ M_b hat(ê);
// and ∂C/∂τ = (M_a ê, −M_b ê). τ is scheduled per frame and may be an optimisation parameter
// (kind joint_motor); static load stepping scales it like any torque.
struct JointMotor {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "joint_motor";
  static constexpr bool kEndOfStep = true;  // term.hpp
  std::array<int, kBlocks> offsets{-1, -1};  // θ_a, θ_b
  int rotation_a = -1, rotation_b = -1;      // State::rotations; b −1: the world
  Vector3 axis_a = Vector3::UnitZ();         // â, unit, in a's body coordinates
  double torque = 0.0;                       // τ, N·m, about +ê (turns b against a by −τ)
  double scale = 1.0;
  ScheduledParameter<1> control;
  Matrix3 R_previous_a = Matrix3::Identity(), R_previous_b = Matrix3::Identity();

  void begin_step(const State& previous, const Step& previous_step);
  void begin_frame(int k) { torque = control.at(k, Eigen::Matrix<double, 1, 1>(torque))(0); }
  bool scheduled() const { return !control.schedule.empty(); }
  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
  void add_parameter_adjoint(const State& q, int frame, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const;

  // ê, and the ConstantTorque that end 0 (a) or 1 (b) feels.
  Vector3 axis() const { return R_previous_a * axis_a; }
  ConstantTorque end_torque(int end) const;
};

// A slider's motor: a force f along the slider's axis, +f ê on a's point and −f ê on b's (as
// the hinge motor's +τ on a: both drive the joint's coordinate, a relative to b, the positive
// way; joint_limits.hpp), ê = R_{a,k−1} â lagged as the hinge motor's axis (above). Both
// forces act along the line through p_a along ê, which holds p_b while the slider holds: they
// are equal, opposite and collinear, so they push a along the rail without a net torque.
// Each end's part is a ConstantForce (loads.hpp) at that end's point, whose potential,
// derivatives and adjoint blocks it takes; the axis's dependence on R_{a,k−1} adds to the
// previous-step block of a:
//   C_a = f M_a ê,  C_b = −f M_b ê  (M = ConstantForce's ∂C/∂F)
//   ⇒ ∂C_a/∂φ_a ⊇ −f M_a hat(ê),  ∂C_b/∂φ_a ⊇ f M_b hat(ê);
// and ∂C/∂f = (M_a ê, −M_b ê). f is scheduled per frame and may be an optimisation
// parameter (kind joint_motor); static load stepping scales it like any force.
struct JointForceMotor {
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "joint_force_motor";
  static constexpr bool kEndOfStep = true;  // term.hpp
  std::array<int, kBlocks> offsets{-1, -1, -1, -1};  // x_a, θ_a, x_b, θ_b
  AttachedPoint a, b;                                // a: a point with a rotation
  Vector3 axis_a = Vector3::UnitX();                 // â, unit, in a's coordinates
  double force = 0.0;                                // f, N, along +ê on a
  double scale = 1.0;
  ScheduledParameter<1> control;
  Matrix3 R_previous_a = Matrix3::Identity();

  void begin_step(const State& previous, const Step& previous_step);
  void begin_frame(int k) { force = control.at(k, Eigen::Matrix<double, 1, 1>(force))(0); }
  bool scheduled() const { return !control.schedule.empty(); }
  double evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const;
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
  void add_parameter_adjoint(const State& q, int frame, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const;

  // ê, and the ConstantForce that end 0 (a) or 1 (b) feels.
  Vector3 axis() const { return R_previous_a * axis_a; }
  ConstantForce end_force(int end) const;
};

}  // namespace liedyn

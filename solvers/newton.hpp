#pragma once
// Newton's method with backtracking line search on one component's incremental potential
// (paper §4.3, eq. 11):
//   H δ = −g   (Lie Hessian and Lie gradient),   x ← x + α δx,   R ← exp(α δθ) R.
// Rotations are re-orthonormalised after every update (docs/design.md §2.3).
//
// Rotation parameterisations (SolverOptions::rotation; paper §3.3, docs/design.md §10), same
// potential, same tolerances, same line search:
//   * Lie (default): as above.
//   * Rotation vectors: each rotation is R = exp(r) with r = log(R) at the start of the
//     solve (so ‖r‖ ≤ π there: the re-wrapping between steps); the unknowns are the r's,
//     with derivatives J_l(r)ᵀ g and J_l(r)ᵀ H J_l(r) + C(r, g) (manifolds/rotation_chart.hpp),
//     and r ← r + α δr. Within a solve ‖r‖ may pass π.
//   * Quaternions: each rotation is R(q) (eq. A.21) of a unit quaternion q, from R at the
//     start of the solve; a step moves q along the unit sphere's tangent and renormalises,
//     q ← (q + α Q(q) δ)/‖·‖ (manifolds/quaternion.hpp). The derivatives with respect to δ at
//     δ = 0 are exactly the Lie ones; the update turns by 2 atan(α‖δ‖/2) instead of α‖δ‖.
//
// Convergence: the Newton step at the current iterate satisfies ‖δ‖∞ ≤ tolerance, i.e. the
// quadratic model puts the minimiser within `tolerance` metres and radians. Unlike a
// gradient threshold this does not depend on the scale of masses, stiffnesses or h.
// The final gradient norm is reported beside it.
// Judging an accepted update q₁ = q₀ ⊕ δ exactly takes an assembly and a factorisation at q₁,
// which a step that converges in one iteration then spends only on the verdict. With
// SolverOptions::convergence_check "estimated" (the default) the Newton step at q₁ is
// estimated with q₀'s factorisation, δ̂ = −H(q₀)⁻¹ g(q₁) (g(q₁) from the line search's pass,
// which then evaluates Ψ and g together), when the full step was taken and the quadratic
// model predicted its decrease of Ψ within kModelAgreement (5 %; newton.cpp): the model's
// error is −⅙ Ψ'''[δ,δ,δ] against ½ δᵀHδ, so H changed by ~3× that fraction along δ, and δ̂
// is the exact step to about that relative accuracy. ‖δ̂‖∞ ≤ tolerance ends the step (one
// assembly, one factorisation); otherwise the next iteration assembles at q₁ as before.
// An estimate is tried only where the last one's contraction C (‖δ̂‖ ≈ C ‖δ‖²) predicts at
// most 10× the tolerance: early iterations of a long solve cannot succeed.
// Under the trapezoidal integrator g(q₁) is taken with the torque fields re-referenced at q₁
// (what the next iteration would assemble) and δ̂ solves with H + K as δ does (below). Not
// estimated: regularised steps, decreases within 100× Ψ's round-off (not measurable).
// take_final_step: the step that ends a solve (δ at a converged iterate, or the estimate δ̂)
// is below the tolerance, but it is known and taking it costs a retraction, no assembly: the
// state then errs by O(‖δ‖²) instead of δ itself. Why it matters: a step left untaken repeats
// its sign from one time step to the next, and on a conservative scheme its ~tolerance-sized
// bias accumulates. The butterfly bolt under the trapezoidal rule at the tolerance 1e-9 lost
// ~3e-9 J per step so, and its flip period, which moves 5740× faster than the energy near the
// separatrix, came out 2.5 % short at h = 10 ms instead of the integrator's own 1e-4
// (Trapezoidal.TheBoltKeepsItsFlipPeriod). The convergence test alone (check()) moves nothing.
//
// Reusing a factorisation (SolverOptions::hessian_reuse = N > 1; docs/design.md §9.2): where
// the predictor already lands within a few tolerances of the solution (a smooth motion), a
// step's cost is its assembly and factorisation, and the Hessian they build barely differs
// from the last step's. A solve then starts with chord steps on the last factorisation M,
// made at most N − 1 steps earlier in the run (not shifted, same start frame):
// δ̃ = −M⁻¹ g(q), one value-and-gradient pass and one solve each, q ← q ⊕ δ̃, for at most
// kMaxChordSteps while each δ̃ is at most kChordContraction (½) of the last; ‖δ̃‖∞ ≤ tolerance
// ends the solve, converged, with that step taken. With ε = ‖I − M⁻¹H‖ (H the Hessian of the
// equations at the iterate) the step lacks (I − M⁻¹H)δ of Newton's, so the state errs by about
// ε·tolerance, against Newton's ~tolerance² — both within the tolerance while ε < 1. A chord
// sequence that stops contracting hands over to Newton's iterations from where it got, which
// assemble and factorise as usual. Measured error: where a new factorisation is made and the
// old one served (or was offered) chord steps, the old one's step at the same iterate is solved
// too, and ε ≈ ‖δ̃ − δ‖∞/‖δ‖∞ is reported (StepReport::reuse_error); above kMaxReuseError (½)
// the window of steps a factorisation may serve halves (at 1 none; it reopens at 2 after N
// factorisations), below a fifth of it it doubles back up to N. Where chord steps keep failing
// (steps that need Newton iterations) the attempts back off: after the second failure in a
// row 1, 2, 4, … up to N solves are skipped. Only where the linear system says its
// factorisations are worth reusing (System::kReusesFactorizations: the sparse one, rods and
// components beyond kDenseLimit DOFs): a dense system's factorisation costs about a gradient
// pass, and chord steps, which converge linearly, cost more than Newton's quadratic ones (the bolt
// under the trapezoidal rule at 1e-9 took 3.9 chord steps per step, 2.4× the time). Not used
// by check() (the exact test) or by the adjoint, which factorises the converged step's own
// Hessian. Ceres and Ipopt ignore N.
//
// Stall: a solve whose iterates stop improving ends early, unconverged, as
// StepStatus::kStalled (state updated, like kMaxIterations): after kStallIterations (10)
// consecutive updates after which none of Ψ, ‖g‖ and ‖δ‖∞ is lower than at the last
// progress — Ψ by more than its round-off (the line search's allowance, 16× the estimate of
// IncrementalPotential::assemble), ‖g‖ and ‖δ‖∞ by 1 % (newton.cpp). Why: near a minimum Ψ
// cannot resolve the remaining decrease, the line search then accepts steps on noise, and
// once ‖g‖ and δ have also reached their round-off floor (or a regularised step is too
// short to move q: H + μI with μ ≫ the curvature), further iterations only shuffle
// round-off. A tolerance below that floor (say 1e-300) could then never be met, and with a
// large max_iterations (2³¹ − 1) the step would run for ever. Real progress, even slow,
// lowers one of the three within a few iterations: quadratic convergence divides ‖g‖ by
// orders of magnitude per update, linear convergence by a fixed factor; at the floor a new
// lowest value of the noise becomes rarer with every iteration, so the count completes.
// Ten rather than fewer: light DOFs beside heavy ones (a 1e-9 kg body between 1e9 N/m
// springs and a 1e6 kg one) keep converging slowly while the heavy DOFs' noise sets all
// three measures; docs/design.md §9.1 gives the measurement.
//
// Indefinite Hessians (compressed springs, large rotations against R̃): when the Cholesky
// factorisation fails, H + μI is factorised with μ = 10⁻⁸·max|H_ii| growing tenfold until
// it succeeds; such iterations are counted in StepReport::regularized_iterations and a
// regularised step never counts as converged.
//
// The trapezoidal integrator (lib/history.hpp), Lie rotations: the step's equations have the
// Jacobian H + K, K = ½ hat(c) on each rotation with a history field c — the skew part of the
// fields' derivative, which the symmetric H lacks —, and Newton solves (H + K) δ = −g. Dense
// and banded systems factorise H + μI + K itself, by LU without pivoting (linear_system.hpp),
// once per iteration for δ and δ̂. Its positive pivots do not prove H + μI positive definite
// (banded_cholesky.hpp), so such a step must also descend: gᵀδ = −δᵀ(H + μI)δ < 0 (the
// slope of Ψ along δ, K adding nothing to it), or μ grows as for a failed factorisation. An
// indefinite H whose negative curvature lies off δ is then not regularised: the step is
// Newton's on the equations, it descends, and Ψ's model along it is right. Once a line search
// has had to shorten the step, the rest of the solve takes Ψ's own Newton steps, H δ = −g
// (Cholesky), re-referenced at every iteration (a fixed point contracting by ‖H⁻¹K‖): the
// equations' step differs from the minimiser of Ψ's model by H⁻¹Kδ, and where K is large
// against H (bodies stacked in contact, hard impacts) it need not serve the line search on Ψ —
// there K at every iteration stalls many more steps, as the fixed point below keeps H's step
// where its series does not settle. A smooth step takes whole steps and keeps K; the
// estimated check is not made on H's factorisation alone. CHOLMOD's path
// factorises H only, and (H + K) δ = −g is solved by kSkewCorrections fixed-point steps
// δ ← δ₀ − H⁻¹Kδ on H's factorisation instead (correct_for_history_skew). Rotation vectors
// and quaternions iterate without K (StepSolver::solve re-solves).
//
// Memory: all buffers are sized in the constructor (the sparse pattern at the first
// assembly); later solves allocate nothing (tests/allocation_test.cpp).
// Linear algebra (solvers/linear_system.hpp): DenseSystem<6> for a single rigid body,
// DenseSystem<Dynamic> for a few bodies coupled by springs, SparseSystem (CHOLMOD) beyond
// kDenseLimit coupled DOFs.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "../lib/incremental_potential.hpp"
#include "../manifolds/quaternion.hpp"
#include "../manifolds/rotation_chart.hpp"
#include "linear_system.hpp"
#include "step_solver.hpp"

namespace liedyn {

// Newton's method on one component, over a linear system type (solvers/linear_system.hpp).
template <class System>
class Newton final : public StepSolver {
 public:
  using Vector = typename System::Vector;

  Newton(Component component, const SolverOptions& options);

  Component& component() override { return component_; }
  const Component& component() const override { return component_; }
  const System& system() const { return system_; }
  // Turns SolverOptions::measure_condition on or off for the next solves.
  void set_measure_condition(bool on) override { options_.measure_condition = on; }

  // The convergence test (step_solver.hpp) at q: one assembly, factorisation and solve.
  StepReport check(State& q) override { return iterate(q, 0); }

 protected:
  // StepSolver::solve: minimises the component's potential, starting from (and writing
  // into) q. On failure, q is restored to its value on entry.
  StepReport minimize(State& q) override { return iterate(q, options_.max_iterations); }

 private:
  // At most max_iterations updates (0: only the test at q, which is left unchanged).
  StepReport iterate(State& q, int max_iterations);
  // Factorises H (with K where skew_factorized_) and solves for δ, regularising if needed;
  // false if even the regularised matrix fails.
  bool factorize_and_solve(StepReport& report, bool& regularized);
  void save(const State& q);
  // |λ|max/|λ|min of the assembled Hessian (an infinite value if singular).
  double hessian_condition() const;
  void restore(State& q);
  void retract(State& q, double alpha);
  // The trapezoidal integrator on a system that cannot factorise H + K (CHOLMOD, above): δ
  // from (H + K) δ = −g by kSkewCorrections fixed-point steps δ ← δ₀ − H⁻¹ K δ on H's
  // factorisation. Each leaves an error ‖H⁻¹K‖ times the last; without them every Newton
  // iteration would.
  void correct_for_history_skew();
  static constexpr int kSkewCorrections = 2;
  // The estimated convergence check at the accepted full step (above), whose Ψ and Lie
  // gradient (trial_gradient_) the line search computed: true, with the report filled in, if
  // ‖H⁻¹ g‖∞ ≤ tolerance with the last factorisation.
  bool converged_by_estimate(const State& q, const RotationVectorChart* chart, double psi,
                             StepReport& report);
  // x = M⁻¹ b with the last factorisation M, and where M lacks the trapezoidal history's K
  // the fixed-point corrections for it (as correct_for_history_skew); false where they do
  // not settle. Uses delta0_, skew_ and delta_ as scratch.
  bool solve_with_last_factorization(const Vector& b, Vector& x);
  // Reusing a factorisation (above): whether the last one may serve this solve, the chord
  // step (true, with q updated and the report filled in, if it is within the tolerance), and
  // the window's adaptation to the error measured at a new factorisation (chord_delta_).
  bool factorization_reusable();
  bool chord_step(State& q, const RotationVectorChart* chart, StepReport& report);
  void adapt_reuse_window(StepReport& report);
  static constexpr double kMaxReuseError = 0.5;
  static constexpr int kMaxChordSteps = 5;
  static constexpr double kChordContraction = 0.5;

  // Sets the rotation-vector or quaternion parameters from the rotations of q (and the
  // rotations from them, so that both agree exactly).
  void enter_parameterization(State& q);

  Component component_;
  SolverOptions options_;
  System system_;
  Vector delta_;
  Vector delta0_, skew_, correction_;  // correct_for_history_skew's and the estimate's scratch
  Vector trial_gradient_;              // g at the line search's full step (the estimate)
  double contraction_ = 0.0;           // C in ‖δ̂‖∞ ≈ C ‖δ‖∞², from the last estimate
  bool skew_factorized_ = false;       // the factorisation includes K (above)
  // Reusing a factorisation (above): the old factorisation's step −δ̃ where a new one is
  // made; whether the last factorisation may be reused (made, and not shifted), the frame and
  // start frame of its step (IncrementalPotential::frame), the chord steps it has served, and
  // the window of steps it may serve (SolverOptions::hessian_reuse, halved where the
  // measured error exceeds kMaxReuseError).
  Vector chord_delta_;
  bool reusable_ = false;
  int factorization_frame_ = 0, factorization_start_ = 0;
  int chords_since_factorization_ = 0;
  int reuse_window_ = 1;
  int closed_factorizations_ = 0;  // factorisations since the window closed (1)
  int chord_backoff_ = 0, chord_skip_ = 0;  // after failed chord steps: solves to skip
  ComponentSnapshot saved_, entry_;  // line-search backtracking; restore on failure
  // Rotation vectors: the chart (current and saved r's and J_l(r)'s).
  RotationVectorChart chart_;
  // Quaternions: current and saved, per rotation of the component.
  std::vector<quat::Vector4> quaternions_, saved_quaternions_;
};

// One rigid body (fixed size), a few coupled bodies (dense), many coupled bodies (CHOLMOD).
template <int N>
using DenseNewton = Newton<DenseSystem<N>>;
using SparseNewton = Newton<SparseSystem>;

// Newton on the linear system that suits the component's size: DenseSystem<6> for one rigid
// body, DenseSystem<Dynamic> up to kDenseLimit DOFs, SparseSystem beyond.
std::unique_ptr<StepSolver> make_newton(Component component, const SolverOptions& options);

extern template class Newton<DenseSystem<6>>;
extern template class Newton<DenseSystem<Eigen::Dynamic>>;
extern template class Newton<SparseSystem>;

}  // namespace liedyn

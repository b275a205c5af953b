#pragma once
// A pulling cable (tendon), paper §7.4: a cable of tension T ≥ 0 routed through points
// attached to rod edges (or bodies), p_j = x_j + R_j p̄_j (state.hpp, AttachedPoint), with
// e.g. p̄ = (ρ cos φ, ρ sin φ, s) in the edge's material frame. Pulling it is the potential
//   V = T Σ_segments ‖p_{j+1} − p_j‖,
// whose force on a routing point is T times the sum of the unit vectors towards its
// neighbours. One term per segment; a cable is its consecutive segments with one tension.
//
// Per segment, with d = p_b − p_a, l = ‖d‖, n = d/l:
//   V = T l,   f = ∂V/∂d = T n,   K = ∂²V/∂d² = T (I − n nᵀ)/l,
// mapped to the blocks (x_a, θ_a, x_b, θ_b) exactly as for a spring (point_pair.hpp,
// eqs. 22, 23): gradient Jdᵀ f, Hessian Jdᵀ K Jd + eq. (23) curvature at each rotation.
// K is PSD (T ≥ 0), but the eq. (23) curvature ½(f_p rᵀ + r f_pᵀ) − (f_p·r) I is indefinite in
// general, so the segment's Lie Hessian can be indefinite: the Newton solver regularises the
// assembled matrix (solvers/newton.hpp).
//
// Degenerate segment, l = 0 (including |d| ≲ 1e-162 m, where d.norm() underflows to 0): V is a
// cone there, V(ε u) = T ε along every unit u, and not differentiable. We return
//   gradient 0 — the smallest element of the generalised gradient {T u : ‖u‖ ≤ 1} (the
//             cone's minimum: a slack cable pulls nothing), and
//   Hessian 0 — K = T (I − n nᵀ)/l is unbounded as l → 0 and has no limit (it depends on the
//             direction of approach), so no bounded curvature exists; 0 is the curvature of
//             the cone along its rays and adds nothing that Newton could mistake for stiffness.
//
// Parameter derivative (adjoint, docs/design.md §8; paper eq. 21): V is linear in T, so
//   ∂C/∂T = ∂(Lie gradient)/∂T = the Lie gradient at T = 1 = Jdᵀ n   (tension_gradient),
// and (∂C/∂T)ᵀ z = tension_gradient(q) · z_local. The term reads only q_k: it has no mixed
// blocks with q_{k−1} or Δq_{k−1}.
//
// No least-squares form (term.hpp): V is linear in T and not a sum of squares, so the Ceres
// back-end treats a cable segment as an unfoldable linear load (OffsetRootForm in
// solvers/ceres_step.cpp: one residual √(2(V + c)) built from evaluate()'s value and gradient).

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

struct CableSegment {
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "cable";
  std::array<int, kBlocks> offsets{-1, -1, -1, -1};  // x_a, θ_a, x_b, θ_b
  AttachedPoint a, b;                                // routing points, in cable order
  double tension = 0.0;  // T [N], ≥ 0: the cable's current tension (set per frame by the caller)
  ScheduledParameter<1> control;  // per-step tensions and their slot in γ (term.hpp)

  // Step k's tension from the schedule (kept constant without one).
  void begin_frame(int k) { tension = control.at(k, Eigen::Matrix<double, 1, 1>(tension))(0); }
  bool scheduled() const { return !control.schedule.empty(); }

  // V = T ‖p_b − p_a‖, and its Lie gradient and Lie Hessian as derived at the top. Valid for any
  // T (linear in it); only T ≥ 0 is physical, and only then is K PSD. Does not check T (it runs
  // in the Newton loop): callers check with validate() when they set it.
  double evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const;

  // ∂(Lie gradient)/∂T: the local gradient at T = 1, Jdᵀ n (0 for a degenerate segment). Used by
  // the adjoint pass: (∂C/∂T)ᵀ z = tension_gradient(q) · z_local. evaluate()'s gradient is
  // exactly T times it when T is a power of two (up to round-off otherwise).
  LocalGradient<4> tension_gradient(const State& q) const;
  // HasParameters (term.hpp): adds (∂C/∂γ)ᵀ z for step `frame`.
  void add_parameter_adjoint(const State& q, int frame, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const;

  // Throws std::invalid_argument naming the field, its value and the rule unless the tension
  // is finite and ≥ 0.
  void validate() const;
};

}  // namespace liedyn

#pragma once
// Contact damping: a dashpot on a contact sample's normal approach velocity while the sample is
// in a collider's penalty zone, as the step's dissipation potential (lagged, as friction is).
//
// The penalty ½ k d² (contact.hpp) is a spring: alone it returns all the energy of an impact,
// and under the trapezoidal rule nothing else takes it (docs/design.md §14). This term adds the
// dashpot that makes the pair a Kelvin–Voigt contact. At the start of step k the zone and the
// normal are frozen at the previous state: with p̂ = p(q_{k−1}),
//   active = ρ − φ(p̂) > 0,   n = ∇φ(p̂)/‖∇φ(p̂)‖,
// and with s = nᵀ(p − p̂) the sample's normal displacement over the step, the dissipation
// potential D(v) = ½ c v_n² times h, at v_n = s/h, is
//   D = c s²/(2h),   f = ∂D/∂p = (c/h) s n   (= c v_n n: the dashpot's force),
//   K = ∂²D/∂p² = (c/h) n nᵀ,
// zero when not active, and mapped to (x, θ) like any attached-point potential
// (attached_point_derivatives, point_pair.hpp). It acts at the step's end (EndOfStep, term.hpp).
//
// Restitution. A mass m on one sample meets a linear spring k and dashpot c: its normal motion
// is a damped oscillator of damping ratio ζ = c/(2√(k m)), which leaves the zone with the
// restitution e = exp(−ζπ/√(1 − ζ²)) (ζ < 1), whatever the impact speed and, once the contact
// lasts many steps, whatever h: c = 2ζ√(k m) with ζ = −ln e/√(π² + ln² e) sets e. Lagging the
// zone shifts the dashpot's onset and end by up to a step, an error O(h/T) in e for a contact
// lasting T = π/√(k/m − ζ²k/m) (ContactDampingScenes.*).
//
// Least-squares form (contract: term.hpp), 1 residual: r = √(c/h) s,
// J = √(c/h) [nᵀ, (r_lever × n)ᵀ]; ½ r² = D and Jᵀ r = the gradient. r = 0, J = 0 when not active.
//
// The adjoint (docs/design.md §8): p̂ and n are functions of q_{k−1}, so the gradient C has the
// mixed block ∂C/∂q_{k−1} (previous_jacobian): with w = p − p̂, G = ∇φ(p̂), g = ‖G‖, N̂ = ∇²φ(p̂),
// P = I − n nᵀ,
//   ∂n/∂p̂ = P N̂/g,   ∂s/∂p̂ = −nᵀ + wᵀ ∂n/∂p̂,   ∂f/∂p̂ = (c/h)(n ∂s/∂p̂ + s ∂n/∂p̂),
// and p̂ = x̂ + R̂ p̄ gives ∂p̂/∂(x̂, θ̂) = [I, −hat(r̂)]; the θ rows of C are r × f. The zone's
// switch at φ(p̂) = ρ is a jump in the dashpot: the adjoint is that of the side the run is on.
// Δq_{k−1} does not enter.

#include "contact.hpp"
#include "dissipation_law.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// The dashpot's law and rate r = c/h = τ k/h (τ = c/k) are NormalDashpot's (dissipation_law.hpp,
// which the dashpots between objects share).
struct ContactDamping : ContactSample, NormalDashpot {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "contact_damping";
  static constexpr bool kEndOfStep = true;  // term.hpp

  // Lagged per step (begin_step): p̂, whether the sample is in the zone, n.
  Vector3 previous_position = Vector3::Zero();
  bool active = false;
  Vector3 normal = Vector3::UnitZ();

  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // ∂C/∂(x̂, θ̂): the 6×6 mixed block of the local gradient C (rows x, θ at q_k) with respect
  // to the sample frame's previous point and rotation (formulas at the top). `previous` must
  // be the state begin_step was given.
  Eigen::Matrix<double, 6, 6> previous_jacobian(const State& q, const State& previous) const;
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z (Δq_{k−1} does not enter).
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;

 private:
  const NormalDashpot& law() const;  // the law, apart from the term's own evaluate and residual
};

}  // namespace liedyn

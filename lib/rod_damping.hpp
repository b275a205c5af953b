#pragma once
// Internal (Kelvin–Voigt) damping of a Cosserat rod: dissipation potentials on the rates of
// its stretch, its shear and its bending and twist, as the step's terms (docs/design.md §6.6).
//
// A damping stress proportional to a strain rate has the dissipation potential
// ½ η (strain rate)² per length; times h, with the rate taken over the step as
// (strain_k − strain_{k−1})/h, it is the elastic term's own form with the stiffness η/h and
// the rest strain replaced by the previous step's strain (frozen in begin_step):
//
//   Stretch, blocks (x_i, x_{i+1}); η_s [N·s] (stress η_s ε̇, ε = (L − l)/l):
//     D = (η_s/(2 l h)) (L − L̂)²,   L = ‖x_{i+1} − x_i‖,  L̂ the same at q_{k−1}:
//     a length spring of stiffness η_s/(l h) and rest length L̂ (length_spring, spring.hpp);
//     its force along the edge is (η_s/l) L̇ = η_s ε̇.
//   Bend and twist at interior node i, blocks (θ_{i−1}, θ_i); η = (η₁, η₂, η₃) [N·m²·s]:
//     D = ½ w (ω − ω̂)ᵀ (η/h) (ω − ω̂),   ω = vee(R_aᵀ R_b)/w,  ω̂ the same at q_{k−1}:
//     RodBendTwist (rod_terms.hpp) with stiffness η/h and rest Darboux vector ω̂; its moment
//     is η ω̇. w is the node's bending length (lib/rod.hpp), as for the elastic term. Across
//     a splice's junction the form sees b's first frame times the junction's twist T, as the
//     elastic term there does (RodBendTwist::frame_offset): R_b T in place of R_b throughout,
//     ω̂ included; a left perturbation of R_b is one of R_b T, so the formulas below hold.
//
//   Shear, blocks (x_i, x_{i+1}, θ_i); η_x [N·s]: the shear strain in the material frame,
//     γ = R_iᵀ d − e_z (d = e/L, unit; objective: a rigid rotation leaves it), over the step:
//     D = ¼ (η_x/h) l ‖γ − γ̂‖² = ¼ (η_x/h) l ‖d − R_i â‖² = ½ (η_x/h) l (1 − dᵀ R_i â),
//     â = R̂_iᵀ d̂ (unit): RodShear (rod_terms.hpp) with stiffness η_x/h and material axis â
//     in place of e_z. Beside the elastic ¼ k_x l ‖γ‖², η_x = β k_x is a Rayleigh damping.
//
// For a rod whose damping is proportional to its stiffness, η = β K (a Rayleigh damping
// C = β K on the bending modes), a mode of angular frequency ω_n has the damping ratio
// ζ_n = β ω_n/2: slow modes ring, fast ones are damped (RodDamping.* tests the first
// cantilever mode's decay). The three terms act at the step's end (EndOfStep, term.hpp): first
// order in the damping, as friction.
//
// Least-squares forms: those of the elastic terms, r = √(η_s/(l h)) (L − L̂),
// r = √w (η/h)^½ (ω − ω̂) and r = √(η_x l/(2h)) (d − R_i â).
//
// The adjoint (docs/design.md §8): L̂ and ω̂ are functions of q_{k−1}, so the gradient C has
// the mixed blocks ∂C/∂q_{k−1} (previous_jacobian):
//   stretch: with n = e/L, n̂ = ê/L̂ and k = η_s/(l h), C = (−f, f), f = k (L − L̂) n, so
//     ∂f/∂(x̂_i, x̂_{i+1}) = −k n (−n̂ᵀ, n̂ᵀ)  (through L̂ only);
//   bend: ∂C/∂ω̂ = (W K, −W K) (RodBendTwist::parameter_jacobians, K = η/h) and
//     ∂ω̂/∂(θ̂_a, θ̂_b) = (−R̂_aᵀ Ĝ, R̂_aᵀ Ĝ)/w,  Ĝ = ½ (tr Ĉ I − Ĉ),  Ĉ = R̂_b (T) R̂_aᵀ
//     (rod_terms.hpp, first order of ω);
//   shear: with c = ½ (η_x/h) l, t = R_i â, P = I − d dᵀ, the gradient
//     (c P t/L, −c P t/L, c d × t) has ∂/∂â = (c P R_i/L, −c P R_i/L, c hat(d) R_i), and
//     ∂â/∂(x̂_i, x̂_{i+1}, θ̂_i) = (−R̂_iᵀ P̂/L̂, R̂_iᵀ P̂/L̂, R̂_iᵀ hat(d̂))
//     (a left perturbation of R̂_i turns R̂_iᵀ d̂ by R̂_iᵀ hat(d̂) δ).
//   Δq_{k−1} enters none of them.

#include "rod_terms.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

struct RodStretchDamping {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "rod_stretch_damping";
  static constexpr bool kEndOfStep = true;  // term.hpp
  std::array<int, kBlocks> offsets{-1, -1};  // x_i, x_{i+1}
  int node0 = -1, node1 = -1;                // i, i+1 (State::points)
  double rest_length = 0.0;                  // l   [m], > 0
  double damping = 0.0;                      // η_s [N·s], > 0
  double time_step = 0.0;                    // h   [s], > 0
  double previous_length = 0.0;              // L̂   [m], lagged (begin_step)

  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // ∂C/∂(x̂_i, x̂_{i+1}) (formulas at the top); `previous` as given to begin_step.
  Eigen::Matrix<double, 6, 6> previous_jacobian(const State& q, const State& previous) const;
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z.
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;

 private:
  double rate() const { return damping / (rest_length * time_step); }  // η_s/(l h)
};

// A damping term that is an elastic term's form with lagged rest values (set in begin_step by
// the term using it): value, Lie gradient, Hessian and residual are the form's.
template <class Form>
struct LaggedForm {
  static constexpr int kBlocks = Form::kBlocks;
  static constexpr bool kEndOfStep = true;  // term.hpp
  static constexpr int kResiduals = Form::kResiduals;
  using Residual = typename Form::Residual;
  using ResidualJacobian = typename Form::ResidualJacobian;
  std::array<int, kBlocks> offsets;  // the form's blocks
  Form form;

  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
    return form.evaluate(q, g, H);
  }
  void residual(const State& q, Residual& r, ResidualJacobian* J) const { form.residual(q, r, J); }

 protected:
  LaggedForm() { offsets.fill(-1); }
};

struct RodBendTwistDamping : LaggedForm<RodBendTwist> {
  static constexpr const char* kName = "rod_bend_twist_damping";
  // offsets: θ_{i−1}, θ_i; form: edges, w, stiffness η/h, rest Darboux ω̂ (begin_step).
  Vector3 damping = Vector3::Zero();  // (η₁, η₂, η₃) [N·m²·s]: bend, bend, twist
  double time_step = 0.0;             // h [s], > 0

  // Sets form's edges, bending length and η/h (a junction's frame offset is set on form).
  void set(int edge0, int edge1, double bending_length);
  void begin_step(const State& previous, const Step& previous_step);

  // ∂C/∂(θ̂_{i−1}, θ̂_i) (formulas at the top); `previous` as given to begin_step.
  Eigen::Matrix<double, 6, 6> previous_jacobian(const State& q, const State& previous) const;
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z.
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
};

struct RodShearDamping : LaggedForm<RodShear> {
  static constexpr const char* kName = "rod_shear_damping";
  // offsets: x_i, x_{i+1}, θ_i; form: nodes, edge, l, stiffness η_x/h, axis â (begin_step).
  double damping = 0.0;    // η_x [N·s], > 0
  double time_step = 0.0;  // h [s], > 0

  // Sets form's nodes, edge, rest length and η_x/h.
  void set(int node0, int node1, int edge, double rest_length);
  void begin_step(const State& previous, const Step& previous_step);

  // ∂C/∂(x̂_i, x̂_{i+1}, θ̂_i) (formulas at the top); `previous` as given to begin_step.
  Eigen::Matrix<double, 9, 9> previous_jacobian(const State& q, const State& previous) const;
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z.
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
};

}  // namespace liedyn

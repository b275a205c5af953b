#pragma once
// Smoothed Coulomb friction of a contact sample as an incremental potential (lagged, after
// Li et al. 2020 (IPC) and Ferguson et al. 2021; paper §7.1).
//
// At the start of step k the normal force and the contact normal are frozen ("lagged") at the
// previous state: with p̂ = p(q_{k−1}) the sample's previous position,
//   λ = k max(0, ρ − φ(p̂)),   n = ∇φ(p̂)/‖∇φ(p̂)‖,   P = I − n nᵀ.
// The sample's tangential displacement over the step is u = P (p − p̂), y = ‖u‖, and
//   D = μ λ f₀(y),   ε = ε_v h (the displacement at the stick–slip transition speed ε_v),
//   f₀(y) = −y³/(3ε²) + y²/ε + ε/3   (y < ε),   y   (y ≥ ε),
// a C² smoothing of μλ‖u‖ (kinetic friction: a force μλ opposing the slip) whose slope
// f₁ = f₀′ rises from 0 to 1 as the slip speed y/h rises from 0 to ε_v. With φ₁ = f₁(y)/y,
//   φ₁ = 2/ε − y/ε²,  φ₁′ = −1/ε²   (y < ε);    φ₁ = 1/y,  φ₁′ = −1/y²   (y ≥ ε),
//   f = ∂D/∂p = μλ φ₁ u,
//   K = ∂²D/∂p² = μλ (φ₁ P + φ₁′ y û ûᵀ),   û = u/y   (PSD: eigenvalues μλ(2/ε − 2y/ε²) ≥ 0
//       along û below ε, 0 above, μλ φ₁ > 0 across; at y = 0, K = 2μλ/ε P),
// then mapped to (x, θ) like any attached-point potential (contact.hpp). A sticking sample
// creeps at a speed below ε_v (f₁ < 1 there); smaller ε_v sticks harder and is stiffer.
//
// Least-squares form (contract: term.hpp), 1 residual: r = √(2D) (D ≥ μλε/3 > 0 whenever
// λ > 0, so r is smooth), J = gradientᵀ/r; r = 0, J = 0 when λ = 0.
//
// The adjoint (docs/design.md §8): λ, n and p̂ are functions of q_{k−1}, so the gradient C has the
// mixed block ∂C/∂q_{k−1} (previous_jacobian): with G = ∇φ(p̂), g = ‖G‖, N̂ = ∇²φ(p̂),
//   ∂λ/∂p̂ = −k G  (λ > 0),   ∂n/∂p̂ = P N̂/g,   ∂u/∂p̂ = −P − (n wᵀ + (n·w) I) ∂n/∂p̂,  w = p − p̂,
//   ∂f/∂p̂ = μ φ₁ u (∂λ/∂p̂)ᵀ + μλ (φ₁ I + φ₁′ y û ûᵀ) ∂u/∂p̂,
// and p̂ = x̂ + R̂ p̄ gives ∂p̂/∂(x̂, θ̂) = [I, −hat(r̂)]; the θ rows of C are r × f.
// Δq_{k−1} does not enter.

#include <cmath>
#include <memory>

#include "contact.hpp"
#include "sdf.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// The smoothed slip law of a tangential displacement u (formulas above), shared by the
// friction terms against colliders (Friction) and between bodies (body_contact.hpp).
struct SmoothedSlip {
  Vector3 u;      // the tangential displacement
  double y;       // ‖u‖
  double phi1;    // f₁(y)/y
  double dphi1;   // φ₁′(y)
  double f0;      // f₀(y)

  SmoothedSlip(const Vector3& tangential, double epsilon);
  // ∂(φ₁ u)/∂u = φ₁ I + (φ₁′/y) u uᵀ (the last part vanishes as y → 0, φ₁′ bounded).
  Matrix3 jacobian() const { return curvature(Matrix3::Identity()); }
  // K/(μλ) = φ₁ P + (φ₁′/y) u uᵀ for the tangent projector P (= jacobian() P, as uᵀP = uᵀ;
  // written symmetric).
  Matrix3 curvature(const Matrix3& P) const;
};

// The least-squares form r = √(2D) of a friction term (D > 0 whenever λ > 0), J = gᵀ/r, for
// any term whose evaluate() gives D and its gradient.
template <class T>
void friction_residual(const T& term, const State& q, typename T::Residual& r,
                       typename T::ResidualJacobian* J) {
  LocalGradient<T::kBlocks> g;
  const double D = term.evaluate(q, J != nullptr ? &g : nullptr, nullptr);
  r(0) = std::sqrt(2.0 * D);
  if (J == nullptr) return;
  if (r(0) > 0.0) {
    *J = g.transpose() / r(0);  // ∂√(2D) = ∂D/√(2D)
  } else {
    J->setZero();
  }
}

struct Friction : ContactSample {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "friction";
  static constexpr bool kEndOfStep = true;  // term.hpp
  double coefficient = 0.0;  // μ
  double epsilon = 0.0;      // ε = ε_v h, m, > 0

  // Lagged per step (begin_step): p̂, λ, n.
  Vector3 previous_position = Vector3::Zero();
  double normal_force = 0.0;
  Vector3 normal = Vector3::UnitZ();

  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // ∂C/∂(x̂, θ̂): the 6×6 mixed block of the local gradient C (rows x, θ at q_k) with respect
  // to the sample frame's previous point and rotation (columns x̂, θ̂; formulas at the top).
  // `previous` must be the state begin_step was given.
  Eigen::Matrix<double, 6, 6> previous_jacobian(const State& q, const State& previous) const;
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z and (∂C/∂Δq_{k−1})ᵀ z.
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;

};

}  // namespace liedyn

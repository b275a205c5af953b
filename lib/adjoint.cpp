// The adjoint blocks of the incremental potential (incremental_potential.hpp, docs/design.md §8):
// each term's Jacobians come from the term itself (its add_step_adjoint and
// add_parameter_adjoint, term.hpp); this file gathers z onto each term's stencil.

#include "incremental_potential.hpp"

#include <Eigen/Cholesky>
#include <type_traits>

#include "so3.hpp"

namespace liedyn {

namespace {

// The term's part of the component vector z (zeros where a block is not a DOF).
template <class T>
LocalGradient<T::kBlocks> gather(const T& term, const Eigen::VectorXd& z) {
  LocalGradient<T::kBlocks> local;
  for (int b = 0; b < T::kBlocks; ++b) {
    const int o = term.offsets[b];
    local.template segment<3>(3 * b) = o < 0 ? Vector3::Zero() : Vector3(z.segment<3>(o));
  }
  return local;
}

// A term none of whose blocks is a DOF contributes nothing (its z is zero).
template <class T>
bool has_dofs(const T& term) {
  for (const int o : term.offsets) {
    if (o >= 0) return true;
  }
  return false;
}

}  // namespace

void IncrementalPotential::add_step_adjoint(const State& q, const State& previous,
                                            const Step& previous_step, const Eigen::VectorXd& z,
                                            Eigen::VectorXd& a_previous,
                                            Eigen::VectorXd& da_previous) const {
  for_each_term_vector([&](const auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    if constexpr (ReadsPreviousStep<T>) {
      if constexpr (std::is_same_v<T, TranslationalInertia> || std::is_same_v<T, RotationalInertia>) {
        if (integrator_ == Integrator::kBdf2) return;  // add_bdf2_adjoint's
      }
      for (const T& t : terms) {
        if (has_dofs(t)) {
          t.add_step_adjoint(q, previous, previous_step, weight(t) * gather(t, z), a_previous,
                             da_previous);
        }
      }
    }
  });
}

void IncrementalPotential::add_parameter_adjoint(const State& q, int frame,
                                                 const Eigen::VectorXd& z,
                                                 Eigen::VectorXd& dgamma) const {
  for_each_term_vector([&](const auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    if constexpr (HasParameters<T>) {
      for (const T& t : terms) {
        if (has_dofs(t)) t.add_parameter_adjoint(q, frame, weight(t) * gather(t, z), dgamma);
      }
    }
  });
}

void IncrementalPotential::add_weighted_terms_adjoint(
    const State& s, const Eigen::VectorXd& G, double w, int frame, const State& previous,
    const Step& previous_step, const Eigen::VectorXd& z, Eigen::VectorXd& u,
    Eigen::VectorXd& a_previous, Eigen::VectorXd& da_previous, Eigen::VectorXd& dgamma) const {
  for_each_term_vector([&](const auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    LocalHessian<T::kBlocks> H;
    for (const T& t : terms) {
      if (!state_term(t) || !has_dofs(t)) continue;
      const LocalGradient<T::kBlocks> wz = w * gather(t, z);
      t.evaluate(s, nullptr, &H);
      const LocalGradient<T::kBlocks> Hz = H * wz;  // H symmetric
      for (int b = 0; b < T::kBlocks; ++b) {
        if (t.offsets[b] >= 0) u.segment<3>(t.offsets[b]) += Hz.template segment<3>(3 * b);
      }
      if constexpr (ReadsPreviousStep<T>) {
        t.add_step_adjoint(s, previous, previous_step, wz, a_previous, da_previous);
      }
      if constexpr (HasParameters<T>) t.add_parameter_adjoint(s, frame, wz, dgamma);
    }
  });
  // The Lie gradient field's derivative is H − ½ hat(G) per rotation block (design §1.4); z is
  // non-zero only on the rotations with inertia.
  for (const RotationalInertia& t : terms<RotationalInertia>()) {
    const int o = t.offsets[0];
    u.segment<3>(o) += 0.5 * w * Vector3(G.segment<3>(o)).cross(Vector3(z.segment<3>(o)));
  }
}

void IncrementalPotential::add_older_adjoint(const State& previous, const Step& previous_step,
                                             const Eigen::VectorXd& u, Eigen::VectorXd& a_previous,
                                             Eigen::VectorXd& da_previous) const {
  for (const TranslationalInertia& t : terms<TranslationalInertia>()) {
    const int o = tangent_point(t.point);
    a_previous.segment<3>(o) += u.segment<3>(t.offsets[0]);
    da_previous.segment<3>(o) -= u.segment<3>(t.offsets[0]);
  }
  for (const RotationalInertia& t : terms<RotationalInertia>()) {
    const int o = tangent_rotation(previous, t.rotation);
    const Vector3 v = previous_step.rotations[t.rotation] * u.segment<3>(t.offsets[0]);
    a_previous.segment<3>(o) += v;
    da_previous.segment<3>(o) -= v;
  }
}

void IncrementalPotential::add_history_adjoint(const State& q, const State& previous,
                                               const Step& previous_step, const Step& step_before,
                                               int frame, const Eigen::VectorXd& z,
                                               Eigen::VectorXd& a_previous,
                                               Eigen::VectorXd& da_previous,
                                               Eigen::VectorXd& da_before,
                                               Eigen::VectorXd& dgamma) {
  if (integrator_ == Integrator::kBdf2) {
    add_bdf2_adjoint(q, previous, previous_step, step_before, frame, z, a_previous, da_previous,
                     da_before, dgamma);
    return;
  }
  const double beta = newmark_beta(integrator_);
  if (beta == 0.0) return;
  const bool first = frame <= 1;
  const std::vector<RotationHistory>& rotations = terms<RotationHistory>();
  // c = (1 − 2β) ∇V(q_{k−1}) + β ∇V(q_{k−2}) − μ_{k−3/2}/h   (frame 1: (½ − β) ∇V(q_0) − π_0/h).
  Eigen::VectorXd& u = adjoint_older_;
  u.setZero(z.size());
  add_weighted_terms_adjoint(previous, gradient_previous_, first ? 0.5 - beta : 1.0 - 2.0 * beta,
                             frame, previous, previous_step, z, u, a_previous, da_previous, dgamma);
  for (const PointHistory& t : terms<PointHistory>()) {
    a_previous.segment<3>(tangent_point(t.point)) += u.segment<3>(t.offsets[0]);
  }
  for (const RotationHistory& t : rotations) {
    a_previous.segment<3>(tangent_rotation(previous, t.rotation)) += u.segment<3>(t.offsets[0]);
  }
  if (!first) {
    u.setZero();
    add_weighted_terms_adjoint(older_, gradient_older_, beta, frame, previous, previous_step, z,
                               u, a_previous, da_previous, dgamma);
    add_older_adjoint(previous, previous_step, u, a_previous, da_previous);
  }
  // The momentum m = μ_{k−3/2}/h (begin_step) enters c with a minus sign.
  const std::vector<RotationalInertia>& inertia = terms<RotationalInertia>();
  for (std::size_t i = 0; i < rotations.size(); ++i) {
    const RotationHistory& t = rotations[i];
    const Matrix3& R = previous.rotations[t.rotation];
    const Matrix3& dR = previous_step.rotations[t.rotation];
    const Matrix3& J = inertia[i].J_over_h2;
    Matrix3 dm_dR, dm_ddR;  // ∂m/∂θ for R → exp(θ) R, ∂m/∂ψ for ΔR → exp(ψ) ΔR
    if (first) {
      // m = A φ, A = R (tr(Ĵ) 1 − Ĵ) Rᵀ, φ = log ΔR_0: dm = hat(θ) m − A hat(θ) φ + A J_l⁻¹(φ) ψ.
      Matrix3 J_phi;
      const Vector3 phi = so3::log(dR, &J_phi);
      const Matrix3 A = R * (J.trace() * Matrix3::Identity() - J) * R.transpose();
      dm_dR = -so3::hat(A * phi) + A * so3::hat(phi);
      dm_ddR = A * J_phi;
    } else {
      // m = 2 vee(B ΔR), B = R Ĵ Rᵀ: dB = hat(θ) B − B hat(θ), d(ΔR) = hat(ψ) ΔR.
      const Matrix3 B = R * J * R.transpose();
      for (int j = 0; j < 3; ++j) {
        const Matrix3 e = so3::hat(Vector3::Unit(j));
        dm_dR.col(j) = 2.0 * so3::vee((e * B - B * e) * dR);
        dm_ddR.col(j) = 2.0 * so3::vee(B * e * dR);
      }
    }
    const int o = tangent_rotation(previous, t.rotation);
    const Vector3 zt = z.segment<3>(t.offsets[0]);
    a_previous.segment<3>(o) -= dm_dR.transpose() * zt;
    da_previous.segment<3>(o) -= dm_ddR.transpose() * zt;
  }
}

void IncrementalPotential::add_bdf2_adjoint(const State& q, const State& previous,
                                            const Step& previous_step, const Step& step_before,
                                            int frame, const Eigen::VectorXd& z,
                                            Eigen::VectorXd& a_previous,
                                            Eigen::VectorXd& da_previous,
                                            Eigen::VectorXd& da_before,
                                            Eigen::VectorXd& dgamma) {
  // Reverse mode through x̃ = ½(5x₁ − 4x₂ + x₃), x₂ = x₁ − Δx_{k−1}, x₃ = x₂ − Δx_{k−2}
  // (x_i = x_{k−i}), and R̃ = ½(5R₁ − 4R₂ + R₃), R₂ = ΔR_{k−1}ᵀ R₁, R₃ = ΔR_{k−2}ᵀ R₂ (design
  // §15.1). At frame 1 Δq_{k−2} is Δq_0 = Δq_{k−1}; at frame 2 it is the initial step
  // corrected by the initial acceleration (begin_bdf2_step), whose inputs Δq_0, q_0 = q_{k−2}
  // and ∇V(q_0) take its cotangent.
  const bool corrected = frame == 2;
  const Step& before = corrected ? corrected_step_ : step_before;
  Eigen::VectorXd& d_before = frame <= 1 ? da_previous : da_before;
  Eigen::VectorXd& older = adjoint_older_;     // at q_{k−2}, component layout
  Eigen::VectorXd& g_bar = adjoint_gradient_;  // of ∇V(q_0) (frame 2)
  older.setZero(z.size());
  if (corrected) g_bar.setZero(z.size());
  for (const TranslationalInertia& t : terms<TranslationalInertia>()) {
    const int o = t.offsets[0];
    const Vector3 x_bar = t.x_tilde_adjoint(z.segment<3>(o));
    const Vector3 x3_bar = 0.5 * x_bar;
    a_previous.segment<3>(tangent_point(t.point)) += 2.5 * x_bar;
    older.segment<3>(o) = -2.0 * x_bar + x3_bar;
    d_before.segment<3>(tangent_point(t.point)) -= x3_bar;
    // Δx_0' = Δx_0 + ∇V(q_0)/(2m/h²).
    if (corrected) g_bar.segment<3>(o) = -x3_bar / t.mass_over_h2;
  }
  for (const RotationalInertia& t : terms<RotationalInertia>()) {
    const int o = t.offsets[0];
    const Matrix3& R1 = previous.rotations[t.rotation];
    const Matrix3& dR2 = before.rotations[t.rotation];
    const Matrix3 R2 = previous_step.rotations[t.rotation].transpose() * R1;
    const Matrix3 R3 = dR2.transpose() * R2;
    // Ḡ_i = c_i Ḡ for R̃ = Σ c_i R_i; R_i → exp(θ_i) R_i: θ̄_i = 2 vee(Ḡ_i R_iᵀ).
    const Matrix3 G = t.R_tilde_adjoint(q, z.segment<3>(o));
    const Vector3 theta3 = so3::vee(G * R3.transpose());
    a_previous.segment<3>(tangent_rotation(previous, t.rotation)) += 5.0 * so3::vee(G * R1.transpose());
    // θ₃ = ΔR_{k−2}ᵀ (θ₂ − ψ_{k−2}).
    older.segment<3>(o) = -4.0 * so3::vee(G * R2.transpose()) + dR2 * theta3;
    const Vector3 psi = -dR2 * theta3;
    if (!corrected) {
      d_before.segment<3>(tangent_rotation(previous, t.rotation)) += psi;
      continue;
    }
    // ΔR_0' = exp(w), w = φ + s, s = A⁻¹ r, r = ∇V(q_0) + ½ φ × A φ, φ = log ΔR_0,
    // A = R_0 (tr(Ĵ) 1 − Ĵ) R_0ᵀ; δA = D(θ₀) with D(v) θ = δA v = (A hat(v) − hat(A v)) θ.
    const Matrix3& R0 = older_.rotations[t.rotation];
    Matrix3 J_phi, J_w;
    const Vector3 phi = so3::log(step_before.rotations[t.rotation], &J_phi);
    const Matrix3 A =
        R0 * (t.J_over_h2.trace() * Matrix3::Identity() - t.J_over_h2) * R0.transpose();
    const Eigen::LDLT<Matrix3> A_inverse(A);
    const Vector3 Aphi = A * phi;
    const Vector3 s =
        A_inverse.solve(Vector3(gradient_older_.segment<3>(o) + 0.5 * phi.cross(Aphi)));
    so3::exp(phi + s, &J_w);
    const Vector3 w_bar = J_w.transpose() * psi;
    const Vector3 p = A_inverse.solve(w_bar);
    const auto D = [&](const Vector3& v) -> Matrix3 { return A * so3::hat(v) - so3::hat(A * v); };
    g_bar.segment<3>(o) = p;
    const Vector3 phi_bar = w_bar + 0.5 * (so3::hat(Aphi) - A * so3::hat(phi)) * p;
    d_before.segment<3>(tangent_rotation(previous, t.rotation)) += J_phi.transpose() * phi_bar;
    older.segment<3>(o) += (0.5 * so3::hat(phi) * D(phi) - D(s)).transpose() * p;
  }
  if (corrected) {
    // ∇V(q_0): its Hessian, the terms' own reads and parameters at q_0 (= q_{k−2}).
    add_weighted_terms_adjoint(older_, gradient_older_, 1.0, frame, previous, previous_step, g_bar,
                               older, a_previous, da_previous, dgamma);
  }
  add_older_adjoint(previous, previous_step, older, a_previous, da_previous);
}

}  // namespace liedyn

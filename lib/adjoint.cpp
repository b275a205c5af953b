// The adjoint blocks of the incremental potential (incremental_potential.hpp, docs/design.md §8):
// each term's Jacobians come from the term itself (its add_step_adjoint and
// add_parameter_adjoint, term.hpp); this file gathers z onto each term's stencil.

#include "incremental_potential.hpp"

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
  // The Lie gradient field's derivative is H − ½ hat(G) per rotation block (design §1.4).
  for (const RotationHistory& t : terms<RotationHistory>()) {
    const int o = t.offsets[0];
    u.segment<3>(o) += 0.5 * w * Vector3(G.segment<3>(o)).cross(Vector3(z.segment<3>(o)));
  }
}

void IncrementalPotential::add_history_adjoint(const State& previous, const Step& previous_step,
                                               int frame, const Eigen::VectorXd& z,
                                               Eigen::VectorXd& a_previous,
                                               Eigen::VectorXd& da_previous,
                                               Eigen::VectorXd& dgamma) const {
  if (integrator_ != Integrator::kTrapezoidal) return;
  const bool first = frame <= 1;
  const std::vector<PointHistory>& points = terms<PointHistory>();
  const std::vector<RotationHistory>& rotations = terms<RotationHistory>();
  // c = ½ ∇V(q_{k−1}) + ¼ ∇V(q_{k−2}) − μ_{k−3/2}/h   (frame 1: ¼ ∇V(q_0) − π_0/h).
  Eigen::VectorXd u = Eigen::VectorXd::Zero(z.size());
  add_weighted_terms_adjoint(previous, gradient_previous_, first ? 0.25 : 0.5, frame, previous,
                             previous_step, z, u, a_previous, da_previous, dgamma);
  for (const PointHistory& t : points) {
    a_previous.segment<3>(tangent_point(t.point)) += u.segment<3>(t.offsets[0]);
  }
  for (const RotationHistory& t : rotations) {
    a_previous.segment<3>(tangent_rotation(previous, t.rotation)) += u.segment<3>(t.offsets[0]);
  }
  if (!first) {
    // q_{k−2} = (x_{k−1} − Δx_{k−1}, ΔR_{k−1}ᵀ R_{k−1}): δx_{k−2} = δx_{k−1} − δΔx and
    // δθ_{k−2} = ΔR_{k−1}ᵀ (δθ_{k−1} − δψ) (left perturbations of R_{k−1} and ΔR_{k−1}).
    u.setZero();
    add_weighted_terms_adjoint(older_, gradient_older_, 0.25, frame, previous, previous_step, z,
                               u, a_previous, da_previous, dgamma);
    for (const PointHistory& t : points) {
      const int o = tangent_point(t.point);
      a_previous.segment<3>(o) += u.segment<3>(t.offsets[0]);
      da_previous.segment<3>(o) -= u.segment<3>(t.offsets[0]);
    }
    for (const RotationHistory& t : rotations) {
      const int o = tangent_rotation(previous, t.rotation);
      const Vector3 v = previous_step.rotations[t.rotation] * u.segment<3>(t.offsets[0]);
      a_previous.segment<3>(o) += v;
      da_previous.segment<3>(o) -= v;
    }
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

}  // namespace liedyn

// The adjoint blocks of the incremental potential (incremental_potential.hpp, docs/design.md §8):
// each term's Jacobians come from the term itself (its add_step_adjoint and
// add_parameter_adjoint, term.hpp); this file gathers z onto each term's stencil.

#include "incremental_potential.hpp"

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
          t.add_step_adjoint(q, previous, previous_step, gather(t, z), a_previous, da_previous);
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
        if (has_dofs(t)) t.add_parameter_adjoint(q, frame, gather(t, z), dgamma);
      }
    }
  });
}

}  // namespace liedyn

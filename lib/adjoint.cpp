// The adjoint blocks of the incremental potential (incremental_potential.hpp, docs/design.md §8):
// each term's Jacobians come from the term itself (inertia.hpp, loads.hpp, rod_terms.hpp,
// spring.hpp); this file gathers z onto each term's stencil and scatters the products.

#include "incremental_potential.hpp"
#include "trajectory.hpp"

namespace liedyn {

namespace {

// The term's part of the component vector z (zeros where a block is not a DOF).
template <class Term>
LocalGradient<Term::kBlocks> gather(const Term& term, const Eigen::VectorXd& z) {
  LocalGradient<Term::kBlocks> local;
  for (int b = 0; b < Term::kBlocks; ++b) {
    const int o = term.offsets[b];
    local.template segment<3>(3 * b) = o < 0 ? Vector3::Zero() : Vector3(z.segment<3>(o));
  }
  return local;
}

// (∂C/∂k)ᵀ z for a term whose value is proportional to its scalar `stiffness` k: ∂C/∂k is
// its gradient at k = 1.
template <class Term>
void add_stiffness_adjoint(const Term& term, const State& q, const Eigen::VectorXd& z,
                           Eigen::VectorXd& dgamma) {
  if (term.stiffness_slot < 0) return;
  Term unit = term;
  unit.stiffness = 1.0;
  LocalGradient<Term::kBlocks> g;
  unit.evaluate(q, &g, nullptr);
  dgamma(term.stiffness_slot) += g.dot(gather(term, z));
}

}  // namespace

void IncrementalPotential::add_step_adjoint(const State& q, const State& previous,
                                            const Step& previous_step, const Eigen::VectorXd& z,
                                            Eigen::VectorXd& a_previous,
                                            Eigen::VectorXd& da_previous) const {
  for (const TranslationalInertia& t : translational_inertia) {
    if (t.offsets[0] < 0) continue;
    const Vector3 w = t.step_jacobian() * z.segment<3>(t.offsets[0]);  // symmetric: = Jᵀ z
    a_previous.segment<3>(tangent_point(t.point)) += w;
    da_previous.segment<3>(tangent_point(t.point)) += w;
  }
  for (const RotationalInertia& t : rotational_inertia) {
    if (t.offsets[0] < 0) continue;
    Matrix3 d_previous, d_step;
    t.step_jacobians(q, previous.rotations[t.rotation], previous_step.rotations[t.rotation],
                     d_previous, d_step);
    const Vector3 zt = z.segment<3>(t.offsets[0]);
    a_previous.segment<3>(tangent_rotation(q, t.rotation)) += d_previous.transpose() * zt;
    da_previous.segment<3>(tangent_rotation(q, t.rotation)) += d_step.transpose() * zt;
  }
  for (const ConstantTorque& t : torques) {
    if (t.offsets[0] < 0) continue;
    a_previous.segment<3>(tangent_rotation(q, t.rotation)) +=
        t.previous_jacobian(q).transpose() * z.segment<3>(t.offsets[0]);
  }
  for (const Friction& t : friction) {
    if (t.normal_force == 0.0) continue;
    // Columns (x̂, θ̂) of the sample's frame: its point and, on a body, its rotation. A body
    // whose rotation is not a DOF keeps its previous rotation fixed as well (none exist).
    const Eigen::Matrix<double, 6, 1> w =
        t.previous_jacobian(q, previous).transpose() * gather(t, z);
    if (t.at.point >= 0) a_previous.segment<3>(tangent_point(t.at.point)) += w.head<3>();
    if (t.at.rotation >= 0) {
      a_previous.segment<3>(tangent_rotation(q, t.at.rotation)) += w.tail<3>();
    }
  }
}

void IncrementalPotential::add_parameter_adjoint(const State& q, int frame,
                                                 const Eigen::VectorXd& z,
                                                 Eigen::VectorXd& dgamma) const {
  for (const ConstantForce& t : forces) {
    const int slot = t.control.slot_at(frame);
    if (slot >= 0) dgamma.segment<3>(slot) += t.force_jacobian(q).transpose() * gather(t, z);
  }
  for (const ConstantTorque& t : torques) {
    const int slot = t.control.slot_at(frame);
    if (slot >= 0) dgamma.segment<3>(slot) += t.torque_jacobian(q).transpose() * gather(t, z);
  }
  for (const RodBendTwist& t : rod_bend_twist) {
    const int slot = t.rest_control.slot_at(frame);
    if (slot < 0 && t.stiffness_slot < 0) continue;
    Eigen::Matrix<double, 6, 3> d_rest, d_stiffness;
    t.parameter_jacobians(q, slot >= 0 ? &d_rest : nullptr,
                          t.stiffness_slot >= 0 ? &d_stiffness : nullptr);
    const LocalGradient<2> zt = gather(t, z);
    if (slot >= 0) dgamma.segment<3>(slot) += d_rest.transpose() * zt;
    if (t.stiffness_slot >= 0) dgamma.segment<3>(t.stiffness_slot) += d_stiffness.transpose() * zt;
  }
  for (const CableSegment& t : cables) {
    const int slot = t.control.slot_at(frame);
    if (slot >= 0) dgamma(slot) += t.tension_gradient(q).dot(gather(t, z));
  }
  for (const Spring& t : springs) add_stiffness_adjoint(t, q, z, dgamma);
  for (const RodStretch& t : rod_stretch) add_stiffness_adjoint(t, q, z, dgamma);
  for (const RodShear& t : rod_shear) add_stiffness_adjoint(t, q, z, dgamma);
}

}  // namespace liedyn

#include "incremental_potential.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "rod_terms.hpp"
#include "so3.hpp"

namespace liedyn {

namespace {

// q ← q ⊖ Δq: the state before a step, from the one after it and the step (x − Δx, ΔRᵀ R).
void step_back(State& q, const Step& step) {
  for (std::size_t i = 0; i < q.points.size(); ++i) q.points[i] -= step.points[i];
  for (std::size_t j = 0; j < q.rotations.size(); ++j) {
    q.rotations[j] = step.rotations[j].transpose() * q.rotations[j];
  }
}

}  // namespace

void IncrementalPotential::begin_step(const State& previous, const Step& previous_step,
                                      int frame, const Step* step_before, int start_frame) {
  // This step continues the last one set up (the next frame of the same run): what the
  // trapezoidal history may carry over (below).
  const bool continues = frame == frame_ + 1 && start_frame == start_frame_;
  frame_ = frame;
  start_frame_ = start_frame;
  for_each_term_vector([&](auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    if constexpr (BeginsStep<T>) {
      for (T& t : terms) t.begin_step(previous, previous_step);
    }
    if constexpr (Scheduled<T>) {
      static_assert(SaysWhetherScheduled<T>, "a Scheduled term says whether it has a schedule (term.hpp)");
      for (T& t : terms) t.begin_frame(frame);
    }
  });
  if (integrator_ == Integrator::kBdf2) {
    if (step_before == nullptr) throw std::logic_error("begin_step: BDF2 needs the step before");
    begin_bdf2_step(previous, previous_step, *step_before, frame - start_frame);
    return;
  }
  const double beta = newmark_beta(integrator_);
  if (beta == 0.0) return;
  // The history terms' fields (lib/history.hpp). At frame 1 the history is the initial
  // velocities: Newmark's first step, c = (½ − β) ∇V(q_0) − π_0/h.
  const bool first = frame - start_frame <= 1;
  // ∇V(q_{k−2}) is the last step's ∇V(q_{k−1}) where this step continues it (the next frame of
  // the run, q_{k−2} its q_{k−1} to round-off) and the state terms are the same functions at
  // both steps (none fixes per-step data or follows a schedule): one gradient pass instead of two.
  older_ = previous;  // sized at the first step (which needs no q_{k−2}): no allocation after it
  if (!first) step_back(older_, previous_step);
  const bool carried =
      !first && continues && at_gradient_state(older_) && !state_terms_change_per_step();
  carried_history_gradient_ = carried;
  if (carried) gradient_older_.swap(gradient_previous_);
  state_terms_gradient(previous, gradient_previous_);
  keep_gradient_state(previous);
  if (!first && !carried) state_terms_gradient(older_, gradient_older_);
  const auto lagged = [&](int offset) -> Vector3 {
    if (first) return (0.5 - beta) * gradient_previous_.segment<3>(offset);
    return (1.0 - 2.0 * beta) * gradient_previous_.segment<3>(offset) +
           beta * gradient_older_.segment<3>(offset);
  };
  for (PointHistory& t : terms<PointHistory>()) t.field = lagged(t.offsets[0]);
  const std::vector<RotationalInertia>& inertia = terms<RotationalInertia>();
  std::vector<RotationHistory>& history = terms<RotationHistory>();
  for (std::size_t t = 0; t < history.size(); ++t) {
    const Matrix3& R = previous.rotations[history[t].rotation];
    const Matrix3& dR = previous_step.rotations[history[t].rotation];
    const Matrix3& J = inertia[t].J_over_h2;  // Ĵ = J/h²
    // The previous step's momentum over h, in gradient units: μ_{k−3/2}/h = 2 vee(R_{k−1} Ĵ
    // R_{k−2}ᵀ) with R_{k−2} = ΔRᵀ R_{k−1} (older_); at frame 1, π_0/h = R_0 (I_b/h²) R_0ᵀ
    // log(ΔR_0) with I_b/h² = tr(Ĵ) 1 − Ĵ.
    const Vector3 momentum =
        first ? Vector3(R * (J.trace() * Matrix3::Identity() - J) * R.transpose() * so3::log(dR))
              : Vector3(2.0 * so3::vee(R * J * older_.rotations[history[t].rotation].transpose()));
    history[t].field = lagged(history[t].offsets[0]) - momentum;
    history[t].reference = so3::orthonormalize(dR * R);  // the simulator's first iterate
  }
}

bool IncrementalPotential::state_terms_change_per_step() const {
  bool changes = false;
  for_each_term_vector([&](const auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    for (const T& t : terms) {
      if (!state_term(t)) continue;
      if constexpr (BeginsStep<T>) changes = true;
      if constexpr (Scheduled<T>) changes = changes || t.scheduled();
    }
  });
  return changes;
}

void IncrementalPotential::begin_bdf2_step(const State& previous, const Step& previous_step,
                                           const Step& step_before, int steps) {
  // `steps`: this step's number counted from the run's start (frame − start_frame).
  if (steps <= 2) {
    // Sized at the first step: no allocation after it (a component first built at the second
    // step, when islands change, allocates there once).
    older_ = previous;
    corrected_step_ = step_before;
  }
  const Step* before = &step_before;
  if (steps == 2) {
    // Δq_0 = (h v_0, exp(h ω_0)) makes x_{−1} = x_0 − h v_0, an O(h²) start that the two-step
    // history would carry into every later step as an O(h) error. With the initial
    // acceleration, x_{−1} = x_0 − h v_0 + ½ h² a_0 and R_{−1} = exp(−h ω_0 + ½ h² α_0) R_0 are
    // O(h³): Δx_0' = Δx_0 + ∇V(q_0)/(2m/h²), ΔR_0' = exp(φ + A⁻¹(∇V(q_0) + ½ φ × A φ)) with
    // φ = h ω_0 and A = 2 I_w/h² (docs/design.md §15). At step 1 x̃ does not depend on a_0.
    step_back(older_, previous_step);
    state_terms_gradient(older_, gradient_older_);  // q_0
    for (const TranslationalInertia& t : terms<TranslationalInertia>()) {
      corrected_step_.points[t.point] =
          step_before.points[t.point] + gradient_older_.segment<3>(t.offsets[0]) / t.mass_over_h2;
    }
    for (const RotationalInertia& t : terms<RotationalInertia>()) {
      const Matrix3& R0 = older_.rotations[t.rotation];
      const Vector3 phi = so3::log(step_before.rotations[t.rotation]);
      const Matrix3 A =
          R0 * (t.J_over_h2.trace() * Matrix3::Identity() - t.J_over_h2) * R0.transpose();
      const Vector3 g = gradient_older_.segment<3>(t.offsets[0]);
      corrected_step_.rotations[t.rotation] =
          so3::exp(phi + A.ldlt().solve(Vector3(g + 0.5 * phi.cross(A * phi))));
    }
    before = &corrected_step_;
  }
  // x̃ = (5x_{k−1} − 4x_{k−2} + x_{k−3})/2, x_{k−2} = x_{k−1} − Δx_{k−1}, x_{k−3} = x_{k−2} − Δx_{k−2};
  // R̃ likewise with R_{k−2} = ΔR_{k−1}ᵀ R_{k−1}, R_{k−3} = ΔR_{k−2}ᵀ R_{k−2} (a matrix, not a
  // rotation, as backward Euler's R̃).
  for (TranslationalInertia& t : terms<TranslationalInertia>()) {
    const Vector3& x1 = previous.points[t.point];
    const Vector3 x2 = x1 - previous_step.points[t.point];
    const Vector3 x3 = x2 - before->points[t.point];
    t.x_tilde = 0.5 * (5.0 * x1 - 4.0 * x2 + x3);
  }
  for (RotationalInertia& t : terms<RotationalInertia>()) {
    const Matrix3& R1 = previous.rotations[t.rotation];
    const Matrix3 R2 = previous_step.rotations[t.rotation].transpose() * R1;
    const Matrix3 R3 = before->rotations[t.rotation].transpose() * R2;
    t.R_tilde = 0.5 * (5.0 * R1 - 4.0 * R2 + R3);
  }
}

void IncrementalPotential::set_integrator(Integrator integrator, int dofs) {
  integrator_ = integrator;
  if (integrator == Integrator::kBdf2) {
    // (2x_k − 5x_{k−1} + 4x_{k−2} − x_{k−3})/h² = 2(x_k − x̃)/h²: twice the inertia.
    for (TranslationalInertia& t : terms<TranslationalInertia>()) t.mass_over_h2 *= 2.0;
    for (RotationalInertia& t : terms<RotationalInertia>()) {
      t.J_over_h2 *= 2.0;
      t.sqrt_J_over_h *= std::sqrt(2.0);
    }
    gradient_older_.setZero(dofs);
    return;
  }
  const double beta = newmark_beta(integrator);
  if (beta == 0.0) return;
  state_weight_ = beta;
  // History term t belongs to inertia term t of its kind (same point or rotation, same
  // offset): begin_step and the Ceres back-end pair them by index.
  gradient_previous_.setZero(dofs);
  gradient_older_.setZero(dofs);
  for (const TranslationalInertia& t : terms<TranslationalInertia>()) {
    PointHistory h;
    h.offsets = t.offsets;
    h.point = t.point;
    add(h);
  }
  for (RotationalInertia& t : terms<RotationalInertia>()) {
    t.variational = true;
    RotationHistory h;
    h.offsets = t.offsets;
    h.rotation = t.rotation;
    add(h);
  }
  gradient_state_points_.resize(terms<PointHistory>().size());
  gradient_state_rotations_.resize(terms<RotationHistory>().size());
}

void IncrementalPotential::keep_gradient_state(const State& q) {
  const std::vector<PointHistory>& points = terms<PointHistory>();
  const std::vector<RotationHistory>& rotations = terms<RotationHistory>();
  for (std::size_t i = 0; i < points.size(); ++i) gradient_state_points_[i] = q.points[points[i].point];
  for (std::size_t i = 0; i < rotations.size(); ++i) {
    gradient_state_rotations_[i] = q.rotations[rotations[i].rotation];
  }
}

bool IncrementalPotential::at_gradient_state(const State& q) const {
  // To round-off: q_{k−2} = step_back(q_{k−1}, Δq_{k−1}) recovers the last step's q_{k−1} to a
  // few ulps; a state that differs by more (another trajectory: the adjoint's components set up
  // frame by frame backwards, an optimiser's next run) is not it.
  constexpr double kRoundoff = 1e-13;
  const std::vector<PointHistory>& points = terms<PointHistory>();
  const std::vector<RotationHistory>& rotations = terms<RotationHistory>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vector3& x = gradient_state_points_[i];
    if (!((q.points[points[i].point] - x).lpNorm<Eigen::Infinity>() <=
          kRoundoff * (1.0 + x.lpNorm<Eigen::Infinity>()))) {
      return false;
    }
  }
  for (std::size_t i = 0; i < rotations.size(); ++i) {
    if (!((q.rotations[rotations[i].rotation] - gradient_state_rotations_[i]).lpNorm<Eigen::Infinity>() <=
          kRoundoff)) {
      return false;
    }
  }
  return true;
}

void IncrementalPotential::rereference_history(const State& q) {
  for (RotationHistory& t : terms<RotationHistory>()) t.rereference(q);
}

double IncrementalPotential::history_reference_distance(const State& q) const {
  double chord = 0.0;  // the angle grows with the chord: one conversion for the largest
  for (const RotationHistory& t : terms<RotationHistory>()) chord = std::max(chord, t.reference_chord(q));
  return RotationHistory::chord_angle(chord);
}

void IncrementalPotential::state_terms_gradient(const State& q, Eigen::VectorXd& g) const {
  g.setZero();
  for_each_term_vector([&](const auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    if constexpr (!EndOfStep<T>) {
      LocalGradient<T::kBlocks> g_local;
      for (const T& t : terms) {
        if (!state_term(t)) continue;  // an exact constraint
        t.evaluate(q, &g_local, nullptr);
        static_for<T::kBlocks>([&](auto i) {
          if (t.offsets[i] < 0) return;
          g.template segment<3>(t.offsets[i]) += g_local.template segment<3>(3 * i);
        });
      }
    }
  });
}

void IncrementalPotential::set_load_scale(double lambda) {
  for_each_term_vector([&](auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    if constexpr (LoadScaled<T>) {
      for (T& t : terms) t.scale = lambda;
    }
  });
}

double IncrementalPotential::value(const State& q) const {
  double value = 0.0;
  for_each_term_vector([&](const auto& terms) {
    for (const auto& term : terms) value += weight(term) * term.evaluate(q, nullptr, nullptr);
  });
  return value;
}

double IncrementalPotential::potential_energy(const State& q) const {
  double energy = 0.0;
  for_each_term_vector([&](const auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    if constexpr (EnergyOfState<T>) {
      for (const T& t : terms) {
        if constexpr (Constraint<T>) {
          if (t.exact) continue;
        }
        energy += t.evaluate(q, nullptr, nullptr);
      }
    }
  });
  return energy;
}

int IncrementalPotential::exact_constraints() const {
  int count = 0;
  exact_constraints_of<false>(*this, [&](const auto&) { ++count; });
  return count;
}

double IncrementalPotential::constraint_violation(const State& q) const {
  double violation = 0.0;
  exact_constraints_of<false>(*this, [&](const auto& t) {
    violation = std::max(violation, t.violation(q));
  });
  return violation;
}

double IncrementalPotential::max_penetration(const State& q) const {
  double deepest = 0.0;
  for_each_term_vector([&](const auto& terms) {
    for (const auto& t : terms) {
      if constexpr (requires { t.penetration(q); }) deepest = std::max(deepest, t.penetration(q));
    }
  });
  return deepest;
}

void IncrementalPotential::update_multipliers(const State& q) {
  exact_constraints_of<false>(*this, [&](auto& t) { t.update_multiplier(q); });
}

void IncrementalPotential::scale_penalties(double factor) {
  exact_constraints_of<false>(*this, [&](auto& t) { t.stiffness *= factor; });
}

void IncrementalPotential::exact_forces(const State& q, std::vector<Vector3>& out) const {
  exact_constraints_of<false>(*this, [&](const auto& t) {
    out.push_back(t.adjoint ? t.multiplier : t.force(q));
  });
}

void IncrementalPotential::set_adjoint_multipliers(const Vector3* multipliers) {
  exact_constraints_of<false>(*this, [&](auto& t) {
    t.adjoint = true;
    t.multiplier = *multipliers++;
  });
}

int IncrementalPotential::exact_equalities() const {
  int count = 0;
  for_each_exact_equality([&](const auto&) { ++count; });
  return count;
}

void IncrementalPotential::constraint_jacobian(const State& q, Eigen::MatrixXd& J) const {
  J.setZero();
  int row = 0;
  exact_constraints_of<false>(*this, [&](const auto& t) {
    using T = std::decay_t<decltype(t)>;
    typename T::ConstraintJacobian local;
    t.constraint(q, &local);
    for (int b = 0; b < T::kBlocks; ++b) {
      if (t.offsets[b] >= 0) J.block(row, t.offsets[b], 3, 3) += local.template block<3, 3>(0, 3 * b);
    }
    row += 3;
  });
}

namespace {

// One shared copy of each collider, for the contact and friction terms of all components.
std::vector<std::shared_ptr<const Collider>> shared_colliders(const Model& model) {
  std::vector<std::shared_ptr<const Collider>> out;
  for (const Collider& c : model.colliders) out.push_back(std::make_shared<const Collider>(c));
  return out;
}

// Whether a material's samples rub: μ > 0, and a dynamic model (static equilibria have no step
// to slip over: friction is a dynamic term).
bool rubs(const Model& model, const ContactMaterial& material) {
  return material.friction > 0.0 && !model.static_equilibrium;
}

// The slip over a step at which a material's friction saturates: ε = ε_v h (friction.hpp).
double slip_zone(const Model& model, const ContactMaterial& material) {
  return material.friction_velocity * model.time_step;
}

// Whether a material's samples are damped: c > 0, and a dynamic model (as friction).
bool damps(const Model& model, const ContactMaterial& material) {
  return material.damping > 0.0 && !model.static_equilibrium;
}

// A material's dashpot: τ = c/k (dissipation_law.hpp; none without damping).
NormalDashpot dashpot(const Model& model, const ContactMaterial& material) {
  return {damps(model, material) ? material.damping / material.stiffness : 0.0, model.time_step};
}

// A sample's penalty term (against a collider: Contact; against a body: BodyContact), its
// friction term where its material rubs and its damping term where it is damped (the dashpot's
// τ = c/k: dissipation_law.hpp).
template <class Penalty, class FrictionTerm, class DampingTerm, class Sample>
void add_sample_terms(const Model& model, const Sample& sample, const ContactMaterial& material,
                      IncrementalPotential& potential) {
  potential.add(Penalty{sample});
  if (rubs(model, material)) {
    FrictionTerm friction;
    static_cast<Sample&>(friction) = sample;
    friction.coefficient = material.friction;
    friction.epsilon = slip_zone(model, material);
    potential.add(friction);
  }
  if (damps(model, material)) {
    DampingTerm damping;
    static_cast<Sample&>(damping) = sample;
    static_cast<NormalDashpot&>(damping) = dashpot(model, material);
    potential.add(damping);
  }
}

// A sample's terms with each collider it touches (ContactMaterial::touches).
void add_contact_terms(const Model& model,
                       const std::vector<std::shared_ptr<const Collider>>& colliders,
                       const ContactMaterial& material, const AttachedPoint& at,
                       const std::array<int, 2>& offsets, IncrementalPotential& p) {
  if (!material.enabled()) return;
  for (const auto& collider : colliders) {
    if (!material.touches(collider->name)) continue;
    const ContactSample sample{offsets, at, collider, material.stiffness, material.radius};
    add_sample_terms<Contact, Friction, ContactDamping>(model, sample, material, p);
  }
}

// The contact candidates of a model (Model::body_pairs, edge_pairs, rod_body_pairs), listed
// once per build, and where each kind's entries start in a coupling key.
struct ContactCandidates {
  std::vector<std::pair<int, int>> bodies;
  std::vector<EdgePair> edges;
  std::vector<std::pair<int, int>> rods_on_bodies;
  std::size_t first_body, first_edge, first_rod_on_body;
  explicit ContactCandidates(const Model& model)
      : bodies(model.body_pairs()),
        edges(model.edge_pairs()),
        rods_on_bodies(model.rod_body_pairs()),
        first_body(model.joints.size()),
        first_edge(first_body + bodies.size()),
        first_rod_on_body(first_edge + edges.size()) {}
};

// Whether candidate p of the kind whose entries start at `first` holds under `key` (a key
// without contact entries holds none).
bool holds(const std::vector<bool>& key, std::size_t first, std::size_t p) {
  return first + p < key.size() && key[first + p];
}

// Every sample of A against B's shape and of B against A's, for each pair of bodies that
// touches under `key` (Model::coupling_key), with its friction where A's μ > 0; A's and B's
// blocks are in one component (a kinematic body's are no DOF).
void add_body_contact_terms(const Model& model, const std::vector<bool>& key, const ContactCandidates& candidates,
                            const std::vector<int>& point_offset, const std::vector<int>& rotation_offset,
                            const std::vector<int>& component_of, std::vector<Component>& components) {
  const std::vector<std::pair<int, int>>& pairs = candidates.bodies;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    if (!holds(key, candidates.first_body, p)) continue;
    for (const auto& [a, b] : {pairs[p], std::pair{pairs[p].second, pairs[p].first}}) {
      const RigidBody& sampled = model.bodies[a];
      const RigidBody& solid = model.bodies[b];
      if (!sampled.contact.enabled() || solid.shape == nullptr) continue;
      for (const Vector3& point : sampled.contact_points) {
        add_sample_terms<BodyContact, BodyFriction, BodyDamping>(
            model,
            BodySample{{point_offset[a], rotation_offset[a], point_offset[b], rotation_offset[b]},
                       {a, a, point},
                       b,
                       solid.shape,
                       sampled.contact.stiffness,
                       sampled.contact.radius},
            sampled.contact, components[component_of[a] >= 0 ? component_of[a] : component_of[b]].potential);
      }
    }
  }
}

// A body point as an attached point: x + R p̄ of the body, or a world anchor (body −1).
AttachedPoint attach(const BodyPoint& bp) { return {bp.body, bp.body, bp.point}; }

// Appends `from` to `into`: its DOF blocks after into's, every term's offsets shifted by
// into.dofs (generic over the term list: each term has its `offsets`).
void append_component(Component& into, Component from) {
  const int base = into.dofs;
  for (DofBlock b : from.points) into.points.push_back({b.index, b.offset + base});
  for (DofBlock b : from.rotations) into.rotations.push_back({b.index, b.offset + base});
  from.potential.for_each_term_vector([&](auto& terms) {
    for (auto& term : terms) {
      for (int& o : term.offsets) {
        if (o >= 0) o += base;
      }
      into.potential.add(std::move(term));
    }
  });
  into.dofs += from.dofs;
}

// The initial penalty ρ of an exact joint part: kExactPenalty times the inertia it holds,
// m/h² (translation) or λ_max(J)/h² (rotation) of its ends together, so that each
// multiplier update of the augmented Lagrangian divides the violation by about
// 1 + ρ/(m/h²) ≈ 10⁴ where inertia dominates, while H stays within 10⁴ of its inertia's
// conditioning. Where other stiffnesses dominate, StepSolver::solve raises ρ.
constexpr double kExactPenalty = 1e4;

// Where each point and rotation of the state is once every body and rod has its place, as
// (component, offset); {−1, −1} if it is not a DOF.
struct DofMap {
  std::vector<std::array<int, 2>> points, rotations;
  DofMap(const Model& model, const std::vector<Component>& components)
      : points(model.point_count(), {-1, -1}),
        rotations(model.rod_rotation(static_cast<int>(model.rods.size()), 0), {-1, -1}) {
    for (int c = 0; c < static_cast<int>(components.size()); ++c) {
      for (const DofBlock& b : components[c].points) points[b.index] = {c, b.offset};
      for (const DofBlock& b : components[c].rotations) rotations[b.index] = {c, b.offset};
    }
  }
};

// The joints' terms (JointSpec), added to the component of the ends.
void add_joint_terms(const Model& model, const std::vector<bool>& key, const DofMap& dofs,
                     std::vector<Component>& components) {
  if (model.joints.empty()) return;
  const std::vector<std::array<int, 2>>& point_dof = dofs.points;
  const std::vector<std::array<int, 2>>& rotation_dof = dofs.rotations;
  // The rods' lumped masses and edge inertias, discretised once for all joints to them.
  std::vector<std::optional<RodDiscretization>> rods(model.rods.size());
  const auto rod = [&](int r) -> const RodDiscretization& {
    if (!rods[r]) rods[r] = discretize(model.rods[r]);
    return *rods[r];
  };
  // An end's mass (what its point moves) and largest rotational inertia, 0 for the world.
  const auto end_mass = [&](const JointEnd& e) {
    switch (e.kind) {
      case JointEnd::Kind::kBody: return model.bodies[e.object].kinematic ? 0.0 : model.bodies[e.object].mass;
      case JointEnd::Kind::kRodNode:
      case JointEnd::Kind::kRodEdge: return rod(e.object).node_mass[e.element];
      default: return 0.0;
    }
  };
  const auto end_inertia = [&](const JointEnd& e) {
    switch (e.kind) {
      case JointEnd::Kind::kBody:
        return model.bodies[e.object].kinematic ? 0.0
                                                : rotational_mass(model.bodies[e.object].inertia).diagonal().maxCoeff();
      case JointEnd::Kind::kRodEdge: return rotational_mass(rod(e.object).edge_inertia[e.element]).diagonal().maxCoeff();
      default: return 0.0;
    }
  };
  const double inv_h2 = 1.0 / (model.time_step * model.time_step);
  // k = 1/compliance, or the initial penalty for compliance 0 (exact).
  const auto set_stiffness = [&](auto& term, double compliance, double inertia) {
    term.exact = compliance == 0.0;
    term.stiffness = term.exact ? kExactPenalty * inertia * inv_h2 : 1.0 / compliance;
  };
  for (std::size_t index = 0; index < model.joints.size(); ++index) {
    if (!key[index]) continue;
    const JointSpec& j = model.joints[index];
    const AttachedPoint pa = model.attached_point(j.a), pb = model.attached_point(j.b);
    // (point, rotation) offsets of each end, and the component of the first DOF among them
    // (Model::validate: one end moves).
    const auto offsets = [&](const AttachedPoint& at) -> std::array<int, 2> {
      return {at.point < 0 ? -1 : point_dof[at.point][1], at.rotation < 0 ? -1 : rotation_dof[at.rotation][1]};
    };
    const std::array<int, 2> oa = offsets(pa), ob = offsets(pb);
    int component = -1;
    for (const auto& [index, dof] : {std::pair{pa.point, &point_dof}, std::pair{pa.rotation, &rotation_dof},
                                     std::pair{pb.point, &point_dof}, std::pair{pb.rotation, &rotation_dof}}) {
      if (component < 0 && index >= 0) component = (*dof)[index][0];
    }
    IncrementalPotential& p = components[component].potential;
    // The rotation blocks (θ_a, θ_b) of the hinge, weld and motor terms.
    const auto rotation_ends = [&](auto& term) {
      term.offsets = {oa[1], ob[1]};
      term.rotation_a = pa.rotation;
      term.rotation_b = pb.rotation;  // −1: the world
    };
    const std::array<int, 4> translation_offsets{oa[0], oa[1], ob[0], ob[1]};
    const double mass = end_mass(j.a) + end_mass(j.b);
    if (j.type == JointSpec::Type::kSlider) {  // the line through p_a along R_a â
      JointLine line;
      line.offsets = translation_offsets;
      line.a = pa;
      line.b = pb;
      line.axis_a = j.axis_a;
      set_stiffness(line, j.compliance, mass);
      p.add(line);
      if (j.has_motor) {
        JointForceMotor motor;
        motor.offsets = translation_offsets;
        motor.a = pa;
        motor.b = pb;
        motor.axis_a = j.axis_a;
        motor.force = j.motor_effort;
        motor.control = j.motor;
        motor.R_previous_a = model.initial_rotation(j.a);
        p.add(motor);
      }
    } else {
      JointPoint translation;
      translation.offsets = translation_offsets;
      translation.a = pa;
      translation.b = pb;
      set_stiffness(translation, j.compliance, mass);
      p.add(translation);
    }
    const double inertia = end_inertia(j.a) + end_inertia(j.b);
    if (j.type == JointSpec::Type::kHinge) {
      JointAlignment hinge;
      rotation_ends(hinge);
      hinge.axis_a = j.axis_a;
      hinge.axis_b = j.axis_b;
      set_stiffness(hinge, j.compliance_rotation, inertia);
      p.add(hinge);
      if (j.has_motor) {
        JointMotor motor;
        rotation_ends(motor);
        motor.axis_a = j.axis_a;
        motor.torque = j.motor_effort;
        motor.control = j.motor;
        motor.R_previous_a = model.initial_rotation(j.a);
        motor.R_previous_b = model.initial_rotation(j.b);
        p.add(motor);
      }
    } else if (j.type == JointSpec::Type::kWeld || j.type == JointSpec::Type::kSlider) {
      JointWeld weld;
      rotation_ends(weld);
      weld.frame_a = j.frame_a;
      weld.frame_b = j.frame_b;
      set_stiffness(weld, j.compliance_rotation, inertia);
      p.add(weld);
    }
    if (j.type == JointSpec::Type::kSplice) {
      // The bending and twist across the junction, as at a rod's interior node between its
      // edges i−1 and i (add_rod_terms): a's last edge and b's first, over their Voronoi
      // length, with the two rods' mean stiffness and the junction's initial curvature at rest.
      // One rod would carry a's last frame across the junction by parallel transport; b's
      // own first frame is its own transport from the z axis, and differs from that by a
      // twist T about b's first edge wherever the rods meet at an angle: the term sees b's
      // frame times T (RodBendTwist::frame_offset).
      const int ra = j.a.object, rb = j.b.object;
      const int edge_a = model.rods[ra].edge_count() - 1;
      const RodDiscretization& da = rod(ra);
      const RodDiscretization& db = rod(rb);
      const std::vector<Vector3>& na = model.rods[ra].nodes;
      const std::vector<Vector3>& nb = model.rods[rb].nodes;
      const Matrix3 carried = so3::orthonormalize(
          minimal_rotation((na[edge_a + 1] - na[edge_a]).normalized(), (nb[1] - nb[0]).normalized()) *
          da.frames[edge_a]);
      RodBendTwist bend;
      bend.edge0 = model.rod_rotation(ra, edge_a);
      bend.edge1 = model.rod_rotation(rb, 0);
      bend.offsets = {rotation_dof[bend.edge0][1], rotation_dof[bend.edge1][1]};
      bend.rest_length = 0.5 * (da.rest_length[edge_a] + db.rest_length[0]);
      bend.stiffness = 0.5 * (model.rods[ra].bending_stiffness + model.rods[rb].bending_stiffness);
      bend.frame_offset = so3::orthonormalize(db.frames[0].transpose() * carried);
      bend.has_frame_offset = so3::distance(bend.frame_offset, Matrix3::Identity()) > 0.0;
      bend.rest_darboux = darboux_vector(da.frames[edge_a], carried, bend.rest_length);
      p.add(bend);
      // Its damping (rod_damping.hpp), as at an interior node: the two rods' mean η.
      const Vector3 eta = 0.5 * (model.rods[ra].bending_damping + model.rods[rb].bending_damping);
      if (!model.static_equilibrium && eta != Vector3::Zero()) {
        RodBendTwistDamping damping;
        damping.offsets = bend.offsets;
        damping.damping = eta;
        damping.time_step = model.time_step;
        damping.set(bend.edge0, bend.edge1, bend.rest_length);
        damping.form.has_frame_offset = bend.has_frame_offset;
        damping.form.frame_offset = bend.frame_offset;
        p.add(damping);
      }
    }
    if (j.has_limits) {  // one term per bound (joint_limits.hpp), as exact or elastic as the joint
      const auto add_bounds = [&](auto limit, double compliance, double inertia_of_ends) {
        set_stiffness(limit, compliance, inertia_of_ends);
        for (const auto& [bound, side] : {std::pair{j.lower_limit, -1.0}, std::pair{j.upper_limit, 1.0}}) {
          limit.bound = bound;
          limit.side = side;
          p.add(limit);
        }
      };
      const Matrix3 Ra0 = model.initial_rotation(j.a);
      if (j.type == JointSpec::Type::kHinge) {
        JointLimit<HingeAngle> limit;
        limit.offsets = {oa[1], ob[1]};
        HingeAngle& angle = limit.coordinate;
        angle.rotation_a = pa.rotation;
        angle.rotation_b = pb.rotation;
        angle.axis_a = j.axis_a;
        // û: the unit vector ⟂ â nearest the coordinate axis least aligned with â.
        Eigen::Index least = 0;
        j.axis_a.cwiseAbs().minCoeff(&least);
        angle.reference_a = j.axis_a.cross(Vector3::Unit(least)).cross(j.axis_a).normalized();
        angle.reference_b = model.initial_rotation(j.b).transpose() * Ra0 * angle.reference_a;
        add_bounds(limit, j.compliance_rotation, inertia);
      } else {
        JointLimit<SliderPosition> limit;
        limit.offsets = translation_offsets;
        SliderPosition& position = limit.coordinate;
        position.a = pa;
        position.b = pb;
        position.axis_a = j.axis_a;
        position.origin = (Ra0 * j.axis_a).dot(model.initial_position(j.a) - model.initial_position(j.b));
        add_bounds(limit, j.compliance, mass);
      }
    }
  }
}

// Union–find: the representative of object i.
int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Contact between the rod edges that touch under `key` (the entries after the body pairs),
// in the component of their nodes. The stiffness per unit length is each rod's contact k over
// its edge's rest length (so a rod lying along another presses with about k per node, as on
// a collider), the two edges' averaged. Friction where either rod's μ > 0, each edge's samples
// with their own rod's μ and ε_v (edge_contact.hpp).
void add_edge_contact_terms(const Model& model, const std::vector<bool>& key, const ContactCandidates& candidates,
                            const DofMap& dofs, std::vector<Component>& components) {
  const std::vector<EdgePair>& pairs = candidates.edges;
  std::vector<std::optional<RodDiscretization>> rods(model.rods.size());
  const auto rest_length = [&](int r, int e) {
    if (!rods[r]) rods[r] = discretize(model.rods[r]);
    return rods[r]->rest_length[e];
  };
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    if (!holds(key, candidates.first_edge, p)) continue;
    const EdgePair& e = pairs[p];
    EdgeContact term;
    term.nodes = {model.rod_point(e.rod_a, e.edge_a), model.rod_point(e.rod_a, e.edge_a + 1),
                  model.rod_point(e.rod_b, e.edge_b), model.rod_point(e.rod_b, e.edge_b + 1)};
    int component = -1;
    for (int b = 0; b < 4; ++b) {
      term.offsets[b] = dofs.points[term.nodes[b]][1];
      if (component < 0) component = dofs.points[term.nodes[b]][0];
    }
    const RodSpec& a = model.rods[e.rod_a];
    const RodSpec& b = model.rods[e.rod_b];
    term.rest_length_a = rest_length(e.rod_a, e.edge_a);
    term.rest_length_b = rest_length(e.rod_b, e.edge_b);
    term.radius_a = a.contact.radius;
    term.radius_b = b.contact.radius;
    term.stiffness = 0.5 * (a.contact.stiffness / term.rest_length_a + b.contact.stiffness / term.rest_length_b);
    IncrementalPotential& potential = components[component].potential;  // Model::edge_pairs: some node is free
    potential.add(term);
    if (rubs(model, a.contact) || rubs(model, b.contact)) {
      EdgeFriction friction{term};
      friction.law = {SlipFriction{a.contact.friction, slip_zone(model, a.contact)},
                      SlipFriction{b.contact.friction, slip_zone(model, b.contact)}};
      potential.add(friction);
    }
    if (damps(model, a.contact) || damps(model, b.contact)) {
      EdgeDamping damping{term};
      damping.law = {dashpot(model, a.contact), dashpot(model, b.contact)};
      potential.add(damping);
    }
  }
}

// A rod against a body's shape (body_contact.hpp), for each (rod, body) pair that touches under
// `key` (the entries after the edge pairs): every edge with a free node by its Gauss points
// (EdgeBodyContact, stiffness per unit length k over the edge's rest length, so that an edge
// lying on the body presses with k as a node did), and the free END nodes by a node sample (a
// sample without a rotation: BodyContact's θ_A block is no DOF), the hemispherical tips that
// the Gauss points never reach; rod and body are then in one component.
void add_rod_body_contact_terms(const Model& model, const std::vector<bool>& key, const ContactCandidates& candidates,
                                const DofMap& dofs, std::vector<Component>& components) {
  const std::vector<std::pair<int, int>>& pairs = candidates.rods_on_bodies;
  std::vector<std::optional<RodDiscretization>> rods(model.rods.size());
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    if (!holds(key, candidates.first_rod_on_body, p)) continue;
    const int r = pairs[p].first, b = pairs[p].second;  // not a structured binding: offset captures r
    const RodSpec& rod = model.rods[r];
    if (!rods[r]) rods[r] = discretize(rod);
    const std::array<int, 2> body = dofs.points[b];
    const int body_rotation = dofs.rotations[b][1];
    const auto offset = [&](int node) { return dofs.points[model.rod_point(r, node)][1]; };  // −1: clamped
    // The body's component, or for a kinematic body (no DOF) the rod's (Model::rod_body_pairs:
    // it has a free node).
    int component = body[0];
    for (int i = 0; component < 0 && i < rod.node_count(); ++i) component = dofs.points[model.rod_point(r, i)][0];
    IncrementalPotential& potential = components[component].potential;
    for (int e = 0; e < rod.edge_count(); ++e) {
      if (offset(e) < 0 && offset(e + 1) < 0) continue;
      const double rest_length = rods[r]->rest_length[e];
      add_sample_terms<EdgeBodyContact, EdgeBodyFriction, EdgeBodyDamping>(
          model,
          EdgeBodySample{{offset(e), offset(e + 1), body[1], body_rotation},
                         {model.rod_point(r, e), model.rod_point(r, e + 1)},
                         b,
                         model.bodies[b].shape,
                         rod.contact.stiffness / rest_length,
                         rod.contact.radius,
                         rest_length},
          rod.contact, potential);
    }
    for (int i : {0, rod.node_count() - 1}) {
      if (offset(i) < 0) continue;
      add_sample_terms<BodyContact, BodyFriction, BodyDamping>(
          model,
          BodySample{{offset(i), -1, body[1], body_rotation}, {model.rod_point(r, i), -1, Vector3::Zero()}, b,
                     model.bodies[b].shape, rod.contact.stiffness, rod.contact.radius},
          rod.contact, potential);
    }
  }
}

}  // namespace

std::vector<Component> build_components(const Model& model, int frame) {
  std::vector<bool> key;
  model.coupling_key(frame, {}, key);
  return build_components(model, key);
}

std::vector<Component> build_components(const Model& model, const std::vector<bool>& key) {
  // Union–find over objects: bodies 0 … n − 1, then rod r as n + r.
  const int n = static_cast<int>(model.bodies.size());
  const int objects = n + static_cast<int>(model.rods.size());
  std::vector<int> parent(objects);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [a, b] : model.couplings(&key)) {
    if (a >= 0 && b >= 0) parent[find_root(parent, a)] = find_root(parent, b);
  }

  std::vector<Component> components;
  std::vector<int> component_of(n, -1);
  std::vector<int> point_offset(n, -1), rotation_offset(n, -1);
  std::vector<int> component_of_root(objects, -1);
  for (int i = 0; i < n; ++i) {
    if (model.bodies[i].kinematic) continue;  // no DOF (lib/kinematic.hpp)
    const int root = find_root(parent, i);
    if (component_of_root[root] < 0) {
      component_of_root[root] = static_cast<int>(components.size());
      components.emplace_back();
    }
    Component& c = components[component_of_root[root]];
    component_of[i] = component_of_root[root];
    point_offset[i] = c.dofs;
    rotation_offset[i] = c.dofs + 3;
    c.points.push_back({i, point_offset[i]});
    c.rotations.push_back({i, rotation_offset[i]});
    c.dofs += 6;
  }

  const double inv_h2 = 1.0 / (model.time_step * model.time_step);
  for (int i = 0; i < n; ++i) {
    const RigidBody& body = model.bodies[i];
    if (body.kinematic) continue;  // no inertia, no load
    IncrementalPotential& p = components[component_of[i]].potential;
    if (!model.static_equilibrium) {
      TranslationalInertia ti;
      ti.offsets = {point_offset[i]};
      ti.point = i;
      ti.mass_over_h2 = body.mass * inv_h2;
      p.add(ti);
      RotationalInertia ri;
      ri.offsets = {rotation_offset[i]};
      ri.rotation = i;
      ri.J_over_h2 = rotational_mass(body.inertia) * inv_h2;
      ri.sqrt_J_over_h = psd_sqrt(ri.J_over_h2);  // J^½/h, for the residual form
      p.add(ri);
    }
    if (!model.gravity.isZero(0.0)) {
      Gravity g;
      g.offsets = {point_offset[i]};
      g.point = i;
      g.weight = body.mass * model.gravity;
      p.add(g);
    }
  }

  auto offsets_of = [&](const BodyPoint& bp) -> std::array<int, 2> {
    if (bp.body < 0) return {-1, -1};
    return {point_offset[bp.body], rotation_offset[bp.body]};
  };

  for (const ForceSpec& f : model.forces) {
    ConstantForce term;
    term.offsets = offsets_of(f.at);
    term.at = attach(f.at);
    term.force = f.force;
    term.control = f.control;
    components[component_of[f.at.body]].potential.add(term);
  }
  for (const TorqueSpec& t : model.torques) {
    ConstantTorque term;
    term.offsets = {rotation_offset[t.body]};
    term.rotation = t.body;
    term.torque = t.torque;
    term.control = t.control;
    components[component_of[t.body]].potential.add(term);
  }
  for (const SpringSpec& s : model.springs) {
    Spring term;
    const auto oa = offsets_of(s.a), ob = offsets_of(s.b);
    term.offsets = {oa[0], oa[1], ob[0], ob[1]};
    term.a = attach(s.a);
    term.b = attach(s.b);
    term.stiffness = s.stiffness;
    term.rest_length = s.rest_length;
    term.stiffness_slot = s.stiffness_slot;
    // The component of the end that moves (Model::validate: one does).
    const int body = s.a.body >= 0 && component_of[s.a.body] >= 0 ? s.a.body : s.b.body;
    components[component_of[body]].potential.add(term);
  }
  const std::vector<std::shared_ptr<const Collider>> colliders = shared_colliders(model);
  for (int i = 0; i < n; ++i) {
    const RigidBody& body = model.bodies[i];
    if (body.kinematic) continue;  // a static collider and a kinematic body move nothing
    for (const Vector3& sample : body.contact_points) {
      add_contact_terms(model, colliders, body.contact, {i, i, sample},
                        {point_offset[i], rotation_offset[i]},
                        components[component_of[i]].potential);
    }
  }
  // Rods: a component of their own, or appended to the component of what they are joined to.
  for (int r = 0; r < static_cast<int>(model.rods.size()); ++r) {
    Component c = build_rod_component(model, r);
    int& into = component_of_root[find_root(parent, n + r)];
    if (into >= 0) {
      append_component(components[into], std::move(c));
    } else if (c.dofs > 0) {
      into = static_cast<int>(components.size());
      components.push_back(std::move(c));
    }
  }
  // Every body and rod has its place: the terms between objects.
  const DofMap dofs(model, components);
  const ContactCandidates candidates(model);
  add_joint_terms(model, key, dofs, components);
  add_body_contact_terms(model, key, candidates, point_offset, rotation_offset, component_of, components);
  add_edge_contact_terms(model, key, candidates, dofs, components);
  add_rod_body_contact_terms(model, key, candidates, dofs, components);
  if (!model.static_equilibrium) {
    for (Component& c : components) c.potential.set_integrator(model.integrator, c.dofs);
  }
  return components;
}

Component build_rod_component(const Model& model, int r) {
  const RodSpec& rod = model.rods[r];
  const RodDiscretization d = model.discretize_rod(r);
  const int n = rod.node_count();
  const int edges = rod.edge_count();
  Component c;
  // Tangent layout: node 0, edge 0, node 1, edge 1, … (clamped ones are not DOFs).
  std::vector<int> node_offset(n, -1), edge_offset(edges, -1);
  std::vector<bool> node_fixed(n, false), edge_fixed(edges, false);
  for (int i : rod.fixed_nodes) node_fixed[i] = true;
  for (int j : rod.fixed_edges) edge_fixed[j] = true;
  for (int i = 0; i < n; ++i) {
    if (!node_fixed[i]) {
      node_offset[i] = c.dofs;
      c.points.push_back({model.rod_point(r, i), c.dofs});
      c.dofs += 3;
    }
    if (i < edges && !edge_fixed[i]) {
      edge_offset[i] = c.dofs;
      c.rotations.push_back({model.rod_rotation(r, i), c.dofs});
      c.dofs += 3;
    }
  }

  const double inv_h2 = 1.0 / (model.time_step * model.time_step);
  IncrementalPotential& p = c.potential;
  for (int i = 0; i < n; ++i) {
    if (node_fixed[i]) continue;  // a clamped node feels neither inertia nor loads
    if (!model.static_equilibrium) {
      TranslationalInertia ti;
      ti.offsets = {node_offset[i]};
      ti.point = model.rod_point(r, i);
      ti.mass_over_h2 = d.node_mass[i] * inv_h2;
      p.add(ti);
    }
    if (!model.gravity.isZero(0.0)) {
      Gravity g;
      g.offsets = {node_offset[i]};
      g.point = model.rod_point(r, i);
      g.weight = d.node_mass[i] * model.gravity;
      p.add(g);
    }
  }
  for (int j = 0; j < edges; ++j) {
    if (!edge_fixed[j] && !model.static_equilibrium) {
      RotationalInertia ri;
      ri.offsets = {edge_offset[j]};
      ri.rotation = model.rod_rotation(r, j);
      ri.J_over_h2 = rotational_mass(d.edge_inertia[j]) * inv_h2;
      ri.sqrt_J_over_h = psd_sqrt(ri.J_over_h2);  // J^½/h (nearly singular for a thin rod: fine)
      p.add(ri);
    }
    RodStretch stretch;
    stretch.offsets = {node_offset[j], node_offset[j + 1]};
    stretch.node0 = model.rod_point(r, j);
    stretch.node1 = model.rod_point(r, j + 1);
    stretch.rest_length = d.rest_length[j];
    stretch.stiffness = rod.stretch_stiffness;
    stretch.stiffness_slot = rod.stretch_stiffness_slot;
    p.add(stretch);
    RodShear shear;
    shear.offsets = {node_offset[j], node_offset[j + 1], edge_offset[j]};
    shear.node0 = stretch.node0;
    shear.node1 = stretch.node1;
    shear.edge = model.rod_rotation(r, j);
    shear.rest_length = d.rest_length[j];
    shear.stiffness = rod.shear_stiffness;
    shear.stiffness_slot = rod.shear_stiffness_slot;
    p.add(shear);
  }
  for (int i = 1; i + 1 < n; ++i) {
    RodBendTwist bend;
    bend.offsets = {edge_offset[i - 1], edge_offset[i]};
    bend.edge0 = model.rod_rotation(r, i - 1);
    bend.edge1 = model.rod_rotation(r, i);
    bend.rest_length = d.bending_length[i - 1];
    bend.stiffness = rod.bending_stiffness;
    bend.rest_darboux = d.rest_darboux[i - 1];
    if (!rod.rest_darboux_controls.empty()) bend.rest_control = rod.rest_darboux_controls[i - 1];
    bend.stiffness_slot = rod.bending_stiffness_slot;
    p.add(bend);
  }
  // Internal damping (rod_damping.hpp): dynamic terms, like friction. Where both ends of an
  // edge or both edges of a node are clamped, the term would have no DOF: none is added.
  if (!model.static_equilibrium) {
    for (int j = 0; j < edges && rod.stretch_damping > 0.0; ++j) {
      if (node_offset[j] < 0 && node_offset[j + 1] < 0) continue;
      RodStretchDamping damping;
      damping.offsets = {node_offset[j], node_offset[j + 1]};
      damping.node0 = model.rod_point(r, j);
      damping.node1 = model.rod_point(r, j + 1);
      damping.rest_length = d.rest_length[j];
      damping.damping = rod.stretch_damping;
      damping.time_step = model.time_step;
      p.add(damping);
    }
    for (int j = 0; j < edges && rod.shear_damping > 0.0; ++j) {
      if (node_offset[j] < 0 && node_offset[j + 1] < 0 && edge_offset[j] < 0) continue;
      RodShearDamping damping;
      damping.offsets = {node_offset[j], node_offset[j + 1], edge_offset[j]};
      damping.damping = rod.shear_damping;
      damping.time_step = model.time_step;
      damping.set(model.rod_point(r, j), model.rod_point(r, j + 1), model.rod_rotation(r, j),
                  d.rest_length[j]);
      p.add(damping);
    }
    for (int i = 1; i + 1 < n && rod.bending_damping != Vector3::Zero(); ++i) {
      if (edge_offset[i - 1] < 0 && edge_offset[i] < 0) continue;
      RodBendTwistDamping damping;
      damping.offsets = {edge_offset[i - 1], edge_offset[i]};
      damping.damping = rod.bending_damping;
      damping.time_step = model.time_step;
      damping.set(model.rod_rotation(r, i - 1), model.rod_rotation(r, i), d.bending_length[i - 1]);
      p.add(damping);
    }
  }
  for (const CableSpec& cable : rod.cables) {
    for (std::size_t k = 0; k + 1 < cable.route.size(); ++k) {
      CableSegment segment;
      const CableRoutePoint& a = cable.route[k];
      const CableRoutePoint& b = cable.route[k + 1];
      segment.offsets = {node_offset[a.edge], edge_offset[a.edge], node_offset[b.edge],
                         edge_offset[b.edge]};
      segment.a = {model.rod_point(r, a.edge), model.rod_rotation(r, a.edge), a.local};
      segment.b = {model.rod_point(r, b.edge), model.rod_rotation(r, b.edge), b.local};
      segment.tension = cable.tension;
      segment.control = cable.control;
      p.add(segment);
    }
  }
  const std::vector<std::shared_ptr<const Collider>> colliders = shared_colliders(model);
  for (int i = 0; i < n; ++i) {
    if (node_fixed[i]) continue;
    add_contact_terms(model, colliders, rod.contact, {model.rod_point(r, i), -1, Vector3::Zero()},
                      {node_offset[i], -1}, p);
  }
  for (const RegionPush& push : rod.region_pushes) {
    for (int i = 0; i < n; ++i) {
      if (node_fixed[i]) continue;
      RegionForce term;
      term.offsets = {node_offset[i]};
      term.point = model.rod_point(r, i);
      term.force = push.force;
      term.center = push.center;
      term.radius = push.radius;
      p.add(term);
    }
  }
  for (const NodeForce& f : rod.node_forces) {
    if (node_fixed[f.node]) continue;
    ConstantForce term;
    term.offsets = {node_offset[f.node], -1};
    term.at.point = model.rod_point(r, f.node);
    term.force = f.force;
    term.control = f.control;
    p.add(term);
  }
  return c;
}

}  // namespace liedyn

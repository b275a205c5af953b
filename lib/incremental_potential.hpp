#pragma once
// The incremental potential Ψ(q_k; q_{k−1}, Δq_{k−1}) of a time step (paper §4.2):
//   Ψ = Σ inertia terms + Σ potentials (gravity, forces, torques, springs)
// under backward Euler; under the trapezoidal and Fox–Goodwin integrators (Model::Integrator)
// the potentials of the state count β (¼, 1/12) and history terms carry the rest
// (lib/history.hpp, weight() below).
// One IncrementalPotential per independent component of a model (bodies not coupled by
// springs are minimised separately). A component composes exactly the term types its
// scene uses: each type lives in its own vector, and an empty vector costs nothing.
//
// Assembly scatters each term's fixed-size local gradient/Hessian into the component's
// tangent vector and dense Hessian through the term's precomputed offsets. It allocates
// nothing: callers provide g and H, sized once.

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "body_contact.hpp"
#include "cable.hpp"
#include "contact.hpp"
#include "edge_contact.hpp"
#include "contact_damping.hpp"
#include "rod_damping.hpp"
#include "friction.hpp"
#include "history.hpp"
#include "inertia.hpp"
#include "joint_limits.hpp"
#include "joint_terms.hpp"
#include "loads.hpp"
#include "model.hpp"
#include "rod_terms.hpp"
#include "so3.hpp"
#include "spring.hpp"

namespace liedyn {

// Adds Hessian blocks into a dense matrix (fixed or dynamic size).
template <class Matrix>
struct DenseHessianSink {
  Matrix& H;
  void clear() { H.setZero(); }
  template <class Block>
  void add(int row, int column, const Block& block) {
    H.template block<3, 3>(row, column) += block;
  }
};

// Takes no Hessian at all: assembly without it evaluates the terms' values and gradients only
// (IncrementalPotential::value_and_gradient).
struct NoHessian {
  void clear() {}
  template <class Block>
  void add(int, int, const Block&) {}
};

class IncrementalPotential {
 public:
  // The one list of term types (term.hpp). Every consumer — assembly, begin_step, load
  // scaling, energy, the adjoint, Ceres's residual blocks — iterates it and dispatches on the
  // terms' capabilities; a new term type is added here and in the builder that creates it.
  using TermTypes = std::tuple<TranslationalInertia, RotationalInertia, PointHistory,
                               RotationHistory, Gravity, ConstantForce,
                               ConstantTorque, RegionForce, Spring, RodStretch, RodShear,
                               RodBendTwist, RodStretchDamping, RodShearDamping, RodBendTwistDamping,
                               CableSegment, JointPoint, JointLine, JointAlignment, JointWeld,
                               JointMotor, JointForceMotor, JointLimit<HingeAngle>,
                               JointLimit<SliderPosition>, Contact, Friction, ContactDamping, BodyContact,
                               BodyFriction, BodyDamping, EdgeContact, EdgeFriction, EdgeDamping,
                               EdgeBodyContact, EdgeBodyFriction, EdgeBodyDamping>;

  // The terms of type T (one contiguous vector per type).
  template <class T>
  std::vector<T>& terms() {
    return std::get<std::vector<T>>(terms_);
  }
  template <class T>
  const std::vector<T>& terms() const {
    return std::get<std::vector<T>>(terms_);
  }
  template <class T>
  void add(T term) {
    terms<T>().push_back(std::move(term));
  }

  // Calls f(terms<T>()) for every T of TermTypes, in that order.
  template <class Function>
  void for_each_term_vector(Function&& f) const {
    std::apply([&](const auto&... vectors) { (f(vectors), ...); }, terms_);
  }
  template <class Function>
  void for_each_term_vector(Function&& f) {
    std::apply([&](auto&... vectors) { (f(vectors), ...); }, terms_);
  }

  // Fixes the per-step data (x̃, R̃, R_{k−1}) from the previous state and step, and the
  // scheduled quantities (forces, torques, cable tensions, rest Darboux vectors; term.hpp) of
  // step `frame` = k ≥ 1, the step that produces q_k. Under the trapezoidal integrator also
  // the history terms' fields (lib/history.hpp): two gradient assemblies of the weighted
  // terms, at q_{k−1} and q_{k−2} (one at frame 1, whose history is the initial velocities).
  // (Where the step continues the last one and no state term changes between steps — begins
  // steps or follows a schedule — the last step's gradient at q_{k−1} serves as this one's at
  // q_{k−2}: one assembly.)
  // Under BDF2 the inertia terms' extrapolation from three states, which needs Δq_{k−2} as
  // `step_before` too (at frame 1 the initial step again; docs/design.md §15).
  // `start_frame`: the frame of the state the run started from (0), or was restarted from
  // (Simulator::set_state): the integrators' first steps, which take their history from the
  // initial step, count from there; the schedules count from frame 0.
  void begin_step(const State& previous, const Step& previous_step, int frame = 1,
                  const Step* step_before = nullptr, int start_frame = 0);
  // The step the last begin_step set up, and its run's start frame (0 before any): Newton
  // counts a reused factorisation's age in steps of one run (SolverOptions::hessian_reuse).
  int frame() const { return frame_; }
  int start_frame() const { return start_frame_; }
  // Trapezoidal: whether the last begin_step took ∇V(q_{k−2}) from the step before (above).
  bool carried_history_gradient() const { return carried_history_gradient_; }

  // The time integrator (Model::Integrator) of a dynamic step, once, after the terms are
  // added: the trapezoidal one adds a history term beside each inertia term and weights the
  // other terms (weight()); BDF2 doubles the inertia terms' m/h² and J/h². `dofs` is the
  // component's tangent size.
  void set_integrator(Integrator integrator, int dofs);
  Integrator integrator() const { return integrator_; }
  // The factor of term t in Ψ: 1, or β (newmark_beta: ¼ trapezoidal, 1/12 Fox–Goodwin) for a
  // term that is neither EndOfStep (term.hpp) nor an exact Constraint (its force is weighted
  // over three states, the history holding the other 1 − β). Every consumer of a term's value, gradient,
  // Hessian or residual applies it (assembly, value(), the Ceres forms).
  template <class T>
  double weight(const T& t) const {
    return state_term(t) ? state_weight_ : 1.0;
  }
  // Whether term t is a potential of the state: neither EndOfStep (term.hpp) nor an exact
  // Constraint. The trapezoidal and Fox–Goodwin history holds these (weight() β).
  template <class T>
  static bool state_term(const T& t) {
    if constexpr (EndOfStep<T>) {
      return false;
    } else if constexpr (Constraint<T>) {
      return !t.exact;
    } else {
      return true;
    }
  }
  // Trapezoidal: moves every rotation history's reference to q (RotationHistory::rereference).
  void rereference_history(const State& q);
  // The largest angle rereference_history(q) would move a reference, 0 without any
  // (StepSolver::solve re-solves while it exceeds the tolerance).
  double history_reference_distance(const State& q) const;
  // The same move, with g the Lie gradient at q about the old references (value_and_gradient's):
  // each history term's part of g is replaced by its gradient about the new reference (its
  // field), so that g becomes what an assembly at q would give (Newton's estimated check).
  template <class Vector>
  void rereference_history(const State& q, Vector& g);
  bool has_rotation_history() const { return !terms<RotationHistory>().empty(); }

  // Multiplies every load (gravity, forces, torques) by λ (static load stepping).
  void set_load_scale(double lambda);

  // Ψ(q).
  double value(const State& q) const;
  // Ψ(q) and its Lie gradient g (overwritten; sized by the caller) in one pass, without the
  // Hessian: Newton's line-search trial where it estimates the next Newton step (newton.hpp).
  // Ψ is summed in value()'s order (the same number).
  template <class Vector>
  double value_and_gradient(const State& q, Vector& g) const;

  // Ψ(q), and its Lie gradient g and Lie Hessian H (overwritten; sized by the caller).
  // If `roundoff` is non-null it receives an estimate of the absolute round-off error of
  // Ψ(q), which the line search needs as a floor:
  //   u · Σ_terms (|Ψ_t| + (‖g_t‖₁ + √(2 |Ψ_t| tr|H_t|)) · s),   s = 1 + max_i ‖x_i‖∞,
  // u the unit round-off. Each DOF carries a relative round-off u (rotation entries are
  // O(1)), so a term's error is its gradient with respect to the stored numbers times their
  // magnitude. That is not the Lie gradient g_t, which vanishes at a stationary point while
  // the gradient with respect to the 9 entries of R does not (e.g. ‖(R − R̃)J‖/h² for the
  // rotational inertia); for a quadratic-like term it is about √(2 Ψ_t ‖H_t‖).
  template <class Vector, class Matrix>
  double assemble(const State& q, Vector& g, Matrix& H, double* roundoff = nullptr) const {
    DenseHessianSink<Matrix> sink{H};
    return assemble_into(q, g, sink, roundoff);
  }

  // The same, with the Hessian's 3×3 blocks handed to `sink`:
  //   sink.clear();  then  sink.add(row_offset, column_offset, block)  for every block of
  // every term whose two offsets are DOFs, always in the same order for a given potential
  // (a sparse sink relies on that order to find each block's place in a fixed pattern).
  template <class Vector, class Sink>
  double assemble_into(const State& q, Vector& g, Sink& sink, double* roundoff = nullptr) const;

  // The building block of assemble_into, for assembly in parallel: the terms of one part,
  // the slice [n·index/count, n·(index + 1)/count) of each term vector (n its length), are
  // added into g and the sink, which are NOT cleared first, in the same order as in
  // assemble_into. Returns their Σ Ψ_t and adds their part of the round-off sum above to
  // *magnitude (if non-null), with s = roundoff_position_scale(q).
  struct Part {
    int index = 0;
    int count = 1;
  };
  template <class Vector, class Sink>
  double add_terms(const State& q, Vector& g, Sink& sink, Part part, double position_scale,
                   double* magnitude) const;
  static double roundoff_position_scale(const State& q) {
    double scale = 1.0;
    for (const Vector3& x : q.points) scale = std::max(scale, 1.0 + x.cwiseAbs().maxCoeff());
    return scale;
  }

  // ---- Adjoint blocks (paper §5, docs/design.md §8; lib/adjoint.cpp) --------------------
  // The derivatives of C = ∇Ψ other than the Hessian, at the converged q = q_k of a step set
  // up by begin_step(previous, previous_step, k). z is this component's adjoint vector
  // (component layout). Whole-state tangent vectors ("full" layout) hold 3 entries per point,
  // then 3 per rotation: point i at 3i, rotation j at 3(P + j), P = q.points.size().
  //   a_previous  += (∂C/∂q_{k−1})ᵀ z,   da_previous += (∂C/∂Δq_{k−1})ᵀ z   (full layout),
  // over the terms that read q_{k−1} or Δq_{k−1} (ReadsPreviousStep, term.hpp).
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const Eigen::VectorXd& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
  //   dgamma += (∂C/∂γ)ᵀ z  for the parameters of step k, over the terms with parameters
  //   (HasParameters, term.hpp).
  // Both apply each term's weight().
  void add_parameter_adjoint(const State& q, int frame, const Eigen::VectorXd& z,
                             Eigen::VectorXd& dgamma) const;
  // Trapezoidal integrator (lib/history.hpp, docs/design.md §14.1). The step's equations
  // C + c = 0 have the Jacobian H + K in q_k: H the assembled Lie Hessian (with every
  // history reference moved to q_k, rereference_history), K = ½ hat(c) on each rotation
  // block, from the history field c being constant in the world. for_each_history_skew:
  // f(o, K_o) for K's blocks, o the rotation's offset; history_skew: out = K v.
  template <class Function>
  void for_each_history_skew(Function&& f) const {
    for (const RotationHistory& t : terms<RotationHistory>()) {
      f(t.offsets[0], Matrix3(so3::hat(0.5 * t.field)));
    }
  }
  template <class In, class Out>
  void history_skew(const In& v, Out& out) const {
    out = Out::Zero(v.size());
    for_each_history_skew([&](int o, const Matrix3& K) {
      out.template segment<3>(o) = K * v.template segment<3>(o);
    });
  }
  // The mixed blocks of what the integrator reads beyond backward Euler's x̃ and R̃, for the
  // step set up by begin_step(previous, previous_step, frame, &step_before) and converged at q:
  //   a_previous += (∂C/∂q_{k−1})ᵀ z,  da_previous += (∂C/∂Δq_{k−1})ᵀ z,
  //   da_before  += (∂C/∂Δq_{k−2})ᵀ z,  dgamma += (∂C/∂γ)ᵀ z   (full layout).
  // Trapezoidal: the history field c (14.4), which reads q_{k−1} and Δq_{k−1} (the weighted
  // terms' gradients at q_{k−1} and at q_{k−2} = q_{k−1} ⊖ Δq_{k−1}, the previous step's
  // momentum) and γ (the weighted terms' parameters there). BDF2: the inertia terms' x̃ and R̃
  // from three states (design §15.1), which read Δq_{k−2} too (at frame 1 the initial step
  // again, whose part joins da_previous), and at frame 2 the initial acceleration from ∇V(q_0)
  // (so q_0 and γ). The inertia terms' own add_step_adjoint (backward Euler's R̃) is skipped
  // under BDF2. Nothing under backward Euler.
  void add_history_adjoint(const State& q, const State& previous, const Step& previous_step,
                           const Step& step_before, int frame, const Eigen::VectorXd& z,
                           Eigen::VectorXd& a_previous, Eigen::VectorXd& da_previous,
                           Eigen::VectorXd& da_before, Eigen::VectorXd& dgamma);

  // Potential energy: the sum of the terms that are energies of the state (EnergyOfState,
  // term.hpp: gravity, constant forces, springs, rod elasticity, contact penalties, elastic
  // joints; not exact joints), what frames.csv reports.
  double potential_energy(const State& q) const;

  // ---- Exact constraints (term.hpp, Constraint; the augmented Lagrangian of
  // StepSolver::solve) ------------------------------------------------------------------
  // The number of exact constraint terms, their largest violation ‖c(q)‖∞ (0 without any),
  // the multiplier update s ← s + c(q) of each, and ρ ← factor·ρ for each.
  int exact_constraints() const;
  double constraint_violation(const State& q) const;
  // The deepest penetration ρ − φ of a contact sample (into a collider or another body: every
  // term with a `penetration`), 0 when none overlaps.
  double max_penetration(const State& q) const;
  void update_multipliers(const State& q);
  void scale_penalties(double factor);
  // For the adjoint (joint_terms.hpp, solvers/adjoint.cpp), in the order of the terms:
  // appends each exact term's λ (its force or torque, world) at q; switches every exact term
  // to the Lagrangian λᵀc + ½ρ‖c‖² with λ from `multipliers` (exact_constraints() of them);
  // and c(q) with J = ∂c/∂q, 3 rows per exact term, in the component's tangent layout
  // (J sized by the caller: 3·exact_constraints() × dofs).
  // (A term already in the Lagrangian form gives its `multiplier` as λ: the Ipopt back-end's.)
  void exact_forces(const State& q, std::vector<Vector3>& out) const;
  void set_adjoint_multipliers(const Vector3* multipliers);
  void constraint_jacobian(const State& q, Eigen::MatrixXd& J) const;

  // ---- Exact equalities as a solver's own constraints (solvers/ipopt_step.hpp) ----------
  // f(t) for every exact term that is an equality (Constraint, not Inequality; term.hpp), in
  // the order of the terms: 3 rows c = t.constraint(q, J) each (kConstraintRank of them
  // independent), and how many there are.
  template <class Function>
  void for_each_exact_equality(Function&& f) const {
    exact_constraints_of<true>(*this, f);
  }
  template <class Function>
  void for_each_exact_equality(Function&& f) {
    exact_constraints_of<true>(*this, f);
  }
  int exact_equalities() const;

 private:
  // f(t) for every exact constraint term t of self (term.hpp, Constraint), or only the
  // equalities (not Inequality).
  template <bool kEqualitiesOnly, class Self, class Function>
  static void exact_constraints_of(Self& self, Function&& f) {
    self.for_each_term_vector([&](auto& terms) {
      using T = typename std::decay_t<decltype(terms)>::value_type;
      if constexpr (Constraint<T> && !(kEqualitiesOnly && Inequality<T>)) {
        for (auto& t : terms) {
          if (t.exact) f(t);
        }
      }
    });
  }
  // Σ ∇Ψ_t over the state terms, unweighted, at q, in the component's tangent layout (g sized
  // by the caller): ∇V(q) of (14.4), and of the initial acceleration under BDF2.
  void state_terms_gradient(const State& q, Eigen::VectorXd& g) const;
  // Whether a term of the state fixes per-step data (BeginsStep) or follows a schedule: its
  // gradient at a state then differs from one step to the next (term.hpp).
  bool state_terms_change_per_step() const;
  // Trapezoidal: the state at which gradient_previous_ was taken, on the component's own blocks
  // (its history terms' points and rotations), and whether q is it to round-off.
  void keep_gradient_state(const State& q);
  bool at_gradient_state(const State& q) const;
  // BDF2's extrapolations x̃ and R̃ of the inertia terms (begin_step; docs/design.md §15).
  void begin_bdf2_step(const State& previous, const Step& previous_step, const Step& step_before,
                       int steps);
  // add_history_adjoint's part of w ∇V at s (s = q_{k−1} or q_{k−2}, G = ∇V(s) from
  // weighted_terms_gradient): u += w (H_V(s) z + ½ G × z on rotations), the derivative of the
  // Lie gradient field ∇V transposed (design §1.4), component layout; and the weighted terms'
  // own reads of q_{k−1} (their reference, ReadsPreviousStep) and of γ at s.
  void add_weighted_terms_adjoint(const State& s, const Eigen::VectorXd& G, double w, int frame,
                                  const State& previous, const Step& previous_step,
                                  const Eigen::VectorXd& z, Eigen::VectorXd& u,
                                  Eigen::VectorXd& a_previous, Eigen::VectorXd& da_previous,
                                  Eigen::VectorXd& dgamma) const;
  // u holds a cotangent at q_{k−2} = q_{k−1} ⊖ Δq_{k−1} on the inertia terms' blocks
  // (component layout): δx_{k−2} = δx_{k−1} − δΔx and δθ_{k−2} = ΔR_{k−1}ᵀ (δθ_{k−1} − δψ)
  // (left perturbations of R_{k−1} and ΔR_{k−1}) carry it to q_{k−1} and Δq_{k−1}.
  void add_older_adjoint(const State& previous, const Step& previous_step,
                         const Eigen::VectorXd& u, Eigen::VectorXd& a_previous,
                         Eigen::VectorXd& da_previous) const;
  // add_history_adjoint under BDF2.
  void add_bdf2_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const Step& step_before, int frame, const Eigen::VectorXd& z,
                        Eigen::VectorXd& a_previous, Eigen::VectorXd& da_previous,
                        Eigen::VectorXd& da_before, Eigen::VectorXd& dgamma);

  Integrator integrator_ = Integrator::kBackwardEuler;
  double state_weight_ = 1.0;  // weight() of the terms of the state
  int frame_ = 0, start_frame_ = 0;  // frame() and start_frame()
  bool carried_history_gradient_ = false;
  // Scratch, sized by set_integrator and at the first step: the state terms' gradients at
  // q_{k−1} and q_{k−2}, and the whole state q_{k−2} (trapezoidal; BDF2: q_0 and its gradient
  // at frame 2), and BDF2's initial step corrected by the initial acceleration.
  Eigen::VectorXd gradient_previous_, gradient_older_;
  // add_history_adjoint's cotangents at q_{k−1}/q_{k−2} and of ∇V(q_0) (component layout),
  // sized at its first call: the backward pass does not allocate per step for them.
  Eigen::VectorXd adjoint_older_, adjoint_gradient_;
  State older_;
  Step corrected_step_;
  std::vector<Vector3> gradient_state_points_;   // keep_gradient_state
  std::vector<Matrix3> gradient_state_rotations_;

  template <class Tuple>
  struct VectorsOf;
  template <class... Ts>
  struct VectorsOf<std::tuple<Ts...>> {
    static_assert((Term<Ts> && ...), "every type of TermTypes is a Term (term.hpp)");
    using type = std::tuple<std::vector<Ts>...>;
  };
  typename VectorsOf<TermTypes>::type terms_;
};

// A set of DOF blocks minimised together, with their place in the tangent vector.
struct DofBlock {
  int index = -1;   // into State::points or State::rotations
  int offset = -1;  // into the component's tangent vector
};

struct Component {
  int dofs = 0;
  std::vector<DofBlock> points;
  std::vector<DofBlock> rotations;
  IncrementalPotential potential;
};

// Splits a validated model into the independent components of a step (its islands: bodies
// and rods joined by springs, by the joints and touching body pairs that `key` says hold —
// Model::coupling_key — share one, each rod alone is one) and builds each component's terms
// with their scatter offsets. Body order is kept; within a component each body contributes
// [x, θ] in that order. A rod whose nodes and edges are all clamped has no DOFs and no
// component. solvers/islands.hpp caches the components by key.
std::vector<Component> build_components(const Model& model, const std::vector<bool>& key);
// The components of step `frame` with no bodies touching.
std::vector<Component> build_components(const Model& model, int frame = 1);

// The component of rod r: lumped inertia, gravity, stretch, shear, bend–twist and node
// forces over its free nodes and edges (docs/design.md §6).
Component build_rod_component(const Model& model, int r);

// ---------------------------------------------------------------------------------------
// Calls f(std::integral_constant<int, i>{}) for i = 0, …, N − 1, unrolled at compile time.
template <int N, class Function>
inline void static_for(Function&& f) {
  [&]<int... I>(std::integer_sequence<int, I...>) {
    (f(std::integral_constant<int, I>{}), ...);
  }(std::make_integer_sequence<int, N>{});
}

template <class Vector>
double IncrementalPotential::value_and_gradient(const State& q, Vector& g) const {
  NoHessian none;
  return assemble_into(q, g, none);
}

template <class Vector>
void IncrementalPotential::rereference_history(const State& q, Vector& g) {
  LocalGradient<1> g_local;
  for (RotationHistory& t : terms<RotationHistory>()) {
    const int o = t.offsets[0];
    t.evaluate(q, &g_local, nullptr);
    g.template segment<3>(o) -= g_local;
    t.rereference(q);
    t.evaluate(q, &g_local, nullptr);
    g.template segment<3>(o) += g_local;
  }
}

template <class Vector, class Sink>
double IncrementalPotential::assemble_into(const State& q, Vector& g, Sink& sink,
                                           double* roundoff) const {
  g.setZero();
  sink.clear();
  double magnitude = 0.0;  // the Σ above
  const double position_scale = roundoff != nullptr ? roundoff_position_scale(q) : 1.0;
  const double value =
      add_terms(q, g, sink, Part{}, position_scale, roundoff != nullptr ? &magnitude : nullptr);
  if (roundoff != nullptr) *roundoff = std::numeric_limits<double>::epsilon() * magnitude;
  return value;
}

template <class Vector, class Sink>
double IncrementalPotential::add_terms(const State& q, Vector& g, Sink& sink, Part part,
                                       double position_scale, double* magnitude) const {
  double value = 0.0;
  double roundoff_sum = 0.0;  // kept local: *magnitude could alias g
  for_each_term_vector([&](const auto& terms) {
    using Term = typename std::decay_t<decltype(terms)>::value_type;
    constexpr int B = Term::kBlocks;
    LocalGradient<B> g_local;
    LocalHessian<B> H_local;
    // The divisions are skipped in the common serial case: on a single rigid body they cost
    // as much as its whole assembly.
    const std::size_t n = terms.size();
    const std::size_t begin = part.count == 1 ? 0 : n * part.index / part.count;
    const std::size_t end = part.count == 1 ? n : n * (part.index + 1) / part.count;
    constexpr bool kHessian = !std::is_same_v<Sink, NoHessian>;
    for (std::size_t t = begin; t < end; ++t) {
      const Term& term = terms[t];
      double term_value = term.evaluate(q, &g_local, kHessian ? &H_local : nullptr);
      // The weight multiplies the value and gradient here, and each Hessian block as the sink
      // takes it (a banded sink reads only the blocks on and below the diagonal).
      const double w = weight(term);
      if (w != 1.0) {
        term_value *= w;
        g_local *= w;
      }
      value += term_value;
      if (kHessian && magnitude != nullptr) {
        const double ambient_gradient =
            std::sqrt(2.0 * std::abs(term_value) * w * H_local.diagonal().cwiseAbs().sum());
        roundoff_sum += std::abs(term_value) +
                        (g_local.template lpNorm<1>() + ambient_gradient) * position_scale;
      }
      // Unrolled at compile time, so that each block's place in H_local is a constant and an
      // inlined sink sees which blocks are diagonal (i = j).
      static_for<B>([&](auto i) {
        const int oi = term.offsets[i];
        if (oi < 0) return;
        g.template segment<3>(oi) += g_local.template segment<3>(3 * i);
        if constexpr (kHessian) {
          static_for<B>([&](auto j) {
            const int oj = term.offsets[j];
            if (oj < 0) return;
            // One call site per block, scaled even when w = 1 (exact, and 9 products): a
            // second call for the unscaled case doubled the code every sink instantiates.
            sink.add(oi, oj, w * H_local.template block<3, 3>(3 * i, 3 * j));
          });
        }
      });
    }
  });
  if (magnitude != nullptr) *magnitude += roundoff_sum;
  return value;
}

}  // namespace liedyn

#pragma once
// A model of rigid bodies and Cosserat rods as a user describes it, in code or through a
// scene file (problems/scene.hpp). Units SI.
// State layout: body i owns point i (centre of mass) and rotation i; then each rod in turn
// owns the next node_count() points (its nodes) and edge_count() rotations (its edges).

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <limits>
#include <optional>
#include <vector>

#include "contact.hpp"
#include "kinematic.hpp"
#include "rod.hpp"
#include "sdf.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// Invalid input to the model; `field` is a dotted path such as "bodies[1].inertia".
// Edge edge_a of rod rod_a and edge edge_b of rod rod_b (rod_a ≤ rod_b; within one rod,
// edge_a < edge_b).
struct EdgePair {
  int rod_a = -1, edge_a = -1, rod_b = -1, edge_b = -1;
};

class ModelError : public std::invalid_argument {
 public:
  ModelError(std::string field, std::string reason);
  const std::string& field() const { return field_; }
  // What is wrong, without the field (what() is "field: reason").
  const std::string& reason() const { return reason_; }

 private:
  std::string field_, reason_;
};

// Throws ModelError(field, …) unless every entry of m is finite.
void require_finite(const Eigen::MatrixXd& m, const std::string& field);

struct RigidBody {
  std::string name;
  double mass = 1.0;                              // kg, > 0
  Matrix3 inertia = Matrix3::Identity();          // body-frame tensor about the centre of mass
  Vector3 position = Vector3::Zero();             // centre of mass, world
  Matrix3 orientation = Matrix3::Identity();      // body → world
  Vector3 linear_velocity = Vector3::Zero();      // world
  Vector3 angular_velocity = Vector3::Zero();     // world
  // Contact samples (body coordinates) against every collider of the model, each a sphere
  // of contact.radius (lib/contact.hpp); none: the body never touches anything.
  std::vector<Vector3> contact_points;
  ContactMaterial contact;
  // The body's solid for other bodies' samples (lib/body_contact.hpp): an SDF in body
  // coordinates (the collider's pose within the body), or none: other bodies pass through it.
  // A shape a body may have (validate_body_shape), or, for a kinematic body, any collider (a
  // moving plane, tube or inside-out shape: unbounded or unsampled solids that only push).
  std::shared_ptr<const Collider> shape;
  // A kinematic body follows this motion from its pose at t = 0 (lib/kinematic.hpp): it is
  // no DOF, holds no inertia (mass, inertia and velocities unused) and feels no load; what
  // it touches and what is joined to it are coupled to it as to the world.
  std::optional<KinematicMotion> kinematic;
};

// End of a spring or point of application of a force: a body point given in body
// coordinates, or (body = −1) a fixed world point.
struct BodyPoint {
  int body = -1;
  Vector3 point = Vector3::Zero();
};

struct SpringSpec {
  BodyPoint a, b;
  double stiffness = 0.0;     // N/m, ≥ 0
  double rest_length = 0.0;   // m, ≥ 0
  int stiffness_slot = -1;    // index in an optimisation's parameter vector γ, or −1
};

// One end of a joint (docs/scene-format.md#joints):
//   body      a body point p̄ and the body's frame (R p̄ + x);
//   rod node  a node's position, without a rotation (ball joints only);
//   rod edge  the edge's material frame R_j anchored at its first node x_j, and a point p̄ in
//             it, p = x_j + R_j p̄ (as a cable's route point, rod.hpp): p̄ = (0, 0, l/2) with
//             l the edge's initial length is its midpoint at the start, and stays so to
//             within the edge's stretch and shear;
//   world     a fixed point in world coordinates, with the identity frame.
struct JointEnd {
  enum class Kind { kWorld, kBody, kRodNode, kRodEdge };
  Kind kind = Kind::kWorld;
  int object = -1;                  // the body, or the rod of a node or an edge
  int element = -1;                 // the rod's node or edge
  Vector3 point = Vector3::Zero();  // body or edge coordinates; world coordinates for the world

  static JointEnd body(int b, const Vector3& p) { return {Kind::kBody, b, -1, p}; }
  static JointEnd world(const Vector3& p) { return {Kind::kWorld, -1, -1, p}; }
  static JointEnd rod_node(int rod, int node) { return {Kind::kRodNode, rod, node, Vector3::Zero()}; }
  static JointEnd rod_edge(int rod, int edge, const Vector3& p) { return {Kind::kRodEdge, rod, edge, p}; }
  bool has_rotation() const { return kind == Kind::kBody || kind == Kind::kRodEdge; }
  bool operator==(const JointEnd&) const = default;
};

// A joint between two ends (above; docs/scene-format.md#joints):
//   translation  p_b = p_a   (the two ends' points); slider: p_b on the line through p_a
//                along R_a â;
//   rotation     hinge: the axes R_a â and R_b b̂ aligned; weld and slider: the initial
//                relative orientation kept, log(R_a A Bᵀ R_bᵀ) = 0; ball: none.
// Each part is elastic, ½ ‖c‖²/compliance (translation) and ½ ‖c‖²/compliance_rotation, or
// exact where its compliance is 0 (the augmented Lagrangian of StepSolver::solve).
// A rod node has no rotation: only a ball joint holds it. Terms: lib/joint_terms.hpp.
struct JointSpec {
  // kSplice: two rods joined end to end as one — the last node of a's rod held to the first
  // of b's (as a ball joint), and the bending and twist across the junction as within a rod.
  enum class Type { kBall, kHinge, kWeld, kSlider, kSplice };
  Type type = Type::kBall;
  JointEnd a, b;
  Vector3 axis_a = Vector3::UnitZ();          // hinge, slider: unit, in a's coordinates
  Vector3 axis_b = Vector3::UnitZ();          // hinge: unit, in b's coordinates
  Matrix3 frame_a = Matrix3::Identity();      // weld, slider: joint frames in the ends' coordinates
  Matrix3 frame_b = Matrix3::Identity();
  double compliance = 0.0;                    // m/N, ≥ 0 (0: exact)
  double compliance_rotation = 0.0;           // rad/(N·m), ≥ 0 (0: exact)
  // Motor (lib/joint_terms.hpp): a hinge's torque about its axis, +τ on a and −τ on b, or a
  // slider's force along its axis, +f on a and −f on b; per step from `motor` (constant
  // `motor_effort` without a schedule).
  bool has_motor = false;
  double motor_effort = 0.0;                  // N·m (hinge) or N (slider)
  ScheduledParameter<1> motor;
  // Limits (lib/joint_limits.hpp): lower ≤ ξ ≤ upper on a hinge's angle (rad) or a slider's
  // position (m), ξ = 0 at the start; as exact or as elastic as the joint.
  bool has_limits = false;
  double lower_limit = 0.0, upper_limit = 0.0;
  // The steps k (1, 2, …) in which the joint holds, first_frame ≤ k ≤ last_frame: every step
  // by default. Outside them it exerts nothing, and what only it joined falls apart into
  // separate islands (a gripper that lets go, a hook that catches). It holds its ends where
  // its anchors say, wherever they are when it starts to hold.
  int first_frame = 1;
  int last_frame = std::numeric_limits<int>::max();
  bool active_at(int frame) const { return first_frame <= frame && frame <= last_frame; }
};

struct ForceSpec {
  BodyPoint at;               // body ≥ 0 required
  Vector3 force = Vector3::Zero();  // world, N
  ScheduledParameter<3> control;    // per-step forces and their slot in γ (lib/term.hpp)
};

struct TorqueSpec {
  int body = -1;
  Vector3 torque = Vector3::Zero();  // world, N·m
  ScheduledParameter<3> control;     // per-step torques and their slot in γ (lib/term.hpp)
};

// How a dynamic step discretises time (docs/design.md §14; static mode has no time and
// ignores it):
//   * backward_euler — the paper's incremental potential: first order, dissipative;
//   * trapezoidal — second order and time-reversible: the trapezoidal rule on the forces of
//     conservative terms, ¼ (f_k + 2 f_{k−1} + f_{k−2}), and the Lie group variational
//     discretisation of rotational inertia (discrete momentum 2 vee(R_k J R_{k−1}ᵀ)/h), solved
//     as a minimisation (lib/history.hpp). Friction, motors and exact joints act at the
//     step's end, as under backward Euler.
//   * fox_goodwin — the same with the forces weighted (f_k + 10 f_{k−1} + f_{k−2})/12 (Newmark's
//     β = 1/12 where the trapezoidal rule is β = ¼): fourth order in the phase of a linear
//     oscillation of points (Numerov's method), where the trapezoidal rule errs by (ωh)²/12, but
//     only conditionally stable, for ωh < √6 on every mode (docs/design.md §14.2). The Simulator
//     checks that bound at the state each set of islands starts from (lib/stability.hpp), and
//     validate() refuses contact and elastic joint limits, whose stiffness appears within a run.
//   * bdf2 — second order and L-stable: the backward difference of the second derivative,
//     M (2x_k − 5x_{k−1} + 4x_{k−2} − x_{k−3})/h² = f_k, as backward Euler's incremental
//     potential with twice the inertia about an extrapolation from three states (docs/design.md
//     §15). It damps what h does not resolve, as backward Euler, but resolved motion only at
//     O((ωh)⁴) per step.
enum class Integrator { kBackwardEuler, kTrapezoidal, kFoxGoodwin, kBdf2 };
// The scene file's names ("backward_euler", "trapezoidal", "fox_goodwin", "bdf2") and back
// (nullopt for another).
const char* to_string(Integrator integrator);
std::optional<Integrator> parse_integrator(std::string_view name);
// β of the integrators that weight the forces of three states β f_k + (1 − 2β) f_{k−1} + β f_{k−2}
// (lib/history.hpp): ¼ for trapezoidal, 1/12 for fox_goodwin; 0 for the others.
double newmark_beta(Integrator integrator);

struct Model {
  double time_step = 0.01;  // h, s, > 0
  Integrator integrator = Integrator::kBackwardEuler;
  Vector3 gravity = Vector3::Zero();
  std::vector<RigidBody> bodies;
  std::vector<SpringSpec> springs;
  std::vector<JointSpec> joints;
  std::vector<ForceSpec> forces;
  std::vector<TorqueSpec> torques;
  std::vector<RodSpec> rods;
  // Static obstacles (lib/sdf.hpp) that the contact samples of bodies and rods touch.
  std::vector<Collider> colliders;

  // Static equilibria instead of dynamics ("mode": "static"): no inertia terms, and step k
  // minimises the potential energy with every load (gravity, forces, torques) scaled by
  // λ_k = min(k / load_steps, 1), and prescribed motions followed to λ_k of their
  // duration (prescribed_motion.hpp). Each part of the model must be anchored (a clamped rod
  // node, a spring chain to a world anchor): free motion has no equilibrium.
  bool static_equilibrium = false;
  int load_steps = 1;

  // The pairs of bodies (a < b) that can touch each other: both with contact enabled, and a
  // sample of one facing the other's shape (RigidBody::shape).
  std::vector<std::pair<int, int>> body_pairs() const;
  // The pairs of rod edges that may touch (EdgePair), after the body pairs in a coupling key:
  // the edges of two rods that both have contact and agree to touch, and a self-contact
  // rod's own edges more than its self_contact_skip apart; none whose four nodes are clamped.
  std::vector<EdgePair> edge_pairs() const;
  // The (rod, body) pairs that may touch, after the edge pairs in a coupling key: a rod with
  // contact (its free nodes, spheres of its contact radius) and a body with a shape, agreeing.
  std::vector<std::pair<int, int>> rod_body_pairs() const;
  // Which couplings hold at a step, as the key of its islands (solvers/islands.hpp): one
  // entry per joint (active at `frame`, JointSpec::active_at), then one per body pair and one
  // per edge pair and one per rod–body pair (`touching`, indexed as body_pairs(), then
  // edge_pairs(), then rod_body_pairs(); all false when empty). Written into `key`.
  void coupling_key(int frame, const std::vector<bool>& touching, std::vector<bool>& key) const;
  // The objects that springs, joints, touching bodies and touching rods couple, as (a, b) pairs: body i is
  // i, rod r is bodies.size() + r, and −1 the world. What ties objects into one island under
  // `key` (coupling_key), and without one (every joint, whatever its steps, and no contact)
  // what anchors them in static mode.
  std::vector<std::pair<int, int>> couplings(const std::vector<bool>* key = nullptr) const;
  // The object (as in couplings()) of a joint end, −1 for the world.
  int object_of(const JointEnd& end) const;

  // A joint end as a point of the state (−1 for the world or no rotation), and its frame's
  // origin and rotation at the start (a rod node: the identity).
  AttachedPoint attached_point(const JointEnd& end) const;
  Vector3 initial_origin(const JointEnd& end) const;
  Matrix3 initial_rotation(const JointEnd& end) const;
  Vector3 initial_position(const JointEnd& end) const {
    return initial_origin(end) + initial_rotation(end) * end.point;
  }

  // Index in State::points of a rod's node, and in State::rotations of a rod's edge (rod =
  // rods.size() with node or edge 0: one past the last).
  int rod_point(int rod, int node) const;
  // Size of State::points: every body, then every rod's nodes.
  int point_count() const { return rod_point(static_cast<int>(rods.size()), 0); }
  int rod_rotation(int rod, int edge) const;
  // A rod's discretisation (lib/rod.hpp) with its ends as the joints hold them (welds, splices).
  RodDiscretization discretize_rod(int rod) const;

  // Throws ModelError naming the first offending field. Checks finiteness, positivity,
  // symmetric positive-definite inertia obeying the triangle inequality, orthonormal
  // orientations, and valid body indices.
  void validate() const;
  // The rod checks of validate(); `path` prefixes field names (e.g. "rods[0]").
  static void validate_rod(const RodSpec& rod, const std::string& path);
  // The prescribed-motion checks of validate_rod (indices, clamping, keyframe order).
  static void validate_motions(const RodSpec& rod, const std::string& path);
  // Dynamic mode: prescribed rotations below π per time step.
  void validate_motion_speeds() const;
  // Dynamic mode under fox_goodwin: no contact and no elastic joint limits (Integrator).
  void validate_conditional_stability() const;
  // The static-mode checks of validate().
  void validate_anchoring() const;
  // The contact checks of validate(): colliders, materials, samples; `path` as above.
  static void validate_contact(const ContactMaterial& contact, const std::string& path);
  // The names in every contact block's collides_with and ignores.
  void validate_contact_names() const;

  // State q_0 and step Δq_0 = (h v_0, exp(h ω_0)) (docs/design.md §2.2); rods start in their
  // initial shape, with parallel-transported edge frames, edges at rest and nodes at their
  // node_velocities (none: at rest). Clamped nodes start at rest whatever node_velocities
  // says (validate refuses a non-zero one): a Δx_0 would carry them along in every step.
  State initial_state() const;
  Step initial_step() const;
};

// Tolerance on the triangle inequality I₁ ≤ I₂ + I₃ (relative to tr I_b): a body whose
// principal moments violate it by more is rejected, a thin rod (I₁ → 0) is accepted.
inline constexpr double kInertiaTolerance = 1e-12;

}  // namespace liedyn

#pragma once
// Penalty contact and friction against the shape of a body B (lib/contact.hpp is the same
// against a static collider; shapes: lib/sdf.hpp).
//
// The sampled side. A term's first two blocks carry the point p that touches B, either
//   on a frame: p = x_A + R_A p̄, blocks (x_A, θ_A): a sample of body A, or a rod's node (no
//               rotation: p̄ = 0 and θ_A is no DOF);
//   on an edge: p = (1 − s) x_0 + s x_1, blocks (x_0, x_1): a point of a rod's edge (the
//               Gauss points below).
// To first order a change of the two blocks moves p by A (δ_0, δ_1), with
//   A = [I, −hat(r)] on a frame (r = R_A p̄, the lever),   A = [(1 − s) I, s I] on an edge,
// and p's only second-order term is the rotated point's, C(r, f_p) at block (1, 1) (paper
// eq. 23, rotated_point_curvature, f_p = ∂V/∂p), which vanishes on an edge with r = 0 (p is
// linear in the nodes). Every formula below is written with A and r, and one code path serves
// both sides: SampledPoint holds (p, A, r), and the terms differ only in how they make it and
// in where their first two blocks live in the state. Why a value rather than templates on
// the sampled side: A is the same 3×6 map for both, the Jacobian J below is built explicitly
// either way (so a general A costs nothing), and the math stays in one compiled function of
// the .cpp instead of being instantiated per side; BodySample and the body terms keep their
// layout and interfaces.
//
// Contact. B's shape is an SDF φ_B in B's coordinates; a sample is a sphere of radius ρ with
// stiffness k, and with w = p − x_B, u = R_Bᵀ w,
//   φ = φ_B(u),   d = ρ − φ,   V = ½ k max(0, d)².
// In world terms n = R_B ∇φ_B(u), N = R_B ∇²φ_B(u) R_Bᵀ, f = ∂V/∂p = −k d n and
// K = k (n nᵀ − d N). A change of the four blocks (sampled side, x_B, θ_B), B's rotation by a
// left perturbation, moves u by R_Bᵀ J δ to first order, with
//   J = [A, −I, hat(w)]
// (B's turn δθ_B moves the field, u = R_Bᵀ exp(−δθ_B) w: the sample seen from B turns by
// −δθ_B about x_B). So the gradient is Jᵀ f and the Hessian is Jᵀ K J plus the second-order
// terms of u (paper eq. 23 for both rotated points, and the cross terms of exp(−δθ_B) with
// the motion of p and x_B), with f in the world:
//   (1, 1): C(r, f)     θ_Bθ_B: C(w, f)     θ_B × (block 0, block 1, x_B): hat(f) [A, −I]
// and their transposes across the diagonal (on a frame: θ_B x_A hat(f), θ_B θ_A −hat(f) hat(r),
// θ_B x_B −hat(f)). As for a collider, K is indefinite where B's surface curves towards the
// sample, exact, and V is C¹ with a jump of K at d = 0.
// The internal forces are equal and opposite: the gradient's parts on p (Aᵀ f) and x_B (−f)
// cancel, and so do the torques about the origin, so contact conserves linear and angular
// momentum (tests/test_body_contact.cpp, tests/test_edge_body_contact.cpp).
//
// Least-squares form, 1 residual per sample: r = √k max(0, d), ∂r/∂(blocks) = −√k nᵀ J where
// d > 0, else 0.
//
// Reads q_k only: the adjoint needs no mixed block (its Hessian enters H_k). Its stencil
// spans two objects: a pair in contact is a coupling, and joins their islands
// (solvers/islands.hpp) for the steps in which it is (ContactSearch, contact_search.hpp).
//
// Friction: friction.hpp's lagged law on the slip of the sample relative to the point of B it
// touched. At the start of the step, with hats for q_{k−1}: the sample at p̂ sits at
// û = R̂_Bᵀ(p̂ − x̂_B) in B's coordinates, and
//   λ = k max(0, ρ − φ_B(û)),   n = R̂_B G/‖G‖ (G = ∇φ_B(û)),   P = I − n nᵀ
// are frozen, as is û: B's material point b̄ = û (LaggedContact). Over the step the sample
// moves from that point by d = p_B − p with p_B = x_B + R_B û (zero at q_{k−1}), and
//   D = μ λ f₀(‖P d‖)
// (f₀ and its slopes: friction.hpp). With
//   f = ∂D/∂d = μλ φ₁ u,   K = μλ (φ₁ P + (φ₁′/y) u uᵀ),   u = P d, y = ‖u‖,
// and r_B = R_B û, ∂d/∂(blocks) = Jd = [−A, I, −hat(r_B)]: the gradient is Jdᵀ f and the
// Hessian Jdᵀ K Jd + C(r, −f) at (1, 1) + C(r_B, f) at θ_Bθ_B (point_pair.hpp's mapping with
// the sampled side's A). A sample sliding over a still body feels μλ against its slip; the
// body the opposite force at its material point, d away: linear momentum is conserved, and the
// couple d × f vanishes where the slip lies in the lagged tangent plane (P d = d).
//
// Least-squares form: r = √(2D), J = gᵀ/r (friction_residual).
//
// Damping: the dashpot of dissipation_law.hpp on the same d, D = ½ r (n·d)² (r = τ k/h) while
// the sample was in contact: the same mapping with its f and K, one residual √r (n·d) with the
// row √r nᵀ Jd. Friction and damping are one term, BodyDissipation<Law>, whose law gives D, f,
// K and ∂f from ∂d, ∂λ and ∂n; the geometry above and the adjoint below are written once.
//
// The adjoint: λ, n and û are functions of q̂ = (the sampled side's blocks, x̂_B, θ̂_B) at
// q_{k−1}, through
//   ∂û/∂q̂ = R̂_Bᵀ Ĵ,   Ĵ = [Â, −I, hat(ŵ)],   ŵ = p̂ − x̂_B   (the contact's J at q_{k−1}),
//   ∂λ/∂q̂ = −k Gᵀ ∂û/∂q̂,
//   ∂n/∂q̂ = (P N/‖G‖) Ĵ − [0, 0, 0, hat(n)]   (N = R̂_B ∇²φ_B(û) R̂_Bᵀ; B's turn carries n),
//   ∂d/∂q̂ = R_B ∂û/∂q̂,   ∂u/∂q̂ = P ∂d/∂q̂ − (n dᵀ + (n·d) I) ∂n/∂q̂,
//   ∂f/∂q̂ = μ φ₁ u ∂λ/∂q̂ + μλ (φ₁ I + (φ₁′/y) u uᵀ) ∂u/∂q̂   (friction; the dashpot's: its law),
// and the gradient C = [−Aᵀ f; f; r_B × f] has ∂C/∂q̂ rows −Aᵀ ∂f (A at q_k: p̂ does not
// enter it), ∂f and hat(r_B) ∂f − hat(f) R_B ∂û/∂q̂ (r_B moves with û). Δq_{k−1} does not
// enter.
//
// Edges (EdgeBodyContact, EdgeBodyFriction). A rod's edge [x_0, x_1] is a capsule of the
// rod's contact radius ρ. Its closest point to B is not a smooth function of the state (it
// jumps along a straight edge lying on a face), so, as between edges (lib/edge_contact.hpp),
// the penalty is integrated along the edge by an N-point Gauss–Legendre rule (nodes s_q,
// weights w_q, Σ w_q = 1) with ℓ̄ the edge's rest length:
//   V = Σ_q c_q ½ κ max(0, ρ − φ(p_q))²,   p_q = (1 − s_q) x_0 + s_q x_1,   c_q = w_q ℓ̄,
// κ a stiffness per unit length: each Gauss point is a sample on an edge with stiffness c_q κ,
// and its friction (damping) a sample's friction (damping) with its own lagged (û_q, λ_q =
// c_q κ max(0, ρ − φ_B(û_q)), n_q); the blocks are (x_0, x_1, x_B, θ_B), a clamped node's or a kinematic
// body's offsets −1. The builder takes κ = k/ℓ̄ (the rod's contact k, as EdgeContact does), so
// that c_q κ = w_q k: an edge lying along a body presses with k in all, about k per node, as
// the node samples it replaces did.
// Tips: the Gauss points never reach an edge's ends (s_1 ≈ 0.07 with 4 points), so the
// hemispherical caps at a rod's two ends are not sampled, and a rod pushed end-on into a body
// would sink by 0.07 ℓ̄ before a Gauss point touched. The two END nodes, when free, keep a
// node sample (a BodyContact on a frame without rotation) with the rod's k. Interior nodes
// need none: the two edges that meet there sample both sides of them. Near an end the node's
// k adds to the edge's (a rod lying flat on a face presses with (n + 1) k over its n nodes
// instead of n k): the ends are a little stiffer, never softer.
// What the quadrature sees, and when more points are needed: contact only where a Gauss point
// is within ρ of B. Consecutive samples along a rod are at most Δ = 0.34 ℓ̄ apart with 4
// points (the middle pair; 0.14 ℓ̄ across a node), 0.18 ℓ̄ with 8. A convex feature of B of
// radius of curvature R (a sphere's or capsule's radius, a box's rounding) crossed between
// two samples pokes into the capsule by up to (R + ρ) − √((R + ρ)² − Δ²/4) ≈ Δ²/(8 (R + ρ)),
// and passes through it when Δ/2 ≥ R + ρ; a sharp box edge (R = 0) crossed at 45° pokes in by
// up to Δ/2 − (√2 − 1) ρ, through the rod when Δ/2 ≥ (√2 + 1) ρ. Δ is about 1.4 ℓ̄/N, so
// where rods cross thin features ℓ̄/N should be below about R + ρ: more points (the builder
// uses 4) or shorter edges. penetration() reports the deepest sample, not the capsule's
// closest distance.

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "edge_contact.hpp"
#include "dissipation_law.hpp"
#include "friction.hpp"
#include "model.hpp"
#include "sdf.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// The sampled side at a state (formulas above): p, A = ∂p/∂(block 0, block 1) and the lever r.
struct SampledPoint {
  Vector3 position;                 // p
  Eigen::Matrix<double, 3, 6> map;  // A
  Vector3 lever;                    // r (0 on an edge)

  // A point on a frame (a body's sample, a rod's node): blocks (x_A, θ_A).
  static SampledPoint on_frame(const AttachedPoint& at, const State& q);
  // The point at s of the edge [x0, x1]: blocks (x_0, x_1).
  static SampledPoint on_edge(const Vector3& x0, const Vector3& x1, double s);
};

// What friction freezes at the start of a step, per sample (formulas above).
struct LaggedContact {
  Vector3 contact_point = Vector3::Zero();  // û, in B's coordinates
  double normal_force = 0.0;                // λ
  Vector3 normal = Vector3::UnitZ();        // n, world
};

// What the contact and friction terms of a sample on a frame share: a sample of A (or a rod's
// node), a sphere of radius ρ, against B's shape with stiffness k.
struct BodySample {
  std::array<int, 4> offsets{-1, -1, -1, -1};  // x_A, θ_A, x_B, θ_B
  AttachedPoint at;                            // the sample, on A
  int body_b = -1;                             // B (State::points and ::rotations)
  std::shared_ptr<const Collider> shape;       // B's shape, in B's coordinates
  double stiffness = 0.0;                      // k, A's
  double radius = 0.0;                         // ρ, A's
};

struct BodyContact : BodySample {
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "body_contact";
  static constexpr bool kEnergyOfState = true;

  // ρ − φ: > 0 when the sample's sphere overlaps B.
  double penetration(const State& q) const;
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;

  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

// The lagged dissipation of a sample against B (friction and damping, formulas above and in
// dissipation_law.hpp): the geometry of the relative displacement d and its adjoint here, the
// law of d in Law (SlipFriction: μ, ε; NormalDashpot: τ, h).
template <class Law>
struct BodyDissipation : BodySample, Law {
  static constexpr int kBlocks = 4;
  static constexpr bool kEndOfStep = true;  // term.hpp

  // Lagged per step (begin_step): a LaggedContact's.
  Vector3 contact_point = Vector3::Zero();  // û, in B's coordinates
  double normal_force = 0.0;                // λ
  Vector3 normal = Vector3::UnitZ();        // n, world

  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;

  // Friction: r = √(2D) (friction_residual); the dashpot: r = √r s (dissipation_law.hpp).
  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // ∂C/∂q̂: the 12×12 mixed block of the local gradient with respect to the previous poses
  // of A and B (formulas above). `previous` must be the state begin_step was given.
  Eigen::Matrix<double, 12, 12> previous_jacobian(const State& q, const State& previous) const;
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;

 private:
  LaggedContact lagged() const { return {contact_point, normal_force, normal}; }
};

struct BodyFriction : BodyDissipation<SlipFriction> {
  static constexpr const char* kName = "body_friction";
};
struct BodyDamping : BodyDissipation<NormalDashpot> {
  static constexpr const char* kName = "body_damping";
};

// What the contact and friction terms of a rod's edge against B's shape share.
struct EdgeBodySample {
  std::array<int, 4> offsets{-1, -1, -1, -1};  // x_0, x_1, x_B, θ_B
  std::array<int, 2> nodes{-1, -1};            // State::points of the edge's two nodes
  int body_b = -1;                             // B
  std::shared_ptr<const Collider> shape;       // B's shape, in B's coordinates
  double stiffness = 0.0;                      // κ, N/m² (per unit length of edge)
  double radius = 0.0;                         // ρ, m
  double rest_length = 0.0;                    // ℓ̄, m: weighs the samples
};

template <int N>
struct BasicEdgeBodyContact : EdgeBodySample {
  static_assert(N >= 1 && N <= kMaxEdgeQuadraturePoints, "Gauss–Legendre points per edge");
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "edge_body_contact";
  static constexpr bool kEnergyOfState = true;
  static constexpr int kQuadraturePoints = N;

  // ρ − φ of the deepest Gauss point: > 0 when its sphere overlaps B.
  double penetration(const State& q) const;
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;

  // One residual per Gauss point: r_q = √(c_q κ) max(0, d_q).
  static constexpr int kResiduals = N;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

template <int N, class Law>
struct BasicEdgeBodyDissipation : EdgeBodySample, Law {
  static_assert(N >= 1 && N <= kMaxEdgeQuadraturePoints, "Gauss–Legendre points per edge");
  static constexpr int kBlocks = 4;
  static constexpr bool kEndOfStep = true;  // term.hpp
  static constexpr int kQuadraturePoints = N;
  std::array<LaggedContact, N> lagged{};  // per Gauss point, fixed by begin_step

  void begin_step(const State& previous, const Step& previous_step);
  // D = Σ_q D_q.
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;

  // Friction: r = √(2D) (friction_residual); the dashpot: one residual per Gauss point.
  static constexpr int kResiduals = Law::kResidualPerSample ? N : 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // ∂C/∂q̂ with respect to the previous positions of the two nodes and the previous pose of B,
  // summed over the Gauss points. `previous` must be the state begin_step was given.
  Eigen::Matrix<double, 12, 12> previous_jacobian(const State& q, const State& previous) const;
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
};

template <int N>
struct BasicEdgeBodyFriction : BasicEdgeBodyDissipation<N, SlipFriction> {
  static constexpr const char* kName = "edge_body_friction";
};
template <int N>
struct BasicEdgeBodyDamping : BasicEdgeBodyDissipation<N, NormalDashpot> {
  static constexpr const char* kName = "edge_body_damping";
};

// 4 Gauss points per edge, as EdgeContact (the rule's size is a template parameter because
// the residual count must be known at compile time).
using EdgeBodyContact = BasicEdgeBodyContact<4>;
using EdgeBodyFriction = BasicEdgeBodyFriction<4>;
using EdgeBodyDamping = BasicEdgeBodyDamping<4>;

extern template struct BasicEdgeBodyContact<1>;
extern template struct BasicEdgeBodyContact<4>;
extern template struct BasicEdgeBodyContact<8>;
extern template struct BodyDissipation<SlipFriction>;
extern template struct BodyDissipation<NormalDashpot>;
extern template struct BasicEdgeBodyDissipation<4, SlipFriction>;
extern template struct BasicEdgeBodyDissipation<4, NormalDashpot>;

// Points on the surface of a body's shape (its coordinates, the shape's pose within the body
// applied), about `spacing` (m, > 0) apart, deterministic, every point of the surface within
// `spacing` of one: a Fibonacci lattice on a sphere and on a capsule's caps, rings along its
// side; a grid on each face of a box (edges and corners included; on a rounded box, moved
// onto its rounded edges and corners); rings about the tube of a torus or link (as many along
// each half circle as its outer equator needs, and along the straight sides); rings along a
// cylinder's side (the rims included) and concentric rings on its caps about their centres;
// on a mesh's triangles, a greedy thinning of candidates a quarter spacing apart (vertices,
// then edges, then faces: corners and edges are sampled first), keeping those ≥ 0.7 spacing
// from every kept one (area-uniform). Throws ModelError(path + ".sample_spacing") if the
// spacing is not positive or would give more than `budget` points, and (path + ".shape…")
// for a shape a body may not have (validate_body_shape).
std::vector<Vector3> surface_samples(const Collider& shape, double spacing, int budget,
                                     const std::string& path);

// Which pairs of bodies touch at a state (Model::body_pairs: the candidates), for the
// couplings of a step. A pair touches when a sample of one body comes within its radius plus
// a margin of the other's shape (the margins of its two bodies added: how far each may move
// in the step). A bounding sphere about each body's centre of mass (its samples' spheres and
// its shape) rules most pairs out first. Allocation-free after construction. A kinematic
// body's shape may be unbounded (a moving plane, an inside-out shape: lib/sdf.hpp,
// validate_body_shape): its reach is +∞, so every pair with it passes the sphere test (and a
// margin of +∞ lets every sample's test pass) and is decided by its samples alone.
class TouchingPairs {
 public:
  TouchingPairs() = default;
  explicit TouchingPairs(const Model& model);

  std::size_t size() const { return pairs_.size(); }
  // The radius about body i's centre of mass that its samples' spheres and its shape fit in
  // (+∞ for an unbounded shape).
  double reach(int body) const { return reach_[body]; }
  // The two bodies of candidate pair p.
  const std::pair<int, int>& pair(int p) const { return pairs_[p]; }
  // Whether candidate pair p is within reach at q, with margin[i] (m) per body.
  bool touches(const State& q, int p, const std::vector<double>& margin) const {
    return near(q, p, margin[pairs_[p].first] + margin[pairs_[p].second]);
  }
  // touching[p] for every candidate pair p (`touching` holds at least size() entries: the
  // body pairs come first in a coupling key). Tests every pair: the reference for
  // ContactSearch's broad phase.
  void find(const State& q, const std::vector<double>& margin, std::vector<bool>& touching) const;
  // Whether pair p penetrates at q (a sample deeper than its radius).
  bool penetrates(const State& q, int p) const { return near(q, p, 0.0); }

 private:
  struct Body {
    std::vector<Vector3> samples;  // none: contact disabled
    double radius = 0.0;
    std::shared_ptr<const Collider> shape;
  };
  // The deepest reach of a sample of `a` into b's shape, ρ − φ (−∞ without one): > −margin
  // when they are within `margin` of touching.
  double overlap(const State& q, int a, int b) const;
  bool near(const State& q, int p, double margin) const;

  std::vector<std::pair<int, int>> pairs_;
  std::vector<Body> bodies_;
  std::vector<double> reach_;
};

// Which (rod, body) pairs (Model::rod_body_pairs) touch at a state, by the samples of the
// terms (EdgeBodyContact's Gauss points on every edge with a free node, and the free end
// nodes): one within the rod's contact radius plus a margin of the body's shape (the margin:
// the body's, as for TouchingPairs, plus the farthest any free node of the rod moved in the
// last step). The body's bounding sphere rules most edges out first (the segment's distance
// to its centre), and most end nodes; an unbounded shape's (reach +∞) rules none out.
// Allocation-free after construction. The entries of the pairs are `touching[first + p]`.
class TouchingRodsAndBodies {
 public:
  TouchingRodsAndBodies() = default;
  explicit TouchingRodsAndBodies(const Model& model);

  std::size_t size() const { return pairs_.size(); }
  // Whether pair p is within reach at q (`step`: the last step's node motions).
  bool touches(const State& q, const Step& step, const std::vector<double>& body_margin, std::size_t p) const;
  // touching[first + p] for every pair p: tests every pair, the reference for ContactSearch's
  // broad phase.
  void find(const State& q, const Step& step, const std::vector<double>& body_margin,
            std::vector<bool>& touching, std::size_t first) const;
  bool penetrates(const State& q, int p) const { return overlap(q, static_cast<std::size_t>(p), 0.0) > 0.0; }

 private:
  struct Pair {
    int body = -1;
    std::vector<int> nodes;                 // State::points of the rod's free nodes
    std::vector<std::array<int, 2>> edges;  // of the nodes of each edge with a free node
    std::vector<int> tips;                  // of its free end nodes
    double radius = 0.0;                    // the rod's contact radius
    double reach = 0.0;                     // the body's bounding radius (+∞: unbounded)
    std::shared_ptr<const Collider> shape;
  };
  // The deepest ρ − φ of a sample within reach + margin of the body's centre (−∞ without one).
  double overlap(const State& q, std::size_t p, double margin) const;
  std::vector<Pair> pairs_;
};

}  // namespace liedyn

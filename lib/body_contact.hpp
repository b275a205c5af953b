#pragma once
// Penalty contact between two bodies: a sample of body A against the shape of body B
// (lib/contact.hpp is the same against a static collider; shapes: lib/sdf.hpp).
//
// The sample is the point p = x_A + R_A p̄ (lever r = R_A p̄), a sphere of radius ρ; B's shape
// is an SDF φ_B in B's coordinates, so with w = p − x_B and u = R_Bᵀ w,
//   φ = φ_B(u),   d = ρ − φ,   V = ½ k max(0, d)².
// In world terms n = R_B ∇φ_B(u), N = R_B ∇²φ_B(u) R_Bᵀ, f = ∂V/∂p = −k d n and
// K = k (n nᵀ − d N). A change of the four blocks (x_A, θ_A, x_B, θ_B), each rotation by a
// left perturbation, moves u by R_Bᵀ J (δx_A, δθ_A, δx_B, δθ_B) to first order, with
//   J = [I, −hat(r), −I, hat(w)]
// (B's turn δθ_B moves the field, u = R_Bᵀ exp(−δθ_B) w: the sample seen from B turns by
// −δθ_B about x_B). So the gradient is Jᵀ f and the Hessian is Jᵀ K J plus the second-order
// terms of u (paper eq. 23 for both rotated points, and the cross terms of exp(−δθ_B) with
// the motion of p and x_B), with f in the world:
//   θ_Aθ_A: C(r, f)          θ_Bθ_B: C(w, f)          (C = rotated_point_curvature)
//   θ_B x_A: hat(f)          θ_B x_B: −hat(f)         θ_B θ_A: −hat(f) hat(r)
// and their transposes across the diagonal. As for a collider, K is indefinite where B's
// surface curves towards the sample, exact, and V is C¹ with a jump of K at d = 0.
// The internal forces are equal and opposite: the gradient's x_A and x_B parts cancel, and
// so do the torques about the origin, so contact between bodies conserves linear and angular
// momentum (tests/test_body_contact.cpp).
//
// Least-squares form, 1 residual: r = √k max(0, d), ∂r/∂(x_A, θ_A, x_B, θ_B) = −√k nᵀ J
// where d > 0, else 0.
//
// Reads q_k only: the adjoint needs no mixed block (its Hessian enters H_k). Its stencil
// spans two bodies: a pair of bodies in contact is a coupling, and joins their islands
// (solvers/islands.hpp) for the steps in which it is (Model::touching_pairs).

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "friction.hpp"
#include "model.hpp"
#include "sdf.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// What the contact and friction terms between two bodies share: a sample of A, a sphere of
// radius ρ, against B's shape with stiffness k.
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

 private:
  // φ_B's value and world-frame derivatives at the sample; w = p − x_B.
  SdfValue field(const State& q, Vector3& w, bool with_hessian) const;
};

// Smoothed Coulomb friction between a sample of body A and body B: friction.hpp's lagged law
// on the slip of the sample relative to the point of B it touched.
//
// At the start of the step, with hats for q_{k−1}: the sample at p̂ = x̂_A + R̂_A p̄ sits at
// û = R̂_Bᵀ(p̂ − x̂_B) in B's coordinates, and
//   λ = k max(0, ρ − φ_B(û)),   n = R̂_B G/‖G‖ (G = ∇φ_B(û)),   P = I − n nᵀ
// are frozen, as is û: B's material point b̄ = û. Over the step the sample moves from that
// point by d = p_B − p_A with p_A = x_A + R_A p̄ and p_B = x_B + R_B û (zero at q_{k−1}), and
//   D = μ λ f₀(‖P d‖)
// (f₀ and its slopes: friction.hpp). The potential is one of the vector between two attached
// points, so the gradient and Hessian are point_pair.hpp's mapping of
//   f = ∂D/∂d = μλ φ₁ u,   K = μλ (φ₁ P + (φ₁′/y) u uᵀ),   u = P d, y = ‖u‖,
// with the levers r_A = R_A p̄, r_B = R_B û. A body sliding over a still one feels μλ against
// its slip; the still one feels the opposite force at the same place (equal and opposite, as
// for BodyContact: momentum is conserved, only energy is dissipated).
//
// Least-squares form: r = √(2D), J = gᵀ/r (friction_residual).
//
// The adjoint: λ, n and û are functions of q̂ = (x̂_A, θ̂_A, x̂_B, θ̂_B), through
//   ∂û/∂q̂ = R̂_Bᵀ Ĵ,   Ĵ = [I, −hat(r̂_A), −I, hat(ŵ)],   ŵ = p̂ − x̂_B   (as BodyContact's J),
//   ∂λ/∂q̂ = −k Gᵀ ∂û/∂q̂,
//   ∂n/∂q̂ = (P N/‖G‖) Ĵ − [0, 0, 0, hat(n)]   (N = R̂_B ∇²φ_B(û) R̂_Bᵀ; B's turn carries n),
//   ∂d/∂q̂ = R_B ∂û/∂q̂,   ∂u/∂q̂ = P ∂d/∂q̂ − (n dᵀ + (n·d) I) ∂n/∂q̂,
//   ∂f/∂q̂ = μ φ₁ u ∂λ/∂q̂ + μλ (φ₁ I + (φ₁′/y) u uᵀ) ∂u/∂q̂,
// and the gradient C = [−f; −r_A × f; f; r_B × f] has ∂C/∂q̂ rows −∂f, −hat(r_A) ∂f, ∂f and
// hat(r_B) ∂f − hat(f) R_B ∂û/∂q̂ (r_B moves with û). Δq_{k−1} does not enter.
struct BodyFriction : BodySample {
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "body_friction";
  double coefficient = 0.0;  // μ, A's
  double epsilon = 0.0;      // ε = ε_v h, m, > 0

  // Lagged per step (begin_step).
  Vector3 contact_point = Vector3::Zero();  // û, in B's coordinates
  double normal_force = 0.0;                // λ
  Vector3 normal = Vector3::UnitZ();        // n, world

  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;

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
  SmoothedSlip slip(const State& q, Vector3& lever_b) const;
};

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
// its shape) rules most pairs out first. Allocation-free after construction. Body shapes are
// spheres, boxes and capsules (whose bounding spheres are known).
class TouchingPairs {
 public:
  TouchingPairs() = default;
  explicit TouchingPairs(const Model& model);

  std::size_t size() const { return pairs_.size(); }
  // The radius about body i's centre of mass that its samples' spheres and its shape fit in.
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

// Which (rod, body) pairs (Model::rod_body_pairs) touch at a state: a free node of the rod
// within the rod's contact radius plus a margin of the body's shape (the margin: the body's,
// as for TouchingPairs, plus the farthest any node of the rod moved in the last step). The
// body's bounding sphere rules most nodes out first. Allocation-free after construction.
// The entries of the pairs are `touching[first + p]`.
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
    std::vector<int> nodes;  // State::points of the rod's free nodes
    double radius = 0.0;     // the rod's contact radius
    double reach = 0.0;      // the body's bounding radius
    std::shared_ptr<const Collider> shape;
  };
  // The deepest ρ − φ of a node within reach + margin of the body's centre (−∞ without one).
  double overlap(const State& q, std::size_t p, double margin) const;
  std::vector<Pair> pairs_;
};

}  // namespace liedyn

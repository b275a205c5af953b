#pragma once
// Penalty contact between two rod edges, each a capsule: edge a = [a0, a1] of radius ρ_a and
// edge b = [b0, b1] of radius ρ_b (edge e of a rod joins its nodes e and e + 1, state.hpp).
//
// Why not the closest distance between the two segments: it is not differentiable where the
// segments are parallel (the closest pair is not unique and jumps as they turn through
// parallel), which is exactly how two rods lying side by side meet; a mollifier (Li et al.
// 2020) repairs that with extra terms. Here the penalty is instead integrated along each edge
// against the other segment, by a fixed Gauss–Legendre rule of N points per edge: each
// sample's distance to a segment is smooth at parallel configurations, and the potential of
// a line contact grows with the length that overlaps, with k a stiffness per unit length.
//
// Point–segment distance. For a point p and a segment [b0, b1], with e = b1 − b0,
//   t̂ = (p − b0)·e / |e|²,   t = clamp(t̂, 0, 1),   w = p − b0 − t e,   d = |w|,   n = w/d.
// At fixed t, w = Σ_i α_i x_i over the blocks x = (p, b0, b1), α = (1, −(1−t), −t).
//   Gradient: ∂d/∂x_i = α_i n. In the interior (0 < t̂ < 1) t minimises |w| so ∂d/∂t = −n·e
//     = 0 (w ⊥ e: the envelope theorem); at an end t is constant. Either way d is C¹ where
//     d > 0, t being continuous in x.
//   Hessian: with P = I − n nᵀ, dn = P dw/d and dw = Σ_j α_j dx_j − e dt. At an end dt = 0:
//     ∂²d/∂x_i∂x_j = α_i α_j P / d.
//   In the interior, differentiating w·e = 0 gives |e|² dt = Σ_j (α_j e + β_j w)·dx_j with
//   β = (0, −1, 1) (de = db1 − db0), and dα_i = −β_i dt; so, with P e = e (n ⊥ e),
//     ∂²d/∂x_i∂x_j = α_i P (α_j I − e g_jᵀ)/d − β_i n g_jᵀ = [α_i α_j P − u_i u_jᵀ] / d,
//     g_j = (α_j e + β_j w)/|e|²,   u_i = (α_i e + β_i w)/|e|,
//   symmetric as it must be: u_i u_jᵀ/d is the curvature given back because the closest
//   point slides along the segment (the Schur complement of minimising over t). It is
//   absent at an end, so the Hessian jumps where t̂ crosses 0 or 1, like a penalty's at
//   contact; the gradient does not. (In the interior the α_i α_j ê êᵀ parts of the two
//   terms cancel, ê = e/|e|: sliding the point along the segment changes nothing.)
//   Degenerate cases: |e| = 0 takes t = 0 (a point, the end formulas); d = 0 (p on the
//   segment) has no direction, and the gradient and Hessian are taken as 0 there (V is not
//   differentiable at that point, a cone as for a spring of zero length, spring.hpp).
//
// Edge–edge potential, δ = ρ_a + ρ_b, Gauss–Legendre nodes s_q on [0, 1] with weights w_q
// (Σ w_q = 1), ℓ̄_a, ℓ̄_b the edges' rest lengths (constants), a(s) = (1 − s) a0 + s a1:
//   V = Σ_q c^a_q ½ k max(0, δ − d(a(s_q), [b0, b1]))² + Σ_q c^b_q ½ k max(0, δ − d(b(s_q), [a0, a1]))²,
//   c^a_q = ½ w_q ℓ̄_a,   c^b_q = ½ w_q ℓ̄_b:
// each edge's penalty integrated along it against the other segment, the two averaged so
// that V is symmetric in a and b. The sample p = (1 − s) p0 + s p1 is linear in the nodes, so
// the chain rule only extends α and β to the blocks (a0, a1, b0, b1):
//   samples of a against [b0, b1]:  α = (1 − s, s, −(1 − t), −t),  β = (0, 0, −1, 1),
//   samples of b against [a0, a1]:  α = (−(1 − t), −t, 1 − s, s),  β = (−1, 1, 0, 0),
// with no second-order term of its own. For one sample in contact (gap γ = δ − d > 0),
// ψ = c ½ k γ², ψ' = ∂ψ/∂d = −c k γ, ψ'' = c k, and
//   gradient block i:   ψ' α_i n,
//   Hessian block ij:   α_i α_j (ψ'' n nᵀ + (ψ'/d) P) − (ψ'/d) u_i u_jᵀ   (interior),
//                       α_i α_j (ψ'' n nᵀ + (ψ'/d) P)                      (at an end).
// ψ' < 0, so the lateral part (ψ'/d) P is negative and the Hessian is indefinite, exact, and
// regularised by the Newton solver like every indefinite Hessian (solvers/newton.hpp). V is
// C¹; its Hessian jumps where a sample's gap reaches 0 and where its projection reaches an end
// of the other segment. V depends on relative positions only and is invariant under rotation:
// the four node forces sum to zero and have no net torque (contact conserves momentum).
//
// What the quadrature sees: contact only where a sample is within δ of the other segment.
// Two edges crossing at a point between samples (spaced about ℓ/N) are missed when δ is
// smaller than about half that spacing, so N should be about ℓ/δ or more for edges much
// longer than their radii; penetration() reports the deepest sample, not the segments'
// closest distance (segment_distance below).
//
// Least-squares form (contract: term.hpp), kResiduals = 2N, samples of a then samples of b:
//   r_q = √(c_q k) max(0, γ_q) = √(w_q ℓ̄ k / 2) max(0, γ_q),   ½‖r‖² = V,
//   J row q = −√(c_q k) (α_i nᵀ)_i   where γ_q > 0 and d_q > 0, else 0,
// so that Jᵀ r is evaluate()'s gradient (also at d = 0, where both take no direction).
//
// All four blocks are points (rod nodes, no rotation): `nodes` index State::points and
// `offsets` the tangent vector. Reads q_k only: the adjoint needs no mixed block.

#include <array>
#include <vector>

#include "dissipation_law.hpp"
#include "model.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// The largest number of Gauss–Legendre points per edge that BasicEdgeContact is built for.
inline constexpr int kMaxEdgeQuadraturePoints = 8;

// The n-point Gauss–Legendre rule on [0, 1] (1 ≤ n ≤ kMaxEdgeQuadraturePoints): nodes in
// increasing order, weights summing to 1; exact for polynomials of degree ≤ 2n − 1.
struct QuadratureRule {
  int size = 0;
  std::array<double, kMaxEdgeQuadraturePoints> nodes{};
  std::array<double, kMaxEdgeQuadraturePoints> weights{};
};
const QuadratureRule& gauss_legendre(int n);

// d(p, [b0, b1]) as derived above; when g (H) is non-null, writes its gradient (Hessian)
// with respect to the blocks (p, b0, b1); both are 0 where d = 0.
double point_segment_distance(const Vector3& p, const Vector3& b0, const Vector3& b1,
                              LocalGradient<3>* g = nullptr, LocalHessian<3>* H = nullptr);

// The closest distance between the segments [a0, a1] and [b0, b1], for reporting (not
// differentiated). The minimum is attained either at a pair of interior points, which is
// then the pair closest between the two lines, or at an end of one of the segments, where it
// is a point–segment distance. So the result is the smallest of the four end-to-segment
// distances and of the lines' closest pair (its parameter on a clamped to the segment, then
// b's point the closest to it, clamped; the clamped closest-points algorithm, Lumelsky 1985,
// with every end case tried rather than chosen). Every candidate is the distance of an
// actual pair of points, so it never undershoots. Where the lines are parallel an end
// attains the minimum; where they are nearly so the 2 × 2 system for a's parameter is
// ill-conditioned, but with b's point fitted to a's the error only slides the pair along
// the lines, which changes the distance by ~ sin²(angle) times the slide squared. Segments
// of zero length are points.
double segment_distance(const Vector3& a0, const Vector3& a1, const Vector3& b0,
                        const Vector3& b1);

// What the contact and friction terms of two rod edges share.
struct EdgeEdgeSample {
  std::array<int, 4> offsets{-1, -1, -1, -1};  // a0, a1, b0, b1 (tangent offsets)
  std::array<int, 4> nodes{-1, -1, -1, -1};    // indices into State::points: a0, a1, b0, b1
  double stiffness = 0.0;      // k, N/m² (per unit length of edge)
  double radius_a = 0.0;       // ρ_a, m
  double radius_b = 0.0;       // ρ_b, m
  double rest_length_a = 0.0;  // ℓ̄_a, m: weighs a's samples
  double rest_length_b = 0.0;  // ℓ̄_b, m
};

template <int N>
struct BasicEdgeContact : EdgeEdgeSample {
  static_assert(N >= 1 && N <= kMaxEdgeQuadraturePoints, "Gauss–Legendre points per edge");
  static constexpr int kBlocks = 4;
  static constexpr const char* kName = "edge_contact";
  static constexpr bool kEnergyOfState = true;
  static constexpr int kQuadraturePoints = N;

  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;
  // ρ_a + ρ_b − the smallest distance of a sample to the other segment: > 0 when overlapping.
  double penetration(const State& q) const;

  static constexpr int kResiduals = 2 * N;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

// What friction freezes per sample of an edge pair at the start of a step (formulas below).
struct LaggedEdgeSample {
  double t = 0.0;                        // t̄: the touched point's parameter on the other segment
  Vector3 separation = Vector3::Zero();  // ŵ = p̂ − (the touched point), d̂ n
  double normal_force = 0.0;             // λ (0: no friction from this sample in this step)
  Vector3 normal = Vector3::UnitZ();     // n = ŵ/d̂
};

// Friction between two edges: friction.hpp's lagged smoothed-Coulomb law per sample of the
// contact above. At the start of step k (hats for q_{k−1}) each sample p̂ = a(s_q) of one
// edge is projected on the other segment, and what the projection touched is frozen: its
// parameter t̄ (a material point of the other edge), and, with d̂ and ŵ the sample's
// distance and offset from it,
//   λ = c_q k max(0, δ − d̂)   (the sample's normal force in the contact term),
//   n = ŵ/d̂,   P = I − n nᵀ.
// Over the step the sample slips relative to that point by
//   W = Σ_i α_i(t̄) x_i − ŵ = Σ_i α_i(t̄) (x_i − x̂_i)   (α at the frozen t̄, blocks a0, a1, b0, b1),
// and D = Σ_q μ λ_q f₀(‖P W_q‖) with ε = ε_v h, μ and ε_v those of the SAMPLED rod (as a
// body's samples use their own body's; a rod with μ = 0 still feels the other's samples).
// W is linear in the nodes at fixed t̄, so with u = P W, y = ‖u‖ and f = μλ φ₁ u,
//   gradient block i:  α_i f,
//   Hessian block ij:  α_i α_j μλ (φ₁ P + (φ₁′/y) u uᵀ)   (positive semi-definite).
// Σ_i α_i = 0: the forces on the two edges are equal and opposite. They act on the rods'
// centre lines, d̂ apart along n, not at the surfaces where the capsules touch: the couple
// d̂ n × f would turn each rod about its own axis, and the rods' material frames do not feel
// it (no friction-driven rolling or twisting of a rod; its centre line is exact).
// A sample lying exactly on the other segment's axis (d̂ = 0) has no normal and is given
// λ = 0 for that step.
//
// Least-squares form: r = √(2D), J = gᵀ/r (friction_residual).
//
// The adjoint: t̄, λ, n and ŵ are functions of q̂ = (x̂_i) through the projection at q_{k−1}.
// With ê, the other segment's vector, and β as above (∂α_i/∂t = −β_i), t̄ moves in the
// interior by γ_j = (α_j ê + β_j ŵ)/|ê|² per x̂_j (at an end, γ_j = 0), and
//   ∂λ/∂x̂_j = −c k α_j n,   ∂n/∂x̂_j = P (α_j I − ê γ_jᵀ)/d̂,
//   ∂W/∂x̂_j = −α_j I − (Σ_i β_i (x_i − x̂_i)) γ_jᵀ,
//   ∂u/∂x̂_j = P ∂W/∂x̂_j − (n Wᵀ + (n·W) I) ∂n/∂x̂_j,
//   ∂f/∂x̂_j = μ φ₁ u (∂λ/∂x̂_j)ᵀ + μλ (φ₁ I + (φ₁′/y) u uᵀ) ∂u/∂x̂_j,
//   ∂(gradient block i)/∂x̂_j = α_i ∂f/∂x̂_j − β_i f γ_jᵀ,
// summed over the samples. Δq_{k−1} does not enter.
// The same per sample under either law of dissipation_law.hpp, d = W: SlipFriction (above),
// or NormalDashpot, D = ½ r (n·W)² while the sample was in contact, with ∂W/∂x_i = α_i I as for
// friction (the gradient α_i f, the Hessian α_i α_j K) and the adjoint's ∂f/∂x̂_j from the law.
// Each side's samples use their own rod's law (Law's members of side 0, a's samples, then 1).
template <int N, class Law>
struct BasicEdgeDissipation : EdgeEdgeSample {
  static_assert(N >= 1 && N <= kMaxEdgeQuadraturePoints, "Gauss–Legendre points per edge");
  static constexpr int kBlocks = 4;
  static constexpr bool kEndOfStep = true;  // term.hpp
  static constexpr int kQuadraturePoints = N;
  std::array<Law, 2> law{};                     // of a's samples, of b's
  std::array<LaggedEdgeSample, 2 * N> lagged{};  // a's samples, then b's; fixed by begin_step

  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;

  // Friction: r = √(2D) (friction_residual); the dashpot: one residual per sample.
  static constexpr int kResiduals = Law::kResidualPerSample ? 2 * N : 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // ∂C/∂q̂: the 12×12 mixed block of the local gradient with respect to the four nodes'
  // previous positions. `previous` must be the state begin_step was given.
  Eigen::Matrix<double, 12, 12> previous_jacobian(const State& q, const State& previous) const;
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
};

template <int N>
struct BasicEdgeFriction : BasicEdgeDissipation<N, SlipFriction> {
  static constexpr const char* kName = "edge_friction";
};
template <int N>
struct BasicEdgeDamping : BasicEdgeDissipation<N, NormalDashpot> {
  static constexpr const char* kName = "edge_damping";
};

// The rule's size is a template parameter because the residual count 2N must be known at
// compile time (Ceres's residual blocks); 4 points per edge by default.
using EdgeContact = BasicEdgeContact<4>;
using EdgeFriction = BasicEdgeFriction<4>;
using EdgeDamping = BasicEdgeDamping<4>;

extern template struct BasicEdgeContact<1>;
extern template struct BasicEdgeContact<2>;
extern template struct BasicEdgeContact<4>;
extern template struct BasicEdgeContact<8>;
extern template struct BasicEdgeDissipation<1, SlipFriction>;
extern template struct BasicEdgeDissipation<4, SlipFriction>;
extern template struct BasicEdgeDissipation<4, NormalDashpot>;

// Which pairs of rod edges (Model::edge_pairs: the candidates) are within reach of each
// other at a state, for the couplings and terms of a step: a pair is within reach when its
// segments come within the sum of their radii plus a margin (the largest distance a node of
// each edge moved in the last step, added). A sphere about each edge's midpoint rules most
// pairs out before the segments' distance. Allocation-free after construction. The entries
// of the candidates are `touching[first + p]` (after the body pairs of a coupling key).
class TouchingEdges {
 public:
  TouchingEdges() = default;
  explicit TouchingEdges(const Model& model);

  std::size_t size() const { return candidates_.size(); }
  // Whether candidate p is within reach at q; `step` holds the last step's node motions
  // (Step::points).
  bool touches(const State& q, const Step& step, std::size_t p) const;
  // touching[first + p] for every candidate p: tests every pair, the reference for
  // ContactSearch's broad phase.
  void find(const State& q, const Step& step, std::vector<bool>& touching, std::size_t first) const;
  bool penetrates(const State& q, int p) const { return gap(q, static_cast<std::size_t>(p)) < 0.0; }
  // The distance between the surfaces of candidate p's edges at q (segment_distance less
  // both radii; < 0 where they overlap).
  double gap(const State& q, std::size_t p) const;
  // The smallest gap over every candidate, +∞ without candidates.
  double min_separation(const State& q) const;

 private:
  struct Candidate {
    std::array<int, 4> nodes;  // State::points of a0, a1, b0, b1
    double radii;              // ρ_a + ρ_b
  };
  std::vector<Candidate> candidates_;
};

}  // namespace liedyn

// A rod's edges against a body's shape (lib/body_contact.hpp: EdgeBodyContact,
// EdgeBodyFriction, the sampled side they share with BodyContact and BodyFriction, and the
// rod–body pairs' detection TouchingRodsAndBodies), then in whole runs.
//
// Terms: value vs Lie gradient vs Lie Hessian by central differences (tests/fd_check.hpp) in
// the tangent space of the edge's two nodes and B's pose, at every rotation of fd::kAngles for
// B, with the touching Gauss point near s = 0 (8 points: s = 0.02), at s = ½ (1 point) and near
// s = 1 (8 points: s = 0.98) and the production rule's (4 points), on spheres, rounded and
// sharp boxes (anywhere, just off an edge and just off a corner) and capsules, for tiny and
// huge stiffnesses; the residual forms; the internal forces' balance (forces and torques);
// friction in stick and slip on both sides of the switch, for time steps from 1e-6 to 1 s, and
// its mixed block with respect to the previous state (the adjoint's), with a mutation check.
// Geometry is O(1) and penetrations ≫ the FD steps, as in tests/test_body_contact.cpp.
//
// Runs: a thin rod with long edges dropped across a thin bar rests on it (node samples alone
// let it through: shown on the same geometry), the bundled scenes with rods on bodies
// (RodContactScenes.* in test_rod_contact_scenes.cpp) are unchanged in kind, and the adjoint's
// gradient through an edge sliding on a body with friction.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "adjoint_check.hpp"
#include "contact_references.hpp"
#include "fd_check.hpp"
#include "lib/body_contact.hpp"
#include "lib/edge_contact.hpp"
#include "lib/incremental_potential.hpp"
#include "lib/sdf.hpp"
#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::edge_body_contact_tests {
namespace {

using fd::kAngles;
using fd::rotation_at;
using fd::trace;

// B's shapes, in B's coordinates (each posed off B's centre of mass).
std::vector<std::shared_ptr<const Collider>> shapes(std::mt19937& rng) {
  std::vector<std::shared_ptr<const Collider>> out;
  for (const Shape& shape : {Shape(SphereShape{0.8}), Shape(BoxShape{Vector3(0.6, 0.9, 1.2), 0.2}),
                             Shape(BoxShape{Vector3(0.6, 0.9, 1.2), 0.0}), Shape(CapsuleShape{0.7, 0.4})}) {
    Collider c;
    c.name = "shape";
    c.shape = shape;
    c.position = fd::random_vector(rng, 0.2);
    c.orientation = rotation_at(0.7, rng);
    out.push_back(std::make_shared<const Collider>(c));
  }
  return out;
}

// Where the touched point lies: anywhere (a random start walked onto the level set), or just
// off an edge or a corner of a box (where its SDF is a cylinder's or a sphere's about the inner
// box's edge or corner).
enum class Region { kAnywhere, kBoxEdge, kBoxCorner };

std::vector<Region> regions(const Collider& shape) {
  if (std::holds_alternative<BoxShape>(shape.shape)) return {Region::kAnywhere, Region::kBoxEdge, Region::kBoxCorner};
  return {Region::kAnywhere};
}

// A point at signed distance `target` from the shape (its coordinates). Off an edge or a
// corner `target` + rounding must be > 0, and the direction from the inner box stays ≥ 0.3 rad
// from the faces' planes, where the SDF's Hessian jumps.
Vector3 place(const Collider& shape, double target, Region region, std::mt19937& rng) {
  if (region == Region::kAnywhere) {
    return test::onto_level_set(shape, shape.position + 0.5 * fd::random_unit(rng), target);
  }
  const BoxShape& box = std::get<BoxShape>(shape.shape);
  const Vector3 inner = box.half_extents - Vector3::Constant(box.rounding);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int free_axis = region == Region::kBoxEdge ? static_cast<int>(3 * unit(rng)) % 3 : -1;
  Vector3 corner, direction;
  for (int i = 0; i < 3; ++i) {
    const double sign = unit(rng) < 0.5 ? -1.0 : 1.0;
    corner(i) = i == free_axis ? inner(i) * (1.6 * unit(rng) - 0.8) : sign * inner(i);
    direction(i) = i == free_axis ? 0.0 : sign * (0.5 + unit(rng));  // components within 1:3
  }
  const Vector3 local = corner + (target + box.rounding) * direction.normalized();
  return shape.position + shape.orientation * local;
}

// An edge [x_0, x_1] against B: State::points {x_B, x_0, x_1}, ::rotations {R_B}.
template <int N>
struct EdgeCase {
  BasicEdgeBodyContact<N> term;
  State q;
};

const fd::Dofs kDofs = {fd::point_dof(1), fd::point_dof(2), fd::point_dof(0), fd::rotation_dof(0)};

// The edge's Gauss point k at depth `depth` in B's shape (its point of `region`), the edge
// (0.35 m long, ℓ̄ = 0.4 m) crossing the surface there with t·n = slope: its points beyond s_k
// lie farther out for slope > 0, deeper for slope < 0. B turned by angle_b; κ = stiffness.
// Whether every Gauss point of the edge is at least 1 mm from where V is not smooth: its
// contact switch ρ − φ = 0, and where the shape's SDF is not C² (a box's planes q_i = 0 and,
// inside its inner box, the medial planes where two q_i tie; a capsule's planes |z| = L). The FD
// checks move a point by up to 4e-4 m (two steps of 1e-4 with levers of 2 m).
template <int N>
bool clear_of_kinks(const BasicEdgeBodyContact<N>& term, const State& q) {
  const Collider& shape = *term.shape;
  const double clearance = 1e-3;
  const QuadratureRule& rule = gauss_legendre(N);
  for (int k = 0; k < N; ++k) {
    const double s = rule.nodes[k];
    const Vector3 p = (1.0 - s) * q.points[term.nodes[0]] + s * q.points[term.nodes[1]];
    const Vector3 u = q.rotations[term.body_b].transpose() * (p - q.points[term.body_b]);
    if (std::abs(term.radius - shape.evaluate(u, false).distance) < clearance) return false;
    const Vector3 x = shape.orientation.transpose() * (u - shape.position);
    if (const auto* box = std::get_if<BoxShape>(&shape.shape)) {
      Vector3 gap = x.cwiseAbs() - (box->half_extents - Vector3::Constant(box->rounding));
      if (gap.cwiseAbs().minCoeff() < clearance) return false;
      std::sort(gap.data(), gap.data() + 3);
      if (gap(2) < 0.0 && gap(2) - gap(1) < clearance) return false;
    }
    if (const auto* capsule = std::get_if<CapsuleShape>(&shape.shape)) {
      if (std::abs(std::abs(x.z()) - capsule->half_length) < clearance) return false;
    }
  }
  return true;
}

template <int N>
EdgeCase<N> make_edge(const std::shared_ptr<const Collider>& shape, int k, double depth, double angle_b,
                      double stiffness, double slope, std::mt19937& rng, Region region = Region::kAnywhere);

// make_edge, drawn again until clear_of_kinks.
template <int N>
EdgeCase<N> smooth_edge(const std::shared_ptr<const Collider>& shape, int k, double depth, double angle_b,
                        double stiffness, double slope, std::mt19937& rng, Region region = Region::kAnywhere) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    EdgeCase<N> c = make_edge<N>(shape, k, depth, angle_b, stiffness, slope, rng, region);
    if (clear_of_kinks(c.term, c.q)) return c;
  }
  ADD_FAILURE() << "no placement clear of the kinks";
  return make_edge<N>(shape, k, depth, angle_b, stiffness, slope, rng, region);
}

template <int N>
EdgeCase<N> make_edge(const std::shared_ptr<const Collider>& shape, int k, double depth, double angle_b,
                      double stiffness, double slope, std::mt19937& rng, Region region) {
  EdgeCase<N> c;
  c.term.shape = shape;
  c.term.radius = 0.1;
  c.term.stiffness = stiffness;
  c.term.rest_length = 0.4;
  c.term.body_b = 0;
  c.term.nodes = {1, 2};
  c.term.offsets = {0, 3, 6, 9};
  const Vector3 touched = place(*shape, c.term.radius - depth, region, rng);
  const Vector3 n = shape->evaluate(touched, false).gradient;
  const Vector3 t = slope * n + std::sqrt(1.0 - slope * slope) * fd::random_perpendicular(n, rng);
  const double length = 0.35;
  const double s = gauss_legendre(N).nodes[k];
  const Matrix3 R_b = rotation_at(angle_b, rng);
  const Vector3 x_b = fd::random_vector(rng, 1.0);
  const auto world = [&](const Vector3& u) { return Vector3(x_b + R_b * u); };
  c.q.points = {x_b, world(touched - s * length * t), world(touched + (1.0 - s) * length * t)};
  c.q.rotations = {R_b};
  return c;
}

// Net force and torque about the origin of a gradient over (x_0, x_1, x_B, θ_B) at q.
std::pair<Vector3, Vector3> net_force_and_torque(const LocalGradient<4>& g, const State& q) {
  const Vector3 force = g.segment<3>(0) + g.segment<3>(3) + g.segment<3>(6);
  const Vector3 torque = q.points[1].cross(Vector3(g.segment<3>(0))) + q.points[2].cross(Vector3(g.segment<3>(3))) +
                         q.points[0].cross(Vector3(g.segment<3>(6))) + g.segment<3>(9);
  return {force, torque};
}

// Which Gauss point touches, and how the edge leaves the surface there.
struct Placement {
  int rule;  // N
  int k;
  double slope;
};
// Near s = 0, at s = ½, near s = 1, and a point of the production rule.
const std::vector<Placement> kPlacements = {{8, 0, 0.6}, {1, 0, 0.6}, {8, 7, -0.6}, {4, 1, 0.6}};

// check_term on make_edge<N>'s case, with N chosen at run time.
template <class Visit>
void with_rule(int n, Visit&& visit) {
  if (n == 1) visit(std::integral_constant<int, 1>{});
  if (n == 4) visit(std::integral_constant<int, 4>{});
  if (n == 8) visit(std::integral_constant<int, 8>{});
}

TEST(EdgeBodyContact, LieDerivativesMatchFiniteDifferencesAlongTheEdgeOnEveryShape) {
  std::mt19937 rng(61);
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const Region region : regions(*shape)) {
      for (const double angle_b : kAngles) {
        for (const Placement& at : kPlacements) {
          for (const double depth : {1e-3, 0.05}) {
            SCOPED_TRACE(trace("angle of B, rule, depth", angle_b, at.rule, depth));
            SCOPED_TRACE(trace("region, sample", static_cast<int>(region), at.k));
            with_rule(at.rule, [&](auto n) {
              const auto c = smooth_edge<decltype(n)::value>(shape, at.k, depth, angle_b, 1e4, at.slope, rng, region);
              ASSERT_GE(c.term.penetration(c.q), depth - 1e-12);
              fd::TermCheckOptions options;
              // Off a box's edge or corner the SDF is a cylinder's or a sphere's of radius ρ −
              // depth + rounding, down to 5 cm, seen through B's turn with levers |w| of 2 m:
              // the value's fourth derivatives reach ~(|w|/radius)² ≈ 1600 times its Hessian's
              // scale, so second differences at the default 1e-4 truncate by ~1e-5 of it, the
              // tolerance. At 2e-5, 25 times less; round-off 16 eps |V|/step² stays ~1e-5 |V|.
              if (region != Region::kAnywhere) options.hessian_from_value.step = 2e-5;
              EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs, options));
              ++checked;
            });
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, (1 + 3 + 3 + 1) * 9 * 4 * 2);
}

TEST(EdgeBodyContact, ExtremeStiffnessesAZeroLengthEdgeAndNoContactOutside) {
  std::mt19937 rng(62);
  for (const auto& shape : shapes(rng)) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      SCOPED_TRACE(trace("stiffness", k));
      const auto c = smooth_edge<4>(shape, 2, 0.02, 1.0, k, 0.4, rng);
      EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs));
    }
    // Both nodes at one point: every Gauss point is there, and the forces on the nodes split
    // the node-sample force by the weights Σ w_q (1 − s_q) = Σ w_q s_q = ½.
    auto point = smooth_edge<4>(shape, 0, 0.03, 2.0, 1e4, 0.6, rng);
    point.q.points[2] = point.q.points[1];
    EXPECT_TRUE(fd::check_term(point.term, point.q, kDofs));
    LocalGradient<4> g;
    point.term.evaluate(point.q, &g, nullptr);
    EXPECT_LT((g.segment<3>(0) - g.segment<3>(3)).norm(), 1e-12 * g.norm());
    // Outside (every Gauss point farther than ρ): value, gradient and Hessian exactly zero.
    const auto apart = make_edge<4>(shape, 0, -0.05, 1.0, 1e4, 0.6, rng);
    LocalHessian<4> H;
    EXPECT_EQ(apart.term.evaluate(apart.q, &g, &H), 0.0);
    EXPECT_TRUE(g.isZero(0.0));
    EXPECT_TRUE(H.isZero(0.0));
  }
}

TEST(EdgeBodyContact, InternalForcesBalanceAndTheResidualFormAgrees) {
  std::mt19937 rng(63);
  for (const auto& shape : shapes(rng)) {
    for (const double angle : {0.0, 1.0, std::numbers::pi - 1e-6, std::numbers::pi}) {
      const auto c = smooth_edge<4>(shape, 1, 0.05, angle, 1e4, 0.3, rng);
      LocalGradient<4> g;
      const double value = c.term.evaluate(c.q, &g, nullptr);
      EXPECT_GT(g.norm(), 1.0);
      // Equal and opposite forces; no net torque about the origin, Σ (x_i × g_x) + g_θ.
      const auto [force, torque] = net_force_and_torque(g, c.q);
      EXPECT_LT(force.norm(), 1e-12 * g.norm());
      EXPECT_LT(torque.norm(), 1e-12 * g.norm() * (1.0 + c.q.points[0].norm() + c.q.points[1].norm()));
      EdgeBodyContact::Residual r;
      EdgeBodyContact::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), value, 1e-12 * value);
      EXPECT_LT((J.transpose() * r - g).norm(), 1e-12 * g.norm());
      const fd::VectorFunction F = fd::residual_of(c.term);
      EXPECT_TRUE(fd::check_vector_jacobian(F, c.q, kDofs, J));
    }
  }
}

// An edge lying flat along a box's face, both nodes d deep, over the face's middle: with
// κ = k/ℓ̄ it presses with k d in all, half on each node, as one node sample of stiffness k at
// that depth would: the weights c_q κ = w_q k sum to k. Any number of Gauss points gives the
// same (a uniform depth is integrated exactly).
TEST(EdgeBodyContact, AnEdgeLyingOnAFacePressesWithKPerEdgeAsANodeSample) {
  Collider box;
  box.shape = BoxShape{Vector3(1.0, 1.0, 0.5), 0.0};
  const auto shape = std::make_shared<const Collider>(box);
  const double k = 3e3, depth = 0.01, rest = 0.4;
  State q;
  q.points = {Vector3::Zero(), Vector3(-0.15, 0.1, 0.5 + 0.1 - depth), Vector3(0.2, 0.1, 0.5 + 0.1 - depth)};
  q.rotations = {Matrix3::Identity()};
  const auto force = [&](auto n) {
    BasicEdgeBodyContact<decltype(n)::value> term;
    term.shape = shape;
    term.radius = 0.1;
    term.rest_length = rest;
    term.stiffness = k / rest;
    term.body_b = 0;
    term.nodes = {1, 2};
    LocalGradient<4> g;
    term.evaluate(q, &g, nullptr);
    EXPECT_TRUE(g.segment<3>(0).isApprox(g.segment<3>(3), 1e-12));
    return Vector3(-(g.segment<3>(0) + g.segment<3>(3)));  // on the rod
  };
  BodyContact node;
  node.shape = shape;
  node.radius = 0.1;
  node.stiffness = k;
  node.body_b = 0;
  node.at = {1, -1, Vector3::Zero()};
  LocalGradient<4> g_node;
  node.evaluate(q, &g_node, nullptr);
  const Vector3 expected = k * depth * Vector3::UnitZ();
  EXPECT_TRUE((-g_node.head<3>()).isApprox(expected, 1e-12));
  for (const Vector3& f : {force(std::integral_constant<int, 1>{}), force(std::integral_constant<int, 4>{}),
                           force(std::integral_constant<int, 8>{})}) {
    EXPECT_TRUE(f.isApprox(expected, 1e-12)) << f.transpose();
  }
}

// ----------------------------------------------------------------------------------------
// Friction.

template <class Term>
struct LaggedCase {
  Term term;
  State previous, q;
};
template <int N>
using FrictionCase = LaggedCase<BasicEdgeBodyFriction<N>>;
using DampingCase = LaggedCase<EdgeBodyDamping>;

// make_edge's contact (Gauss point 1 at 0.02 deep, the edge leaving at slope 0.3: several
// points touch) at the previous state; then B moved and turned by a small rigid motion and
// the edge carried with it, plus a slip `slip` along the touching point's lagged tangent plane
// and `normal_move` along its normal: each Gauss point slips by about `slip` relative to the
// point of B it touched (exactly on a flat face). The term's law is `law`.
template <class Term, class Law>
LaggedCase<Term> lagged_case(const std::shared_ptr<const Collider>& shape, double angle_b, double slip,
                             const Law& law, double stiffness, std::mt19937& rng, double normal_move = 0.002,
                             Region region = Region::kAnywhere) {
  constexpr int N = Term::kQuadraturePoints;
  const EdgeCase<N> start = smooth_edge<N>(shape, 1, 0.02, angle_b, stiffness, 0.3, rng, region);
  LaggedCase<Term> c;
  static_cast<EdgeBodySample&>(c.term) = start.term;
  static_cast<Law&>(c.term) = law;
  c.previous = start.q;
  c.term.begin_step(c.previous, Step{});
  const Vector3 n = c.term.lagged[1].normal;
  c.q = c.previous;
  const Matrix3 turn = so3::exp(0.1 * fd::random_unit(rng));
  c.q.rotations[0] = turn * c.previous.rotations[0];
  c.q.points[0] += fd::random_vector(rng, 0.05);
  const Vector3 move = slip * fd::random_perpendicular(n, rng) + normal_move * n;
  for (int i : {1, 2}) {
    c.q.points[i] = c.q.points[0] + turn * (c.previous.points[i] - c.previous.points[0]) + move;
  }
  return c;
}

template <int N>
FrictionCase<N> friction_case(const std::shared_ptr<const Collider>& shape, double angle_b, double slip,
                              double epsilon, double stiffness, std::mt19937& rng, double normal_move = 0.002,
                              Region region = Region::kAnywhere) {
  return lagged_case<BasicEdgeBodyFriction<N>>(shape, angle_b, slip, SlipFriction{0.4, epsilon}, stiffness, rng,
                                               normal_move, region);
}

// The tangential slip y_q of every Gauss point in contact (the lagged law's u = P d).
template <int N>
std::vector<double> slips(const FrictionCase<N>& c) {
  std::vector<double> out;
  const QuadratureRule& rule = gauss_legendre(N);
  for (int k = 0; k < N; ++k) {
    const LaggedContact& l = c.term.lagged[k];
    if (l.normal_force == 0.0) continue;
    const double s = rule.nodes[k];
    const Vector3 p = (1.0 - s) * c.q.points[1] + s * c.q.points[2];
    const Vector3 d = c.q.points[0] + c.q.rotations[0] * l.contact_point - p;
    out.push_back((d - l.normal.dot(d) * l.normal).norm());
  }
  return out;
}

// friction_case, drawn again until at least two Gauss points touch and every one's slip is
// on the side of the switch y = ε that `slip` is, 2 % clear of it (on a curved shape the
// points' normals differ, and so do their slips).
FrictionCase<4> clear_of_switch(const std::shared_ptr<const Collider>& shape, double angle_b, double slip,
                                double epsilon, std::mt19937& rng) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    const FrictionCase<4> c = friction_case<4>(shape, angle_b, slip, epsilon, 1e4, rng);
    const std::vector<double> y = slips(c);
    if (y.size() >= 2 && std::all_of(y.begin(), y.end(), [&](double yq) {
          return (yq < epsilon) == (slip < epsilon) && std::abs(yq - epsilon) > 0.02 * epsilon;
        })) {
      return c;
    }
  }
  ADD_FAILURE() << "no placement clear of the switch";
  return friction_case<4>(shape, angle_b, slip, epsilon, 1e4, rng);
}

TEST(EdgeBodyFriction, LieDerivativesInStickAndSlipMatchFiniteDifferences) {
  std::mt19937 rng(64);
  const double epsilon = 1e-2;
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const double angle_b : kAngles) {
      // Deep in the stick regime, near the switch on both sides, and sliding.
      for (const double slip : {0.3 * epsilon, 0.9 * epsilon, 1.1 * epsilon, 20.0 * epsilon}) {
        SCOPED_TRACE(trace("angle of B, slip", angle_b, slip));
        const FrictionCase<4> c = clear_of_switch(shape, angle_b, slip, epsilon, rng);
        EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs, fd::stick_zone()));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 4 * 9 * 4);
}

TEST(EdgeBodyFriction, SlidingForceIsMuLambdaAgainstTheSlipAndEqualAndOpposite) {
  std::mt19937 rng(65);
  for (const auto& shape : shapes(rng)) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      SCOPED_TRACE(trace("stiffness", k));
      const FrictionCase<4> c = friction_case<4>(shape, 2.0, 0.05, 1e-4, k, rng, 0.0);
      LocalGradient<4> g;
      c.term.evaluate(c.q, &g, nullptr);
      // Equal and opposite forces. B's acts at its material point, the slip d away from the
      // edge's: their couple, Σ d_q × f_q, is at most |d| μ Σ λ_q here (no torque on a face,
      // below, where every point's slip lies in its tangent plane).
      const auto [force, torque] = net_force_and_torque(g, c.q);
      EXPECT_LT(force.norm(), 1e-12 * g.norm());
      // Sliding (y ≈ 500 ε): each touching point feels μλ_q; all slip nearly the same way, so
      // the force on the edge is nearly μ Σ λ_q, against its slip (at most that: exactly on a
      // face).
      double mu_lambda = 0.0;
      for (const LaggedContact& l : c.term.lagged) mu_lambda += c.term.coefficient * l.normal_force;
      const Vector3 on_edge = -(g.segment<3>(0) + g.segment<3>(3));
      // The edge's motion relative to B (the same for both nodes: carried rigidly, then moved).
      const Matrix3 turn = c.q.rotations[0] * c.previous.rotations[0].transpose();
      const Vector3 slip_of_edge = c.q.points[1] - c.q.points[0] - turn * (c.previous.points[1] - c.previous.points[0]);
      EXPECT_LE(torque.norm(), slip_of_edge.norm() * mu_lambda * (1.0 + 1e-9));
      EXPECT_LE(on_edge.norm(), mu_lambda * (1.0 + 1e-12));
      EXPECT_GT(on_edge.norm(), 0.9 * mu_lambda);
      EXPECT_LT(on_edge.dot(slip_of_edge), -0.9 * on_edge.norm() * slip_of_edge.norm());
      fd::TermCheckOptions options;
      options.hessian_from_value.step = 1e-5;
      EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs, options));
    }
  }
  // On a face every point slips by the same vector: the force is μ Σ λ_q exactly.
  const auto box = shapes(rng)[2];
  std::mt19937 face_rng(66);
  for (int attempt = 0; attempt < 20; ++attempt) {
    const FrictionCase<4> c = friction_case<4>(box, 1.0, 0.05, 1e-4, 1e4, face_rng, 0.0);
    Vector3 n0 = Vector3::Zero();
    bool one_face = true;
    double mu_lambda = 0.0;
    for (const LaggedContact& l : c.term.lagged) {
      if (l.normal_force == 0.0) continue;
      if (n0.isZero()) n0 = l.normal;
      one_face = one_face && l.normal.isApprox(n0, 1e-12);
      mu_lambda += c.term.coefficient * l.normal_force;
    }
    if (!one_face) continue;
    LocalGradient<4> g;
    c.term.evaluate(c.q, &g, nullptr);
    EXPECT_NEAR((g.segment<3>(0) + g.segment<3>(3)).norm(), mu_lambda, 1e-12 * mu_lambda);
    const auto [force, torque] = net_force_and_torque(g, c.q);
    EXPECT_LT(force.norm(), 1e-12 * g.norm());
    EXPECT_LT(torque.norm(), 1e-12 * g.norm() * (1.0 + c.q.points[0].norm() + c.q.points[1].norm()));
    return;
  }
  ADD_FAILURE() << "no placement on a single face of the box";
}

TEST(EdgeBodyFriction, NoLaggedContactNoFriction) {
  std::mt19937 rng(67);
  const auto shape = shapes(rng).front();
  const EdgeCase<4> apart = make_edge<4>(shape, 0, -0.05, 1.0, 1e4, 0.6, rng);
  EdgeBodyFriction term;
  static_cast<EdgeBodySample&>(term) = apart.term;
  static_cast<SlipFriction&>(term) = SlipFriction{0.4, 1e-3};
  term.begin_step(apart.q, Step{});
  for (const LaggedContact& l : term.lagged) EXPECT_EQ(l.normal_force, 0.0);
  State q = apart.q;
  q.points[1] += Vector3(0.01, 0.02, -0.03);
  LocalGradient<4> g;
  LocalHessian<4> H;
  EXPECT_EQ(term.evaluate(q, &g, &H), 0.0);
  EXPECT_TRUE(g.isZero(0.0));
  EXPECT_TRUE(H.isZero(0.0));
  EXPECT_TRUE(term.previous_jacobian(q, apart.q).isZero(0.0));
  EdgeBodyFriction::Residual r;
  EdgeBodyFriction::ResidualJacobian J;
  term.residual(q, r, &J);
  EXPECT_EQ(r(0), 0.0);
  EXPECT_TRUE(J.isZero(0.0));
}

TEST(EdgeBodyFriction, ResidualFormReproducesValueAndGradient) {
  std::mt19937 rng(68);
  for (const auto& shape : shapes(rng)) {
    for (const double slip : {0.3e-2, 5e-2}) {
      const FrictionCase<4> c = friction_case<4>(shape, 1.3, slip, 1e-2, 1e4, rng);
      LocalGradient<4> g;
      const double D = c.term.evaluate(c.q, &g, nullptr);
      EdgeBodyFriction::Residual r;
      EdgeBodyFriction::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * D);
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12));
      const fd::VectorFunction F = fd::residual_of(c.term);
      EXPECT_TRUE(fd::check_vector_jacobian(F, c.q, kDofs, J));
    }
  }
}

TEST(EdgeBodyFriction, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  // C(q; q_{k−1}): the local gradient at the fixed current state as a function of the previous
  // node positions and B's previous pose, through every Gauss point's û, λ and n (begin_step
  // re-run at every perturbed q_{k−1}).
  std::mt19937 rng(69);
  int checked = 0, mutants = 0;
  for (const auto& shape : shapes(rng)) {
    for (const Region region : regions(*shape)) {
      for (const double angle_b : kAngles) {
        for (const double slip : {0.3e-2, 5e-2}) {
          SCOPED_TRACE(trace("angle of B, slip, region", angle_b, slip, static_cast<int>(region)));
          const FrictionCase<4> c = friction_case<4>(shape, angle_b, slip, 1e-2, 1e4, rng, 0.002, region);
          const fd::VectorFunction C = fd::lagged_gradient(c.term, c.q);
          const Eigen::MatrixXd J = c.term.previous_jacobian(c.q, c.previous);
          fd::FdOptions o;
          o.step = 2e-7;  // the stick zone's truncation, as in the Lie derivatives' test
          EXPECT_TRUE(fd::check_vector_jacobian(C, c.previous, kDofs, J, o));
          ++checked;
          // Mutations a wrong mapping would make: the two nodes' columns swapped (weights
          // 1 − s and s exchanged), B's previous turn ignored. The check must see both.
          if (angle_b == 1.0) {
            Eigen::MatrixXd swapped = J;
            swapped.middleCols<3>(0) = J.middleCols<3>(3);
            swapped.middleCols<3>(3) = J.middleCols<3>(0);
            Eigen::MatrixXd unturned = J;
            unturned.rightCols<3>().setZero();
            EXPECT_FALSE(fd::check_vector_jacobian(C, c.previous, kDofs, swapped, o));
            EXPECT_FALSE(fd::check_vector_jacobian(C, c.previous, kDofs, unturned, o));
            ++mutants;
          }
          // add_step_adjoint puts (∂C/∂q̂)ᵀ z at the two nodes' and B's entries of the
          // whole-state layout.
          const LocalGradient<4> z = LocalGradient<4>::Random();
          Eigen::VectorXd a = Eigen::VectorXd::Zero(tangent_size(c.q)), da = a;
          c.term.add_step_adjoint(c.q, c.previous, Step{}, z, a, da);
          const LocalGradient<4> expected = J.transpose() * z;
          EXPECT_TRUE(a.segment<3>(tangent_point(1)).isApprox(expected.segment<3>(0), 1e-14));
          EXPECT_TRUE(a.segment<3>(tangent_point(2)).isApprox(expected.segment<3>(3), 1e-14));
          EXPECT_TRUE(a.segment<3>(tangent_point(0)).isApprox(expected.segment<3>(6), 1e-14));
          EXPECT_TRUE(a.segment<3>(tangent_rotation(c.q, 0)).isApprox(expected.segment<3>(9), 1e-14));
          EXPECT_TRUE(da.isZero(0.0));
        }
      }
    }
  }
  EXPECT_EQ(checked, (1 + 3 + 3 + 1) * 9 * 2);
  EXPECT_EQ(mutants, (1 + 3 + 3 + 1) * 2);
}

TEST(EdgeBodyFriction, TinyAndHugeTimeStepsKeepDerivativesExactAndTheForceBounded) {
  // ε = ε_v h over h from 1e-6 to 1 s at ε_v = 1e-3 m/s. The geometry is scaled with ε (a
  // sphere of radius 100 ε off B's centre by 30 ε, an edge of 60 ε lying across it with its
  // middle 20 ε deep: every Gauss point touches, the outer ones 4.5 ε less deep), slips 0.5 ε
  // and 3 ε, so that the state's round-off stays far below FD steps that fit in the quadratic
  // zone (fd::within_zone, as for BodyFriction).
  std::mt19937 rng(70);
  for (const double h : {1e-6, 1e-3, 1.0}) {
    const double epsilon = 1e-3 * h;
    Collider sphere;
    sphere.shape = SphereShape{100.0 * epsilon};
    sphere.position = 30.0 * epsilon * fd::random_unit(rng);
    const auto shape = std::make_shared<const Collider>(sphere);
    for (const double factor : {0.5, 3.0}) {
      SCOPED_TRACE(trace("h factor", h, factor));
      EdgeBodyFriction term;
      term.shape = shape;
      term.radius = 10.0 * epsilon;
      term.rest_length = 60.0 * epsilon;
      term.stiffness = 1e4 / term.rest_length;
      term.coefficient = 0.4;
      term.epsilon = epsilon;
      term.body_b = 0;
      term.nodes = {1, 2};
      State previous;
      previous.rotations = {rotation_at(1.0, rng)};
      previous.points = {10.0 * epsilon * fd::random_unit(rng), Vector3::Zero(), Vector3::Zero()};
      const Vector3 n = fd::random_unit(rng), t = fd::random_perpendicular(n, rng);
      const Vector3 middle = previous.points[0] + previous.rotations[0] * sphere.position + (90.0 * epsilon) * n;
      previous.points[1] = middle - 30.0 * epsilon * t;
      previous.points[2] = middle + 30.0 * epsilon * t;
      term.begin_step(previous, Step{});
      for (const LaggedContact& l : term.lagged) ASSERT_GT(l.normal_force, 0.0);
      State q = previous;
      const Vector3 slip = factor * epsilon * fd::random_perpendicular(n, rng);
      q.points[1] += slip;
      q.points[2] += slip;
      // The θ rows' non-zero check is the O(1) test above.
      EXPECT_TRUE(fd::check_term(term, q, kDofs, fd::within_zone(epsilon)));
    }
    // At O(1) geometry the same ε gives a force never above Coulomb's μ Σ λ_q, whatever the slip.
    std::mt19937 rng_case(71);
    for (const double slip : {0.0, 0.5 * epsilon, epsilon, 1e3 * epsilon}) {
      const FrictionCase<4> c = friction_case<4>(shapes(rng_case)[1], 1.0, slip, epsilon, 1e4, rng_case, 0.0);
      LocalGradient<4> g;
      LocalHessian<4> H;
      c.term.evaluate(c.q, &g, &H);
      double mu_lambda = 0.0;
      for (const LaggedContact& l : c.term.lagged) mu_lambda += c.term.coefficient * l.normal_force;
      EXPECT_LE((g.segment<3>(0) + g.segment<3>(3)).norm(), mu_lambda * (1.0 + 1e-9));
      EXPECT_TRUE(H.allFinite());
    }
  }
}

// ----------------------------------------------------------------------------------------
// Damping (the dashpot law of lib/dissipation_law.hpp per Gauss point).

// τ = c/k = 30/1e4 s, h = 1 ms.
DampingCase damping_case(const std::shared_ptr<const Collider>& shape, double angle_b, double normal_move,
                         std::mt19937& rng, double h = 1e-3, double c = 30.0, Region region = Region::kAnywhere) {
  return lagged_case<EdgeBodyDamping>(shape, angle_b, 0.02, NormalDashpot{c / 1e4, h}, 1e4, rng, normal_move, region);
}

TEST(EdgeBodyDamping, LieDerivativesMatchFiniteDifferences) {
  std::mt19937 rng(164);
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const double angle_b : kAngles) {
      for (const double normal_move : {-0.004, 0.003}) {
        SCOPED_TRACE(trace("angle of B, normal move", angle_b, normal_move));
        const DampingCase c = damping_case(shape, angle_b, normal_move, rng);
        EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 4 * 9 * 2);
}

TEST(EdgeBodyDamping, AnEdgeOnAFaceFeelsItsShareOfTheMaterialsDashpot) {
  // An edge on the box's face moved 3 mm into it: each touching Gauss point's dashpot is
  // τ = c/k times its stiffness w_q ℓ̄ κ, so the force on the edge is τ ℓ̄ κ v_n n Σ_touching w_q,
  // v_n = 3 mm/h, equal and opposite on B and torque-free. (The builder's κ = k/ℓ̄ makes an
  // edge touching all along, Σ_q w_q = 1, feel the c of a node sample of its material.)
  std::mt19937 rng(165);
  const auto box = shapes(rng)[2];
  const QuadratureRule& rule = gauss_legendre(4);
  for (int attempt = 0; attempt < 50; ++attempt) {
    DampingCase d = damping_case(box, 1.0, -0.003, rng);
    Vector3 n0 = Vector3::Zero();
    bool one_face = true;
    double weight = 0.0;
    for (int k = 0; k < 4; ++k) {
      const LaggedContact& l = d.term.lagged[k];
      if (l.normal_force == 0.0) continue;
      if (n0.isZero()) n0 = l.normal;
      one_face = one_face && l.normal.isApprox(n0, 1e-12);
      weight += rule.weights[k];
    }
    if (!one_face) continue;
    // Without the sideways slide: the edge moved by exactly −3 mm along n relative to B.
    const Matrix3 turn = d.q.rotations[0] * d.previous.rotations[0].transpose();
    for (int i : {1, 2}) {
      d.q.points[i] = d.q.points[0] + turn * (d.previous.points[i] - d.previous.points[0]) - 0.003 * n0;
    }
    LocalGradient<4> g;
    d.term.evaluate(d.q, &g, nullptr);
    const Vector3 on_edge = -(g.segment<3>(0) + g.segment<3>(3));
    const double tau = 30.0 / 1e4;
    const double expected = weight * d.term.rest_length * d.term.stiffness * tau * 0.003 / 1e-3;
    EXPECT_TRUE(on_edge.isApprox(expected * n0, 1e-9)) << on_edge.transpose() << " against " << expected;
    const auto [force, torque] = net_force_and_torque(g, d.q);
    EXPECT_LT(force.norm(), 1e-12 * g.norm());
    EXPECT_LT(torque.norm(), 1e-11 * g.norm() * (1.0 + d.q.points[0].norm() + d.q.points[1].norm()));
    return;
  }
  ADD_FAILURE() << "no placement on a single face of the box";
}

TEST(EdgeBodyDamping, ResidualFormHasOneResidualPerGaussPoint) {
  std::mt19937 rng(166);
  for (const auto& shape : shapes(rng)) {
    for (const double normal_move : {-0.004, 0.0, 0.003}) {
      const DampingCase c = damping_case(shape, 1.3, normal_move, rng);
      LocalGradient<4> g;
      const double D = c.term.evaluate(c.q, &g, nullptr);
      EdgeBodyDamping::Residual r;
      EdgeBodyDamping::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      static_assert(EdgeBodyDamping::kResiduals == 4);
      for (int k = 0; k < 4; ++k) {
        if (c.term.lagged[k].normal_force == 0.0) {
          EXPECT_EQ(r(k), 0.0);
        }
      }
      EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * D);
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::residual_of(c.term), c.q, kDofs, J));
    }
  }
}

TEST(EdgeBodyDamping, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  std::mt19937 rng(167);
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const Region region : regions(*shape)) {
      for (const double angle_b : kAngles) {
        SCOPED_TRACE(trace("angle of B, region", angle_b, static_cast<int>(region)));
        const DampingCase c = damping_case(shape, angle_b, -0.004, rng, 1e-3, 30.0, region);
        const Eigen::MatrixXd J = c.term.previous_jacobian(c.q, c.previous);
        EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(c.term, c.q), c.previous, kDofs, J));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, (1 + 3 + 3 + 1) * 9);
}

TEST(EdgeBodyDamping, TinyAndHugeTimeStepsAndDampingsKeepDerivativesExact) {
  std::mt19937 rng(168);
  const auto shape = shapes(rng)[1];
  for (const double h : {1e-6, 1e-3, 1.0}) {
    for (const double c : {1e-3, 1.0, 1e6}) {
      SCOPED_TRACE(trace("h c", h, c));
      const DampingCase d = damping_case(shape, 2.0, -0.004, rng, h, c);
      EXPECT_TRUE(fd::check_term(d.term, d.q, kDofs));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(d.term, d.q), d.previous, kDofs,
                                            d.term.previous_jacobian(d.q, d.previous)));
    }
  }
}

// ----------------------------------------------------------------------------------------
// Rods on bodies in whole runs.

// A thin bar, a kinematic capsule of radius R = 2 cm along y with its axis at z = 0.1 m, and a
// rod of 5 edges of ℓ̄ = 10 cm and radius ρ = 5 mm across it at height `height`, the bar under
// the middle of the middle edge: the nodes nearest to it are 5 cm to either side, farther
// than R + ρ = 2.5 cm; the edge's middle Gauss points 1.7 cm, nearer.
Scene bar_and_rod(double height, const std::string& rod_extra = "") {
  const std::string h = std::to_string(height);
  return parse_scene(R"({"time_step": 0.002, "frames": 300, "gravity": [0, 0, -9.81],
      "bodies": [{"name": "bar", "position": [0, 0, 0.1], "orientation": [0.7071067811865476, -0.7071067811865476, 0, 0],
                  "kinematic": {"linear_velocity": [0, 0, 0]},
                  "contact": {"stiffness": 1e4, "shape": {"type": "capsule", "half_length": 0.2, "radius": 0.02}}}],
      "rods": [{"name": "rod", "shape": {"type": "line", "start": [-0.25, 0, )" + h + R"(], "end": [0.25, 0, )" + h +
                         R"(], "edges": 5},
                "mass": 0.05, "radius": 0.005, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                "bending_stiffness": [1e-3, 1e-3, 1e-3], "contact": {"stiffness": 1e4, "friction": 0.5})" +
                         rod_extra + "}]}",
                     "rod_on_bar.json");
}

// The terms of a touching (rod, body) pair: one EdgeBodyContact (and, with friction, one
// EdgeBodyFriction) per edge with a free node, a BodyContact (and BodyFriction) per free end
// node, with κ = k/ℓ̄; none on an edge whose nodes are both clamped, none on a clamped tip.
TEST(EdgeBodyContactScenes, APairTouchingHasTermsOnItsFreeEdgesAndTips) {
  const Scene scene = bar_and_rod(0.1, R"(, "fixed_nodes": [0, 1])");
  const Model& model = scene.model;
  std::vector<bool> key;
  model.coupling_key(1, {true}, key);  // no joints, body pairs or edge pairs: the one rod–body pair
  const std::vector<Component> components = build_components(model, key);
  ASSERT_EQ(components.size(), 1u);  // the bar is kinematic: the rod's
  const IncrementalPotential& p = components[0].potential;
  ASSERT_EQ(p.terms<EdgeBodyContact>().size(), 4u);
  EXPECT_EQ(p.terms<EdgeBodyFriction>().size(), 4u);
  ASSERT_EQ(p.terms<BodyContact>().size(), 1u);
  EXPECT_EQ(p.terms<BodyFriction>().size(), 1u);
  const EdgeBodyContact& first = p.terms<EdgeBodyContact>().front();
  EXPECT_EQ(first.nodes[0], model.rod_point(0, 1));
  EXPECT_EQ(first.offsets[0], -1);  // node 1 is clamped
  EXPECT_GE(first.offsets[1], 0);
  EXPECT_EQ(first.offsets[2], -1);  // a kinematic body: no DOF
  EXPECT_EQ(first.offsets[3], -1);
  EXPECT_NEAR(first.stiffness * first.rest_length, 1e4, 1e-9);
  EXPECT_NEAR(first.rest_length, 0.1, 1e-12);
  EXPECT_EQ(p.terms<BodyContact>().front().at.point, model.rod_point(0, 5));
  EXPECT_EQ(p.terms<BodyContact>().front().stiffness, 1e4);
}

// The bar's surface to the rod's centreline, from 1000 points along each edge: the true
// separation of the capsules is this less ρ (negative: they overlap).
double centreline_clearance(const Model& model, const State& q) {
  const Collider& bar = *model.bodies[0].shape;
  double nearest = std::numeric_limits<double>::infinity();
  for (int e = 0; e < model.rods[0].edge_count(); ++e) {
    const Vector3& a = q.points[model.rod_point(0, e)];
    const Vector3& b = q.points[model.rod_point(0, e + 1)];
    for (int i = 0; i <= 1000; ++i) {
      const Vector3 p = a + (b - a) * (i / 1000.0);
      nearest = std::min(nearest, bar.evaluate(q.rotations[0].transpose() * (p - q.points[0]), false).distance);
    }
  }
  return nearest;
}

// The deepest Gauss point of rod 0's edges in body 0's shape (ρ − φ, EdgeBodyContact's
// penetration), and of its nodes as node samples (BodyContact's, the old rule's).
double deepest_edge_sample(const Model& model, const State& q) {
  const RodDiscretization rod = discretize(model.rods[0]);
  double deepest = -std::numeric_limits<double>::infinity();
  for (int e = 0; e < model.rods[0].edge_count(); ++e) {
    EdgeBodyContact edge;
    edge.shape = model.bodies[0].shape;
    edge.radius = model.rods[0].contact.radius;
    edge.body_b = 0;
    edge.nodes = {model.rod_point(0, e), model.rod_point(0, e + 1)};
    edge.rest_length = rod.rest_length[e];
    deepest = std::max(deepest, edge.penetration(q));
  }
  return deepest;
}
double deepest_node_sample(const Model& model, const State& q) {
  double deepest = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < model.rods[0].node_count(); ++i) {
    BodyContact node;
    node.shape = model.bodies[0].shape;
    node.radius = model.rods[0].contact.radius;
    node.body_b = 0;
    node.at = {model.rod_point(0, i), -1, Vector3::Zero()};
    deepest = std::max(deepest, node.penetration(q));
  }
  return deepest;
}

// The old rule, node samples only, would let the rod through the bar: lowered through it in
// steps of 1 mm, from 4 cm above the axis to 4 cm below, no node ever comes within ρ of the
// bar (no force would resist), while the edges' Gauss points do, the deepest by R + ρ −
// 1.7 cm = 8 mm with the rod on the axis, and the pair is detected.
TEST(EdgeBodyContactScenes, NodeSamplesAloneWouldLetARodThroughABarThatItsEdgesHold) {
  const Scene scene = bar_and_rod(0.1);
  const Model& model = scene.model;
  ASSERT_EQ(model.rod_body_pairs().size(), 1u);
  const TouchingRodsAndBodies touching(model);
  double deepest_node = -std::numeric_limits<double>::infinity(), deepest_edge = deepest_node;
  int detected = 0;
  for (int mm = -40; mm <= 40; ++mm) {
    State q = model.initial_state();
    for (int i = 0; i < model.rods[0].node_count(); ++i) q.points[model.rod_point(0, i)].z() = 0.1 + 1e-3 * mm;
    deepest_node = std::max(deepest_node, deepest_node_sample(model, q));
    const double edges = deepest_edge_sample(model, q);
    deepest_edge = std::max(deepest_edge, edges);
    EXPECT_EQ(touching.penetrates(q, 0), edges > 0.0) << mm;
    detected += touching.penetrates(q, 0);
  }
  EXPECT_LT(deepest_node, -0.02);  // the nodes stay 2 cm clear of touching
  EXPECT_NEAR(deepest_edge, 0.025 - 0.5 * (gauss_legendre(4).nodes[2] - gauss_legendre(4).nodes[1]) * 0.1, 1e-9);
  EXPECT_GT(detected, 30);
  std::cout << "rod lowered through the bar: deepest node sample " << deepest_node << " m, deepest edge sample "
            << deepest_edge << " m\n";
}

// The rod dropped onto the bar (its middle Gauss points 2 mm above touching) rests across it:
// its centreline stays above the bar's axis, and the bar pokes into the rod's capsule by no
// more than the header's bound for samples Δ = 0.34 ℓ̄ apart, (R + ρ) − √((R + ρ)² − Δ²/4) =
// 6.7 mm, give or take the penalty's give: 0.3 mm at rest, 1 mm while it lands.
// TouchingRodsAndBodies's margin sees the pair before it touches: the rod 12 mm from touching
// is not touching at rest, and is when a node moved 2 cm in the last step.
TEST(EdgeBodyContactScenes, AThinRodWithLongEdgesDroppedAcrossABarRestsOnIt) {
  const double R_rho = 0.025, half_gap = 0.5 * (gauss_legendre(4).nodes[2] - gauss_legendre(4).nodes[1]) * 0.1;
  const Scene scene = bar_and_rod(0.1 + std::sqrt(std::pow(R_rho + 0.002, 2) - half_gap * half_gap));
  const Model& model = scene.model;
  const TouchingRodsAndBodies touching(model);
  State above = model.initial_state();
  for (int i = 0; i < model.rods[0].node_count(); ++i) {
    above.points[model.rod_point(0, i)].z() = 0.1 + std::sqrt(std::pow(R_rho + 0.012, 2) - half_gap * half_gap);
  }
  std::vector<bool> found(1, false);
  Step still;
  still.points.assign(model.point_count(), Vector3::Zero());
  touching.find(above, still, {0.0}, found, 0);
  EXPECT_FALSE(found[0]);
  Step moved = still;
  moved.points[model.rod_point(0, 3)] = Vector3(0, 0, -0.02);
  touching.find(above, moved, {0.0}, found, 0);
  EXPECT_TRUE(found[0]);
  touching.find(model.initial_state(), still, {0.0}, found, 0);
  EXPECT_FALSE(found[0]);  // 2 mm from touching
  touching.find(model.initial_state(), moved, {0.0}, found, 0);
  EXPECT_TRUE(found[0]);

  Simulator sim(model, scene.solver);
  double clearance = std::numeric_limits<double>::infinity();
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << k << ": " << r.message;
    clearance = std::min(clearance, centreline_clearance(model, sim.state()));
  }
  const double at_rest = centreline_clearance(model, sim.state());
  const double bound = R_rho - std::sqrt(R_rho * R_rho - half_gap * half_gap);
  const double radius = 0.005;
  EXPECT_LT(radius - at_rest, bound + 3e-4);  // the overlap at rest, ρ − clearance
  EXPECT_GT(radius - at_rest, bound - 3e-4);  // the bar does sit between the two samples
  EXPECT_LT(radius - clearance, bound + 1e-3);
  const Vector3 middle = 0.5 * (sim.state().points[model.rod_point(0, 2)] + sim.state().points[model.rod_point(0, 3)]);
  EXPECT_GT(middle.z(), 0.1 + 0.015);  // resting on top of the bar, not through it
  EXPECT_LT(middle.z(), 0.1 + 0.025);
  EXPECT_EQ(sim.contact_pairs(), 1);
  std::cout << "rod on the bar: overlap of bar and capsule " << radius - at_rest << " m at rest, " << radius - clearance
            << " m at most (bound " << bound << " m), middle of the middle edge at z = " << middle.z() << " m\n";
}

// The adjoint through edges sliding with friction on a body: a rod of 4 edges of 12.5 cm
// thrown sideways and down onto a box resting on the floor, its middle node (no tip: only the
// edges sample there) landing on the box's top and sliding on, γ its initial node velocities.
TEST(EdgeBodyContactAdjoint, TheGradientRunsBackThroughEdgesSlidingOnABody) {
  std::string velocities;
  for (int i = 0; i <= 4; ++i) velocities += std::string(i ? ", " : "") + "[0.6, 0, -0.5]";
  const Scene scene = parse_scene(R"({"time_step": 0.002, "frames": 80, "gravity": [0, 0, -9.81],
      "solver": {"tolerance": 1e-12, "max_iterations": 100},
      "colliders": [{"type": "plane"}],
      "bodies": [{"name": "box", "density": 500, "position": [0, 0, 0.0505],
                  "contact": {"stiffness": 1e4, "radius": 0.001,
                              "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.05]}, "sample_spacing": 0.05}}],
      "rods": [{"name": "thrown", "shape": {"type": "line", "start": [-0.25, 0.02, 0.125], "end": [0.25, 0.02, 0.125], "edges": 4},
                "mass": 0.05, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                "bending_stiffness": [1e-3, 1e-3, 1e-3], "node_velocities": [)" + velocities + R"(],
                "contact": {"stiffness": 2e3, "friction": 0.5}}],
      "optimization": {
        "parameters": [{"kind": "rod_node_velocities", "rod": "thrown"}],
        "objective": [{"term": "point_targets", "rod": "thrown", "frame": -1,
                       "polyline": [[0.1, -0.2, 0.2], [0.1, 0.2, 0.2]]}]}})",
                                  "edges_on_box_adjoint.json");
  const Model& model = scene.model;
  Simulator forward(model, scene.solver);
  int touching = 0;
  double landed_at = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < scene.frames; ++k) {
    ASSERT_TRUE(forward.step().converged()) << k;
    if (deepest_edge_sample(model, forward.state()) <= 0.0) continue;
    ++touching;
    if (std::isnan(landed_at)) landed_at = forward.state().points[model.rod_point(0, 2)].x();
  }
  ASSERT_GT(touching, 40);  // its edges touched the box for most of the run
  EXPECT_GT(forward.state().points[model.rod_point(0, 2)].x() - landed_at, 0.01);  // and slid on it
  EXPECT_TRUE(test::gradient_agrees(scene));
}

}  // namespace
}  // namespace liedyn::edge_body_contact_tests

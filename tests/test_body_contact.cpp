// Contact between two bodies (lib/body_contact.hpp): a sample of A against B's shape, and its
// friction. Value vs Lie gradient vs Lie Hessian by central differences in the tangent space
// of both poses (tests/fd_check.hpp), for spheres, rounded boxes and capsules (posed within
// B), at every rotation of fd::kAngles for A and for B, over penetrations and stiffnesses
// from tiny to huge, sticking and sliding, time steps from tiny to huge; the residual forms;
// friction's mixed block with respect to the previous poses (the adjoint's); and the internal
// forces' balance (no net force or torque: what makes contact between bodies conserve
// momentum).
//
// Geometry is O(1) and penetrations ≫ the FD steps, as in tests/test_contact.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "contact_references.hpp"
#include "fd_check.hpp"
#include "mesh_models.hpp"
#include "lib/body_contact.hpp"
#include "lib/mesh_sdf.hpp"
#include "lib/sdf.hpp"
#include "lib/so3.hpp"

namespace liedyn::body_contact_tests {
namespace {

using test::box_mesh;

using fd::kAngles;
using fd::rotation_at;
using fd::trace;

// B's shapes, in B's coordinates (each posed off B's centre of mass).
std::vector<std::shared_ptr<const Collider>> shapes(std::mt19937& rng) {
  std::vector<std::shared_ptr<const Collider>> out;
  for (const Shape& shape : {Shape(SphereShape{0.8}), Shape(BoxShape{Vector3(0.6, 0.9, 1.2), 0.2}),
                             Shape(CapsuleShape{0.7, 0.4})}) {
    Collider c;
    c.name = "shape";
    c.shape = shape;
    c.position = fd::random_vector(rng, 0.2);
    c.orientation = rotation_at(0.7, rng);
    out.push_back(std::make_shared<const Collider>(c));
  }
  return out;
}

// A point at signed distance `target` from the shape (its coordinates), found by walking
// along the SDF's gradient from a random start.
Vector3 place(const Collider& shape, double target, std::mt19937& rng) {
  return test::onto_level_set(shape, shape.position + 0.5 * fd::random_unit(rng), target);
}

struct Pair {
  BodyContact term;
  State q;
};

// Body A (0) with a sample at p̄ = (0.3, −0.4, 0.2) touching body B (1) at depth `depth`,
// A turned by angle_a and B by angle_b.
Pair make_pair(const std::shared_ptr<const Collider>& shape, double depth, double angle_a,
               double angle_b, double stiffness, std::mt19937& rng) {
  Pair c;
  c.term.shape = shape;
  c.term.radius = 0.1;
  c.term.stiffness = stiffness;
  c.term.body_b = 1;
  c.term.offsets = {0, 3, 6, 9};
  const Vector3 local(0.3, -0.4, 0.2);
  c.term.at = {0, 0, local};
  const Matrix3 R_b = rotation_at(angle_b, rng);
  const Vector3 x_b = fd::random_vector(rng, 1.0);
  const Vector3 p = x_b + R_b * place(*shape, c.term.radius - depth, rng);
  const Matrix3 R_a = rotation_at(angle_a, rng);
  c.q.points = {p - R_a * local, x_b};
  c.q.rotations = {R_a, R_b};
  return c;
}

const fd::Dofs kDofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1), fd::rotation_dof(1)};

// Net force and torque about the origin of a 4-block gradient (x_A, θ_A, x_B, θ_B) at q.
std::pair<Vector3, Vector3> net_force_and_torque(const LocalGradient<4>& g, const State& q) {
  const Vector3 force = g.segment<3>(0) + g.segment<3>(6);
  const Vector3 torque = q.points[0].cross(Vector3(g.segment<3>(0))) + g.segment<3>(3) +
                         q.points[1].cross(Vector3(g.segment<3>(6))) + g.segment<3>(9);
  return {force, torque};
}

TEST(BodyContact, LieDerivativesOfBothPosesMatchFiniteDifferences) {
  std::mt19937 rng(41);
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const double angle_a : kAngles) {
      for (const double angle_b : kAngles) {
        for (const double depth : {1e-3, 0.05}) {
          SCOPED_TRACE(trace("angles of A and B, depth", angle_a, angle_b, depth));
          const Pair c = make_pair(shape, depth, angle_a, angle_b, 1e4, rng);
          ASSERT_NEAR(c.term.penetration(c.q), depth, 1e-12);
          EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 9 * 9 * 2);
}

TEST(BodyContact, ExtremeStiffnessesAndNoContactOutside) {
  std::mt19937 rng(42);
  for (const auto& shape : shapes(rng)) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      SCOPED_TRACE(trace("stiffness", k));
      const Pair c = make_pair(shape, 0.02, 1.0, 2.5, k, rng);
      EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs));
    }
    // Outside (φ > ρ): value, gradient and Hessian exactly zero.
    const Pair apart = make_pair(shape, -0.05, 1.0, 2.5, 1e4, rng);
    LocalGradient<4> g;
    LocalHessian<4> H;
    EXPECT_EQ(apart.term.evaluate(apart.q, &g, &H), 0.0);
    EXPECT_TRUE(g.isZero(0.0));
    EXPECT_TRUE(H.isZero(0.0));
  }
}

TEST(BodyContact, InternalForcesBalanceAndTheResidualFormAgrees) {
  std::mt19937 rng(43);
  for (const auto& shape : shapes(rng)) {
    for (const double angle : {0.0, 1.0, std::numbers::pi - 1e-6}) {
      const Pair c = make_pair(shape, 0.05, angle, 2.0 * angle, 1e4, rng);
      LocalGradient<4> g;
      const double value = c.term.evaluate(c.q, &g, nullptr);
      // Equal and opposite forces; no net torque about the origin, Σ (x_i × g_x + g_θ).
      const auto [force, torque] = net_force_and_torque(g, c.q);
      EXPECT_LT(force.norm(), 1e-12 * g.norm());
      EXPECT_LT(torque.norm(), 1e-12 * g.norm() * (1.0 + c.q.points[0].norm() + c.q.points[1].norm()));
      EXPECT_GT(g.norm(), 1.0);
      BodyContact::Residual r;
      BodyContact::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), value, 1e-12 * value);
      EXPECT_LT((J.transpose() * r - g).norm(), 1e-12 * g.norm());
    }
  }
}

// ----------------------------------------------------------------------------------------
// Surface samples.

TEST(SurfaceSamples, LieOnTheShapeAndCoverItAtTheirSpacing) {
  std::mt19937 rng(51);
  const double spacing = 0.05;
  struct Case {
    Shape shape;
    double area;  // of the surface, m²
  };
  const double pi = std::numbers::pi;
  for (const Case& k :
       {Case{SphereShape{0.3}, 4 * pi * 0.09},
        Case{BoxShape{Vector3(0.2, 0.3, 0.1), 0.0}, 8 * 0.11},
        Case{BoxShape{Vector3(0.2, 0.3, 0.1), 0.03}, 0.0}, Case{CapsuleShape{0.25, 0.1}, 0.0},
        Case{CapsuleShape{0.0, 0.1}, 0.0}, Case{TorusShape{0.25, 0.1}, 4 * pi * pi * 0.025},
        Case{TorusShape{0.3, 0.02}, 4 * pi * pi * 0.006},  // a tube thinner than the spacing
        Case{LinkShape{0.2, 0.2, 0.07}, 2 * pi * 0.07 * (0.8 + 2 * pi * 0.2)},
        Case{CylinderShape{0.15, 0.3}, 2 * pi * 0.15 * (0.6 + 0.15)},
        Case{CylinderShape{0.3, 0.01}, 2 * pi * 0.3 * (0.02 + 0.3)},      // a disc
        Case{CylinderShape{0.02, 0.2}, 2 * pi * 0.02 * (0.4 + 0.02)}}) {  // a needle
    Collider c;
    c.shape = k.shape;
    c.position = fd::random_vector(rng, 0.3);
    c.orientation = rotation_at(1.2, rng);
    const std::vector<Vector3> samples = surface_samples(c, spacing, 100000, "bodies[0].contact");
    ASSERT_GT(samples.size(), 20u);
    EXPECT_EQ(samples, surface_samples(c, spacing, 100000, "bodies[0].contact"));  // deterministic
    // About `spacing` apart: about one sample per spacing² (rings about a fat torus crowd
    // on its inner side).
    if (k.area > 0.0) {
      EXPECT_GE(samples.size(), k.area / (spacing * spacing));
      EXPECT_LE(samples.size(), 3.0 * k.area / (spacing * spacing) + 40);
    }
    double farthest_gap = 0.0;
    for (const Vector3& p : samples) EXPECT_NEAR(c.evaluate(p, false).distance, 0.0, 1e-12);
    // Every point of the surface (random points walked onto it) has a sample within about
    // the spacing: the lattices' and grids' largest gaps are below it. The points start in a
    // box about the shape, reaching the inner side of a torus or link through its hole.
    for (int i = 0; i < 1000; ++i) {
      Vector3 p = c.position + c.orientation * fd::random_vector(rng, 0.6);
      for (int j = 0; j < 50; ++j) {
        const SdfValue s = c.evaluate(p, false);
        p -= s.distance * s.gradient;
      }
      ASSERT_NEAR(c.evaluate(p, false).distance, 0.0, 1e-12);
      double nearest = std::numeric_limits<double>::infinity();
      for (const Vector3& q : samples) nearest = std::min(nearest, (q - p).norm());
      farthest_gap = std::max(farthest_gap, nearest);
    }
    EXPECT_LT(farthest_gap, spacing) << k.shape.index();
  }
}

// A mesh's samples: on its triangles, ≥ 0.7 spacing apart (a thinning), every point of its
// triangles within the spacing of one, its corners sampled, deterministic; one per ~(0.7
// spacing)² of area. A box mesh (large faces), and a finely meshed sphere (triangles much
// smaller than the spacing).
// A UV sphere of radius r: `rings` latitudes (poles apart), `around` longitudes.
TriangleMesh uv_sphere(double r, int rings, int around) {
  TriangleMesh m;
  m.vertices.emplace_back(0, 0, r);
  for (int i = 1; i < rings; ++i) {
    const double theta = std::numbers::pi * i / rings;
    for (int j = 0; j < around; ++j) {
      const double phi = 2 * std::numbers::pi * j / around;
      m.vertices.emplace_back(r * std::sin(theta) * std::cos(phi),
                              r * std::sin(theta) * std::sin(phi), r * std::cos(theta));
    }
  }
  m.vertices.emplace_back(0, 0, -r);
  const int south = static_cast<int>(m.vertices.size()) - 1;
  const auto at = [around](int i, int j) { return 1 + (i - 1) * around + (j % around); };
  for (int j = 0; j < around; ++j) {
    m.triangles.push_back({0, at(1, j), at(1, j + 1)});
    for (int i = 1; i + 1 < rings; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
    m.triangles.push_back({south, at(rings - 1, j + 1), at(rings - 1, j)});
  }
  return m;
}

double triangle_distance(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
  // The nearest point of the plane if it falls inside, else of the three edges.
  const Vector3 n = (b - a).cross(c - a).normalized();
  const Vector3 q = p - n.dot(p - a) * n;
  const bool inside = n.dot((b - a).cross(q - a)) >= 0 && n.dot((c - b).cross(q - b)) >= 0 &&
                      n.dot((a - c).cross(q - c)) >= 0;
  if (inside) return std::abs(n.dot(p - a));
  const auto segment = [&p](const Vector3& u, const Vector3& v) {
    const double t = std::clamp((p - u).dot(v - u) / (v - u).squaredNorm(), 0.0, 1.0);
    return (p - u - t * (v - u)).norm();
  };
  return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

TEST(SurfaceSamples, OnAMeshAreThinnedCandidatesOnItsTriangles) {
  std::mt19937 rng(61);
  const double spacing = 0.05;
  for (const TriangleMesh& mesh : {box_mesh(Vector3(0.2, 0.15, 0.1)), uv_sphere(0.2, 40, 80)}) {
    Collider c;
    c.shape = MeshShape{std::make_shared<const GridSdf>(mesh, 0.02, 0.04),
                        std::make_shared<const TriangleMesh>(mesh)};
    c.position = fd::random_vector(rng, 0.3);
    c.orientation = rotation_at(2.0, rng);
    const std::vector<Vector3> samples = surface_samples(c, spacing, 100000, "bodies[0].contact");
    EXPECT_EQ(samples, surface_samples(c, spacing, 100000, "bodies[0].contact"));
    std::vector<Vector3> local;
    for (const Vector3& p : samples) local.push_back(c.orientation.transpose() * (p - c.position));
    double area = 0.0;
    std::vector<double> cumulative;
    for (const auto& t : mesh.triangles) {
      area += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]])
                        .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]])
                        .norm();
      cumulative.push_back(area);
    }
    EXPECT_GE(local.size(), area / (spacing * spacing));
    EXPECT_LE(local.size(), 3.0 * area / (spacing * spacing));
    for (std::size_t i = 0; i < local.size(); ++i) {
      double on = std::numeric_limits<double>::infinity();
      for (const auto& t : mesh.triangles) {
        on = std::min(on, triangle_distance(local[i], mesh.vertices[t[0]], mesh.vertices[t[1]],
                                            mesh.vertices[t[2]]));
      }
      EXPECT_LE(on, 1e-12) << local[i].transpose();
      for (std::size_t j = 0; j < i; ++j) EXPECT_GE((local[i] - local[j]).norm(), 0.7 * spacing);
    }
    // The box's corners are samples.
    if (mesh.vertices.size() == 8) {
      for (const Vector3& v : mesh.vertices) {
        double nearest = std::numeric_limits<double>::infinity();
        for (const Vector3& q : local) nearest = std::min(nearest, (q - v).norm());
        EXPECT_LE(nearest, 1e-12) << v.transpose();
      }
    }
    // Area-uniform random points of the triangles (and the vertices) have a sample within the
    // spacing.
    double farthest_gap = 0.0;
    std::vector<Vector3> probes = mesh.vertices;
    for (int i = 0; i < 2000; ++i) {
      const double pick = std::uniform_real_distribution<double>(0, area)(rng);
      const auto& t = mesh.triangles[std::lower_bound(cumulative.begin(), cumulative.end(), pick) -
                                     cumulative.begin()];
      double u = std::uniform_real_distribution<double>(0, 1)(rng),
             v = std::uniform_real_distribution<double>(0, 1)(rng);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      probes.push_back(mesh.vertices[t[0]] + u * (mesh.vertices[t[1]] - mesh.vertices[t[0]]) +
                       v * (mesh.vertices[t[2]] - mesh.vertices[t[0]]));
    }
    for (const Vector3& p : probes) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const Vector3& q : local) nearest = std::min(nearest, (q - p).norm());
      farthest_gap = std::max(farthest_gap, nearest);
    }
    EXPECT_LT(farthest_gap, spacing);
  }
}

// The radius the contact search bounds a body by (TouchingPairs::reach): its samples' spheres
// and every point where its shape's φ ≤ 0 lie within it, and it is not much larger.
TEST(SurfaceSamples, AndTheShapeFitInTheBodysReach) {
  std::mt19937 rng(71);
  const TriangleMesh box = box_mesh(Vector3(0.2, 0.15, 0.1));
  struct Case {
    Shape shape;
    double extent;  // the largest ‖x‖ of the solid about its own centre
  };
  for (const Case& k : {Case{TorusShape{0.25, 0.1}, 0.35}, Case{LinkShape{0.2, 0.2, 0.07}, 0.47},
                        Case{CylinderShape{0.15, 0.3}, std::hypot(0.15, 0.3)},
                        Case{MeshShape{std::make_shared<const GridSdf>(box, 0.02, 0.04),
                                       std::make_shared<const TriangleMesh>(box)},
                             Vector3(0.2, 0.15, 0.1).norm()}}) {
    Model model;
    RigidBody body;
    body.contact.stiffness = 1.0;
    body.contact.radius = 0.01;
    Collider c;
    c.shape = k.shape;
    c.position = Vector3(0.05, -0.02, 0.03);
    c.orientation = rotation_at(1.0, rng);
    body.contact_points = surface_samples(c, 0.05, 100000, "bodies[0].contact");
    body.shape = std::make_shared<const Collider>(c);
    model.bodies.push_back(body);
    const double reach = TouchingPairs(model).reach(0);
    for (const Vector3& p : body.contact_points) EXPECT_LE(p.norm() + 0.01, reach);
    for (int i = 0; i < 20000; ++i) {
      const Vector3 p = fd::random_vector(rng, 0.7);
      if (c.evaluate(p, false).distance <= 0.0) {
        EXPECT_LE(p.norm(), reach) << p.transpose();
      }
    }
    // Tight: the shape's extent about its centre plus the centre's offset (a mesh: plus the
    // grid's interpolation bound √3 h, h = 0.02).
    EXPECT_LE(reach, c.position.norm() + k.extent + std::sqrt(3.0) * 0.02 + 1e-12);
  }
}

TEST(SurfaceSamples, ASpacingThatIsNotPositiveOrTooFineIsAnErrorNamingItsField) {
  const TriangleMesh box = box_mesh(Vector3(0.1, 0.1, 0.1));
  // A needle: its area (the estimate's measure) says ~80 samples at 0.01, its length needs
  // ~140: the thinning itself stops at the budget.
  const TriangleMesh needle = box_mesh(Vector3(0.5, 5e-4, 5e-4));
  const auto error = [](const Shape& shape, double spacing, int budget) {
    Collider c;
    c.shape = shape;
    try {
      surface_samples(c, spacing, budget, "bodies[2].contact");
    } catch (const ModelError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  for (const Shape& shape :
       {Shape(SphereShape{0.1}), Shape(TorusShape{0.1, 0.02}), Shape(LinkShape{0.1, 0.1, 0.02}),
        Shape(CylinderShape{0.1, 0.1}),
        Shape(MeshShape{std::make_shared<const GridSdf>(box, 0.02, 0.04),
                        std::make_shared<const TriangleMesh>(box)}),
        Shape(MeshShape{std::make_shared<const GridSdf>(needle, 0.02, 0.04),
                        std::make_shared<const TriangleMesh>(needle)})}) {
    for (const double spacing : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), 1e-6}) {
      EXPECT_EQ(error(shape, spacing, 1000), "bodies[2].contact.sample_spacing")
          << shape.index() << " " << spacing;
    }
    // Never more samples than the budget: one fewer than the spacing gives is refused.
    Collider c;
    c.shape = shape;
    const auto count = static_cast<int>(surface_samples(c, 0.01, 100000, "b").size());
    EXPECT_EQ(error(shape, 0.01, count - 1), "bodies[2].contact.sample_spacing") << shape.index();
  }
  // Shapes a body may not have.
  EXPECT_EQ(error(PlaneShape{}, 0.01, 1000), "bodies[2].contact.shape.type");
  EXPECT_EQ(error(TubeShape{{{0, 0, 0}, {1, 0, 0}}, 0.1}, 0.01, 1000),
            "bodies[2].contact.shape.type");
}

// ----------------------------------------------------------------------------------------
// Friction between bodies.

template <class Term>
struct LaggedPair {
  Term term;
  State previous, q;
};
using FrictionPair = LaggedPair<BodyFriction>;
using DampingPair = LaggedPair<BodyDamping>;

// A's sample 0.02 deep in B at the previous state (make_pair's geometry), then both bodies
// moved and turned (B by a small rigid motion, A turned by 0.2 rad) so that the sample slips
// by `slip` along the lagged tangent plane relative to the point of B it touched, and moves
// by `normal_move` along the normal. The term's law is `law`.
template <class Term, class Law>
LaggedPair<Term> lagged_pair(const std::shared_ptr<const Collider>& shape, double angle_a, double angle_b,
                             double slip, const Law& law, double stiffness, std::mt19937& rng,
                             double normal_move = 0.002) {
  const Pair start = make_pair(shape, 0.02, angle_a, angle_b, stiffness, rng);
  LaggedPair<Term> c;
  static_cast<BodySample&>(c.term) = start.term;
  static_cast<Law&>(c.term) = law;
  c.previous = start.q;
  c.term.begin_step(c.previous, Step{});
  const Vector3 n = c.term.normal;
  c.q = c.previous;
  c.q.rotations[1] = so3::exp(0.1 * fd::random_unit(rng)) * c.previous.rotations[1];
  c.q.points[1] += fd::random_vector(rng, 0.05);
  const Vector3 p_b = c.q.points[1] + c.q.rotations[1] * c.term.contact_point;
  c.q.rotations[0] = so3::exp(0.2 * fd::random_unit(rng)) * c.previous.rotations[0];
  const Vector3 p_a = p_b + slip * fd::random_perpendicular(n, rng) + normal_move * n;
  c.q.points[0] = p_a - c.q.rotations[0] * c.term.at.local;
  return c;
}

FrictionPair friction_pair(const std::shared_ptr<const Collider>& shape, double angle_a, double angle_b,
                           double slip, double epsilon, double stiffness, std::mt19937& rng,
                           double normal_move = 0.002) {
  return lagged_pair<BodyFriction>(shape, angle_a, angle_b, slip, SlipFriction{0.4, epsilon}, stiffness, rng,
                                   normal_move);
}

TEST(BodyFriction, LieDerivativesInStickAndSlipMatchFiniteDifferences) {
  std::mt19937 rng(44);
  const double epsilon = 1e-2;
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const double angle_a : kAngles) {
      for (const double angle_b : {0.0, 1e-9, 2.5, std::numbers::pi}) {
        // Deep in the stick regime, near the switch on both sides, and sliding.
        for (const double slip : {0.3 * epsilon, 0.9 * epsilon, 1.1 * epsilon, 20.0 * epsilon}) {
          SCOPED_TRACE(trace("angles of A and B, slip", angle_a, angle_b, slip));
          const FrictionPair c = friction_pair(shape, angle_a, angle_b, slip, epsilon, 1e4, rng);
          ASSERT_NEAR(c.term.normal_force, 1e4 * 0.02, 1e-9);
          EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs, fd::stick_zone()));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 9 * 4 * 4);
}

TEST(BodyFriction, SlidingForceIsMuLambdaAgainstTheSlipAndEqualAndOpposite) {
  std::mt19937 rng(45);
  for (const auto& shape : shapes(rng)) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      SCOPED_TRACE(trace("stiffness", k));
      const FrictionPair c = friction_pair(shape, 1.0, 2.0, 0.05, 1e-4, k, rng, 0.0);
      LocalGradient<4> g;
      c.term.evaluate(c.q, &g, nullptr);
      // Sliding (y = 500 ε): the force on A's sample, −∂D/∂p_A, is μλ along the slip of B
      // relative to A, i.e. against A's slip.
      const double mu_lambda = c.term.coefficient * c.term.normal_force;
      const Vector3 slip_of_a = c.term.at.position(c.q) - (c.q.points[1] + c.q.rotations[1] * c.term.contact_point);
      EXPECT_TRUE((-g.head<3>()).isApprox(-mu_lambda * slip_of_a.normalized(), 1e-12));
      const auto [force, torque] = net_force_and_torque(g, c.q);
      EXPECT_LT(force.norm(), 1e-12 * g.norm());
      EXPECT_LT(torque.norm(), 1e-12 * g.norm() * (1.0 + c.q.points[0].norm() + c.q.points[1].norm()));
      fd::TermCheckOptions options;
      options.hessian_from_value.step = 1e-5;
      EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs, options));
    }
  }
}

TEST(BodyFriction, NoLaggedContactNoFriction) {
  std::mt19937 rng(46);
  const auto shape = shapes(rng).front();
  const Pair apart = make_pair(shape, -0.05, 1.0, 2.5, 1e4, rng);
  BodyFriction term;
  static_cast<BodySample&>(term) = apart.term;
  term.coefficient = 0.4;
  term.epsilon = 1e-3;
  term.begin_step(apart.q, Step{});
  EXPECT_EQ(term.normal_force, 0.0);
  State q = apart.q;
  q.points[0] += Vector3(0.01, 0.02, -0.03);
  LocalGradient<4> g;
  LocalHessian<4> H;
  EXPECT_EQ(term.evaluate(q, &g, &H), 0.0);
  EXPECT_TRUE(g.isZero(0.0));
  EXPECT_TRUE(H.isZero(0.0));
  EXPECT_TRUE(term.previous_jacobian(q, apart.q).isZero(0.0));
}

TEST(BodyFriction, ResidualFormReproducesValueAndGradient) {
  std::mt19937 rng(47);
  for (const auto& shape : shapes(rng)) {
    for (const double slip : {0.3e-2, 5e-2}) {
      const FrictionPair c = friction_pair(shape, 1.3, 0.4, slip, 1e-2, 1e4, rng);
      LocalGradient<4> g;
      const double D = c.term.evaluate(c.q, &g, nullptr);
      BodyFriction::Residual r;
      BodyFriction::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * D);
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12));
      const fd::VectorFunction F = fd::residual_of(c.term);
      EXPECT_TRUE(fd::check_vector_jacobian(F, c.q, kDofs, J));
    }
  }
}

TEST(BodyFriction, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  // C(q; q_{k−1}): the local gradient at the fixed current state as a function of both
  // previous poses, through û, λ and n (begin_step re-run at every perturbed q_{k−1}).
  std::mt19937 rng(48);
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const double angle_a : kAngles) {
      for (const double angle_b : kAngles) {
        for (const double slip : {0.3e-2, 5e-2}) {
          SCOPED_TRACE(trace("angles of A and B, slip", angle_a, angle_b, slip));
          const FrictionPair c = friction_pair(shape, angle_a, angle_b, slip, 1e-2, 1e4, rng);
          const fd::VectorFunction C = fd::lagged_gradient(c.term, c.q);
          const Eigen::MatrixXd J = c.term.previous_jacobian(c.q, c.previous);
          fd::FdOptions o;
          o.step = 2e-7;  // the stick zone's truncation, as in the Lie derivatives' test
          EXPECT_TRUE(fd::check_vector_jacobian(C, c.previous, kDofs, J, o));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 9 * 9 * 2);
}

TEST(BodyFriction, TinyAndHugeTimeStepsKeepDerivativesExactAndTheForceBounded) {
  // ε = ε_v h over h from 1e-6 to 1 s at ε_v = 1e-3 m/s. The geometry is scaled with ε (a
  // sphere of radius 100 ε, levers of 50 ε, a penetration of 20 ε, slips 0.5 ε and 3 ε) so
  // that the state's round-off eps·|p| stays far below FD steps that fit in the quadratic
  // zone: 1e-4 ε for first differences, 1e-3 ε for second differences of the value (as for
  // Friction in test_contact.cpp).
  std::mt19937 rng(49);
  for (const double h : {1e-6, 1e-3, 1.0}) {
    const double epsilon = 1e-3 * h;
    Collider sphere;
    sphere.shape = SphereShape{100.0 * epsilon};
    const auto shape = std::make_shared<const Collider>(sphere);
    for (const double factor : {0.5, 3.0}) {
      SCOPED_TRACE(trace("h factor", h, factor));
      BodyFriction term;
      term.shape = shape;
      term.radius = 10.0 * epsilon;
      term.stiffness = 1e4;
      term.coefficient = 0.4;
      term.epsilon = epsilon;
      term.body_b = 1;
      term.offsets = {0, 3, 6, 9};
      term.at = {0, 0, 50.0 * epsilon * fd::random_unit(rng)};
      State previous;
      previous.rotations = {rotation_at(2.0, rng), rotation_at(1.0, rng)};
      previous.points = {Vector3::Zero(), 30.0 * epsilon * fd::random_unit(rng)};
      const Vector3 direction = fd::random_unit(rng);
      const Vector3 p = previous.points[1] + (90.0 * epsilon) * direction;  // 20 ε deep
      previous.points[0] = p - previous.rotations[0] * term.at.local;
      term.begin_step(previous, Step{});
      ASSERT_NEAR(term.normal_force, 1e4 * 20.0 * epsilon, 1e-6 * term.normal_force);
      State q = previous;
      q.points[0] += factor * epsilon * fd::random_perpendicular(term.normal, rng);
      // The θ rows' non-zero check is the O(1) test above.
      EXPECT_TRUE(fd::check_term(term, q, kDofs, fd::within_zone(epsilon)));
    }
    // At O(1) geometry the same ε gives a force never above Coulomb's μλ, whatever the slip.
    std::mt19937 rng_pair(50);
    for (const double slip : {0.0, 0.5 * epsilon, epsilon, 1e3 * epsilon}) {
      const FrictionPair c = friction_pair(shapes(rng_pair)[1], 1.0, 2.0, slip, epsilon, 1e4, rng_pair, 0.0);
      LocalGradient<4> g;
      LocalHessian<4> H;
      c.term.evaluate(c.q, &g, &H);
      EXPECT_LE(g.head<3>().norm(), c.term.coefficient * c.term.normal_force * (1.0 + 1e-9));
      EXPECT_TRUE(H.allFinite());
    }
  }
}

// ----------------------------------------------------------------------------------------
// Damping between bodies (the dashpot law of lib/dissipation_law.hpp on the relative
// displacement of body_contact.hpp's friction): D = ½ (τ k/h) (n·d)².

// c = 30 N·s/m at k = 1e4 N/m, h = 1 ms.
DampingPair damping_pair(const std::shared_ptr<const Collider>& shape, double angle_a, double angle_b,
                         double slide, double normal_move, std::mt19937& rng, double h = 1e-3, double c = 30.0) {
  return lagged_pair<BodyDamping>(shape, angle_a, angle_b, slide, NormalDashpot{c / 1e4, h}, 1e4, rng, normal_move);
}

TEST(BodyDamping, LieDerivativesMatchFiniteDifferences) {
  std::mt19937 rng(144);
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const double angle_a : kAngles) {
      for (const double angle_b : {0.0, 1e-9, 2.5, std::numbers::pi}) {
        // Approaching and receding, sliding across the normal.
        for (const double normal_move : {-0.004, 0.003}) {
          SCOPED_TRACE(trace("angles of A and B, normal move", angle_a, angle_b, normal_move));
          const DampingPair c = damping_pair(shape, angle_a, angle_b, 0.02, normal_move, rng);
          ASSERT_GT(c.term.normal_force, 0.0);
          EXPECT_TRUE(fd::check_term(c.term, c.q, kDofs));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 9 * 4 * 2);
}

TEST(BodyDamping, IsTheDashpotOnTheRelativeNormalVelocityEqualAndOppositeAndTorqueFree) {
  std::mt19937 rng(145);
  for (const auto& shape : shapes(rng)) {
    for (const double h : {1e-6, 1e-3, 1.0}) {
      SCOPED_TRACE(trace("h", h));
      // A's sample moved 3 mm into B relative to the point it touched, nothing across.
      const double c = 30.0;
      const DampingPair pair = damping_pair(shape, 1.0, 2.0, 0.0, -0.003, rng, h, c);
      LocalGradient<4> g;
      const double D = pair.term.evaluate(pair.q, &g, nullptr);
      // The force on A, −∂D/∂x_A, is c v_n n with v_n = 3 mm/h: it pushes A back out.
      const Vector3 expected = (c * 0.003 / h) * pair.term.normal;
      EXPECT_TRUE((-g.head<3>()).isApprox(expected, 1e-9)) << (-g.head<3>()).transpose();
      EXPECT_NEAR(D, 0.5 * (c / h) * 0.003 * 0.003, 1e-9 * D);
      // B feels the opposite force at its material point, on the line of the normal: no net
      // force, no net torque.
      const auto [force, torque] = net_force_and_torque(g, pair.q);
      EXPECT_LT(force.norm(), 1e-12 * g.norm());
      EXPECT_LT(torque.norm(), 1e-11 * g.norm() * (1.0 + pair.q.points[0].norm() + pair.q.points[1].norm()));
    }
  }
}

TEST(BodyDamping, NoLaggedContactNoDamping) {
  std::mt19937 rng(146);
  const Pair apart = make_pair(shapes(rng).front(), -0.05, 1.0, 2.5, 1e4, rng);
  BodyDamping term;
  static_cast<BodySample&>(term) = apart.term;
  static_cast<NormalDashpot&>(term) = NormalDashpot{3e-3, 1e-3};
  term.begin_step(apart.q, Step{});
  EXPECT_EQ(term.normal_force, 0.0);
  State q = apart.q;
  q.points[0] += Vector3(0.01, 0.02, -0.03);
  LocalGradient<4> g;
  LocalHessian<4> H;
  EXPECT_EQ(term.evaluate(q, &g, &H), 0.0);
  EXPECT_TRUE(g.isZero(0.0));
  EXPECT_TRUE(H.isZero(0.0));
  BodyDamping::Residual r;
  BodyDamping::ResidualJacobian J;
  term.residual(q, r, &J);
  EXPECT_TRUE(r.isZero(0.0));
  EXPECT_TRUE(J.isZero(0.0));
  EXPECT_TRUE(term.previous_jacobian(q, apart.q).isZero(0.0));
}

TEST(BodyDamping, ResidualFormReproducesValueAndGradient) {
  std::mt19937 rng(147);
  for (const auto& shape : shapes(rng)) {
    for (const double normal_move : {-0.004, 0.0, 0.003}) {
      const DampingPair c = damping_pair(shape, 1.3, 0.4, 0.02, normal_move, rng);
      LocalGradient<4> g;
      const double D = c.term.evaluate(c.q, &g, nullptr);
      BodyDamping::Residual r;
      BodyDamping::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * D);
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::residual_of(c.term), c.q, kDofs, J));
    }
  }
}

TEST(BodyDamping, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  // Through û, n and the previous poses (begin_step re-run at every perturbed q_{k−1}; the
  // sample is 2 cm deep, far from the zone's switch).
  std::mt19937 rng(148);
  int checked = 0;
  for (const auto& shape : shapes(rng)) {
    for (const double angle_a : kAngles) {
      for (const double angle_b : kAngles) {
        SCOPED_TRACE(trace("angles of A and B", angle_a, angle_b));
        const DampingPair c = damping_pair(shape, angle_a, angle_b, 0.02, -0.004, rng);
        const Eigen::MatrixXd J = c.term.previous_jacobian(c.q, c.previous);
        EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(c.term, c.q), c.previous, kDofs, J));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 3 * 9 * 9);
}

TEST(BodyDamping, TinyAndHugeTimeStepsAndDampingsKeepDerivativesExact) {
  // D is quadratic in the state for any c/h, from 1e-3 (c = 1e-3, h = 1 s) to 1e12 (c = 1e6,
  // h = 1e-6 s): the derivatives scale with it and stay exact (relative).
  std::mt19937 rng(149);
  const auto shape = shapes(rng)[1];
  for (const double h : {1e-6, 1e-3, 1.0}) {
    for (const double c : {1e-3, 1.0, 1e6}) {
      SCOPED_TRACE(trace("h c", h, c));
      const DampingPair d = damping_pair(shape, 2.0, 1.0, 0.01, -0.004, rng, h, c);
      EXPECT_TRUE(fd::check_term(d.term, d.q, kDofs));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(d.term, d.q), d.previous, kDofs,
                                            d.term.previous_jacobian(d.q, d.previous)));
    }
  }
}

}  // namespace
}  // namespace liedyn::body_contact_tests

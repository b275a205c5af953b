// Contact between two bodies (lib/body_contact.hpp): a sample of A against B's shape. Value
// vs Lie gradient vs Lie Hessian by central differences in the tangent space of both poses
// (tests/fd_check.hpp), for spheres, rounded boxes and capsules (posed within B), at every
// rotation of fd::kAngles for A and for B, over penetrations and stiffnesses from tiny to
// huge; the residual form; and the internal forces' balance (no net force or torque: what
// makes contact between bodies conserve momentum).
//
// Geometry is O(1) and penetrations ≫ the FD steps, as in tests/test_contact.cpp.

#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

#include "fd_check.hpp"
#include "lib/body_contact.hpp"
#include "lib/sdf.hpp"
#include "lib/so3.hpp"

namespace liedyn {
namespace {

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
  Vector3 p = shape.position + 0.5 * fd::random_unit(rng);
  for (int i = 0; i < 100; ++i) {
    const SdfValue s = shape.evaluate(p, false);
    const double error = s.distance - target;
    if (std::abs(error) < 1e-13) break;
    p -= error * s.gradient / s.gradient.squaredNorm();
  }
  return p;
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
      const Vector3 force = g.segment<3>(0) + g.segment<3>(6);
      const Vector3 torque = c.q.points[0].cross(Vector3(g.segment<3>(0))) + g.segment<3>(3) +
                             c.q.points[1].cross(Vector3(g.segment<3>(6))) + g.segment<3>(9);
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

}  // namespace
}  // namespace liedyn

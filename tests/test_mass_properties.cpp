// Mass and inertia from a shape and a density (lib/mass_properties.hpp): the closed forms
// against the textbook ones where they exist (sphere, sharp box, a capsule of zero length),
// against a midpoint-rule integration over the shape's SDF (every part of a heavily rounded
// box and of a capsule matters), turned by the shape's orientation; and a scene's "density".

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "fd_check.hpp"
#include "lib/mass_properties.hpp"
#include "lib/model.hpp"
#include "problems/scene.hpp"

namespace liedyn {
namespace {

Collider solid(const Shape& shape, const Matrix3& orientation = Matrix3::Identity()) {
  Collider c;
  c.shape = shape;
  c.orientation = orientation;
  return c;
}

// Midpoint rule over n³ cells of the box [−L, L]³ (shape axes), each cell counted by the
// fraction of it inside, 1/2 − φ/cell clamped to [0, 1] (exact for a face parallel to the
// cell's, first order in the angle otherwise): a counted-or-not cell would be off by up to
// half a layer of cells on a flat face, ~1e-2 here. What remains is the fraction's error
// where the surface is oblique to the cells: ~5e-4 relative at n = 160 on these O(1) shapes,
// against the percent or more that dropping any one part of the closed forms costs.
MassProperties integrated(const Collider& c, double half_width, double density, int n) {
  const double cell = 2.0 * half_width / n, dV = cell * cell * cell;
  double volume = 0.0;
  Matrix3 second = Matrix3::Zero();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) {
        const Vector3 p = Vector3(i + 0.5, j + 0.5, k + 0.5) * cell - Vector3::Constant(half_width);
        const double inside = std::clamp(0.5 - c.evaluate(p, false).distance / cell, 0.0, 1.0);
        volume += inside * dV;
        second += inside * dV * p * p.transpose();
      }
    }
  }
  MassProperties m;
  m.mass = density * volume;
  m.inertia = density * (second.trace() * Matrix3::Identity() - second);
  return m;
}

TEST(MassProperties, TextbookSolids) {
  const double rho = 7.0;
  const MassProperties s = mass_properties(solid(SphereShape{0.3}), rho, "bodies[0]");
  const double m_s = rho * 4.0 / 3.0 * std::numbers::pi * 0.027;
  EXPECT_NEAR(s.mass, m_s, 1e-14 * m_s);
  EXPECT_TRUE(s.inertia.isApprox(0.4 * m_s * 0.09 * Matrix3::Identity(), 1e-14));
  const MassProperties b = mass_properties(solid(BoxShape{Vector3(0.1, 0.2, 0.3), 0.0}), rho, "bodies[0]");
  const double m_b = rho * 0.2 * 0.4 * 0.6;
  EXPECT_NEAR(b.mass, m_b, 1e-14 * m_b);
  EXPECT_TRUE(b.inertia.isApprox(Matrix3(Vector3(0.16 + 0.36, 0.04 + 0.36, 0.04 + 0.16).asDiagonal()) * (m_b / 12.0), 1e-14));
  // A capsule of zero length is a sphere; a box rounded all the way to a cube's half extent
  // would be one too, and at rounding → e it tends to it.
  const MassProperties c = mass_properties(solid(CapsuleShape{0.0, 0.3}), rho, "bodies[0]");
  EXPECT_NEAR(c.mass, s.mass, 1e-14 * m_s);
  EXPECT_TRUE(c.inertia.isApprox(s.inertia, 1e-14));
  const MassProperties r = mass_properties(solid(BoxShape{Vector3::Constant(0.3), 0.3 * (1 - 1e-9)}), rho, "bodies[0]");
  EXPECT_NEAR(r.mass, s.mass, 1e-7 * m_s);
  EXPECT_TRUE(r.inertia.isApprox(s.inertia, 1e-7));
}

TEST(MassProperties, AgreeWithIntegrationOverTheShapeAndTurnWithIt) {
  std::mt19937 rng(3);
  const double rho = 1000.0;
  struct Case {
    Shape shape;
    double half_width;
  };
  for (const Case& k : {Case{BoxShape{Vector3(0.3, 0.5, 0.7), 0.25}, 0.71}, Case{BoxShape{Vector3(0.3, 0.5, 0.7), 0.1}, 0.71},
                        Case{CapsuleShape{0.4, 0.25}, 0.66}}) {
    const Matrix3 Q = fd::rotation_at(1.1, rng);
    const MassProperties exact = mass_properties(solid(k.shape, Q), rho, "bodies[0]");
    const MassProperties axes = mass_properties(solid(k.shape), rho, "bodies[0]");
    const MassProperties numeric = integrated(solid(k.shape), k.half_width, rho, 160);
    EXPECT_NEAR(axes.mass, numeric.mass, 1e-3 * numeric.mass);
    EXPECT_TRUE(axes.inertia.isApprox(numeric.inertia, 1e-3)) << axes.inertia << "\n\n" << numeric.inertia;
    EXPECT_TRUE(exact.inertia.isApprox(Q * axes.inertia * Q.transpose(), 1e-13));
    EXPECT_NEAR(exact.mass, axes.mass, 1e-14 * axes.mass);
  }
}

TEST(MassProperties, ASceneMayGiveADensityInsteadOfMassAndInertia) {
  const auto body = [](const std::string& mass, const std::string& shape) {
    return parse_scene(R"({"time_step": 0.01, "frames": 1, "bodies": [{"name": "b", )" + mass +
                           R"(, "contact": {"stiffness": 1e4, "shape": )" + shape + "}}]}",
                       "density.json");
  };
  const Scene s = body(R"("density": 500)", R"({"type": "box", "half_extents": [0.1, 0.2, 0.3]})");
  EXPECT_NEAR(s.model.bodies[0].mass, 500 * 0.2 * 0.4 * 0.6, 1e-12);
  const auto error = [&](const std::string& mass, const std::string& shape) {
    try {
      body(mass, shape);
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  const std::string box = R"({"type": "box", "half_extents": [0.1, 0.2, 0.3]})";
  EXPECT_EQ(error(R"("density": 500, "mass": 1)", box), "bodies[0].mass: give \"density\" or \"mass\" and \"inertia\", not both");
  EXPECT_EQ(error(R"("density": -1)", box), "bodies[0].density: must be a finite positive number of kg/m³");
  EXPECT_EQ(error(R"("density": 500)", R"({"type": "sphere", "radius": 0.1, "position": [0, 0, 0.1]})"),
            "bodies[0].contact.shape.position: must be the body's origin (its centre of mass) when the body gives a \"density\"");
  EXPECT_EQ(error(R"("mass": 1)", box), "bodies[0].inertia: is required but missing");
}

}  // namespace
}  // namespace liedyn

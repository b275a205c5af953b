// Paper Fig. 6's kind of scene: a chain of interlocked links wound onto a spinning spool with a
// weight at its end (contact/spool_chain.json, written by scripts/make_chain_scene.py; link
// shapes: lib/sdf.hpp, body–body contact: lib/body_contact.hpp, kinematic spool:
// lib/kinematic.hpp).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <random>
#include <variant>
#include <vector>

#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

// The centre line of a link (the stadium of its shape) in the world, as a closed polygon.
std::vector<Vector3> core_curve(const LinkShape& link, const Vector3& x, const Matrix3& R, int per_arc = 48) {
  std::vector<Vector3> out;
  const double L = link.half_length, Rm = link.major_radius;
  for (int side : {1, -1}) {  // the arc about (side L, 0), then the straight part back
    for (int i = 0; i <= per_arc; ++i) {
      const double a = -std::numbers::pi / 2 + std::numbers::pi * i / per_arc;
      const Vector3 p(side * (L + Rm * std::cos(a)), side * Rm * std::sin(a), 0.0);
      out.push_back(x + R * p);
    }
  }
  return out;
}

// The Gauss linking number of two closed polygons, by counting signed crossings in a
// projection along a generic direction (each crossing of a over b counts its sign; the sum over
// crossings where a passes over b is the linking number). An integer whatever the direction,
// as long as no vertex projects onto the other polygon: a random direction avoids it.
int linking_number(const std::vector<Vector3>& a, const std::vector<Vector3>& b, const Vector3& view) {
  // A frame with view as its z axis.
  const Vector3 e3 = view.normalized();
  const Vector3 e1 = e3.unitOrthogonal();
  const Vector3 e2 = e3.cross(e1);
  const auto plane = [&](const Vector3& p) { return Eigen::Vector2d(p.dot(e1), p.dot(e2)); };
  const auto cross2 = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
  int twice = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Vector3& a0 = a[i];
    const Vector3& a1 = a[(i + 1) % a.size()];
    const Eigen::Vector2d p = plane(a0), r = plane(a1) - p;
    for (std::size_t j = 0; j < b.size(); ++j) {
      const Vector3& b0 = b[j];
      const Vector3& b1 = b[(j + 1) % b.size()];
      const Eigen::Vector2d q = plane(b0), s = plane(b1) - q;
      const double denominator = cross2(r, s);
      if (denominator == 0.0) continue;
      const double t = cross2(q - p, s) / denominator, u = cross2(q - p, r) / denominator;
      if (t < 0.0 || t >= 1.0 || u < 0.0 || u >= 1.0) continue;
      // Which is above (towards the viewer) at the crossing, and the crossing's sign.
      const double height_a = (a0 + t * (a1 - a0)).dot(e3), height_b = (b0 + u * (b1 - b0)).dot(e3);
      const int sign = denominator > 0.0 ? 1 : -1;
      twice += height_a > height_b ? sign : -sign;
    }
  }
  return twice / 2;
}

TEST(LinkingNumber, CountsTwoInterlockedRingsAndNoneApart) {
  const LinkShape ring{0.0, 1.0, 0.1};
  const Matrix3 quarter = Eigen::AngleAxisd(std::numbers::pi / 2, Vector3::UnitX()).toRotationMatrix();
  const Vector3 view = Vector3(0.3, 0.5, 0.81).normalized();
  EXPECT_EQ(std::abs(linking_number(core_curve(ring, Vector3::Zero(), Matrix3::Identity()),
                                    core_curve(ring, Vector3(1, 0, 0), quarter), view)), 1);
  EXPECT_EQ(linking_number(core_curve(ring, Vector3::Zero(), Matrix3::Identity()),
                           core_curve(ring, Vector3(2.5, 0, 0), quarter), view), 0);
}

// The bundled chain on the spool, its first 0.2 s (the whole 1.2 s run takes minutes: the
// README gives its figures and the command that checks the linking over all of it; under the
// sanitizers, ten times slower, its first 0.04 s): every step converges, no sample sinks by a wire's radius, and no
// link passes through another — at every frame the linking number of each two links' centre
// lines is ±1 for neighbours and 0 for the others near each other, an integer that can only
// change when the two wires cross.
TEST(SpoolChain, NoLinkPassesThroughAnotherAsTheSpoolTurns) {
  Scene scene = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/spool_chain.json");
  const Model& model = scene.model;
  std::vector<int> links;
  int weight = -1, spool = -1;
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) {
    if (model.bodies[b].shape != nullptr && std::holds_alternative<LinkShape>(model.bodies[b].shape->shape)) {
      links.push_back(b);
    }
    if (model.bodies[b].name == "weight") weight = b;
    if (model.bodies[b].name == "spool") spool = b;
  }
  ASSERT_EQ(links.size(), 21u);
  ASSERT_GE(weight, 0);
  ASSERT_GE(spool, 0);
  const LinkShape& shape = std::get<LinkShape>(model.bodies[links[0]].shape->shape);
  const double extent = shape.half_length + shape.major_radius + shape.minor_radius;

  Simulator sim(model, scene.solver);
  const Vector3 view = Vector3(0.31, 0.47, 0.83).normalized();  // generic: no vertex projects onto a wire
  const auto curve = [&](int b) { return core_curve(shape, sim.state().points[b], sim.state().rotations[b]); };
  const auto check_links = [&](int k) {
    for (std::size_t i = 0; i < links.size(); ++i) {
      for (std::size_t j = i + 1; j < links.size(); ++j) {
        const bool neighbours = j == i + 1;
        // Links farther apart than their extents cannot be linked without having met.
        if (!neighbours && (sim.state().points[links[i]] - sim.state().points[links[j]]).norm() > 2.0 * extent) continue;
        const int linked = std::abs(linking_number(curve(links[i]), curve(links[j]), view));
        ASSERT_EQ(linked, neighbours ? 1 : 0) << "links " << i + 1 << " and " << j + 1 << " at frame " << k;
      }
    }
  };
  check_links(0);
#if defined(__SANITIZE_ADDRESS__)
  const int frames = std::min(scene.frames, 20);
#else
  const int frames = std::min(scene.frames, 100);
#endif
  double deepest = 0.0;
  for (int k = 1; k <= frames; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << k << ": " << r.message;
    deepest = std::max(deepest, sim.max_penetration());
    check_links(k);
  }
  EXPECT_LT(deepest, shape.minor_radius);
  std::cout << "spool chain: " << frames << " steps, deepest sample " << deepest << " m, weight at z = "
            << sim.state().points[weight].z() << " m\n";
}

}  // namespace
}  // namespace liedyn

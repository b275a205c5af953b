// Moving colliders of every type (lib/kinematic.hpp, problems/scene.cpp): planes, tubes and
// inside-out shapes as the shapes of kinematic bodies. Their reach (lib/body_contact.cpp) is
// +∞ for a plane or a complement and a tube's farthest polyline point plus its radius; the
// broad phase keeps every pair with an unbounded object; the contact and friction terms
// evaluate any collider in the body's frame (finite differences); whole runs: a rising floor
// lifts a box with its sink depth mg/(nk) below it, a tilting plane holds a frictional box
// and lets a frictionless one slide downhill, a moving lumen carries a rod; a moving plane at
// rest is the static plane, and one moving at constant velocity is the static plane seen
// from a moving frame (Galilean); gradients through contact with a moving plane.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <variant>
#include <vector>

#include "adjoint_check.hpp"
#include "contact_references.hpp"
#include "fd_check.hpp"
#include "mesh_models.hpp"
#include "lib/body_contact.hpp"
#include "lib/broad_phase.hpp"
#include "lib/contact_search.hpp"
#include "lib/edge_contact.hpp"
#include "lib/mesh_sdf.hpp"
#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::moving_colliders_tests {
namespace {

using fd::kInf;
constexpr double kGravity = 9.81;

Collider make_collider(const Shape& shape, bool inside, const Vector3& position = Vector3::Zero(),
                       const Matrix3& orientation = Matrix3::Identity()) {
  Collider c;
  c.name = "shape";
  c.shape = shape;
  c.inside = inside;
  c.position = position;
  c.orientation = orientation;
  return c;
}

RigidBody kinematic_body(const std::string& name, const Collider& shape) {
  RigidBody b;
  b.name = name;
  b.kinematic = KinematicMotion{};
  b.shape = std::make_shared<const Collider>(shape);
  return b;
}

// ---------------------------------------------------------------------------------------
// Reach and the broad phase.

// A kinematic body may have any collider; a plane's and every complement's reach is +∞, a
// tube's its offset plus its farthest polyline point plus its radius (every point of the
// solid lies within it), a mesh without its triangles the farthest corner of its grid's box
// plus √3 h.
TEST(MovingColliders, ReachIsUnboundedForAPlaneOrAComplementAndBoundsATube) {
  const Matrix3 turned = so3::exp(Vector3(0.3, -0.5, 0.8));
  const Collider tube = make_collider(TubeShape{{Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(1, 1, 0)}, 0.1}, false,
                                      Vector3(0.3, -0.4, 0.0), turned);
  const auto grid = std::make_shared<const GridSdf>(test::box_mesh(Vector3(0.2, 0.3, 0.4)), 0.05, 0.1);
  Model model;
  model.time_step = 0.01;
  model.bodies = {kinematic_body("floor", make_collider(PlaneShape{}, false, Vector3(1, 2, 3), turned)),
                  kinematic_body("bowl", make_collider(SphereShape{0.5}, true)),
                  kinematic_body("can", make_collider(CapsuleShape{0.3, 0.1}, true)),
                  kinematic_body("lumen", make_collider(tube.shape, true)),
                  kinematic_body("tube", tube),
                  kinematic_body("grid", make_collider(MeshShape{grid, nullptr}, false))};
  EXPECT_NO_THROW(model.validate());
  const TouchingPairs pairs(model);
  for (int b = 0; b < 4; ++b) EXPECT_EQ(pairs.reach(b), kInf) << model.bodies[b].name;
  EXPECT_DOUBLE_EQ(pairs.reach(4), 0.5 + std::sqrt(2.0) + 0.1);
  const Vector3 corner = grid->origin().cwiseAbs().cwiseMax(grid->max_corner().cwiseAbs());
  EXPECT_DOUBLE_EQ(pairs.reach(5), corner.norm() + std::sqrt(3.0) * 0.05);
  // The tube's solid lies within its reach: points of a cube about it, those inside the solid.
  std::mt19937 rng(3);
  double farthest = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const Vector3 p = fd::random_vector(rng, 2.5);
    if (tube.evaluate(p, false).distance <= 0.0) farthest = std::max(farthest, p.norm());
  }
  EXPECT_GT(farthest, 0.0);  // some were found
  EXPECT_LE(farthest, pairs.reach(4));
}

using test::every_overlap;

// Unbounded boxes (±∞: an unbounded reach) among moving ones: each meets every other box,
// and the pairs are exactly those of testing every pair, as the boxes move.
TEST(MovingColliders, SweepAndPruneMeetsEveryBoxWithAnUnboundedOne) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const int n = 60;
  const std::vector<int> unbounded = {3, 41};
  std::vector<Vector3> centre(n);
  for (Vector3& c : centre) c = Vector3(uniform(rng), 3.0 * uniform(rng), uniform(rng));
  std::vector<Aabb> boxes(n);
  std::vector<std::pair<int, int>> pairs;
  SweepAndPrune sweep;
  for (int query = 0; query < 20; ++query) {
    for (int i = 0; i < n; ++i) {
      centre[i] += 0.02 * Vector3(uniform(rng), uniform(rng), uniform(rng));
      boxes[i] = {centre[i].array() - 0.05, centre[i].array() + 0.05};
    }
    for (int i : unbounded) boxes[i] = {centre[i].array() - kInf, centre[i].array() + kInf};
    sweep.overlapping(boxes, pairs);
    std::sort(pairs.begin(), pairs.end());
    ASSERT_EQ(pairs, every_overlap(boxes)) << "query " << query;
    for (int u : unbounded) {
      EXPECT_EQ(std::count_if(pairs.begin(), pairs.end(), [&](auto p) { return p.first == u || p.second == u; }), n - 1);
    }
  }
}

// ---------------------------------------------------------------------------------------
// The terms against B's shape, for the shapes only a moving collider may have: value, Lie
// gradient and Lie Hessian by central differences (tests/fd_check.hpp), as
// tests/test_body_contact.cpp and tests/test_edge_body_contact.cpp do for the body shapes.

// B's unbounded and unsampled shapes, posed within B: a tilted plane, a bowl, the inside of a
// capsule, a bent tube and its lumen.
std::vector<std::shared_ptr<const Collider>> moving_shapes(std::mt19937& rng) {
  std::vector<std::shared_ptr<const Collider>> out;
  const TubeShape bent{{Vector3(-1, 0, 0), Vector3(0, 0, 0), Vector3(0.8, 0.6, 0)}, 0.5};
  for (const auto& [shape, inside] : {std::pair{Shape(PlaneShape{}), false}, std::pair{Shape(SphereShape{1.0}), true},
                                      std::pair{Shape(CapsuleShape{0.7, 0.6}), true},
                                      std::pair{Shape(TubeShape{bent.polyline, 0.3}), false},
                                      std::pair{Shape(bent), true}}) {
    out.push_back(std::make_shared<const Collider>(
        make_collider(shape, inside, fd::random_vector(rng, 0.2), fd::rotation_at(0.7, rng))));
  }
  return out;
}

// Whether a point u of B's coordinates is at least 1 mm from where a sample's V is not C²:
// the contact switch ρ − φ = 0, a capsule's planes |z| = L, a tube's planes through its
// vertices normal to a segment and the medial surface between its two segments. The checks
// move a point by up to ~4e-4 m (two steps of 1e-4 with levers of 2 m); a clearance of
// 5e-4 keeps a sample placed exactly 1e-3 deep (to round-off) clear of the switch.
bool clear_of_kinks(const Collider& shape, double radius, const Vector3& u) {
  constexpr double kClearance = 5e-4;
  if (std::abs(radius - shape.evaluate(u, false).distance) < kClearance) return false;
  const Vector3 x = shape.orientation.transpose() * (u - shape.position);
  if (const auto* capsule = std::get_if<CapsuleShape>(&shape.shape)) {
    return std::abs(std::abs(x.z()) - capsule->half_length) >= kClearance;
  }
  if (const auto* tube = std::get_if<TubeShape>(&shape.shape)) {
    std::vector<double> distances;
    for (std::size_t j = 0; j + 1 < tube->polyline.size(); ++j) {
      const Vector3 a = tube->polyline[j], b = tube->polyline[j + 1];
      const double length = (b - a).norm(), along = (x - a).dot(b - a) / length;
      if (std::abs(along) < kClearance || std::abs(along - length) < kClearance) return false;
      distances.push_back(point_segment_distance(x, a, b));
    }
    return std::abs(distances[0] - distances[1]) >= kClearance;
  }
  return true;
}

// A point at signed distance `target` from the shape (its coordinates): a start near its
// frame's origin walked along the SDF's gradient onto the level set.
Vector3 place(const Collider& shape, double target, std::mt19937& rng) {
  return test::onto_level_set(shape, shape.position + shape.orientation * (0.3 * fd::random_unit(rng)), target);
}

// Body A's sample p̄ = (0.3, −0.4, 0.2) `depth` deep in body B's shape, clear of its kinks,
// B turned by angle_b (A by 0.9 rad).
struct SamplePair {
  BodyContact term;
  State q;
};

SamplePair sample_pair(const std::shared_ptr<const Collider>& shape, double depth, double angle_b, std::mt19937& rng) {
  SamplePair c;
  c.term.shape = shape;
  c.term.radius = 0.1;
  c.term.stiffness = 1e4;
  c.term.body_b = 1;
  c.term.offsets = {0, 3, 6, 9};
  const Vector3 local(0.3, -0.4, 0.2);
  c.term.at = {0, 0, local};
  Vector3 touched = place(*shape, c.term.radius - depth, rng);
  for (int attempt = 0; attempt < 100 && !clear_of_kinks(*shape, c.term.radius, touched); ++attempt) {
    touched = place(*shape, c.term.radius - depth, rng);
  }
  EXPECT_TRUE(clear_of_kinks(*shape, c.term.radius, touched));
  const Matrix3 R_b = fd::rotation_at(angle_b, rng), R_a = fd::rotation_at(0.9, rng);
  const Vector3 x_b = fd::random_vector(rng, 1.0);
  c.q.points = {x_b + R_b * touched - R_a * local, x_b};
  c.q.rotations = {R_a, R_b};
  return c;
}

const fd::Dofs kBodyDofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1), fd::rotation_dof(1)};

TEST(MovingColliders, BodyContactAndFrictionAgainstAnyColliderMatchFiniteDifferences) {
  std::mt19937 rng(71);
  int checked = 0;
  for (const auto& shape : moving_shapes(rng)) {
    for (const double angle_b : {0.0, 1e-9, 0.7, 2.5, std::numbers::pi}) {
      for (const double depth : {1e-3, 0.05}) {
        SCOPED_TRACE(fd::trace("shape, angle of B, depth", static_cast<double>(shape->shape.index()), angle_b, depth));
        const SamplePair c = sample_pair(shape, depth, angle_b, rng);
        ASSERT_NEAR(c.term.penetration(c.q), depth, 1e-12);
        EXPECT_TRUE(fd::check_term(c.term, c.q, kBodyDofs));
        // Friction: lagged at c.q, then both bodies moved so that the sample slips by `slip`
        // along the lagged tangent plane (tests/test_body_contact.cpp's friction_pair).
        for (const double slip : {3e-3, 5e-2}) {
          BodyFriction f;
          static_cast<BodySample&>(f) = c.term;
          f.coefficient = 0.4;
          f.epsilon = 1e-2;
          f.begin_step(c.q, Step{});
          ASSERT_NEAR(f.normal_force, 1e4 * depth, 1e-9);
          State q = c.q;
          q.rotations[1] = so3::exp(0.1 * fd::random_unit(rng)) * c.q.rotations[1];
          q.points[1] += fd::random_vector(rng, 0.05);
          q.rotations[0] = so3::exp(0.2 * fd::random_unit(rng)) * c.q.rotations[0];
          const Vector3 p_b = q.points[1] + q.rotations[1] * f.contact_point;
          q.points[0] = p_b + slip * fd::random_perpendicular(f.normal, rng) - q.rotations[0] * f.at.local;
          EXPECT_TRUE(fd::check_term(f, q, kBodyDofs, fd::stick_zone())) << "slip " << slip;
          const fd::VectorFunction C = fd::lagged_gradient(f, q);
          EXPECT_TRUE(fd::check_vector_jacobian(C, c.q, kBodyDofs, f.previous_jacobian(q, c.q), fd::stick_zone().gradient))
              << "slip " << slip;
        }
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 5 * 5 * 2);
}

// A rod's edge crossing B's surface (slope 0.6 out of it) with its Gauss point k `depth` deep.
TEST(MovingColliders, EdgeBodyContactAgainstAnyColliderMatchesFiniteDifferences) {
  std::mt19937 rng(72);
  const QuadratureRule& rule = gauss_legendre(EdgeBodyContact::kQuadraturePoints);
  int checked = 0;
  for (const auto& shape : moving_shapes(rng)) {
    for (const double angle_b : {0.0, 0.7, std::numbers::pi}) {
      for (const int k : {0, 2}) {
        for (const double depth : {1e-3, 0.05}) {
          SCOPED_TRACE(fd::trace("angle of B, Gauss point, depth", angle_b, k, depth));
          SCOPED_TRACE(fd::trace("shape", static_cast<double>(shape->shape.index())));
          EdgeBodyContact term;
          term.shape = shape;
          term.radius = 0.1;
          term.stiffness = 1e4;
          term.rest_length = 0.4;
          term.body_b = 0;
          term.nodes = {1, 2};
          term.offsets = {0, 3, 6, 9};
          const Matrix3 R_b = fd::rotation_at(angle_b, rng);
          const Vector3 x_b = fd::random_vector(rng, 1.0);
          State q;
          const auto clear = [&] {
            for (int i = 0; i < rule.size; ++i) {
              const Vector3 p = (1.0 - rule.nodes[i]) * q.points[1] + rule.nodes[i] * q.points[2];
              if (!clear_of_kinks(*shape, term.radius, R_b.transpose() * (p - x_b))) return false;
            }
            return true;
          };
          for (int attempt = 0; attempt < 100 && (attempt == 0 || !clear()); ++attempt) {
            const Vector3 touched = place(*shape, term.radius - depth, rng);
            const Vector3 n = shape->evaluate(touched, false).gradient;
            const Vector3 t = 0.6 * n + 0.8 * fd::random_perpendicular(n, rng);
            const double s = rule.nodes[k], length = 0.35;
            q.points = {x_b, x_b + R_b * (touched - s * length * t), x_b + R_b * (touched + (1.0 - s) * length * t)};
            q.rotations = {R_b};
          }
          ASSERT_TRUE(clear());
          ASSERT_GE(term.penetration(q), depth - 1e-12);
          EXPECT_TRUE(fd::check_term(term, q, {fd::point_dof(1), fd::point_dof(2), fd::point_dof(0), fd::rotation_dof(0)}));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 5 * 3 * 2 * 2);
}

// ---------------------------------------------------------------------------------------
// Whole runs.

// A box of 10 cm (1 kg from its density) sampled every 2.5 cm, on a floor that is a moving
// collider (`floor_motion`: its "kinematic" block); μ = `friction`.
Scene box_on_moving_floor(const std::string& floor_motion, double friction, int frames = 200) {
  return parse_scene(R"({"time_step": 0.005, "frames": )" + std::to_string(frames) + R"(, "gravity": [0, 0, -9.81],
    "bodies": [{"name": "box", "position": [0, 0, 0.05], "density": 1000,
                "contact": {"stiffness": 1e4, "friction": )" + std::to_string(friction) + R"(,
                            "shape": {"type": "box", "half_extents": [0.05, 0.05, 0.05]}, "sample_spacing": 0.025}}],
    "colliders": [{"name": "floor", "type": "plane", "kinematic": )" + floor_motion + "}]}",
                     "moving_floor.json");
}

// (a) The floor rises at 0.1 m/s under a box resting on it: the box rises with it. Once the
// start's jolt has died out the box moves at the floor's constant velocity, so (backward
// Euler's inertia term vanishing) its n bottom samples hold its weight alone: each sinks by
// mg/(nk), and the box's bottom stays that far below the floor.
TEST(MovingColliders, ARisingFloorLiftsABoxWithItsSinkDepthBelowIt) {
  const Scene scene = box_on_moving_floor(R"({"linear_velocity": [0, 0, 0.1]})", 0.5);
  const RigidBody& box = scene.model.bodies[0];
  const int bottom = static_cast<int>(std::count_if(box.contact_points.begin(), box.contact_points.end(),
                                                    [](const Vector3& p) { return std::abs(p.z() + 0.05) < 1e-12; }));
  ASSERT_EQ(bottom, 25);  // a 5 × 5 grid on the bottom face, its edges included
  const double sink = box.mass * kGravity / (bottom * box.contact.stiffness);
  Simulator sim(scene.model, scene.solver);
  double worst = 0.0;
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    const double floor = sim.state().points[1].z();
    EXPECT_NEAR(floor, 0.1 * k * scene.model.time_step, 1e-15);
    const double gap = sim.state().points[0].z() - 0.05 - floor;  // the box's bottom above the floor
    if (k * scene.model.time_step >= 0.25) worst = std::max(worst, std::abs(gap + sink));
  }
  std::printf("[ measured ] rising floor: sink mg/(nk) = %.6g m, |gap + sink| ≤ %.3g m over the last 0.75 s, "
              "box at %.6f m (floor %.6f m)\n",
              sink, worst, sim.state().points[0].z(), sim.state().points[1].z());
  EXPECT_LT(worst, 1e-3 * sink);
  // Δx/h: the Newton tolerance of 1e-9 m over h = 5 ms allows 2e-7 m/s.
  EXPECT_NEAR(sim.linear_velocity(0).z(), 0.1, 1e-6);
  EXPECT_LT(sim.state().points[0].head<2>().norm(), 1e-9);  // straight up
  EXPECT_LT((sim.state().rotations[0] - Matrix3::Identity()).norm(), 1e-9);
}

// (b) The floor turns about the world's x axis at 0.2 rad/s (0.2 rad after 1 s; tan 0.2 =
// 0.20 < μ = 0.5): its uphill direction is its own +y (R e_y = (0, cos θ, sin θ)). A box with
// friction stays where it was on it (in the plane's frame), to within the lagged law's creep
// below ε_v = 1 mm/s; without friction it slides towards −y, by about s(t) = g (t/ω −
// sin(ωt)/ω²) (s'' = g sin ωt along the slope, ignoring the centrifugal ω² s and backward
// Euler's O(h) lag, each about 1 % here).
TEST(MovingColliders, ATiltingPlaneHoldsAFrictionalBoxAndAFrictionlessOneSlidesDownhill) {
  const double omega = 0.2;
  const auto run = [&](double friction) {
    const Scene scene = box_on_moving_floor(R"({"angular_velocity": [0.2, 0, 0]})", friction);
    Simulator sim(scene.model, scene.solver);
    for (int k = 1; k <= scene.frames; ++k) EXPECT_TRUE(sim.step().converged()) << k;
    // The box's centre in the plane's frame.
    return Vector3(sim.state().rotations[1].transpose() * (sim.state().points[0] - sim.state().points[1]));
  };
  const Vector3 held = run(0.5), sliding = run(0.0);
  const double t = 1.0, expected = kGravity * (t / omega - std::sin(omega * t) / (omega * omega));
  std::printf("[ measured ] tilting plane, 0.2 rad after 1 s: with friction the box moved %.3g m along the plane "
              "(height %.6f m); without it slid %.4f m downhill (estimate %.4f m)\n",
              held.head<2>().norm(), held.z(), -sliding.y(), expected);
  EXPECT_LT(held.head<2>().norm(), 1e-3);
  EXPECT_NEAR(held.z(), 0.05, 1e-3);  // still on the plane
  EXPECT_LT(sliding.y(), 0.0);        // downhill
  EXPECT_NEAR(-sliding.y(), expected, 0.05 * expected);
  EXPECT_NEAR(sliding.z(), 0.05, 1e-3);
}

// (c) A rod (0.4 m, 20 edges, radius 5 mm, 10 g) lying at the bottom of a lumen of radius
// 2 cm — the inside of a tube, or of a capsule — that moves sideways at 0.1 m/s for 1 s:
// the wall pushes the rod along (it swings in the lumen, backward Euler damping the swing),
// the rod's centre travels the lumen's 0.1 m to within the free play R − ρ = 1.5 cm, and no
// node or Gauss point comes near passing through the wall (deepest ρ − φ reported).
TEST(MovingColliders, AMovingLumenCarriesARodAndNothingPassesThrough) {
  const std::string rod = R"("rods": [{"name": "rod",
      "shape": {"type": "line", "start": [-0.2, 0, -0.015], "end": [0.2, 0, -0.015], "edges": 20},
      "mass": 0.01, "radius": 0.005, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
      "bending_stiffness": [1e-4, 1e-4, 1e-4], "contact": {"stiffness": 1e3}}])";
  const std::string motion = R"("kinematic": {"linear_velocity": [0, 0.1, 0]})";
  for (const std::string lumen :
       {R"({"name": "lumen", "type": "tube", "radius": 0.02, "inside": true, "points": [[-0.4, 0, 0], [0.4, 0, 0]], )",
        R"({"name": "lumen", "type": "capsule", "half_length": 0.3, "radius": 0.02, "inside": true,
            "orientation": [0.7071067811865476, 0, 0.7071067811865476, 0], )"}) {
    SCOPED_TRACE(lumen);
    const Scene scene = parse_scene(R"({"time_step": 0.002, "frames": 500, "gravity": [0, 0, -9.81], )" + rod +
                                        R"(, "colliders": [)" + lumen + motion + "}]}",
                                    "lumen.json");
    ASSERT_EQ(scene.model.bodies.size(), 1u);
    const Model& model = scene.model;
    const Collider& wall = *model.bodies[0].shape;
    const double radius = model.rods[0].contact.radius;
    const QuadratureRule& rule = gauss_legendre(EdgeBodyContact::kQuadraturePoints);
    Simulator sim(model, scene.solver);
    const auto centre = [&] {
      Vector3 sum = Vector3::Zero();
      for (int i = 0; i < model.rods[0].node_count(); ++i) sum += sim.state().points[model.rod_point(0, i)];
      return Vector3(sum / model.rods[0].node_count());
    };
    const Vector3 start = centre();
    double deepest = -kInf, reported = 0.0, farthest_off_axis = 0.0;
    for (int k = 1; k <= scene.frames; ++k) {
      ASSERT_TRUE(sim.step().converged()) << k;
      const State& q = sim.state();
      const auto depth = [&](const Vector3& p) {
        return radius - wall.evaluate(q.rotations[0].transpose() * (p - q.points[0]), false).distance;
      };
      for (int e = 0; e < model.rods[0].edge_count(); ++e) {
        const Vector3& x0 = q.points[model.rod_point(0, e)];
        const Vector3& x1 = q.points[model.rod_point(0, e + 1)];
        deepest = std::max({deepest, depth(x0), depth(x1)});
        for (int i = 0; i < rule.size; ++i) deepest = std::max(deepest, depth((1.0 - rule.nodes[i]) * x0 + rule.nodes[i] * x1));
      }
      reported = std::max(reported, sim.max_penetration());
      farthest_off_axis = std::max(farthest_off_axis, (centre() - q.points[0]).tail<2>().norm());
    }
    const double travelled = centre().y() - start.y();
    std::printf("[ measured ] rod in a moving %s: centre travelled %.4f m (lumen 0.1 m), at most %.4f m off the "
                "lumen's axis (free play 0.015 m); deepest node or Gauss point %.3g m (ρ = %.3g m; max_penetration %.3g m)\n",
                std::holds_alternative<TubeShape>(wall.shape) ? "tube lumen" : "capsule", travelled, farthest_off_axis,
                deepest, radius, reported);
    EXPECT_NEAR(sim.state().points[0].y(), 0.1, 1e-12);
    EXPECT_NEAR(travelled, 0.1, 0.015);
    EXPECT_LT(farthest_off_axis, 0.015 + 1e-3);
    EXPECT_LT(deepest, 0.1 * radius);
    EXPECT_GT(deepest, 0.0);  // it did press on the wall
    EXPECT_LE(reported, deepest + 1e-12);
  }
}

// (d) A body of "bodies" keeps the shapes a body may have (it may be sampled or filled): a
// plane, a tube or an inside-out shape is refused naming the field, kinematic or not, and so
// is a dynamic body's in the model; a kinematic body's is any collider. A moving collider's
// parameters are still checked.
TEST(MovingColliders, OrdinaryBodiesStillRefuseUnboundedShapesNamingTheField) {
  const auto field_of = [](const std::string& body, const std::string& colliders = "") {
    try {
      parse_scene(R"({"time_step": 0.01, "frames": 1, "bodies": [{"name": "b", )" + body + "}]" + colliders + "}",
                  "bad.json");
    } catch (const SceneError& e) {
      // A refused body shape says where such a shape belongs: a moving collider.
      if (e.field().find(".contact.shape.") != std::string::npos) {
        EXPECT_NE(e.reason().find("\"kinematic\""), std::string::npos) << e.reason();
      }
      return e.field();
    }
    return std::string("accepted");
  };
  const std::string mass = R"("mass": 1, "inertia": [1, 1, 1])";
  const std::string dynamic = mass + ", ";
  const std::string kinematic = R"("kinematic": {"linear_velocity": [0, 0, 1]}, )";
  for (const std::string& how : {dynamic, kinematic}) {
    SCOPED_TRACE(how);
    EXPECT_EQ(field_of(how + R"("contact": {"stiffness": 1e3, "shape": {"type": "plane"}})"),
              "bodies[0].contact.shape.type");
    EXPECT_EQ(field_of(how + R"("contact": {"stiffness": 1e3, "shape": {"type": "tube", "radius": 0.1,
                                                                         "points": [[0, 0, 0], [1, 0, 0]]}})"),
              "bodies[0].contact.shape.type");
    EXPECT_EQ(field_of(how + R"("contact": {"stiffness": 1e3, "shape": {"type": "sphere", "radius": 1, "inside": true}})"),
              "bodies[0].contact.shape.inside");
  }
  EXPECT_EQ(field_of(R"("density": 1000, "contact": {"stiffness": 1e3, "shape": {"type": "plane"}})"),
            "bodies[0].contact.shape.type");
  EXPECT_EQ(field_of(dynamic + R"("contact": {"stiffness": 1e3, "sample_spacing": 0.1,
                                             "shape": {"type": "capsule", "half_length": 1, "radius": 0.1, "inside": true}})"),
            "bodies[0].contact.shape.inside");
  // Moving colliders: any type; their own fields checked as a collider's.
  const std::string moving = R"(, "colliders": [{"name": "m", "kinematic": {"linear_velocity": [1, 0, 0]}, )";
  EXPECT_EQ(field_of(dynamic + R"("contact": {"stiffness": 1e3, "points": [[0, 0, 0]]})", moving + R"("type": "plane"}])"),
            "accepted");
  EXPECT_EQ(field_of(dynamic + R"("contact": {"stiffness": 1e3, "points": [[0, 0, 0]]})",
                     moving + R"("type": "tube", "radius": 0.1, "inside": true, "points": [[0, 0, -1], [0, 0, 1]]}])"),
            "accepted");
  EXPECT_EQ(field_of(mass, moving + R"("type": "tube", "radius": 0, "points": [[0, 0, 0], [1, 0, 0]]}])"),
            "colliders[0].radius");

  // The model: a dynamic body's shape must be a body's; a kinematic body's may be any collider.
  const auto model_field = [](RigidBody body) {
    Model model;
    model.time_step = 0.01;
    model.bodies = {std::move(body)};
    try {
      model.validate();
    } catch (const ModelError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  RigidBody solid;
  solid.name = "b";
  for (const auto& [shape, inside, field] :
       {std::tuple{Shape(PlaneShape{}), false, "bodies[0].contact.shape.type"},
        std::tuple{Shape(TubeShape{{Vector3(0, 0, 0), Vector3(1, 0, 0)}, 0.1}), false, "bodies[0].contact.shape.type"},
        std::tuple{Shape(SphereShape{1.0}), true, "bodies[0].contact.shape.inside"}}) {
    solid.kinematic.reset();
    solid.shape = std::make_shared<const Collider>(make_collider(shape, inside));
    EXPECT_EQ(model_field(solid), field);
    solid.kinematic = KinematicMotion{};
    EXPECT_EQ(model_field(solid), "accepted");
  }
}

// A box thrown spinning onto a tilted floor, with friction, once against a static collider
// and once against a moving collider given zero velocities (`motion`).
Scene thrown_box(const std::string& floor, double friction = 0.5, const std::string& box_velocity = "[1, 0.5, 0]") {
  return parse_scene(R"({"time_step": 0.002, "frames": 300, "gravity": [0, 0, -9.81],
    "solver": {"tolerance": 1e-12, "max_iterations": 50},
    "bodies": [{"name": "box", "position": [0, 0, 0.2], "orientation": [0.8, 0.36, 0.48, 0], "density": 1000,
                "linear_velocity": )" + box_velocity + R"(, "angular_velocity": [2, -1, 3],
                "contact": {"stiffness": 1e4, "friction": )" + std::to_string(friction) + R"(,
                            "shape": {"type": "box", "half_extents": [0.05, 0.04, 0.03]}, "sample_spacing": 0.02}}],
    "colliders": [)" + floor + "]}",
                     "thrown.json");
}

// (e) A moving plane that does not move is the static plane: the same samples against the
// same φ in the same frame (BodyContact and BodyFriction against the kinematic body's shape
// instead of the collider terms of lib/contact.hpp), the same trajectory to 1e-12. Newton
// solves to 1e-14, so that the comparison sees the terms rather than where each solve
// stopped: at the scene's 1e-12 the frictional runs' rotations differ by 1.07e-12.
TEST(MovingColliders, AMovingPlaneAtRestIsTheStaticPlane) {
  const std::string plane = R"({"name": "floor", "type": "plane", "normal": [0.1, -0.05, 1], "position": [0, 0, -0.02])";
  for (const double friction : {0.0, 0.5}) {
    Scene fixed = thrown_box(plane + "}", friction);
    Scene still = thrown_box(plane + R"(, "kinematic": {"linear_velocity": [0, 0, 0]}})", friction);
    fixed.solver.tolerance = still.solver.tolerance = 1e-14;
    Simulator a(fixed.model, fixed.solver), b(still.model, still.solver);
    double position = 0.0, rotation = 0.0;
    int touching = 0;
    for (int k = 1; k <= fixed.frames; ++k) {
      ASSERT_TRUE(a.step().converged()) << k;
      ASSERT_TRUE(b.step().converged()) << k;
      position = std::max(position, (a.state().points[0] - b.state().points[0]).cwiseAbs().maxCoeff());
      rotation = std::max(rotation, (a.state().rotations[0] - b.state().rotations[0]).cwiseAbs().maxCoeff());
      touching += b.contact_pairs() > 0;
    }
    std::printf("[ measured ] plane at rest vs static plane, μ = %.1f: |Δx|∞ ≤ %.3g m, |ΔR|∞ ≤ %.3g "
                "(%d of %d frames in contact)\n",
                friction, position, rotation, touching, fixed.frames);
    EXPECT_GT(touching, 50);
    EXPECT_LT(position, 1e-12);
    EXPECT_LT(rotation, 1e-12);
  }
}

// (e) Galilean invariance, frictionless: a floor moving at a constant v (up and sideways)
// under a thrown box gives the box the motion, relative to the floor, that a static floor
// gives a box thrown with its velocity less v. Backward Euler's inertia term and the penalty
// see only relative positions and velocities, so the two runs are the same steps up to the
// Newton tolerance (1e-10 here) and round-off.
TEST(MovingColliders, AMovingPlaneGivesTheRelativeMotionOfAStaticOneWithTheBodyGivenMinusV) {
  const std::string plane = R"({"name": "floor", "type": "plane", "normal": [0.1, -0.05, 1], "position": [0, 0, -0.02])";
  const auto with_tolerance = [](Scene s) {
    s.solver.tolerance = 1e-10;
    return s;
  };
  const Scene moving = with_tolerance(
      thrown_box(plane + R"(, "kinematic": {"linear_velocity": [0.3, -0.2, 0.25]}})", 0.0, "[1, 0.5, 0]"));
  const Scene fixed = with_tolerance(thrown_box(plane + "}", 0.0, "[0.7, 0.7, -0.25]"));
  Simulator a(moving.model, moving.solver), b(fixed.model, fixed.solver);
  const Vector3 start = a.state().points[1];
  double position = 0.0, rotation = 0.0;
  int touching = 0;
  for (int k = 1; k <= moving.frames; ++k) {
    ASSERT_TRUE(a.step().converged()) << k;
    ASSERT_TRUE(b.step().converged()) << k;
    const Vector3 relative = a.state().points[0] - (a.state().points[1] - start);
    position = std::max(position, (relative - b.state().points[0]).cwiseAbs().maxCoeff());
    rotation = std::max(rotation, (a.state().rotations[0] - b.state().rotations[0]).cwiseAbs().maxCoeff());
    touching += b.contact_pairs() > 0;
  }
  std::printf("[ measured ] Galilean check (v = (0.3, −0.2, 0.25) m/s, 300 steps): |Δx|∞ ≤ %.3g m, |ΔR|∞ ≤ %.3g "
              "(%d frames in contact)\n",
              position, rotation, touching);
  EXPECT_GT(touching, 50);
  EXPECT_LT(position, 1e-9);
  EXPECT_LT(rotation, 1e-9);
}

// The pairs within reach through the broad phase are those of testing every candidate, at
// every step of a run with a tilting plane (unbounded, turning: margin +∞) under a box, a
// rising floor it never reaches, and a rod in a moving lumen (unbounded, translating).
TEST(MovingColliders, TheBroadPhaseFindsWhatTestingEveryCandidateFinds) {
  const Scene scene = parse_scene(R"({"time_step": 0.005, "frames": 100, "gravity": [0, 0, -9.81],
    "bodies": [{"name": "box", "position": [0, 0, 0.05], "density": 1000,
                "contact": {"stiffness": 1e4, "friction": 0.5, "ignores": ["lumen"],
                            "shape": {"type": "box", "half_extents": [0.05, 0.05, 0.05]}, "sample_spacing": 0.025}}],
    "rods": [{"name": "rod", "shape": {"type": "line", "start": [-0.2, 1, 0.485], "end": [0.2, 1, 0.485], "edges": 10},
              "mass": 0.01, "radius": 0.005, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
              "bending_stiffness": [1e-4, 1e-4, 1e-4], "contact": {"stiffness": 1e3}}],
    "colliders": [{"name": "floor", "type": "plane", "kinematic": {"angular_velocity": [0.2, 0, 0]}},
                  {"name": "low", "type": "plane", "position": [0, 0, -1], "kinematic": {"linear_velocity": [0, 0, 0.1]}},
                  {"name": "lumen", "type": "tube", "radius": 0.02, "inside": true, "points": [[-0.4, 1, 0.5], [0.4, 1, 0.5]],
                   "kinematic": {"linear_velocity": [0, 0.1, 0]}}]})",
                                  "search.json");
  Simulator sim(scene.model, scene.solver);
  ContactSearch search(scene.model), exhaustive(scene.model);
  ASSERT_EQ(search.size(), 2u + 4u);  // the box with each plane; the rod with every collider and the box
  std::vector<bool> fast(search.size()), every(search.size());
  int touching = 0;
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    search.find(sim.state(), sim.last_step(), fast);
    exhaustive.find_exhaustively(sim.state(), sim.last_step(), every);
    ASSERT_EQ(fast, every) << k;
    touching += static_cast<int>(std::count(fast.begin(), fast.end(), true));
  }
  EXPECT_GE(touching, 2 * scene.frames);  // the box on the floor and the rod in the lumen, every step
}

// (f) The adjoint through contact with a moving, turning plane: a ball (with friction)
// thrown against a wall that comes towards it; the parameters are its initial velocity
// (tests/test_kinematic.cpp's moving bumper, with a plane).
TEST(MovingColliders, TheGradientRunsThroughContactWithAMovingPlane) {
  const Scene scene = parse_scene(R"({"time_step": 0.001, "frames": 150, "solver": {"tolerance": 1e-12, "max_iterations": 50},
    "bodies": [
      {"name": "ball", "mass": 1, "inertia": [0.004, 0.004, 0.004], "position": [0, 0.05, 0], "linear_velocity": [2, 0, 0],
       "contact": {"stiffness": 1e5, "radius": 0.005, "friction": 0.5, "shape": {"type": "sphere", "radius": 0.1},
                   "sample_spacing": 0.02}}],
    "colliders": [{"name": "wall", "type": "plane", "normal": [-1, 0.3, 0], "position": [0.25, 0, 0],
                   "kinematic": {"linear_velocity": [-0.5, 0.3, 0], "angular_velocity": [0, 0, 1]}}],
    "optimization": {"parameters": [{"kind": "body_linear_velocity", "body": "ball"}],
                     "objective": [{"term": "body_pose", "body": "ball", "frame": -1, "position": [-0.1, 0.1, 0]}]}})",
                                  "wall.json");
  // The throw does reach the wall (otherwise the check would not be through contact).
  Simulator sim(scene.model, scene.solver);
  int touching = 0;
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    touching += sim.contact_pairs() > 0;
  }
  EXPECT_GT(touching, 5);
  EXPECT_LT(sim.linear_velocity(0).x(), 0.0);  // bounced back
  EXPECT_TRUE(test::gradient_agrees(scene));
}

}  // namespace
}  // namespace liedyn::moving_colliders_tests

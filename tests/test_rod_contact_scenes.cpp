// Contact between rods and within a rod, in whole runs (lib/edge_contact.hpp: the term is
// FD-tested in test_edge_contact.cpp; the candidates and the pairs within reach:
// Model::edge_pairs, TouchingEdges): the bundled rope coil with and without self-contact,
// a rod dropped across another, two rods colliding without gravity (momentum), filters, a rod
// sliding and sticking on two tilted rods against the closed form of friction, and the
// adjoint through rod–rod contact and friction.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <filesystem>
#include <limits>
#include <numbers>
#include <string>
#include <variant>

#include "adjoint_check.hpp"
#include "lib/edge_contact.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

Scene rod_coil() {
  return load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/rod_coil.json");
}

// The bundled coil: its coils pile up on the floor and on one another, and no two edges more
// than 2 apart come closer than the rope's radius, centreline to centreline (a surface
// separation of −ρ). Without self-contact the same run passes the coils through one another
// (measured with the self-contact model's candidates on the other run's states).
TEST(RodContactScenes, TheCoiledRopeLiesOnItselfAndWithoutSelfContactPassesThrough) {
  const Scene with = rod_coil();
  const RodSpec& rope = with.model.rods[0];
  ASSERT_TRUE(rope.self_contact);
  const double radius = rope.contact.radius;
  Scene without = with;
  without.model.rods[0].self_contact = false;
  const TouchingEdges candidates(with.model);
  ASSERT_EQ(candidates.size(), 157u * 158u / 2u);  // 160 edges, pairs more than 2 apart

  Simulator sim(with.model, with.solver);
  Simulator through(without.model, without.solver);
  double closest = std::numeric_limits<double>::infinity(), closest_without = closest;
  int frames_in_contact = 0;
  for (int k = 1; k <= with.frames; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << k << ": " << r.message;
    ASSERT_TRUE(through.step().state_updated()) << k;
    closest = std::min(closest, sim.min_rod_separation());
    closest_without = std::min(closest_without, candidates.min_separation(through.state()));
    frames_in_contact += sim.min_rod_separation() < 0.0;
  }
  EXPECT_GT(closest, -radius);              // never closer than half the diameter
  EXPECT_GT(frames_in_contact, 20);          // and the coils did lie on one another
  EXPECT_LT(closest_without, -1.5 * radius);  // through one another without it
  int on_floor = 0;
  for (int i = 0; i < rope.node_count(); ++i) on_floor += sim.state().points[sim.model().rod_point(0, i)].z() < 0.03;
  EXPECT_GT(on_floor, 80);
  std::cout << "coil: closest surface separation " << closest << " m (without self-contact " << closest_without
            << "), " << sim.island_sets() << " sets of islands built over " << with.frames << " steps\n";
}

// A rod of 10 edges dropped across another lying on the floor: it comes to rest on it, its
// middle at about three radii above the floor; told to ignore it, it falls to the floor.
TEST(RodContactScenes, ARodDroppedAcrossAnotherRestsOnIt) {
  const auto scene = [](const std::string& filter) {
    const auto rod = [](const std::string& name, const std::string& start, const std::string& end,
                        const std::string& filter) {
      return R"({"name": ")" + name + R"(", "shape": {"type": "line", "start": )" + start + R"(, "end": )" + end +
             R"(, "edges": 10}, "mass": 0.05, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                 "bending_stiffness": [1e-3, 1e-3, 1e-3], "contact": {"stiffness": 1e4, "friction": 0.5)" + filter + "}}";
    };
    return parse_scene(R"({"time_step": 0.002, "frames": 400, "gravity": [0, 0, -9.81],
                           "colliders": [{"name": "floor", "type": "plane"}], "rods": [)" +
                           rod("below", "[-0.25, 0, 0.0099]", "[0.25, 0, 0.0099]", "") + "," +
                           rod("above", "[0.01, -0.25, 0.05]", "[0.01, 0.25, 0.05]", filter) + "]}",
                       "crossing.json");
  };
  const auto middle_height = [](const Scene& s) {
    Simulator sim(s.model, s.solver);
    for (int k = 1; k <= s.frames; ++k) EXPECT_TRUE(sim.step().state_updated()) << k;
    return sim.state().points[sim.model().rod_point(1, 5)].z();
  };
  EXPECT_EQ(scene("").model.edge_pairs().size(), 100u);
  EXPECT_NEAR(middle_height(scene("")), 0.03, 0.003);
  const Scene ignoring = scene(R"(, "ignores": ["below"])");
  EXPECT_TRUE(ignoring.model.edge_pairs().empty());
  EXPECT_LT(middle_height(ignoring), 0.0105);
}

// Two rods thrown at each other without gravity or colliders, crossing at right angles: the
// contact forces are internal, so the total momentum stays, to the solver's tolerance.
TEST(RodContactScenes, TwoRodsCollidingKeepTheirMomentum) {
  const auto rod = [](const std::string& name, const std::string& start, const std::string& end, const std::string& v) {
    std::string velocities;
    for (int i = 0; i <= 8; ++i) velocities += std::string(i ? ", " : "") + v;
    return R"({"name": ")" + name + R"(", "shape": {"type": "line", "start": )" + start + R"(, "end": )" + end +
           R"(, "edges": 8}, "mass": 0.05, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
               "bending_stiffness": [1e-3, 1e-3, 1e-3], "node_velocities": [)" + velocities +
           R"(], "contact": {"stiffness": 1e4}})";
  };
  const Scene s = parse_scene(R"({"time_step": 0.001, "frames": 300, "solver": {"tolerance": 1e-12},
                                  "rods": [)" + rod("a", "[-0.2, 0, 0.1]", "[0.2, 0, 0.1]", "[0, 0, -1]") + "," +
                                  rod("b", "[0.03, -0.2, -0.1]", "[0.03, 0.2, -0.1]", "[0, 0, 1]") + "]}",
                              "collision.json");
  Simulator sim(s.model, s.solver);
  std::vector<double> mass;
  for (const RodSpec& r : s.model.rods) {
    const RodDiscretization d = discretize(r);
    mass.insert(mass.end(), d.node_mass.begin(), d.node_mass.end());
  }
  const auto total = [&] {
    Vector3 p = Vector3::Zero();
    for (std::size_t i = 0; i < mass.size(); ++i) p += mass[i] * sim.last_step().points[i] / s.model.time_step;
    return p;
  };
  const Vector3 p0 = total();
  double drift = 0.0, closest = std::numeric_limits<double>::infinity();
  for (int k = 1; k <= s.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    drift = std::max(drift, (total() - p0).norm());
    closest = std::min(closest, sim.min_rod_separation());
  }
  EXPECT_LT(closest, 0.0);  // they met
  EXPECT_GT(closest, -0.01);
  EXPECT_LT(drift, 1e-8);
  // They bounced apart: a's momentum points up again, b's down.
  Vector3 a = Vector3::Zero();
  for (int i = 0; i <= 8; ++i) a += mass[i] * sim.linear_velocity(s.model.rod_point(0, i));
  EXPECT_GT(a.z(), 0.0);
  EXPECT_LT((p0 - a).z(), 0.0);
}

// The adjoint through rod–rod contact: a rod thrown across another; γ its initial node
// velocities, the loss its final distance to a target line. Frictionless, the other rod lying
// on the floor; and with friction between the rods, the other rod clamped in the air (the
// bundled optimization/rod_throw_friction.json): the lagged friction's mixed blocks
// (EdgeFriction::previous_jacobian) enter the backward pass. Not with friction on the floor
// as well: the rods then stick to it within ε_v h = 2e-6 m of slip, and central differences
// straddle that zone's edge (README, "Contact and friction").
TEST(RodContactAdjoint, TheGradientRunsBackThroughContactAndFrictionBetweenRods) {
  const Scene on_floor = parse_scene(R"({
    "time_step": 0.002, "frames": 100, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-12, "max_iterations": 100 },
    "colliders": [ { "type": "plane" } ],
    "rods": [ { "name": "below", "shape": { "type": "line", "start": [-0.25, 0, 0.0099], "end": [0.25, 0, 0.0099], "edges": 6 },
                "mass": 0.05, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                "bending_stiffness": [1e-3, 1e-3, 1e-3], "contact": { "stiffness": 2e3 } },
              { "name": "thrown", "shape": { "type": "line", "start": [0.02, -0.2, 0.06], "end": [0.02, 0.2, 0.06], "edges": 6 },
                "mass": 0.05, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                "bending_stiffness": [1e-3, 1e-3, 1e-3], "contact": { "stiffness": 2e3 } } ],
    "optimization": {
      "parameters": [ { "kind": "rod_node_velocities", "rod": "thrown" } ],
      "objective": [ { "term": "point_targets", "rod": "thrown", "frame": -1,
                       "polyline": [[0.1, -0.2, 0.1], [0.1, 0.2, 0.1]] } ] } })",
                                     "rods_adjoint.json");
  const Scene frictional =
      load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/optimization/rod_throw_friction.json");
  Scene frictionless = frictional;
  for (RodSpec& rod : frictionless.model.rods) rod.contact.friction = 0.0;
  // The thrown rod's middle node at the end, and the closest the rods came.
  const auto run = [](const Scene& s) {
    Simulator forward(s.model, s.solver);
    double closest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < s.frames; ++k) {
      forward.step();
      closest = std::min(closest, forward.min_rod_separation());
    }
    return std::pair{forward.state().points[s.model.rod_point(1, 3)], closest};
  };
  // And with a dashpot between the rods (EdgeDamping, c = 0.5 N·s/m on both).
  const Scene damped = [&] {
    Scene s = frictional;
    for (RodSpec& rod : s.model.rods) rod.contact.damping = 0.5;
    return s;
  }();
  for (const Scene* s : {&on_floor, &frictional, &damped}) {
    ASSERT_LT(run(*s).second, 0.0);  // the rods touch: the check runs through their contact
    EXPECT_TRUE(test::gradient_agrees(*s));
  }
  // Friction changed the outcome: the thrown rod ends elsewhere than without it.
  EXPECT_GT((run(frictional).first - run(frictionless).first).norm(), 1e-3);
}

// Friction between rods against its closed form: a short rod (the slider, 4 edges) lies on two
// parallel clamped rods (the rails, 3 cm apart centre to centre, all radii 1 cm), under gravity
// tilted by θ along the rails. Each rail's contact normal leans by φ from the vertical, sin φ =
// 1.5/2, so the rails press with W cos θ / cos φ in all (a wedge), and the slider
//   slides with a = g (sin θ − μ cos θ / cos φ) when tan θ > μ / cos φ,
//   creeps at ε_v (1 − √(1 − tan θ cos φ / μ)) below it (the smoothed law's f₁ = that fraction
//   of μλ; friction.hpp), and
//   slides with a = g sin θ without friction.
// Backward Euler is exact for a constant force, so the acceleration is measured between
// 0.1 s and 0.2 s from the slider's middle node.
TEST(RodContactScenes, ARodOnTwoTiltedRodsSticksBelowItsFrictionAngleAndSlidesAboveIt) {
  const double g = 9.81, cos_phi = std::sqrt(1.0 - 0.75 * 0.75), epsilon_v = 1e-3;
  const auto middle_velocity = [&](double mu, double theta, double at) {
    const auto rod = [&](const std::string& name, double y, double z, double half, int edges, bool clamped) {
      std::string fixed;
      for (int i = 0; clamped && i <= edges; ++i) fixed += std::string(i ? ", " : "") + std::to_string(i);
      const std::string fixed_edges = clamped ? fixed.substr(0, fixed.rfind(',')) : "";
      return R"({"name": ")" + name + R"(", "shape": {"type": "line", "start": [)" + std::to_string(-half) + ", " +
             std::to_string(y) + ", " + std::to_string(z) + "], \"end\": [" + std::to_string(half) + ", " + std::to_string(y) +
             ", " + std::to_string(z) + "], \"edges\": " + std::to_string(edges) +
             R"(}, "mass": 0.05, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                 "bending_stiffness": [1e-3, 1e-3, 1e-3], "fixed_nodes": [)" + fixed + R"(], "fixed_edges": [)" + fixed_edges +
             R"(], "contact": {"stiffness": 1e4, "friction": )" + std::to_string(mu) + "}}";
    };
    const double z = 0.02 * cos_phi;  // resting on both rails
    const Scene s = parse_scene(R"({"time_step": 0.002, "frames": 100, "gravity": [)" + std::to_string(g * std::sin(theta)) +
                                    ", 0, " + std::to_string(-g * std::cos(theta)) + R"(], "rods": [)" +
                                    rod("left", -0.015, 0.0, 0.5, 20, true) + "," + rod("right", 0.015, 0.0, 0.5, 20, true) +
                                    "," + rod("slider", 0.0, z, 0.1, 4, false) + "]}",
                                "slider.json");
    Simulator sim(s.model, s.solver);
    const int middle = s.model.rod_point(2, 2);
    double v = 0.0;
    for (int k = 1; k <= static_cast<int>(std::lround(at / s.model.time_step)); ++k) {
      EXPECT_TRUE(sim.step().converged()) << k;
      v = sim.linear_velocity(middle).x();
    }
    return v;
  };
  const double theta_slide = 35.0 * std::numbers::pi / 180.0, theta_stick = 20.0 * std::numbers::pi / 180.0;
  const auto acceleration = [&](double mu, double theta) {
    return (middle_velocity(mu, theta, 0.2) - middle_velocity(mu, theta, 0.1)) / 0.1;
  };
  const double mu = 0.3;
  EXPECT_NEAR(acceleration(0.0, theta_slide), g * std::sin(theta_slide), 0.01 * g * std::sin(theta_slide));
  const double sliding = g * (std::sin(theta_slide) - mu * std::cos(theta_slide) / cos_phi);
  EXPECT_NEAR(acceleration(mu, theta_slide), sliding, 0.01 * sliding);
  const double creep = epsilon_v * (1.0 - std::sqrt(1.0 - std::tan(theta_stick) * cos_phi / mu));
  EXPECT_NEAR(middle_velocity(mu, theta_stick, 0.2), creep, 0.03 * creep);
}

// Rods on bodies: a rod's free nodes against a body's shape (BodyContact with a sample that has
// no rotation). A rod dropped across a box resting on the floor comes to rest on the box; told
// to ignore it, it falls through to the floor. A rod thrown at a free ball without gravity
// keeps the total momentum of rod and ball.
std::string rod_json(const std::string& name, const std::string& start, const std::string& end, const std::string& extra) {
  return R"({"name": ")" + name + R"(", "shape": {"type": "line", "start": )" + start + R"(, "end": )" + end +
         R"(, "edges": 10}, "mass": 0.05, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
             "bending_stiffness": [1e-3, 1e-3, 1e-3])" + extra + "}";
}

TEST(RodContactScenes, ARodDroppedOnABoxRestsOnItAndPushesABall) {
  const auto scene = [](const std::string& filter) {
    return parse_scene(R"({"time_step": 0.002, "frames": 400, "gravity": [0, 0, -9.81],
        "colliders": [{"name": "floor", "type": "plane"}],
        "bodies": [{"name": "box", "density": 500, "position": [0, 0, 0.0505],
                    "contact": {"stiffness": 1e5, "radius": 0.001, "friction": 0.5,
                                "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.05]}, "sample_spacing": 0.05}}],
        "rods": [)" + rod_json("rod", "[-0.25, 0.02, 0.13]", "[0.25, 0.02, 0.13]",
                              R"(, "contact": {"stiffness": 1e4, "friction": 0.5)" + filter + "}") + "]}",
                       "rod_on_box.json");
  };
  // The lowest node over the box's top (|x| < 9 cm) at the end.
  const auto lowest_over_box = [](const Scene& s) {
    Simulator sim(s.model, s.solver);
    for (int k = 1; k <= s.frames; ++k) EXPECT_TRUE(sim.step().state_updated()) << k;
    double lowest = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 10; ++i) {
      const Vector3& x = sim.state().points[sim.model().rod_point(0, i)];
      if (std::abs(x.x()) < 0.09) lowest = std::min(lowest, x.z());
    }
    return lowest;
  };
  ASSERT_EQ(scene("").model.rod_body_pairs().size(), 1u);
  // Draped over the box (its ends on the floor): no node sinks into the top, at 10.05 cm,
  // by more than a millimetre beyond its radius.
  EXPECT_GT(lowest_over_box(scene("")), 0.1005 + 0.01 - 1e-3);
  EXPECT_LT(lowest_over_box(scene(R"(, "ignores": ["box"])")), 0.0105);  // through it, onto the floor

  const Scene ball = parse_scene(R"({"time_step": 0.001, "frames": 200, "solver": {"tolerance": 1e-12},
      "bodies": [{"name": "ball", "density": 1000, "contact": {"stiffness": 1e4, "shape": {"type": "sphere", "radius": 0.05}}}],
      "rods": [)" + rod_json("rod", "[-0.2, 0.01, 0.1]", "[0.2, 0.01, 0.1]", R"(, "node_velocities": [[0, 0, -1], [0, 0, -1],
          [0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, -1]],
          "contact": {"stiffness": 1e4})") + "]}",
      "rod_on_ball.json");
  Simulator sim(ball.model, ball.solver);
  const RodDiscretization d = discretize(ball.model.rods[0]);
  const auto momentum = [&] {
    Vector3 p = ball.model.bodies[0].mass * sim.linear_velocity(0);
    for (int i = 0; i <= 10; ++i) p += d.node_mass[i] * sim.linear_velocity(ball.model.rod_point(0, i));
    return p;
  };
  const Vector3 p0 = momentum();
  double drift = 0.0;
  int touching = 0;
  for (int k = 1; k <= ball.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    drift = std::max(drift, (momentum() - p0).norm());
    touching += sim.contact_pairs() > 0;
  }
  EXPECT_GT(touching, 5);
  EXPECT_LT(drift, 1e-8);
  // The ball was pushed down: it carries a good part of the rod's momentum.
  EXPECT_LT(ball.model.bodies[0].mass * sim.linear_velocity(0).z(), -0.3 * p0.norm());
}

// The adjoint through contact between a rod and a body: the rod thrown onto a box resting on
// the floor, γ its initial node velocities; and with the rod's contact damped (c = 2 N·s/m:
// EdgeBodyDamping on its edges, BodyDamping at its tips, the floor's ContactDamping), whose
// mixed blocks then enter the backward pass.
TEST(RodContactAdjoint, TheGradientRunsBackThroughARodOnABody) {
  for (const std::string damping : {"", R"(, "damping": 2)"}) {
    SCOPED_TRACE(damping);
    const Scene scene = parse_scene(R"({"time_step": 0.002, "frames": 80, "gravity": [0, 0, -9.81],
      "solver": {"tolerance": 1e-12, "max_iterations": 100},
      "colliders": [{"type": "plane"}],
      "bodies": [{"name": "box", "density": 500, "position": [0, 0, 0.0505],
                  "contact": {"stiffness": 1e4, "radius": 0.001,
                              "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.05]}, "sample_spacing": 0.05}}],
      "rods": [)" + rod_json("thrown", "[-0.25, 0.02, 0.13]", "[0.25, 0.02, 0.13]",
                             R"(, "contact": {"stiffness": 2e3)" + damping + "}") + R"(],
      "optimization": {
        "parameters": [{"kind": "rod_node_velocities", "rod": "thrown"}],
        "objective": [{"term": "point_targets", "rod": "thrown", "frame": -1,
                       "polyline": [[0.1, -0.2, 0.2], [0.1, 0.2, 0.2]]}]}})",
                                    "rod_on_box_adjoint.json");
    Simulator forward(scene.model, scene.solver);
    int touching = 0;
    for (int k = 0; k < scene.frames; ++k) {
      forward.step();
      touching += forward.contact_pairs() > 1;  // the box on the floor, and the rod on the box
    }
    ASSERT_GT(touching, 5);
    EXPECT_TRUE(test::gradient_agrees(scene));
  }
}

// The bundled polyp (contact/polyp.json): the endoscope of tube_insertion.json rides over a
// rigid ball welded to the tube's wall in its way. Its nodes touch the ball for many frames
// but never sink into it by their radius, the weld holds the ball in place, and the tip still
// passes the S-bend and climbs (z > 0.1 m at the end).
TEST(RodContactScenes, TheEndoscopeRidesOverThePolyp) {
  const Scene scene = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/polyp.json");
  ASSERT_EQ(scene.model.rod_body_pairs().size(), 1u);
  const RodSpec& rod = scene.model.rods[0];
  const double ball = std::get<SphereShape>(scene.model.bodies[0].shape->shape).radius;
  const Vector3 centre = scene.model.bodies[0].position;
  Simulator sim(scene.model, scene.solver);
  double closest = std::numeric_limits<double>::infinity(), moved = 0.0;
  int touching = 0;
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << k << ": " << r.message;
    double nearest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < rod.node_count(); ++i) {
      nearest = std::min(nearest, (sim.state().points[sim.model().rod_point(0, i)] - centre).norm() - ball);
    }
    closest = std::min(closest, nearest);
    touching += nearest < rod.contact.radius;
    moved = std::max(moved, (sim.state().points[0] - centre).norm());
  }
  EXPECT_GT(touching, 100);
  EXPECT_GT(closest, 0.5 * rod.contact.radius);  // node centres stay well outside the ball
  EXPECT_LT(moved, 1e-6);
  EXPECT_GT(sim.state().points[sim.model().rod_point(0, rod.node_count() - 1)].z(), 0.1);
}

TEST(RodContactScenes, SelfContactKeysAreChecked) {
  const auto error = [](const std::string& contact) {
    try {
      parse_scene(R"({"time_step": 0.01, "frames": 1, "rods": [{"name": "r", "shape": {"type": "line", "start": [0, 0, 0],
                       "end": [1, 0, 0], "edges": 10}, "mass": 1, "radius": 0.01, "stretch_stiffness": 1, "shear_stiffness": 1,
                       "bending_stiffness": [1, 1, 1], "contact": {"stiffness": 1e3, )" + contact + "}}]}",
                  "s.json");
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(R"("self_contact": true, "self_contact_skip": 3)"), "accepted");
  EXPECT_EQ(error(R"("self_contact": 1)"), "rods[0].contact.self_contact: must be true or false (got number)");
  EXPECT_EQ(error(R"("self_contact_skip": 0)").rfind("rods[0].contact.self_contact_skip: ", 0), 0u);
}

}  // namespace
}  // namespace liedyn

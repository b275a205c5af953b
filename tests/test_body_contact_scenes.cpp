// Contact between bodies in whole runs (lib/body_contact.hpp; pairs and islands:
// TouchingPairs, solvers/islands.hpp): the bundled two balls, head-on and off-centre.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <fstream>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include "adjoint_check.hpp"
#include "cli_fixture.hpp"
#include "lib/body_contact.hpp"
#include "problems/recorded_run.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

Scene two_spheres() {
  return load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/two_spheres.json");
}

Vector3 momentum(const Simulator& sim) {
  Vector3 p = Vector3::Zero();
  for (std::size_t i = 0; i < sim.model().bodies.size(); ++i) {
    p += sim.model().bodies[i].mass * sim.linear_velocity(static_cast<int>(i));
  }
  return p;
}

// Without friction and with friction between the balls (μ = 0.5 on both): the forces are
// internal either way.
TEST(BodyContactScenes, TwoBallsCollideKeepingTheirMomentumAndLosingEnergy) {
  for (const double friction : {0.0, 0.5}) {
    for (const double offset : {0.0, 0.05}) {  // head-on, and the bundled off-centre shot
      SCOPED_TRACE(testing::Message() << "offset " << offset << ", friction " << friction);
      Scene scene = two_spheres();
      scene.model.bodies[0].position.y() = offset;
      for (RigidBody& b : scene.model.bodies) b.contact.friction = friction;
      Simulator sim(scene.model, scene.solver);
      const Vector3 p0 = momentum(sim);
      double energy = sim.kinetic_energy() + sim.potential_energy();
      double deepest = 0.0, drift = 0.0, rise = 0.0;
      int touching = 0, islands_apart = 0, islands_together = 0;
      for (int k = 1; k <= scene.frames; ++k) {
        const StepReport r = sim.step();
        ASSERT_TRUE(r.converged()) << k << ": " << r.message;
        const double e = sim.kinetic_energy() + sim.potential_energy();
        rise = std::max(rise, e - energy);
        energy = e;
        drift = std::max(drift, (momentum(sim) - p0).norm());
        deepest = std::max(deepest, sim.max_penetration());
        touching += sim.contact_pairs() > 0;
        (sim.islands() == 1 ? islands_together : islands_apart) += 1;
      }
      // The internal forces cancel in every step's force balance: the momentum moves only by the
      // solver's residual (tolerance 1e-12 m on the Newton step).
      EXPECT_LT(drift, 1e-9 * p0.norm());
      EXPECT_LE(rise, 1e-12);
      EXPECT_LT(deepest, scene.model.bodies[0].contact.radius);  // no sample through the other's
      EXPECT_GT(deepest, 0.0);
      // They met and parted: the pair coupled them into one island for a while only.
      EXPECT_GT(touching, 5);
      EXPECT_GT(islands_together, 5);
      EXPECT_GT(islands_apart, 100);
      // The target was struck: it carries a good part of the momentum.
      EXPECT_GT(sim.linear_velocity(1).norm(), 0.3 * p0.norm() / scene.model.bodies[1].mass);
      EXPECT_GT(sim.island_sets(), 1);
    }
  }
}

// A ball's contact normals pass through its centre, so without friction two colliding balls
// do not spin, and with friction the off-centre shot sets both spinning. The samples see the
// other ball's sphere at their own places, not at the exact contact point: their torques
// cancel only as the lattice gets fine (without friction, 2.1 rad/s at the bundled 2 cm,
// 0.23 at 1 cm, 0.024 at 5 mm, against the shot's 2 m/s at 0.1 m); at 5 mm spacing
// (spheres of 1.25 mm) the artefact is two orders below friction's spin.
TEST(BodyContactScenes, BallsSpinOnlyWithFriction) {
  for (const double friction : {0.0, 0.5}) {
    SCOPED_TRACE(friction);
    Scene scene = two_spheres();
    for (RigidBody& b : scene.model.bodies) {
      b.contact_points = surface_samples(*b.shape, 0.005, 100000, "test");
      b.contact.radius = 0.00125;
      b.contact.friction = friction;
    }
    Simulator sim(scene.model, scene.solver);
    for (int k = 1; k <= scene.frames; ++k) ASSERT_TRUE(sim.step().converged()) << k;
    ASSERT_GT(sim.linear_velocity(1).norm(), 0.5);  // struck
    for (int ball : {0, 1}) {
      if (friction > 0.0) {
        EXPECT_GT(sim.angular_velocity(ball).norm(), 1.0);
      } else {
        EXPECT_LT(sim.angular_velocity(ball).norm(), 0.05);
      }
    }
  }
}

// The bundled tower (contact/box_tower.json): four boxes on a floor tilted by 10°, below the
// friction angle (26.6°) and the tipping angle (14°). Friction between the boxes and on the
// floor holds it: no box moves more than 1 mm over the 3 s (the first step, before any
// friction is lagged in, and the creep of sticking below ε_v make up what they do move).
// Without friction it slides away; tilted by 30°, past both angles, it falls.
TEST(BodyContactScenes, ATowerOfBoxesStandsOnATiltedFloorByFrictionAndFallsPastItsAngle) {
  const Scene bundled = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/box_tower.json");
  ASSERT_EQ(bundled.model.bodies.size(), 4u);
  const int top = 3;
  // A step of a sliding or tumbling tower may stall at round-off, the Hessian shifted where
  // a sharp edge's SDF curves (a step ~1e-13 m off): its state stands. The standing tower
  // converges in every step.
  const auto run = [&](const Scene& scene, int frames, bool every_step_converges = false) {
    Simulator sim(scene.model, scene.solver);
    const Vector3 start = sim.state().points[top];
    double drift = 0.0;
    for (int k = 1; k <= frames; ++k) {
      const StepReport r = sim.step();
      if (!r.state_updated()) {
        ADD_FAILURE() << k << ": " << r.message;
        break;
      }
      if (every_step_converges) {
        EXPECT_TRUE(r.converged()) << k << ": " << r.message;
      }
      drift = std::max(drift, (sim.state().points[top] - start).norm());
    }
    return std::tuple{drift, sim.state().points[top], sim.contact_pairs()};
  };
  const auto [drift, end, pairs] = run(bundled, bundled.frames, true);
  EXPECT_LE(drift, 1e-3);
  EXPECT_EQ(pairs, 4);  // the floor and the bottom box, and three pairs of boxes
  EXPECT_GE(bundled.frames * bundled.model.time_step, 3.0);

  Scene frictionless = bundled;
  for (RigidBody& b : frictionless.model.bodies) b.contact.friction = 0.0;
  EXPECT_GT(std::get<0>(run(frictionless, 100)), 0.05);  // in 1 s

  Scene steep = bundled;
  const double angle = 30.0 * std::numbers::pi / 180.0;
  steep.model.gravity = 9.81 * Vector3(std::sin(angle), 0.0, -std::cos(angle));
  const auto [steep_drift, steep_end, steep_pairs] = run(steep, 200);
  EXPECT_LT(steep_end.z(), 0.5 * bundled.model.bodies[top].position.z());  // fallen
}

// A pair that only meets within a step: the cue at rest, its samples 1 mm off the target, pushed by
// 500 N for one 10 ms step, 5 cm at 1 kg, half the target's radius. At the step's start
// nothing is within reach (no motion yet: margin 0); the step's solution lies deep in the
// target, so the step is solved again with the pair coupled, and ends with the cue resting on
// the target's surface at the penalty's depth F/k, not inside it.
TEST(BodyContactScenes, APairThatMeetsWithinAStepIsSolvedAgainCoupled) {
  Scene scene = two_spheres();
  scene.model.time_step = 0.01;
  for (RigidBody& b : scene.model.bodies) {
    b.linear_velocity.setZero();
    b.contact.stiffness = 1e6;
  }
  scene.model.bodies[0].position = Vector3(-0.206, 0.0, 0.0);  // samples 1 mm off
  ForceSpec push;
  push.at.body = 0;
  push.force = Vector3(500.0, 0.0, 0.0);
  scene.model.forces.push_back(push);
  Simulator sim(scene.model, scene.solver);
  EXPECT_EQ(sim.contact_pairs(), 0);
  const StepReport r = sim.step();
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(sim.contact_pairs(), 1);
  EXPECT_EQ(sim.islands(), 1);
  EXPECT_GT(sim.max_penetration(), 0.0);
  EXPECT_LT(sim.max_penetration(), scene.model.bodies[0].contact.radius);
  // The report counts both rounds' work: the first round's two single-body solves assembled at
  // least max(their iterations, 1) times each, the coupled solve at least its iterations, and
  // the report's iterations are the first round's largest plus the coupled solve's.
  EXPECT_GE(r.assemblies, r.iterations + 1);
  EXPECT_GE(r.factorizations, r.assemblies);
}

// A body's shape and its samples: bad values name their field.
TEST(BodyContactScenes, BadShapesNameTheirField) {
  const auto error = [](const std::string& contact) {
    try {
      parse_scene(R"({ "time_step": 0.01, "frames": 1, "bodies": [ { "name": "a", "mass": 1, "inertia": [1, 1, 1],
                       "contact": { "stiffness": 1e4, )" + contact + " } } ] }",
                  "s.json");
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(R"("shape": { "type": "sphere", "radius": 0.1 }, "sample_spacing": 0.02)"), "accepted");
  EXPECT_EQ(error(R"("shape": { "type": "plane" })"),
            "bodies[0].contact.shape.type: a body's shape must be a sphere, box, capsule, torus, "
            "cylinder, link or mesh (a moving plane, tube or inside-out shape is a collider with a "
            "\"kinematic\" block)");
  EXPECT_EQ(error(R"("shape": { "type": "sphere", "radius": 0.1, "inside": true })"),
            "bodies[0].contact.shape.inside: a body's shape is a solid, not its complement (a moving "
            "plane, tube or inside-out shape is a collider with a \"kinematic\" block)");
  EXPECT_EQ(error(R"("sample_spacing": 0.02, "points": [[0, 0, 0]])"),
            "bodies[0].contact.sample_spacing: samples a \"shape\": give one");
  EXPECT_EQ(error(R"("shape": { "type": "box", "half_extents": [1, 1, 1] }, "sample_spacing": 0)"),
            "bodies[0].contact.sample_spacing: must be a positive number of metres");
  EXPECT_EQ(error(R"("shape": { "type": "sphere", "radius": 1 }, "sample_spacing": 1e-6)")
                .rfind("bodies[0].contact.sample_spacing: would give about ", 0),
            0u);
}

// The billiard shot with friction between the balls (μ = 1 on both): the gradient runs back
// through the lagged friction's mixed blocks (BodyFriction::add_step_adjoint; without them
// the worst relative error is 1.7, not ~1e-6).
TEST(BodyContactAdjoint, TheBilliardGradientRunsBackThroughFrictionBetweenTheBalls) {
  Scene scene = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/optimization/billiard.json");
  for (RigidBody& b : scene.model.bodies) b.contact.friction = 1.0;
  EXPECT_TRUE(test::gradient_agrees(scene));
}

// ... and through the dashpot between them (BodyDamping, c = 20 N·s/m on both balls' samples:
// ζ ≈ 0.05 per sample), under backward Euler and the trapezoidal rule (the history terms'
// blocks beside the dashpot's).
TEST(BodyContactAdjoint, TheBilliardGradientRunsBackThroughDampingBetweenTheBalls) {
  for (const Integrator integrator : {Integrator::kBackwardEuler, Integrator::kTrapezoidal}) {
    SCOPED_TRACE(to_string(integrator));
    Scene scene =
        load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/optimization/billiard.json");
    scene.model.integrator = integrator;
    for (RigidBody& b : scene.model.bodies) b.contact.damping = 20.0;
    EXPECT_TRUE(test::gradient_agrees(scene));
  }
}

// "collides_with" and "ignores": a ball told to ignore another passes through it, one told
// to ignore the floor falls through it, and a pair touches only when both agree.
TEST(BodyContactScenes, CollidesWithAndIgnoresNarrowWhatTouches) {
  const auto scene = [](const std::string& a_filter, const std::string& b_filter) {
    const auto ball = [](const std::string& name, double x, double v, const std::string& filter) {
      return R"({"name": ")" + name + R"(", "mass": 1, "inertia": [0.004, 0.004, 0.004], "position": [)" +
             std::to_string(x) + R"(, 0, 0.2], "linear_velocity": [)" + std::to_string(v) +
             R"(, 0, 0], "contact": {"stiffness": 1e5, "radius": 0.005, "shape": {"type": "sphere", "radius": 0.1},
                 "sample_spacing": 0.03)" + filter + "}}";
    };
    return parse_scene(R"({"time_step": 0.001, "frames": 300, "gravity": [0, 0, -9.81],
                           "colliders": [{"name": "floor", "type": "plane"}], "bodies": [)" +
                           ball("a", -0.3, 2.0, a_filter) + "," + ball("b", 0.0, 0.0, b_filter) + "]}",
                       "filters.json");
  };
  // Each run: where a and b end (x of a, z of a).
  const auto run = [](const Scene& s) {
    Simulator sim(s.model, s.solver);
    for (int k = 1; k <= s.frames; ++k) EXPECT_TRUE(sim.step().state_updated()) << k;
    return std::pair{sim.state().points[0].x(), sim.state().points[0].z()};
  };
  const auto [x_hit, z_hit] = run(scene("", ""));
  EXPECT_LT(x_hit, -0.05);  // struck b and stopped short of it (head-on: b took its speed)
  EXPECT_GT(z_hit, 0.09);   // on the floor
  EXPECT_GT(run(scene(R"(, "ignores": ["b"])", "")).first, 0.2);  // through b
  EXPECT_GT(run(scene("", R"(, "collides_with": ["floor"])")).first, 0.2);  // b does not agree
  EXPECT_LT(run(scene(R"(, "collides_with": ["b", "floor"])", "")).first, -0.05);
  EXPECT_LT(run(scene(R"(, "ignores": ["floor"])", "")).second, 0.0);  // through the floor
  EXPECT_EQ(scene(R"(, "ignores": ["b"])", "").model.body_pairs().size(), 0u);

  const auto error = [&](const std::string& filter) {
    try {
      scene(filter, "");
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(R"(, "ignores": ["c"])"), "bodies[0].contact.ignores[0]: no body, rod or collider is named \"c\"");
  EXPECT_EQ(error(R"(, "collides_with": ["floor", "a"])"), "bodies[0].contact.collides_with[1]: names its own object");
  EXPECT_EQ(error(R"(, "collides_with": ["b"], "ignores": ["floor"])"),
            "bodies[0].contact.ignores: give \"collides_with\" or \"ignores\", not both");
  EXPECT_EQ(error(R"(, "ignores": [3])"), "bodies[0].contact.ignores[0]: must be the name of a body or a collider");
}

class BodyContactCli : public test::CliFixture {
 protected:
  BodyContactCli() : CliFixture("liedyn_body_contact_test_") {}
};

// frames.csv counts the pairs in contact per frame: none before the balls meet, one (the
// pair) while they touch, none after.
TEST_F(BodyContactCli, FramesCsvCountsThePairsInContact) {
  const std::filesystem::path scene =
      std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/two_spheres.json";
  const Result r = run({"simulate", scene.string(), "--out", "balls"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const FramesTable frames = read_frames_table(dir_ / "balls" / "frames.csv");
  std::string counts;
  for (const double pairs : frames.numbers("contact_pairs")) {
    const char c = static_cast<char>('0' + static_cast<int>(pairs));
    if (counts.empty() || counts.back() != c) counts += c;
  }
  // min_rod_separation is empty without rods; every solve assembled and factorised (dense
  // bodies never reuse a factorisation), frame 0 none.
  for (const double separation : frames.numbers("min_rod_separation")) EXPECT_TRUE(std::isnan(separation));
  const std::vector<double> assemblies = frames.numbers("assemblies");
  const std::vector<double> factorizations = frames.numbers("factorizations");
  const std::vector<double> reused = frames.numbers("reused_factorizations");
  EXPECT_EQ(assemblies[0], 0.0);
  for (std::size_t k = 1; k < assemblies.size(); ++k) {
    EXPECT_GE(assemblies[k], 1.0) << k;
    EXPECT_GE(factorizations[k], 1.0) << k;
    EXPECT_EQ(reused[k], 0.0) << k;
  }
  EXPECT_EQ(counts, "010");
}

// The billiard shot (optimization/billiard.json): the gradient through the collision agrees
// with central differences, and NLopt's and Ipopt's L-BFGS aim the cue ball so that the
// target ends within the normalised loss of 1e-4.
TEST_F(BodyContactCli, TheBilliardShotIsDifferentiableAndAimed) {
  const std::filesystem::path scene =
      std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/optimization/billiard.json";
  const Result check = run({"gradcheck", scene.string()});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  for (const char* optimizer : {"nlopt-lbfgs", "ipopt-lbfgs"}) {
    SCOPED_TRACE(optimizer);
    const std::string out = std::string("shot_") + optimizer;
    const Result r = run({"optimize", scene.string(), "--optimizer", optimizer, "--out", out});
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_LE(test::best_normalized_loss(dir_ / out / "history.csv"), 1e-4);
  }
}

}  // namespace
}  // namespace liedyn

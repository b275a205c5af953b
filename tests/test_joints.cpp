// Elastic joints between bodies and the world (lib/model.hpp JointSpec, built into springs
// and the rotational terms of lib/joint_terms.hpp, whose derivatives tests/test_joint_terms.cpp
// checks by finite differences): the scene format, mechanics against closed forms, the
// back-ends and parameterisations against each other, and the adjoint through a joint.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_fixture.hpp"
#include "lib/incremental_potential.hpp"
#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;
const fs::path kScenes = fs::path(LIEDYN_SOURCE_DIR) / "problems/scenes";

Scene joint_scene(const std::string& name) {
  return load_scene(kScenes / "joints" / name);
}

// World position of body point p̄.
Vector3 world_point(const State& q, int body, const Vector3& local) {
  return q.points[body] + q.rotations[body] * local;
}

// The period of the pendulum on its hinge against the closed form: small-amplitude
// 2π √((I + mL²)/(mgL)) = 1.678 s, lengthened by θ₀²/16 at θ₀ = 0.3 (the next term of the
// series, 11θ₀⁴/3072, is 3e-5). Backward Euler shifts the period by O((ωh)²) ≈ 6e-5 at
// h = 2 ms (ω = 3.74 rad/s) and the hinge's compliance by ~1e-6: 1e-3 bounds all of them with
// room, while a pivot in the wrong place (L off by 1 %) would miss by 5e-3.
TEST(Joints, HingedPendulumSwingsWithTheCompoundPendulumPeriod) {
  const Scene scene = joint_scene("pendulum.json");
  Simulator sim(scene.model, scene.solver);
  std::vector<double> crossings;
  double x_before = sim.state().points[0].x(), out_of_plane = 0.0, gap = 0.0;
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << "frame " << k;
    const double x = sim.state().points[0].x();
    if (x_before < 0.0 && x >= 0.0) {
      crossings.push_back(sim.time() - scene.model.time_step * x / (x - x_before));
    }
    x_before = x;
    out_of_plane = std::max(out_of_plane, std::abs(sim.state().points[0].y()));
    gap = std::max(gap, world_point(sim.state(), 0, Vector3(0, 0, 0.5)).norm());
  }
  ASSERT_GE(crossings.size(), 3u);
  const double m = 1.0, I = 0.1, L = 0.5, g = 9.81, theta0 = 0.3;
  const double expected =
      2.0 * std::numbers::pi * std::sqrt((I + m * L * L) / (m * g * L)) * (1.0 + theta0 * theta0 / 16.0);
  for (std::size_t i = 1; i < crossings.size(); ++i) {
    EXPECT_NEAR((crossings[i] - crossings[i - 1]) / expected, 1.0, 1e-3) << "period " << i;
  }
  EXPECT_EQ(out_of_plane, 0.0);  // a swing in the x-z plane stays there exactly
  // The pivot stays at the origin within the hinge's compliance × its load (≲ 20 N).
  EXPECT_LT(gap, 20.0 * 1e-7);
}

// Kicked out of its plane, the hinge holds the axis: the body's swing axis stays within the
// rotational compliance × the torque it takes (ω_x = 1 rad/s against k = 1e7 N·m/rad and
// I = 0.1 kg m²: an angle ~ ω √(I/k) = 1e-4 rad).
TEST(Joints, AHingeHoldsItsAxisAgainstAnOutOfPlaneKick) {
  Scene scene = joint_scene("pendulum.json");
  scene.model.bodies[0].angular_velocity = Vector3(1.0, 0.0, 0.0);
  Simulator sim(scene.model, scene.solver);
  double tilt = 0.0;
  for (int k = 1; k <= 500; ++k) {
    ASSERT_TRUE(sim.step().state_updated()) << "frame " << k;
    const Vector3 axis = sim.state().rotations[0] * Vector3::UnitY();
    tilt = std::max(tilt, std::acos(std::min(1.0, axis.dot(Vector3::UnitY()))));
  }
  EXPECT_GT(tilt, 1e-6);  // the kick did reach the hinge
  EXPECT_LT(tilt, 1e-3);
}

// A body welded to the world, in static equilibrium under gravity and a torque: it sags by
// m g × compliance and turns by τ × compliance_rotation (to second order in the angle).
TEST(Joints, AWeldedBodySagsAndTurnsByItsCompliances) {
  const Scene scene = parse_scene(R"({
    "mode": "static", "time_step": 0.01, "frames": 4, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-12, "max_iterations": 50 },
    "bodies": [ { "name": "b", "mass": 2, "inertia": [1, 2, 3], "position": [1, 2, 3],
                  "orientation": [0.9, 0.3, -0.2, 0.2449489742783178] } ],
    "torques": [ { "body": "b", "torque": [0, 0, 0.5] } ],
    "joints": [ { "type": "weld", "compliance": 1e-4, "compliance_rotation": 2e-4,
                  "a": { "body": "b" } } ] })",
                                 "weld.json");
  Simulator sim(scene.model, scene.solver);
  const Matrix3 R0 = sim.state().rotations[0];
  for (int k = 1; k <= scene.frames; ++k) ASSERT_TRUE(sim.step().converged()) << k;
  EXPECT_NEAR(sim.state().points[0].z() - 3.0, -2.0 * 9.81 * 1e-4, 1e-12);
  EXPECT_NEAR(sim.state().points[0].x(), 1.0, 1e-12);
  const Vector3 turn = so3::log(sim.state().rotations[0] * R0.transpose());
  EXPECT_NEAR(turn.z(), 0.5 * 2e-4, 1e-8);
  EXPECT_NEAR(turn.head<2>().norm(), 0.0, 1e-8);
}

// The largest gap over the first `frames` frames between the chain's hinge points (link 0's
// back end and the origin, each link's back end and the previous link's front end).
double largest_hinge_gap(const Scene& scene, int frames, double* energy_increase = nullptr) {
  Simulator sim(scene.model, scene.solver);
  double energy = sim.kinetic_energy() + sim.potential_energy(), gap = 0.0, increase = -INFINITY;
  const Vector3 back(-0.1, 0, 0), front(0.1, 0, 0);
  for (int k = 1; k <= frames; ++k) {
    EXPECT_TRUE(sim.step().converged()) << "frame " << k;
    const double e = sim.kinetic_energy() + sim.potential_energy();
    increase = std::max(increase, e - energy);
    energy = e;
    gap = std::max(gap, world_point(sim.state(), 0, back).norm());
    for (int i = 1; i < 4; ++i) {
      gap = std::max(gap, (world_point(sim.state(), i, back) -
                           world_point(sim.state(), i - 1, front)).norm());
    }
  }
  if (energy_increase != nullptr) *energy_increase = increase;
  return gap;
}

// The hinged chain: backward Euler never adds energy (the joints' terms are in the reported
// potential energy), and a hinge is a spring of stiffness 1/compliance: its gap is the force
// it carries times the compliance, so ten times stiffer hinges open ten times less (over the
// first 0.3 s, before the chain's motion depends chaotically on the compliance). The forces
// reach tens of newtons (the whip of the last links: 0.1 kg at several m/s on 0.2 m), hence
// the bound of 100 N × compliance.
TEST(Joints, HingedChainNeverGainsEnergyAndItsHingesAreSpringsOfTheirCompliance) {
  Scene scene = joint_scene("chain.json");
  double increase = 0.0;
  const double gap = largest_hinge_gap(scene, scene.frames, &increase);
  EXPECT_LE(increase, 1e-12);
  EXPECT_LT(gap, 100.0 * 1e-6);
  const double early = largest_hinge_gap(scene, 300);
  for (JointSpec& j : scene.model.joints) j.compliance = j.compliance_rotation = 1e-7;
  const double stiffer = largest_hinge_gap(scene, 300);
  EXPECT_GT(early, 0.0);
  EXPECT_NEAR(stiffer / early, 0.1, 0.02) << early << " against " << stiffer;
}

// Every back-end and parameterisation (Ipopt has no quat) gives the Newton/Lie trajectory of the chain (the
// hinges between bodies and to the world) to within the step tolerance's effect.
TEST(Joints, BackEndsAndParameterisationsAgreeOnTheChain) {
  Scene scene = joint_scene("chain.json");
  const int frames = 100;
  const auto run = [&](Backend backend, RotationParameterization rotation) {
    SolverOptions o = scene.solver;
    o.backend = backend;
    o.rotation = rotation;
    Simulator sim(scene.model, o);
    for (int k = 1; k <= frames; ++k) {
      const StepReport r = sim.step();
      EXPECT_TRUE(r.state_updated()) << to_string(backend) << " frame " << k << " " << r.message;
    }
    return sim.state();
  };
  const State reference = run(Backend::kNewton, RotationParameterization::kLie);
  const struct {
    Backend backend;
    RotationParameterization rotation;
  } cases[] = {{Backend::kNewton, RotationParameterization::kRotationVector},
               {Backend::kNewton, RotationParameterization::kQuaternion},
               {Backend::kCeres, RotationParameterization::kLie},
               {Backend::kCeres, RotationParameterization::kRotationVector},
               {Backend::kCeres, RotationParameterization::kQuaternion},
               {Backend::kIpopt, RotationParameterization::kLie},
               {Backend::kIpopt, RotationParameterization::kRotationVector}};
  for (const auto& c : cases) {
    const State q = run(c.backend, c.rotation);
    for (int i = 0; i < 4; ++i) {
      EXPECT_LT((q.points[i] - reference.points[i]).norm(), 1e-6)
          << to_string(c.backend) << "/" << to_string(c.rotation) << " link " << i;
      EXPECT_LT(so3::distance(q.rotations[i], reference.rotations[i]), 1e-6)
          << to_string(c.backend) << "/" << to_string(c.rotation) << " link " << i;
    }
  }
}

// A rod hanging from a gripper that swings on a hinge (joints/gripper_rod.json): the ball
// joint to the rod's top node makes rod and gripper one component; the joint stays closed
// within compliance × load (the rod's weight 0.49 N, with its swing a few newtons at most:
// 10 N × 1e-6), and the energy never increases.
TEST(Joints, ARodHangsFromAGripperByABallJoint) {
  const Scene scene = joint_scene("gripper_rod.json");
  EXPECT_EQ(build_components(scene.model).size(), 1u);
  Simulator sim(scene.model, scene.solver);
  const int top = scene.model.rod_point(0, 0);
  double energy = sim.kinetic_energy() + sim.potential_energy(), gap = 0.0;
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << "frame " << k;
    const double e = sim.kinetic_energy() + sim.potential_energy();
    EXPECT_LE(e, energy + 1e-12) << "frame " << k;
    energy = e;
    gap = std::max(gap, (world_point(sim.state(), 0, Vector3(0, 0, -0.1)) - sim.state().points[top]).norm());
  }
  EXPECT_LT(gap, 10.0 * 1e-6);
  EXPECT_GT(gap, 0.0);
  // The rod swings with the gripper: its tip has moved in x.
  const int tip = scene.model.rod_point(0, scene.model.rods[0].node_count() - 1);
  EXPECT_GT(std::abs(sim.state().points[tip].x() - scene.model.rods[0].nodes.back().x()), 1e-2);
  // Every back-end follows the same trajectory over the first 100 frames.
  const auto run = [&](Backend backend) {
    SolverOptions o = scene.solver;
    o.backend = backend;
    Simulator s(scene.model, o);
    for (int k = 1; k <= 100; ++k) EXPECT_TRUE(s.step().state_updated()) << to_string(backend) << " frame " << k;
    return s.state();
  };
  const State newton = run(Backend::kNewton);
  for (const Backend b : {Backend::kCeres, Backend::kIpopt}) {
    const State q = run(b);
    for (std::size_t i = 0; i < q.points.size(); ++i) {
      EXPECT_LT((q.points[i] - newton.points[i]).norm(), 1e-6) << to_string(b) << " point " << i;
    }
  }
}

// Bad joints are refused naming the field; what is not implemented says so.
TEST(Joints, BadJointsNameTheirField) {
  const auto error = [](const std::string& joint) {
    const std::string text = R"({ "time_step": 0.01, "frames": 1,
      "bodies": [ { "name": "a", "mass": 1, "inertia": [1, 1, 1] },
                  { "name": "r", "mass": 1, "inertia": [1, 1, 1], "position": [1, 0, 0] } ],
      "joints": [ )" + joint + " ] }";
    try {
      parse_scene(text, "j.json");
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 0, "a": { "body": "a" } })")
                .rfind("joints[0].compliance: exact joints (compliance 0) are not implemented yet", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": -1, "a": { "body": "a" } })")
                .rfind("joints[0].compliance: must be a finite number > 0", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "slider", "compliance": 1, "a": { "body": "a" } })")
                .rfind("joints[0].type: \"slider\" joints are not implemented yet", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "twist", "compliance": 1, "a": { "body": "a" } })")
                .rfind("joints[0].type: unknown joint type \"twist\"", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 1, "a": { "body": "a" }, "b": { "rod": "x", "node": 0 } })")
                .rfind("joints[0].b.rod: names no rod \"x\"", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 1, "a": { "body": "a" }, "b": { "rod": "x", "edge": 0 } })")
                .rfind("joints[0].b.edge: joints to rod edges are not implemented yet", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "hinge", "compliance": 1, "a": { "body": "a" } })")
                .rfind("joints[0].a.axis: a hinge needs its axis", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "hinge", "compliance": 1, "a": { "body": "a", "axis": [0, 0, 0] } })")
                .rfind("joints[0].a.axis: must be a non-zero vector", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 1, "a": { "body": "a", "axis": [0, 0, 1] } })")
                .rfind("joints[0].a.axis: only a hinge has an axis", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 1, "a": { "body": "a" }, "b": { "body": "a" } })")
                .rfind("joints[0].b.body: joins a body to itself", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "hinge", "compliance": 1, "a": { "body": "a", "axis": [0, 0, 1] }, "limits": [0, 1] })")
                .rfind("joints[0].limits: joint limits and motors are not implemented yet", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 1, "a": { "world": [0, 0, 0] } })")
                .rfind("joints[0].a.world: end a must be a body", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 1, "a": { "body": "a" }, "colour": 1 })")
                .rfind("joints[0].colour: unknown key", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "ball", "compliance": 1, "a": { "body": "a" } })"), "accepted");
}

// The joints in static mode anchor bodies, as springs do.
TEST(Joints, AJointToTheWorldAnchorsABodyInStaticMode) {
  const std::string body = R"("bodies": [ { "name": "a", "mass": 1, "inertia": [1, 1, 1] } ])";
  EXPECT_THROW(parse_scene(R"({ "mode": "static", "time_step": 0.01, "frames": 1, )" + body + "}", "s.json"),
               SceneError);
  EXPECT_NO_THROW(parse_scene(R"({ "mode": "static", "time_step": 0.01, "frames": 1, )" + body +
                                  R"(, "joints": [ { "type": "ball", "compliance": 1, "a": { "body": "a" } } ] })",
                              "s.json"));
}

class JointsCli : public test::CliFixture {
 protected:
  JointsCli() : CliFixture("liedyn_joints_test_") {}
};

// The adjoint through every joint type: gradcheck on a chain of a hinge to the world, a
// ball joint and a weld, optimising the initial velocities towards a pose; and through a rod
// held by a ball joint.
TEST_F(JointsCli, GradcheckPassesThroughEveryJointType) {
  {
    std::ofstream(dir_ / "scene.json") << R"({
      "time_step": 0.01, "frames": 30, "gravity": [0, 0, -9.81],
      "solver": { "tolerance": 1e-11, "max_iterations": 50 },
      "bodies": [
        { "name": "l0", "mass": 1, "inertia": [0.02, 0.03, 0.04], "position": [0.2, 0, 0] },
        { "name": "l1", "mass": 1, "inertia": [0.02, 0.03, 0.04], "position": [0.6, 0, 0] },
        { "name": "l2", "mass": 0.5, "inertia": [0.01, 0.02, 0.02], "position": [1.0, 0, 0.1] } ],
      "joints": [
        { "type": "hinge", "compliance": 1e-4, "a": { "body": "l0", "point": [-0.2, 0, 0], "axis": [0, 1, 0.2] } },
        { "type": "ball", "compliance": 1e-4, "a": { "body": "l1", "point": [-0.2, 0, 0] }, "b": { "body": "l0" } },
        { "type": "weld", "compliance": 1e-3, "a": { "body": "l2", "point": [-0.2, 0, -0.1] }, "b": { "body": "l1" } } ],
      "optimization": {
        "parameters": [ { "kind": "body_angular_velocity", "body": "l0" },
                        { "kind": "body_linear_velocity", "body": "l2" } ],
        "objective": [ { "term": "body_pose", "body": "l2", "frame": -1,
                         "position": [0.5, 0.3, -0.5], "orientation": [1, 0, 0, 0], "orientation_weight": 1 } ] } })";
  }
  const Result r = run({"gradcheck", "scene.json"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  // Through a body–rod component: the gripper's spin moves the rod it holds.
  nlohmann::json gripper =
      nlohmann::json::parse(test::read_file(kScenes / "joints/gripper_rod.json"));
  gripper["frames"] = 40;
  gripper["optimization"] = nlohmann::json::parse(R"({
      "parameters": [ { "kind": "body_angular_velocity", "body": "gripper" },
                      { "kind": "rod_node_velocities", "rod": "rod" } ],
      "objective": [ { "term": "body_pose", "body": "gripper", "frame": -1,
                       "position": [0.1, 0.05, -0.2], "orientation": [1, 0, 0, 0], "orientation_weight": 1 },
                     { "term": "point_targets", "rod": "rod", "frame": -1,
                       "polyline": [[0.2, 0.1, -0.3], [0.3, 0.2, -0.8]] } ] })");
  std::ofstream(dir_ / "gripper.json") << gripper.dump();
  const Result through_rod = run({"gradcheck", "gripper.json"});
  EXPECT_EQ(through_rod.exit_code, 0) << through_rod.out << through_rod.err;
}

}  // namespace
}  // namespace liedyn

// Islands that change during a run (solvers/islands.hpp): joints with active_frames split
// and join the components, each set of islands is built once, and what a released body does
// afterwards is free flight.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

RigidBody link(const std::string& name, const Vector3& position) {
  RigidBody b;
  b.name = name;
  b.mass = 0.5;
  b.inertia = Vector3(0.01, 0.02, 0.025).asDiagonal();
  b.position = position;
  b.angular_velocity = Vector3(0.5, -1.0, 2.0);
  return b;
}

// Two links under gravity, link 0 hinged to the world at the origin and link 1 welded to it at
// x = 0.5; `weld` gives the weld's active_frames, `hinge` the hinge's.
Model hinged_pair(int weld_first, int weld_last, int hinge_last = std::numeric_limits<int>::max()) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  model.bodies = {link("link0", Vector3(0.25, 0.0, 0.0)), link("link1", Vector3(0.75, 0.0, 0.0))};
  JointSpec hinge;
  hinge.type = JointSpec::Type::kHinge;
  hinge.a = JointEnd::body(0, Vector3(-0.25, 0.0, 0.0));
  hinge.b = JointEnd::world(Vector3::Zero());
  hinge.axis_a = hinge.axis_b = Vector3::UnitY();
  hinge.last_frame = hinge_last;
  JointSpec weld;
  weld.type = JointSpec::Type::kWeld;
  weld.a = JointEnd::body(1, Vector3(-0.25, 0.0, 0.0));
  weld.b = JointEnd::body(0, Vector3(0.25, 0.0, 0.0));
  weld.first_frame = weld_first;
  weld.last_frame = weld_last;
  model.joints = {hinge, weld};
  return model;
}

SolverOptions tight() {
  SolverOptions options;
  options.tolerance = 1e-12;
  return options;
}

TEST(ChangingIslands, AJointThatLetsGoSplitsTheIslandAndOneThatCatchesJoinsIt) {
  // The weld holds in steps 1–10 only: one island, then two.
  Simulator released(hinged_pair(1, 10), tight());
  EXPECT_EQ(released.islands(), 1);
  for (int k = 1; k <= 10; ++k) ASSERT_TRUE(released.step().converged()) << k;
  EXPECT_EQ(released.islands(), 1);
  ASSERT_TRUE(released.step().converged());
  EXPECT_EQ(released.islands(), 2);
  EXPECT_EQ(released.island_sets(), 2);
  // The weld holds from step 6 on: two islands, then one.
  Simulator caught(hinged_pair(6, std::numeric_limits<int>::max()), tight());
  EXPECT_EQ(caught.islands(), 2);
  for (int k = 1; k <= 5; ++k) ASSERT_TRUE(caught.step().converged()) << k;
  EXPECT_EQ(caught.islands(), 2);
  ASSERT_TRUE(caught.step().converged());
  EXPECT_EQ(caught.islands(), 1);
  EXPECT_LE(caught.constraint_violation(), 1e-12);
}

TEST(ChangingIslands, ASetThatHoldsAgainIsNotBuiltAgain) {
  // The weld holds in steps 4–6: sets {hinge}, {hinge, weld}, then {hinge} again.
  Simulator sim(hinged_pair(4, 6), tight());
  for (int k = 1; k <= 20; ++k) ASSERT_TRUE(sim.step().converged()) << k;
  EXPECT_EQ(sim.islands(), 2);
  EXPECT_EQ(sim.island_sets(), 2);
}

TEST(ChangingIslands, AReleasedBodyFliesFreely) {
  // Both joints let go after step 30: from then on each link is a free rigid body under
  // gravity, whose backward-Euler step is exactly x_k = 2 x_{k−1} − x_{k−2} + g h² (the
  // minimiser of ½ m/h² ‖x − x̃‖² − m g·x), whatever it did before.
  const Model model = hinged_pair(1, 30, 30);
  Simulator sim(model, tight());
  std::vector<Vector3> x;
  for (int k = 1; k <= 60; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    x.push_back(sim.state().points[1]);
  }
  EXPECT_EQ(sim.islands(), 2);
  const double h = model.time_step;
  // x[k − 1] is x_k. Step 31 is the first without the joints: from k = 31 on the rule holds.
  double worst = 0.0;
  for (int k = 31; k <= 60; ++k) {
    const Vector3 predicted = 2.0 * x[k - 2] - x[k - 3] + model.gravity * h * h;
    worst = std::max(worst, (x[k - 1] - predicted).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-12);
  // Before the release the weld held the link in place relative to link 0: not free flight.
  const Vector3 held = 2.0 * x[18] - x[17] + model.gravity * h * h;
  EXPECT_GT((x[19] - held).norm(), 1e-6);
}

// The bundled scene: the gripper's weld on the rod's first edge holds for 50 steps, then
// the rod flies off on its own. One island, then two; and from step 51 on the rod's centre of
// mass falls freely: its internal forces cancel, so Σ m_i (x_k − 2 x_{k−1} + x_{k−2}) = M g h²
// to the solver's tolerance (1e-9 m per coordinate and step).
TEST(ChangingIslands, TheBundledReleaseSceneLetsGo) {
  const Scene scene = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/joints/release.json");
  Simulator sim(scene.model, scene.solver);
  const int nodes = scene.model.rods[0].node_count();
  const RodDiscretization rod = discretize(scene.model.rods[0]);
  double M = 0.0;
  for (const double m : rod.node_mass) M += m;
  std::vector<Vector3> centre;  // per step k ≥ 1
  for (int k = 1; k <= 150; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    EXPECT_EQ(sim.islands(), k <= 50 ? 1 : 2) << k;
    Vector3 c = Vector3::Zero();
    for (int i = 0; i < nodes; ++i) c += rod.node_mass[i] * sim.state().points[scene.model.rod_point(0, i)];
    centre.push_back(c / M);
  }
  const double h = scene.model.time_step;
  double free_flight = 0.0;
  for (int k = 51; k <= 150; ++k) {
    const Vector3 a = centre[k - 1] - 2.0 * centre[k - 2] + centre[k - 3];
    free_flight = std::max(free_flight, (a - scene.model.gravity * h * h).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(free_flight, 1e-9);
  // While held, the gripper pulls on it: not free flight.
  const Vector3 held = centre[29] - 2.0 * centre[28] + centre[27];
  EXPECT_GT((held - scene.model.gravity * h * h).norm(), 1e-6);
}

// "active_frames" in a scene, and its bad values named by field.
TEST(ChangingIslands, ActiveFramesInAScene) {
  const auto parse = [](const std::string& extra, const char* type = "ball") {
    const std::string text = R"({ "time_step": 0.01, "frames": 1,
      "bodies": [ { "name": "a", "mass": 1, "inertia": [1, 1, 1] } ],
      "rods": [ { "name": "r", "shape": { "type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": 2 },
                  "mass": 0.1, "radius": 0.01, "stretch_stiffness": 100, "shear_stiffness": 100,
                  "bending_stiffness": [1, 1, 1] },
                { "name": "s", "shape": { "type": "line", "start": [1, 0, 0], "end": [2, 0, 0], "edges": 2 },
                  "mass": 0.1, "radius": 0.01, "stretch_stiffness": 100, "shear_stiffness": 100,
                  "bending_stiffness": [1, 1, 1] } ],
      "joints": [ )" + std::string(std::string(type) == "splice"
                                       ? R"({ "type": "splice", "a": { "rod": "r", "node": 2 }, "b": { "rod": "s", "node": 0 })"
                                       : R"({ "type": "ball", "a": { "body": "a" })") +
                             extra + " } ] }";
    try {
      const Scene scene = parse_scene(text, "j.json");
      return "accepted [" + std::to_string(scene.model.joints[0].first_frame) + ", " +
             (scene.model.joints[0].last_frame == std::numeric_limits<int>::max()
                  ? std::string("end")
                  : std::to_string(scene.model.joints[0].last_frame)) + "]";
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
  };
  EXPECT_EQ(parse(""), "accepted [1, end]");
  EXPECT_EQ(parse(R"(, "active_frames": [3, 7])"), "accepted [3, 7]");
  EXPECT_EQ(parse(R"(, "active_frames": [3, -1])"), "accepted [3, end]");
  EXPECT_EQ(parse(R"(, "active_frames": [5, 5])"), "accepted [5, 5]");
  EXPECT_EQ(parse(R"(, "active_frames": [0, 7])").rfind("joints[0].active_frames[0]: must be an integer in [1, ", 0), 0u);
  EXPECT_EQ(parse(R"(, "active_frames": [7, 3])").rfind("joints[0].active_frames[1]: must be -1 (to the end) or a step >= first (7)", 0), 0u);
  EXPECT_EQ(parse(R"(, "active_frames": [7, 0])").rfind("joints[0].active_frames[1]: must be -1", 0), 0u);
  EXPECT_EQ(parse(R"(, "active_frames": [2.5, 4])").rfind("joints[0].active_frames[0]: must be an integer", 0), 0u);
  EXPECT_EQ(parse(R"(, "active_frames": 3)").rfind("joints[0].active_frames: must be [first, last]", 0), 0u);
  EXPECT_EQ(parse(R"(, "active_frames": [1, 2, 3])").rfind("joints[0].active_frames: must be [first, last]", 0), 0u);
  EXPECT_EQ(parse("", "splice"), "accepted [1, end]");
  EXPECT_EQ(parse(R"(, "active_frames": [1, 4])", "splice")
                .rfind("joints[0].active_frames: a splice makes two rods one for the whole run", 0),
            0u);
}

class ChangingIslandsCli : public test::CliFixture {
 protected:
  ChangingIslandsCli() : CliFixture("liedyn_changing_islands_test_") {}
};

// The adjoint through islands that change: a double pendulum whose second link lets go of the
// first after step 15 of 30 (its hinge's active_frames) and flies on; both links' initial
// spins and the second's pose at the end (not l2's initial linear velocity: its component along the
// link, which the joints cancel in the first step, has a gradient at the round-off of the
// exact or stiff joints — 1.2e-5 relative with or without the release, and with a 1e-9 m/N
// elastic hinge too). The backward pass takes each step's own islands (and,
// exact, its own multipliers), so the gradient runs across the split. Elastic and exact
// (Newton's augmented Lagrangian, and Ipopt's own constraints).
TEST_F(ChangingIslandsCli, GradcheckPassesThroughARelease) {
  for (const auto& [compliance, backend] :
       {std::pair{"1e-4", "newton"}, std::pair{"0", "newton"}, std::pair{"0", "ipopt"}}) {
    SCOPED_TRACE(std::string(compliance) + " " + backend);
    std::ofstream(dir_ / "scene.json") << R"({ "time_step": 0.01, "frames": 30, "gravity": [0, 0, -9.81],
      "solver": { "backend": ")" << backend << R"(", "tolerance": 1e-12, "max_iterations": 100 },
      "bodies": [ { "name": "l1", "mass": 1, "inertia": [0.01, 0.02, 0.02], "position": [0.2, 0, 0],
                    "angular_velocity": [0, 0.5, 0] },
                  { "name": "l2", "mass": 0.3, "inertia": [0.005, 0.01, 0.01], "position": [0.6, 0, 0],
                    "angular_velocity": [0, 1, 0] } ],
      "joints": [ { "type": "hinge", "compliance": )" << compliance << R"(, "a": { "body": "l1", "point": [-0.2, 0, 0], "axis": [0, 1, 0] } },
                  { "type": "hinge", "compliance": )" << compliance << R"(, "a": { "body": "l2", "point": [-0.2, 0, 0], "axis": [0, 1, 0] },
                    "b": { "body": "l1" }, "active_frames": [1, 15] } ],
      "optimization": {
        "parameters": [ { "kind": "body_angular_velocity", "body": "l1" },
                        { "kind": "body_angular_velocity", "body": "l2" } ],
        "objective": [ { "term": "body_pose", "body": "l2", "frame": -1,
                         "position": [0.4, 0, -0.3], "orientation": [1, 0, 0, 0], "orientation_weight": 1 } ] } })";
    const Result r = run({"gradcheck", "scene.json", "--step", "1e-5"});
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  }
}

}  // namespace
}  // namespace liedyn

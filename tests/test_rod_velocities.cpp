// Initial node velocities of rods (issue 17, items 8 and 21): clamped nodes and edges keep
// their prescribed state whatever velocities the free nodes start with; the parameter block
// rod_node_velocities covers the free nodes only (its adjoint against central differences);
// and a rod's "node_velocities" in a scene file (problems/scene.cpp, docs/scene-format.md).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "rod_models.hpp"
#include "solvers/gradient_check.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::rod_velocities_tests {
namespace {

constexpr int kNodes = 6;  // the rods below: 5 edges of 0.1 m along x

// A cantilever under gravity: node 0 and edge 0 clamped.
Model cantilever() {
  Model m;
  m.time_step = 0.01;
  m.gravity = Vector3(0.0, 0.0, -9.81);
  RodSpec rod = test_models::uniform_rod(kNodes - 1, 0.5, 0.15, 0.01, 5e2, 50.0, 1.0);
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  m.rods.push_back(rod);
  return m;
}

// A rod clamped at both ends (nodes 0 and 5, edges 0 and 4) whose right end is pulled along x,
// lifted and twisted by a keyframed motion (lib/prescribed_motion.hpp); no gravity.
Model pulled_rod() {
  Model m;
  m.time_step = 0.01;
  RodSpec rod = test_models::uniform_rod(kNodes - 1, 0.5, 0.15, 0.01, 5e2, 50.0, 1.0);
  rod.fixed_nodes = {0, kNodes - 1};
  rod.fixed_edges = {0, kNodes - 2};
  PrescribedMotion end;
  end.nodes = {kNodes - 1};
  end.edges = {kNodes - 2};
  end.center = rod.nodes.back();
  end.keyframes = {{0.05, Vector3(0.02, 0.0, 0.03), Vector3(0.3, 0.0, 0.0)},
                   {0.2, Vector3(0.05, 0.01, 0.0), Vector3(0.5, 0.0, 0.0)}};
  rod.prescribed_motions = {end};
  m.rods.push_back(rod);
  return m;
}

// γ of a rod_node_velocities block: a different velocity for each entry, so that every
// entry of the gradient differs.
Eigen::VectorXd varied_velocities(int size) {
  Eigen::VectorXd gamma(size);
  for (int i = 0; i < size; ++i) gamma(i) = 0.3 * std::sin(1.0 + 0.7 * i);
  return gamma;
}

// Every node of rod 0 against targets off the initial line, at the last frame.
Objective node_targets(const Model& m) {
  std::vector<int> points;
  std::vector<Vector3> targets;
  for (int i = 0; i < kNodes; ++i) {
    points.push_back(m.rod_point(0, i));
    targets.push_back(Vector3(0.1 * i, 0.04 * std::sin(i), -0.02 * i));
  }
  Objective g;
  g.add(std::make_shared<PointTargets>(points, targets, -1, 1.0));
  return g;
}

SolverOptions tight() { return test_models::newton(1e-12, 100); }

// The adjoint gradient at γ against central differences of the loss (tight forward solves;
// step 1e-5: the resolution of test_adjoint.cpp). Entries must agree to 1e-5 relative, and
// the gradient must be worth checking.
void expect_adjoint_matches_differences(const DifferentiableSimulation& sim,
                                        const Eigen::VectorXd& gamma) {
  GradientCheckOptions o;
  o.step = 1e-5;
  const GradientCheckResult r = check_gradient(sim, gamma, o);
  double largest = 0.0;
  for (const GradientCheckEntry& e : r.entries) {
    largest = std::max(largest, std::abs(e.finite_difference));
  }
  EXPECT_GT(largest, 1e-4 * std::abs(r.loss)) << "the gradient is negligible: the check means nothing";
  ASSERT_GE(r.worst, 0);
  const GradientCheckEntry& worst = r.entries[static_cast<std::size_t>(
      std::find_if(r.entries.begin(), r.entries.end(),
                   [&](const GradientCheckEntry& e) { return e.index == r.worst; }) -
      r.entries.begin())];
  EXPECT_LE(r.max_relative_error, 1e-5)
      << sim.parameters().describe(sim.base_model(), r.worst) << ": adjoint " << worst.adjoint
      << ", finite difference " << worst.finite_difference;
}

// ---------------------------------------------------------------------------------------
// Item 8: the parameter block, the forward run and the adjoint.

TEST(RodNodeVelocityParameters, BlockCoversTheFreeNodesUnderTheirOwnIndices) {
  Model m = cantilever();
  m.rods[0].fixed_nodes = {3, 0};  // in any order
  ParameterSet p(4);
  p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "p[0]");
  ASSERT_EQ(p.size(), 3 * (kNodes - 2));
  ASSERT_EQ(p.blocks()[0].size, 3 * (kNodes - 2));
  EXPECT_EQ(p.describe(m, 0), "rods[0].node_velocities[1][0]");
  EXPECT_EQ(p.describe(m, 5), "rods[0].node_velocities[2][2]");
  EXPECT_EQ(p.describe(m, 6), "rods[0].node_velocities[4][0]");
  EXPECT_EQ(p.describe(m, 11), "rods[0].node_velocities[5][2]");

  // Initial values: the free nodes' velocities, in node order; apply writes them back and
  // leaves the clamped nodes at rest.
  for (int i = 0; i < kNodes; ++i) {
    m.rods[0].node_velocities.push_back(i == 0 || i == 3 ? Vector3::Zero()
                                                         : Vector3(i, 10.0 * i, 100.0 * i));
  }
  const Eigen::VectorXd gamma = p.initial_values(m);
  ASSERT_EQ(gamma.size(), p.size());
  EXPECT_EQ(gamma.segment<3>(0), Vector3(1.0, 10.0, 100.0));
  EXPECT_EQ(gamma.segment<3>(3), Vector3(2.0, 20.0, 200.0));
  EXPECT_EQ(gamma.segment<3>(6), Vector3(4.0, 40.0, 400.0));
  EXPECT_EQ(gamma.segment<3>(9), Vector3(5.0, 50.0, 500.0));
  Model at_rest = m;
  at_rest.rods[0].node_velocities.clear();
  const Model applied = p.apply(at_rest, gamma);
  ASSERT_EQ(applied.rods[0].node_velocities.size(), std::size_t(kNodes));
  for (int i = 0; i < kNodes; ++i) {
    EXPECT_EQ(applied.rods[0].node_velocities[i], m.rods[0].node_velocities[i]) << "node " << i;
  }
}

TEST(RodNodeVelocityParameters, ARodWithEveryNodeClampedHasNoBlock) {
  Model m = cantilever();
  m.rods[0].fixed_nodes.clear();
  for (int i = 0; i < kNodes; ++i) m.rods[0].fixed_nodes.push_back(i);
  ParameterSet p(4);
  try {
    p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "optimization.parameters[0]");
    ADD_FAILURE() << "a block of no entries was accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "optimization.parameters[0]");
    EXPECT_NE(std::string(e.what()).find("free node"), std::string::npos) << e.what();
  }
}

// Whatever γ says, the clamped node and edge of the cantilever never move, while the free
// nodes start with the velocities of γ.
TEST(RodNodeVelocityParameters, ClampedNodeAndEdgeStayPrescribedWhateverTheVelocities) {
  const Model m = cantilever();
  ParameterSet p(20);
  p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "p[0]");
  const DifferentiableSimulation sim(m, p, node_targets(m), tight());
  Eigen::VectorXd gamma(p.size());
  for (int i = 0; i < p.size(); i += 3) gamma.segment<3>(i) = Vector3(0.5, -0.4, 0.8);
  const DifferentiableSimulation::Result r = sim.evaluate(gamma, nullptr);
  const Trajectory& t = r.trajectory;
  ASSERT_EQ(t.frames(), 20);
  const int clamped = m.rod_point(0, 0), tip = m.rod_point(0, kNodes - 1);
  const int clamped_edge = m.rod_rotation(0, 0);
  EXPECT_EQ(t.initial_step.points[clamped], Vector3::Zero());
  EXPECT_EQ(t.initial_step.points[tip], m.time_step * Vector3(0.5, -0.4, 0.8));
  for (int k = 0; k <= t.frames(); ++k) {
    EXPECT_EQ(t.states[k].points[clamped], m.rods[0].nodes[0]) << "frame " << k;
    EXPECT_EQ(t.states[k].rotations[clamped_edge], t.states[0].rotations[clamped_edge])
        << "frame " << k;
  }
  // The free nodes did take the velocity: the tip leaves the run from rest by h v per step at
  // first (the stiff rod then swings back).
  const Trajectory resting = sim.evaluate(Eigen::VectorXd::Zero(p.size()), nullptr).trajectory;
  const double speed = Vector3(0.5, -0.4, 0.8).norm();
  EXPECT_GT((t.states[1].points[tip] - resting.states[1].points[tip]).norm(),
            0.5 * m.time_step * speed);
}

TEST(RodNodeVelocityParameters, AdjointMatchesFiniteDifferencesOnAClampedRod) {
  const Model m = cantilever();
  ParameterSet p(12);
  p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "p[0]");
  const DifferentiableSimulation sim(m, p, node_targets(m), tight());
  expect_adjoint_matches_differences(sim, varied_velocities(p.size()));
}

// The same with the other rotation parameterisations of the forward solves (the adjoint is
// theirs too: it linearises the converged steps).
TEST(RodNodeVelocityParameters, AdjointMatchesFiniteDifferencesUnderEveryParameterization) {
  const Model m = cantilever();
  ParameterSet p(8);
  p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "p[0]");
  for (RotationParameterization rotation :
       {RotationParameterization::kRotationVector, RotationParameterization::kQuaternion}) {
    SCOPED_TRACE(to_string(rotation));
    SolverOptions o = tight();
    o.rotation = rotation;
    const DifferentiableSimulation sim(m, p, node_targets(m), o);
    expect_adjoint_matches_differences(sim, varied_velocities(p.size()));
  }
}

// Keyframed clamps: the moved end follows its path exactly, and the fixed end stays, with or
// without initial velocities on the free nodes; the adjoint still matches the differences.
TEST(RodNodeVelocityParameters, PrescribedMotionIsNotDisturbed) {
  const Model m = pulled_rod();
  const int frames = 15;
  ParameterSet p(frames);
  p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "p[0]");
  ASSERT_EQ(p.size(), 3 * (kNodes - 2));
  const DifferentiableSimulation sim(m, p, node_targets(m), tight());
  const Eigen::VectorXd gamma = 3.0 * varied_velocities(p.size());
  const Trajectory moving = sim.evaluate(gamma, nullptr).trajectory;
  const Trajectory resting = sim.evaluate(Eigen::VectorXd::Zero(p.size()), nullptr).trajectory;
  const PrescribedMotion& motion = m.rods[0].prescribed_motions[0];
  const int left = m.rod_point(0, 0), right = m.rod_point(0, kNodes - 1);
  const int left_edge = m.rod_rotation(0, 0), right_edge = m.rod_rotation(0, kNodes - 2);
  const State& q0 = moving.states[0];
  for (int k = 1; k <= frames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const RigidTransform T = motion.at(k * m.time_step);
    for (const Trajectory* t : {&moving, &resting}) {
      const State& q = t->states[k];
      EXPECT_EQ(q.points[left], q0.points[left]);
      EXPECT_EQ(q.rotations[left_edge], q0.rotations[left_edge]);
      EXPECT_LT((q.points[right] - motion.move_point(T, q0.points[right])).norm(), 1e-15);
      EXPECT_LT(so3::distance(q.rotations[right_edge], T.rotation * q0.rotations[right_edge]),
                1e-14);
    }
  }
  // The velocities do move the free nodes (by about h |v| = 0.004 m in the first step).
  const int middle = m.rod_point(0, 2);
  EXPECT_GT((moving.states[1].points[middle] - resting.states[1].points[middle]).norm(), 1e-3);
  expect_adjoint_matches_differences(sim, gamma);
}

TEST(RodNodeVelocities, AClampedNodesVelocityMustBeZero) {
  Model m = pulled_rod();
  m.rods[0].node_velocities.assign(kNodes, Vector3(0.1, 0.0, 0.0));
  m.rods[0].node_velocities[0].setZero();
  try {  // node 5 is clamped (and moved by the prescribed motion)
    m.validate();
    ADD_FAILURE() << "a clamped node with a velocity was accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "rods[0].node_velocities[5]");
    EXPECT_NE(std::string(e.what()).find("clamped"), std::string::npos) << e.what();
  }
  m.rods[0].node_velocities[kNodes - 1].setZero();
  EXPECT_NO_THROW(m.validate());
  // And the clamped node starts at rest in the initial step, which gives the others h v.
  const Step dq = m.initial_step();
  EXPECT_EQ(dq.points[m.rod_point(0, 0)], Vector3::Zero());
  EXPECT_EQ(dq.points[m.rod_point(0, 1)], m.time_step * Vector3(0.1, 0.0, 0.0));
}

// ---------------------------------------------------------------------------------------
// Item 21: "node_velocities" in a scene.

constexpr const char* kSource = "rod_velocities.json";

// A scene of one rod of 4 edges along x (5 nodes), whose members `members` (each followed by
// ", ") are added to the rod object.
std::string rod_scene(const std::string& members, const std::string& gravity = "[0, 0, 0]") {
  return R"({"time_step": 0.01, "frames": 30, "gravity": )" + gravity + R"(,
    "solver": { "tolerance": 1e-12 },
    "rods": [ { )" + members + R"("name": "r",
      "shape": { "type": "line", "start": [0, 0, 0], "end": [0.4, 0, 0], "edges": 4 },
      "mass": 0.1, "radius": 0.01, "stretch_stiffness": 1e3, "shear_stiffness": 1e2,
      "bending_stiffness": [0.5, 0.5, 0.5] } ] })";
}

void expect_rejected(const std::string& text, const std::string& field,
                     const std::string& reason_part) {
  SCOPED_TRACE(text);
  try {
    parse_scene(text, kSource);
    ADD_FAILURE() << "the scene was accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), kSource);
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::string(kSource) + ": " + field + ": "),
              std::string::npos)
        << e.what();
    EXPECT_NE(e.reason().find(reason_part), std::string::npos)
        << "reason \"" << e.reason() << "\" lacks \"" << reason_part << "\"";
  }
}

TEST(SceneRodVelocities, AFreeRodWithUniformVelocityTranslatesByVelocityTimesTime) {
  const Vector3 v(0.3, -0.2, 0.1);
  const Scene s = parse_scene(
      rod_scene(R"("node_velocities": [[0.3, -0.2, 0.1], [0.3, -0.2, 0.1], [0.3, -0.2, 0.1],
                                       [0.3, -0.2, 0.1], [0.3, -0.2, 0.1]], )"),
      kSource);
  ASSERT_EQ(s.model.rods[0].node_velocities.size(), 5u);
  for (const Vector3& u : s.model.rods[0].node_velocities) EXPECT_EQ(u, v);
  Simulator sim(s.model, s.solver);
  for (int k = 1; k <= s.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << "step " << k;
    for (int i = 0; i < 5; ++i) {
      const Vector3 expected = s.model.rods[0].nodes[i] + sim.time() * v;
      EXPECT_LT((sim.state().points[i] - expected).norm(), 1e-12) << "step " << k << ", node " << i;
      EXPECT_LT((sim.linear_velocity(i) - v).norm(), 1e-9) << "step " << k << ", node " << i;
    }
  }
}

TEST(SceneRodVelocities, AClampedNodeAtRestIsAcceptedAndStays) {
  const Scene s = parse_scene(
      rod_scene(R"("fixed_nodes": [0], "fixed_edges": [0],
                   "node_velocities": [[0, 0, 0], [0, 0.1, 0], [0, 0.2, 0], [0, 0.3, 0], [0, 0.4, 0]], )",
                "[0, 0, -9.81]"),
      kSource);
  Simulator sim(s.model, s.solver);
  EXPECT_NEAR(sim.linear_velocity(4).y(), 0.4, 1e-15);
  double farthest = 0.0;  // sideways, of the tip (the stiff rod swings back and forth)
  for (int k = 1; k <= s.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << "step " << k;
    EXPECT_EQ(sim.state().points[0], Vector3::Zero()) << "step " << k;
    farthest = std::max(farthest, sim.state().points[4].y());
  }
  EXPECT_GT(farthest, 0.002);  // at least half of h · 0.4 m/s: the tip took its velocity
}

TEST(SceneRodVelocities, BadVelocitiesNameTheirField) {
  // One velocity per node, no fewer, no more (an empty list too is a wrong count).
  expect_rejected(rod_scene(R"("node_velocities": [[0, 0, 0], [0, 0, 0], [0, 0, 0]], )"),
                  "rods[0].node_velocities", "has 3 entries, but the rod has 5 nodes");
  expect_rejected(rod_scene(R"("node_velocities": [], )"), "rods[0].node_velocities",
                  "has 0 entries, but the rod has 5 nodes");
  expect_rejected(rod_scene(R"("node_velocities": {"x": 1}, )"), "rods[0].node_velocities",
                  "must be an array");
  // Each a 3-number array of finite numbers.
  expect_rejected(
      rod_scene(R"("node_velocities": [[0, 0, 0], [0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]], )"),
      "rods[0].node_velocities[1]", "must be an array of 3 numbers");
  expect_rejected(
      rod_scene(R"("node_velocities": [[0, 0, 0], [0, 0, 0], [0, 0, "fast"], [0, 0, 0], [0, 0, 0]], )"),
      "rods[0].node_velocities[2][2]", "must be a number");
  expect_rejected(
      rod_scene(R"("node_velocities": [[0, 0, 0], [0, 0, 0], [0, 0, 0], [1e999, 0, 0], [0, 0, 0]], )"),
      "rods[0].node_velocities[3][0]", "finite");
  // A clamped node's velocity must be zero, a node clamped for a prescribed motion too.
  expect_rejected(rod_scene(R"("fixed_nodes": [0, 3],
      "node_velocities": [[0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 1e-9, 0], [0, 1, 0]], )"),
                  "rods[0].node_velocities[3]", "clamped");
  expect_rejected(rod_scene(R"("fixed_nodes": [4],
      "prescribed_motions": [ { "nodes": [4], "keyframes": [ { "time": 1, "translation": [0.1, 0, 0] } ] } ],
      "node_velocities": [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0.1, 0, 0]], )"),
                  "rods[0].node_velocities[4]", "clamped");
  // The clamped nodes are range-checked first (an index out of range is named as before).
  expect_rejected(rod_scene(R"("fixed_nodes": [7],
      "node_velocities": [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]], )"),
                  "rods[0].fixed_nodes[0]", "refers to node 7");
}

}  // namespace
}  // namespace liedyn::rod_velocities_tests

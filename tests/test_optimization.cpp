// Trajectory optimisation from scene files (problems/optimization.hpp, docs/scene-format.md
// §Optimization): the "optimization" block's parameters (sizes of lib/parameters.hpp) and
// objective terms (their values on a known trajectory), its errors (SceneError naming the
// file and the exact field), the bundled problems (problems/scenes/optimization/, letters/),
// the `liedyn gradcheck` and `liedyn optimize` commands run as real processes (exit codes,
// history, checkpoints, --resume), and the forward pass of DifferentiableSimulation against a
// plain Simulator run of the same scene.

// GCC 12's libstdc++ <regex>, inlined under the sanitizer build's flags, warns that a
// std::function inside its automaton "may be used uninitialized" (a false positive in the
// library, not in this file); it is silenced for this file only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <gtest/gtest.h>

#include "cli_fixture.hpp"
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "problems/letters.hpp"
#include "problems/optimization.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::optimization_tests {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSource = "opt_scene.json";
constexpr int kFrames = 5;

// The model of the parsing tests. Bodies "ball" (0) and "box" (1, at (0, 0, 1), v = (1, 2, 2));
// a spring from each to the world (so that static mode is anchored), index 1 the box's
// (stiffness 20); forces and torques, index 1 on the box (force (0, 1, 0)); rods "stub" (0:
// 2 nodes, no interior node) and "arm" (1: 4 nodes (0.1 i, 0, 0), two node forces, index 1
// (0, 0, −2), two cables, index 1 of tension 2.5, bending (1, 2, 3)), both clamped at node 0.
// State points: ball 0, box 1, stub 2–3, arm 4–7.
std::string model_json() {
  return R"(
    "bodies": [
      { "name": "ball", "mass": 1, "inertia": [0.1, 0.1, 0.1], "position": [2, 0, 0] },
      { "name": "box", "mass": 2, "inertia": [0.2, 0.3, 0.4], "position": [0, 0, 1],
        "linear_velocity": [1, 2, 2], "angular_velocity": [0, 0, 1] } ],
    "springs": [ { "body_a": "ball", "point_b": [2, 0, 1], "stiffness": 10 },
                 { "body_a": "box", "point_b": [0, 0, 2], "stiffness": 20 } ],
    "forces": [ { "body": "ball", "force": [1, 0, 0] }, { "body": "box", "force": [0, 1, 0] } ],
    "torques": [ { "body": "ball", "torque": [0, 0, 0.1] }, { "body": "box", "torque": [0.2, 0, 0] } ],
    "rods": [
      { "name": "stub", "nodes": [[0, 1, 0], [0, 1, 0.1]], "mass": 0.1, "radius": 0.01,
        "stretch_stiffness": 100, "shear_stiffness": 10, "bending_stiffness": [1, 1, 1],
        "fixed_nodes": [0], "fixed_edges": [0] },
      { "name": "arm", "shape": { "type": "line", "start": [0, 0, 0], "end": [0.3, 0, 0], "edges": 3 },
        "mass": 0.1, "radius": 0.01, "stretch_stiffness": 100, "shear_stiffness": 10,
        "bending_stiffness": [1, 2, 3], "fixed_nodes": [0], "fixed_edges": [0],
        "node_forces": [ { "node": 3, "force": [0, 0, -1] }, { "node": 2, "force": [0, 0, -2] } ],
        "cables": [ { "edges": [0, 2], "tension": 1.5 }, { "edges": [1, 2], "tension": 2.5 } ] } ])";
}

// A scene of that model whose "optimization" member is `optimization` (JSON text; none if
// empty), with `frames` frames in mode `mode`.
std::string scene_text(const std::string& optimization, int frames = kFrames,
                       const std::string& mode = "dynamic") {
  std::string text = R"({ "time_step": 0.01, "frames": )" + std::to_string(frames) +
                     R"(, "mode": ")" + mode + "\"," + model_json();
  if (!optimization.empty()) text += ",\n  \"optimization\": " + optimization;
  return text + "\n}";
}

// An optimization block with the given parameter and term lists (JSON array contents) and
// extra members `extra` (must start with ", " when given).
std::string block(const std::string& parameters, const std::string& objective,
                  const std::string& extra = "") {
  return R"({ "parameters": [)" + parameters + R"(], "objective": [)" + objective + "]" + extra +
         " }";
}

const std::string kForceParameter = R"({ "kind": "force", "index": 1 })";
const std::string kEffortTerm = R"({ "term": "effort" })";

Scene parsed(const std::string& text) {
  try {
    return parse_scene(text, kSource);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "scene rejected: " << e.what() << "\n" << text;
    throw;
  }
}

// Parses text that must be rejected; returns the error, or nothing after failing the test.
std::optional<SceneError> rejected(const std::string& text) {
  try {
    parse_scene(text, kSource);
  } catch (const SceneError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected a SceneError, got another exception: " << e.what();
    return std::nullopt;
  }
  ADD_FAILURE() << "scene was accepted";
  return std::nullopt;
}

// The error names the file and exactly `field`, what() reads "<file>: <field>: <reason>",
// and the reason contains `reason_part`.
void expect_rejected(const std::string& text, const std::string& field,
                     const std::string& reason_part) {
  SCOPED_TRACE(text);
  const std::optional<SceneError> e = rejected(text);
  if (!e) return;
  EXPECT_EQ(e->file(), kSource) << e->what();
  EXPECT_EQ(e->field(), field) << e->what();
  EXPECT_EQ(std::string(e->what()), std::string(kSource) + ": " + field + ": " + e->reason());
  EXPECT_NE(e->reason().find(reason_part), std::string::npos)
      << "reason \"" << e->reason() << "\" lacks \"" << reason_part << "\"";
}

void expect_parameter_rejected(const std::string& parameters, const std::string& field,
                               const std::string& reason_part,
                               const std::string& mode = "dynamic") {
  expect_rejected(scene_text(block(parameters, kEffortTerm), kFrames, mode), field, reason_part);
}

void expect_term_rejected(const std::string& term, const std::string& field,
                          const std::string& reason_part) {
  expect_rejected(scene_text(block(kForceParameter, term)), field, reason_part);
}

// A made-up trajectory of the model: every point of q_0 lifted by (0, 0, k) at frame k, the
// rotations as in q_0. Objective values on it are known in closed form.
Trajectory lifted_trajectory(const Model& model, int frames) {
  Trajectory t;
  t.time_step = model.time_step;
  t.initial_step = model.initial_step();
  const State q0 = model.initial_state();
  for (int k = 0; k <= frames; ++k) {
    State q = q0;
    for (Vector3& p : q.points) p.z() += k;
    t.states.push_back(q);
  }
  return t;
}

// The loss of a scene's objective on lifted_trajectory at the initial parameters.
double lifted_loss(const Scene& s) {
  const OptimizationSpec& spec = *s.optimization;
  return spec.objective.value(lifted_trajectory(s.model, s.frames),
                              spec.parameters.initial_values(s.model));
}

// The one objective term of a scene with parameter `parameters` and term `term`.
Scene scene_with_term(const std::string& term, const std::string& parameters = kForceParameter) {
  return parsed(scene_text(block(parameters, term)));
}

// ---------------------------------------------------------------------------------------
// Parameters: each kind gives its block, documented size, names and initial values.

struct KindCase {
  std::string json;
  ParameterKind kind;
  int index, sub, size;
  std::string first_name;    // ParameterSet::describe of its first entry
  std::vector<double> head;  // its first initial values (the scene's)
  int period;                // per-step kinds: the initial values repeat with this period
};

std::vector<KindCase> kind_cases() {
  const int n = kFrames, nodes = 4;
  // clang-format off
  return {
      {R"({"kind": "body_linear_velocity", "body": "box"})", ParameterKind::kBodyLinearVelocity,
       1, -1, 3, "bodies[1].linear_velocity[0]", {1, 2, 2}, 0},
      {R"({"kind": "body_angular_velocity", "body": "box"})", ParameterKind::kBodyAngularVelocity,
       1, -1, 3, "bodies[1].angular_velocity[0]", {0, 0, 1}, 0},
      {R"({"kind": "body_position", "body": "box"})", ParameterKind::kBodyPosition, 1, -1, 3,
       "bodies[1].position[0]", {0, 0, 1}, 0},
      {R"({"kind": "body_orientation", "body": "box"})", ParameterKind::kBodyOrientation, 1, -1,
       3, "bodies[1].orientation_increment[0]", {0, 0, 0}, 0},
      {R"({"kind": "rod_node_velocities", "rod": "arm"})", ParameterKind::kRodNodeVelocities, 1,
       -1, 3 * (nodes - 1), "rods[1].node_velocities[1][0]", {0, 0, 0}, 3},
      {R"({"kind": "force", "index": 1})", ParameterKind::kForce, 1, -1, 3 * n,
       "forces[1].frame[1][0]", {0, 1, 0}, 3},
      {R"({"kind": "torque", "index": 1})", ParameterKind::kTorque, 1, -1, 3 * n,
       "torques[1].frame[1][0]", {0.2, 0, 0}, 3},
      {R"({"kind": "node_force", "rod": "arm", "node_force": 1})", ParameterKind::kNodeForce, 1,
       1, 3 * n, "rods[1].node_forces[1].frame[1][0]", {0, 0, -2}, 3},
      {R"({"kind": "cable_tension", "rod": "arm", "cable": 1})", ParameterKind::kCableTension, 1,
       1, n, "rods[1].cables[1].tension.frame[1]", {2.5}, 1},
      {R"({"kind": "rest_darboux", "rod": "arm"})", ParameterKind::kRestDarboux, 1, -1,
       3 * (nodes - 2), "rods[1].rest_darboux[0][0]", {0, 0, 0}, 3},
      {R"({"kind": "rest_darboux_per_frame", "rod": "arm"})", ParameterKind::kRestDarbouxPerFrame,
       1, -1, 3 * (nodes - 2) * n, "rods[1].rest_darboux.frame[1][0][0]", {0, 0, 0}, 3},
      {R"({"kind": "spring_stiffness", "index": 1})", ParameterKind::kSpringStiffness, 1, -1, 1,
       "springs[1].stiffness", {20}, 0},
      {R"({"kind": "stretch_stiffness", "rod": "arm"})", ParameterKind::kStretchStiffness, 1, -1,
       1, "rods[1].stretch_stiffness", {100}, 0},
      {R"({"kind": "shear_stiffness", "rod": "arm"})", ParameterKind::kShearStiffness, 1, -1, 1,
       "rods[1].shear_stiffness", {10}, 0},
      {R"({"kind": "bending_stiffness", "rod": "arm"})", ParameterKind::kBendingStiffness, 1, -1,
       3, "rods[1].bending_stiffness[0]", {1, 2, 3}, 0},
  };
  // clang-format on
}

TEST(OptimizationParse, EveryParameterKindGivesItsDocumentedBlock) {
  const std::vector<KindCase> cases = kind_cases();
  ASSERT_EQ(cases.size(), 15u);  // every ParameterKind
  for (const KindCase& c : cases) {
    SCOPED_TRACE(c.json);
    const Scene s = parsed(scene_text(block(c.json, kEffortTerm)));
    ASSERT_TRUE(s.optimization.has_value());
    const ParameterSet& p = s.optimization->parameters;
    EXPECT_EQ(p.frames(), kFrames);
    ASSERT_EQ(p.blocks().size(), 1u);
    const ParameterBlock& b = p.blocks()[0];
    EXPECT_EQ(b.kind, c.kind);
    EXPECT_EQ(to_string(b.kind), nlohmann::json::parse(c.json).at("kind").get<std::string>());
    EXPECT_EQ(b.index, c.index);
    EXPECT_EQ(b.sub, c.sub);
    EXPECT_EQ(b.offset, 0);
    EXPECT_EQ(b.size, c.size);
    EXPECT_EQ(p.size(), c.size);
    EXPECT_EQ(p.describe(s.model, 0), c.first_name);
    const Eigen::VectorXd gamma = p.initial_values(s.model);
    ASSERT_EQ(gamma.size(), c.size);
    for (std::size_t i = 0; i < c.head.size(); ++i)
      EXPECT_NEAR(gamma(int(i)), c.head[i], 1e-12) << i;
    if (c.period > 0) {
      for (int i = c.period; i < gamma.size(); ++i) EXPECT_EQ(gamma(i), gamma(i % c.period)) << i;
    }
    // The effort term (no "parameters") covers the whole block.
    ASSERT_EQ(s.optimization->objective.terms().size(), 1u);
    EXPECT_EQ(s.optimization->objective.terms()[0]->name(), "effort");
  }
}

TEST(OptimizationParse, PerFrameNamesCountFramesFromOne) {
  const Scene s = parsed(scene_text(block(
      R"({"kind": "rest_darboux_per_frame", "rod": "arm"}, {"kind": "cable_tension", "rod": "arm", "cable": 0})",
      kEffortTerm)));
  const ParameterSet& p = s.optimization->parameters;
  ASSERT_EQ(p.size(), 3 * 2 * kFrames + kFrames);
  // Frame-major: frame 1's two interior nodes, then frame 2's, …
  EXPECT_EQ(p.describe(s.model, 3 * 2 - 1), "rods[1].rest_darboux.frame[1][1][2]");
  EXPECT_EQ(p.describe(s.model, 3 * 2), "rods[1].rest_darboux.frame[2][0][0]");
  EXPECT_EQ(p.describe(s.model, 3 * 2 * kFrames - 1), "rods[1].rest_darboux.frame[5][1][2]");
  EXPECT_EQ(p.describe(s.model, 3 * 2 * kFrames), "rods[1].cables[0].tension.frame[1]");
  EXPECT_EQ(p.describe(s.model, p.size() - 1), "rods[1].cables[0].tension.frame[5]");
}

TEST(OptimizationParse, BoundsApplyToEveryEntryOfTheirBlock) {
  const Scene unbounded = parsed(scene_text(block(kForceParameter, kEffortTerm)));
  EXPECT_FALSE(unbounded.optimization->parameters.bounded());
  const Scene s = parsed(scene_text(block(
      R"({"kind": "force", "index": 1, "lower": -1, "upper": 2},
         {"kind": "rod_node_velocities", "rod": "arm"},
         {"kind": "cable_tension", "rod": "arm", "cable": 1, "lower": 0})",
      kEffortTerm)));
  const ParameterSet& p = s.optimization->parameters;
  ASSERT_TRUE(p.bounded());
  const Eigen::VectorXd lower = p.lower_bounds(), upper = p.upper_bounds();
  ASSERT_EQ(lower.size(), p.size());
  ASSERT_EQ(upper.size(), p.size());
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<double, double>> expected = {{-1, 2}, {-inf, inf}, {0, inf}};
  ASSERT_EQ(p.blocks().size(), expected.size());
  for (std::size_t b = 0; b < expected.size(); ++b) {
    const ParameterBlock& block = p.blocks()[b];
    for (int i = block.offset; i < block.offset + block.size; ++i) {
      EXPECT_EQ(lower(i), expected[b].first) << "block " << b << ", entry " << i;
      EXPECT_EQ(upper(i), expected[b].second) << "block " << b << ", entry " << i;
    }
  }
}

TEST(OptimizationParse, BlocksFollowEachOtherInListOrder) {
  // Every kind at once, except rest_darboux_per_frame (a repeat of rest_darboux on one rod).
  std::string list;
  std::vector<KindCase> used;
  for (const KindCase& c : kind_cases()) {
    if (c.kind == ParameterKind::kRestDarbouxPerFrame) continue;
    list += (list.empty() ? "" : ", ") + c.json;
    used.push_back(c);
  }
  const Scene s = parsed(scene_text(block(list, kEffortTerm)));
  const ParameterSet& p = s.optimization->parameters;
  ASSERT_EQ(p.blocks().size(), used.size());
  int offset = 0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    SCOPED_TRACE(used[i].json);
    EXPECT_EQ(p.blocks()[i].kind, used[i].kind);
    EXPECT_EQ(p.blocks()[i].offset, offset);
    EXPECT_EQ(p.blocks()[i].size, used[i].size);
    EXPECT_EQ(p.describe(s.model, offset), used[i].first_name);
    offset += used[i].size;
  }
  EXPECT_EQ(p.size(), offset);
  // One effort term per block when "parameters" is not given.
  EXPECT_EQ(s.optimization->objective.terms().size(), used.size());
}

TEST(OptimizationParse, OptimizerSettingsAndDefaults) {
  const Scene d = parsed(scene_text(block(kForceParameter, kEffortTerm)));
  const OptimizerOptions defaults;
  EXPECT_EQ(d.optimization->optimizer.optimizer, Optimizer::kNloptLbfgs);
  EXPECT_EQ(d.optimization->optimizer.max_iterations, defaults.max_iterations);
  EXPECT_EQ(d.optimization->optimizer.target_normalized_loss, defaults.target_normalized_loss);
  EXPECT_EQ(d.optimization->optimizer.lbfgs_memory, defaults.lbfgs_memory);
  EXPECT_EQ(d.optimization->loss_scale, 0.0);

  const Scene s = parsed(scene_text(
      block(kForceParameter, kEffortTerm,
            R"(, "optimizer": "ipopt-lbfgs", "max_iterations": 7, "target_normalized_loss": 0,
         "lbfgs_memory": 3, "loss_scale": 2.5)")));
  EXPECT_EQ(s.optimization->optimizer.optimizer, Optimizer::kIpoptLbfgs);
  EXPECT_EQ(s.optimization->optimizer.max_iterations, 7);
  EXPECT_EQ(s.optimization->optimizer.target_normalized_loss, 0.0);
  EXPECT_EQ(s.optimization->optimizer.lbfgs_memory, 3);
  EXPECT_EQ(s.optimization->loss_scale, 2.5);
  EXPECT_EQ(
      parsed(scene_text(block(kForceParameter, kEffortTerm, R"(, "optimizer": "ceres-lbfgs")")))
          .optimization->optimizer.optimizer,
      Optimizer::kCeresLbfgs);

  // Without the block there is none.
  EXPECT_FALSE(parsed(scene_text("")).optimization.has_value());
}

// ---------------------------------------------------------------------------------------
// Objective terms: values on lifted_trajectory (frame k = q_0 lifted by k in z; 5 frames).
// The rod "arm" has nodes (0.1 i, 0, 0), i = 0…3; the box is at (0, 0, 1).

const std::string kArmLifted1 = "[[0, 0, 1], [0.1, 0, 1], [0.2, 0, 1], [0.3, 0, 1]]";

TEST(OptimizationParse, PointTargetsFromTargets) {
  // Default frame: the last (5): each node is 4 above its target → w · 4 · 16.
  const Scene s = scene_with_term(
      R"({"term": "point_targets", "rod": "arm", "weight": 0.5, "targets": )" + kArmLifted1 + "}");
  ASSERT_EQ(s.optimization->objective.terms().size(), 1u);
  EXPECT_EQ(s.optimization->objective.terms()[0]->name(), "point_targets");
  EXPECT_NEAR(lifted_loss(s), 0.5 * 4 * 16, 1e-12);
  // "frame": 3: 2 above.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "point_targets", "rod": "arm", "frame": 3, "targets": )" +
                  kArmLifted1 + "}")),
              4 * 4, 1e-12);
  // "frame": 0 (the initial state): 1 below.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "point_targets", "rod": "arm", "frame": 0, "targets": )" +
                  kArmLifted1 + "}")),
              4 * 1, 1e-12);
}

TEST(OptimizationParse, PointTargetsFromAPolylineAreResampledByArcLength) {
  // Two or three points along the same segment: resampled to the 4 nodes' spacing.
  for (const std::string polyline :
       {"[[0, 0, 1], [0.3, 0, 1]]", "[[0, 0, 1], [0.25, 0, 1], [0.3, 0, 1]]"}) {
    SCOPED_TRACE(polyline);
    const Scene s = scene_with_term(
        R"({"term": "point_targets", "rod": "arm", "frame": 1, "polyline": )" + polyline + "}");
    EXPECT_EQ(s.optimization->objective.terms()[0]->name(), "point_targets");
    EXPECT_NEAR(lifted_loss(s), 0.0, 1e-24);
  }
  // Reversed: node i meets target 3 − i, at frame 1.
  const Scene reversed = scene_with_term(
      R"({"term": "point_targets", "rod": "arm", "frame": 1, "polyline": [[0.3, 0, 1], [0, 0, 1]]})");
  EXPECT_NEAR(lifted_loss(reversed), 0.09 + 0.01 + 0.01 + 0.09, 1e-12);
}

TEST(OptimizationParse, PointTargetsFromALetter) {
  // "I" is the stroke x = 0, y ∈ [0, 1] of the em box: at height 0.3 and origin (1, 0, 0) the
  // 4 targets are (1, y, 0), y ∈ {0, 0.1, 0.2, 0.3} (in either order). At frame 0:
  // Σ (1 − 0.1 i)² + Σ y² = 2.94 + 0.14.
  const Scene s = scene_with_term(
      R"({"term": "point_targets", "rod": "arm", "frame": 0, "letter": "I", "height": 0.3, "origin": [1, 0, 0]})");
  EXPECT_EQ(s.optimization->objective.terms()[0]->name(), "point_targets");
  EXPECT_NEAR(lifted_loss(s), 3.08, 1e-12);
  // Any letter: the targets are letter_target's.
  const Scene g = scene_with_term(
      R"({"term": "point_targets", "rod": "arm", "frame": 0, "letter": "G", "height": 0.5, "origin": [0, -1, 0]})");
  const std::vector<Vector3> targets = letter_target('G', 0.5, Vector3(0, -1, 0), 4);
  double expected = 0.0;
  for (int i = 0; i < 4; ++i) expected += (Vector3(0.1 * i, 0, 0) - targets[i]).squaredNorm();
  EXPECT_GT(expected, 0.1);
  EXPECT_NEAR(lifted_loss(g), expected, 1e-12);
}

TEST(OptimizationParse, BodyPoseTerm) {
  // The box ends (frame 5) at (0, 0, 6) with the identity orientation. Target height 0.5 at
  // weight 2 (z only) and a quarter turn about z at weight 3: 2 · 5.5² + 3 (π/2)².
  const std::string quarter_turn = "[0.7071067811865476, 0, 0, 0.7071067811865476]";
  const Scene s = scene_with_term(
      R"({"term": "body_pose", "body": "box", "position": [0, 0, 0.5], "position_weights": [0, 0, 2],
          "orientation": )" +
      quarter_turn + R"(, "orientation_weight": 3})");
  ASSERT_EQ(s.optimization->objective.terms().size(), 1u);
  EXPECT_EQ(s.optimization->objective.terms()[0]->name(), "body_pose");
  const double quarter = std::numbers::pi / 2;
  EXPECT_NEAR(lifted_loss(s), 2 * 5.5 * 5.5 + 3 * quarter * quarter, 1e-9);
  // A position alone: weights 1 on every axis, no orientation term.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "body_pose", "body": "box", "position": [1, 0, 6]})")),
              1.0, 1e-12);
  // An orientation alone: weight 1, no position term.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "body_pose", "body": "box", "orientation": )" + quarter_turn + "}")),
              quarter * quarter, 1e-9);
  // At frame 2 the box is at (0, 0, 3).
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "body_pose", "body": "box", "frame": 2, "position": [0, 0, 0]})")),
              9.0, 1e-12);
}

TEST(OptimizationParse, BodyPoseWeightScalesTheWholeTerm) {
  // "every term has weight (default 1)" and the loss is the weighted sum of its terms: the
  // weight must scale the position part too, not only the orientation part.
  const std::string quarter_turn = "[0.7071067811865476, 0, 0, 0.7071067811865476]";
  const std::string pose =
      R"("term": "body_pose", "body": "box", "position": [0, 0, 0.5], "position_weights": [0, 0, 2],
         "orientation": )" +
      quarter_turn;
  const double once = lifted_loss(scene_with_term("{" + pose + "}"));
  EXPECT_NEAR(lifted_loss(scene_with_term("{" + pose + R"(, "weight": 2})")), 2 * once,
              1e-9 * once);
  // Position only: weight 2 doubles it.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "body_pose", "body": "box", "position": [1, 0, 6], "weight": 2})")),
              2.0, 1e-12);
}

TEST(OptimizationParse, ProjectedTrajectoryWithACurvePerFrame) {
  // The arm's tip (0.3, 0, k) seen in the xz plane is (0.3, k), k = 1…5.
  const Scene exact = scene_with_term(
      R"({"term": "projected_trajectory", "rod": "arm", "node": 3, "plane": "xz",
          "curve": [[0.3, 1], [0.3, 2], [0.3, 3], [0.3, 4], [0.3, 5]]})");
  ASSERT_EQ(exact.optimization->objective.terms().size(), 1u);
  EXPECT_EQ(exact.optimization->objective.terms()[0]->name(), "projected_trajectory");
  EXPECT_NEAR(lifted_loss(exact), 0.0, 1e-24);
  const Scene off = scene_with_term(
      R"({"term": "projected_trajectory", "rod": "arm", "node": 3, "plane": "xz", "weight": 0.5,
          "curve": [[0.3, 1], [0.3, 2], [0.3, 3], [0.3, 4], [0.3, 7]]})");
  EXPECT_NEAR(lifted_loss(off), 0.5 * 4, 1e-12);
  // "zx" swaps the axes: (k, 0.3).
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "projected_trajectory", "rod": "arm", "node": 3, "plane": "zx",
                      "curve": [[1, 0.3], [2, 0.3], [3, 0.3], [4, 0.3], [5, 0.3]]})")),
              0.0, 1e-24);
  // A body, default plane xy: the box is at (0, 0) throughout.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "projected_trajectory", "body": "box",
                      "curve": [[0, 0], [0, 0], [0, 0], [0, 0], [1, 0]]})")),
              1.0, 1e-12);
}

TEST(OptimizationParse, ProjectedTrajectoryResamplesOtherCurves) {
  // 2 points ≠ 5 frames: resampled to 5 points by arc length, first and last kept.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "projected_trajectory", "rod": "arm", "node": 3, "plane": "xz",
                      "curve": [[0.3, 1], [0.3, 5]]})")),
              0.0, 1e-20);
  // (0.3, 0 … 8) every 2 against (0.3, 1 … 5): differences −1, 0, 1, 2, 3.
  EXPECT_NEAR(lifted_loss(scene_with_term(
                  R"({"term": "projected_trajectory", "rod": "arm", "node": 3, "plane": "xz",
                      "curve": [[0.3, 0], [0.3, 3], [0.3, 8]]})")),
              15.0, 1e-12);
}

TEST(OptimizationParse, EffortOverAllOrSomeParameters) {
  // γ: the box's force (0, 1, 0) in each of 5 frames (Σγ² = 5), then its velocity (1, 2, 2)
  // (Σγ² = 9).
  const std::string parameters =
      kForceParameter + R"(, {"kind": "body_linear_velocity", "body": "box"})";
  const Scene all = scene_with_term(R"({"term": "effort", "weight": 0.1})", parameters);
  ASSERT_EQ(all.optimization->objective.terms().size(), 2u);  // one per block
  for (const auto& t : all.optimization->objective.terms()) EXPECT_EQ(t->name(), "effort");
  EXPECT_NEAR(lifted_loss(all), 0.1 * (5 + 9), 1e-12);
  const Scene velocity =
      scene_with_term(R"({"term": "effort", "weight": 0.1, "parameters": [1]})", parameters);
  ASSERT_EQ(velocity.optimization->objective.terms().size(), 1u);
  EXPECT_NEAR(lifted_loss(velocity), 0.1 * 9, 1e-12);
  const Scene force = scene_with_term(R"({"term": "effort", "parameters": [0]})", parameters);
  EXPECT_NEAR(lifted_loss(force), 5.0, 1e-12);
  // Terms add up.
  const Scene both = scene_with_term(
      R"({"term": "effort", "parameters": [0]}, {"term": "point_targets", "rod": "arm", "targets": )" +
          kArmLifted1 + "}",
      parameters);
  ASSERT_EQ(both.optimization->objective.terms().size(), 2u);
  EXPECT_EQ(both.optimization->objective.terms()[1]->name(), "point_targets");
  EXPECT_NEAR(lifted_loss(both), 5.0 + 4 * 16, 1e-12);
}

// ---------------------------------------------------------------------------------------
// Errors: a SceneError naming the file and the exact field.

TEST(OptimizationErrors, UnknownKindTermOrKey) {
  expect_parameter_rejected(kForceParameter + R"(, {"kind": "velocity", "body": "box"})",
                            "optimization.parameters[1].kind",
                            "unknown parameter kind \"velocity\"");
  expect_term_rejected(R"({"term": "distance"})", "optimization.objective[0].term",
                       "unknown objective term \"distance\"");
  expect_parameter_rejected(R"({"kind": "body_position", "body": "box", "axis": 0})",
                            "optimization.parameters[0].axis", "unknown key");
  expect_parameter_rejected(R"({"kind": "force", "index": 1, "rod": "arm"})",
                            "optimization.parameters[0].rod", "unknown key");
  expect_term_rejected(R"({"term": "effort", "scale": 2})", "optimization.objective[0].scale",
                       "unknown key");
  expect_term_rejected(
      kEffortTerm + R"(, {"term": "body_pose", "body": "box", "positon": [0, 0, 0]})",
      "optimization.objective[1].positon", "unknown key");
  expect_rejected(scene_text(block(kForceParameter, kEffortTerm, R"(, "colour": "red")")),
                  "optimization.colour", "unknown key");
  expect_parameter_rejected(R"({"body": "box"})", "optimization.parameters[0].kind",
                            "required but missing");
  expect_term_rejected(R"({"rod": "arm"})", "optimization.objective[0].term",
                       "required but missing");
}

TEST(OptimizationErrors, NamesThatDoNotExist) {
  expect_parameter_rejected(R"({"kind": "body_position", "body": "crate"})",
                            "optimization.parameters[0].body", "no body is named \"crate\"");
  expect_parameter_rejected(R"({"kind": "body_position", "body": "arm"})",
                            "optimization.parameters[0].body", "no body is named \"arm\"");
  expect_parameter_rejected(R"({"kind": "rod_node_velocities", "rod": "whip"})",
                            "optimization.parameters[0].rod", "no rod is named \"whip\"");
  expect_parameter_rejected(R"({"kind": "bending_stiffness", "rod": "box"})",
                            "optimization.parameters[0].rod", "no rod is named \"box\"");
  expect_term_rejected(R"({"term": "body_pose", "body": "crate", "position": [0, 0, 0]})",
                       "optimization.objective[0].body", "no body is named \"crate\"");
  expect_term_rejected(R"({"term": "point_targets", "rod": "whip", "letter": "S"})",
                       "optimization.objective[0].rod", "no rod is named \"whip\"");
  expect_term_rejected(
      R"({"term": "projected_trajectory", "rod": "whip", "node": 0, "curve": [[0, 0], [1, 1]]})",
      "optimization.objective[0].rod", "no rod is named \"whip\"");
}

TEST(OptimizationErrors, IndicesOutOfRange) {
  expect_parameter_rejected(R"({"kind": "node_force", "rod": "arm", "node_force": 2})",
                            "optimization.parameters[0].node_force", "node force 2 of rod 1, which has 2");
  expect_parameter_rejected(R"({"kind": "node_force", "rod": "stub", "node_force": 0})",
                            "optimization.parameters[0].node_force", "node force 0 of rod 0, which has 0");
  expect_parameter_rejected(R"({"kind": "node_force", "rod": "arm", "node_force": -1})",
                            "optimization.parameters[0].node_force", "must be an integer in [0,");
  expect_parameter_rejected(R"({"kind": "cable_tension", "rod": "arm", "cable": 2})",
                            "optimization.parameters[0].cable", "cable 2 of rod 1, which has 2");
  expect_parameter_rejected(R"({"kind": "cable_tension", "rod": "arm"})",
                            "optimization.parameters[0].cable", "required but missing");
  expect_parameter_rejected(R"({"kind": "force", "index": 2})", "optimization.parameters[0].index",
                            "force 2");
  expect_parameter_rejected(R"({"kind": "torque", "index": 5})", "optimization.parameters[0].index",
                            "torque 5");
  expect_parameter_rejected(R"({"kind": "spring_stiffness", "index": 2})",
                            "optimization.parameters[0].index", "spring 2");
  expect_parameter_rejected(R"({"kind": "rest_darboux", "rod": "stub"})",
                            "optimization.parameters[0]", "no interior node");
  expect_term_rejected(
      R"({"term": "projected_trajectory", "rod": "arm", "node": 4, "curve": [[0, 0], [1, 1]]})",
      "optimization.objective[0].node", "must be an integer in [0, 3]");
  expect_term_rejected(R"({"term": "body_pose", "body": "box", "frame": 6, "position": [0, 0, 0]})",
                       "optimization.objective[0].frame", "must be an integer in [-1, 5]");
  expect_term_rejected(R"({"term": "effort", "parameters": [1]})",
                       "optimization.objective[0].parameters[0]", "must be an integer in [0, 0]");
}

TEST(OptimizationErrors, PointTargetSources) {
  expect_term_rejected(
      R"({"term": "point_targets", "rod": "arm", "targets": [[0, 0, 0], [1, 0, 0], [2, 0, 0]]})",
      "optimization.objective[0].targets", "has 3 points, but the rod has 4 nodes");
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm", "targets": )" + kArmLifted1 +
                           R"(, "letter": "S"})",
                       "optimization.objective[0].targets",
                       "exactly one of targets, polyline or letter");
  expect_term_rejected(
      R"({"term": "point_targets", "rod": "arm", "polyline": [[0, 0, 0], [1, 0, 0]], "letter": "S"})",
      "optimization.objective[0].targets", "exactly one of targets, polyline or letter");
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm"})",
                       "optimization.objective[0].targets",
                       "exactly one of targets, polyline or letter");
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm", "targets": [[0, 0, 0], [1, 0]]})",
                       "optimization.objective[0].targets[1]", "must be an array of 3 numbers");
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm", "polyline": [[0, 0, 0]]})",
                       "optimization.objective[0].polyline", "at least 2 points");
  for (const std::string letter : {"1", "?", "\u00e9"}) {
    SCOPED_TRACE(letter);
    const std::optional<SceneError> e = rejected(
        scene_text(block(kForceParameter, R"({"term": "point_targets", "rod": "arm", "letter": ")" +
                                              letter + "\"}")));
    if (e) {
      EXPECT_EQ(e->field(), "optimization.objective[0].letter") << e->what();
    }
  }
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm", "letter": "AB"})",
                       "optimization.objective[0].letter", "one character");
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm", "letter": ""})",
                       "optimization.objective[0].letter", "one character");
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm", "letter": "S", "height": 0})",
                       "optimization.objective[0].height", "must be positive");
}

TEST(OptimizationErrors, DegenerateCurvesAreSceneErrors) {
  // A polyline or curve of zero length cannot be resampled: bad input, named like the rest
  // (not a bare std::invalid_argument from resample_polyline, which the CLI reports as an
  // I/O error with exit status 1).
  expect_term_rejected(
      R"({"term": "point_targets", "rod": "arm", "polyline": [[1, 0, 0], [1, 0, 0]]})",
      "optimization.objective[0].polyline", "");
  expect_term_rejected(
      R"({"term": "projected_trajectory", "rod": "arm", "node": 3, "curve": [[1, 0], [1, 0]]})",
      "optimization.objective[0].curve", "");
}

TEST(OptimizationErrors, BadWeightsAndTermFields) {
  expect_term_rejected(R"({"term": "effort", "weight": -1})", "optimization.objective[0].weight",
                       "≥ 0");
  expect_term_rejected(R"({"term": "point_targets", "rod": "arm", "letter": "S", "weight": -0.5})",
                       "optimization.objective[0].weight", "≥ 0");
  expect_term_rejected(
      R"({"term": "body_pose", "body": "box", "position": [0, 0, 0], "position_weights": [1, -1, 1]})",
      "optimization.objective[0].position_weights", "≥ 0");
  expect_term_rejected(R"({"term": "body_pose", "body": "box", "orientation": [1, 1, 0, 0]})",
                       "optimization.objective[0].orientation", "unit quaternion");
  expect_term_rejected(
      R"({"term": "body_pose", "body": "box", "orientation": [1, 0, 0, 0], "orientation_weight": -1})",
      "optimization.objective[0].orientation_weight", "≥ 0");
  expect_term_rejected(
      R"({"term": "projected_trajectory", "body": "box", "plane": "xx", "curve": [[0, 0], [1, 1]]})",
      "optimization.objective[0].plane", "two different axes");
  expect_term_rejected(R"({"term": "projected_trajectory", "body": "box", "curve": [[0, 0]]})",
                       "optimization.objective[0].curve", "at least 2 points");
  expect_term_rejected(
      R"({"term": "projected_trajectory", "body": "box", "curve": [[0, 0], [1, 1, 1]]})",
      "optimization.objective[0].curve[1]", "must be an array of 2 numbers");
}

TEST(OptimizationErrors, OptimizerSettings) {
  const auto with = [](const std::string& extra) {
    return scene_text(block(kForceParameter, kEffortTerm, extra));
  };
  expect_rejected(with(R"(, "optimizer": "bfgs")"), "optimization.optimizer",
                  "unknown optimizer \"bfgs\"");
  expect_rejected(with(R"(, "max_iterations": 0)"), "optimization.max_iterations",
                  "must be an integer in [1,");
  expect_rejected(with(R"(, "max_iterations": 2.5)"), "optimization.max_iterations",
                  "must be an integer");
  expect_rejected(with(R"(, "target_normalized_loss": -1e-3)"),
                  "optimization.target_normalized_loss", "must be a finite number >= 0");
  expect_rejected(with(R"(, "lbfgs_memory": 0)"), "optimization.lbfgs_memory",
                  "must be an integer in [1,");
  expect_rejected(with(R"(, "loss_scale": -1)"), "optimization.loss_scale", "must be > 0");
}

TEST(OptimizationErrors, Bounds) {
  expect_parameter_rejected(R"({"kind": "force", "index": 1, "lower": 1, "upper": 1})",
                            "optimization.parameters[0].lower",
                            "the lower bound (1) must be below the upper bound (1)");
  expect_parameter_rejected(R"({"kind": "force", "index": 1, "upper": -1e300, "lower": 0})",
                            "optimization.parameters[0].lower", "must be below the upper bound");
  expect_parameter_rejected(R"({"kind": "force", "index": 1, "lower": "0"})",
                            "optimization.parameters[0].lower", "must be a number");
  // The initial γ must lie within the bounds: the box's force is (0, 1, 0) in every frame,
  // the arm's cable 1 pulls with 2.5.
  expect_parameter_rejected(R"({"kind": "force", "index": 1, "lower": 0.5})",
                            "optimization.parameters[0].lower",
                            "the initial value 0 of forces[1].frame[1][0] is below its lower bound (0.5)");
  expect_parameter_rejected(
      kForceParameter + R"(, {"kind": "cable_tension", "rod": "arm", "cable": 1, "upper": 2})",
      "optimization.parameters[1].upper",
      "the initial value 2.5 of rods[1].cables[1].tension.frame[1] is above its upper bound (2)");
  // Bounds that differ beyond 6 digits are printed so that they differ.
  expect_parameter_rejected(R"({"kind": "force", "index": 1, "lower": 0.1000001, "upper": 0.1})",
                            "optimization.parameters[0].lower", "(0.10000009999999999) must be below the upper bound (0.10000000000000001)");
  // A bounded scene whose optimizer is Ceres still loads (gradcheck and simulate need no
  // optimiser; `optimize` refuses it, OptimizationCli.CablesOnlyPull).
  const Scene ceres = parsed(scene_text(block(R"({"kind": "force", "index": 1, "upper": 5})",
                                              kEffortTerm, R"(, "optimizer": "ceres-lbfgs")")));
  EXPECT_TRUE(ceres.optimization->parameters.bounded());
}

TEST(OptimizationErrors, BlockStructure) {
  expect_rejected(scene_text(block(kForceParameter, kEffortTerm), 0), "frames",
                  "at least one frame");
  expect_rejected(scene_text(block("", kEffortTerm)), "optimization.parameters",
                  "at least one parameter");
  expect_rejected(scene_text(block(kForceParameter, "")), "optimization.objective",
                  "at least one term");
  expect_rejected(scene_text(R"({"objective": [{"term": "effort"}]})"), "optimization.parameters",
                  "required but missing");
  expect_rejected(scene_text(R"({"parameters": [{"kind": "force", "index": 1}]})"),
                  "optimization.objective", "required but missing");
  expect_rejected(scene_text("[]"), "optimization", "must be a JSON object");
  expect_rejected(scene_text(R"({"parameters": {"kind": "force"}, "objective": []})"),
                  "optimization.parameters", "must be an array");
  expect_rejected(scene_text(block("3", kEffortTerm)), "optimization.parameters[0]",
                  "must be a JSON object");
}

TEST(OptimizationErrors, RepeatedParameters) {
  expect_parameter_rejected(kForceParameter + ", " + kForceParameter, "optimization.parameters[1]",
                            "repeats the parameter force 1");
  expect_parameter_rejected(
      R"({"kind": "body_position", "body": "ball"}, {"kind": "body_position", "body": "box"},
         {"kind": "body_position", "body": "box"})",
      "optimization.parameters[2]", "repeats the parameter body_position 1");
  // The static and the per-frame rest shape of one rod are the same numbers.
  expect_parameter_rejected(
      R"({"kind": "rest_darboux", "rod": "arm"}, {"kind": "rest_darboux_per_frame", "rod": "arm"})",
      "optimization.parameters[1]", "repeats");
  // Different cables, node forces, bodies: not repeats.
  const Scene s = parsed(scene_text(block(
      R"({"kind": "cable_tension", "rod": "arm", "cable": 0}, {"kind": "cable_tension", "rod": "arm", "cable": 1},
         {"kind": "node_force", "rod": "arm", "node_force": 0}, {"kind": "node_force", "rod": "arm", "node_force": 1},
         {"kind": "body_position", "body": "ball"}, {"kind": "body_position", "body": "box"})",
      kEffortTerm)));
  EXPECT_EQ(s.optimization->parameters.size(), 2 * kFrames + 2 * 3 * kFrames + 6);
}

TEST(OptimizationErrors, InitialVelocitiesInAStaticScene) {
  for (const std::string kind : {"body_linear_velocity", "body_angular_velocity"}) {
    expect_parameter_rejected(R"({"kind": ")" + kind + R"(", "body": "box"})",
                              "optimization.parameters[0]", "static mode", "static");
  }
  expect_parameter_rejected(kForceParameter + R"(, {"kind": "rod_node_velocities", "rod": "arm"})",
                            "optimization.parameters[1]", "static mode", "static");
  // Other kinds are fine in static mode.
  const Scene s = parsed(scene_text(
      block(
          R"({"kind": "body_position", "body": "box"}, {"kind": "node_force", "rod": "arm", "node_force": 0})",
          kEffortTerm),
      kFrames, "static"));
  EXPECT_EQ(s.optimization->parameters.size(), 3 + 3 * kFrames);
}

// ---------------------------------------------------------------------------------------
// The bundled problems.

const fs::path kSourceDir = LIEDYN_SOURCE_DIR;

std::vector<fs::path> scene_files(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

double rod_length(const RodSpec& rod) {
  double length = 0.0;
  for (int i = 0; i + 1 < rod.node_count(); ++i) length += (rod.nodes[i + 1] - rod.nodes[i]).norm();
  return length;
}

TEST(OptimizationScenes, BundledProblemsLoad) {
  const std::map<std::string, int> sizes = {
      {"die_throw.json", 6},                         // ω_0 and v_0
      {"die_throw_contact.json", 3},                 // ω_0
      {"cable_tip_curve.json", 8 * 100},             // 8 cables × 100 frames
      {"rest_shape_tip_curve.json", 3 * 13 * 100},   // 13 interior nodes × 100 frames
      {"arm_reach.json", 6 * 50},                    // 6 motors × 50 frames
      {"billiard.json", 3},                          // the cue ball's v_0
      {"rod_throw_friction.json", 3 * 7}};           // the thrown rod's 7 node velocities
  std::vector<fs::path> files = scene_files(kSourceDir / "problems/scenes/optimization");
  const std::vector<fs::path> letters = scene_files(kSourceDir / "problems/scenes/letters");
  EXPECT_EQ(files.size(), 7u);
  EXPECT_EQ(letters.size(), 7u);
  files.insert(files.end(), letters.begin(), letters.end());
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    Scene s;
    ASSERT_NO_THROW(s = load_scene(file));
    ASSERT_TRUE(s.optimization.has_value());
    EXPECT_GT(s.optimization->parameters.size(), 0);
    EXPECT_FALSE(s.optimization->objective.terms().empty());
    EXPECT_NO_THROW(make_differentiable_simulation(s));
    const auto size = sizes.find(file.filename().string());
    if (size != sizes.end()) {
      EXPECT_EQ(s.optimization->parameters.size(), size->second);
    }
  }
}

TEST(OptimizationScenes, LetterRodsAreAsLongAsTheirLetters) {
  // Node counts of paper Table 3, as scripts/make_letter_scenes.py writes them.
  const std::map<char, int> nodes = {{'S', 61}, {'I', 17}, {'G', 65}, {'R', 69},
                                     {'A', 49}, {'P', 86}, {'H', 61}};
  const std::string script = [] {
    std::ifstream in(kSourceDir / "scripts/make_letter_scenes.py");
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }();
  ASSERT_FALSE(script.empty());
  for (const auto& [letter, count] : nodes) {
    const std::string name = std::string("letter_") + letter + ".json";
    SCOPED_TRACE(name);
    const Scene s = load_scene(kSourceDir / "problems/scenes/letters" / name);
    ASSERT_EQ(s.model.rods.size(), 1u);
    const RodSpec& rod = s.model.rods[0];
    EXPECT_EQ(rod.name, std::string(1, letter));
    EXPECT_EQ(rod.node_count(), count);
    const double expected = polyline_length(letter_polyline(letter)) * 0.5;
    EXPECT_NEAR(rod_length(rod), expected, 1e-5 * expected);
    // A straight line: the length is also the distance between its ends.
    EXPECT_NEAR((rod.nodes.back() - rod.nodes.front()).norm(), rod_length(rod), 1e-9);
    // The script's row for the letter: (nodes, length).
    std::smatch row;
    const std::regex pattern(std::string("\"") + letter + "\": \\((\\d+), ([0-9.]+)\\)");
    ASSERT_TRUE(std::regex_search(script, row, pattern));
    EXPECT_EQ(std::stoi(row[1].str()), count);
    EXPECT_NEAR(std::stod(row[2].str()), expected, 1e-5 * expected);
    // The optimisation: every node's initial velocity, towards the letter.
    ASSERT_TRUE(s.optimization.has_value());
    EXPECT_EQ(s.optimization->parameters.size(), 3 * count);
    ASSERT_EQ(s.optimization->parameters.blocks().size(), 1u);
    EXPECT_EQ(s.optimization->parameters.blocks()[0].kind, ParameterKind::kRodNodeVelocities);
    ASSERT_EQ(s.optimization->objective.terms().size(), 1u);
    EXPECT_EQ(s.optimization->objective.terms()[0]->name(), "point_targets");
  }
}

// ---------------------------------------------------------------------------------------
// DifferentiableSimulation: its forward pass is the plain simulation of the scene.

// A dynamic scene with a body and a clamped rod under gravity, and parameters of every way
// γ enters a model: initial velocities, per-step loads, a per-step cable tension, rest shape.
std::string dynamic_scene() {
  return R"({
    "time_step": 0.01, "frames": 12, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-11 },
    "bodies": [ { "name": "box", "mass": 0.5, "inertia": [0.01, 0.02, 0.025], "position": [0, 0, 1],
                  "linear_velocity": [0.3, 0, 1], "angular_velocity": [1, -2, 3] } ],
    "forces": [ { "body": "box", "point": [0, 0.1, 0], "force": [0.5, 0, 0] } ],
    "torques": [ { "body": "box", "torque": [0, 0, 0.01] } ],
    "rods": [ { "name": "arm", "shape": { "type": "line", "start": [0, 0, 0], "end": [0.4, 0, 0], "edges": 5 },
                "mass": 0.1, "radius": 0.01, "stretch_stiffness": 200, "shear_stiffness": 20,
                "bending_stiffness": [0.05, 0.05, 0.05], "fixed_nodes": [0], "fixed_edges": [0],
                "node_forces": [ { "node": 5, "force": [0, 0.1, 0] } ],
                "cables": [ { "edges": [0, 3], "angle": 90, "tension": 0.5 } ] } ],
    "optimization": {
      "parameters": [ { "kind": "body_angular_velocity", "body": "box" },
                      { "kind": "body_linear_velocity", "body": "box" },
                      { "kind": "force", "index": 0 }, { "kind": "torque", "index": 0 },
                      { "kind": "node_force", "rod": "arm", "node_force": 0 },
                      { "kind": "cable_tension", "rod": "arm", "cable": 0 },
                      { "kind": "rest_darboux_per_frame", "rod": "arm" },
                      { "kind": "bending_stiffness", "rod": "arm" } ],
      "objective": [
        { "term": "body_pose", "body": "box", "position": [0, 0, 0.5],
          "orientation": [0.7071067811865476, 0.7071067811865476, 0, 0] },
        { "term": "point_targets", "rod": "arm", "frame": 6, "polyline": [[0, 0, 0], [0.3, 0, -0.2]] },
        { "term": "projected_trajectory", "rod": "arm", "node": 5, "plane": "xz", "curve": [[0.4, 0], [0.3, -0.1]] },
        { "term": "effort", "weight": 0.01, "parameters": [2, 5] } ] } })";
}

// The plain simulation of `model`, recorded like DifferentiableSimulation records it.
Trajectory plain_run(const Model& model, const SolverOptions& options, int frames) {
  Simulator simulator(model, options);
  Trajectory t;
  t.time_step = model.time_step;
  t.static_equilibrium = model.static_equilibrium;
  t.initial_step = simulator.last_step();
  t.states.push_back(simulator.state());
  for (int k = 1; k <= frames; ++k) {
    const StepReport report = simulator.step();
    EXPECT_TRUE(report.converged()) << "frame " << k;
    t.states.push_back(simulator.state());
  }
  return t;
}

double max_point_difference(const Trajectory& a, const Trajectory& b) {
  double d = 0.0;
  EXPECT_EQ(a.states.size(), b.states.size());
  for (std::size_t k = 0; k < std::min(a.states.size(), b.states.size()); ++k) {
    EXPECT_EQ(a.states[k].points.size(), b.states[k].points.size());
    for (std::size_t i = 0; i < std::min(a.states[k].points.size(), b.states[k].points.size());
         ++i) {
      d = std::max(d, (a.states[k].points[i] - b.states[k].points[i]).norm());
    }
  }
  return d;
}

TEST(OptimizationSimulation, ForwardPassIsThePlainSimulation) {
  const Scene s = parsed(dynamic_scene());
  const DifferentiableSimulation sim = make_differentiable_simulation(s);
  EXPECT_EQ(sim.frames(), 12);
  const Eigen::VectorXd gamma = sim.initial_parameters();
  ASSERT_EQ(gamma.size(), 3 + 3 + 36 + 36 + 36 + 12 + 3 * 4 * 12 + 3);
  const DifferentiableSimulation::Result r = sim.evaluate(gamma, nullptr);
  const Trajectory plain = plain_run(s.model, s.solver, s.frames);
  const double loss = s.optimization->objective.value(plain, gamma);
  EXPECT_GT(loss, 1e-2);  // not trivially zero
  EXPECT_NEAR(r.loss, loss, 1e-9 * loss);
  EXPECT_LT(max_point_difference(r.trajectory, plain), 1e-9);
  // The box fell and the rod sagged: the comparison is of a real motion.
  EXPECT_LT(plain.states.back().points[0].z(), 1.0 + 0.12 - 0.05);
  EXPECT_LT(plain.states.back().points[s.model.rod_point(0, 5)].z(), -1e-3);
  // With a gradient the loss is the same.
  Eigen::VectorXd gradient;
  EXPECT_EQ(sim.evaluate(gamma, &gradient).loss, r.loss);
  EXPECT_EQ(gradient.size(), gamma.size());
  EXPECT_TRUE(gradient.allFinite());
  EXPECT_GT(gradient.norm(), 0.0);
}

TEST(OptimizationSimulation, ChangedParametersAreTheChangedModel) {
  const Scene s = parsed(dynamic_scene());
  const DifferentiableSimulation sim = make_differentiable_simulation(s);
  Eigen::VectorXd gamma = sim.initial_parameters();
  // γ[3…5] is the box's initial velocity (after ω_0); γ[6…8] the force in frame 1.
  gamma.segment<3>(3) = Vector3(-0.2, 0.4, 2.0);
  Model changed = s.model;
  changed.bodies[0].linear_velocity = Vector3(-0.2, 0.4, 2.0);
  const Trajectory plain = plain_run(changed, s.solver, s.frames);
  const double loss = s.optimization->objective.value(plain, gamma);
  const DifferentiableSimulation::Result r = sim.evaluate(gamma, nullptr);
  EXPECT_NEAR(r.loss, loss, 1e-9 * loss);
  EXPECT_LT(max_point_difference(r.trajectory, plain), 1e-9);
  // …and differs from the loss at the scene's values.
  EXPECT_GT(std::abs(r.loss - sim.evaluate(sim.initial_parameters(), nullptr).loss), 1e-3 * loss);
}

TEST(OptimizationSimulation, WrongSizeOfGammaThrows) {
  const Scene s = parsed(dynamic_scene());
  const DifferentiableSimulation sim = make_differentiable_simulation(s);
  const int n = sim.parameters().size();
  Eigen::VectorXd gradient;
  EXPECT_THROW(sim.evaluate(Eigen::VectorXd::Zero(n - 1), nullptr), std::invalid_argument);
  EXPECT_THROW(sim.evaluate(Eigen::VectorXd::Zero(n + 1), &gradient), std::invalid_argument);
  EXPECT_THROW(sim.evaluate(Eigen::VectorXd(), nullptr), std::invalid_argument);
  // A scene without the block has nothing to differentiate.
  Scene plain = s;
  plain.optimization.reset();
  EXPECT_THROW(make_differentiable_simulation(plain), SceneError);
}

// ---------------------------------------------------------------------------------------
// `liedyn gradcheck` and `liedyn optimize`, run as processes.

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, sep)) out.push_back(item);
  return out;
}

std::string last_line(const std::string& text) {
  std::vector<std::string> lines = split(text, '\n');
  while (!lines.empty() && lines.back().empty()) lines.pop_back();
  return lines.empty() ? std::string() : lines.back();
}

struct History {
  std::string header;
  std::vector<std::string> lines;  // the rows as written
  std::vector<int> iteration;
  std::vector<double> loss, normalized_loss, gradient_norm, seconds;
  double best_normalized_loss() const {
    return normalized_loss.empty()
               ? INFINITY
               : *std::min_element(normalized_loss.begin(), normalized_loss.end());
  }
};

History read_history(const fs::path& file) {
  History h;
  const std::vector<std::string> lines = split(liedyn::test::read_file(file), '\n');
  if (lines.empty()) {
    ADD_FAILURE() << file << " is empty";
    return h;
  }
  h.header = lines[0];
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> f = split(lines[i], ',');
    if (f.size() != 5) {
      ADD_FAILURE() << file << " line " << i + 1 << ": \"" << lines[i] << "\"";
      continue;
    }
    h.lines.push_back(lines[i]);
    h.iteration.push_back(std::stoi(f[0]));
    h.loss.push_back(std::stod(f[1]));
    h.normalized_loss.push_back(std::stod(f[2]));
    h.gradient_norm.push_back(std::stod(f[3]));
    h.seconds.push_back(std::stod(f[4]));
  }
  return h;
}

class OptimizationCli : public liedyn::test::CliFixture {
 protected:
  OptimizationCli() : CliFixture("liedyn_optimization_test_") {}

  static std::string die() {
    return (kSourceDir / "problems/scenes/optimization/die_throw.json").string();
  }

  // No temporary file or staging folder (problems/output_folder.hpp) is left in `out`.
  static void expect_no_temporaries(const fs::path& out) {
    for (const auto& entry : fs::directory_iterator(out)) {
      EXPECT_EQ(entry.path().filename().string().find(".liedyn-"), std::string::npos) << entry.path();
    }
  }

  // The history of a run: header, iterations 0, 1, … in order, normalized_loss = loss / the
  // first row's loss (the loss scale: the initial loss), finite non-negative columns.
  static History checked_history(const fs::path& out) {
    const History h = read_history(out / "history.csv");
    EXPECT_EQ(h.header, "iteration,loss,normalized_loss,gradient_norm,seconds");
    EXPECT_FALSE(h.lines.empty());
    if (h.lines.empty()) return h;
    EXPECT_EQ(h.iteration[0], 0);
    EXPECT_NEAR(h.normalized_loss[0], 1.0, 1e-12);
    for (std::size_t i = 0; i < h.lines.size(); ++i) {
      SCOPED_TRACE(h.lines[i]);
      if (i > 0) {
        EXPECT_EQ(h.iteration[i], h.iteration[i - 1] + 1);
        EXPECT_GE(h.seconds[i], h.seconds[i - 1]);
      }
      EXPECT_NEAR(h.normalized_loss[i], h.loss[i] / h.loss[0],
                  1e-12 * h.normalized_loss[i] + 1e-300);
      EXPECT_GE(h.gradient_norm[i], 0.0);
      EXPECT_TRUE(std::isfinite(h.loss[i]) && std::isfinite(h.gradient_norm[i]));
    }
    return h;
  }

};

const std::regex kGradcheckLine(
    "^gradcheck: max_rel_error=[0-9.eE+-]+ params=6 tolerance=[0-9.eE+-]+$");

TEST_F(OptimizationCli, GradcheckOfTheDieThrowPasses) {
  const Result r = run({"gradcheck", die()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string line = last_line(r.out);
  EXPECT_TRUE(std::regex_match(line, kGradcheckLine)) << line;
  // The error it reports is within the default tolerance 1e-5.
  const std::smatch m = [&] {
    std::smatch s;
    std::regex_search(line, s, std::regex("max_rel_error=([0-9.eE+-]+)"));
    return s;
  }();
  ASSERT_EQ(m.size(), 2u) << line;
  EXPECT_LE(std::stod(m[1].str()), 1e-5) << line;
  // --verbose adds one row per parameter, named.
  const Result v = run({"gradcheck", die(), "--verbose"});
  ASSERT_EQ(v.exit_code, 0) << v.out << v.err;
  EXPECT_NE(v.out.find("parameter,adjoint,finite_difference,relative_error\n"), std::string::npos)
      << v.out;
  for (const std::string name :
       {"bodies[0].angular_velocity[0],", "bodies[0].linear_velocity[2],"}) {
    EXPECT_NE(v.out.find("\n" + name), std::string::npos) << name << "\n" << v.out;
  }
  EXPECT_TRUE(std::regex_match(last_line(v.out), kGradcheckLine)) << v.out;
}

// The max_rel_error of a gradcheck's last line.
double gradcheck_error(const std::string& out) {
  std::smatch m;
  const std::string line = last_line(out);
  if (!std::regex_search(line, m, std::regex("max_rel_error=([0-9.eE+-]+)"))) return -1.0;
  return std::stod(m[1].str());
}

// Every bundled optimisation scene (letters included) passes gradcheck under the three time
// integrators, its integrator set from the command line (one test per integrator, so that they
// run side by side). The forward tolerance is set to 1e-14: at the scenes' own (1e-10, 1e-12)
// the differences of the loss measure the forward solver's noise (the letters at their
// defaults: up to 1.2 relative), not the gradient (docs/design.md §8.5); at 1e-13 the rod
// thrown across a rod with friction still does under BDF2 (1.0e-5, 2.6e-6 at 1e-14). 12
// sampled parameters per scene. Some need more than that: the die through contact under the
// second-order integrators (GradcheckOfTheBouncingDieConvergesAsTheStepShrinks) and the two
// tip-curve rods under backward Euler and BDF2 (GradcheckOfTheTipCurveRodsDoesNotDependOnThe-
// ForwardTolerance).
class OptimizationCliIntegrator : public OptimizationCli,
                                  public ::testing::WithParamInterface<const char*> {};

TEST_P(OptimizationCliIntegrator, GradcheckPassesOnEveryBundledOptimisationScene) {
  const std::string integrator = GetParam();
  std::vector<fs::path> scenes;
  for (const char* folder : {"problems/scenes/optimization", "problems/scenes/letters"}) {
    for (const auto& entry : fs::directory_iterator(kSourceDir / folder)) {
      if (entry.path().extension() == ".json") scenes.push_back(entry.path());
    }
  }
  std::sort(scenes.begin(), scenes.end());
  ASSERT_EQ(scenes.size(), 14u);
  int checked = 0;
  for (const fs::path& scene : scenes) {
    if (integrator == "fox_goodwin") {
      // Conditionally stable: it refuses the scenes with contact, and those whose rods' stretch
      // is beyond its stable step at their h (lib/stability.hpp), naming why.
      const Result r = run({"gradcheck", scene.string(), "--sample", "12", "--step", "1e-5",
                            "--set", "integrator=fox_goodwin", "--set", "solver.tolerance=1e-14"});
      if (r.exit_code != 0) {
        EXPECT_EQ(r.exit_code, 2) << scene << r.err;
        EXPECT_TRUE(r.err.find("cannot have contact under the fox_goodwin") != std::string::npos ||
                    r.err.find("time_step: is too large for the fox_goodwin") != std::string::npos)
            << scene << r.err;
        continue;
      }
      ++checked;
      const double error = gradcheck_error(r.out);
      EXPECT_GE(error, 0.0) << scene << r.out;
      EXPECT_LE(error, 1e-5) << scene << r.out;
      continue;
    }
    if (integrator != "backward_euler" && scene.stem() == "die_throw_contact") continue;
    if (integrator != "trapezoidal" &&
        (scene.stem() == "cable_tip_curve" || scene.stem() == "rest_shape_tip_curve")) {
      continue;
    }
    SCOPED_TRACE(scene.filename().string() + " " + integrator);
    const Result r = run({"gradcheck", scene.string(), "--sample", "12", "--step", "1e-5",
                          "--set", "integrator=" + integrator, "--set", "solver.tolerance=1e-14"});
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    const double error = gradcheck_error(r.out);
    EXPECT_GE(error, 0.0) << r.out;
    EXPECT_LE(error, 1e-5) << r.out;
  }
  // fox_goodwin: the arm, the die thrown without contact and the letters A, H and I.
  if (integrator == "fox_goodwin") {
    EXPECT_EQ(checked, 5);
  }
}

INSTANTIATE_TEST_SUITE_P(Integrators, OptimizationCliIntegrator,
                         ::testing::Values("backward_euler", "trapezoidal", "fox_goodwin", "bdf2"),
                         [](const auto& info) { return std::string(info.param); });

// The die thrown onto the table under the second-order integrators keeps bouncing: under the
// trapezoidal rule its stiff contact is undamped (ω h = 6 at h = 2 ms), and the loss after 400
// frames changes by O(1) within 1e-4 of the throw, so differences of 1e-5 relative see a
// different bounce (error 1.75); shrinking the step, they converge to the adjoint: measured
// 0.87, 9e-3, 4.4e-4 at 1e-7, 1e-8, 1e-9. BDF2 damps the contact, but less than backward
// Euler: from frame ~170 (the die tipping over an edge) the loss is as sensitive, and the
// differences converge more slowly; over its first 200 frames, measured 1.8, 9.9e-2, 1.7e-3 at
// 1e-5, 1e-9, 1e-10 (over 400: 1.0, 0.27, 0.18 at 1e-5, 1e-9, 1e-10, the last one at the
// resolution of the loss).
TEST_F(OptimizationCli, GradcheckOfTheBouncingDieConvergesAsTheStepShrinks) {
  const std::string scene = (kSourceDir / "problems/scenes/optimization/die_throw_contact.json").string();
  struct Setting {
    std::string integrator, frames;
    std::vector<std::string> steps;
    double last;  // the largest error accepted at the smallest step
  };
  for (const Setting& setting : {Setting{"trapezoidal", "400", {"1e-5", "1e-8", "1e-9"}, 1e-3},
                                 Setting{"bdf2", "200", {"1e-5", "1e-9", "1e-10"}, 1e-2}}) {
    std::vector<double> errors;
    for (const std::string& step : setting.steps) {
      const Result r = run({"gradcheck", scene, "--step", step, "--set",
                            "integrator=" + setting.integrator, "--set", "frames=" + setting.frames,
                            "--set", "solver.tolerance=1e-14"});
      errors.push_back(gradcheck_error(r.out));
      std::cout << "[ measured ] " << setting.integrator << ", step " << step
                << ": max_rel_error " << errors.back() << "\n";
    }
    EXPECT_GT(errors[0], 0.1) << setting.integrator;
    EXPECT_LT(errors[1], 0.1 * errors[0]) << setting.integrator;
    EXPECT_LT(errors[2], 0.2 * errors[1]) << setting.integrator;
    EXPECT_LT(errors[2], setting.last) << setting.integrator;
  }
}

// The tip-curve rods under backward Euler and BDF2 (cable tensions, rest Darboux vectors per
// frame): the controls of the first frames move the final tip by little (gradient entries 1e-2
// of the largest), and the differences of 1e-5 leave errors above the 1e-5 of the test above
// whatever the forward tolerance: measured at 1e-13 and 1e-15, backward Euler cable arm 1.45e-5
// and 1.45e-5, rest shape 2.4e-7 and 2.4e-7; BDF2 8.4e-6, 6.2e-6 and 1.8e-7, 1.8e-7. They did
// depend on it before Newton took its final step (newton.hpp: take_final_step): 1.0e-3 and
// 1.5e-5 for the cable arm, the forward solver's noise at 1e-13 in the differences.
TEST_F(OptimizationCli, GradcheckOfTheTipCurveRodsDoesNotDependOnTheForwardTolerance) {
  for (const std::string integrator : {"backward_euler", "bdf2"}) {
    for (const char* name : {"cable_tip_curve.json", "rest_shape_tip_curve.json"}) {
      const std::string scene = (kSourceDir / "problems/scenes/optimization" / name).string();
      std::vector<double> errors;
      for (const std::string tolerance : {"1e-13", "1e-15"}) {
        const Result r = run({"gradcheck", scene, "--sample", "12", "--step", "1e-5", "--set",
                              "integrator=" + integrator, "--set", "solver.tolerance=" + tolerance});
        errors.push_back(gradcheck_error(r.out));
        std::cout << "[ measured ] " << name << " " << integrator << " forward tolerance "
                  << tolerance << ": max_rel_error " << errors.back() << "\n";
      }
      EXPECT_GE(errors[1], 0.0) << name << " " << integrator;
      EXPECT_LT(errors[0], 2.0 * errors[1]) << name << " " << integrator;
      EXPECT_LT(errors[0], 1e-4) << name << " " << integrator;
    }
  }
}

// --set on a single-run command: a value over the scene file's, named in what the run reports;
// a malformed one or a path that leads nowhere is a bad-input error (exit 2) naming it.
TEST_F(OptimizationCli, SetOverridesTheSceneAndRejectsWhatItCannotApply) {
  const Result ok = run({"gradcheck", die(), "--set", "integrator=trapezoidal"});
  EXPECT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  const Result unknown = run({"gradcheck", die(), "--set", "integrator=midpoint"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("integrator=midpoint"), std::string::npos) << unknown.err;
  EXPECT_NE(unknown.err.find("integrator"), std::string::npos) << unknown.err;
  const Result malformed = run({"gradcheck", die(), "--set", "integrator"});
  EXPECT_EQ(malformed.exit_code, 2);
  EXPECT_NE(malformed.err.find("--set integrator: expected PATH=VALUE"), std::string::npos)
      << malformed.err;
  const Result nowhere = run({"gradcheck", die(), "--set", "bodies.5.mass=1"});
  EXPECT_EQ(nowhere.exit_code, 2);
  EXPECT_NE(nowhere.err.find("index 5 is out of range"), std::string::npos) << nowhere.err;
  // A run's manifest names its settings with the scene; the value took effect (2 frames).
  const Result sim = run({"simulate", die(), "--set", "frames=2", "--out", "sim", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  EXPECT_NE(liedyn::test::read_file(dir_ / "sim/run.json").find("die_throw.json [frames=2]"),
            std::string::npos);
  // frames.csv: a header and frames 0, 1, 2.
  EXPECT_EQ(split(liedyn::test::read_file(dir_ / "sim/frames.csv"), '\n').size(), 4u);
}

// gradcheck --parameters: the gradient at the γ an optimisation ended at (parameters.csv),
// e.g. where it stalled; the file's rows must be the scene's parameters, in order.
TEST_F(OptimizationCli, GradcheckAtTheParametersOfARun) {
  ASSERT_EQ(run({"optimize", die(), "--out", "die", "--max-iterations", "3"}).exit_code, 3);
  const auto loss_of = [](const std::string& out) {
    std::smatch m;
    EXPECT_TRUE(std::regex_search(out, m, std::regex("(?:^|\n)loss ([0-9.eE+-]+);"))) << out;
    return m.size() == 2 ? std::stod(m[1].str()) : -1.0;
  };
  const Result at_start = run({"gradcheck", die()});
  const Result at_run = run({"gradcheck", die(), "--parameters", "die/parameters.csv", "--verbose"});
  ASSERT_EQ(at_run.exit_code, 0) << at_run.out << at_run.err;
  EXPECT_TRUE(std::regex_match(last_line(at_run.out), kGradcheckLine)) << at_run.out;
  // The loss there is the run's best, not the start's.
  const nlohmann::json checkpoint =
      nlohmann::json::parse(liedyn::test::read_file(dir_ / "die/checkpoint.json"));
  EXPECT_NEAR(loss_of(at_run.out), checkpoint.at("best_loss").get<double>(),
              1e-5 * checkpoint.at("best_loss").get<double>());
  EXPECT_LT(loss_of(at_run.out), 0.9 * loss_of(at_start.out));

  const std::string good = liedyn::test::read_file(dir_ / "die/parameters.csv");
  const std::vector<std::string> rows = split(good, '\n');
  ASSERT_EQ(rows.size(), 7u);
  const auto rejected_with = [&](const std::string& text, const std::string& message) {
    SCOPED_TRACE(message);
    { std::ofstream(dir_ / "bad.csv") << text; }
    const Result r = run({"gradcheck", die(), "--parameters", "bad.csv"});
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("bad.csv: " + message), std::string::npos) << r.err;
  };
  std::string lines;
  for (std::size_t i = 1; i < rows.size(); ++i) lines += rows[i] + "\n";
  rejected_with(lines, "line 1: must be the header \"parameter,value\"");
  rejected_with("parameter,value\n" + rows[2] + "\n", "line 2: expected the parameter bodies[0].angular_velocity[0]");
  rejected_with("parameter,value\n" + rows[1] + "\n", "line 3: missing: the scene has 6 parameters, the file 1");
  rejected_with("parameter,value\nbodies[0].angular_velocity[0],fast\n",
                "line 2: the value of bodies[0].angular_velocity[0] must be a finite number (got \"fast\")");
  rejected_with("parameter,value\nbodies[0].angular_velocity[0],1e999\n", "line 2: the value of");
  rejected_with("parameter,value\nbodies[0].angular_velocity[0],1.5x\n", "line 2: the value of");
  rejected_with(good + "bodies[0].angular_velocity[0],1\n", "line 8: more rows than the scene's 6");
  rejected_with(good + "\n\njunk\n", "line 10: more rows than the scene's 6");
  rejected_with("parameter,value\nbodies[0].angular_velocity[0], 1\n", "line 2: the value of");
  rejected_with("", "is empty");
  rejected_with("\n  \n", "is empty");
  const Result directory = run({"gradcheck", die(), "--parameters", "die"});
  EXPECT_EQ(directory.exit_code, 2);
  EXPECT_NE(directory.err.find("die: cannot open the parameters file"), std::string::npos)
      << directory.err;
  // CRLF line endings, surrounding blanks and blank lines are read as the plain file.
  std::string crlf = "\r\n";
  for (const std::string& row : rows) crlf += "  " + row + " \r\n\r\n";
  { std::ofstream(dir_ / "crlf.csv") << crlf; }
  const Result windows = run({"gradcheck", die(), "--parameters", "crlf.csv"});
  EXPECT_EQ(windows.exit_code, 0) << windows.out << windows.err;
  EXPECT_NEAR(loss_of(windows.out), loss_of(at_run.out), 1e-12 * loss_of(at_run.out));
  const Result missing = run({"gradcheck", die(), "--parameters", "none.csv"});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("none.csv: cannot open the parameters file"), std::string::npos)
      << missing.err;
}

TEST_F(OptimizationCli, GradcheckAtToleranceZeroFails) {
  const Result r = run({"gradcheck", die(), "--tolerance", "0"});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_TRUE(std::regex_match(last_line(r.out), kGradcheckLine)) << r.out;
}

TEST_F(OptimizationCli, GradcheckSampleChecksThatMany) {
  const Result r = run({"gradcheck", die(), "--sample", "3", "--seed", "7"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(std::regex_match(
      last_line(r.out),
      std::regex("^gradcheck: max_rel_error=[0-9.eE+-]+ params=3 tolerance=[0-9.eE+-]+$")))
      << r.out;
}

TEST_F(OptimizationCli, SceneWithoutOptimizationBlockExits2) {
  { std::ofstream(dir_ / "plain.json") << scene_text(""); }
  const Result g = run({"gradcheck", "plain.json"});
  EXPECT_EQ(g.exit_code, 2) << g.out << g.err;
  EXPECT_NE(g.err.find("optimization"), std::string::npos) << g.err;
  EXPECT_NE(g.err.find("plain.json"), std::string::npos) << g.err;
  const Result o = run({"optimize", "plain.json", "--out", "out"});
  EXPECT_EQ(o.exit_code, 2) << o.out << o.err;
  EXPECT_NE(o.err.find("optimization"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));  // bad input: nothing written
}

TEST_F(OptimizationCli, MissingOrBadSceneExits2) {
  const Result g = run({"gradcheck", "no_such_scene.json"});
  EXPECT_EQ(g.exit_code, 2) << g.out << g.err;
  EXPECT_NE(g.err.find("no_such_scene.json"), std::string::npos) << g.err;
  const Result o = run({"optimize", "no_such_scene.json", "--out", "out"});
  EXPECT_EQ(o.exit_code, 2) << o.out << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  // An invalid optimization block: exit 2 with the field.
  {
    std::ofstream(dir_ / "bad.json")
        << scene_text(block(kForceParameter, kEffortTerm, R"(, "max_iterations": 0)"));
  }
  const Result b = run({"optimize", "bad.json", "--out", "out"});
  EXPECT_EQ(b.exit_code, 2) << b.out << b.err;
  EXPECT_NE(b.err.find("bad.json: optimization.max_iterations: "), std::string::npos) << b.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(OptimizationCli, OptimizeTheDieThrowReachesTheTarget) {
  const Result r = run({"optimize", die(), "--out", "die"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const fs::path out = dir_ / "die";
  const History h = checked_history(out);
  ASSERT_FALSE(h.lines.empty());
  EXPECT_GT(h.lines.size(), 1u);
  EXPECT_LE(h.normalized_loss.back(), 1e-4);  // the scene's target_normalized_loss
  EXPECT_LE(h.best_normalized_loss(), 1e-4);

  // parameters.csv: the 6 named parameters of the best γ.
  const std::vector<std::string> lines = split(liedyn::test::read_file(out / "parameters.csv"), '\n');
  ASSERT_EQ(lines.size(), 7u) << liedyn::test::read_file(out / "parameters.csv");
  EXPECT_EQ(lines[0], "parameter,value");
  const std::vector<std::string> names = {
      "bodies[0].angular_velocity[0]", "bodies[0].angular_velocity[1]",
      "bodies[0].angular_velocity[2]", "bodies[0].linear_velocity[0]",
      "bodies[0].linear_velocity[1]",  "bodies[0].linear_velocity[2]"};
  std::vector<double> best;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::vector<std::string> f = split(lines[i + 1], ',');
    ASSERT_EQ(f.size(), 2u) << lines[i + 1];
    EXPECT_EQ(f[0], names[i]);
    best.push_back(std::stod(f[1]));
    EXPECT_TRUE(std::isfinite(best.back()));
  }
  // The best point is not the start ω_0 = (5, −8, 12), v_0 = (0.5, 0, 1).
  EXPECT_GT(std::abs(best[0] - 5) + std::abs(best[1] + 8) + std::abs(best[2] - 12) +
                std::abs(best[5] - 1),
            0.1);

  // The checkpoint holds the same history and the best parameters.
  ASSERT_TRUE(fs::exists(out / "checkpoint.json"));
  const nlohmann::json checkpoint = nlohmann::json::parse(liedyn::test::read_file(out / "checkpoint.json"));
  ASSERT_TRUE(checkpoint.contains("best") && checkpoint.contains("history"));
  EXPECT_EQ(checkpoint.at("history").size(), h.lines.size());
  const std::vector<double> stored = checkpoint.at("best").get<std::vector<double>>();
  ASSERT_EQ(stored.size(), 6u);
  for (std::size_t i = 0; i < 6; ++i)
    EXPECT_NEAR(stored[i], best[i], 1e-12 * (1 + std::abs(best[i])));
  EXPECT_NEAR(checkpoint.at("best_loss").get<double>() / h.loss[0], h.best_normalized_loss(),
              1e-12);

  // trajectory.csv of the optimised throw, and nothing half-written.
  ASSERT_TRUE(fs::exists(out / "trajectory.csv"));
  EXPECT_EQ(split(liedyn::test::read_file(out / "trajectory.csv"), '\n').size(),
            1u + 51u);  // header + frames 0…50
  expect_no_temporaries(out);
}

TEST_F(OptimizationCli, OtherOptimizers) {
  const Result ceres = run({"optimize", die(), "--out", "ceres", "--optimizer", "ceres-lbfgs"});
  EXPECT_EQ(ceres.exit_code, 0) << ceres.out << ceres.err;
  EXPECT_NE(ceres.out.find("ceres-lbfgs"), std::string::npos) << ceres.out;
  ASSERT_TRUE(fs::exists(dir_ / "ceres/history.csv"));
  EXPECT_LE(checked_history(dir_ / "ceres").best_normalized_loss(), 1e-4);
  expect_no_temporaries(dir_ / "ceres");

  // Ipopt may stop short or fail on this problem (a trial step can spin the die faster than
  // π per time step): every documented outcome is legitimate, with its history written.
  const Result ipopt = run({"optimize", die(), "--out", "ipopt", "--optimizer", "ipopt-lbfgs"});
  EXPECT_TRUE(ipopt.exit_code == 0 || ipopt.exit_code == 3 || ipopt.exit_code == 4)
      << ipopt.exit_code << "\n"
      << ipopt.out << ipopt.err;
  EXPECT_NE(ipopt.out.find("ipopt-lbfgs"), std::string::npos) << ipopt.out;
  ASSERT_TRUE(fs::exists(dir_ / "ipopt/history.csv"));
  checked_history(dir_ / "ipopt");
  expect_no_temporaries(dir_ / "ipopt");

  const Result bogus = run({"optimize", die(), "--out", "bogus", "--optimizer", "bogus"});
  EXPECT_EQ(bogus.exit_code, 2) << bogus.out << bogus.err;
  EXPECT_NE(bogus.err.find("--optimizer"), std::string::npos) << bogus.err;
  EXPECT_NE(bogus.err.find("bogus"), std::string::npos) << bogus.err;
  EXPECT_FALSE(fs::exists(dir_ / "bogus"));
}

// The bundled letters (paper Fig. 1, Table 3) end to end: I with every back-end and A with
// NLopt reach the scenes' normalised loss of 1e-3 well within their 100 iterations (measured
// 3–5 and 11 evaluations, README "Differentiable simulation"; the slow letters S and R are
// left to scripts/letters_table.py). The final rod, replayed in trajectory.csv, must lie on
// the letter: the normalised loss is Σ‖x_i − t_i‖² over its initial value.
TEST_F(OptimizationCli, LettersIAndAReachTheTarget) {
  const std::vector<std::pair<char, std::string>> runs = {
      {'I', "nlopt-lbfgs"}, {'I', "ceres-lbfgs"}, {'I', "ipopt-lbfgs"}, {'A', "nlopt-lbfgs"}};
  for (const auto& [letter, optimizer] : runs) {
    SCOPED_TRACE(std::string(1, letter) + " " + optimizer);
    const std::string scene =
        (kSourceDir / "problems/scenes/letters" / (std::string("letter_") + letter + ".json"))
            .string();
    const std::string out = std::string(1, letter) + "-" + optimizer;
    const Result r = run({"optimize", scene, "--out", out, "--optimizer", optimizer});
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    const History h = checked_history(dir_ / out);
    EXPECT_LE(h.best_normalized_loss(), 1e-3);
    EXPECT_LT(h.lines.size(), 50u);  // evaluations; the scenes allow 100 iterations
    EXPECT_GT(h.normalized_loss.front(), 0.999);  // it starts from the straight rod at rest

    // The replayed last frame against the letter's target points.
    const Scene s = load_scene(scene);
    const RodSpec& rod = s.model.rods[0];
    const std::vector<Eigen::Vector3d> target =
        letter_target(letter, 0.5, Eigen::Vector3d::Zero(), rod.node_count());
    double initial = 0.0, final = 0.0;
    for (int i = 0; i < rod.node_count(); ++i) initial += (rod.nodes[i] - target[i]).squaredNorm();
    int rows = 0;
    for (const std::string& line :
         split(liedyn::test::read_file(dir_ / out / "trajectory.csv"), '\n')) {
      const std::vector<std::string> f = split(line, ',');
      if (f.size() < 8 || f[0] != std::to_string(s.frames) || f[3] != "node") continue;
      const int i = std::stoi(f[4]);
      final += (Eigen::Vector3d(std::stod(f[5]), std::stod(f[6]), std::stod(f[7])) - target[i])
                   .squaredNorm();
      ++rows;
    }
    EXPECT_EQ(rows, rod.node_count());
    EXPECT_LE(final / initial, 1e-3 * (1 + 1e-6));
    EXPECT_NEAR(final / initial, h.best_normalized_loss(), 1e-6);
  }
}

// The cable problem (paper Fig. 10) with its cables bounded to pull (tension ≥ 0): NLopt
// reaches the target with no negative tension, and some tensions rest on the bound (without
// it the optimum pushes: half the tensions went negative, down to −53 N). Ceres's L-BFGS
// cannot keep bounds, so asking for it is bad input (exit 2, nothing written).
TEST_F(OptimizationCli, CablesOnlyPull) {
  const std::string scene =
      (kSourceDir / "problems/scenes/optimization/cable_tip_curve.json").string();
  const Result r = run({"optimize", scene, "--out", "cables"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_LE(checked_history(dir_ / "cables").best_normalized_loss(), 1e-3);
  const std::vector<std::string> lines =
      split(liedyn::test::read_file(dir_ / "cables/parameters.csv"), '\n');
  ASSERT_EQ(lines.size(), 1u + 800u);
  int on_bound = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const double tension = std::stod(split(lines[i], ',').at(1));
    EXPECT_GE(tension, 0.0) << lines[i];
    on_bound += tension == 0.0;
  }
  EXPECT_GT(on_bound, 0);

  const Result ceres = run({"optimize", scene, "--out", "ceres", "--optimizer", "ceres-lbfgs"});
  EXPECT_EQ(ceres.exit_code, 2) << ceres.out << ceres.err;
  EXPECT_NE(ceres.err.find("cable_tip_curve.json: --optimizer: the parameters have bounds, and "
                           "ceres-lbfgs cannot respect bounds"),
            std::string::npos)
      << ceres.err;
  EXPECT_FALSE(fs::exists(dir_ / "ceres"));

  // The same with Ceres named in the scene: the error names the scene's field, and an
  // override to NLopt runs.
  nlohmann::json with_ceres = nlohmann::json::parse(liedyn::test::read_file(scene));
  with_ceres["optimization"]["optimizer"] = "ceres-lbfgs";
  with_ceres["optimization"]["max_iterations"] = 2;
  { std::ofstream(dir_ / "ceres.json") << with_ceres.dump(); }
  const Result named = run({"optimize", "ceres.json", "--out", "named"});
  EXPECT_EQ(named.exit_code, 2) << named.out << named.err;
  EXPECT_NE(named.err.find("ceres.json: optimization.optimizer: the parameters have bounds"),
            std::string::npos)
      << named.err;
  EXPECT_FALSE(fs::exists(dir_ / "named"));
  const Result overridden =
      run({"optimize", "ceres.json", "--out", "overridden", "--optimizer", "nlopt-lbfgs"});
  EXPECT_EQ(overridden.exit_code, 3) << overridden.out << overridden.err;  // 2 iterations: short
}

// --resume from a checkpoint whose best point lies outside bounds added to the scene since:
// bad input naming the checkpoint and the entry (exit 2), nothing changed.
TEST_F(OptimizationCli, ResumeOfAnEditedSceneExits2) {
  // Bounds added to the scene make it another problem: its checkpoint is refused.
  ASSERT_EQ(run({"optimize", die(), "--out", "die", "--max-iterations", "2"}).exit_code, 3);
  const std::string before = liedyn::test::read_file(dir_ / "die/history.csv");
  nlohmann::json bounded = nlohmann::json::parse(liedyn::test::read_file(die()));
  bounded["optimization"]["parameters"][1]["lower"] = -10;
  bounded["optimization"]["parameters"][1]["upper"] = 1.0;
  { std::ofstream(dir_ / "bounded.json") << bounded.dump(); }
  const Result r = run({"optimize", "bounded.json", "--out", "die", "--resume"});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("checkpoint.json: problem.scene: is \""), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the checkpoint belongs to another problem (the scene's content differs)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(liedyn::test::read_file(dir_ / "die/history.csv"), before);
  // A longer run of the same scene is the same problem.
  const Result longer = run({"optimize", die(), "--out", "die", "--resume", "--max-iterations", "3"});
  EXPECT_NE(longer.exit_code, 2) << longer.out << longer.err;
}

TEST_F(OptimizationCli, ResumeFromACheckpointOfAnotherProblemExits2) {
  // Letter I's checkpoint copied into letter A's folder used to resume and report I's loss.
  const fs::path letters = kSourceDir / "problems/scenes/letters";
  ASSERT_EQ(run({"optimize", (letters / "letter_I.json").string(), "--out", "I", "--max-iterations", "2"}).exit_code, 3);
  ASSERT_EQ(run({"optimize", (letters / "letter_A.json").string(), "--out", "A", "--max-iterations", "2"}).exit_code, 3);
  fs::copy_file(dir_ / "I/checkpoint.json", dir_ / "A/checkpoint.json",
                fs::copy_options::overwrite_existing);
  const Result r = run({"optimize", (letters / "letter_A.json").string(), "--out", "A", "--resume"});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("problem.scene"), std::string::npos) << r.err;
  // Another optimiser is another problem too.
  const Result other = run({"optimize", die(), "--out", "die", "--max-iterations", "2"});
  ASSERT_EQ(other.exit_code, 3) << other.err;
  const Result switched = run({"optimize", die(), "--out", "die", "--resume", "--optimizer", "ipopt-lbfgs"});
  EXPECT_EQ(switched.exit_code, 2) << switched.out << switched.err;
  EXPECT_NE(switched.err.find("problem.optimizer: is \"nlopt-lbfgs\", this run's \"ipopt-lbfgs\""),
            std::string::npos)
      << switched.err;
}

TEST_F(OptimizationCli, ResumeChecksTheStoredNumbers) {
  ASSERT_EQ(run({"optimize", die(), "--out", "die", "--max-iterations", "2"}).exit_code, 3);
  const nlohmann::json good = nlohmann::json::parse(liedyn::test::read_file(dir_ / "die/checkpoint.json"));
  const auto resume_with = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json c = good;
    edit(c);
    std::ofstream(dir_ / "die/checkpoint.json") << c.dump();
    return run({"optimize", die(), "--out", "die", "--resume"});
  };
  // best_loss -5 used to exit 0 with "target reached".
  Result r = resume_with([](nlohmann::json& c) { c["best_loss"] = -5; });
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("checkpoint.json: best_loss: is -5, but the loss at the checkpoint's best point is"),
            std::string::npos)
      << r.err;
  r = resume_with([](nlohmann::json& c) { c["best"][5] = c["best"][5].get<double>() + 0.1; });
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("best_loss"), std::string::npos) << r.err;
  r = resume_with([](nlohmann::json& c) { c["loss_scale"] = 0; });
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("loss_scale: must be a finite number > 0"), std::string::npos) << r.err;
  r = resume_with([](nlohmann::json& c) { c.erase("problem"); });
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("problem: is missing"), std::string::npos) << r.err;
  // The untouched checkpoint resumes.
  r = resume_with([](nlohmann::json&) {});
  EXPECT_NE(r.exit_code, 2) << r.out << r.err;
}

TEST_F(OptimizationCli, ResumeOutsideNewBoundsExits2) {
  // A checkpoint whose best point was moved outside the scene's bounds.
  nlohmann::json bounded = nlohmann::json::parse(liedyn::test::read_file(die()));
  bounded["optimization"]["parameters"][1]["lower"] = -10;
  bounded["optimization"]["parameters"][1]["upper"] = 10.0;
  { std::ofstream(dir_ / "bounded.json") << bounded.dump(); }
  ASSERT_EQ(run({"optimize", "bounded.json", "--out", "die", "--max-iterations", "2"}).exit_code, 3);
  nlohmann::json checkpoint =
      nlohmann::json::parse(liedyn::test::read_file(dir_ / "die/checkpoint.json"));
  checkpoint["best"][5] = 11.0;  // bodies[0].linear_velocity[2]
  { std::ofstream(dir_ / "die/checkpoint.json") << checkpoint.dump(); }
  const std::string before = liedyn::test::read_file(dir_ / "die/history.csv");
  const Result r = run({"optimize", "bounded.json", "--out", "die", "--resume"});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("checkpoint.json: best: the value "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("of bodies[0].linear_velocity[2] is above its upper bound (10) in the scene"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(liedyn::test::read_file(dir_ / "die/history.csv"), before);
}

TEST_F(OptimizationCli, ResumeContinuesTheHistory) {
  const Result first = run({"optimize", die(), "--out", "die", "--max-iterations", "3"});
  ASSERT_EQ(first.exit_code, 3) << first.out << first.err;  // stopped short of the target
  const History before = checked_history(dir_ / "die");
  ASSERT_FALSE(before.lines.empty());
  EXPECT_LE(before.lines.size(), 3u);  // NLopt: an iteration is an evaluation
  EXPECT_GT(before.best_normalized_loss(), 1e-4);

  const Result second = run({"optimize", die(), "--out", "die", "--resume"});
  ASSERT_EQ(second.exit_code, 0) << second.out << second.err;
  const History after = checked_history(dir_ / "die");  // iterations keep increasing by 1
  ASSERT_GT(after.lines.size(), before.lines.size());
  for (std::size_t i = 0; i < before.lines.size(); ++i) {
    EXPECT_EQ(after.lines[i], before.lines[i]) << "row " << i << " changed on resume";
  }
  EXPECT_EQ(after.iteration[before.lines.size()], before.iteration.back() + 1);
  EXPECT_LE(after.best_normalized_loss(), 1e-4);
  // The resumed run starts from the best point so far: its first loss is the best before.
  EXPECT_LE(after.normalized_loss[before.lines.size()], before.best_normalized_loss() * (1 + 1e-9));
  const nlohmann::json checkpoint = nlohmann::json::parse(liedyn::test::read_file(dir_ / "die/checkpoint.json"));
  EXPECT_EQ(checkpoint.at("history").size(), after.lines.size());
  expect_no_temporaries(dir_ / "die");
}

// A resumed Ipopt run used to start from scratch at the best point (its adaptive barrier
// pulled the iterate off the bounds): on the bounded cable problem, interrupted after 8
// iterations, --resume took 6377 evaluations (6048 infeasible trial points) and missed the
// target, against 16 for the whole uninterrupted run. It now continues (a warm start,
// solvers/optimizer.hpp): at most twice the evaluations the uninterrupted run had left.
TEST_F(OptimizationCli, IpoptResumeCostsAtMostTwiceWhatWasLeft) {
  const std::string scene =
      (kSourceDir / "problems/scenes/optimization/cable_tip_curve.json").string();
  const Result whole = run({"optimize", scene, "--out", "whole", "--optimizer", "ipopt-lbfgs"});
  ASSERT_EQ(whole.exit_code, 0) << whole.out << whole.err;
  const std::size_t uninterrupted = read_history(dir_ / "whole/history.csv").lines.size();

  const Result first = run({"optimize", scene, "--out", "cut", "--optimizer", "ipopt-lbfgs",
                            "--max-iterations", "8"});
  ASSERT_EQ(first.exit_code, 3) << first.out << first.err;
  const std::size_t before = read_history(dir_ / "cut/history.csv").lines.size();
  ASSERT_LT(before, uninterrupted);
  const Result resumed = run({"optimize", scene, "--out", "cut", "--optimizer", "ipopt-lbfgs", "--resume"});
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out << resumed.err;
  const History after = read_history(dir_ / "cut/history.csv");
  // (Ipopt's first evaluation is not at γ₀ but pushed into the box: no checked_history.)
  EXPECT_LE(after.best_normalized_loss(), 1e-3);
  EXPECT_LE(after.lines.size() - before, 2 * (uninterrupted - before))
      << uninterrupted << " evaluations uninterrupted, " << before << " before the cut";
}

TEST_F(OptimizationCli, ResumeWithoutACheckpointFails) {
  const Result r = run({"optimize", die(), "--out", "empty", "--resume"});
  EXPECT_NE(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.err.find("checkpoint.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "empty/history.csv"));
}

}  // namespace
}  // namespace liedyn::optimization_tests

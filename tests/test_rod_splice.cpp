// A splice (joints of type "splice", lib/incremental_potential.cpp's add_joint_terms): two
// rods joined end to end are one rod. Its parts are the exact point joint (the last node of
// a's rod on the first of b's) and the rod's own bending and twist term across the junction,
// so that with the lumped masses summing at the junction (half an edge from each side) the
// pair has the single rod's energy and inertia term for term. Checked against one rod of
// the same total length, mass and stiffness, node for node:
//  * a clamped cantilever under gravity and a tip load in static equilibrium;
//  * the same cantilever swinging (dynamic mode), every frame;
//  * a free rod spinning and bending in free flight (no clamp, both halves free);
// and the bad inputs, each naming its field.
// Agreement: the step tolerance 1e-10 bounds each solve's error; as for the clamp of
// tests/test_rod_joints.cpp, the cantilever's softest mode turns it into ≲ 1e-8 m at the
// tip, and the splice's exact joint holds to 1e-10 m. 1e-7 m bounds both; without the
// junction's bending term (a plain ball joint) the rod differs by centimetres.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "lib/so3.hpp"

#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::rod_splice_tests {
namespace {

constexpr double kAgreement = 1e-7;

// A rod along x from x0 to x1 with `edges` edges and mass ∝ length (0.05 kg for 0.6 m).
std::string rod(const std::string& name, double x0, double x1, int edges, const std::string& extra) {
  return R"({ "name": ")" + name + R"(", "shape": { "type": "line", "start": [)" + std::to_string(x0) +
         R"(, 0, 0], "end": [)" + std::to_string(x1) + R"(, 0, 0], "edges": )" + std::to_string(edges) +
         R"( }, "mass": )" + std::to_string(0.05 * (x1 - x0) / 0.6) + R"(, "radius": 0.005,
      "stretch_stiffness": 1000, "shear_stiffness": 1000, "bending_stiffness": [0.005, 0.004, 0.003] )" +
         extra + " }";
}

std::string scene(const std::string& mode, const std::string& rods, const std::string& rest = "") {
  return R"({ "mode": ")" + mode + R"(", "time_step": 0.005, "frames": 40, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-10, "max_iterations": 200 }, "rods": [ )" + rods + " ]" + rest + " }";
}

// The nodes and edge frames of a run's last state, every step converged and the splice held.
struct Shape {
  std::vector<Vector3> nodes;
  std::vector<Matrix3> frames;
};

Shape run(const std::string& text, std::vector<Shape>* every = nullptr) {
  const Scene s = parse_scene(text, "splice.json");
  Simulator sim(s.model, s.solver);
  for (int k = 1; k <= s.frames; ++k) {
    const StepReport r = sim.step();
    EXPECT_TRUE(r.converged()) << "frame " << k << ": " << r.message;
    EXPECT_LE(r.constraint_violation, s.solver.tolerance) << k;
    if (every != nullptr) every->push_back({sim.state().points, sim.state().rotations});
  }
  return {sim.state().points, sim.state().rotations};
}

// The spliced pair's nodes in the single rod's order: a's 0…6, then b's 1…6 (b's node 0 is
// a's node 6); its edges a's 0…5 then b's 0…5 — the state's own order, less b's node 0.
double largest_difference(const Shape& one, const Shape& two) {
  double d = 0.0;
  for (int i = 0; i <= 12; ++i) {
    const int j = i <= 6 ? i : i + 1;
    d = std::max(d, (one.nodes[i] - two.nodes[j]).norm());
  }
  for (int e = 0; e < 12; ++e) d = std::max(d, so3::distance(one.frames[e], two.frames[e]) * 0.6);
  return d;
}

const std::string kTip = R"(, "node_forces": [ { "node": 6, "force": [0, 0.05, -0.2] } ])";
const std::string kTipOfOne = R"(, "node_forces": [ { "node": 12, "force": [0, 0.05, -0.2] } ])";
const std::string kClamp = R"(, "fixed_nodes": [0], "fixed_edges": [0])";
const std::string kSplice = R"(, "joints": [ { "type": "splice", "a": { "rod": "a", "node": 6 }, "b": { "rod": "b", "node": 0 } } ])";

TEST(RodSplice, TwoRodsSplicedEndToEndAreOneCantileverInStaticEquilibrium) {
  const Shape one = run(scene("static", rod("r", 0, 0.6, 12, kClamp + kTipOfOne)));
  const Shape two = run(scene("static", rod("a", 0, 0.3, 6, kClamp) + ", " + rod("b", 0.3, 0.6, 6, kTip), kSplice));
  EXPECT_GT(-one.nodes[12].z(), 0.05);  // a large deflection, not a rod at rest
  EXPECT_LT(largest_difference(one, two), kAgreement);
}

TEST(RodSplice, TwoRodsSplicedEndToEndSwingAsOneRodFrameByFrame) {
  std::vector<Shape> one, two;
  run(scene("dynamic", rod("r", 0, 0.6, 12, kClamp + kTipOfOne)), &one);
  run(scene("dynamic", rod("a", 0, 0.3, 6, kClamp) + ", " + rod("b", 0.3, 0.6, 6, kTip), kSplice), &two);
  ASSERT_EQ(one.size(), two.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < one.size(); ++k) worst = std::max(worst, largest_difference(one[k], two[k]));
  EXPECT_LT(worst, kAgreement);
  EXPECT_GT(-one.back().nodes[12].z(), 1e-2);
  // A ball joint in place of the splice is a free joint in the middle of the cantilever (in
  // static mode b would have no equilibrium to converge to: it spins freely about its axis).
  std::string ball = kSplice;
  ball.replace(ball.find("splice"), 6, "ball");
  std::vector<Shape> loose;
  run(scene("dynamic", rod("a", 0, 0.3, 6, kClamp) + ", " + rod("b", 0.3, 0.6, 6, kTip), ball), &loose);
  EXPECT_GT(largest_difference(one.back(), loose.back()), 1e-2);
}

// No clamp, no gravity: thrown spinning, both halves free, the splice's joint force and
// bending internal to the pair.
TEST(RodSplice, AFreeSplicedRodFliesAsOneRod) {
  const std::string spin = R"(, "node_velocities": [)";
  // Node velocities of a spin about z through the middle plus a bend: v_i = ω × (x_i − c) + w_i.
  const auto velocities = [](double x0, int nodes) {
    std::string v;
    for (int i = 0; i < nodes; ++i) {
      const double x = x0 + 0.05 * i - 0.3;
      v += (i ? ", " : "") + std::string("[0, ") + std::to_string(2.0 * x) + ", " + std::to_string(0.5 * x * x) + "]";
    }
    return v + "]";
  };
  auto free_scene = [&](const std::string& rods, const std::string& rest) {
    std::string s = scene("dynamic", rods, rest);
    s.replace(s.find(R"("gravity": [0, 0, -9.81])"), 24, R"("gravity": [0, 0, 0])");
    return s;
  };
  std::vector<Shape> one, two;
  run(free_scene(rod("r", 0, 0.6, 12, spin + velocities(0, 13)), ""), &one);
  run(free_scene(rod("a", 0, 0.3, 6, spin + velocities(0, 7)) + ", " + rod("b", 0.3, 0.6, 6, spin + velocities(0.3, 7)),
                 kSplice),
      &two);
  double worst = 0.0;
  for (std::size_t k = 0; k < one.size(); ++k) worst = std::max(worst, largest_difference(one[k], two[k]));
  EXPECT_LT(worst, kAgreement);
  EXPECT_GT((one.back().nodes[0] - Vector3(0, 0, 0)).norm(), 1e-2);  // it moved
}

// The corner rod of the angle tests: nodes `first` … `last` of one rod of 12 edges, 6 along x
// and 6 turned 40° about z and rising; an isotropic section (K₁ = K₂).
std::string bent(const std::string& name, int first, int last, const std::string& extra) {
  std::string nodes = R"("nodes": [)";
  for (int i = first; i <= last; ++i) {
    const Vector3 x = i <= 6 ? Vector3(0.05 * i, 0, 0)
                             : Vector3(0.3, 0, 0) + 0.05 * (i - 6) * Vector3(std::cos(0.7), std::sin(0.7), 0.2).normalized();
    nodes += (i > first ? ", [" : "[") + std::to_string(x.x()) + ", " + std::to_string(x.y()) + ", " + std::to_string(x.z()) + "]";
  }
  return R"({ "name": ")" + name + R"(", )" + nodes + R"(], "mass": )" + std::to_string(0.05 * (last - first) / 12.0) +
         R"(, "radius": 0.005,
      "stretch_stiffness": 1000, "shear_stiffness": 1000, "bending_stiffness": [0.005, 0.005, 0.003] )" +
         extra + " }";
}
const std::string kTipOfB = R"(, "node_forces": [ { "node": 6, "force": [0, 0.05, -0.2] } ])";

// The twist T between b's first frame and the one rod's frame there (see the angle test).
Matrix3 junction_twist(const std::string& one_text, const std::string& two_text) {
  const Scene two = parse_scene(two_text, "s.json");
  const Scene one = parse_scene(one_text, "r.json");
  return two.model.initial_state().rotations[6].transpose() * one.model.initial_state().rotations[6];
}

// The largest difference over every frame, b's frames compared times T.
double largest_difference(const std::vector<Shape>& one, std::vector<Shape> two, const Matrix3& T) {
  double worst = 0.0;
  for (std::size_t k = 0; k < one.size(); ++k) {
    for (int e = 6; e < 12; ++e) two[k].frames[e] = two[k].frames[e] * T;
    worst = std::max(worst, largest_difference(one[k], two[k]));
  }
  return worst;
}

// Two rods meeting at an angle (b turned 40° about z from a, and its end rising): one rod
// would carry a's last frame across the corner by parallel transport, b's own first frame is
// its own transport from the z axis, and the two differ by a twist T about b's first edge.
// The junction's term sees b's frame times T, so the pair is the bent single rod — with an
// isotropic section (K₁ = K₂: b's own terms do not see the twist; with K₁ ≠ K₂ b's
// cross-section is its own, turned by T from one rod's). b's frames are compared times T.
TEST(RodSplice, TwoRodsMeetingAtAnAngleAreOneBentRod) {
  for (const char* mode : {"static", "dynamic"}) {
    SCOPED_TRACE(mode);
    const std::string one_text = scene(mode, bent("r", 0, 12, kClamp + kTipOfOne));
    const std::string two_text = scene(mode, bent("a", 0, 6, kClamp) + ", " + bent("b", 6, 12, kTipOfB), kSplice);
    std::vector<Shape> one, two;
    run(one_text, &one);
    run(two_text, &two);
    const Matrix3 T = junction_twist(one_text, two_text);
    EXPECT_GT(so3::distance(T, Matrix3::Identity()), 0.05);  // the frames differ: a twist
    EXPECT_LT(largest_difference(one, two, T), kAgreement);
    const Scene start_one = parse_scene(one_text, "r.json");
    EXPECT_GT((one.back().nodes[12] - start_one.model.initial_state().points[12]).norm(), 1e-2);
  }
}

// With internal damping (lib/rod_damping.hpp) on both rods, the junction is damped as an
// interior node (the rods' mean η, b's frame times T): the pair is the one damped rod, straight
// and at an angle (η₁ = η₂: as for K, b's own terms see its own cross-section). Without the
// junction's damping term the two differ by 4.9 and 6.9 cm.
TEST(RodSplice, DampedRodsSplicedAreOneDampedRod) {
  const std::string eta = R"(, "bending_damping": [1e-3, 1e-3, 6e-4], "stretch_damping": 0.2)";
  const std::string straight_one = scene("dynamic", rod("r", 0, 0.6, 12, kClamp + kTipOfOne + eta));
  const std::string straight_two =
      scene("dynamic", rod("a", 0, 0.3, 6, kClamp + eta) + ", " + rod("b", 0.3, 0.6, 6, kTip + eta), kSplice);
  const std::string corner_one = scene("dynamic", bent("r", 0, 12, kClamp + kTipOfOne + eta));
  const std::string corner_two =
      scene("dynamic", bent("a", 0, 6, kClamp + eta) + ", " + bent("b", 6, 12, kTipOfB + eta), kSplice);
  for (const auto& [one_text, two_text] : {std::pair{straight_one, straight_two}, std::pair{corner_one, corner_two}}) {
    SCOPED_TRACE(one_text == straight_one ? "straight" : "at an angle");
    std::vector<Shape> one, two, undamped;
    run(one_text, &one);
    run(two_text, &two);
    const Matrix3 T = junction_twist(one_text, two_text);
    EXPECT_LT(largest_difference(one, two, T), kAgreement);
    // The damping changes the motion by far more than the agreement: the one rod's tip with
    // and without it.
    std::string plain = one_text;
    plain.replace(plain.find(eta), eta.size(), "");
    run(plain, &undamped);
    ASSERT_EQ(undamped.size(), one.size());
    double change = 0.0;
    for (std::size_t k = 0; k < one.size(); ++k) {
      change = std::max(change, (one[k].nodes[12] - undamped[k].nodes[12]).norm());
    }
    EXPECT_GT(change, 1e3 * kAgreement);
  }
}

TEST(RodSplice, BadSplicesNameTheirField) {
  const auto error = [](const std::string& joint, const std::string& optimization = "") {
    try {
      parse_scene(scene("dynamic", rod("a", 0, 0.3, 6, "") + ", " + rod("b", 0.3, 0.6, 6, ""),
                        R"(, "bodies": [ { "name": "body", "mass": 1, "inertia": [1, 1, 1] } ], "joints": [ )" + joint + " ]" +
                            optimization),
                  "bad.json");
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(R"({ "type": "splice", "a": { "rod": "a", "node": 6 }, "b": { "rod": "b", "node": 0 } })"), "accepted");
  EXPECT_EQ(error(R"({ "type": "splice", "a": { "rod": "a", "node": 5 }, "b": { "rod": "b", "node": 0 } })")
                .rfind("joints[0].a.node: must be the last node of a rod (6 for rod \"a\")", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "splice", "a": { "rod": "a", "node": 6 }, "b": { "rod": "b", "node": 6 } })")
                .rfind("joints[0].b.node: must be the first node of a rod (0 for rod \"b\")", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "splice", "a": { "body": "body" }, "b": { "rod": "b", "node": 0 } })")
                .rfind("joints[0].a: a splice joins the last node of one rod (a) to the first node of another (b)", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "splice", "a": { "rod": "a", "edge": 5 }, "b": { "rod": "b", "node": 0 } })")
                .rfind("joints[0].a: a splice joins", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "splice", "a": { "rod": "a", "node": 6 } })").rfind("joints[0].b: a splice joins", 0), 0u);
  EXPECT_EQ(error(R"({ "type": "splice", "compliance_rotation": 1, "a": { "rod": "a", "node": 6 }, "b": { "rod": "b", "node": 0 } })")
                .rfind("joints[0].compliance_rotation: a splice bends and twists as the rods do", 0),
            0u);
  EXPECT_EQ(error(R"({ "type": "splice", "a": { "rod": "a", "node": 6 }, "b": { "rod": "b", "node": 0 }, "limits": [-1, 1] })")
                .rfind("joints[0].limits: only a hinge", 0),
            0u);
  EXPECT_NE(error(R"({ "type": "splice", "a": { "rod": "a", "node": 6 }, "b": { "rod": "b", "node": 0 } })",
                  R"(, "optimization": { "parameters": [ { "kind": "bending_stiffness", "rod": "b" } ],
                       "objective": [ { "term": "point_targets", "rod": "b", "frame": -1, "polyline": [[0, 0, 0], [1, 0, 0]] } ] })")
                .find("is spliced (joints[0])"),
            std::string::npos);
}

}  // namespace
}  // namespace liedyn::rod_splice_tests

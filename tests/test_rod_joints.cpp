// Joints that hold rods by their nodes and edges (lib/model.hpp JointEnd): an exact weld of a
// rod edge is a clamp, a rod welded at both ends to two bodies carries them as the clamped
// rod carries loads, joint forces between rods and bodies are internal (momentum), the
// back-ends agree, and bad rod ends are refused naming their field.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "lib/rod.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

// A 0.6 m rod of 12 edges along x from the origin, in a scene of `mode` ("static" or
// "dynamic") with the step tolerance 1e-10; `rod_extra` and `rest` are spliced into the rod
// and after it.
std::string rod_scene(const std::string& mode, const std::string& rod_extra, const std::string& rest,
                      const std::string& gravity = "[0, 0, -9.81]") {
  return R"({ "mode": ")" + mode + R"(", "time_step": 0.005, "frames": 40, "gravity": )" + gravity + R"(,
    "solver": { "tolerance": 1e-10, "max_iterations": 100 },
    "rods": [ { "name": "r", "shape": { "type": "line", "start": [0, 0, 0], "end": [0.6, 0, 0], "edges": 12 },
                "mass": 0.05, "radius": 0.005, "stretch_stiffness": 1000, "shear_stiffness": 1000,
                "bending_stiffness": [0.005, 0.005, 0.004] )" +
         rod_extra + " } ]" + rest + " }";
}

// The final state of a scene run to its last frame; every step must converge, and exact
// joints must hold to the tolerance.
State run_to_end(const std::string& text, double* violation = nullptr) {
  const Scene scene = parse_scene(text, "rod_joints.json");
  Simulator sim(scene.model, scene.solver);
  double worst = 0.0;
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport report = sim.step();
    EXPECT_TRUE(report.converged()) << "frame " << k << ": " << report.message;
    if (!report.converged()) break;
    worst = std::max(worst, report.constraint_violation);
  }
  if (violation != nullptr) *violation = worst;
  return sim.state();
}

double largest_difference(const State& a, const State& b, int first_point, int points) {
  double d = 0.0;
  for (int i = 0; i < points; ++i) d = std::max(d, (a.points[first_point + i] - b.points[first_point + i]).norm());
  return d;
}

// The step tolerance 1e-10 bounds the gradient; the cantilever's softest mode (bending,
// K/L ≈ 0.004/0.6 N·m) turns that into an error ~1e-10/(K/L²) ≈ 1e-8 m at the tip, and the
// exact weld's violation (≤ 1e-10 m and rad) moves the tip by less than 1e-9 m. 1e-7 m bounds
// both; a joint that let the edge turn (a ball joint in place of the weld) sags the tip by
// 0.18 m more. A weld holds the whole frame, so any point of the edge clamps it alike (the
// midpoint, by default, too).
constexpr double kClampAgreement = 1e-7;

TEST(RodJoints, AnExactWeldOfTheFirstEdgeToTheWorldIsAClamp) {
  for (const std::string mode : {"static", "dynamic"}) {
    SCOPED_TRACE(mode);
    const State clamped = run_to_end(rod_scene(mode, R"(, "fixed_nodes": [0], "fixed_edges": [0])", ""));
    double violation = 0.0;
    const State welded = run_to_end(
        rod_scene(mode, "", R"(, "joints": [ { "type": "weld", "a": { "rod": "r", "edge": 0 } } ])"),
        &violation);
    EXPECT_LE(violation, 1e-10);
    const double tip_sag = -welded.points.back().z();
    EXPECT_GT(tip_sag, 1e-3);  // the load is felt: the comparison is not between two rods at rest
    EXPECT_LT(largest_difference(clamped, welded, 0, 13), kClampAgreement);
  }
}

// The rod held at both ends by exact welds: its first edge to the world (a clamp, lib/rod.hpp),
// its last edge (at node 11) to a 20 g body centred on node 11. In static mode that body only
// weighs on node 11, rigidly attached to edge 11, so the rod equals the clamped rod with a
// node force m g at node 11. Gravity 1 m/s²: the clamp then carries 0.026 N·m, kinks of
// 0.2 rad at the hinges next to it; under 9.81 m/s² the rod would fold at them (kinks near
// π/2, past which a hinge's moment K sin φ cos φ/w falls), far outside what 12 edges resolve.
TEST(RodJoints, ARodWeldedToTheWorldAndToABodyCarriesItAsAClampedRodCarriesALoad) {
  const std::string bodies = R"(,
    "bodies": [ { "name": "tip", "mass": 0.02, "inertia": [1e-5, 1e-5, 1e-5], "position": [0.55, 0, 0] } ],
    "joints": [ { "type": "weld", "a": { "rod": "r", "edge": 0, "point": [0, 0, 0] } },
                { "type": "weld", "a": { "rod": "r", "edge": 11, "point": [0, 0, 0] }, "b": { "body": "tip" } } ])";
  double violation = 0.0;
  const State welded = run_to_end(rod_scene("static", "", bodies, "[0, 0, -1]"), &violation);
  EXPECT_LE(violation, 1e-10);
  const State clamped = run_to_end(rod_scene(
      "static", R"(, "fixed_nodes": [0], "fixed_edges": [0], "node_forces": [ { "node": 11, "force": [0, 0, -0.02] } ])", "",
      "[0, 0, -1]"));
  // The state's points: the body, then the rod's nodes.
  EXPECT_GT(-welded.points[1 + 12].z(), 1e-3);
  double d = 0.0;
  for (int i = 0; i < 13; ++i) d = std::max(d, (clamped.points[i] - welded.points[1 + i]).norm());
  EXPECT_LT(d, kClampAgreement);
  // The tip body turns with the last edge it is welded to: R_tip R_edge⁻¹ keeps its initial
  // value (the body starts unturned, the edge in its parallel-transported frame).
  const Matrix3 edge0 = parallel_transport_frames(parse_scene(rod_scene("dynamic", "", ""), "r.json").model.rods[0].nodes)[11];
  EXPECT_LT((welded.rotations[0] * welded.rotations[1 + 11].transpose() - edge0.transpose()).norm(), 1e-9);
}

// The same rod free in space between two spinning bodies, welded to the first edge of one and
// the last edge of the other (at node 12), one end elastic: joint forces are internal, so the
// total momentum Σ m v stays what the bodies started with. Each step's gradient norm ‖g‖ ≤
// 1e-10 (N/m·s² ⋅ m: a force) changes it by at most h √(blocks) ‖g‖ ≈ 2e-12 N·s; over 200
// steps the bound is 1e-9 of the initial 0.07 N·s.
TEST(RodJoints, ForcesBetweenARodAndTheBodiesWeldedToItAreInternal) {
  const std::string bodies = R"(,
    "bodies": [ { "name": "left", "mass": 0.1, "inertia": [1e-4, 2e-4, 3e-4], "position": [-0.05, 0, 0],
                  "linear_velocity": [0, 0.3, 0.1], "angular_velocity": [2, 0, 1] },
                { "name": "right", "mass": 0.2, "inertia": [2e-4, 2e-4, 1e-4], "position": [0.65, 0, 0],
                  "linear_velocity": [0.1, 0.2, -0.3], "angular_velocity": [0, -3, 0] } ],
    "joints": [ { "type": "weld", "a": { "rod": "r", "edge": 0, "point": [0, 0, 0] }, "b": { "body": "left" } },
                { "type": "hinge", "compliance": 1e-5, "a": { "rod": "r", "edge": 11, "point": [0, 0, 0.05], "axis": [1, 0, 0] },
                  "b": { "body": "right" } } ])";
  std::string text = rod_scene("dynamic", "", bodies, "[0, 0, 0]");
  text.replace(text.find(R"("frames": 40)"), 12, R"("frames": 200)");
  const Scene scene = parse_scene(text, "free.json");
  const RodDiscretization rod = discretize(scene.model.rods[0]);
  Simulator sim(scene.model, scene.solver);
  const double h = scene.model.time_step;
  const Vector3 initial = 0.1 * Vector3(0, 0.3, 0.1) + 0.2 * Vector3(0.1, 0.2, -0.3);
  double drift = 0.0;
  State before = sim.state();
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport report = sim.step();
    ASSERT_TRUE(report.converged()) << "frame " << k << ": " << report.message;
    EXPECT_LE(report.constraint_violation, 1e-10) << "frame " << k;
    const State& q = sim.state();
    Vector3 momentum = (0.1 * (q.points[0] - before.points[0]) + 0.2 * (q.points[1] - before.points[1])) / h;
    for (int i = 0; i < 13; ++i) momentum += rod.node_mass[i] * (q.points[2 + i] - before.points[2 + i]) / h;
    drift = std::max(drift, (momentum - initial).norm());
    before = q;
  }
  EXPECT_LT(drift, 1e-9 * initial.norm());
  // The rod was carried and bent: its middle left the line it started on.
  EXPECT_GT(std::hypot(before.points[2 + 6].y(), before.points[2 + 6].z()), 1e-2);
}

// The three back-ends follow the same trajectory through rod-edge and rod-node joints.
TEST(RodJoints, BackEndsAgreeThroughRodEdgeAndRodNodeJoints) {
  const std::string bodies = R"(,
    "bodies": [ { "name": "arm", "mass": 0.3, "inertia": [1e-3, 1e-3, 5e-4], "position": [-0.1, 0, 0] } ],
    "joints": [ { "type": "hinge", "a": { "body": "arm", "point": [-0.1, 0, 0], "axis": [0, 1, 0] } },
                { "type": "weld", "a": { "rod": "r", "edge": 0 }, "b": { "body": "arm" } },
                { "type": "ball", "compliance": 1e-4, "a": { "rod": "r", "node": 12 }, "b": { "world": [0.6, 0, 0.05] } } ])";
  const Scene scene = parse_scene(rod_scene("dynamic", "", bodies), "arm.json");
  const auto run = [&](Backend backend) {
    SolverOptions o = scene.solver;
    o.backend = backend;
    Simulator s(scene.model, o);
    // Ceres stalls within a few times the tolerance on stiff exact joints (its trust region
    // stops on relative decrease): its steps must update the state, not all converge.
    for (int k = 1; k <= 30; ++k) EXPECT_TRUE(s.step().state_updated()) << to_string(backend) << " frame " << k;
    return s.state();
  };
  const State newton = run(Backend::kNewton);
  EXPECT_GT((newton.points[0] - scene.model.bodies[0].position).norm(), 1e-4);  // the arm swung
  for (const Backend b : {Backend::kCeres, Backend::kIpopt}) {
    const State q = run(b);
    EXPECT_LT(largest_difference(newton, q, 0, static_cast<int>(q.points.size())), 1e-6) << to_string(b);
  }
}

// Each offending field is named.
TEST(RodJoints, BadRodEndsNameTheirField) {
  const auto error = [](const std::string& joints, const std::string& rod_extra = "") {
    try {
      parse_scene(rod_scene("dynamic", rod_extra,
                            R"(, "bodies": [ { "name": "b", "mass": 1, "inertia": [1, 1, 1] } ], "joints": [ )" + joints + " ]"),
                  "bad.json");
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  const auto starts = [](const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; };
  EXPECT_TRUE(starts(error(R"({ "type": "weld", "a": { "rod": "r", "edge": 12 } })"), "joints[0].a.edge:")) << error(R"({ "type": "weld", "a": { "rod": "r", "edge": 12 } })");
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "rod": "r", "node": 13 } })"), "joints[0].a.node:"));
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "rod": "r" } })"),
                     "joints[0].a.node: give one of \"node\" (a position) or \"edge\" (a frame)"));
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "rod": "r", "node": 1, "edge": 1 } })"), "joints[0].a.node: give one of"));
  EXPECT_TRUE(starts(error(R"({ "type": "hinge", "a": { "body": "b", "axis": [0, 0, 1] }, "b": { "rod": "r", "node": 3 } })"),
                     "joints[0].b.node: a rod node has a position only: only a ball joint can hold it"));
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "rod": "r", "node": 3, "point": [0, 0, 1] } })"),
                     "joints[0].a.point: a rod node end has no point or axis of its own"));
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "body": "r" } })"), "joints[0].a.body: names the rod \"r\""));
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "body": "b", "edge": 2 } })"), "joints[0].a.edge: a node or an edge belongs to a \"rod\""));
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "body": "b", "rod": "r", "node": 2 } })"), "joints[0].a.world: give one of"));
  EXPECT_TRUE(starts(error(R"({ "type": "ball", "a": { "rod": "r", "node": 2 }, "b": { "rod": "r", "node": 2 } })"),
                     "joints[0].b: joins an end to itself"));
  EXPECT_TRUE(starts(error(R"({ "type": "weld", "a": { "rod": "r", "edge": 0 } })", R"(, "fixed_nodes": [0], "fixed_edges": [0])"),
                     "joints[0].b: neither end can move"));
  EXPECT_TRUE(starts(error(R"({ "type": "weld", "a": { "rod": "r", "edge": 0 }, "b": { "rod": "r", "edge": 5, "axis": [1, 0, 0] } })"),
                     "joints[0].b.axis: only a hinge or a slider has an axis"));
  // Accepted: two nodes of one rod (a loop), an edge held by an edge, a clamped node held.
  EXPECT_EQ(error(R"({ "type": "ball", "a": { "rod": "r", "node": 0 }, "b": { "rod": "r", "node": 12 } })"), "accepted");
  EXPECT_EQ(error(R"({ "type": "hinge", "a": { "rod": "r", "edge": 0, "axis": [1, 0, 0] }, "b": { "rod": "r", "edge": 11 } })"), "accepted");
  EXPECT_EQ(error(R"({ "type": "ball", "a": { "body": "b" }, "b": { "rod": "r", "node": 0 } })", R"(, "fixed_nodes": [0])"), "accepted");
}

}  // namespace
}  // namespace liedyn

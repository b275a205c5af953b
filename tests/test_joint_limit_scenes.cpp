// Joint limits in whole scenes (lib/joint_limits.hpp, "limits" in docs/scene-format.md): the
// mechanics a stop must reproduce, derived by hand.
//  * A link on a hinge to the world, pressed by gravity against its upper stop in static
//    equilibrium: exact, it rests at the stop with the stop's torque m g l cos(hi); elastic,
//    at the angle where (θ − hi)/c = m g l cos θ.
//  * A cart dropped along a vertical rail onto its slider's lower stop: it rests there with
//    the stop's force m g, the lower stop holding and the upper one idle.
//  * A wheel spun by its hinge motor through several turns into a stop beyond 2π (the angle
//    is continued across turns): it comes to rest at the stop, having turned hi in total,
//    with the stop's torque equal to the motor's.
//  * joints/stops.json ends as its description says.
//  * The three back-ends agree on a pendulum swinging into an exact stop.
//  * gradcheck through an active stop, exact and elastic.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

constexpr double kG = 9.81;

// The angle of a rotation about y, for rotations about y (R = exp(θ y)).
double angle_about_y(const Matrix3& R) { return std::atan2(R(0, 2), R(2, 2)); }

// Exact joints' multipliers of the one component, in the order the terms are listed
// (IncrementalPotential::TermTypes): the joints' point and axis parts, then the limits,
// lower before upper.
std::vector<Vector3> stop_forces(const Simulator& sim) {
  std::vector<Vector3> forces;
  sim.exact_forces(forces);
  return forces;
}

// Runs every frame of the scene: each step converges, its exact joints and stops held to the
// tolerance.
void run_holding_the_stops(Simulator& sim, const Scene& scene) {
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << k << ": " << r.message;
    EXPECT_LE(r.constraint_violation, scene.solver.tolerance) << k;
  }
}

// How well an exact stop's multiplier λ = ρ (g + s) is known once the step has converged:
// the gap g is within the tolerance of zero, so λ within ρ·tolerance, ρ = 10⁴ m/h² the exact
// joints' penalty for ends of mass m (for a rotation, of an inertia below the largest
// principal moment; lib/incremental_potential.cpp).
double multiplier_accuracy(double mass, const Scene& scene) {
  const double h = scene.model.time_step;
  return 1e4 * mass / (h * h) * scene.solver.tolerance;
}

// A 1 kg link whose centre is 0.5 m from a hinge to the world about y, horizontal at the
// start: gravity turns it the positive way about y, against the upper limit 0.5 rad.
std::string hanging_link(const std::string& mode, const std::string& compliance) {
  return R"({ "mode": ")" + mode + R"(", "time_step": 0.01, "frames": )" +
         (mode == "static" ? "4" : "150") + R"(, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-11, "max_iterations": 100 },
    "bodies": [ { "name": "link", "mass": 1, "inertia": [0.01, 0.02, 0.02], "position": [0.5, 0, 0] } ],
    "joints": [ { "type": "hinge", )" + compliance + R"("a": { "body": "link", "point": [-0.5, 0, 0], "axis": [0, 1, 0] },
                  "limits": [-0.2, 0.5] } ] })";
}

TEST(JointLimits, AHingeRestsAgainstItsStopExactlyOrByItsCompliance) {
  const double hi = 0.5, arm = 0.5;
  {
    const Scene scene = parse_scene(hanging_link("static", ""), "stop.json");
    Simulator sim(scene.model, scene.solver);
    for (int k = 1; k <= scene.frames; ++k) ASSERT_TRUE(sim.step().converged()) << k;
    EXPECT_NEAR(angle_about_y(sim.state().rotations[0]), hi, 1e-9);
    // Point (3), axis (3), lower stop (idle), upper stop (the torque gravity exerts).
    const std::vector<Vector3> f = stop_forces(sim);
    ASSERT_EQ(f.size(), 4u);
    EXPECT_EQ(f[2](0), 0.0);
    EXPECT_NEAR(f[3](0), 1.0 * kG * arm * std::cos(hi), 1e-7);
  }
  // Elastic stop (the point exact): θ − hi = c m g l cos θ, solved by Newton here.
  const double c = 0.01;
  const Scene scene = parse_scene(hanging_link("static", R"("compliance": 0, "compliance_rotation": 0.01, )"),
                                  "soft_stop.json");
  Simulator sim(scene.model, scene.solver);
  for (int k = 1; k <= scene.frames; ++k) ASSERT_TRUE(sim.step().converged()) << k;
  double theta = hi;
  for (int i = 0; i < 20; ++i) {
    const double r = theta - hi - c * kG * arm * std::cos(theta);
    theta -= r / (1.0 + c * kG * arm * std::sin(theta));
  }
  EXPECT_GT(theta - hi, 0.04);  // the stop gives by a visible amount
  EXPECT_NEAR(angle_about_y(sim.state().rotations[0]), theta, 1e-9);
}

// Dropped from rest along a vertical rail (to the world) onto its lower stop 0.2 m below (the
// slider's position is the cart's, a, relative to the world, b): the exact stop takes the
// cart's momentum in one step (backward Euler's inelastic impact) and then holds its weight.
TEST(JointLimits, ACartFallsOntoItsSlidersStopAndRestsThereOnItsWeight) {
  const Scene scene = parse_scene(R"({ "time_step": 0.01, "frames": 60, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-11, "max_iterations": 100 },
    "bodies": [ { "name": "cart", "mass": 2, "inertia": [0.01, 0.02, 0.03], "position": [0.3, 0, 1] } ],
    "joints": [ { "type": "slider", "a": { "body": "cart", "axis": [0, 0, 1] }, "limits": [-0.2, 0.1] } ] })",
                                  "rail.json");
  Simulator sim(scene.model, scene.solver);
  run_holding_the_stops(sim, scene);
  EXPECT_NEAR(sim.state().points[0].z(), 1.0 - 0.2, 1e-9);
  EXPECT_NEAR(sim.state().points[0].x(), 0.3, 1e-12);
  // Line (3), weld (3), lower stop: the weight; upper stop idle.
  const std::vector<Vector3> f = stop_forces(sim);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_NEAR(f[2](0), 2.0 * kG, multiplier_accuracy(2.0, scene));
  EXPECT_EQ(f[3](0), 0.0);
}

// A wheel (I_z = 0.01) driven by its hinge motor (τ = 1 N·m) from rest: free, it turns
// τ t²/(2 I) = 50 t² (less: backward Euler damps it), so it passes the half turn, the full
// turn and beyond before meeting the stop at hi = 3π + 0.5. It must stop there, not at the
// wrap of hi into (−π, π] (0.5 − π), and then hold the motor's torque.
TEST(JointLimits, AHingeLimitBeyondAFullTurnStopsAWheelAfterItsTurns) {
  const double hi = 3.0 * std::numbers::pi + 0.5;
  const Scene scene = parse_scene(R"({ "time_step": 0.005, "frames": 200,
    "solver": { "tolerance": 1e-11, "max_iterations": 100 },
    "bodies": [ { "name": "wheel", "mass": 1, "inertia": [0.02, 0.02, 0.01] } ],
    "joints": [ { "type": "hinge", "a": { "body": "wheel", "axis": [0, 0, 1] }, "motor": { "torque": 1 },
                  "limits": [-1, )" + std::to_string(hi) + R"(] } ] })",
                                  "wheel.json");
  Simulator sim(scene.model, scene.solver);
  double turned = 0.0;
  Matrix3 before = sim.state().rotations[0];
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    const Vector3 step = so3::log(sim.state().rotations[0] * before.transpose());
    before = sim.state().rotations[0];
    turned += step.z();
  }
  // std::to_string keeps 6 decimals of hi: compare with the bound the scene holds.
  const double bound = scene.model.joints[0].upper_limit;
  EXPECT_NEAR(bound, hi, 1e-6);
  EXPECT_NEAR(turned, bound, 1e-8);
  const std::vector<Vector3> f = stop_forces(sim);  // point, axis, lower, upper
  ASSERT_EQ(f.size(), 4u);
  EXPECT_NEAR(f[3](0), 1.0, multiplier_accuracy(0.02, scene));
}

// The link released from the horizontal swings into its exact upper stop, which takes its
// momentum and holds it; Newton, Ceres and Ipopt (each inside the augmented Lagrangian)
// follow the same trajectory through the impact.
TEST(JointLimits, BackEndsAgreeThroughTheStops) {
  const Scene scene = parse_scene(hanging_link("dynamic", ""), "swing.json");
  const auto run = [&](Backend backend) {
    SolverOptions o = scene.solver;
    o.backend = backend;
    Simulator s(scene.model, o);
    // Ceres stalls within a few times the tolerance on exact joints (its trust region stops
    // on relative decrease): its steps must update the state, not all converge.
    for (int k = 1; k <= 40; ++k) EXPECT_TRUE(s.step().state_updated()) << to_string(backend) << " frame " << k;
    return s.state();
  };
  const State newton = run(Backend::kNewton);
  EXPECT_NEAR(angle_about_y(newton.rotations[0]), 0.5, 1e-8);  // it reached the stop
  for (const Backend b : {Backend::kCeres, Backend::kIpopt}) {
    const State q = run(b);
    EXPECT_LT((q.points[0] - newton.points[0]).norm(), 1e-6) << to_string(b);
    EXPECT_LT(so3::distance(q.rotations[0], newton.rotations[0]), 1e-6) << to_string(b);
  }
}

// joints/stops.json does what its description says: the arm ends on its stop at 1.2 rad,
// held by m g l cos(1.2); the cart 0.25 m down its rail on the lower stop, held by
// m g sin 30° − 5 N; every step converged with the stops to the tolerance.
TEST(JointLimits, TheBundledStopsSceneEndsOnItsStops) {
  const Scene scene = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/joints/stops.json");
  Simulator sim(scene.model, scene.solver);
  run_holding_the_stops(sim, scene);
  const double tol = scene.solver.tolerance;
  EXPECT_NEAR(angle_about_y(sim.state().rotations[0]), 1.2, 2 * tol);
  const Vector3 rail(std::sqrt(0.75), 0, 0.5);
  EXPECT_NEAR((sim.state().points[1] - scene.model.bodies[1].position).dot(rail), -0.25, 2 * tol);
  EXPECT_LT((sim.state().points[1] - scene.model.bodies[1].position).cross(rail).norm(), 2 * tol);
  // One component per body: the hinge's point, axis, lower and upper stop; the slider's
  // line, weld, lower and upper stop.
  const std::vector<Vector3> f = stop_forces(sim);
  ASSERT_EQ(f.size(), 8u);
  EXPECT_NEAR(f[3](0), 1.0 * kG * 0.4 * std::cos(1.2), multiplier_accuracy(0.02, scene));
  EXPECT_NEAR(f[6](0), 2.0 * kG * 0.5 - 5.0, multiplier_accuracy(2.0, scene));
  EXPECT_EQ(f[2](0), 0.0);
  EXPECT_EQ(f[7](0), 0.0);
}

class JointLimitsCli : public test::CliFixture {
 protected:
  JointLimitsCli() : CliFixture("liedyn_joint_limits_test_") {}
};

// The adjoint through an active stop: link 1 of a double pendulum lies on its hinge's upper
// stop (hi = 0, where it starts) under gravity while link 2 swings from its tip; the initial
// spin of link 2 and its pose at the end. Exact: the stop is an active equality row of the
// constrained adjoint in every frame; elastic: link 1 rocks on the stop's compliance.
TEST_F(JointLimitsCli, GradcheckPassesThroughAnActiveStopExactAndElastic) {
  for (const bool exact : {true, false}) {
    SCOPED_TRACE(exact ? "exact" : "elastic");
    const std::string compliance = exact ? "" : R"("compliance": 1e-4, )";
    std::ofstream(dir_ / "scene.json") << R"({ "time_step": 0.01, "frames": 30, "gravity": [0, 0, -9.81],
      "solver": { "tolerance": )" << (exact ? "1e-12" : "1e-11") << R"(, "max_iterations": 100 },
      "bodies": [ { "name": "l1", "mass": 1, "inertia": [0.01, 0.02, 0.02], "position": [0.2, 0, 0] },
                  { "name": "l2", "mass": 0.3, "inertia": [0.005, 0.01, 0.01], "position": [0.6, 0, 0],
                    "angular_velocity": [0, 1, 0] } ],
      "joints": [ { "type": "hinge", )" << compliance << R"("a": { "body": "l1", "point": [-0.2, 0, 0], "axis": [0, 1, 0] },
                    "limits": [-1, 0] },
                  { "type": "hinge", )" << compliance << R"("a": { "body": "l2", "point": [-0.2, 0, 0], "axis": [0, 1, 0] },
                    "b": { "body": "l1" } } ],
      "optimization": {
        "parameters": [ { "kind": "body_angular_velocity", "body": "l2" } ],
        "objective": [ { "term": "body_pose", "body": "l2", "frame": -1,
                         "position": [0.4, 0, -0.3], "orientation": [1, 0, 0, 0], "orientation_weight": 1 } ] } })";
    const Result r = run({"gradcheck", "scene.json", "--step", "1e-5"});
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  }
}

}  // namespace
}  // namespace liedyn

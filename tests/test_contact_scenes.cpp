// Contact and friction in whole simulations (lib/contact.hpp, lib/friction.hpp), against
// mechanics: a puck on an incline sticks below tan θ = μ (creeping at the speed the smoothed
// Coulomb law predicts) and slides with a = g(sin θ − μ cos θ) above it; a frictionless
// bounce never gains energy; a spinning disk on a plane loses its spin at the rate μ m g a/I;
// the bundled contact scenes converge every step, keep penetrations within a stated fraction
// of the contact radius, and come to rest; the three back-ends agree on a contact scene.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <string>

#include "adjoint_check.hpp"
#include "lib/model.hpp"
#include "lib/so3.hpp"
#include "problems/optimization.hpp"
#include "problems/scene.hpp"
#include "solvers/gradient_check.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kG = 9.81;

Collider plane_with_normal(const Vector3& n) {
  Collider c;
  c.name = "plane";
  c.shape = PlaneShape{};
  c.orientation = minimal_rotation(Vector3::UnitZ(), n.normalized());  // frame z = n
  return c;
}

// A puck: one contact sample at its centre of mass, a sphere of radius r (no friction
// torque, so its rotation stays put and the test sees the translational law alone).
RigidBody puck(double mass, double radius, double stiffness, double friction) {
  RigidBody b;
  b.name = "puck";
  b.mass = mass;
  b.inertia = Vector3::Constant(0.4 * mass * radius * radius).asDiagonal();
  b.contact_points = {Vector3::Zero()};
  b.contact.stiffness = stiffness;
  b.contact.radius = radius;
  b.contact.friction = friction;
  return b;
}

TEST(ContactSimulator, ReportsTheDeepestPenetration) {
  // A puck resting at depth d below its radius on a plane, beside one clear of it.
  Model model;
  model.gravity = Vector3::Zero();
  model.colliders = {plane_with_normal(Vector3::UnitZ())};
  RigidBody deep = puck(0.1, 0.02, 1e4, 0.0);
  deep.position = Vector3(0, 0, 0.02 - 3e-4);
  RigidBody clear = puck(0.1, 0.02, 1e4, 0.0);
  clear.name = "clear";
  clear.position = Vector3(1, 0, 0.5);
  model.bodies = {deep, clear};
  const Simulator sim(model, SolverOptions{});
  EXPECT_NEAR(sim.max_penetration(), 3e-4, 1e-15);
  model.bodies = {clear};
  EXPECT_EQ(Simulator(model, SolverOptions{}).max_penetration(), 0.0);
}

struct InclineRun {
  double creep_speed;     // mean speed along the slope over the second half, m/s
  double acceleration;    // (v(T) − v(T/2)) / (T/2) along the slope, m/s²
};

// A puck released at its equilibrium depth on a plane tilted by θ about y, h = 1 ms, for T.
InclineRun run_incline(double theta, double mu, double seconds) {
  Model model;
  model.time_step = 1e-3;
  model.gravity = Vector3(0, 0, -kG);
  const Vector3 n(-std::sin(theta), 0.0, std::cos(theta));  // the plane's normal
  const Vector3 down_slope(-std::cos(theta), 0.0, -std::sin(theta));
  model.colliders = {plane_with_normal(n)};
  const double m = 0.1, r = 0.02, k = 1e4;
  RigidBody b = puck(m, r, k, mu);
  b.position = (r - m * kG * std::cos(theta) / k) * n;  // at rest on the plane
  model.bodies = {b};
  Simulator sim(model, SolverOptions{});
  const int steps = static_cast<int>(std::lround(seconds / model.time_step));
  double s_half = 0.0, v_half = 0.0;
  for (int k = 1; k <= steps; ++k) {
    const StepReport report = sim.step();
    EXPECT_TRUE(report.converged()) << "step " << k;
    if (k == steps / 2) {
      s_half = sim.state().points[0].dot(down_slope);
      v_half = sim.linear_velocity(0).dot(down_slope);
    }
  }
  const double half = 0.5 * seconds;
  InclineRun run;
  run.creep_speed = (sim.state().points[0].dot(down_slope) - s_half) / half;
  run.acceleration = (sim.linear_velocity(0).dot(down_slope) - v_half) / half;
  return run;
}

TEST(ContactIncline, BelowTheFrictionAngleThePuckSticksCreepingAtTheSmoothedLawsSpeed) {
  // tan θ < μ: static friction holds. The smoothed law f₁(y) = 2y/ε − y²/ε² (friction.hpp)
  // balances the slope when μ λ f₁ = m g sin θ with λ = m g cos θ, i.e. at the slip per step
  // y = ε (1 − √(1 − tan θ/μ)): a creep speed y/h = ε_v (1 − √(1 − tan θ/μ)) < ε_v.
  const double mu = 0.5;
  for (double degrees : {10.0, 20.0, 25.0}) {
    SCOPED_TRACE(degrees);
    const double theta = degrees * kPi / 180.0;
    const InclineRun run = run_incline(theta, mu, 1.0);
    const double predicted = 1e-3 * (1.0 - std::sqrt(1.0 - std::tan(theta) / mu));
    EXPECT_GT(run.creep_speed, 0.0);
    EXPECT_LT(run.creep_speed, 1e-3);  // below ε_v: it sticks
    // Steady creep: the lagged λ equals m g cos θ once the normal oscillation has died out;
    // 1 % covers what is left of it after half a second.
    EXPECT_NEAR(run.creep_speed, predicted, 0.01 * predicted);
    std::cout << "incline " << degrees << "°, μ = " << mu << ": creep " << run.creep_speed
              << " m/s, smoothed law " << predicted << " m/s\n";
    EXPECT_NEAR(run.acceleration, 0.0, 1e-4);
  }
}

TEST(ContactIncline, AboveTheFrictionAngleThePuckSlidesWithCoulombsAcceleration) {
  // tan θ > μ: a = g (sin θ − μ cos θ). Backward Euler integrates a constant force exactly in
  // the velocities, and above ε_v the smoothed law is exactly Coulomb's (f₁ = 1), so the only
  // error is the solver's: positions within the Newton tolerance 1e-9 m make each velocity
  // good to 1e-6 m/s, and two of them over 0.5 s bound a ≥ 0.59 m/s² to 7e-6 relative (the
  // measured error is ~1e-11).
  const double mu = 0.3;
  for (double degrees : {20.0, 30.0, 45.0, 60.0}) {
    SCOPED_TRACE(degrees);
    const double theta = degrees * kPi / 180.0;
    const InclineRun run = run_incline(theta, mu, 1.0);
    const double a = kG * (std::sin(theta) - mu * std::cos(theta));
    EXPECT_NEAR(run.acceleration, a, 1e-5 * a);
    std::cout << "incline " << degrees << "°, μ = " << mu << ": a = " << run.acceleration
              << " m/s², g(sin θ − μ cos θ) = " << a << " (relative error "
              << std::abs(run.acceleration - a) / a << ")\n";
  }
  // Frictionless: a = g sin θ.
  const InclineRun free = run_incline(30.0 * kPi / 180.0, 0.0, 1.0);
  EXPECT_NEAR(free.acceleration, kG * 0.5, 1e-5 * kG * 0.5);
}

TEST(ContactEnergy, AFrictionlessBounceNeverGainsEnergy) {
  // Gravity plus a half-space penalty is convex in x, and for a convex V backward Euler
  // dissipates: E_k + ½ m ‖v_k − v_{k−1}‖² ≤ E_{k−1} exactly at the minimiser. The check
  // allows what the Newton tolerance (1e-12 m per step) can leave: ‖∇Ψ‖ · 1e-12 ≈ 1e-12 J.
  Model model;
  model.time_step = 1e-3;
  model.gravity = Vector3(0, 0, -kG);
  model.colliders = {plane_with_normal(Vector3::UnitZ())};
  for (double h : {1e-4, 1e-3, 1e-2}) {
    SCOPED_TRACE(h);
    model.time_step = h;
    RigidBody b = puck(0.1, 0.02, 1e4, 0.0);
    b.position = Vector3(0, 0, 0.1);
    b.linear_velocity = Vector3(0.3, 0, 0);
    model.bodies = {b};
    SolverOptions options;
    options.tolerance = 1e-12;
    Simulator sim(model, options);
    double energy = sim.kinetic_energy() + sim.potential_energy();
    const double initial = energy;
    int bounces = 0;
    double previous_vz = 0.0;
    const int steps = static_cast<int>(std::lround(1.0 / h));
    for (int k = 0; k < steps; ++k) {
      ASSERT_TRUE(sim.step().converged()) << "step " << k;
      const double e = sim.kinetic_energy() + sim.potential_energy();
      EXPECT_LE(e, energy + 1e-12) << "step " << k;
      energy = e;
      const double vz = sim.linear_velocity(0).z();
      if (previous_vz < 0.0 && vz >= 0.0) ++bounces;
      previous_vz = vz;
    }
    EXPECT_GE(bounces, 1);
    EXPECT_LT(energy, initial);
  }
}

TEST(ContactEnergy, ATumblingFrictionlessBoxGainsNoEnergyBeyondTheTolerance) {
  // Samples off the centre of mass make V non-convex in the rotation, so the exact bound of
  // the puck does not hold step by step; over the run, energy must still not grow: each step
  // may add at most what a non-convex minimiser can, here measured against 1e-6 of the
  // initial energy.
  Model model;
  model.time_step = 1e-3;
  model.gravity = Vector3(0, 0, -kG);
  model.colliders = {plane_with_normal(Vector3::UnitZ())};
  RigidBody b;
  b.name = "box";
  b.mass = 0.2;
  const Vector3 half(0.05, 0.03, 0.02);
  b.inertia = (b.mass / 3.0 * Vector3(half.y() * half.y() + half.z() * half.z(),
                                      half.x() * half.x() + half.z() * half.z(),
                                      half.x() * half.x() + half.y() * half.y()))
                  .asDiagonal();
  for (int s = 0; s < 8; ++s) {
    b.contact_points.push_back(
        Vector3(s & 1 ? 1 : -1, s & 2 ? 1 : -1, s & 4 ? 1 : -1).cwiseProduct(half));
  }
  b.contact.stiffness = 1e4;
  b.position = Vector3(0, 0, 0.15);
  b.orientation = so3::exp(Vector3(0.4, 0.3, 0.1));
  b.angular_velocity = Vector3(3, -2, 5);
  model.bodies = {b};
  SolverOptions options;
  options.tolerance = 1e-12;
  Simulator sim(model, options);
  const double initial = sim.kinetic_energy() + sim.potential_energy();
  double highest = initial;
  for (int k = 0; k < 1500; ++k) {
    ASSERT_TRUE(sim.step().converged()) << "step " << k;
    highest = std::max(highest, sim.kinetic_energy() + sim.potential_energy());
  }
  EXPECT_LE(highest, initial * (1.0 + 1e-6));
  EXPECT_LT(sim.kinetic_energy() + sim.potential_energy(), initial);
}

// A flat disk of radius a touching a plane at 16 samples on its rim, spinning about the
// vertical at ω₀, with friction μ; spin measured at steps 40 and 120 (h = 1 ms).
struct DiskSpin {
  double deceleration;  // (ω(40 h) − ω(120 h)) / 80 h
  double mean_cubed;    // ⟨ω³⟩ over that window for ω falling linearly: (ω_a⁴ − ω_b⁴)/(4(ω_a − ω_b))
  double final_spin;    // after 300 steps
  bool reversed;        // the spin changed sign at some step
};
DiskSpin spin_disk(double mu) {
  Model model;
  model.time_step = 1e-3;
  model.gravity = Vector3(0, 0, -kG);
  model.colliders = {plane_with_normal(Vector3::UnitZ())};
  const double m = 0.2, a = 0.05, k = 2e4;
  RigidBody disk;
  disk.name = "disk";
  disk.mass = m;
  disk.inertia = Vector3(0.25 * m * a * a, 0.25 * m * a * a, 0.5 * m * a * a).asDiagonal();
  for (int s = 0; s < 16; ++s) {
    const double phi = 2.0 * kPi * s / 16.0;
    disk.contact_points.push_back(Vector3(a * std::cos(phi), a * std::sin(phi), 0.0));
  }
  disk.contact.stiffness = k;
  disk.contact.friction = mu;
  disk.position = Vector3(0, 0, -m * kG / (16.0 * k));  // resting depth
  disk.angular_velocity = Vector3(0, 0, 20.0);
  model.bodies = {disk};
  Simulator sim(model, SolverOptions{});
  double omega_a = 0.0, omega_b = 0.0;
  DiskSpin out{0.0, 0.0, 0.0, false};
  for (int step = 1; step <= 300; ++step) {
    EXPECT_TRUE(sim.step().converged()) << "step " << step;
    const double omega = sim.angular_velocity(0).z();
    if (step == 40) omega_a = omega;
    if (step == 120) omega_b = omega;
    out.reversed = out.reversed || omega < -1e-6;
  }
  out.deceleration = (omega_a - omega_b) / 0.08;
  out.mean_cubed = (std::pow(omega_a, 4) - std::pow(omega_b, 4)) / (4.0 * (omega_a - omega_b));
  out.final_spin = sim.angular_velocity(0).z();
  return out;
}

TEST(ContactFriction, ASpinningDiskOnAPlaneLosesItsSpinAtCoulombsRate) {
  // Each sample slides at a ω ≫ ε_v, so friction is exactly Coulomb's, μ λ per sample; with
  // Σλ = m g the torque is μ m g a and I_z = ½ m a² gives α = 2 μ g / a, until the spin stops
  // (and never reverses). Backward Euler itself slows a spin too: its energy factor
  // (1 + ω²h²)⁻² per step (docs/design.md §13) is a deceleration c ω³ with c ≈ h. c is measured on
  // the same disk without friction and added at the friction run's own ⟨ω³⟩ (1.2 % of α
  // here), which leaves 0.2 % for the ripple of the normal force.
  const DiskSpin frictionless = spin_disk(0.0);
  EXPECT_FALSE(frictionless.reversed);
  EXPECT_GT(frictionless.final_spin, 15.0);  // no friction: it spins on
  const double c = frictionless.deceleration / frictionless.mean_cubed;
  EXPECT_NEAR(c, 1e-3, 2e-4);  // ≈ h
  const double mu = 0.3, a = 0.05;
  const DiskSpin spin = spin_disk(mu);
  const double alpha = 2.0 * mu * kG / a + c * spin.mean_cubed;
  EXPECT_NEAR(spin.deceleration, alpha, 2e-3 * alpha);
  std::cout << "spinning disk: α = " << spin.deceleration << " rad/s², 2μg/a = "
            << 2.0 * mu * kG / a << " plus backward Euler's " << c * spin.mean_cubed << "\n";
  EXPECT_FALSE(spin.reversed);
  EXPECT_LT(std::abs(spin.final_spin), 1e-2);  // stopped (t_stop ≈ 0.17 s)
}

// ---------------------------------------------------------------------------------------
// The bundled scenes.

struct SceneRun {
  double max_penetration = 0.0;
  double final_kinetic_energy = 0.0;
  int unconverged = 0;
  State final_state;
};

SceneRun run_scene(const std::string& file, int frames, Backend backend = Backend::kNewton,
                   RotationParameterization rotation = RotationParameterization::kLie) {
  Scene scene = load_scene(std::string(LIEDYN_SOURCE_DIR) + "/problems/scenes/contact/" + file);
  scene.solver.backend = backend;
  scene.solver.rotation = rotation;
  Simulator sim(scene.model, scene.solver);
  SceneRun run;
  run.max_penetration = sim.max_penetration();
  for (int k = 0; k < frames; ++k) {
    const StepReport report = sim.step();
    EXPECT_TRUE(report.state_updated()) << file << " step " << k << ": " << report.message;
    if (!report.state_updated()) break;
    if (!report.converged()) ++run.unconverged;
    run.max_penetration = std::max(run.max_penetration, sim.max_penetration());
  }
  run.final_kinetic_energy = sim.kinetic_energy();
  run.final_state = sim.state();
  return run;
}

TEST(ContactScenes, TheDieLandsOnAFaceWithinAFractionOfAMillimetre) {
  // Worst impact: all of the landing speed v = √(v_z² + 2 g h₀) = 1.8 m/s on one sample,
  // ½ m v² = ½ k d², bounds the depth by v √(m/k) = 0.57 mm (k = 1e5 N/m, m = 10 g), 6 % of
  // the die's half size (measured: 0.1 mm).
  const SceneRun run = run_scene("die_throw.json", 1500);
  EXPECT_EQ(run.unconverged, 0);
  EXPECT_LT(run.max_penetration, 0.57e-3);
  EXPECT_LT(run.final_kinetic_energy, 1e-8);  // at rest
  EXPECT_NEAR(run.final_state.points[0].z(), 0.01, 1e-5);  // resting on a face
}

TEST(ContactScenes, BodiesTumblingOnAPlaneAndInABowlComeToRest) {
  for (const char* file : {"plane_tumble.json", "bowl_tumble.json"}) {
    SCOPED_TRACE(file);
    const SceneRun run = run_scene(file, 1000);
    EXPECT_EQ(run.unconverged, 0);
    // k = 2e4 N/m and 0.2 kg landing at ≤ 2 m/s (dropped from ≤ 0.2 m): d ≤ v √(m/k) ≈
    // 6.3 mm if one sample took it all (measured: 0.8 mm on the plane, 1.8 mm in the bowl).
    EXPECT_LT(run.max_penetration, 6.3e-3);
    EXPECT_LT(run.final_kinetic_energy, 1e-3);
  }
}

TEST(ContactScenes, TheRodAdvancesThroughTheTubeWithoutLeavingIt) {
  // 600 of the scene's 2000 frames: the tip enters the S-bend. The push (0.1 N on each of
  // ~30 nodes) and the bending moment of the rod in the bend press nodes into the wall; at
  // k = 3e3 N/m a node carrying 3 N sinks 1 mm. Half the rod radius (3 mm) is the bound.
  Scene scene = load_scene(std::string(LIEDYN_SOURCE_DIR) + "/problems/scenes/contact/tube_insertion.json");
  const SceneRun run = run_scene("tube_insertion.json", 600);
  EXPECT_EQ(run.unconverged, 0);
  EXPECT_LT(run.max_penetration, 0.5 * scene.model.rods[0].radius);
  const int tip = scene.model.rod_point(0, scene.model.rods[0].node_count() - 1);
  const Vector3 start = scene.model.rods[0].nodes.back();
  EXPECT_GT((run.final_state.points[tip] - start).norm(), 0.1);  // it moved in
}

TEST(ContactScenes, AMeshColliderGivesTheAnalyticPlanesTrajectory) {
  // mesh_slab.json is die_throw.json with the table as a triangle mesh sampled on a 1 cm grid
  // (lib/mesh_sdf.hpp). Where the nearest feature is the top face the node values are exact
  // and the trilinear interpolant of a linear function is the function itself: the die never
  // nears the slab's edges (0.5 m away), so only round-off separates the runs (measured
  // 2e-9 m over 1500 frames of impacts, sliding and rest).
  const SceneRun plane = run_scene("die_throw.json", 1500);
  const SceneRun mesh = run_scene("mesh_slab.json", 1500);
  EXPECT_EQ(mesh.unconverged, 0);
  EXPECT_LT((mesh.final_state.points[0] - plane.final_state.points[0]).norm(), 1e-7);
  EXPECT_LT(so3::distance(mesh.final_state.rotations[0], plane.final_state.rotations[0]), 1e-6);
  EXPECT_NEAR(mesh.max_penetration, plane.max_penetration, 1e-7);
}

TEST(ContactScenes, CeresAndIpoptAgreeWithNewtonThroughContactAndFriction) {
  // The die's first 150 frames include the first impact and sliding with friction.
  const SceneRun newton = run_scene("die_throw.json", 150);
  for (Backend backend : {Backend::kCeres, Backend::kIpopt}) {
    SCOPED_TRACE(to_string(backend));
    const SceneRun other = run_scene("die_throw.json", 150, backend);
    EXPECT_LT((other.final_state.points[0] - newton.final_state.points[0]).norm(), 1e-6);
    EXPECT_LT(so3::distance(other.final_state.rotations[0], newton.final_state.rotations[0]), 1e-5);
  }
}

TEST(ContactScenes, RotationVectorsAndQuaternionsAgreeWithLieThroughContact) {
  // 300 frames: the die's first impacts (it lands at ~0.17 s) and its tumbling with friction.
  const SceneRun lie = run_scene("die_throw.json", 300);
  for (auto rotation : {RotationParameterization::kRotationVector, RotationParameterization::kQuaternion}) {
    SCOPED_TRACE(to_string(rotation));
    const SceneRun other = run_scene("die_throw.json", 300, Backend::kNewton, rotation);
    EXPECT_EQ(other.unconverged, 0);
    EXPECT_LT((other.final_state.points[0] - lie.final_state.points[0]).norm(), 1e-6);
    EXPECT_LT(so3::distance(other.final_state.rotations[0], lie.final_state.rotations[0]), 1e-6);
  }
}

// ---------------------------------------------------------------------------------------
// Adjoint gradients through contact and friction, end to end (the terms' own blocks are
// checked in test_contact.cpp): central differences of the loss at a tight forward tolerance
// (the step: adjoint_check.hpp).

TEST(ContactAdjoint, TheDieThrowGradientRunsBackThroughContactAndFriction) {
  const Scene scene = load_scene(std::string(LIEDYN_SOURCE_DIR) +
                                 "/problems/scenes/optimization/die_throw_contact.json");
  EXPECT_TRUE(test::gradient_agrees(scene));
  const DifferentiableSimulation sim = make_differentiable_simulation(scene);
  EXPECT_GT(sim.evaluate(sim.initial_parameters(), nullptr).loss, 0.1);  // far from the target: worth checking
}

TEST(ContactAdjoint, RodNodeVelocitiesThroughAFrictionalFloor) {
  // A rod thrown down onto a floor with friction: the nodes hit, slide and stick; γ = its
  // initial node velocities, g = distance of the final nodes to a target line.
  const std::string text = R"({
    "time_step": 0.005, "frames": 60, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-12, "max_iterations": 100 },
    "colliders": [ { "type": "plane", "normal": [0, 0.2, 1] } ],
    "rods": [ { "name": "rod", "shape": { "type": "line", "start": [0, 0, 0.03], "end": [0.3, 0, 0.05], "edges": 6 },
                "mass": 0.05, "radius": 0.005, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                "bending_stiffness": [1e-3, 1e-3, 1e-3],
                "contact": { "stiffness": 2e3, "friction": 0.4 } } ],
    "optimization": {
      "parameters": [ { "kind": "rod_node_velocities", "rod": "rod" } ],
      "objective": [ { "term": "point_targets", "rod": "rod", "frame": -1,
                       "polyline": [[0.1, 0.1, 0], [0.4, 0.1, 0]] } ] } })";
  const Scene scene = parse_scene(text, "rod_on_floor");
  Eigen::VectorXd gamma = make_differentiable_simulation(scene).initial_parameters();
  for (int i = 0; i < gamma.size(); i += 3) gamma.segment<3>(i) = Vector3(0.3, 0.1, -0.5);
  // The run must touch the floor, and friction must act: check it before trusting the check.
  Simulator forward(scene.model, scene.solver);
  double deepest = -1.0;
  for (int k = 0; k < scene.frames; ++k) {
    forward.step();
    deepest = std::max(deepest, forward.max_penetration());
  }
  // (The plain run starts at rest; the optimised parameters only move it harder.)
  EXPECT_GT(deepest, 0.0);
  EXPECT_TRUE(test::gradient_agrees(scene, gamma));
}

}  // namespace
}  // namespace liedyn

// Contact and friction in whole simulations (lib/contact.hpp, lib/friction.hpp), against
// mechanics: a puck on an incline sticks below tan θ = μ (creeping at the speed the smoothed
// Coulomb law predicts) and slides with a = g(sin θ − μ cos θ) above it; a frictionless
// bounce never gains energy; a spinning disk on a plane loses its spin at the rate μ m g a/I;
// the bundled contact scenes converge every step, keep penetrations within a stated fraction
// of the contact radius, and come to rest; the three back-ends agree on a contact scene; a
// damped contact bounces with the restitution its dashpot declares, whatever the time step.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numbers>
#include <string>

#include "adjoint_check.hpp"
#include "trajectory_compare.hpp"
#include "lib/model.hpp"
#include "lib/so3.hpp"
#include "problems/optimization.hpp"
#include "problems/scene.hpp"
#include "solvers/gradient_check.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::contact_scenes_tests {
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

// Contact damping (lib/contact_damping.hpp): the restitution of a dropped puck,
// problems/scenes/contact/puck_bounce.json.
//
// The puck (m = 0.1 kg, one sample of radius ρ at its centre) meets a plane with the penalty
// k = 1e4 N/m: ω₀ = √(k/m) = 316 rad/s, a contact of ≈ 10 ms. The dashpot c = 2ζ√(k m) with
// ζ = −ln e/√(π² + ln² e) sets e = 0.5 for a spring–dashpot without gravity. The reference is
// that oscillator with gravity (it shortens the rebound by ~g/(ω₀ v) ≈ 1 %), integrated by RK4
// at 1e-7 s from the moment the sphere touches (z = ρ, falling at v_in) to the moment it leaves
// (z = ρ again): e_ref = v_out/v_in. The simulation measures e = √(H_out/H_in) from the
// heights of the sphere's centre above z = ρ at release and at the top of the rebound, which
// free flight (exact under both integrators for a constant force) turns into the speeds at z = ρ.
struct PuckDrop {
  Model model;
  double drop = 0.0;  // H_in, m
  double mass = 0.0, stiffness = 0.0, damping = 0.0;
};

PuckDrop puck_drop() {
  const Scene scene = load_scene(std::string(LIEDYN_SOURCE_DIR) + "/problems/scenes/contact/puck_bounce.json");
  const RigidBody& b = scene.model.bodies.at(0);
  return {scene.model, b.position.z() - b.contact.radius, b.mass, b.contact.stiffness, b.contact.damping};
}

// √(H_out/H_in) of the first bounce at step h, with the dashpot `damping`.
double restitution(const PuckDrop& drop, double h, double damping, Integrator integrator) {
  Model model = drop.model;
  model.time_step = h;
  model.integrator = integrator;
  RigidBody& b = model.bodies[0];
  b.contact.damping = damping;
  SolverOptions options;
  options.tolerance = 1e-12;
  Simulator sim(model, options);
  bool touched = false;
  double top = 0.0;
  // Long enough to fall, bounce and pass the rebound's top (≤ the drop's height).
  const int steps = static_cast<int>(std::lround(3.0 * std::sqrt(2.0 * drop.drop / kG) / h));
  for (int k = 0; k < steps; ++k) {
    EXPECT_TRUE(sim.step().converged()) << "h " << h << " step " << k;
    const double z = sim.state().points[0].z() - b.contact.radius;
    if (z < 0.0) touched = true;
    if (touched && z > 0.0) top = std::max(top, z);
  }
  return std::sqrt(top / drop.drop);
}

// The spring–dashpot with gravity, from touch-down at speed v_in to lift-off: v_out/v_in.
double oscillator_restitution(const PuckDrop& drop, double v_in) {
  const double dt = 1e-7, k = drop.stiffness / drop.mass, c = drop.damping / drop.mass;
  // u = depth below touch-down (> 0 inside), w = du/dt.
  const auto accel = [&](double u, double w) { return kG - k * u - c * w; };
  double u = 0.0, w = v_in;
  while (true) {
    const double k1u = w, k1w = accel(u, w);
    const double k2u = w + 0.5 * dt * k1w, k2w = accel(u + 0.5 * dt * k1u, w + 0.5 * dt * k1w);
    const double k3u = w + 0.5 * dt * k2w, k3w = accel(u + 0.5 * dt * k2u, w + 0.5 * dt * k2w);
    const double k4u = w + dt * k3w, k4w = accel(u + dt * k3u, w + dt * k3w);
    const double u_next = u + dt / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
    const double w_next = w + dt / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
    if (u > 0.0 && u_next <= 0.0) {  // lift-off within this step: interpolate w at u = 0
      const double t = u / (u - u_next);
      return -(w + t * (w_next - w)) / v_in;
    }
    u = u_next;
    w = w_next;
  }
}

TEST(ContactDampingScenes, ADroppedPuckBouncesWithTheDeclaredRestitutionAtEveryTimeStep) {
  // Under the trapezoidal rule the penalty returns the energy it stores; the dashpot alone takes
  // it. The lagged zone starts and stops the dashpot up to a step late, an O(h/T) error whose
  // sign depends on where in a step the contact starts: measured (printed) 0.4925, 0.4979,
  // 0.5036 against e_ref = 0.4932 at 1, 0.5, 0.25 ms (10 to 40 steps per contact; 0.461 at
  // 2 ms, 0.4937 at 31 µs). e must be within 0.05 of the declared 0.5 (the target) and within
  // 0.02 of the oscillator's at every h. Backward Euler's, for contrast: 0.31, 0.39, 0.45.
  const PuckDrop drop = puck_drop();
  const double e = 0.5;
  const double zeta = -std::log(e) / std::sqrt(kPi * kPi + std::log(e) * std::log(e));
  // The scene's c, written to 6 digits, is the one that declares e = 0.5.
  EXPECT_NEAR(drop.damping, 2.0 * zeta * std::sqrt(drop.stiffness * drop.mass), 1e-4);
  const double reference = oscillator_restitution(drop, std::sqrt(2.0 * kG * drop.drop));
  std::printf("puck: c = %.4f N s/m for e = %.2f; oscillator with gravity e_ref = %.5f\n",
              drop.damping, e, reference);
  EXPECT_NEAR(reference, e, 0.02);  // gravity's share, ~g/(ω₀ v_in)
  for (double h : {1e-3, 5e-4, 2.5e-4}) {
    SCOPED_TRACE(h);
    const double trapezoidal = restitution(drop, h, drop.damping, Integrator::kTrapezoidal);
    const double euler = restitution(drop, h, drop.damping, Integrator::kBackwardEuler);
    const double undamped = restitution(drop, h, 0.0, Integrator::kTrapezoidal);
    std::printf("  h = %.2e s: e trapezoidal %.5f, backward Euler %.5f; undamped trapezoidal %.5f\n",
                h, trapezoidal, euler, undamped);
    EXPECT_NEAR(trapezoidal, e, 0.05);
    EXPECT_NEAR(trapezoidal, reference, 0.02);
    // Without the dashpot the trapezoidal rule returns nearly all of it (0.9964 at 1 ms): a
    // bounce with no declared dissipation is elastic, up to the penalty's O((ω₀h)²).
    EXPECT_GT(undamped, 0.99);
  }
}

// The declared restitution between two free bodies and against a moving collider: no gravity,
// so the contact is a linear spring–dashpot on the relative normal motion, with the reduced
// mass μ = m_a m_b/(m_a + m_b) (μ = m against a kinematic body), which leaves contact with
// exactly e = exp(−ζπ/√(1 − ζ²)), ζ = c/(2√(k μ)), whatever h (the lagged zone aside: an
// O(h/T) error, as on a static floor). A puck (one sample at its centre, 0.1 kg) meets a
// sphere of 0.3 kg at rest, then a kinematic plane moving towards it at 0.5 m/s (Galilean:
// the relative speeds count).
double separation_restitution(double h, Integrator integrator, bool moving_plane, double damping,
                              double* momentum_error = nullptr) {
  const std::string puck = R"({"name": "puck", "mass": 0.1, "inertia": [1.6e-5, 1.6e-5, 1.6e-5],
        "position": [-0.2, 0, 0], "linear_velocity": [1, 0, 0],
        "contact": {"stiffness": 1e4, "radius": 0.02, "damping": )" + std::to_string(damping) +
                           R"(, "points": [[0, 0, 0]]}})";
  const std::string other =
      moving_plane ? R"("colliders": [{"name": "wall", "type": "plane", "normal": [-1, 0, 0], "position": [0.1, 0, 0],
                                       "kinematic": {"linear_velocity": [-0.5, 0, 0]}}])"
                   : R"("bodies": [)" + puck + R"(, {"name": "ball", "mass": 0.3, "inertia": [1.2e-3, 1.2e-3, 1.2e-3],
                        "contact": {"stiffness": 1e4, "shape": {"type": "sphere", "radius": 0.1}}}])";
  const std::string text = R"({"time_step": )" + std::to_string(h) + R"(, "frames": 1, "gravity": [0, 0, 0],
      "solver": {"tolerance": 1e-12, "max_iterations": 50}, )" +
                           (moving_plane ? R"("bodies": [)" + puck + "], " + other : other) + "}";
  Scene scene = parse_scene(text, "separation.json");
  scene.model.integrator = integrator;
  Simulator sim(scene.model, scene.solver);
  const auto velocity = [&](const State& before, int body) { return (sim.state().points[body].x() - before.points[body].x()) / h; };
  const double v_other = moving_plane ? -0.5 : 0.0;
  const double v_in = 1.0 - v_other;  // the approach speed
  // 0.25 s: the gap (7.5 cm at 1.5 m/s, 8 cm at 1 m/s) closes, the contact (< 10 ms) ends, and
  // the bodies fly apart.
  const int steps = static_cast<int>(std::lround(0.25 / h));
  State before = sim.state();
  for (int k = 0; k < steps; ++k) {
    before = sim.state();
    EXPECT_TRUE(sim.step().converged()) << "h " << h << " step " << k;
  }
  EXPECT_EQ(sim.contact_pairs(), 0);  // apart again
  const double v_puck = velocity(before, 0);
  const double v_after = moving_plane ? v_other : velocity(before, 1);
  if (momentum_error != nullptr && !moving_plane) *momentum_error = std::abs(0.1 * v_puck + 0.3 * v_after - 0.1);
  return (v_after - v_puck) / v_in;
}

TEST(ContactDampingScenes, FreeBodiesAndAMovingWallSeparateWithTheDeclaredRestitution) {
  const double e = 0.5, k = 1e4;
  const double zeta = -std::log(e) / std::sqrt(kPi * kPi + std::log(e) * std::log(e));
  for (const bool moving_plane : {false, true}) {
    const double mu = moving_plane ? 0.1 : 0.1 * 0.3 / 0.4;
    const double c = 2.0 * zeta * std::sqrt(k * mu);
    for (double h : {1e-3, 5e-4, 2.5e-4}) {
      SCOPED_TRACE(std::string(moving_plane ? "moving plane" : "free ball") + ", h = " + std::to_string(h));
      double momentum = 0.0;
      const double trapezoidal = separation_restitution(h, Integrator::kTrapezoidal, moving_plane, c, &momentum);
      const double undamped = separation_restitution(h, Integrator::kTrapezoidal, moving_plane, 0.0);
      const double euler = separation_restitution(h, Integrator::kBackwardEuler, moving_plane, c);
      std::printf("%s, c = %.4f N s/m, h = %.2e s: e trapezoidal %.5f (undamped %.5f), backward Euler %.5f\n",
                  moving_plane ? "puck on a moving plane" : "puck on a free ball", c, h, trapezoidal, undamped, euler);
      EXPECT_NEAR(trapezoidal, e, 0.05);
      EXPECT_GT(undamped, 0.99);
      // The dashpot's forces are equal and opposite: momentum is kept through the damped impact.
      if (!moving_plane) {
        EXPECT_LT(momentum, 1e-9);
      }
    }
  }
}

TEST(ContactDampingScenes, TheThreeBackEndsAgreeOnTheBounce) {
  // Ceres takes the damping as its residual √(c/h) nᵀ(p − p̂), Ipopt as a term of the objective:
  // the first 450 frames (the fall, the bounce at 0.30 s, the rise) within 1e-6 m of Newton's at the
  // tolerance 1e-9 (Ceres cannot reach the scene's 1e-12: README, "Back-ends").
  Scene scene = load_scene(std::string(LIEDYN_SOURCE_DIR) + "/problems/scenes/contact/puck_bounce.json");
  scene.solver.tolerance = 1e-9;
  const test::Trajectory newton = test::run_frames(scene.model, scene.solver, 450, "newton");
  for (const Backend b : {Backend::kCeres, Backend::kIpopt}) {
    SCOPED_TRACE(to_string(b));
    SolverOptions options = scene.solver;
    options.backend = b;
    const auto [dx, dR] = test::deviation(newton, test::run_frames(scene.model, options, 450, to_string(b)));
    EXPECT_LE(dx, 1e-6);
    EXPECT_LE(dR, 1e-6);
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

TEST(ContactAdjoint, TheDieThrowGradientRunsBackThroughContactDamping) {
  // The same throw (backward Euler) with a dashpot on
  // every sample, c = 2 N·s/m (ζ ≈ 0.06 per sample): the gradient runs back through
  // ContactDamping's mixed block too (without it: 2 % off). The zone is lagged, a jump in the
  // step map where a sample's previous penetration crosses 0; the central differences (1e-5
  // relative) stay clear of those on this run.
  Scene scene = load_scene(std::string(LIEDYN_SOURCE_DIR) +
                           "/problems/scenes/optimization/die_throw_contact.json");
  scene.model.bodies[0].contact.damping = 2.0;
  EXPECT_TRUE(test::gradient_agrees(scene));
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
  // Under the three integrators; under the trapezoidal rule also with contact damping (the
  // adjoint's history blocks, lib/adjoint.cpp, beside the contact terms' own). The trapezoidal
  // rod bounces on (its contact undamped or lightly damped), and its loss is far more curved:
  // differences of 1e-5 are off by their truncation (4e-3, damped 5e-2), those of 1e-6 by
  // 4.6e-5 and 2.8e-5 on the worst entry, one 0.6 % the size of the largest (3e-7 of it), as
  // at 1e-7 — so 1e-6, within 1e-4.
  // BDF2 damps the bounce as backward Euler does, and passes at backward Euler's defaults.
  for (const std::string integrator :
       {"backward_euler", "bdf2", "trapezoidal", "trapezoidal damped"}) {
    SCOPED_TRACE(integrator);
    Scene scene = parse_scene(text, "rod_on_floor");
    if (integrator == "bdf2") scene.model.integrator = Integrator::kBdf2;
    if (integrator.starts_with("trapezoidal")) scene.model.integrator = Integrator::kTrapezoidal;
    if (integrator == "trapezoidal damped") scene.model.rods[0].contact.damping = 0.5;
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
    if (!integrator.starts_with("trapezoidal")) {
      EXPECT_TRUE(test::gradient_agrees(scene, gamma));
    } else {
      EXPECT_TRUE(test::gradient_agrees(scene, gamma, 1e-6, 1e-4));
    }
  }
}

}  // namespace
}  // namespace liedyn::contact_scenes_tests

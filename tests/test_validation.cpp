// Validation against analytical mechanics (docs/design.md §13):
//   * torque-free asymmetric body vs the closed-form solution of Euler's equations
//     (Landau & Lifshitz, Mechanics §37): period of the body-frame angular velocity;
//   * kinetic energy of a free body never increases (backward Euler only dissipates);
//   * orientations stay on SO(3) over 10⁵ steps;
//   * the butterfly bolt (problems/scenes/butterfly_bolt.json) flips, one Newton update per step;
//   * compound pendulum period and heavy-top precession, the pivot being a stiff
//     zero-rest-length spring to a world anchor;
//   * the validation scenes shipped in problems/scenes/ run with every step converged.
//
// Every tolerance below is derived from the physics or from the order of the method and
// stated next to the assertion; the measured values are printed on stdout so that a
// failure shows by how much.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "lib/inertia.hpp"
#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

// Complete elliptic integral of the first kind K(k) (modulus k, 0 ≤ k < 1) by the
// arithmetic–geometric mean: K(k) = π / (2 AGM(1, √(1 − k²))). Converges quadratically;
// stop when the two means agree to round-off.
double elliptic_k(double k) {
  double a = 1.0;
  double b = std::sqrt(1.0 - k * k);
  for (int i = 0; i < 64 && std::abs(a - b) > 1e-15 * a; ++i) {
    const double mean = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = mean;
  }
  return std::numbers::pi / (2.0 * a);
}

// Time at which a sampled signal crosses zero between samples (t0, f0) and (t1, f1), by
// linear interpolation. Its error is O(h² f''/f') and f'' vanishes with f for the signals
// measured here, so interpolation is far below the discretisation errors being measured.
double crossing_time(double t0, double f0, double t1, double f1) {
  return t0 + (t1 - t0) * f0 / (f0 - f1);
}

Model free_body(double h, const Matrix3& inertia, const Matrix3& orientation,
                const Vector3& omega_world) {
  Model model;
  model.time_step = h;
  RigidBody body;
  body.name = "body";
  body.inertia = inertia;
  body.orientation = orientation;
  body.angular_velocity = omega_world;
  model.bodies.push_back(body);
  return model;
}

// A generic asymmetric body: principal moments 1 : 1.7 : 2.3 in axes not aligned with the
// body frame, so that every entry of I_b and J is non-zero.
Matrix3 generic_inertia() {
  const Matrix3 Q = so3::exp(Vector3(0.4, 0.9, -0.3));
  return Q * Vector3(1.0, 1.7, 2.3).asDiagonal() * Q.transpose();
}

// ---------------------------------------------------------------------------------------
// The AGM implementation of K itself, against known values: K(0) = π/2 and the
// lemniscatic case K(1/√2) = Γ(1/4)² / (4√π). Round-off level agreement is expected.
TEST(Validation, EllipticIntegralByAgm) {
  EXPECT_NEAR(elliptic_k(0.0), std::numbers::pi / 2.0, 1e-15);
  const double gamma_quarter = std::tgamma(0.25);
  EXPECT_NEAR(elliptic_k(std::sqrt(0.5)),
              gamma_quarter * gamma_quarter / (4.0 * std::sqrt(std::numbers::pi)), 1e-14);
  // Abramowitz & Stegun Table 17.1 (modular angle α, k = sin α): K(75°) = 2.7680631454,
  // K(85°) = 3.8317419998; 25-digit values from mpmath.ellipk.
  EXPECT_NEAR(elliptic_k(std::sin(75.0 * std::numbers::pi / 180.0)), 2.768063145368768, 1e-13);
  EXPECT_NEAR(elliptic_k(std::sin(85.0 * std::numbers::pi / 180.0)), 3.831741999784146, 1e-13);
}

// ---------------------------------------------------------------------------------------
// 1. Free asymmetric body vs Euler's equations in closed form.
//
// With I1 < I2 < I3 and L² > 2E I2 (rotation about the major axis), Landau & Lifshitz §37:
//   ω2(t) = √((2E I3 − L²)/(I2 (I3 − I2))) sn τ,   τ = t √((I3 − I2)(L² − 2E I1)/(I1 I2 I3)),
//   k²    = (I2 − I1)(2E I3 − L²) / ((I3 − I2)(L² − 2E I1)),
// so ω2 has period T = 4 K(k) √(I1 I2 I3 / ((I3 − I2)(L² − 2E I1))). Starting with ω2 = 0
// puts t = 0 at a zero of sn; ω2 then crosses zero downwards at T/2 and upwards at T.
//
// Backward Euler dissipates energy (about 2|ω|²h per unit time), and T depends on E and L,
// so the numerical period is compared with the closed form for the INITIAL E and L, over
// the FIRST period only: the drift of E and L within it is an O(h) error, like the method's
// own, and both vanish as h → 0. Hence T(h) = T + a h + O(h²): successive errors halve
// with h, and the Richardson value 2T(h/2) − T(h) removes the O(h) term.
struct FreeBodyPeriod {
  double period = 0.0;      // time of the second zero crossing of ω_b,2 after t = 0
  double half_period = 0.0;  // time of the first (downward) one
  bool first_downward = false;
  int unconverged = 0;
};

FreeBodyPeriod measure_free_body_period(double h, const Vector3& principal,
                                        const Vector3& omega_body, double t_max) {
  const Matrix3 R0 = so3::exp(Vector3(0.3, -0.2, 0.5));  // generic initial orientation
  Model model = free_body(h, principal.asDiagonal(), R0, R0 * omega_body);
  SolverOptions options;
  // The period is the quantity measured, so solve each step well below the O(h²)
  // remainder we resolve (1e-4 relative): ‖δ‖∞ ≤ 1e-10 rad per step. (Tighter tolerances
  // run into the line-search round-off issue documented in DISABLED_TightTolerance... below.)
  options.tolerance = 1e-10;
  Simulator sim(model, options);

  FreeBodyPeriod result;
  int crossings = 0;
  double previous = 0.0;
  const int steps = static_cast<int>(t_max / h);
  for (int k = 1; k <= steps && crossings < 2; ++k) {
    if (!sim.step().converged()) ++result.unconverged;
    // Body-frame angular velocity ω_b = Rᵀ ω_world (the same for R_k and R_{k−1}, since
    // ΔR_k leaves its own axis fixed).
    const double w2 = (sim.state().rotations[0].transpose() * sim.angular_velocity(0))(1);
    if (k > 1 && (previous < 0.0) != (w2 < 0.0)) {
      const double t = crossing_time((k - 1) * h, previous, k * h, w2);
      if (++crossings == 1) {
        result.half_period = t;
        result.first_downward = previous > 0.0;
      } else {
        result.period = t;
      }
    }
    previous = w2;
  }
  return result;
}

TEST(Validation, FreeBodyPeriodMatchesEulerClosedForm) {
  const double I1 = 1.0, I2 = 2.0, I3 = 3.0;
  const Vector3 principal(I1, I2, I3);
  const Vector3 omega_body(0.6, 0.0, 0.8);  // ω2 = 0: t = 0 is a zero of sn
  const double two_E = omega_body.dot(principal.cwiseProduct(omega_body));
  const double L2 = principal.cwiseProduct(omega_body).squaredNorm();
  ASSERT_GT(L2, two_E * I2) << "closed form below assumes rotation about the major axis";
  const double k2 = (I2 - I1) * (two_E * I3 - L2) / ((I3 - I2) * (L2 - two_E * I1));
  const double T_exact =
      4.0 * elliptic_k(std::sqrt(k2)) * std::sqrt(I1 * I2 * I3 / ((I3 - I2) * (L2 - two_E * I1)));
  std::printf("free body: k² = %.6f, closed-form period T = %.10f s\n", k2, T_exact);

  const std::vector<double> steps = {4e-3, 2e-3, 1e-3, 5e-4};
  std::vector<double> periods;
  for (double h : steps) {
    const FreeBodyPeriod m = measure_free_body_period(h, principal, omega_body, 2.0 * T_exact);
    EXPECT_EQ(m.unconverged, 0) << "h = " << h;
    ASSERT_GT(m.period, 0.0) << "no full period of ω_b,2 measured at h = " << h;
    // The first crossing is the downward one near T/2 (ω̇2 = (I3 − I1) ω3 ω1 / I2 > 0 at 0).
    EXPECT_TRUE(m.first_downward) << "h = " << h;
    EXPECT_NEAR(m.half_period / T_exact, 0.5, 0.02) << "h = " << h;
    std::printf("  h = %-7g T(h) = %.10f  relative error %+.4e\n", h, m.period,
                m.period / T_exact - 1.0);
    periods.push_back(m.period);
  }
  // First order: error(h) / error(h/2) = 2 (1 + O(h)). The O(h) correction is the size of
  // the second-order remainder relative to the first-order error, which the Richardson
  // check below bounds by 1e-4 / 1e-3 ≈ 0.1 at the coarsest h; the band 2 ± 0.1 still
  // rejects any other order (√2 for order ½, 4 for order 2).
  for (std::size_t i = 1; i < periods.size(); ++i) {
    const double ratio = (periods[i - 1] - T_exact) / (periods[i] - T_exact);
    std::printf("  error ratio h = %g → %g: %.5f\n", steps[i - 1], steps[i], ratio);
    EXPECT_NEAR(ratio, 2.0, 0.1) << "h = " << steps[i - 1] << " → " << steps[i];
  }
  // Richardson: 2T(h/2) − T(h) = T + O(h²); with the finest pair (h = 1e-3, 5e-4) the
  // remainder must be below 1e-4 relative (the brief's accuracy target; the O(h) error
  // being removed is 3e-3 at h = 1e-3, so this is a 30× reduction or better).
  const std::size_t n = periods.size();
  const double richardson = 2.0 * periods[n - 1] - periods[n - 2];
  std::printf("  Richardson 2T(h/2) − T(h) = %.10f  relative error %+.3e\n", richardson,
              richardson / T_exact - 1.0);
  EXPECT_NEAR(richardson / T_exact, 1.0, 1e-4);
}

// ---------------------------------------------------------------------------------------
// 2. Free body: backward Euler never gains energy.
//
// Two energies are checked every frame:
//   * the reported one, ½ ωᵀ (R I_b Rᵀ) ω with ω = log(ΔR_k)/h (Simulator::kinetic_energy);
//   * the discrete one of the incremental potential, ‖(R_k − R_{k−1}) J^½‖²_F / (2h²).
// Both are expected to decrease monotonically; round-off in either is ~1e-15 relative, so
// an increase beyond 1e-12 relative is a real gain. The decrease per step is O((|ω|h)²)
// relative (≥ 1.6e-4 in these runs), far above the effect of the Newton tolerance
// (≤ 1e-9 rad per step, i.e. ≤ 1e-9/(|ω|h) relative in ω), so the check is not masked by
// solver noise.
struct EnergyRun {
  int steps = 0;
  int unconverged = 0;
  int reported_increases = 0, discrete_increases = 0;
  double max_reported_change = -1.0, max_discrete_change = -1.0;  // relative, per step
  double first_energy = 0.0, last_energy = 0.0;
};

EnergyRun run_energy(double h, const Vector3& omega, int steps) {
  const Matrix3 I = generic_inertia();
  const Matrix3 J = rotational_mass(I);
  Model model = free_body(h, I, so3::exp(Vector3(-0.2, 0.1, 0.7)), omega);
  // Library default tolerance: see DISABLED_TightToleranceDoesNotStall below for why
  // tighter tolerances are not used at h = 0.1.
  Simulator sim(model, SolverOptions{});
  auto discrete = [&](const Matrix3& R, const Matrix3& R_previous) {
    const Matrix3 D = R - R_previous;
    return (D * J * D.transpose()).trace() / (2.0 * h * h);
  };
  EnergyRun run;
  run.steps = steps;
  double E = sim.kinetic_energy();
  double E_discrete = discrete(sim.state().rotations[0],
                               sim.last_step().rotations[0].transpose() * sim.state().rotations[0]);
  run.first_energy = E;
  for (int k = 1; k <= steps; ++k) {
    const Matrix3 R_previous = sim.state().rotations[0];
    if (!sim.step().converged()) ++run.unconverged;
    const double E_next = sim.kinetic_energy();
    const double E_discrete_next = discrete(sim.state().rotations[0], R_previous);
    const double change = (E_next - E) / E;
    const double change_discrete = (E_discrete_next - E_discrete) / E_discrete;
    if (change > 1e-12) ++run.reported_increases;
    if (change_discrete > 1e-12) ++run.discrete_increases;
    run.max_reported_change = std::max(run.max_reported_change, change);
    run.max_discrete_change = std::max(run.max_discrete_change, change_discrete);
    E = E_next;
    E_discrete = E_discrete_next;
  }
  run.last_energy = E;
  return run;
}

void expect_monotone(const EnergyRun& run, const char* label) {
  std::printf("%s: %d steps, KE %.6g → %.6g, largest per-step relative change: reported %+.3e, "
              "discrete %+.3e\n",
              label, run.steps, run.first_energy, run.last_energy, run.max_reported_change,
              run.max_discrete_change);
  EXPECT_EQ(run.unconverged, 0) << label;
  EXPECT_EQ(run.reported_increases, 0) << label << ": largest relative increase of ½ωᵀIω "
                                       << run.max_reported_change;
  EXPECT_EQ(run.discrete_increases, 0)
      << label << ": largest relative increase of ‖ΔR J^½‖²/(2h²) " << run.max_discrete_change;
  // It does dissipate (otherwise "never increases" would be vacuous).
  EXPECT_LT(run.last_energy, run.first_energy) << label;
}

TEST(Validation, FreeBodyKineticEnergyNeverIncreases) {
  // Moderate: |ω| h = 0.026 rad per step.
  expect_monotone(run_energy(0.01, Vector3(0.7, -1.3, 2.1), 5000), "h = 0.01, |ω| = 2.6");
  // Large step, fast spin: |ω| h = 2.6 rad per step (close to the log's cut at π).
  expect_monotone(run_energy(0.1, Vector3(7.0, -13.0, 21.0), 3000), "h = 0.1, |ω| = 26");
}

// ---------------------------------------------------------------------------------------
// 3. Orientation stays on SO(3): 10⁵ steps of a fast-spinning generic body (|ω| h ≈ 0.25
// rad per step initially). Each Newton update and the step extrapolation re-orthonormalise
// (docs/design.md §2.3), which keeps the error at round-off, ~1e-16 per entry; 1e-12 leaves
// room for the norms of a 3×3 matrix and slow accumulation, yet catches any drift: without
// re-orthonormalisation the R̃ = 2R_{k−1} − R_{k−2} extrapolation amplifies round-off from
// step to step (docs/design.md §2.3 reports blow-up within ~50 steps at h = 0.01).
TEST(Validation, FreeBodyOrientationStaysOrthonormal) {
  Model model = free_body(0.01, generic_inertia(), so3::exp(Vector3(1.0, -2.0, 0.5)),
                          Vector3(9.0, -14.0, 19.0));
  Simulator sim(model, SolverOptions{});
  double worst_orthogonality = 0.0, worst_determinant = 0.0;
  int unconverged = 0;
  for (int k = 1; k <= 100000; ++k) {
    if (!sim.step().converged()) ++unconverged;
    const Matrix3& R = sim.state().rotations[0];
    worst_orthogonality =
        std::max(worst_orthogonality, (R.transpose() * R - Matrix3::Identity()).norm());
    worst_determinant = std::max(worst_determinant, std::abs(R.determinant() - 1.0));
  }
  std::printf("10⁵ steps: max ‖RᵀR − I‖_F = %.3e, max |det R − 1| = %.3e\n", worst_orthogonality,
              worst_determinant);
  EXPECT_EQ(unconverged, 0);
  EXPECT_EQ(sim.frame(), 100000);
  EXPECT_LT(worst_orthogonality, 1e-12);
  EXPECT_LT(worst_determinant, 1e-12);
}

// ---------------------------------------------------------------------------------------
// 4. Butterfly bolt (paper Fig. 4): spin started close to the intermediate principal axis.
// The body-frame angular momentum L_b = I_b Rᵀ ω along that axis must change sign (the
// flip) within the scene's 1000 frames and swing to the other side, i.e. reach at least
// half of −|L_b| (a wobble that merely crosses zero would not); and the paper's claim
// holds: with Lie derivatives one Newton update per step meets the tolerance.
TEST(Validation, ButterflyBoltFlipsWithOneNewtonIterationPerStep) {
  Scene scene = load_scene(LIEDYN_SOURCE_DIR "/problems/scenes/butterfly_bolt.json");
  ASSERT_EQ(scene.model.bodies.size(), 1u);
  scene.solver.max_iterations = 1;
  const Matrix3 I = scene.model.bodies[0].inertia;
  Eigen::SelfAdjointEigenSolver<Matrix3> eig(I);  // ascending eigenvalues
  const Vector3 intermediate = eig.eigenvectors().col(1);

  Simulator sim(scene.model, scene.solver);
  const auto L_body = [&] {
    return Vector3(I * (sim.state().rotations[0].transpose() * sim.angular_velocity(0)));
  };
  const double L0 = L_body().dot(intermediate);
  ASSERT_GT(std::abs(L0), 0.9 * L_body().norm()) << "scene should start near the intermediate axis";

  int unconverged = 0, first_unconverged = -1, flip_frame = -1;
  double most_reversed = 0.0;  // min over frames of sign(L0) L_b·e_int / |L_b|
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport report = sim.step();
    ASSERT_TRUE(report.state_updated()) << "frame " << k << ": " << to_string(report.status);
    if (!report.converged()) {
      ++unconverged;
      if (first_unconverged < 0) first_unconverged = k;
    }
    const Vector3 L = L_body();
    const double along = std::copysign(1.0, L0) * L.dot(intermediate);
    if (along < 0.0 && flip_frame < 0) flip_frame = k;
    most_reversed = std::min(most_reversed, along / L.norm());
  }
  std::printf("butterfly bolt: flip at frame %d of %d, most reversed L_int/|L| = %.4f, "
              "unconverged steps with max_iterations = 1: %d\n",
              flip_frame, scene.frames, most_reversed, unconverged);
  EXPECT_GT(flip_frame, 0) << "no flip within " << scene.frames << " frames";
  EXPECT_LT(most_reversed, -0.5);
  EXPECT_EQ(unconverged, 0) << "first unconverged step: frame " << first_unconverged;
}

// ---------------------------------------------------------------------------------------
// 5a. Compound pendulum hanging from a world anchor by a stiff zero-rest-length spring.
//
// Body: m = 1 kg, I = 0.1 kg m² about the swing axis (y), pivot point L = 0.5 m above the
// centre of mass, released from rest at θ0 = 0.02 rad in the x-z plane. Rigid pivot,
// small amplitude: T_c = 2π √((I + mL²)/(m g L)) = 1.6784 s. Two small, known corrections
// make the reference T_ref the test compares with:
//   * amplitude: T = T_c (1 + θ0²/16 + O(θ0⁴)) = T_c (1 + 2.5e-5);
//   * spring compliance: the pivot moves. With a zero-rest-length spring the potential is
//     ½k‖p‖², exactly separable, and the linearised (pivot x, θ) system has mass matrix
//     [[m, mL], [mL, I + mL²]] and stiffness diag(k, mgL); its low root is
//     ω² ≈ ω_c² (1 − (m/k) ω_c² mL²/(I + mL²)): +5e-7 on T at k = 1e7 N/m.
//   k = 1e7 N/m keeps the sag mg/k ≈ 1e-6 m and the compliance correction 5e-7, while
//   √(k/m) = 3162 rad/s is only ~1000 ω_c; backward Euler damps that mode (h √(k/m) ≥ 3) and
//   the Newton system stays well conditioned (kh²/m ≤ 160 against m/h²).
//
// Order of convergence. For the linear(ised) oscillator backward Euler multiplies the
// mode by 1/(1 − iωh) per step: the amplitude decays at first order, but the phase advance
// is atan(ωh) = ωh (1 − (ωh)²/3 + …). Zero crossings do not see the amplitude, so the
// measured period converges at SECOND order, T_BE(h) = 2πh / atan(ω h) = T (1 + (ωh)²/3):
// the error ratio on halving h is 4, not 2. (The free body's period is first order only
// because there the period depends on E and L, which the dissipation changes at O(h).)
// The test asserts the order and the exact discrete period T_BE(h).
TEST(Validation, CompoundPendulumPeriod) {
  const double m = 1.0, L = 0.5, g = 9.81, I = 0.1, k = 1e7, theta0 = 0.02;
  const double T_compound = 2.0 * std::numbers::pi * std::sqrt((I + m * L * L) / (m * g * L));
  // Low root of det(K − ω² M) = 0 for M = [[m, mL], [mL, I + mL²]], K = diag(k, mgL).
  const double qa = m * (I + m * L * L) - m * m * L * L;
  const double qb = -(k * (I + m * L * L) + m * m * g * L);
  const double qc = k * m * g * L;
  const double omega2 = (-qb - std::sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa);
  const double T_ref = 2.0 * std::numbers::pi / std::sqrt(omega2) * (1.0 + theta0 * theta0 / 16.0);
  const double omega_ref = 2.0 * std::numbers::pi / T_ref;
  std::printf("pendulum: T_compound = %.10f s, T_ref = %.10f s (%+.3e)\n", T_compound, T_ref,
              T_ref / T_compound - 1.0);
  // The reference IS the compound-pendulum period up to the two documented corrections.
  ASSERT_NEAR(T_ref / T_compound - 1.0, theta0 * theta0 / 16.0, 1e-6);

  const std::vector<double> steps = {4e-3, 2e-3, 1e-3};
  std::vector<double> errors, periods;
  for (double h : steps) {
    Model model;
    model.time_step = h;
    model.gravity = Vector3(0.0, 0.0, -g);
    RigidBody body;
    body.name = "pendulum";
    body.mass = m;
    body.inertia = Vector3(0.1, I, 0.02).asDiagonal();
    body.orientation = so3::exp(Vector3(0.0, theta0, 0.0));
    // Pivot at its static position (spring stretched by the weight): only the swing mode
    // is excited.
    const Vector3 pivot(0.0, 0.0, -m * g / k);
    body.position = pivot - body.orientation * Vector3(0.0, 0.0, L);
    model.bodies.push_back(body);
    SpringSpec spring;
    spring.a.body = -1;  // world anchor at the origin
    spring.b.body = 0;
    spring.b.point = Vector3(0.0, 0.0, L);
    spring.stiffness = k;
    spring.rest_length = 0.0;
    model.springs.push_back(spring);
    SolverOptions options;
    options.tolerance = 1e-10;
    Simulator sim(model, options);

    std::vector<double> crossings;
    double previous = theta0;
    int unconverged = 0;
    for (int n = 1; n <= static_cast<int>(2.0 * T_ref / h) && crossings.size() < 3; ++n) {
      if (!sim.step().converged()) ++unconverged;
      const Matrix3& R = sim.state().rotations[0];
      const double theta = std::atan2(R(0, 2), R(2, 2));  // tilt of the body z axis about y
      if ((theta < 0.0) != (previous < 0.0)) {
        crossings.push_back(crossing_time((n - 1) * h, previous, n * h, theta));
      }
      previous = theta;
    }
    EXPECT_EQ(unconverged, 0) << "h = " << h;
    ASSERT_EQ(crossings.size(), 3u) << "h = " << h;
    const double T = crossings[2] - crossings[0];
    const double T_be = T_ref * omega_ref * h / std::atan(omega_ref * h);
    std::printf("  h = %-6g T(h) = %.10f  error vs T_ref %+.4e, vs T_BE(h) %+.3e\n", h, T,
                T / T_ref - 1.0, T / T_be - 1.0);
    // Exact discrete period of backward Euler. Left-over effects: the amplitude decays by
    // exp(−π ω h) ≈ 5 % per period at h = 4e-3, which lowers the θ0²/16 term by ~1e-6;
    // the O(θ0⁴) amplitude term is 6e-10. Hence 2e-6, ~10× below the smallest second-order
    // error tested (4.7e-6 at h = 1e-3) and ~40× below the first-order error a
    // phase-lagging scheme would show (ωh/2 ≈ 2e-3 at h = 1e-3).
    EXPECT_NEAR(T / T_be, 1.0, 2e-6) << "h = " << h;
    errors.push_back(T / T_ref - 1.0);
    periods.push_back(T);
  }
  for (std::size_t i = 1; i < errors.size(); ++i) {
    const double ratio = errors[i - 1] / errors[i];
    std::printf("  error ratio h = %g → %g: %.4f\n", steps[i - 1], steps[i], ratio);
    // Second order: 4 ± 0.5. The ±2e-6 of the line above is ≤ 10 % of the errors here.
    EXPECT_NEAR(ratio, 4.0, 0.5);
  }
  // Second-order Richardson (4T(h/2) − T(h))/3 removes the (ωh)²/3 term: what is left is the
  // ~1e-6 amplitude-decay effect discussed above.
  const std::size_t n = periods.size();
  const double richardson = (4.0 * periods[n - 1] - periods[n - 2]) / 3.0;
  std::printf("  Richardson (4T(h/2) − T(h))/3 = %.10f  error vs T_ref %+.3e, vs T_compound "
              "%+.3e\n",
              richardson, richardson / T_ref - 1.0, richardson / T_compound - 1.0);
  EXPECT_NEAR(richardson / T_ref, 1.0, 2e-6);
}

// ---------------------------------------------------------------------------------------
// 5b. Heavy symmetric top with its tip held at a world anchor by a stiff spring.
//
// m = 1 kg, I1 = I2 = 0.02, I3 = 0.036 kg m² (about the centre of mass), tip l = 0.1 m below
// the centre of mass on the symmetry axis a, tilt θ = 0.5 rad, spin ω3 = a·ω = 30 rad/s.
// Gyroscopic approximation: Ω_g = m g l / (I3 ω3) = 0.908 rad/s. Exact steady precession
// (torque balance dL/dt = Ω ẑ × L): m g l = Ω (I3 ω3 − I1' Ω cos θ), I1' = I1 + m l², whose slow
// root is Ω_e = Ω_g (1 + ε + 2ε² + …) with ε = I1' cos θ Ω_g / (I3 ω3) = 2.2 %: the
// gyroscopic formula's relative error is O(precession/spin), here ε ≈ 0.022.
//
// The top starts in exact steady precession (ω = (ω3 − Ω_e cos θ) a + Ω_e ẑ, v = ω × l a), so
// there is no nutation to average out. Backward Euler damps the spin at a relative rate
// ≈ ω3² h per unit time (2 % over the 1 s window at h = 2.5e-5); the precession follows the
// current spin adiabatically (the spin changes over seconds, the nutation period is
// 2π I1'/(I3 ω3) = 0.17 s), so the references use the measured ω3(t), averaged over the
// window: Ω_g = ⟨m g l/(I3 ω3(t))⟩ and Ω_e = ⟨Ω_e(ω3(t))⟩.
// Spring: k = 1e7 N/m, √(k/m) = 3162 rad/s ≫ nutation frequency I3 ω3/I1' = 36 rad/s, so
// compliance enters as (36/3162)² ≈ 1e-4; sag mg/k = 1e-6 m = 1e-5 l; kh²/m = 6e-3, so
// the spring barely changes the Newton system (m/h² dominates).
TEST(Validation, HeavyTopPrecession) {
  const double m = 1.0, l = 0.1, g = 9.81, I1 = 0.02, I3 = 0.036, k = 1e7, tilt = 0.5;
  const double w3 = 30.0, h = 2.5e-5, window = 1.0;
  const double I1p = I1 + m * l * l, mgl = m * g * l, c = std::cos(tilt);
  const auto steady = [&](double spin) {  // slow root of m g l = Ω (I3 ω3 − I1' Ω cos θ)
    return (I3 * spin - std::sqrt(I3 * I3 * spin * spin - 4.0 * I1p * c * mgl)) / (2.0 * I1p * c);
  };
  const double Omega0 = steady(w3);
  const double epsilon = I1p * c * (mgl / (I3 * w3)) / (I3 * w3);

  Model model;
  model.time_step = h;
  model.gravity = Vector3(0.0, 0.0, -g);
  RigidBody body;
  body.name = "top";
  body.mass = m;
  body.inertia = Vector3(I1, I1, I3).asDiagonal();
  body.orientation = so3::exp(Vector3(tilt, 0.0, 0.0));
  const Vector3 a = body.orientation * Vector3::UnitZ();
  const Vector3 tip(0.0, 0.0, -m * g / k);  // static sag of the tip
  body.position = tip + l * a;
  body.angular_velocity = (w3 - Omega0 * c) * a + Omega0 * Vector3::UnitZ();
  body.linear_velocity = body.angular_velocity.cross(l * a);
  model.bodies.push_back(body);
  SpringSpec spring;
  spring.a.body = -1;
  spring.b.body = 0;
  spring.b.point = Vector3(0.0, 0.0, -l);
  spring.stiffness = k;
  spring.rest_length = 0.0;
  model.springs.push_back(spring);
  SolverOptions options;
  options.tolerance = 1e-10;
  Simulator sim(model, options);

  const int steps = static_cast<int>(std::lround(window / h));
  double azimuth = std::atan2(a.y(), a.x());
  const double azimuth0 = azimuth;
  double sum_gyroscopic = 0.0, sum_exact = 0.0, max_tilt_error = 0.0, spin = w3;
  int unconverged = 0;
  for (int n = 1; n <= steps; ++n) {
    if (!sim.step().converged()) ++unconverged;
    const Vector3 axis = sim.state().rotations[0].col(2);
    double d = std::atan2(axis.y(), axis.x()) - std::remainder(azimuth, 2.0 * std::numbers::pi);
    azimuth += std::remainder(d, 2.0 * std::numbers::pi);  // unwrap
    spin = axis.dot(sim.angular_velocity(0));
    sum_gyroscopic += mgl / (I3 * spin);
    sum_exact += steady(spin);
    max_tilt_error = std::max(max_tilt_error, std::abs(std::acos(axis.z()) - tilt));
  }
  const double measured = (azimuth - azimuth0) / (steps * h);
  const double gyroscopic = sum_gyroscopic / steps;
  const double exact = sum_exact / steps;
  std::printf("heavy top: h = %g, %d steps; ω3 %.4f → %.4f rad/s (%+.2f %%)\n", h, steps, w3,
              spin, 100.0 * (spin / w3 - 1.0));
  std::printf("  precession measured %.6f rad/s; gyroscopic ⟨mgl/(I3 ω3)⟩ %.6f (%+.4e, ε = "
              "%.4e); exact steady root %.6f (%+.3e); max |tilt − θ| %.2e rad\n",
              measured, gyroscopic, measured / gyroscopic - 1.0, epsilon, exact,
              measured / exact - 1.0, max_tilt_error);
  EXPECT_EQ(unconverged, 0);
  // Preconditions of the comparison: the spin decays slowly (adiabatic), the top neither
  // falls nor nutates appreciably (a 1 % change of tilt would change ε by < 1e-4 relative).
  ASSERT_GT(spin / w3, 0.95);
  EXPECT_LT(max_tilt_error, 5e-3);
  // Gyroscopic approximation: low by ε + O(ε²) (ε² = 5e-4); the band [ε/2, 3ε/2] checks both
  // the value m g l/(I3 ω3) and the sign and size of its leading correction.
  EXPECT_GT(measured / gyroscopic - 1.0, 0.5 * epsilon);
  EXPECT_LT(measured / gyroscopic - 1.0, 1.5 * epsilon);
  // Exact steady precession: 1e-3 ≈ ε/20 bounds the numerical error left once the spin decay
  // is accounted for (other O(h) damping, the half-step lag of ω = log(ΔR)/h, spring
  // compliance ~1e-4), and distinguishes the exact root from the gyroscopic value.
  EXPECT_NEAR(measured / exact, 1.0, 1e-3);
}

// ---------------------------------------------------------------------------------------
// The validation scenes shipped in problems/scenes/ load and run with every step converged
// (what `liedyn simulate` requires for exit status 0).
TEST(Validation, ValidationScenesRunWithEveryStepConverged) {
  for (const char* name : {"free_body", "pendulum", "heavy_top"}) {
    SCOPED_TRACE(name);
    const Scene scene =
        load_scene(std::string(LIEDYN_SOURCE_DIR "/problems/scenes/") + name + ".json");
    EXPECT_FALSE(scene.description.empty());
    Simulator sim(scene.model, scene.solver);
    int unconverged = 0;
    for (int k = 1; k <= scene.frames; ++k) {
      const StepReport report = sim.step();
      ASSERT_TRUE(report.state_updated()) << "frame " << k << ": " << to_string(report.status);
      if (!report.converged()) ++unconverged;
    }
    EXPECT_EQ(unconverged, 0);
    EXPECT_EQ(sim.frame(), scene.frames);
  }
}

// ---------------------------------------------------------------------------------------
// Regression: tight Newton tolerances must converge, not stall on round-off. At convergence
// the Newton decrease ½ gᵀδ (~1e-18 here) is far below the round-off of
// Ψ = ‖(R − R̃) J^½‖²/(2h²), which is ~eps ‖R − R̃‖ ‖J‖/h² in absolute terms (R − R̃ cancels
// O(1) entries). A line search that allowed only 64 eps |Ψ| failed with line_search_failed
// after ~200 frames at h = 0.1, tolerance 1e-10, and hit max_iterations at h = 0.01,
// tolerance 1e-12; the allowance is now estimated from the terms (IncrementalPotential::assemble).
TEST(Validation, TightToleranceDoesNotStall) {
  struct Case {
    double h, tolerance;
    int frames;
  };
  for (const Case c : {Case{0.1, 1e-10, 300}, Case{0.01, 1e-12, 300}}) {
    Model model = free_body(c.h, generic_inertia(), so3::exp(Vector3(-0.2, 0.1, 0.7)),
                            Vector3(0.7, -1.3, 2.1));
    SolverOptions options;
    options.tolerance = c.tolerance;
    Simulator sim(model, options);
    for (int k = 1; k <= c.frames; ++k) {
      const StepReport report = sim.step();
      ASSERT_TRUE(report.converged())
          << "h = " << c.h << ", tolerance " << c.tolerance << ", frame " << k << ": "
          << to_string(report.status) << " after " << report.iterations
          << " iterations, ‖δ‖∞ = " << report.step_norm << ", ‖g‖ = " << report.gradient_norm;
    }
  }
}

}  // namespace
}  // namespace liedyn

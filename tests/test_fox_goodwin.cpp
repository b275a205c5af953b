// The fox_goodwin integrator (Model::Integrator; docs/design.md §14.2): Newmark's β = 1/12,
// fourth order in the phase of an oscillation and stable for ωh < √6 — the phase measured on a
// linear oscillator against the scheme's closed form and the trapezoidal rule's, the stability
// bound estimated (lib/stability.hpp) against a dense eigensolver and enforced at its edge, and
// what the integrator refuses. Its discrete equations, adjoint blocks, back-ends and restarts
// are tested with the trapezoidal rule's (test_integrators.cpp, test_adjoint.cpp).

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "lib/incremental_potential.hpp"
#include "lib/stability.hpp"
#include "models.hpp"
#include "problems/scene.hpp"
#include "problems/scene_settings.hpp"
#include "rod_models.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems" / "scenes";

// A body of mass 2 kg on a zero-length spring of 200 N/m to the origin, ẍ = −ω² x with
// ω = 10 rad/s exactly (the spring's force k (x − 0) is linear), on an ellipse that never
// passes through the spring's anchor.
constexpr double kOmega = 10.0;

Model oscillator(Integrator integrator, double h) {
  Model model;
  model.time_step = h;
  model.integrator = integrator;
  RigidBody b;
  b.name = "mass";
  b.mass = 2.0;
  b.inertia = Vector3(0.1, 0.2, 0.3).asDiagonal();
  b.position = Vector3(0.1, 0.0, 0.0);
  b.linear_velocity = Vector3(0.0, 0.5, 0.0);
  model.bodies.push_back(b);
  SpringSpec s;
  s.a = BodyPoint{-1, Vector3::Zero()};
  s.b = BodyPoint{0, Vector3::Zero()};
  s.stiffness = 200.0;
  s.rest_length = 0.0;
  model.springs.push_back(s);
  return model;
}

// The scheme's frequency Ω from its states: a linear two-step scheme gives
// x_{k+1} + x_{k−1} = 2 cos(Ωh) x_k for k ≥ 1, here fitted by least squares over 200 steps.
double measured_frequency(Integrator integrator, double h) {
  SolverOptions options;
  options.tolerance = 1e-13;
  Simulator sim(oscillator(integrator, h), options);
  std::vector<Vector3> x = {sim.state().points[0]};
  for (int k = 1; k <= 200; ++k) {
    EXPECT_TRUE(sim.step().converged()) << k;
    x.push_back(sim.state().points[0]);
  }
  double across = 0.0, along = 0.0;
  for (std::size_t k = 1; k + 1 < x.size(); ++k) {
    across += (x[k + 1] + x[k - 1]).dot(x[k]);
    along += 2.0 * x[k].squaredNorm();
  }
  return std::acos(across / along) / h;
}

// Newmark (γ = ½) on ẍ = −ω² x: (1 + βs) (x_{k+1} + x_{k−1}) = (2 − (1 − 2β) s) x_k, s = (ωh)².
double closed_form_frequency(double beta, double h) {
  const double s = kOmega * kOmega * h * h;
  return std::acos((2.0 - (1.0 - 2.0 * beta) * s) / (2.0 * (1.0 + beta * s))) / h;
}

// The oscillation's frequency is the scheme's closed form to round-off, and its error falls
// 16× per halving of h (Fox–Goodwin: −(ωh)⁴/480 relative), the trapezoidal rule's 4×
// (−(ωh)²/12): at ωh = 0.4 already 40× less.
TEST(FoxGoodwin, OscillatesAtItsClosedFormFrequencyWithAFourthOrderPhaseError) {
  std::vector<double> fox, trapezoid;
  for (const double h : {0.04, 0.02, 0.01}) {
    const double omega_fox = measured_frequency(Integrator::kFoxGoodwin, h);
    const double omega_trapezoid = measured_frequency(Integrator::kTrapezoidal, h);
    EXPECT_NEAR(omega_fox, closed_form_frequency(1.0 / 12.0, h), 1e-9 * kOmega) << h;
    EXPECT_NEAR(omega_trapezoid, closed_form_frequency(0.25, h), 1e-9 * kOmega) << h;
    fox.push_back(std::abs(omega_fox - kOmega) / kOmega);
    trapezoid.push_back(std::abs(omega_trapezoid - kOmega) / kOmega);
    const double s = kOmega * h;
    std::printf("ωh = %.2f: relative frequency error fox_goodwin %.3e ((ωh)⁴/480 = %.3e), "
                "trapezoidal %.3e ((ωh)²/12 = %.3e)\n",
                s, fox.back(), std::pow(s, 4) / 480.0, trapezoid.back(), s * s / 12.0);
    EXPECT_NEAR(fox.back(), std::pow(s, 4) / 480.0, 0.1 * fox.back()) << h;
  }
  EXPECT_GE(trapezoid[0] / fox[0], 40.0);
  for (std::size_t i = 1; i < fox.size(); ++i) {
    EXPECT_NEAR(fox[i - 1] / fox[i], 16.0, 1.0) << i;
    EXPECT_NEAR(trapezoid[i - 1] / trapezoid[i], 4.0, 0.2) << i;
  }
}

// (ωh)² of the stiffest mode against Eigen's dense generalised eigensolver, K v = s (M/h²) v,
// on the component's own Hessians: a spring chain of three bodies (points and rotations,
// 18 DOFs: Lanczos is exact there) and a free 60-edge rod (363 DOFs, more than the iterations
// Lanczos takes: the largest Ritz value from below, within the top of the rod's spectrum).
TEST(FoxGoodwin, TheStiffestModeIsTheDenseEigensolversLargest) {
  Model chain = test_models::spring_chain(3);
  Model rod;
  rod.time_step = 1e-3;
  rod.rods.push_back(test_models::uniform_rod(60, 1.0, 0.1, 0.01, 4e2, 1e2, 0.5));
  for (Model* model : {&chain, &rod}) {
    model->integrator = Integrator::kFoxGoodwin;
    const std::vector<Component> components = build_components(*model);
    ASSERT_EQ(components.size(), 1u);
    const Component& c = components[0];
    const State q = model->initial_state();
    // K: the potential's Hessian less the inertia's, over the state weight β; M/h²: the
    // inertia terms' Hessian at R = R̃ (the first step's: begin_step sets R̃ = R_0).
    IncrementalPotential P = c.potential;
    Step still = model->initial_step();
    for (Vector3& x : still.points) x.setZero();
    for (Matrix3& R : still.rotations) R.setIdentity();
    P.begin_step(q, still);
    Eigen::VectorXd g(c.dofs);
    Eigen::MatrixXd H(c.dofs, c.dofs), M = Eigen::MatrixXd::Zero(c.dofs, c.dofs);
    P.assemble(q, g, H);
    for (const TranslationalInertia& t : P.terms<TranslationalInertia>()) {
      M.block<3, 3>(t.offsets[0], t.offsets[0]) = t.mass_over_h2 * Matrix3::Identity();
    }
    for (const RotationalInertia& t : P.terms<RotationalInertia>()) {
      const Matrix3& R = q.rotations[t.rotation];
      M.block<3, 3>(t.offsets[0], t.offsets[0]) =
          R * (t.J_over_h2.trace() * Matrix3::Identity() - t.J_over_h2) * R.transpose();
    }
    const Eigen::MatrixXd K = (H - M) / P.weight(Spring{});
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense(
        0.5 * (K + K.transpose()), M, Eigen::EigenvaluesOnly);
    const double exact = dense.eigenvalues().maxCoeff();
    const double estimate = largest_mode_step_squared(c, q);
    std::printf("%d DOFs: largest (ωh)² %.10e, dense %.10e\n", c.dofs, estimate, exact);
    ASSERT_GT(exact, 1e-3);
    EXPECT_LE(estimate, exact * (1.0 + 1e-10));
    EXPECT_GE(estimate, exact * (1.0 - (c.dofs <= 100 ? 1e-10 : 1e-3)));
  }
}

// At 0.98 of the bound h < √6/ω the oscillator runs, and keeps the invariant of its two-step
// recurrence x_{k+1} + x_{k−1} = 2c x_k (c = cos Ωh): I = |x_k|² − 2c x_k·x_{k−1} + |x_{k−1}|²,
// which bounds |x_k|² by I/(1 − |c|) (c = −0.946 this near the bound: 14× the start's |x|²);
// at 1.02 the Simulator refuses the model, naming time_step and the bound, and the
// trapezoidal rule (stable at any h) takes it.
TEST(FoxGoodwin, RunsBelowItsStableStepAndRefusesOneAbove) {
  const double bound = std::sqrt(6.0) / kOmega;
  {
    const Model model = oscillator(Integrator::kFoxGoodwin, 0.98 * bound);
    const double h = model.time_step;
    const std::vector<Component> components = build_components(model);
    EXPECT_NEAR(largest_mode_step_squared(components[0], model.initial_state()),
                std::pow(kOmega * h, 2), 1e-9);
    const double c = std::cos(closed_form_frequency(1.0 / 12.0, h) * h);
    SolverOptions options;
    options.tolerance = 1e-13;
    Simulator sim(model, options);
    Vector3 before = sim.state().points[0];
    ASSERT_TRUE(sim.step().converged());
    Vector3 now = sim.state().points[0];
    const auto invariant = [&] { return now.squaredNorm() - 2 * c * now.dot(before) + before.squaredNorm(); };
    const double I = invariant();
    double largest = 0.0, drift = 0.0;
    for (int k = 2; k <= 2000; ++k) {
      ASSERT_TRUE(sim.step().converged()) << k;
      before = now;
      now = sim.state().points[0];
      largest = std::max(largest, now.squaredNorm());
      drift = std::max(drift, std::abs(invariant() - I));
    }
    std::printf("ωh = %.3f: invariant %.6e, drift %.2e, largest |x|² %.4e (bound %.4e)\n", kOmega * h,
                I, drift, largest, I / (1 - std::abs(c)));
    EXPECT_LE(drift, 1e-9 * I);
    EXPECT_LE(largest, I / (1 - std::abs(c)) * (1 + 1e-9));
  }
  try {
    Simulator sim(oscillator(Integrator::kFoxGoodwin, 1.02 * bound), SolverOptions{});
    FAIL() << "accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "time_step");
    EXPECT_NE(e.reason().find("fox_goodwin"), std::string::npos) << e.what();
    EXPECT_NE(e.reason().find("0.245"), std::string::npos) << e.what();  // √6/ω
  }
  Simulator trapezoidal(oscillator(Integrator::kTrapezoidal, 1.02 * bound), SolverOptions{});
  EXPECT_TRUE(trapezoidal.step().converged());
}

// A scene file gets the same check when it is loaded, naming the file: PyElastica's Timoshenko
// beam, whose stiffest mode (the stretch of its 3 cm edges, ω ≈ 943 rad/s) bounds h at 2.6 ms.
TEST(FoxGoodwin, ASceneBeyondItsStableStepIsRefusedWhenLoaded) {
  const std::filesystem::path beam = kScenes / "timoshenko_beam.json";
  EXPECT_EQ(load_scene(beam, {"integrator=fox_goodwin", "time_step=0.0025"}).model.integrator,
            Integrator::kFoxGoodwin);
  try {
    load_scene(beam, {"integrator=fox_goodwin", "time_step=0.0027"});
    FAIL() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "time_step");
    EXPECT_NE(std::string(e.what()).find("timoshenko_beam.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0.0026"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(load_scene(beam, {"integrator=trapezoidal", "time_step=0.0027"}));
}

// Contact and elastic joint limits switch a stiffness on within a step, where no check at the
// start sees it: refused under fox_goodwin, naming the field; exact limits are constraints
// (no stiffness) and pass.
TEST(FoxGoodwin, RefusesContactAndElasticJointLimits) {
  const auto refused = [](const std::filesystem::path& scene, std::vector<std::string> settings,
                          const std::string& field) {
    SCOPED_TRACE(scene.filename().string());
    EXPECT_NO_THROW(load_scene(scene, settings));
    settings.push_back("integrator=fox_goodwin");
    try {
      load_scene(scene, settings);
      ADD_FAILURE() << "accepted";
    } catch (const SceneError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
      EXPECT_NE(std::string(e.what()).find("trapezoidal"), std::string::npos) << e.what();
    }
  };
  refused(kScenes / "optimization" / "die_throw_contact.json", {}, "bodies[0].contact");
  refused(kScenes / "optimization" / "rod_throw_friction.json", {}, "rods[0].contact");
  refused(kScenes / "joints" / "stops.json", {"joints.0.compliance_rotation=1e-4"}, "joints[0].limits");
  EXPECT_NO_THROW(load_scene(kScenes / "joints" / "stops.json", {"integrator=fox_goodwin"}));
}

}  // namespace
}  // namespace liedyn

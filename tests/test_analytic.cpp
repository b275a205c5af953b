// The closed-form solutions a scene can declare with "analytic" (problems/analytic.hpp), the
// exact references of `liedyn sweep`:
//   * free_body: the formula checked on its own (Rᵀ Ṙ = hat(I_b⁻¹ Rᵀ L) by central differences
//     in time, L constant, x(t) a parabola), then a backward-Euler simulation converging to it
//     at first order in h;
//   * cantilever: the discrete rod against w(s), off by second-order terms (predicted node by
//     node by the hinge-chain model of tests/test_rod_validation.cpp), the error quartering
//     with doubled edges;
//   * axial_stretch: exact for the discrete rod, to the solver's tolerance;
//   * check_analytic: every assumption it enforces, one scene breaking each, rejected by
//     parse_scene as a SceneError at field "analytic" whose reason names the assumption.
// Tolerances are derived next to their assertions; measured values are printed.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lib/so3.hpp"
#include "problems/analytic.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

using nlohmann::json;

// Every frame of the scene, frame 0 included; every step must converge.
std::vector<State> simulate(const Scene& scene) {
  Simulator sim(scene.model, scene.solver);
  std::vector<State> states{sim.state()};
  for (int k = 0; k < scene.frames; ++k) {
    const StepReport r = sim.step();
    EXPECT_TRUE(r.converged()) << scene.source << " step " << k << ": " << to_string(r.status);
    states.push_back(sim.state());
  }
  return states;
}

// Largest position (‖·‖∞) and rotation (geodesic angle) errors of `states` against the exact
// frames, over every frame and every point and rotation the solution describes.
struct Errors {
  double position = 0.0, orientation = 0.0;
};
Errors errors(const std::vector<State>& states, const std::vector<ExactFrame>& exact) {
  EXPECT_EQ(states.size(), exact.size());
  Errors e;
  for (std::size_t k = 0; k < std::min(states.size(), exact.size()); ++k) {
    for (const auto& [i, x] : exact[k].points) {
      e.position = std::max(e.position, (states[k].points[i] - x).cwiseAbs().maxCoeff());
    }
    for (const auto& [i, R] : exact[k].rotations) {
      e.orientation = std::max(e.orientation, so3::distance(states[k].rotations[i], R));
    }
  }
  return e;
}

// ---------------------------------------------------------------------------------------
// free_body
// ---------------------------------------------------------------------------------------

// A body frame turned by Q against its principal axes: I_b = Q diag(moments) Qᵀ is a full
// tensor, so the symmetry axis is found by the eigen-decomposition, not read off a diagonal.
Matrix3 rotated_inertia(const Vector3& moments) {
  const Matrix3 Q = so3::exp(Vector3(0.3, -0.5, 0.4));
  Matrix3 I = Q * moments.asDiagonal() * Q.transpose();
  return 0.5 * (I + I.transpose());  // symmetric to the last bit
}

json matrix_json(const Matrix3& M) {
  json rows = json::array();
  for (int i = 0; i < 3; ++i) rows.push_back({M(i, 0), M(i, 1), M(i, 2)});
  return rows;
}

// A thrown axisymmetric body spinning about a generic axis under gravity (as
// problems/scenes/free_body_symmetric.json), with its inertia tensor `inertia`.
json free_body_json(double h, int frames, const Matrix3& inertia) {
  json scene = json::parse(R"({
    "analytic": "free_body",
    "gravity": [0, 0, -9.81],
    "solver": { "backend": "newton", "rotation": "lie", "tolerance": 1e-12, "max_iterations": 50 },
    "bodies": [ { "name": "body", "mass": 1.0, "position": [0, 0, 1],
                  "orientation": [0.9, 0.3, -0.2, 0.2449489742783178],
                  "linear_velocity": [1, 0, 5], "angular_velocity": [0.7, -1.3, 2.1] } ] })");
  scene["time_step"] = h;
  scene["frames"] = frames;
  scene["bodies"][0]["inertia"] = matrix_json(inertia);
  return scene;
}

Scene parse(const json& scene, const std::string& source = "analytic_test.json") {
  return parse_scene(scene.dump(), source);
}

// The formula on its own, for a prolate (1, 1, 1.6) and an oblate (1.6, 1.6, 1) body (the
// two branches of the axis search): sampled every δ = 1e-4 s over 2 s.
//   * Rᵀ Ṙ = hat(Ω), Ω = I_b⁻¹ Rᵀ L₀, with Ṙ by central differences (R(t+δ) − R(t−δ))/(2δ):
//     truncation δ²/6 ‖R⃛‖ ≤ δ²/6 (|ω| + |λ|)³ ≈ 1e-8/6 · 4³ ≈ 1e-7, round-off ε/δ ≈ 1e-12.
//     Tolerance 1e-6 rad/s; a wrong λ (the body-frame spin about the axis, ~0.8 rad/s here)
//     or a wrong factor order would show as O(1) rad/s.
//   * L(t) = R I_b Ω_fd = L₀ (angular momentum conserved): the same error times ‖I_b‖ ≤ 1.6.
//   * x(t): second differences over δ_x = 100 δ equal g (exact for a parabola; round-off
//     4ε |x|/δ_x² ≈ 4e-16 · 10 / 1e-4 ≈ 4e-11, tolerance 1e-8), and x(δ_x) − x(0) =
//     δ_x (v₀ + g δ_x/2) (tolerance 1e-12 m, round-off of |x| ~ 1).
TEST(AnalyticFreeBody, FormulaSolvesEulersEquationsAndTheCentreOfMassFallsFreely) {
  const double delta = 1e-4;
  const int samples = 20000;
  for (const Vector3& moments : {Vector3(1.0, 1.0, 1.6), Vector3(1.6, 1.6, 1.0)}) {
    SCOPED_TRACE("moments " + std::to_string(moments(0)) + ", " + std::to_string(moments(2)));
    const Matrix3 I = rotated_inertia(moments);
    const Scene scene = parse(free_body_json(delta, samples, I));
    const RigidBody& b = scene.model.bodies[0];
    // L₀ from the scene's own input: ω₀ is in the world frame, I_b in the body frame.
    const Matrix3 R0 = so3::from_quaternion(
        Eigen::Quaterniond(0.9, 0.3, -0.2, 0.2449489742783178).normalized());
    const Vector3 L0 = R0 * I * R0.transpose() * Vector3(0.7, -1.3, 2.1);
    const std::vector<ExactFrame> exact = exact_trajectory(scene);
    ASSERT_EQ(exact.size(), std::size_t(samples) + 1);
    ASSERT_EQ(exact[0].points.size(), 1u);
    ASSERT_EQ(exact[0].rotations.size(), 1u);
    EXPECT_LT(so3::distance(exact[0].rotations[0].second, R0), 1e-14);
    EXPECT_LT((exact[0].points[0].second - Vector3(0, 0, 1)).norm(), 1e-15);

    auto R = [&](int k) { return exact[k].rotations[0].second; };
    auto x = [&](int k) { return exact[k].points[0].second; };
    double worst_omega = 0.0, worst_momentum = 0.0, worst_axis_spin = 0.0;
    for (int k = 1; k < samples; k += 37) {
      const Matrix3 Rdot = (R(k + 1) - R(k - 1)) / (2.0 * delta);
      const Matrix3 body_rate = R(k).transpose() * Rdot;
      const Vector3 omega = I.inverse() * R(k).transpose() * L0;
      worst_omega = std::max(worst_omega, (body_rate - so3::hat(omega)).cwiseAbs().maxCoeff());
      worst_momentum =
          std::max(worst_momentum, (R(k) * I * so3::vee(body_rate) - L0).cwiseAbs().maxCoeff());
      // The test's premise: the body-frame spin differs from L/I⊥, else λ would go untested.
      worst_axis_spin =
          std::max(worst_axis_spin, (omega - R(k).transpose() * L0 / moments(0)).norm());
    }
    std::printf("free_body formula (I_a = %.1f): max |RᵀṘ − hat(Ω)| = %.3g, max |L − L₀| = %.3g\n",
                moments(2), worst_omega, worst_momentum);
    EXPECT_LT(worst_omega, 1e-6);
    EXPECT_LT(worst_momentum, 1.6e-6);
    EXPECT_GT(worst_axis_spin, 0.1);

    const int stride = 100;
    const double dx = stride * delta;
    EXPECT_LT((x(stride) - x(0) - dx * (b.linear_velocity + 0.5 * dx * scene.model.gravity))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12);
    for (int k = stride; k + stride <= samples; k += 7 * stride) {
      const Vector3 second = (x(k + stride) - 2.0 * x(k) + x(k - stride)) / (dx * dx);
      EXPECT_LT((second - scene.model.gravity).cwiseAbs().maxCoeff(), 1e-8) << "k = " << k;
    }
  }
}

// Backward Euler converges to the formula at first order. Errors at t = T = 1 s, h = 0.02,
// 0.01, 0.005, Newton tolerance 1e-12 (far below the errors, ≥ 1e-4).
//   * Position: with Δx₀ = h v₀ the scheme gives x_k = x₀ + k h v₀ + h² g k(k+1)/2, so the
//     error is exactly ½ |g| h t: ratio 2 up to the solver tolerance (asserted to 1e-6).
//   * Rotation: e(h) = A h + B h² + …, so e(h)/e(h/2) = 2 (1 + B h/(2A) + O(h²)): the ratio
//     differs from 2 by |B/A| h, B/A a rate of the motion, a few |ω₀| ≈ 2.6 rad/s: ≲ 0.1 at
//     h = 0.02. Tolerance ±0.15. Being O(h), that difference must shrink from the first pair
//     of runs to the second (it halves). A formula that is not the limit of the scheme would
//     leave an error that does not vanish with h: ratios falling towards 1, not towards 2.
TEST(AnalyticFreeBody, BackwardEulerConvergesToItAtFirstOrder) {
  const double T = 1.0;
  const Matrix3 I = rotated_inertia(Vector3(1.0, 1.0, 1.6));
  std::vector<Errors> e;
  for (const double h : {0.02, 0.01, 0.005}) {
    const Scene scene = parse(free_body_json(h, static_cast<int>(std::lround(T / h)), I));
    const std::vector<State> states = simulate(scene);
    const std::vector<ExactFrame> exact = exact_trajectory(scene);
    ASSERT_EQ(states.size(), exact.size());
    // At t = T only: the error grows with t, so this is also the largest.
    const Errors end = errors({states.back()}, {exact.back()});
    std::printf("free_body h = %.3f: |x − x_exact|∞ = %.6g m, angle = %.6g rad at t = %.1f s\n",
                h, end.position, end.orientation, T);
    EXPECT_NEAR(end.position, 0.5 * 9.81 * h * T, 1e-6 * end.position) << "h = " << h;
    e.push_back(end);
  }
  std::vector<double> ratios;
  for (std::size_t i = 0; i + 1 < e.size(); ++i) {
    EXPECT_NEAR(e[i].position / e[i + 1].position, 2.0, 1e-6) << "halving step " << i;
    ratios.push_back(e[i].orientation / e[i + 1].orientation);
    std::printf("free_body rotation error ratio %zu: %.4f\n", i, ratios.back());
    EXPECT_NEAR(ratios.back(), 2.0, 0.15) << "halving step " << i;
  }
  EXPECT_LT(std::abs(ratios[1] - 2.0), std::abs(ratios[0] - 2.0));
}

// ---------------------------------------------------------------------------------------
// cantilever
// ---------------------------------------------------------------------------------------

// A straight rod of `edges` edges along x, length 1, clamped at node 0 and edge 0, tip force
// (0, 0, −F) in 2 load steps, EI = 1, k_s = k_x = 1e6 (as problems/scenes/cantilever_small.json).
json cantilever_json(int edges, double F) {
  json scene = json::parse(R"({
    "analytic": "cantilever", "mode": "static", "time_step": 0.01, "frames": 2,
    "solver": { "tolerance": 1e-12, "max_iterations": 100 },
    "rods": [ { "name": "beam", "mass": 0.1, "radius": 0.01,
                "stretch_stiffness": 1e6, "shear_stiffness": 1e6, "bending_stiffness": [1, 1, 1],
                "fixed_nodes": [0], "fixed_edges": [0] } ] })");
  json& rod = scene["rods"][0];
  rod["shape"] = {{"type", "line"}, {"start", {0, 0, 0}}, {"end", {1, 0, 0}}, {"edges", edges}};
  rod["node_forces"] = json::array({{{"node", edges}, {"force", {0, 0, -F}}}});
  return scene;
}

// The discrete rod is a chain of rigid links with hinges at the interior nodes
// (tests/test_rod_validation.cpp, test_rod_model.cpp), of stiffness EI/w_j over their cells:
// w_j = l, and 3l/2 at node 1 next to the clamp (lib/rod.hpp). The hinge at node j carries the
// moment F (n − j) l and kinks by F (n − j) l w_j/EI, which lowers node i > j by that angle
// times (i − j) l; shear adds 2F/k_x per edge (test_rod_model.cpp). Deflection of node i:
//   δ_i = F l³/EI Σ_{j<i} (n − j)(i − j) c_j + 2 F i l / k_x,   c_j = w_j/l.
// Neglected: geometric non-linearity, O((F L²/EI)²) = 1e-6 relative to δ.
double hinge_chain_deflection(int n, int i, double F) {
  const double l = 1.0 / n;
  double sum = 0.0;
  for (int j = 1; j < i; ++j) sum += double(n - j) * (i - j) * (j == 1 ? 1.5 : 1.0);
  return F * l * l * l * sum + 2.0 * F * i * l / 1e6;
}

// The exact w(s) = F s² (3L − s)/(6 EI) against the discrete rod: the difference is the
// discretisation's, which the hinge chain predicts node by node; the largest is at the tip,
// w_L (5/(2n²) − 3/(2n³)) (test_models::clamped_rod_tip_fraction).
// F = 1e-3 (F L²/EI = 1e-3): the linear theory and the hinge chain are then both good to
// ~1e-6 of w_L = 3.3e-4 m, while the errors are ≥ 0.6 % of it (≥ 2.35 % with 10 edges); so the
// measured error must match the predicted one to 1e-3 relative (5e-3 at 20 edges, where the
// 1e-6 is 1.7e-4 of the tip error and the shear's 2e-9 m 1e-3 of it; Newton's tolerance
// 1e-12 m is 5e-7 of the errors). Doubling the edges from 10 to 20 divides it by
// (5/200 − 3/2000)/(5/800 − 3/16000) = 3.876 (second order: → 4).
// Rotations: the chain's edge j ≥ 1 has turned by the kinks before it,
// F l Σ_{i≤j} (n − i) w_i/EI, while the formula gives it w′ at its midpoint: the difference is
// 3 F L²/(8 EI n²) for every such edge (same tolerance); the clamped edge 0 turns in neither.
// An edge turned about the wrong axis would be off by 2w′ ≈ 1e-3 rad.
TEST(AnalyticCantilever, DiscreteRodIsOffBySecondOrderTermsThatQuarterWithDoubledEdges) {
  const double F = 1e-3, wL = F / 3.0;
  std::vector<double> tip_errors;
  for (const int n : {10, 20}) {
    const Scene scene = parse(cantilever_json(n, F));
    const std::vector<State> states = simulate(scene);
    const std::vector<ExactFrame> exact = exact_trajectory(scene);
    ASSERT_EQ(exact.size(), 3u);
    ASSERT_EQ(exact.back().points.size(), std::size_t(n) + 1);
    ASSERT_EQ(exact.back().rotations.size(), std::size_t(n));
    // The exact tip deflection at full load and at λ = 1/2.
    EXPECT_NEAR(-exact[2].points.back().second.z(), wL, 1e-15);
    EXPECT_NEAR(-exact[1].points.back().second.z(), wL / 2, 1e-15);
    // Node by node, at full load: measured error = predicted error.
    double predicted_max = 0.0;
    for (int i = 0; i <= n; ++i) {
      const double s = double(i) / n;
      const double w = F * s * s * (3.0 - s) / 6.0;
      const Vector3& x = states[2].points[scene.model.rod_point(0, i)];
      const double measured = w + x.z();  // exact − discrete deflection (z points down)
      const double predicted = w - hinge_chain_deflection(n, i, F);
      EXPECT_NEAR(measured, predicted, 1e-3 * std::abs(predicted) + 1e-12) << "node " << i;
      predicted_max = std::max(predicted_max, std::abs(predicted));
    }
    const Errors e = errors(states, exact);
    const double tolerance = n == 10 ? 1e-3 : 5e-3;
    std::printf("cantilever %d edges: max |x − x_exact|∞ = %.6g m (predicted %.6g), "
                "w_L (5/(2n²) − 3/(2n³)) = %.6g, edge angles %.3g rad\n",
                n, e.position, predicted_max, wL * (2.5 / (n * n) - 1.5 / (n * n * n)), e.orientation);
    EXPECT_NEAR(e.position, predicted_max, tolerance * predicted_max);
    EXPECT_NEAR(e.position, wL * (2.5 / (n * n) - 1.5 / (n * n * n)), tolerance * e.position);
    const double angle_error = 0.375 * F / (n * n);
    EXPECT_NEAR(e.orientation, angle_error, tolerance * angle_error);
    tip_errors.push_back(e.position);
  }
  std::printf("cantilever error ratio 10 → 20 edges: %.4f\n", tip_errors[0] / tip_errors[1]);
  EXPECT_NEAR(tip_errors[0] / tip_errors[1], 0.0235 / 0.0060625, 2e-2);
}

// ---------------------------------------------------------------------------------------
// axial_stretch
// ---------------------------------------------------------------------------------------

// problems/scenes/axial_stretch.json (20 edges, 10 N on k_s = 1e4 N: 1 mm at the tip): the
// tension is F in every edge, ‖e‖ = l (1 + F/k_s) and no edge turns, exactly, for the
// discrete rod too. What is left is Newton's: it stops once its step is ≤ 1e-10 (m, rad), and
// converges quadratically, so each load step is solved to ~1e-10; tolerance 1e-9 (ten times
// that), a millionth of the 1 mm stretch — any error in the formula (a factor of l, of n)
// would be ≥ 5e-5 m.
TEST(AnalyticAxialStretch, ExactForTheDiscreteRodToTheSolverTolerance) {
  const Scene scene = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) /
                                 "problems/scenes/axial_stretch.json");
  ASSERT_EQ(scene.analytic, AnalyticSolution::kAxialStretch);
  const std::vector<State> states = simulate(scene);
  const std::vector<ExactFrame> exact = exact_trajectory(scene);
  ASSERT_EQ(exact.size(), std::size_t(scene.frames) + 1);
  const int tip = scene.model.rod_point(0, 20);
  EXPECT_NEAR(exact.back().points.back().second.x() - 1.0, 1e-3, 1e-15);  // F L / k_s
  EXPECT_EQ(exact.back().points.back().first, tip);
  EXPECT_NEAR(states.back().points[tip].x() - 1.0, 1e-3, 1e-9);
  const Errors e = errors(states, exact);
  std::printf("axial_stretch: max |x − x_exact|∞ = %.3g m, edge angles %.3g rad\n", e.position,
              e.orientation);
  EXPECT_LT(e.position, 1e-9);
  EXPECT_LT(e.orientation, 1e-9);
}

// ---------------------------------------------------------------------------------------
// check_analytic: one broken assumption per scene
// ---------------------------------------------------------------------------------------

json free_body_base() { return free_body_json(0.01, 5, Matrix3(Vector3(1, 1, 1.6).asDiagonal())); }

// A scene that breaks one assumption of its declared solution: without "analytic" it is a
// valid scene (so the rejection is check_analytic's); with it, a SceneError at "analytic"
// whose reason contains `names`.
void expect_rejected(json scene, const std::string& names) {
  SCOPED_TRACE(names);
  const std::string declared = scene["analytic"];
  scene["analytic"] = "none";
  EXPECT_NO_THROW(parse(scene)) << "the scene is invalid even without \"analytic\"";
  scene["analytic"] = declared;
  try {
    parse(scene, "broken.json");
    ADD_FAILURE() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "analytic") << e.what();
    EXPECT_EQ(e.file(), "broken.json");
    EXPECT_NE(e.reason().find(names), std::string::npos) << e.what();
    EXPECT_NE(e.reason().find("\"" + declared + "\" needs"), std::string::npos) << e.what();
  }
}

TEST(AnalyticCheck, TheBaseScenesAreAccepted) {
  EXPECT_EQ(parse(free_body_base()).analytic, AnalyticSolution::kFreeBody);
  EXPECT_EQ(parse(cantilever_json(5, 0.01)).analytic, AnalyticSolution::kCantilever);
  json stretch = cantilever_json(5, 0.01);
  stretch["analytic"] = "axial_stretch";
  stretch["rods"][0]["node_forces"][0]["force"] = {0.01, 0, 0};
  EXPECT_EQ(parse(stretch).analytic, AnalyticSolution::kAxialStretch);
}

TEST(AnalyticCheck, FreeBodyRejectsEachBrokenAssumption) {
  {
    json two = free_body_base();
    json second = two["bodies"][0];
    second["name"] = "other";
    two["bodies"].push_back(second);
    expect_rejected(two, "exactly one body");
  }
  {
    json torque = free_body_base();
    torque["torques"] = json::array({{{"body", "body"}, {"torque", {0, 0, 0.1}}}});
    expect_rejected(torque, "no springs, forces or torques");
  }
  {
    // Static mode needs the body anchored (a spring to the world); the mode is checked first.
    json stat = free_body_base();
    stat["mode"] = "static";
    stat["springs"] = json::array(
        {{{"body_a", "body"}, {"point_b", {0, 0, 2}}, {"stiffness", 100}, {"rest_length", 0}}});
    expect_rejected(stat, "\"mode\": \"dynamic\"");
  }
  {
    // 1 : 1.2 : 1.6, turned: no two principal moments equal.
    json asym = free_body_json(0.01, 5, rotated_inertia(Vector3(1.0, 1.2, 1.6)));
    expect_rejected(asym, "axisymmetric inertia");
  }
}

TEST(AnalyticCheck, RodSolutionsRejectEachBrokenAssumption) {
  {
    json bent = cantilever_json(3, 0.01);
    json& rod = bent["rods"][0];
    rod.erase("shape");
    rod["nodes"] = {{0, 0, 0}, {1.0 / 3, 0, 0}, {2.0 / 3, 0.01, 0}, {1, 0, 0}};
    expect_rejected(bent, "a straight rod");
  }
  {
    json oblique = cantilever_json(5, 0.01);
    oblique["rods"][0]["node_forces"][0]["force"] = {0.001, 0, -0.01};
    expect_rejected(oblique, "perpendicular to the rod");
  }
  {
    json anisotropic = cantilever_json(5, 0.01);
    anisotropic["rods"][0]["bending_stiffness"] = {1, 2, 1};
    expect_rejected(anisotropic, "isotropic bending");
  }
  {
    json extra = cantilever_json(5, 0.01);
    extra["rods"][0]["fixed_nodes"] = {0, 2};
    expect_rejected(extra, "\"fixed_nodes\": [0]");
    extra["analytic"] = "axial_stretch";
    extra["rods"][0]["node_forces"][0]["force"] = {0.01, 0, 0};
    expect_rejected(extra, "\"fixed_nodes\": [0]");
  }
  {
    json dynamic = cantilever_json(5, 0.01);
    dynamic["mode"] = "dynamic";
    expect_rejected(dynamic, "\"mode\": \"static\"");
  }
  {
    json middle = cantilever_json(5, 0.01);
    middle["rods"][0]["node_forces"][0]["node"] = 3;
    expect_rejected(middle, "on the last node");
  }
  {
    json curved = cantilever_json(3, 0.01);
    curved["rods"][0]["rest_shape"] = {
        {"type", "helix"}, {"radius", 0.2}, {"pitch", 0.1}, {"turns", 0.5}, {"edges", 3}};
    expect_rejected(curved, "a straight rest shape");
  }
  {
    json sideways = cantilever_json(5, 0.01);
    sideways["analytic"] = "axial_stretch";
    expect_rejected(sideways, "a tip force along the rod");
  }
  {
    json heavy = cantilever_json(5, 0.01);
    heavy["gravity"] = {0, 0, -9.81};
    expect_rejected(heavy, "zero gravity");
  }
}

TEST(AnalyticCheck, AnUnknownSolutionIsRejected) {
  json scene = free_body_base();
  scene["analytic"] = "spinning_top";
  try {
    parse(scene, "unknown.json");
    ADD_FAILURE() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "analytic") << e.what();
    EXPECT_NE(e.reason().find("unknown solution \"spinning_top\""), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace liedyn

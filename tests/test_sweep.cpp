// `liedyn sweep` (problems/sweep.hpp): the --set axis syntax, the grid (size, order, frames
// rescaled with h), its errors raised before anything runs, the references (analytic, or a
// run at the finest settings with Newton and lie; one per value of a model axis), the
// metrics (errors against the reference, energy drift, gradient error of an optimisation
// scene), the CSV and its Pareto column, the PNGs, and the command line (exit codes 0, 2, 4).
// Scenes are small and inline (each run well under a second); tolerances are derived next to
// their assertions and measured values printed.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "problems/sweep.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;

// A body hung from the world origin by a spring (k = 20 N/m, rest length its initial 0.2 m),
// spinning, under gravity: 0.2 s in 10 steps of 0.02 s. No analytic solution.
constexpr const char* kPendulum = R"({
  "time_step": 0.02, "frames": 10, "gravity": [0, 0, -9.81],
  "solver": { "backend": "newton", "rotation": "lie", "tolerance": 1e-10, "max_iterations": 50 },
  "bodies": [ { "name": "bob", "mass": 1, "inertia": [0.02, 0.03, 0.04], "position": [0.2, 0, 0],
                "angular_velocity": [0.5, -1, 2] } ],
  "springs": [ { "body_b": "bob", "point_b": [0, 0, 0], "stiffness": 20 } ] })";

// A torque-free axisymmetric body thrown under gravity, declaring its solution: 0.2 s.
constexpr const char* kFreeBody = R"({
  "analytic": "free_body", "time_step": 0.02, "frames": 10, "gravity": [0, 0, -9.81],
  "solver": { "tolerance": 1e-12 },
  "bodies": [ { "name": "top", "mass": 2, "inertia": [1, 1, 1.6], "position": [0, 0, 1],
                "linear_velocity": [1, 0, 5], "angular_velocity": [0.7, -1.3, 2.1] } ] })";

// A rod clamped at node 0 sagging under its weight (static, no analytic solution): 4 edges,
// 0.1 kg over 1 m, EI = 1 N m²: the tip sags ~ q L⁴/(8 EI) ≈ 0.1 m at full load.
constexpr const char* kSaggingRod = R"({
  "mode": "static", "time_step": 0.01, "frames": 5, "gravity": [0, 0, -9.81],
  "solver": { "tolerance": 1e-10, "max_iterations": 100 },
  "rods": [ { "name": "beam", "shape": { "type": "line", "start": [0, 0, 0], "end": [1, 0, 0],
                                          "edges": 4 },
              "mass": 0.1, "radius": 0.01, "stretch_stiffness": 1e4, "shear_stiffness": 1e4,
              "bending_stiffness": [1, 1, 1], "fixed_nodes": [0], "fixed_edges": [0] } ] })";

// A die-throw-like optimisation problem (problems/scenes/optimization/die_throw.json) made
// cheap: 5 frames. Its inertia is not isotropic, so that the rotation is non-linear in the
// step and the Newton tolerance shows in the trajectory (and the gradient).
constexpr const char* kThrow = R"({
  "time_step": 0.02, "frames": 5, "gravity": [0, 0, -9.81],
  "solver": { "backend": "newton", "rotation": "lie", "tolerance": 1e-10, "max_iterations": 50 },
  "bodies": [ { "name": "die", "mass": 0.01, "inertia": [4e-7, 6e-7, 9e-7], "position": [0, 0, 0.3],
                "linear_velocity": [0.5, 0, 1.0], "angular_velocity": [5, -8, 12] } ],
  "optimization": {
    "parameters": [ { "kind": "body_angular_velocity", "body": "die" },
                    { "kind": "body_linear_velocity", "body": "die" } ],
    "objective": [ { "term": "body_pose", "body": "die", "frame": -1, "position": [0, 0, 0.05],
                     "position_weights": [0, 0, 100], "orientation": [0, 0, 0, 1],
                     "orientation_weight": 1 } ] } })";

SweepOptions options(std::vector<std::string> sets) {
  SweepOptions o;
  for (const std::string& s : sets) o.axes.push_back(parse_sweep_axis(s));
  return o;
}

SweepResult sweep(const char* scene, std::vector<std::string> sets) {
  return run_sweep(scene, "scene.json", options(std::move(sets)));
}

// The "a b c" of every run, to compare grids in one assertion.
std::vector<std::string> settings_of(const SweepResult& r) {
  std::vector<std::string> out;
  for (const SweepRun& run : r.runs) {
    std::string s;
    for (const std::string& v : run.settings) s += (s.empty() ? "" : " ") + v;
    out.push_back(s);
  }
  return out;
}

void expect_completed(const SweepRun& run) {
  EXPECT_FALSE(run.failed) << run.failure;
  EXPECT_EQ(run.frames_completed, run.frames);
  EXPECT_EQ(run.unconverged_steps, 0);
  EXPECT_GT(run.newton_iterations, 0);
  EXPECT_GT(run.factorizations, 0);
  EXPECT_GT(run.wall_seconds, 0.0);
}

// ---------------------------------------------------------------------------------------
// parse_sweep_axis
// ---------------------------------------------------------------------------------------

TEST(SweepAxis, SplitsValuesOnTopLevelCommas) {
  const SweepAxis h = parse_sweep_axis("time_step=0.02,0.01");
  EXPECT_EQ(h.path, "time_step");
  EXPECT_EQ(h.values, (std::vector<std::string>{"0.02", "0.01"}));
  const SweepAxis k = parse_sweep_axis("rods.0.bending_stiffness=[1,1,2],[2,2,4]");
  EXPECT_EQ(k.path, "rods.0.bending_stiffness");
  EXPECT_EQ(k.values, (std::vector<std::string>{"[1,1,2]", "[2,2,4]"}));
  const SweepAxis o = parse_sweep_axis("solver.ceres={\"a\":1,\"b\":2},lie");
  EXPECT_EQ(o.values, (std::vector<std::string>{"{\"a\":1,\"b\":2}", "lie"}));
  EXPECT_EQ(parse_sweep_axis("solver.rotation=quat").values, std::vector<std::string>{"quat"});
}

TEST(SweepAxis, RejectsAMissingPathOrValue) {
  for (const char* bad : {"time_step", "time_step=", "=0.01", "time_step=0.02,,0.01",
                          "time_step=0.02,", "time_step=,0.02", ""}) {
    SCOPED_TRACE(bad);
    try {
      parse_sweep_axis(bad);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("--set ") + bad), std::string::npos)
          << e.what();
    }
  }
}

// ---------------------------------------------------------------------------------------
// The grid and its errors
// ---------------------------------------------------------------------------------------

TEST(SweepGrid, EveryCombinationFirstAxisOutermost) {
  const SweepResult r = sweep(kPendulum, {"springs.0.stiffness=20,40", "solver.tolerance=1e-6,1e-8",
                                          "solver.max_iterations=20"});
  EXPECT_EQ(r.scene, "scene.json");
  EXPECT_EQ(r.axis_names,
            (std::vector<std::string>{"springs.0.stiffness", "solver.tolerance",
                                      "solver.max_iterations"}));
  EXPECT_EQ(settings_of(r), (std::vector<std::string>{"20 1e-6 20", "20 1e-8 20", "40 1e-6 20",
                                                      "40 1e-8 20"}));
  for (const SweepRun& run : r.runs) {
    expect_completed(run);
    EXPECT_EQ(run.frames, 10);  // no time_step axis: the scene's frames
  }
  // The settings took effect: the stiffer spring swings differently, so its own reference
  // (one per value of the model axis) is needed; a looser tolerance costs fewer iterations.
  EXPECT_EQ(r.references.size(), 2u);
  EXPECT_LE(r.runs[0].newton_iterations, r.runs[1].newton_iterations);
}

TEST(SweepGrid, BadPathsThrowNamingTheSetBeforeAnythingRuns) {
  struct Case {
    const char* set;
    const char* names;
  };
  for (const Case& c : {Case{"bodies.5.mass=1", "index 5 is out of range"},
                        Case{"time_step.x=1", "\"time_step\" is a number"},
                        Case{"bodies..mass=1", "empty segment"},
                        Case{"bodies.first.mass=1", "must be an index"}}) {
    SCOPED_TRACE(c.set);
    std::ostringstream progress;
    SweepOptions o = options({"solver.tolerance=1e-6,1e-8", c.set});
    o.progress = &progress;
    const std::string path = std::string(c.set).substr(0, std::string(c.set).find('='));
    try {
      run_sweep(kPendulum, "scene.json", o);
      ADD_FAILURE() << "accepted";
    } catch (const SceneError& e) {
      EXPECT_EQ(e.field(), "--set " + path) << e.what();
      EXPECT_NE(e.reason().find(c.names), std::string::npos) << e.what();
    }
    EXPECT_EQ(progress.str(), "");  // nothing ran
  }
}

// A bad value in the third of four grid points (the first axis outermost): the whole grid is
// parsed before the first run, so the progress stream (one line per finished run) stays
// empty, and the error names the first bad point.
TEST(SweepGrid, BadValuesThrowNamingTheFieldAndThePointBeforeAnythingRuns) {
  std::ostringstream progress;
  SweepOptions o = options({"time_step=0.02,-0.01", "solver.tolerance=1e-6,1e-8"});
  o.progress = &progress;
  try {
    run_sweep(kPendulum, "scene.json", o);
    ADD_FAILURE() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "time_step") << e.what();
    EXPECT_NE(e.file().find("scene.json"), std::string::npos) << e.what();
    EXPECT_NE(e.file().find("time_step=-0.01 solver.tolerance=1e-6"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(progress.str(), "");

  // The same sweep without the bad value does run, and reports each run.
  o = options({"solver.tolerance=1e-6,1e-8", "time_step=0.02"});
  o.progress = &progress;
  EXPECT_EQ(run_sweep(kPendulum, "scene.json", o).runs.size(), 2u);
  EXPECT_NE(progress.str().find("sweep 3/3: solver.tolerance=1e-8 time_step=0.02"),
            std::string::npos)
      << progress.str();
}

TEST(SweepGrid, ADuplicatedAxisThrows) {
  try {
    sweep(kPendulum, {"time_step=0.02", "solver.tolerance=1e-6", "time_step=0.01"});
    ADD_FAILURE() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "--set time_step") << e.what();
    EXPECT_NE(e.reason().find("twice"), std::string::npos) << e.what();
  }
}

TEST(SweepGrid, RejectsBadOptions) {
  SweepOptions o = options({"time_step=0.02"});
  o.reference_refinement = 0;
  EXPECT_THROW(run_sweep(kPendulum, "scene.json", o), std::invalid_argument);
  o.reference_refinement = 4;
  o.repeats = 0;
  EXPECT_THROW(run_sweep(kPendulum, "scene.json", o), std::invalid_argument);
}

// frames × h is the scene's 0.2 s for every h, unless frames is an axis itself.
TEST(SweepGrid, FramesFollowTheTimeStepUnlessFramesIsAnAxis) {
  const SweepResult r = sweep(kPendulum, {"time_step=0.04,0.02,0.01"});
  ASSERT_EQ(r.runs.size(), 3u);
  EXPECT_EQ(r.runs[0].frames, 5);
  EXPECT_EQ(r.runs[1].frames, 10);
  EXPECT_EQ(r.runs[2].frames, 20);
  for (const SweepRun& run : r.runs) expect_completed(run);
  EXPECT_TRUE(std::any_of(r.notes.begin(), r.notes.end(), [](const std::string& n) {
    return n.find("frames = round(T/h)") != std::string::npos && n.find("0.2 s") != std::string::npos;
  })) << r.notes.front();

  const SweepResult fixed = sweep(kPendulum, {"time_step=0.02,0.01", "frames=4"});
  ASSERT_EQ(fixed.runs.size(), 2u);
  for (const SweepRun& run : fixed.runs) {
    EXPECT_EQ(run.frames, 4);
    EXPECT_EQ(run.frames_completed, 4);
  }
  EXPECT_TRUE(std::none_of(fixed.notes.begin(), fixed.notes.end(), [](const std::string& n) {
    return n.find("round(T/h)") != std::string::npos;
  }));
  // One reference (frames is a model axis with one value) covering the longest run,
  // 4 × 0.02 s, at 0.01/4 s: 32 frames.
  ASSERT_EQ(fixed.references.size(), 1u);
  EXPECT_EQ(fixed.references[0].frames, 32);
}

// ---------------------------------------------------------------------------------------
// References and errors
// ---------------------------------------------------------------------------------------

// The reference: h_min/4 (frames for the same 0.2 s), tolerance min/100, Newton with lie
// although the scene says quat. It is listed in `references` and named by every run.
TEST(SweepReference, FinestSettingsWithNewtonAndLie) {
  std::string scene = kPendulum;
  scene.replace(scene.find("\"lie\""), 5, "\"quat\"");
  const SweepResult r =
      run_sweep(scene, "scene.json", options({"time_step=0.02,0.01", "solver.tolerance=1e-6,1e-8"}));
  ASSERT_EQ(r.runs.size(), 4u);
  ASSERT_EQ(r.references.size(), 1u);
  const SweepRun& ref = r.references[0];
  const std::string label =
      "time_step=0.0025 frames=80 solver.tolerance=1e-10 solver.backend=newton "
      "solver.rotation=lie";
  ASSERT_EQ(ref.settings.size(), 1u);
  EXPECT_EQ(ref.settings[0], label);
  EXPECT_EQ(ref.reference, "(reference)");
  EXPECT_EQ(ref.frames, 80);
  expect_completed(ref);
  for (const SweepRun& run : r.runs) {
    EXPECT_EQ(run.reference, label);
    expect_completed(run);
    EXPECT_TRUE(std::isfinite(run.position_error));
    EXPECT_TRUE(std::isfinite(run.orientation_error));
    EXPECT_TRUE(std::isnan(run.gradient_error));  // not an optimisation scene
  }
  EXPECT_TRUE(std::any_of(r.notes.begin(), r.notes.end(), [](const std::string& n) {
    return n.find("reference runs at the grid's finest settings") != std::string::npos;
  }));
}

// Errors against the reference at h_ref = h_min/4 = 0.0025: first order in h, e(h) ≈ C (h −
// h_ref) (both runs err the same way, the reference by C h_ref), so halving h from 0.02 to
// 0.01 divides the error by (0.02 − 0.0025)/(0.01 − 0.0025) = 2.33. The next term is relative
// O(ω h), ω ≈ √(g/0.2 m) ≈ 7 rad/s the swing's rate: ~0.14 at h = 0.02. Tolerance ±0.35 (15 %
// of 2.33); second order would give ≥ 4, no convergence 1.
// The tolerance axis: 1e-6 and 1e-8 on a Newton step both leave solver errors ≪ the time
// step's (~1e-2 m), so the two tolerances' errors agree to 1 %.
// Dynamic: energy drift ≥ 0 (backward Euler dissipates; > 0 for a swinging body).
TEST(SweepReference, PositionErrorFallsAtFirstOrderInTheTimeStep) {
  const SweepResult r = sweep(kPendulum, {"time_step=0.02,0.01", "solver.tolerance=1e-6,1e-8"});
  ASSERT_EQ(r.runs.size(), 4u);
  for (const SweepRun& run : r.runs) {
    std::printf("pendulum h = %s tol = %s: position error %.6g m, orientation %.6g rad, energy "
                "drift %.6g J\n",
                run.settings[0].c_str(), run.settings[1].c_str(), run.position_error,
                run.orientation_error, run.energy_drift);
    EXPECT_GT(run.energy_drift, 0.0);
    EXPECT_TRUE(std::isfinite(run.momentum_drift));
  }
  for (const int tol : {0, 1}) {
    const double ratio = r.runs[tol].position_error / r.runs[2 + tol].position_error;
    EXPECT_NEAR(ratio, 0.0175 / 0.0075, 0.35) << "tolerance " << r.runs[tol].settings[1];
  }
  EXPECT_NEAR(r.runs[0].position_error / r.runs[1].position_error, 1.0, 0.01);
}

// A model axis changes the physics: each value gets its own reference, named in the runs.
TEST(SweepReference, OneReferencePerValueOfAModelAxis) {
  const SweepResult r = sweep(kPendulum, {"time_step=0.02,0.01", "springs.0.stiffness=20,40"});
  ASSERT_EQ(r.runs.size(), 4u);
  ASSERT_EQ(r.references.size(), 2u);
  std::vector<std::string> labels;
  for (const SweepRun& ref : r.references) {
    expect_completed(ref);
    labels.push_back(ref.settings.at(0));
  }
  std::sort(labels.begin(), labels.end());
  EXPECT_EQ(labels, (std::vector<std::string>{
                        "time_step=0.0025 frames=80 springs.0.stiffness=20 solver.backend=newton "
                        "solver.rotation=lie",
                        "time_step=0.0025 frames=80 springs.0.stiffness=40 solver.backend=newton "
                        "solver.rotation=lie"}));
  for (const SweepRun& run : r.runs) {
    EXPECT_NE(run.reference.find("springs.0.stiffness=" + run.settings[1] + " "),
              std::string::npos)
        << run.reference;
    expect_completed(run);
  }
  // Each run is measured against its own stiffness's reference: the same errors, to the bit,
  // as in a sweep of that stiffness alone.
  for (const int k : {20, 40}) {
    const std::string stiffness = std::to_string(k);
    const SweepResult alone = sweep(kPendulum, {"time_step=0.02,0.01",
                                                "springs.0.stiffness=" + stiffness});
    ASSERT_EQ(alone.runs.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
      const SweepRun& run = r.runs[2 * i + (k == 40 ? 1 : 0)];
      ASSERT_EQ(run.settings[1], stiffness);
      EXPECT_EQ(run.position_error, alone.runs[i].position_error) << stiffness << " " << i;
      EXPECT_EQ(run.orientation_error, alone.runs[i].orientation_error) << stiffness << " " << i;
    }
  }
  EXPECT_NE(r.runs[0].position_error, r.runs[1].position_error);
}

// The integrator is a method, not physics: one reference for both, the trapezoidal rule's at
// h_min/4. Against it the trapezoidal errors fall 4× per halving of h (second order: e ∝ h² −
// h_ref², ratio (0.02² − 0.0025²)/(0.01² − 0.0025²) = 4.2) and backward Euler's 2× (first
// order against a reference ~1e3 times more accurate than itself, not its own 2.33 above),
// each within 15 %; at every h the trapezoidal one is the smaller.
TEST(SweepReference, IntegratorsShareTheSecondOrderReference) {
  const SweepResult r = sweep(kPendulum, {"integrator=backward_euler,trapezoidal", "time_step=0.02,0.01"});
  ASSERT_EQ(r.runs.size(), 4u);
  ASSERT_EQ(r.references.size(), 1u);
  const std::string label = "integrator=trapezoidal time_step=0.0025 frames=80 solver.backend=newton "
                            "solver.rotation=lie";
  EXPECT_EQ(r.references[0].settings.at(0), label);
  for (const SweepRun& run : r.runs) {
    expect_completed(run);
    EXPECT_EQ(run.reference, label);
    std::printf("pendulum %s h = %s: position error %.6g m\n", run.settings[0].c_str(),
                run.settings[1].c_str(), run.position_error);
  }
  const double euler = r.runs[0].position_error / r.runs[1].position_error;
  const double trapezoid = r.runs[2].position_error / r.runs[3].position_error;
  EXPECT_NEAR(euler, 2.0, 0.3);
  EXPECT_NEAR(trapezoid, (0.02 * 0.02 - 0.0025 * 0.0025) / (0.01 * 0.01 - 0.0025 * 0.0025), 0.63);
  EXPECT_LT(r.runs[2].position_error, r.runs[0].position_error);
  EXPECT_LT(r.runs[3].position_error, r.runs[1].position_error);
}

// An analytic scene: no reference runs; the position error is exactly backward Euler's on
// the free fall, ½ |g| h T (tests/test_analytic.cpp), T = 0.2 s, to the solver tolerance.
TEST(SweepReference, AnalyticSceneIsComparedWithItsSolution) {
  std::ostringstream progress;
  SweepOptions o = options({"time_step=0.02,0.01"});
  o.progress = &progress;
  const SweepResult r = run_sweep(kFreeBody, "free.json", o);
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_TRUE(r.references.empty());
  EXPECT_NE(progress.str().find("sweep 2/2"), std::string::npos) << progress.str();
  for (const SweepRun& run : r.runs) {
    expect_completed(run);
    EXPECT_EQ(run.reference, "analytic free_body");
    const double h = std::stod(run.settings[0]);
    EXPECT_NEAR(run.position_error, 0.5 * 9.81 * h * 0.2, 1e-6 * run.position_error) << h;
    EXPECT_GT(run.orientation_error, 0.0);
  }
  // Rotation: first order too (ratio 2 within O(h), ±0.15 at h = 0.02; test_analytic.cpp).
  const double ratio = r.runs[0].orientation_error / r.runs[1].orientation_error;
  std::printf("free body in a sweep: rotation error ratio %.4f\n", ratio);
  EXPECT_NEAR(ratio, 2.0, 0.15);
  EXPECT_TRUE(std::any_of(r.notes.begin(), r.notes.end(), [](const std::string& n) {
    return n.find("analytic solution \"free_body\"") != std::string::npos;
  }));
}

// A run whose first step fails (a weight of 1e300 N overflows Ψ at the first Newton step) is
// kept as a failed run, with the step's reason, beside the two that complete.
TEST(SweepReference, AFailedStepIsAFailedRun) {
  const SweepResult r =
      sweep(kPendulum, {"solver.backend=newton,ipopt", "gravity.0=0,1e300", "frames=3"});
  ASSERT_EQ(r.runs.size(), 4u);
  for (const std::size_t i : {0u, 2u}) {
    expect_completed(r.runs[i]);
    EXPECT_TRUE(std::isfinite(r.runs[i].position_error)) << i;
  }
  for (const std::size_t i : {1u, 3u}) {
    const SweepRun& bad = r.runs[i];
    EXPECT_EQ(bad.settings[1], "1e300");
    EXPECT_TRUE(bad.failed);
    EXPECT_NE(bad.failure.find("step 1 (t = 0.02 s) failed"), std::string::npos) << bad.failure;
    EXPECT_EQ(bad.frames_completed, 0);
    EXPECT_TRUE(std::isnan(bad.position_error));
  }
  EXPECT_NE(r.runs[3].failure.find("Ipopt: "), std::string::npos) << r.runs[3].failure;
  // newton with gravity.0 = 0 is the reference's own setting: identical to it.
  EXPECT_EQ(r.runs[0].position_error, 0.0);
}

// Static: runs compare with the reference (the most load steps, 10) at load fractions k/5
// against the reference's frames 2k. The equilibria do not depend on the path, so both runs
// agree with it to the solver tolerance (1e-10 per step; 1e-8 allowed); compared frame by
// frame instead, λ = 0.2 against 0.1, they would differ by a tenth of the ~0.1 m sag.
TEST(SweepReference, StaticScenesCompareAtLoadFractions) {
  const SweepResult r = sweep(kSaggingRod, {"frames=5,10"});
  ASSERT_EQ(r.runs.size(), 2u);
  ASSERT_EQ(r.references.size(), 1u);
  EXPECT_EQ(r.references[0].settings[0], "frames=10 solver.backend=newton solver.rotation=lie");
  EXPECT_EQ(r.references[0].frames, 10);
  for (const SweepRun& run : r.runs) {
    expect_completed(run);
    std::printf("static rod, %s load steps: position error %.3g m\n", run.settings[0].c_str(),
                run.position_error);
    EXPECT_LT(run.position_error, 1e-8);
    EXPECT_LT(run.orientation_error, 1e-8);
    EXPECT_TRUE(std::isnan(run.energy_drift));  // not defined in static mode
    EXPECT_TRUE(std::isnan(run.momentum_drift));
  }
  EXPECT_EQ(r.runs[0].frames, 5);
  EXPECT_EQ(r.runs[1].frames, 10);
}

// The adjoint gradient of each run against central differences of the reference's loss
// (tolerance 1e-12): with Newton stopping at 1e-3 the trajectory, hence the loss and its
// gradient, is off by the unfinished Newton step; at 1e-10 only the differences' own error is
// left. Both finite, the tight one smaller.
TEST(SweepReference, OptimizationSceneGetsAGradientError) {
  const SweepResult r = sweep(kThrow, {"solver.tolerance=1e-3,1e-10"});
  ASSERT_EQ(r.runs.size(), 2u);
  ASSERT_EQ(r.references.size(), 1u);
  EXPECT_EQ(r.references[0].settings[0],
            "solver.tolerance=1e-12 solver.backend=newton solver.rotation=lie");
  for (const SweepRun& run : r.runs) {
    std::printf("throw, tolerance %s: gradient error %.3g (%.3g s), position error %.3g m\n",
                run.settings[0].c_str(), run.gradient_error, run.gradient_seconds,
                run.position_error);
    expect_completed(run);
    EXPECT_TRUE(std::isfinite(run.gradient_error));
    EXPECT_GT(run.gradient_seconds, 0.0);
  }
  EXPECT_LT(r.runs[1].gradient_error, r.runs[0].gradient_error);
}

// ---------------------------------------------------------------------------------------
// sweep_csv, write_sweep
// ---------------------------------------------------------------------------------------

SweepRun made_run(const std::string& setting, double seconds, double position) {
  SweepRun run;
  run.settings = {setting};
  run.frames = run.frames_completed = 10;
  run.wall_seconds = seconds;
  run.position_error = position;
  return run;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// The value in `column` (0-based) of a CSV line without quoted fields.
std::string field(const std::string& line, int column) {
  std::istringstream in(line);
  std::string value;
  for (int i = 0; i <= column; ++i) std::getline(in, value, ',');
  return value;
}

constexpr const char* kColumns =
    "frames_requested,frames_completed,wall_seconds,parallel_runs,newton_iterations,factorizations,"
    "unconverged_steps,"
    "position_error,orientation_error,energy_drift,momentum_drift,gradient_error,"
    "gradient_seconds,pareto,failed,reference,failure";
constexpr int kPareto = 14;  // its column with one axis

// On the front: no other run both faster and more accurate; identical points do not dominate
// each other; a failed run never is (even the fastest and most accurate).
TEST(SweepCsv, OneRowPerRunWithTheParetoFront) {
  SweepResult r;
  r.axis_names = {"time_step"};
  r.runs = {made_run("a", 1.0, 0.1),   made_run("b", 2.0, 0.05), made_run("c", 3.0, 0.2),
            made_run("d", 0.5, 0.3),   made_run("e", 0.1, 0.001), made_run("f", 2.0, 0.05),
            made_run("g", 4.0, SweepRun::kNaN)};
  r.runs[4].failed = true;
  r.runs[0].reference = "time_step=0.0025";
  const std::vector<std::string> csv = lines(sweep_csv(r));
  ASSERT_EQ(csv.size(), 8u);
  EXPECT_EQ(csv[0], std::string("time_step,") + kColumns);
  const char* expected[] = {"1", "1", "0", "1", "0", "1", "0"};
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(field(csv[i + 1], 0), r.runs[i].settings[0]) << csv[i + 1];
    EXPECT_EQ(field(csv[i + 1], kPareto), expected[i]) << csv[i + 1];
    EXPECT_EQ(field(csv[i + 1], kPareto + 1), i == 4 ? "1" : "0") << csv[i + 1];
  }
  EXPECT_EQ(csv[1], "a,10,10,1,1,0,0,0,0.1,nan,nan,nan,nan,nan,1,0,time_step=0.0025,");
}

// The front is over the position error, else the orientation error when no run has a
// positive position error, else the gradient error.
TEST(SweepCsv, TheParetoFrontFallsBackToOrientationThenGradient) {
  SweepResult r;
  r.axis_names = {"solver.rotation"};
  r.runs = {made_run("lie", 1.0, 0.0), made_run("quat", 2.0, 0.0)};
  r.runs[0].orientation_error = 0.2;  // faster, less accurate: both on the front
  r.runs[1].orientation_error = 0.1;
  std::vector<std::string> csv = lines(sweep_csv(r));
  EXPECT_EQ(field(csv[1], kPareto), "1");
  EXPECT_EQ(field(csv[2], kPareto), "1");
  r.runs[1].orientation_error = 0.3;  // now dominated
  csv = lines(sweep_csv(r));
  EXPECT_EQ(field(csv[1], kPareto), "1");
  EXPECT_EQ(field(csv[2], kPareto), "0");

  for (SweepRun& run : r.runs) run.position_error = run.orientation_error = SweepRun::kNaN;
  r.runs[0].gradient_error = 1e-3;
  r.runs[1].gradient_error = 1e-6;  // slower, more accurate
  csv = lines(sweep_csv(r));
  EXPECT_EQ(field(csv[1], kPareto), "1");
  EXPECT_EQ(field(csv[2], kPareto), "1");
  r.runs[1].gradient_error = 1e-2;
  csv = lines(sweep_csv(r));
  EXPECT_EQ(field(csv[2], kPareto), "0");
}

TEST(SweepCsv, QuotesFieldsWithCommasAndQuotes) {
  SweepResult r;
  r.axis_names = {"rods.0.bending_stiffness"};
  r.runs = {made_run("[1,1,2]", 1.0, 0.1)};
  r.runs[0].failed = true;
  r.runs[0].failure = "step 3 failed: \"nan\" in the gradient, 2 iterations";
  const std::vector<std::string> csv = lines(sweep_csv(r));
  ASSERT_EQ(csv.size(), 2u);
  EXPECT_EQ(csv[1].rfind("\"[1,1,2]\",10,10,", 0), 0u) << csv[1];
  const std::string tail = ",0,1,,\"step 3 failed: \"\"nan\"\" in the gradient, 2 iterations\"";
  ASSERT_GE(csv[1].size(), tail.size());
  EXPECT_EQ(csv[1].substr(csv[1].size() - tail.size()), tail) << csv[1];
}

class SweepFiles : public test::CliFixture {
 protected:
  SweepFiles() : CliFixture("liedyn_sweep_test_") {}

  std::vector<std::string> listing(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }
};

// Plots for the metrics with a finite value only; the nested directory is created.
TEST_F(SweepFiles, WritesTheCsvAndAPlotPerFiniteMetric) {
  SweepResult r;
  r.scene = "scene.json";
  r.axis_names = {"time_step", "solver.rotation"};
  r.runs = {made_run("0.02", 0.01, 1e-2), made_run("0.01", 0.02, 5e-3)};
  r.runs[1].settings.push_back("quat");
  r.runs[0].settings.push_back("lie");
  for (SweepRun& run : r.runs) {
    run.orientation_error = 1e-3;
    run.energy_drift = 0.5;
  }
  const fs::path out = dir_ / "nested" / "out";
  {
    OutputFolder folder(out, "sweep", nullptr);
    write_sweep(r, folder);
  }
  EXPECT_EQ(listing(out), (std::vector<std::string>{"energy_drift_vs_time.png",
                                                    "orientation_error_vs_time.png",
                                                    "position_error_vs_time.png", "run.json",
                                                    "sweep.csv", "sweep.json"}));
  EXPECT_EQ(test::read_file(out / "sweep.csv"), sweep_csv(r));
  EXPECT_EQ(test::read_file(out / "sweep.json"), sweep_to_json(r).dump(1) + "\n");
  EXPECT_EQ(test::read_file(out / "position_error_vs_time.png").substr(1, 3), "PNG");

  r.runs[0].gradient_error = 0.1;  // one finite value is enough for a plot
  {
    OutputFolder folder(out, "sweep", nullptr);
    write_sweep(r, folder);
  }
  EXPECT_TRUE(fs::exists(out / "gradient_error_vs_time.png"));
  EXPECT_FALSE(fs::exists(out / "momentum_drift_vs_time.png"));
}

// ---------------------------------------------------------------------------------------
// The command line
// ---------------------------------------------------------------------------------------

class SweepCli : public test::CliFixture {
 protected:
  SweepCli() : CliFixture("liedyn_sweep_cli_test_") {}
  void SetUp() override {
    CliFixture::SetUp();
    std::ofstream(dir_ / "scene.json") << kPendulum;
  }
  Result sweep(std::vector<std::string> args) {
    args.insert(args.begin(), {"sweep", "scene.json"});
    return run(args);
  }
};

TEST_F(SweepCli, WritesTheCsvAndExits0) {
  const Result r = sweep({"--set", "time_step=0.02,0.01", "--out", "out", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(r.err, "");  // --quiet
  const std::vector<std::string> csv = lines(test::read_file(dir_ / "out" / "sweep.csv"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[0], std::string("time_step,") + kColumns);
  EXPECT_EQ(field(csv[1], 0), "0.02");
  EXPECT_EQ(field(csv[2], 0), "0.01");
  EXPECT_EQ(field(csv[2], 1), "20");
  EXPECT_TRUE(fs::exists(dir_ / "out" / "position_error_vs_time.png"));
  EXPECT_NE(r.out.find("sweep of scene.json: 2 runs"), std::string::npos) << r.out;
}

TEST_F(SweepCli, BadSetExits2AndCreatesNothing) {
  struct Case {
    const char* set;
    const char* names;  // in the message
  };
  for (const Case& c : {Case{"time_step", "--set time_step: expected PATH=VALUE"},
                        Case{"time_step=0.02,", "--set time_step=0.02,: empty value"},
                        Case{"bodies.5.mass=1", "--set bodies.5.mass: index 5 is out of range"},
                        Case{"time_step=-1", "time_step: must be positive"}}) {
    SCOPED_TRACE(c.set);
    const Result r = sweep({"--set", c.set, "--out", "out", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find(c.names), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out"));
    EXPECT_EQ(r.out, "");
  }
}

TEST_F(SweepCli, AFailedRunExits4AndStillWritesTheCsv) {
  const Result r = sweep({"--set", "gravity.0=0,1e300", "--backends", "newton", "--rotations",
                          "quat", "--out", "out", "--quiet"});
  EXPECT_EQ(r.exit_code, 4) << r.out << r.err;
  const std::vector<std::string> csv = lines(test::read_file(dir_ / "out" / "sweep.csv"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[0], std::string("gravity.0,solver.backend,solver.rotation,") + kColumns);
  EXPECT_EQ(csv[1].rfind("0,newton,quat,10,10,", 0), 0u) << csv[1];
  EXPECT_NE(csv[2].find("line_search_failed"), std::string::npos) << csv[2];
  EXPECT_NE(r.out.find("FAILED"), std::string::npos) << r.out;
}

TEST_F(SweepCli, BackendsAndRotationsAreAxes) {
  const Result r = sweep({"--rotations", "lie,quat", "--backends", "newton", "--out", "out",
                          "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::vector<std::string> csv = lines(test::read_file(dir_ / "out" / "sweep.csv"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[0], std::string("solver.backend,solver.rotation,") + kColumns);
  EXPECT_EQ(csv[1].rfind("newton,lie,10,10,", 0), 0u) << csv[1];
  EXPECT_EQ(csv[2].rfind("newton,quat,10,10,", 0), 0u) << csv[2];
}

}  // namespace
}  // namespace liedyn

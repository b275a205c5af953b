// Newton reusing a factorisation over several steps (SolverOptions::hessian_reuse, newton.hpp,
// "Reusing a factorisation"): chord steps on a recent factorisation end a solve only where
// the exact test agrees that it converged; the window of steps a factorisation serves, a
// restart, the default that reuses nothing; the error measured where a new factorisation
// meets the old one; the scene key.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "exact_test.hpp"
#include "problems/scene.hpp"
#include "problems/scene_settings.hpp"
#include "solvers/newton.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::hessian_reuse_tests {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes";

// One component at every step: rods (a shearable beam under the three integrators and three
// parameterisations, a pendulum swinging through large angles, a helix pulled straight, a
// helix buckling into a perversion, a rod pushed through a tube, whose contacts switch) on
// sparse systems, which reuse factorisations; rigid
// bodies (the bolt's flips, the free body, a die thrown onto a table) on dense ones, which
// do not (newton.hpp).
enum class Expect {
  kMostSteps,  // the Hessian changes little from step to step: most solves end on chord steps
  kSome,       // steps that need Newton iterations: few or none
  kNone,       // a dense system: a new factorisation at every solve
};
struct Case {
  std::string file;
  std::vector<std::string> settings;
  Expect expect;
};
const std::vector<Case> kCases = {
    {"timoshenko_beam.json", {"frames=200", "integrator=backward_euler", "solver.tolerance=1e-5"}, Expect::kMostSteps},
    {"timoshenko_beam.json", {"frames=200", "integrator=trapezoidal"}, Expect::kMostSteps},
    {"timoshenko_beam.json", {"frames=200", "integrator=bdf2", "solver.rotation=rotvec"}, Expect::kMostSteps},
    {"timoshenko_beam.json", {"frames=200", "integrator=trapezoidal", "solver.rotation=quat"}, Expect::kMostSteps},
    {"rod_pendulum.json", {"frames=100"}, Expect::kSome},
    {"helix_pull.json", {"frames=100"}, Expect::kSome},
    {"helix_perversion.json", {"frames=60"}, Expect::kSome},
    {"contact/tube_insertion.json", {"frames=900"}, Expect::kSome},
    {"butterfly_bolt.json", {"frames=100", "integrator=trapezoidal"}, Expect::kNone},
    {"contact/die_throw.json", {"frames=100"}, Expect::kNone},
};

struct Counts {
  int steps = 0, chord_ended = 0, factorizations = 0;
  double largest_verdict = 0.0;  // the exact test's Newton step after a chord-ended solve / tolerance
  double reuse_error = 0.0;
};

// Runs the case with hessian_reuse = `reuse` and, after every step that chord steps ended,
// makes the exact test at its final state with a fresh solver on the step's own potential
// (one assembly and a new factorisation there, StepSolver::check).
Counts run_and_check(const Case& c, int reuse) {
  Scene scene = load_scene(kScenes / c.file, c.settings);
  scene.solver.hessian_reuse = reuse;
  SolverOptions exact_options = scene.solver;
  exact_options.hessian_reuse = 1;
  Counts counts;
  testing::run_with_exact_test(
      scene, exact_options, [](const StepReport& report) { return report.reused_factorizations > 0; },
      [&](int k, const StepReport& report, const StepReport* verdict) {
        ++counts.steps;
        counts.factorizations += report.factorizations;
        counts.reuse_error = std::max(counts.reuse_error, report.reuse_error);
        if (verdict == nullptr) return;
        EXPECT_EQ(report.assemblies, 0) << "step " << k;
        EXPECT_EQ(report.factorizations, 0) << "step " << k;
        ++counts.chord_ended;
        counts.largest_verdict =
            std::max(counts.largest_verdict, verdict->step_norm / scene.solver.tolerance);
        EXPECT_LE(verdict->step_norm, scene.solver.tolerance) << "step " << k;
      });
  return counts;
}

// Every solve that chord steps end passes the exact test; on smooth problems most solves end
// so, with one factorisation per window of 10 steps at most; the default reuses nothing.
TEST(HessianReuse, ChordEndedStepsPassTheExactTest) {
  for (const Case& c : kCases) {
    std::string label = c.file;
    for (const std::string& s : c.settings) label += " " + s;
    SCOPED_TRACE(label);
    const Counts reused = run_and_check(c, 10);
    const Counts fresh = run_and_check(c, 1);
    std::printf("%s: %d steps, %d ended by chord steps (exact test's step at most %.3g × tolerance, "
                "largest measured error %.3g); factorisations %d reused, %d fresh\n",
                label.c_str(), reused.steps, reused.chord_ended, reused.largest_verdict,
                reused.reuse_error, reused.factorizations, fresh.factorizations);
    EXPECT_EQ(fresh.chord_ended, 0);
    EXPECT_EQ(fresh.reuse_error, 0.0);
    EXPECT_GE(fresh.factorizations, fresh.steps);
    switch (c.expect) {
      case Expect::kMostSteps:
        EXPECT_LT(reused.factorizations, fresh.factorizations / 2);
        EXPECT_GE(reused.chord_ended, reused.steps * 2 / 3);
        EXPECT_LE(reused.factorizations, reused.steps / 10 + reused.steps - reused.chord_ended);
        EXPECT_LT(reused.reuse_error, 0.5);
        break;
      case Expect::kSome:
        // Where chord steps rarely end a solve, trying them costs few factorisations more.
        EXPECT_LE(reused.factorizations, fresh.factorizations * 21 / 20);
        break;
      case Expect::kNone:
        EXPECT_EQ(reused.chord_ended, 0);
        EXPECT_EQ(reused.factorizations, fresh.factorizations);
        break;
    }
  }
}

// hessian_reuse = 4 on the beam (every solve ends on chord steps): a factorisation at steps
// 1, 5, 9, …; a restart (Simulator::set_state) factorises at its first step again.
TEST(HessianReuse, AFactorisationServesItsWindowAndARestartFactorisesAgain) {
  Scene scene = load_scene(kScenes / "timoshenko_beam.json",
                           {"integrator=backward_euler", "solver.tolerance=1e-5", "solver.hessian_reuse=4"});
  Simulator sim(scene.model, scene.solver);
  for (int k = 1; k <= 12; ++k) {
    const StepReport report = sim.step();
    ASSERT_TRUE(report.converged()) << k;
    const bool window_start = (k - 1) % 4 == 0;
    EXPECT_EQ(report.factorizations, window_start ? 1 : 0) << "step " << k;
    EXPECT_EQ(report.reused_factorizations, window_start ? 0 : 1) << "step " << k;
  }
  sim.set_state(sim.state(), sim.last_step());
  const StepReport restarted = sim.step();
  EXPECT_EQ(restarted.factorizations, 1);
  EXPECT_EQ(restarted.reused_factorizations, 0);
  EXPECT_EQ(sim.step().reused_factorizations, 1);
}

// Where a new factorisation meets one that served chord steps, the old one's step at the same
// iterate is measured against the new one: on the beam, whose Hessian barely changes, the
// error is small but not zero; where it exceeds ½ (a rod hitting a tube's wall) the window is
// halved, so the next factorisation comes sooner.
TEST(HessianReuse, TheErrorOfReusedStepsIsMeasured) {
  Scene beam = load_scene(kScenes / "timoshenko_beam.json",
                          {"frames=40", "integrator=trapezoidal", "solver.tolerance=1e-5",
                           "solver.hessian_reuse=10"});
  Simulator sim(beam.model, beam.solver);
  double error = 0.0;
  for (int k = 1; k <= beam.frames; ++k) error = std::max(error, sim.step().reuse_error);
  EXPECT_GT(error, 0.0);
  EXPECT_LT(error, 0.05);

  // After a measured error above ½ the window is halved (10 → 5 or less), so the next
  // factorisation follows within 5 steps.
  Scene tube = load_scene(kScenes / "contact/tube_insertion.json", {"frames=900", "solver.hessian_reuse=10"});
  Simulator pushed(tube.model, tube.solver);
  int large = 0, last_large = -1;
  for (int k = 1; k <= tube.frames; ++k) {
    const StepReport report = pushed.step();
    ASSERT_TRUE(report.converged()) << k;
    if (last_large > 0 && report.factorizations > 0) {
      EXPECT_LE(k - last_large, 5) << "step " << k;
      last_large = -1;
    }
    if (report.reuse_error > 0.5) {
      ++large;
      last_large = k;
    }
  }
  EXPECT_GT(large, 0);
}

// The scene key: integers ≥ 1, named in the error otherwise; SolverOptions::validate agrees.
TEST(HessianReuse, SceneKeyIsParsedAndBadValuesNamed) {
  const std::string body = R"("bodies": [{"name": "b", "mass": 1, "inertia": [1, 1, 1]}])";
  const std::string base =
      R"({"time_step": 0.01, "frames": 1, )" + body + R"(, "solver": {"hessian_reuse": )";
  EXPECT_EQ(parse_scene(base + "8}}", "inline").solver.hessian_reuse, 8);
  EXPECT_EQ(parse_scene(R"({"time_step": 0.01, "frames": 1, )" + body + "}", "inline").solver.hessian_reuse, 1);
  for (const char* bad : {"0", "-3", "2.5", "\"10\""}) {
    SCOPED_TRACE(bad);
    try {
      parse_scene(base + bad + "}}", "inline");
      FAIL() << "accepted";
    } catch (const SceneError& e) {
      EXPECT_EQ(e.field(), "solver.hessian_reuse");
    }
  }
  // With the assembled convergence check (a new factorisation for every verdict) chord steps,
  // which end solves on an old one, are refused rather than silently overriding it.
  try {
    parse_scene(base + R"(4, "convergence_check": "assembled"}})", "inline");
    FAIL() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "solver.hessian_reuse");
    EXPECT_NE(std::string(e.what()).find("assembled"), std::string::npos);
  }
  EXPECT_EQ(parse_scene(base + R"(1, "convergence_check": "assembled"}})", "inline").solver.hessian_reuse, 1);
  for (const auto& [reuse, check] : {std::pair{0, ConvergenceCheck::kEstimated},
                                     std::pair{2, ConvergenceCheck::kAssembled}}) {
    SolverOptions options;
    options.hessian_reuse = reuse;
    options.convergence_check = check;
    try {
      options.validate();
      FAIL() << "accepted " << reuse;
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find("solver.hessian_reuse"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace liedyn::hessian_reuse_tests

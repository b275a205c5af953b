#pragma once
// The exact convergence test after chosen steps of a run (StepSolver::check: a new assembly
// and factorisation at the step's final state, with a fresh Newton solver on the step's own
// potential): what shortcuts that end a solve early — the estimated check, chord steps on a
// reused factorisation (solvers/newton.hpp) — are held to.

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <vector>

#include "problems/scene.hpp"
#include "solvers/newton.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::testing {

// Runs the scene (one component) with its solver options; after every step, calls
// observe(k, report, verdict) with verdict the exact test's report where judged(report) asked
// for it (nullptr otherwise). The exact solver uses `exact_options`.
inline void run_with_exact_test(const Scene& scene, const SolverOptions& exact_options,
                                const std::function<bool(const StepReport&)>& judged,
                                const std::function<void(int, const StepReport&, const StepReport*)>& observe) {
  Simulator sim(scene.model, scene.solver);
  std::vector<Component> components = build_components(scene.model);
  ASSERT_EQ(components.size(), 1u);
  const std::unique_ptr<StepSolver> exact = make_newton(std::move(components[0]), exact_options);
  Step before = sim.last_step();  // Δq_{k−2} (the initial step at the first two steps)
  for (int k = 1; k <= scene.frames; ++k) {
    const State previous = sim.state();
    const Step previous_step = sim.last_step();
    const StepReport report = sim.step();
    EXPECT_TRUE(report.converged()) << k;
    if (judged(report)) {
      exact->component().potential.begin_step(previous, previous_step, k, &before);
      State q = sim.state();
      const StepReport verdict = exact->check(q);
      observe(k, report, &verdict);
    } else {
      observe(k, report, nullptr);
    }
    if (k >= 2) before = previous_step;
  }
}

}  // namespace liedyn::testing

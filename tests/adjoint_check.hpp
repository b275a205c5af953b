#pragma once
// The adjoint gradient of a scene's optimisation against central differences, for the tests
// that run it through contact: steps of 1e-5 relative, which stay clear of the contact
// switches on those runs (contact is C¹, the lagged normal force only C⁰ in q_{k−1}, so a step
// across a switch sees O(step) errors; 1e-4 does not stay clear on the die: 8e-2).

#include <gtest/gtest.h>

#include <Eigen/Core>

#include "problems/optimization.hpp"
#include "problems/scene.hpp"
#include "solvers/gradient_check.hpp"

namespace liedyn::test {

// At γ, or at the scene's own parameters when γ is empty; `step` and `tolerance` as in
// GradientCheckOptions.
inline ::testing::AssertionResult gradient_agrees(const Scene& scene, const Eigen::VectorXd& gamma = {},
                                                  double step = 1e-5, double tolerance = 1e-5) {
  const DifferentiableSimulation sim = make_differentiable_simulation(scene);
  GradientCheckOptions options;
  options.step = step;
  options.tolerance = tolerance;
  const GradientCheckResult r = check_gradient(sim, gamma.size() > 0 ? gamma : sim.initial_parameters(), options);
  if (r.passed()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max relative error " << r.max_relative_error << " at parameter " << r.worst;
}

}  // namespace liedyn::test

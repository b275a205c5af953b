// OptimizerOptions::warm_start (solvers/optimizer.hpp): a run continued from an earlier run's
// best point (`liedyn optimize --resume`) with Ipopt costs about what the uninterrupted run
// had left, on the bounded cable problem where Ipopt's default start took 6377 evaluations
// (6048 infeasible trial points) after 8 iterations and missed the target;
// and the warm start begins at x0 itself, not at a point pushed into the box.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "lib/model.hpp"
#include "problems/optimization.hpp"
#include "problems/scene.hpp"
#include "solvers/adjoint.hpp"
#include "solvers/optimizer.hpp"

namespace liedyn {
namespace {

using Eigen::VectorXd;

TEST(OptimizerWarmStart, IpoptResumeOnTheCableCostsAtMostTwiceWhatWasLeft) {
  const Scene scene =
      load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/optimization/cable_tip_curve.json");
  const DifferentiableSimulation sim = make_differentiable_simulation(scene);
  ASSERT_TRUE(sim.parameters().bounded());
  const Bounds bounds{sim.parameters().lower_bounds(), sim.parameters().upper_bounds()};
  const ObjectiveFunction f = objective_of(sim);
  const VectorXd x0 = sim.initial_parameters();
  const double scale = sim.evaluate(x0, nullptr).loss;  // optimize's loss_scale (none given)

  OptimizerOptions options = scene.optimization->optimizer;
  options.optimizer = Optimizer::kIpoptLbfgs;
  const OptimizationResult full = minimize(f, x0, scale, options, {}, bounds);
  ASSERT_TRUE(full.reached_target) << full.status << ": " << full.message;

  for (const int k : {4, 8}) {
    SCOPED_TRACE("interrupted after " + std::to_string(k) + " iterations");
    OptimizerOptions first = options;
    first.max_iterations = k;
    const OptimizationResult part = minimize(f, x0, scale, first, {}, bounds);
    ASSERT_EQ(part.status, "max_iterations");
    ASSERT_LT(part.evaluations, full.evaluations);
    const int left = full.evaluations - part.evaluations;

    OptimizerOptions resumed = options;
    resumed.warm_start = true;
    // Without the warm start k = 8 ran to its 200 iterations; 60 keep a regression short.
    resumed.max_iterations = 60;
    const OptimizationResult rest = minimize(f, part.best_x, scale, resumed, {}, bounds);
    EXPECT_TRUE(rest.reached_target) << rest.status << ": " << rest.message;
    EXPECT_LE(rest.evaluations, 2 * left)
        << "the uninterrupted run had " << left << " evaluations left after " << part.evaluations
        << "; " << rest.message;
    EXPECT_LE(rest.best_loss, part.best_loss);
  }
}

// Ipopt's default bound_push moves a start within 1e-2 of a bound 1e-2 into the box; a warm
// start is evaluated where it is (x0's loss is the checkpoint's best loss).
TEST(OptimizerWarmStart, IpoptWarmStartIsEvaluatedAtX0) {
  const int n = 6;
  VectorXd x0(n);
  for (int i = 0; i < n; ++i) x0[i] = 1e-4 * (i + 1);  // just inside the lower bounds 0
  const Bounds bounds{VectorXd::Zero(n), VectorXd::Constant(n, 2.0)};
  // f = ½ ‖x − c‖², c = (1, …, 1) inside the box.
  const ObjectiveFunction f = [](const VectorXd& x, VectorXd& g) {
    g = x - VectorXd::Ones(x.size());
    return 0.5 * g.squaredNorm();
  };
  for (const bool warm : {false, true}) {
    SCOPED_TRACE(warm ? "warm start" : "default start");
    std::vector<VectorXd> points;
    const EvaluationCallback record = [&](const Evaluation&, const VectorXd& x, const VectorXd&) {
      points.push_back(x);
    };
    OptimizerOptions options;
    options.optimizer = Optimizer::kIpoptLbfgs;
    options.max_iterations = 50;
    options.target_normalized_loss = 1e-10;
    options.warm_start = warm;
    VectorXd g0(n);
    const OptimizationResult r = minimize(f, x0, f(x0, g0), options, record, bounds);
    ASSERT_FALSE(points.empty());
    if (warm) {
      EXPECT_EQ(points.front(), x0);
    } else {
      EXPECT_GE(points.front().minCoeff(), 1e-2 - 1e-12);  // today's start: pushed in
    }
    EXPECT_TRUE(r.reached_target) << r.status << ": " << r.message;
    EXPECT_LE((r.best_x - VectorXd::Ones(n)).lpNorm<Eigen::Infinity>(), 1e-4);
  }
}

// NLopt and Ceres start at x0 either way: the same evaluations with and without it.
TEST(OptimizerWarmStart, NloptAndCeresIgnoreIt) {
  const ObjectiveFunction f = [](const VectorXd& x, VectorXd& g) {
    double value = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double d = std::pow(10.0, static_cast<double>(i) / (x.size() - 1));
      g[i] = d * (x[i] - std::sin(1.0 + static_cast<double>(i)));
      value += 0.5 * g[i] * (x[i] - std::sin(1.0 + static_cast<double>(i)));
    }
    return value;
  };
  const VectorXd x0 = VectorXd::Zero(8);
  for (const Optimizer o : {Optimizer::kNloptLbfgs, Optimizer::kCeresLbfgs}) {
    OptimizerOptions options;
    options.optimizer = o;
    options.target_normalized_loss = 1e-9;
    const OptimizationResult cold = minimize(f, x0, 1.0, options);
    options.warm_start = true;
    const OptimizationResult warm = minimize(f, x0, 1.0, options);
    EXPECT_EQ(warm.evaluations, cold.evaluations) << to_string(o);
    EXPECT_EQ(warm.best_x, cold.best_x) << to_string(o);
  }
}

}  // namespace
}  // namespace liedyn

// The outer optimisers (solvers/optimizer.hpp): each of the three L-BFGS back-ends reaches
// the target on a convex quadratic and on Rosenbrock, stops at the target and at the
// iteration cap, returns the best point ever evaluated, reports every evaluation, and turns
// a throwing or non-finite objective into status "failed" with the best point before it.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/optimizer.hpp"

namespace liedyn {
namespace {

using Eigen::VectorXd;

// f = ½ Σ dᵢ (xᵢ − cᵢ)², dᵢ from 1 to `condition` (geometrically), minimum 0 at c.
struct Quadratic {
  VectorXd d, c;
  Quadratic(int n, double condition) : d(n), c(n) {
    for (int i = 0; i < n; ++i) {
      d[i] = std::pow(condition, static_cast<double>(i) / (n - 1));
      c[i] = std::sin(1.0 + i);
    }
  }
  double operator()(const VectorXd& x, VectorXd& g) const {
    g = d.cwiseProduct(x - c);
    return 0.5 * (x - c).dot(g);
  }
};

// The chained Rosenbrock function, f = Σ_{i<n−1} 100 (x_{i+1} − xᵢ²)² + (1 − xᵢ)², minimum 0
// at (1, …, 1); for n = 2 the classic one. Standard start (−1.2, 1, −1.2, 1, …): f = 24.2 for
// n = 2, 2057 for n = 10. (From (−1.2, 1, 1, …, 1) all three back-ends end in the local
// minimum near x₀ = −1, f ≈ 3.99, for n = 10.)
double rosenbrock(const VectorXd& x, VectorXd& g) {
  double f = 0.0;
  g.setZero();
  for (Eigen::Index i = 0; i + 1 < x.size(); ++i) {
    const double a = x[i + 1] - x[i] * x[i], b = 1.0 - x[i];
    f += 100.0 * a * a + b * b;
    g[i] += -400.0 * a * x[i] - 2.0 * b;
    g[i + 1] += 200.0 * a;
  }
  return f;
}

VectorXd rosenbrock_start(int n) {
  VectorXd x(n);
  for (int i = 0; i < n; ++i) x[i] = i % 2 == 0 ? -1.2 : 1.0;
  return x;
}

double value_at(const ObjectiveFunction& f, const VectorXd& x) {
  VectorXd g(x.size());
  return f(x, g);
}

// Every evaluation reported to the callback.
struct History {
  std::vector<Evaluation> evaluations;
  std::vector<VectorXd> points;
  EvaluationCallback callback() {
    return [this](const Evaluation& e, const VectorXd& x, const VectorXd&) {
      evaluations.push_back(e);
      points.push_back(x);
    };
  }
};

OptimizerOptions options_for(Optimizer optimizer, int max_iterations, double target) {
  OptimizerOptions options;
  options.optimizer = optimizer;
  options.max_iterations = max_iterations;
  options.target_normalized_loss = target;
  return options;
}

class OptimizerBackend : public ::testing::TestWithParam<Optimizer> {};

TEST_P(OptimizerBackend, QuadraticIn50DimensionsReachesTarget) {
  const Quadratic q(50, 100.0);
  const ObjectiveFunction f = q;
  const VectorXd x0 = VectorXd::Zero(50);
  const double scale = value_at(f, x0);
  const OptimizationResult r = minimize(f, x0, scale, options_for(GetParam(), 500, 1e-8));
  EXPECT_EQ(r.status, "target_reached") << r.message;
  EXPECT_TRUE(r.reached_target);
  EXPECT_LE(r.best_normalized_loss, 1e-8);
  EXPECT_DOUBLE_EQ(r.best_loss, value_at(f, r.best_x));
  // ½ d_min ‖x − c‖² ≤ f ≤ 1e-8 · scale: the point is near the minimiser.
  EXPECT_LE((r.best_x - q.c).norm(), std::sqrt(2.0 * 1e-8 * scale / q.d.minCoeff()));
  EXPECT_LT(r.evaluations, 200);
}

TEST_P(OptimizerBackend, RosenbrockReachesTargetFromStandardStart) {
  for (const int n : {2, 10}) {
    const ObjectiveFunction f = rosenbrock;
    const VectorXd x0 = rosenbrock_start(n);
    const double scale = value_at(f, x0);
    const OptimizationResult r = minimize(f, x0, scale, options_for(GetParam(), 1000, 1e-6));
    EXPECT_EQ(r.status, "target_reached") << "n = " << n << ": " << r.message;
    EXPECT_LE(r.best_normalized_loss, 1e-6) << "n = " << n;
    EXPECT_LT((r.best_x - VectorXd::Ones(n)).norm(), 0.1) << "n = " << n;
    EXPECT_LE(r.iterations, 1000);
  }
}

TEST_P(OptimizerBackend, ConvergesAtAStationaryPointWithoutTarget) {
  const ObjectiveFunction f = rosenbrock;
  const OptimizationResult r =
      minimize(f, rosenbrock_start(2), 24.2, options_for(GetParam(), 500, 0.0));
  EXPECT_EQ(r.status, "converged") << r.message;
  EXPECT_FALSE(r.reached_target);  // target 0: never
  VectorXd g(2);
  f(r.best_x, g);
  EXPECT_LE(g.lpNorm<Eigen::Infinity>() / 24.2, 10 * kStationaryGradient);
  EXPECT_LT(r.best_normalized_loss, 1e-12);
}

TEST_P(OptimizerBackend, StopsAtTargetWellBeforeTheCap) {
  // A quadratic of condition 1e4 in 100-D: more than 60 iterations to a stationary point (and
  // ~330 to 1e-8), ~30 to a normalised loss of 1e-3.
  const ObjectiveFunction f = Quadratic(100, 1e4);
  const VectorXd x0 = VectorXd::Zero(100);
  const double scale = value_at(f, x0);
  const OptimizationResult no_target = minimize(f, x0, scale, options_for(GetParam(), 60, 0.0));
  ASSERT_EQ(no_target.status, "max_iterations") << no_target.message;

  History history;
  const OptimizationResult r =
      minimize(f, x0, scale, options_for(GetParam(), 1000, 1e-3), history.callback());
  EXPECT_EQ(r.status, "target_reached") << r.message;
  EXPECT_TRUE(r.reached_target);
  EXPECT_LE(r.best_normalized_loss, 1e-3);
  EXPECT_LE(r.iterations, 45);
  EXPECT_LE(r.evaluations, 50);
  // The rule is tested between iterations (NLopt: between line searches): few evaluations
  // after the first one at or below the target.
  int first = 0;
  while (history.evaluations[first].normalized_loss > 1e-3) ++first;
  EXPECT_LE(r.evaluations - (first + 1), 3);
}

TEST_P(OptimizerBackend, AlreadyAtTargetStopsAtOnce) {
  const ObjectiveFunction f = rosenbrock;
  const VectorXd x0 = VectorXd::Constant(4, 1.0 + 1e-6);
  const OptimizationResult r = minimize(f, x0, 1.0, options_for(GetParam(), 100, 1e-3));
  EXPECT_EQ(r.status, "target_reached") << r.message;
  EXPECT_EQ(r.evaluations, 1);
  EXPECT_EQ(r.iterations, GetParam() == Optimizer::kNloptLbfgs ? 1 : 0);  // NLopt: = evaluations
  EXPECT_EQ(r.best_x, x0);
}

TEST_P(OptimizerBackend, RespectsMaxIterations) {
  const ObjectiveFunction f = rosenbrock;
  const VectorXd x0 = rosenbrock_start(2);
  for (const int max : {1, 5}) {
    const OptimizationResult r = minimize(f, x0, 24.2, options_for(GetParam(), max, 1e-12));
    EXPECT_EQ(r.status, "max_iterations") << "max " << max << ": " << r.message;
    EXPECT_LE(r.iterations, max);
    EXPECT_GE(r.iterations, 1);
    if (GetParam() == Optimizer::kNloptLbfgs) {
      EXPECT_EQ(r.evaluations, max);
    }
    EXPECT_LT(r.best_loss, 24.2);  // some progress
  }
}

TEST_P(OptimizerBackend, ReturnsBestOfAllEvaluationsAndCountsThem) {
  const ObjectiveFunction f = rosenbrock;
  const VectorXd x0 = rosenbrock_start(10);
  const double scale = value_at(f, x0);
  History history;
  const OptimizationResult r =
      minimize(f, x0, scale, options_for(GetParam(), 40, 0.0), history.callback());
  ASSERT_FALSE(history.evaluations.empty());
  ASSERT_EQ(static_cast<int>(history.evaluations.size()), r.evaluations);
  EXPECT_EQ(r.status, "max_iterations") << r.message;
  int best = 0;
  for (int k = 0; k < r.evaluations; ++k) {
    const Evaluation& e = history.evaluations[k];
    EXPECT_EQ(e.evaluation, k + 1);
    EXPECT_DOUBLE_EQ(e.normalized_loss, e.loss / scale);
    EXPECT_LE(e.iteration, r.iterations);
    if (k > 0) {
      EXPECT_GE(e.iteration, history.evaluations[k - 1].iteration);
      EXPECT_GE(e.seconds, history.evaluations[k - 1].seconds);
      EXPECT_NE(history.points[k], history.points[k - 1]) << "evaluated twice in a row";
    }
    if (e.loss < history.evaluations[best].loss) best = k;
  }
  EXPECT_EQ(history.points[0], x0);
  EXPECT_EQ(r.best_loss, history.evaluations[best].loss);
  EXPECT_EQ(r.best_x, history.points[best]);
  EXPECT_DOUBLE_EQ(r.best_normalized_loss, r.best_loss / scale);
  EXPECT_LT(r.best_loss, 1e-2 * scale);
}

TEST_P(OptimizerBackend, BestPointIsKeptWhenTheLastEvaluationIsWorse) {
  // Stop (by a throw) right after the first evaluation that is worse than an earlier one, a
  // line-search trial point: the result must be the earlier point, not the last one.
  double lowest = std::numeric_limits<double>::infinity();
  bool worse_seen = false;
  VectorXd lowest_x;
  const ObjectiveFunction f = [&](const VectorXd& x, VectorXd& g) {
    if (worse_seen) throw std::runtime_error("stop");
    const double v = rosenbrock(x, g);
    if (v > lowest) worse_seen = true;
    if (v < lowest) {
      lowest = v;
      lowest_x = x;
    }
    return v;
  };
  History history;
  const OptimizationResult r = minimize(f, rosenbrock_start(10), 2057.0,
                                        options_for(GetParam(), 200, 1e-12), history.callback());
  ASSERT_TRUE(worse_seen) << "no evaluation was worse than an earlier one";
  EXPECT_EQ(r.status, "failed");
  EXPECT_GT(history.evaluations.back().loss, r.best_loss);
  EXPECT_EQ(r.best_loss, lowest);
  EXPECT_EQ(r.best_x, lowest_x);
}

TEST_P(OptimizerBackend, InconsistentGradientStallsWithoutFailing) {
  // ∇f has the wrong sign in x₀: no direction the back-ends compute descends in x₀, so they
  // stall with x₀ where it was. Not a failure, not convergence; the best point is kept.
  const ObjectiveFunction f = [](const VectorXd& x, VectorXd& g) {
    g = 2.0 * x;
    g[0] = -g[0];
    return x.squaredNorm();
  };
  const VectorXd x0 = VectorXd::LinSpaced(5, 1.0, 2.0);
  const bool ipopt = GetParam() == Optimizer::kIpoptLbfgs;
  const OptimizationResult r =
      minimize(f, x0, 1.0, options_for(GetParam(), ipopt ? 20 : 200, 1e-8));
  if (ipopt) {
    // Ipopt never gives up here: ~40 evaluations per iteration, until max_iter.
    EXPECT_EQ(r.status, "max_iterations") << r.message;
  } else {
    EXPECT_EQ(r.status, "roundoff_limited") << r.message;
  }
  EXPECT_FALSE(r.reached_target);
  EXPECT_LE(r.best_loss, x0.squaredNorm());
  EXPECT_DOUBLE_EQ(r.best_loss, value_at(f, r.best_x));
}

TEST_P(OptimizerBackend, InfeasibleTrialPointsShortenTheStepInCeresAndIpopt) {
  // Rosenbrock defined only for ‖x‖∞ ≤ 1.3: the first trial steps of all three back-ends from
  // the standard start leave that box.
  int infeasible = 0;
  const ObjectiveFunction f = [&infeasible](const VectorXd& x, VectorXd& g) {
    if (x.lpNorm<Eigen::Infinity>() > 1.3) {
      ++infeasible;
      throw InfeasiblePoint("outside the box");
    }
    return rosenbrock(x, g);
  };
  const OptimizationResult r =
      minimize(f, rosenbrock_start(2), 24.2, options_for(GetParam(), 200, 1e-6));
  ASSERT_GT(infeasible, 0);
  if (GetParam() == Optimizer::kNloptLbfgs) {  // no way to step back: a failure
    EXPECT_EQ(r.status, "failed");
    EXPECT_EQ(r.message, "outside the box");
    EXPECT_EQ(infeasible, 1);
  } else {
    EXPECT_EQ(r.status, "target_reached") << r.message;
    EXPECT_NE(r.message.find(std::to_string(infeasible) +
                             " trial points could not be evaluated (last: outside the box)"),
              std::string::npos)
        << r.message;
  }
  EXPECT_LE(r.best_x.lpNorm<Eigen::Infinity>(), 1.3);
  EXPECT_DOUBLE_EQ(r.best_loss, value_at(f, r.best_x));

  // An infeasible x0 is a failure for all.
  const VectorXd outside = VectorXd::Constant(2, 2.0);
  const OptimizationResult at_x0 = minimize(f, outside, 1.0, options_for(GetParam(), 20, 1e-6));
  EXPECT_EQ(at_x0.status, "failed") << at_x0.message;
  EXPECT_NE(at_x0.message.find("outside the box"), std::string::npos) << at_x0.message;
  EXPECT_EQ(at_x0.best_x, outside);
  EXPECT_EQ(at_x0.best_loss, std::numeric_limits<double>::infinity());
}

TEST_P(OptimizerBackend, ThrowingObjectiveFailsWithBestPointBefore) {
  int calls = 0;
  const ObjectiveFunction f = [&calls](const VectorXd& x, VectorXd& g) {
    if (++calls == 5) throw std::runtime_error("forward step 12 did not converge");
    return rosenbrock(x, g);
  };
  History history;
  const OptimizationResult r = minimize(f, rosenbrock_start(2), 24.2,
                                        options_for(GetParam(), 100, 1e-8), history.callback());
  EXPECT_EQ(r.status, "failed");
  EXPECT_EQ(r.message, "forward step 12 did not converge");
  EXPECT_EQ(calls, 5);  // stopped at once: f never called again
  EXPECT_EQ(r.evaluations, 5);
  ASSERT_EQ(history.evaluations.size(), 4u);
  int best = 0;
  for (int k = 1; k < 4; ++k) {
    if (history.evaluations[k].loss < history.evaluations[best].loss) best = k;
  }
  EXPECT_EQ(r.best_loss, history.evaluations[best].loss);
  EXPECT_EQ(r.best_x, history.points[best]);
  EXPECT_LT(r.best_loss, 24.2);
}

TEST_P(OptimizerBackend, NonFiniteLossOrGradientFails) {
  for (const bool in_gradient : {false, true}) {
    int calls = 0;
    const ObjectiveFunction f = [&](const VectorXd& x, VectorXd& g) {
      double v = rosenbrock(x, g);
      if (++calls == 3) {
        if (in_gradient) {
          g[1] = std::numeric_limits<double>::infinity();
        } else {
          v = std::numeric_limits<double>::quiet_NaN();
        }
      }
      return v;
    };
    const OptimizationResult r =
        minimize(f, rosenbrock_start(2), 24.2, options_for(GetParam(), 100, 1e-8));
    EXPECT_EQ(r.status, "failed");
    EXPECT_EQ(calls, 3);
    EXPECT_NE(r.message.find(in_gradient ? "gradient entry [1] = inf" : "loss of nan"),
              std::string::npos)
        << r.message;
    EXPECT_NE(r.message.find("evaluation 3"), std::string::npos) << r.message;
    EXPECT_TRUE(std::isfinite(r.best_loss));
  }
}

TEST_P(OptimizerBackend, FailingFirstEvaluationReturnsX0) {
  const ObjectiveFunction f = [](const VectorXd&, VectorXd&) -> double {
    throw std::runtime_error("no");
  };
  const VectorXd x0 = rosenbrock_start(4);
  const OptimizationResult r = minimize(f, x0, 1.0, options_for(GetParam(), 10, 1e-3));
  EXPECT_EQ(r.status, "failed");
  EXPECT_EQ(r.message, "no");
  EXPECT_EQ(r.evaluations, 1);
  EXPECT_EQ(r.best_x, x0);
  EXPECT_EQ(r.best_loss, std::numeric_limits<double>::infinity());
  EXPECT_FALSE(r.reached_target);
}

TEST_P(OptimizerBackend, ThrowingCallbackFails) {
  const EvaluationCallback callback = [](const Evaluation& e, const VectorXd&, const VectorXd&) {
    if (e.evaluation == 2) throw std::runtime_error("disk full");
  };
  const OptimizationResult r =
      minimize(rosenbrock, rosenbrock_start(2), 24.2, options_for(GetParam(), 100, 1e-8), callback);
  EXPECT_EQ(r.status, "failed");
  EXPECT_EQ(r.message, "on_evaluation: disk full");
  EXPECT_EQ(r.evaluations, 2);
}

TEST_P(OptimizerBackend, ForeignExceptionIsRethrown) {
  const ObjectiveFunction f = [](const VectorXd& x, VectorXd& g) {
    if (x[0] != -1.2) throw 42;
    return rosenbrock(x, g);
  };
  EXPECT_THROW(minimize(f, rosenbrock_start(2), 24.2, options_for(GetParam(), 100, 1e-8)), int);
}

INSTANTIATE_TEST_SUITE_P(AllBackends, OptimizerBackend,
                         ::testing::Values(Optimizer::kNloptLbfgs, Optimizer::kCeresLbfgs,
                                           Optimizer::kIpoptLbfgs),
                         [](const ::testing::TestParamInfo<Optimizer>& info) {
                           switch (info.param) {
                             case Optimizer::kNloptLbfgs:
                               return std::string("nlopt");
                             case Optimizer::kCeresLbfgs:
                               return std::string("ceres");
                             case Optimizer::kIpoptLbfgs:
                               return std::string("ipopt");
                           }
                           return std::string("unknown");
                         });

// Runs `call` and returns the std::invalid_argument's message ("" if none was thrown).
template <class Call>
std::string invalid_argument_message(Call call) {
  try {
    call();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(OptimizerOptions, InvalidValuesNameTheField) {
  const auto message_for = [](const OptimizerOptions& options, double loss_scale = 1.0) {
    return invalid_argument_message(
        [&] { minimize(rosenbrock, rosenbrock_start(2), loss_scale, options); });
  };
  OptimizerOptions options;
  EXPECT_NO_THROW(options.validate());

  options = {};
  options.max_iterations = 0;
  EXPECT_NE(message_for(options).find("optimization.max_iterations"), std::string::npos);
  EXPECT_THROW(options.validate(), std::invalid_argument);

  options = {};
  options.target_normalized_loss = -1e-3;
  EXPECT_NE(message_for(options).find("optimization.target_normalized_loss"), std::string::npos);
  options.target_normalized_loss = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message_for(options).find("optimization.target_normalized_loss"), std::string::npos);

  options = {};
  options.lbfgs_memory = 0;
  EXPECT_NE(message_for(options).find("optimization.lbfgs_memory"), std::string::npos);

  options = {};
  options.target_normalized_loss = 0.0;  // valid: no target
  EXPECT_NO_THROW(options.validate());
  for (const double bad : {0.0, -1.0, std::numeric_limits<double>::infinity()}) {
    EXPECT_NE(message_for(OptimizerOptions{}, bad).find("loss_scale"), std::string::npos) << bad;
  }
  EXPECT_NE(invalid_argument_message([] {
              minimize(rosenbrock, VectorXd(), 1.0, OptimizerOptions{});
            }).find("x0"),
            std::string::npos);
}

// Box bounds (solvers/optimizer.hpp, Bounds). The quadratic's minimiser c_i = sin(1 + i) has
// entries of both signs; bounds [0, 0.5] cut it off on both sides, so the box minimiser is
// clamp(c, 0, 0.5) (the quadratic is separable) and the unconstrained one is outside.
class BoundedBackend : public ::testing::TestWithParam<Optimizer> {};

TEST_P(BoundedBackend, QuadraticEndsAtTheClampedMinimiserAndNeverLeavesTheBox) {
  const int n = 8;
  const Quadratic q(n, 10.0);
  const Bounds bounds{VectorXd::Zero(n), VectorXd::Constant(n, 0.5)};
  ASSERT_LT(q.c.minCoeff(), -0.5);  // the set-up: c lies outside the box on both sides
  ASSERT_GT(q.c.maxCoeff(), 0.8);
  const VectorXd expected = q.c.cwiseMax(0.0).cwiseMin(0.5);
  VectorXd g(n);
  const double floor = q(expected, g);  // the least loss within the box
  double outside = 0.0;                 // how far any evaluated point left the box
  const ObjectiveFunction f = [&](const VectorXd& x, VectorXd& gradient) {
    outside = std::max({outside, (-x).maxCoeff(), (x.array() - 0.5).maxCoeff()});
    return q(x, gradient);
  };
  const VectorXd x0 = VectorXd::Constant(n, 0.25);
  const OptimizationResult r =
      minimize(f, x0, value_at(f, x0), options_for(GetParam(), 200, 0.0), {}, bounds);
  EXPECT_TRUE(r.status == "converged" || r.status == "roundoff_limited") << r.status << ": " << r.message;
  EXPECT_LE(outside, 0.0);  // every evaluation, trial points included, within the box
  EXPECT_LT((r.best_x - expected).lpNorm<Eigen::Infinity>(), 1e-4) << r.best_x.transpose();
  EXPECT_LT(r.best_loss - floor, 1e-6 * floor);
  // Without the bounds the same run goes below the box's floor: the bounds were binding.
  const OptimizationResult free = minimize(f, x0, value_at(f, x0), options_for(GetParam(), 200, 0.0));
  EXPECT_LT(free.best_loss, 0.5 * floor);
}

INSTANTIATE_TEST_SUITE_P(NloptAndIpopt, BoundedBackend,
                         ::testing::Values(Optimizer::kNloptLbfgs, Optimizer::kIpoptLbfgs),
                         [](const ::testing::TestParamInfo<Optimizer>& info) {
                           return std::string(info.param == Optimizer::kNloptLbfgs ? "nlopt" : "ipopt");
                         });

TEST(OptimizerBounds, BadBoundsAndCeresAreRejected) {
  const Quadratic q(3, 1.0);
  const ObjectiveFunction f = q;
  const VectorXd x0 = VectorXd::Constant(3, 0.5);
  const auto message_for = [&](const Bounds& bounds, Optimizer optimizer = Optimizer::kNloptLbfgs) {
    return invalid_argument_message(
        [&] { minimize(f, x0, 1.0, options_for(optimizer, 10, 0.0), {}, bounds); });
  };
  const double inf = std::numeric_limits<double>::infinity();
  const VectorXd zero = VectorXd::Zero(3), one = VectorXd::Ones(3);
  EXPECT_NE(message_for({zero, VectorXd::Ones(2)}).find("sizes 3 and 2 for 3"), std::string::npos);
  EXPECT_NE(message_for({one, one}).find("parameter 0: the lower bound 1 is not below"), std::string::npos);
  VectorXd nan = zero;
  nan(2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message_for({nan, one}).find("parameter 2:"), std::string::npos);
  VectorXd tight = one;
  tight(1) = 0.4;
  EXPECT_NE(message_for({zero, tight}).find("parameter 1: x0 = 0.5 is outside [0, 0.4]"),
            std::string::npos)
      << message_for({zero, tight});
  const std::string ceres = message_for({zero, VectorXd::Constant(3, inf)}, Optimizer::kCeresLbfgs);
  EXPECT_NE(ceres.find("ceres-lbfgs cannot respect bounds"), std::string::npos) << ceres;
  // Infinite bounds everywhere are no bounds, for every back-end (Ceres included).
  const Bounds none{VectorXd::Constant(3, -inf), VectorXd::Constant(3, inf)};
  for (const Optimizer o : {Optimizer::kNloptLbfgs, Optimizer::kCeresLbfgs, Optimizer::kIpoptLbfgs}) {
    EXPECT_EQ(message_for(none, o), "") << to_string(o);
  }
}

TEST(OptimizerOptions, NamesRoundTrip) {
  for (const auto o : {Optimizer::kNloptLbfgs, Optimizer::kCeresLbfgs, Optimizer::kIpoptLbfgs}) {
    const std::optional<Optimizer> parsed = parse_optimizer(to_string(o));
    ASSERT_TRUE(parsed.has_value()) << to_string(o);
    EXPECT_EQ(*parsed, o);
  }
  EXPECT_STREQ(to_string(Optimizer::kNloptLbfgs), "nlopt-lbfgs");
  EXPECT_STREQ(to_string(Optimizer::kCeresLbfgs), "ceres-lbfgs");
  EXPECT_STREQ(to_string(Optimizer::kIpoptLbfgs), "ipopt-lbfgs");
  EXPECT_EQ(OptimizerOptions{}.optimizer, Optimizer::kNloptLbfgs);
  for (const char* bad : {"", "lbfgs", "NLOPT-LBFGS", "nlopt", "ceres-lbfgs ", "ipopt_lbfgs"}) {
    EXPECT_FALSE(parse_optimizer(bad).has_value()) << bad;
  }
}

}  // namespace
}  // namespace liedyn

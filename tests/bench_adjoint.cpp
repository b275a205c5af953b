// Google Benchmark for differentiable simulation (solvers/adjoint.hpp): one evaluation of the
// loss and its adjoint gradient on the bundled problems, with the forward pass (simulation +
// loss) and the backward pass (one Hessian factorisation and solve per frame, the mixed
// blocks) timed apart. Issue 6's target is backward ≤ 1× forward.
//
// The point γ matters: at γ₀ the letters' rods rest and their forward Newton solves take no
// iteration, which would flatter the forward pass. Each problem is therefore measured at the
// point NLopt's L-BFGS reaches after 5 evaluations from γ₀ within the scene's bounds (computed
// once, in the set-up), a point the optimiser really evaluates. Counters: forward_ms, backward_ms (means per
// evaluation) and backward_over_forward.
//
// Run in Release:
//   ./build/tests/liedyn_bench --benchmark_filter=Adjoint --benchmark_repetitions=5

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>
#include <utility>

#include "problems/optimization.hpp"
#include "problems/scene.hpp"
#include "solvers/adjoint.hpp"
#include "solvers/optimizer.hpp"

namespace {

using liedyn::DifferentiableSimulation;

struct Problem {
  DifferentiableSimulation sim;
  Eigen::VectorXd gamma;
};

// The scene's differentiable simulation and the point 5 L-BFGS evaluations reach.
const Problem& problem(const std::string& scene) {
  static std::map<std::string, std::unique_ptr<Problem>> cache;
  std::unique_ptr<Problem>& p = cache[scene];
  if (p == nullptr) {
    const liedyn::Scene s = liedyn::load_scene(std::string(LIEDYN_SOURCE_DIR) + "/" + scene);
    DifferentiableSimulation sim = liedyn::make_differentiable_simulation(s);
    const Eigen::VectorXd gamma0 = sim.initial_parameters();
    liedyn::OptimizerOptions options = s.optimization->optimizer;  // the scene's, but NLopt
    options.optimizer = liedyn::Optimizer::kNloptLbfgs;
    options.max_iterations = 5;
    options.target_normalized_loss = 0.0;
    const auto f = [&sim](const Eigen::VectorXd& x, Eigen::VectorXd& gradient) {
      return sim.evaluate(x, &gradient).loss;
    };
    const double scale = sim.evaluate(gamma0, nullptr).loss;
    liedyn::Bounds bounds;  // the scene's (the cables pull)
    if (sim.parameters().bounded()) {
      bounds = {sim.parameters().lower_bounds(), sim.parameters().upper_bounds()};
    }
    const liedyn::OptimizationResult r = liedyn::minimize(f, gamma0, scale, options, {}, bounds);
    p = std::make_unique<Problem>(Problem{std::move(sim), r.best_x});
  }
  return *p;
}

void BM_Adjoint_Evaluation(benchmark::State& state, const std::string& scene) {
  const Problem& p = problem(scene);
  Eigen::VectorXd gradient;
  double forward = 0.0, backward = 0.0;
  for (auto _ : state) {
    const DifferentiableSimulation::Result r = p.sim.evaluate(p.gamma, &gradient);
    benchmark::DoNotOptimize(gradient.data());
    forward += r.forward_seconds;
    backward += r.backward_seconds;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["forward_ms"] = 1e3 * forward / n;
  state.counters["backward_ms"] = 1e3 * backward / n;
  state.counters["backward_over_forward"] = backward / forward;
}

// The problems, registered from one table (name, scene).
const int registered = [] {
  const std::pair<const char*, const char*> problems[] = {
      {"LetterS", "problems/scenes/letters/letter_S.json"},
      {"LetterP", "problems/scenes/letters/letter_P.json"},
      {"RestShape", "problems/scenes/optimization/rest_shape_tip_curve.json"},
      {"Cables", "problems/scenes/optimization/cable_tip_curve.json"},
      {"Die", "problems/scenes/optimization/die_throw.json"},
      {"DieThroughContact", "problems/scenes/optimization/die_throw_contact.json"}};
  for (const auto& [name, scene] : problems) {
    benchmark::RegisterBenchmark((std::string("BM_Adjoint_Evaluation/") + name).c_str(),
                                 BM_Adjoint_Evaluation, std::string(scene))
        ->Unit(benchmark::kMillisecond);
  }
  return 0;
}();

}  // namespace

// Google Benchmark for the rod path: the 969-DOF helical rod of problems/scenes (paper
// Table 1's helical-perversion size). Where the time of a Newton iteration goes: assembly
// of Ψ, g and the banded H; banded factorisation + solve against CHOLMOD's on the same
// matrix; one whole Newton iteration; one whole simulator step. The paper's anchor (laptop,
// single thread): 608 µs assembly + 191 µs solve per iteration.
//
// Assembly, Newton iteration and step run with 1 and 2 assembly threads (the argument); their
// times are wall-clock (UseRealTime), as CPU time would count one thread only.
//
// Run in Release (see bench_newton.cpp):
//   ./build-bench/tests/liedyn_bench --benchmark_filter=Rod --benchmark_repetitions=5

#include <benchmark/benchmark.h>

#include <string>

#include "problems/scene.hpp"
#include "solvers/newton.hpp"
#include "solvers/simulator.hpp"

namespace {

using liedyn::Component;
using liedyn::SolverOptions;
using liedyn::SparseSystem;
using liedyn::State;

const char* const kScene = LIEDYN_SOURCE_DIR "/problems/scenes/helix_perversion.json";

// The rod's component at the start of its first step (iterate = extrapolated state).
struct RodProblem {
  liedyn::Scene scene = liedyn::load_scene(kScene);
  Component component;
  State q;

  RodProblem() {
    std::vector<Component> components = liedyn::build_components(scene.model);
    component = std::move(components.at(0));
    q = scene.model.initial_state();
    component.potential.begin_step(q, scene.model.initial_step());
  }
};

void BM_Rod_Assemble(benchmark::State& state) {
  RodProblem p;
  SparseSystem system(p.component, SparseSystem::Factorization::kUndecided,
                      static_cast<int>(state.range(0)));
  double roundoff = 0.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p.q);
    const double psi = system.assemble(p.component.potential, p.q, &roundoff);
    benchmark::DoNotOptimize(psi);
    benchmark::ClobberMemory();
  }
  state.counters["dofs"] = p.component.dofs;
  state.counters["parts"] = system.assembly_parts();
}
BENCHMARK(BM_Rod_Assemble)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

// Factorisation of H + μI (μ = 0) and the two triangular solves, with the factorisation the
// sparse system picks for a rod (banded) and with CHOLMOD imposed.
template <SparseSystem::Factorization kFactorization>
void BM_Rod_FactorizeSolve(benchmark::State& state) {
  RodProblem p;
  SparseSystem system(p.component, kFactorization);
  system.assemble(p.component.potential, p.q, nullptr);
  Eigen::VectorXd delta(p.component.dofs);
  bool ok = true;
  for (auto _ : state) {
    ok = system.factorize(0.0) && ok;
    system.solve(delta);
    benchmark::DoNotOptimize(delta);
    benchmark::ClobberMemory();
  }
  if (!ok) state.SkipWithError("Hessian not positive definite");
  state.counters["stored_nonzeros"] = static_cast<double>(system.stored_nonzeros());
}
BENCHMARK_TEMPLATE(BM_Rod_FactorizeSolve, SparseSystem::Factorization::kBanded)
    ->Name("BM_Rod_FactorizeSolve_Banded")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Rod_FactorizeSolve, SparseSystem::Factorization::kCholmod)
    ->Name("BM_Rod_FactorizeSolve_Cholmod")
    ->Unit(benchmark::kMicrosecond);

// One Newton iteration as the simulator runs it: at a converged iterate, solve() assembles,
// factorises, solves, finds ‖δ‖∞ ≤ tolerance and returns.
void BM_Rod_NewtonIteration(benchmark::State& state) {
  RodProblem p;
  SolverOptions options;
  options.assembly_threads = static_cast<int>(state.range(0));
  liedyn::SparseNewton newton(std::move(p.component), options);
  if (!newton.solve(p.q).converged()) state.SkipWithError("first solve did not converge");
  for (auto _ : state) {
    const liedyn::StepReport r = newton.solve(p.q);
    benchmark::DoNotOptimize(r);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Rod_NewtonIteration)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

// Whole simulator steps of the scene (they continue its trajectory across iterations).
void BM_Rod_Step(benchmark::State& state) {
  liedyn::Scene scene = liedyn::load_scene(kScene);
  scene.solver.assembly_threads = static_cast<int>(state.range(0));
  liedyn::Simulator sim(scene.model, scene.solver);
  long iterations = 0, not_converged = 0;
  for (auto _ : state) {
    const liedyn::StepReport r = sim.step();
    iterations += r.iterations;
    not_converged += r.converged() ? 0 : 1;
    benchmark::DoNotOptimize(r);
  }
  using benchmark::Counter;
  state.counters["newton_iters_per_step"] =
      Counter(static_cast<double>(iterations), Counter::kAvgIterations);
  if (not_converged > 0) state.SkipWithError("a step did not converge");
}
BENCHMARK(BM_Rod_Step)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace

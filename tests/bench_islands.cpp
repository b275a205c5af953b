// Google Benchmark for the islands of a step (SolverOptions::island_threads): whole simulator
// steps of a scene of independent objects, solved one island after the other (argument 1) or
// on two threads (argument 2). Wall-clock times (UseRealTime).
//   * BM_Islands_Rods: 8 cantilevers of 40 edges (243 DOFs each), swinging under gravity.
//   * BM_Islands_Bodies: 64 free rigid bodies spinning (6 DOFs each, the fixed-size path).
//
// Run in Release (see bench_newton.cpp):
//   ./build/tests/liedyn_bench --benchmark_filter=Islands --benchmark_repetitions=5

#include <benchmark/benchmark.h>

#include <string>

#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace {

std::string rods_scene(int rods) {
  std::string list;
  for (int i = 0; i < rods; ++i) {
    const std::string y = std::to_string(0.1 * i);
    list += std::string(i > 0 ? ", " : "") + R"({ "name": "r)" + std::to_string(i) +
            R"(", "shape": { "type": "line", "start": [0, )" + y + R"(, 0], "end": [1, )" + y +
            R"(, 0], "edges": 40 }, "mass": 0.3, "radius": 0.01, "stretch_stiffness": 3000,
              "shear_stiffness": 1200, "bending_stiffness": [0.08, 0.08, 0.06],
              "fixed_nodes": [0], "fixed_edges": [0] })";
  }
  return R"({ "time_step": 0.01, "frames": 1, "gravity": [0, 0, -9.81],
              "solver": { "tolerance": 1e-9 }, "rods": [ )" + list + "] }";
}

std::string bodies_scene(int bodies) {
  std::string list;
  for (int i = 0; i < bodies; ++i) {
    list += std::string(i > 0 ? ", " : "") + R"({ "name": "b)" + std::to_string(i) +
            R"(", "mass": 1, "inertia": [1, 2, 3], "position": [)" + std::to_string(i) +
            R"(, 0, 0], "angular_velocity": [0.1, 2, 0.1] })";
  }
  return R"({ "time_step": 0.01, "frames": 1, "solver": { "tolerance": 1e-9 }, "bodies": [ )" +
         list + "] }";
}

void run_steps(benchmark::State& state, const std::string& json) {
  liedyn::Scene scene = liedyn::parse_scene(json, "islands.json");
  scene.solver.island_threads = static_cast<int>(state.range(0));
  liedyn::Simulator sim(scene.model, scene.solver);
  long not_converged = 0;
  for (auto _ : state) {
    const liedyn::StepReport r = sim.step();
    not_converged += r.converged() ? 0 : 1;
    benchmark::DoNotOptimize(r);
  }
  if (not_converged > 0) state.SkipWithError("a step did not converge");
}

void BM_Islands_Rods(benchmark::State& state) { run_steps(state, rods_scene(8)); }
BENCHMARK(BM_Islands_Rods)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_Islands_Bodies(benchmark::State& state) { run_steps(state, bodies_scene(64)); }
BENCHMARK(BM_Islands_Bodies)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace

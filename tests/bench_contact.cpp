// Google Benchmark for contact between rods (lib/edge_contact.hpp), on the bundled rope coil
// (problems/scenes/contact/rod_coil.json: 160 edges, 12 403 candidate pairs of edges):
//   * BM_RodCoil_Step/1: the run's steps one after another (restarted when it ends), with
//     self-contact; /0: the same scene without it. Their ratio is what contact costs.
//   * BM_RodCoil_Detection: the search for the pairs within reach (TouchingEdges::find), the
//     part of a step that looks for contact, on the run's own states (every 10th step).
//
// Run in Release (see bench_newton.cpp):
//   ./build/tests/liedyn_bench --benchmark_filter=RodCoil --benchmark_repetitions=3

#include <benchmark/benchmark.h>

#include <filesystem>
#include <vector>

#include "lib/contact_search.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace {

liedyn::Scene coil(bool self_contact) {
  liedyn::Scene scene =
      liedyn::load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/rod_coil.json");
  scene.model.rods[0].self_contact = self_contact;
  return scene;
}

void BM_RodCoil_Step(benchmark::State& state) {
  const liedyn::Scene scene = coil(state.range(0) != 0);
  auto sim = std::make_unique<liedyn::Simulator>(scene.model, scene.solver);
  for (auto _ : state) {
    if (sim->frame() == scene.frames) {
      state.PauseTiming();
      sim = std::make_unique<liedyn::Simulator>(scene.model, scene.solver);
      state.ResumeTiming();
    }
    const liedyn::StepReport r = sim->step();
    if (!r.converged()) state.SkipWithError("a step did not converge");
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_RodCoil_Step)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

void BM_RodCoil_Detection(benchmark::State& state) {
  const liedyn::Scene scene = coil(true);
  liedyn::Simulator sim(scene.model, scene.solver);
  std::vector<liedyn::State> states;
  std::vector<liedyn::Step> steps;
  for (int k = 1; k <= scene.frames; ++k) {
    sim.step();
    if (k % 10 == 0) {
      states.push_back(sim.state());
      steps.push_back(sim.last_step());
    }
  }
  liedyn::ContactSearch search(scene.model);
  std::vector<bool> touching(search.size());
  const bool broad_phase = state.range(0) != 0;
  std::size_t i = 0;
  for (auto _ : state) {
    if (broad_phase) {
      search.find(states[i], steps[i], touching);
    } else {
      search.find_exhaustively(states[i], steps[i], touching);
    }
    benchmark::DoNotOptimize(touching);
    i = (i + 1) % states.size();
  }
}
BENCHMARK(BM_RodCoil_Detection)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

}  // namespace

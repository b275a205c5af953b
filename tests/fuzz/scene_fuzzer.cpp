// libFuzzer harness for the scene loader (docs/fuzzing.md; run with scripts/fuzz.sh).
//
// Each input is parsed as a scene file. Bad input must end in a SceneError (ModelError is
// accepted too: it is the model's own validation error). A scene that parses is then built
// the way the commands build it before their first step: `liedyn simulate` constructs a
// Simulator (which validates the model and the solver options again, discretises the rods and
// sets up the back-end's step solvers) and evaluates the frame-0 energies; `liedyn gradcheck`
// and `liedyn optimize` construct a DifferentiableSimulation. Nothing is stepped.
//
// Anything else is a bug and is left to crash the fuzzer: another exception type escaping
// (std::out_of_range, nlohmann::json::exception, std::bad_alloc, …), a ModelError from the
// build stage (the parser accepted a scene that the commands then reject as an internal error,
// exit code 1 instead of 2), a sanitizer report, a timeout or running out of memory.

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

#include "problems/optimization.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace {

// Budget of the build stage, so that each input stays cheap: scenes within the parser's limits
// but larger than this (a rod of 10⁶ edges is a valid scene) are parsed and validated only.
constexpr long long kMaxBuiltElements = 20000;  // bodies + rod nodes + rod edges
constexpr int kMaxBuiltParameters = 100000;     // size of an optimisation's γ

long long element_count(const liedyn::Model& model) {
  long long n = static_cast<long long>(model.bodies.size());
  for (const liedyn::RodSpec& rod : model.rods) n += rod.node_count() + rod.edge_count();
  return n;
}

// What the commands build from a parsed scene before stepping.
void build(liedyn::Scene scene) {
  if (element_count(scene.model) > kMaxBuiltElements) return;
  // Keep the fuzzer from writing files or printing: output options only.
  scene.solver.ipopt.output_file.clear();
  scene.solver.ipopt.print_level = 0;
  scene.solver.ceres.verbose = false;

  liedyn::Simulator sim(scene.model, scene.solver);
  volatile double energy = sim.kinetic_energy() + sim.potential_energy();
  volatile double momentum = sim.angular_momentum().norm();
  (void)energy;
  (void)momentum;

  if (scene.optimization && scene.optimization->parameters.size() <= kMaxBuiltParameters) {
    const liedyn::DifferentiableSimulation diff = liedyn::make_differentiable_simulation(scene);
    (void)diff;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  liedyn::Scene scene;
  try {
    scene = liedyn::parse_scene(text, "fuzz.json");
  } catch (const liedyn::SceneError&) {
    return 0;
  } catch (const liedyn::ModelError&) {
    return 0;
  }
  build(std::move(scene));
  return 0;
}

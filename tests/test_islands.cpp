// The islands of a step on several threads (SolverOptions::island_threads, Simulator::step):
// the same trajectory, bit for bit, as one island after the other — the islands share no
// state — for rods, bodies, joints and springs under Newton and Ceres; Ipopt's islands stay
// sequential; bad values are refused naming the field.

#include <gtest/gtest.h>

#include <string>

#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

// Three rods, two bodies on a hinge to the world, one free body: four islands.
const char* const kScene = R"({
  "time_step": 0.01, "frames": 40, "gravity": [0, 0, -9.81],
  "solver": { "tolerance": 1e-10 },
  "bodies": [ { "name": "a", "mass": 1, "inertia": [0.02, 0.03, 0.04], "position": [0.2, 5, 0] },
              { "name": "b", "mass": 1, "inertia": [0.02, 0.03, 0.04], "position": [0.6, 5, 0] },
              { "name": "free", "mass": 2, "inertia": [1, 2, 3], "position": [0, -5, 0],
                "angular_velocity": [0.1, 3, 0.2] } ],
  "joints": [ { "type": "hinge", "a": { "body": "a", "point": [-0.2, 0, 0], "axis": [0, 1, 0] } },
              { "type": "ball", "compliance": 1e-6, "a": { "body": "b", "point": [-0.2, 0, 0] }, "b": { "body": "a" } } ],
  "rods": [
    { "name": "r0", "shape": { "type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": 12 },
      "mass": 0.3, "radius": 0.01, "stretch_stiffness": 3000, "shear_stiffness": 1200,
      "bending_stiffness": [0.08, 0.08, 0.06], "fixed_nodes": [0], "fixed_edges": [0] },
    { "name": "r1", "shape": { "type": "line", "start": [0, 1, 0], "end": [1, 1, 0.2], "edges": 9 },
      "mass": 0.2, "radius": 0.01, "stretch_stiffness": 3000, "shear_stiffness": 1200,
      "bending_stiffness": [0.08, 0.08, 0.06], "fixed_nodes": [0], "fixed_edges": [0] },
    { "name": "r2", "shape": { "type": "line", "start": [0, 2, 0], "end": [0.5, 2, 0], "edges": 6 },
      "mass": 0.1, "radius": 0.01, "stretch_stiffness": 3000, "shear_stiffness": 1200,
      "bending_stiffness": [0.08, 0.08, 0.06], "fixed_nodes": [0] } ] })";

State final_state(const Scene& scene, Backend backend, int threads) {
  SolverOptions options = scene.solver;
  options.backend = backend;
  options.island_threads = threads;
  Simulator sim(scene.model, options);
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport r = sim.step();
    // Ceres stalls on some rod steps a little above 1e-10 (its Gauss–Newton model, README):
    // what is compared here is the trajectory, whatever the steps' statuses.
    EXPECT_TRUE(backend == Backend::kCeres ? r.state_updated() : r.converged())
        << to_string(backend) << " threads " << threads << " frame " << k << " " << r.message;
  }
  return sim.state();
}

TEST(Islands, TwoThreadsGiveTheSameTrajectoryBitForBit) {
  const Scene scene = parse_scene(kScene, "islands.json");
  ASSERT_EQ(build_components(scene.model).size(), 5u);  // a+b, free, r0, r1, r2
  for (const Backend backend : {Backend::kNewton, Backend::kCeres}) {
    SCOPED_TRACE(to_string(backend));
    const State one = final_state(scene, backend, 1);
    for (const int threads : {2, 0}) {
      const State many = final_state(scene, backend, threads);
      for (std::size_t i = 0; i < one.points.size(); ++i) EXPECT_EQ(one.points[i], many.points[i]) << i;
      for (std::size_t i = 0; i < one.rotations.size(); ++i) {
        EXPECT_EQ(one.rotations[i], many.rotations[i]) << i;
      }
    }
  }
}

TEST(Islands, BadThreadCountsAreRefused) {
  for (const char* bad : {"-1", "257", "1.5"}) {
    std::string json = kScene;
    json.replace(json.find("\"tolerance\": 1e-10"), 18, std::string("\"island_threads\": ") + bad);
    try {
      parse_scene(json, "islands.json");
      ADD_FAILURE() << bad << " accepted";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("solver.island_threads"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace liedyn

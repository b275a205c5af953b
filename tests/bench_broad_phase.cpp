// Google Benchmark: the broad phase of contact detection (lib/broad_phase.hpp) against FCL's
// broad-phase managers (Debian's libfcl-dev), on the boxes of the bundled rope coil's 160
// edges (problems/scenes/contact/rod_coil.json: each edge's capsule, grown by the farthest its
// rod's nodes moved in the last step, as ContactSearch grows them) at every 10th step of its
// run. Each query is what a step would do: bring every box to its new place, then list the
// pairs that overlap.
//   /0 SweepAndPrune (ours, the order of the last query kept)
//   /1 fcl::DynamicAABBTreeCollisionManager (update every object, then collide)
//   /2 every pair of boxes tested (what the candidates cost without a broad phase)
// Each reports the pairs it found per query (`pairs`). (FCL's SaPCollisionManager is left out:
// its first query on these boxes had not returned after minutes.)
//
//   ./build/tests/liedyn_bench --benchmark_filter=BroadPhase --benchmark_repetitions=3

#include <benchmark/benchmark.h>

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/narrowphase/collision_object.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <vector>

#include "lib/broad_phase.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace {

using liedyn::Aabb;

// The edge boxes at every 10th step of the coil's run.
const std::vector<std::vector<Aabb>>& coil_boxes() {
  static const std::vector<std::vector<Aabb>> frames = [] {
    const liedyn::Scene scene =
        liedyn::load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/rod_coil.json");
    const liedyn::RodSpec& rod = scene.model.rods[0];
    liedyn::Simulator sim(scene.model, scene.solver);
    std::vector<std::vector<Aabb>> out;
    for (int k = 1; k <= scene.frames; ++k) {
      sim.step();
      if (k % 10 != 0) continue;
      const auto& x = sim.state().points;
      double moved = 0.0;
      for (int i = 0; i < rod.node_count(); ++i) {
        moved = std::max(moved, sim.last_step().points[scene.model.rod_point(0, i)].norm());
      }
      const double grow = rod.contact.radius + moved;
      std::vector<Aabb> boxes;
      for (int e = 0; e < rod.edge_count(); ++e) {
        const liedyn::Vector3& a = x[scene.model.rod_point(0, e)];
        const liedyn::Vector3& b = x[scene.model.rod_point(0, e + 1)];
        boxes.push_back({a.cwiseMin(b).array() - grow, a.cwiseMax(b).array() + grow});
      }
      out.push_back(std::move(boxes));
    }
    return out;
  }();
  return frames;
}

bool count_pair(fcl::CollisionObjectd*, fcl::CollisionObjectd*, void* data) {
  ++*static_cast<std::size_t*>(data);
  return false;  // go on
}

void BM_BroadPhase_Coil(benchmark::State& state) {
  const std::vector<std::vector<Aabb>>& frames = coil_boxes();
  const int n = static_cast<int>(frames[0].size());
  const int method = static_cast<int>(state.range(0));

  liedyn::SweepAndPrune sweep;
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(static_cast<std::size_t>(n) * n);

  // FCL: one box-shaped object per edge, resized and moved to the edge's box at each query.
  std::vector<std::shared_ptr<fcl::Boxd>> shapes;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  std::vector<fcl::CollisionObjectd*> registered;
  for (int i = 0; i < n; ++i) {
    shapes.push_back(std::make_shared<fcl::Boxd>(1.0, 1.0, 1.0));
    objects.push_back(std::make_unique<fcl::CollisionObjectd>(shapes.back()));
    registered.push_back(objects.back().get());
  }
  std::unique_ptr<fcl::BroadPhaseCollisionManagerd> manager;
  if (method == 1) manager = std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>();
  const auto place = [&](const std::vector<Aabb>& boxes) {
    for (int i = 0; i < n; ++i) {
      shapes[i]->side = boxes[i].hi - boxes[i].lo;
      shapes[i]->computeLocalAABB();
      objects[i]->setTranslation(0.5 * (boxes[i].lo + boxes[i].hi));
      objects[i]->computeAABB();
    }
  };
  if (manager) {
    place(frames[0]);
    manager->registerObjects(registered);
    manager->setup();
  }

  std::size_t found = 0, queries = 0, f = 0;
  for (auto _ : state) {
    const std::vector<Aabb>& boxes = frames[f];
    std::size_t count = 0;
    if (method == 0) {
      sweep.overlapping(boxes, pairs);
      count = pairs.size();
    } else if (method == 2) {
      for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) {
          count += (boxes[i].lo.array() <= boxes[j].hi.array()).all() && (boxes[j].lo.array() <= boxes[i].hi.array()).all();
        }
      }
    } else {
      place(boxes);
      manager->update();
      manager->collide(&count, count_pair);
    }
    benchmark::DoNotOptimize(count);
    found += count;
    ++queries;
    f = (f + 1) % frames.size();
  }
  state.counters["pairs"] = static_cast<double>(found) / static_cast<double>(queries);
}
BENCHMARK(BM_BroadPhase_Coil)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace

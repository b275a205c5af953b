// The broad phase of contact detection (lib/broad_phase.hpp) against testing every pair of
// boxes, and ContactSearch (lib/contact_search.hpp) against testing every candidate pair,
// on the states of whole runs of the bundled scenes where objects touch each other.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "contact_references.hpp"
#include "lib/broad_phase.hpp"
#include "lib/contact_search.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

using test::every_overlap;

std::vector<std::pair<int, int>> sorted(std::vector<std::pair<int, int>> pairs) {
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// Random boxes moved a little between queries (the insertion sort's case), now and then
// stretched along another axis (a change of sweep axis), and boxes that only touch (closed
// intervals): the same pairs as testing all of them, each once.
TEST(SweepAndPrune, FindsExactlyTheOverlappingPairsAsBoxesMove) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int n : {0, 1, 2, 10, 200}) {
    SweepAndPrune sweep;
    std::vector<Vector3> centre(n), half(n);
    for (int i = 0; i < n; ++i) {
      centre[i] = Vector3(uniform(random), uniform(random), uniform(random));
      half[i] = 0.05 * Vector3(1.0 + uniform(random), 1.0 + uniform(random), 1.0 + uniform(random));
    }
    std::vector<Aabb> boxes(n);
    std::vector<std::pair<int, int>> pairs;
    std::size_t total = 0;
    for (int query = 0; query < 30; ++query) {
      const Vector3 stretch = query % 10 < 5 ? Vector3(1, 1, 1) : Vector3(0.2, 5.0, 1.0);  // axis x, then y
      for (int i = 0; i < n; ++i) {
        centre[i] += 0.01 * Vector3(uniform(random), uniform(random), uniform(random));
        const Vector3 c = centre[i].cwiseProduct(stretch);
        boxes[i] = {c - half[i], c + half[i]};
      }
      sweep.overlapping(boxes, pairs);
      for (const auto& [i, j] : pairs) ASSERT_LT(i, j);
      ASSERT_EQ(sorted(pairs), every_overlap(boxes)) << "n = " << n << ", query " << query;
      total += pairs.size();
    }
    if (n == 200) {
      EXPECT_GT(total, 100u);  // the comparison saw overlaps
    }
  }
  // Touching faces and a box inside another.
  std::vector<Aabb> boxes = {{Vector3(0, 0, 0), Vector3(1, 1, 1)},
                             {Vector3(1, 0, 0), Vector3(2, 1, 1)},
                             {Vector3(0.2, 0.2, 0.2), Vector3(0.3, 0.3, 0.3)},
                             {Vector3(2.0 + 1e-12, 0, 0), Vector3(3, 1, 1)}};
  SweepAndPrune sweep;
  std::vector<std::pair<int, int>> pairs;
  sweep.overlapping(boxes, pairs);
  EXPECT_EQ(sorted(pairs), (std::vector<std::pair<int, int>>{{0, 1}, {0, 2}}));
}

// Over a whole run, at every step's start: the pairs within reach found through the broad
// phase are those found by testing every candidate, and so are the overlaps and the closest
// rod separation reported per frame.
void expect_search_matches_every_pair(const std::string& scene_file, int frames, int min_touching) {
  Scene scene = load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes" / scene_file);
  Simulator sim(scene.model, scene.solver);
  ContactSearch search(scene.model), exhaustive(scene.model);
  const TouchingEdges edges(scene.model);
  ASSERT_GT(search.size(), 0u);
  std::vector<bool> fast(search.size()), every(search.size()), with_overlaps(search.size());
  int touching = 0;
  for (int k = 1; k <= std::min(frames, scene.frames); ++k) {
    ASSERT_TRUE(sim.step().state_updated()) << scene_file << ", step " << k;
    search.find(sim.state(), sim.last_step(), fast);
    exhaustive.find_exhaustively(sim.state(), sim.last_step(), every);
    ASSERT_EQ(fast, every) << scene_file << ", step " << k;
    touching += static_cast<int>(std::count(fast.begin(), fast.end(), true));
    // Overlaps: what add_penetrating adds to an empty set is what penetrating counts.
    std::fill(with_overlaps.begin(), with_overlaps.end(), false);
    search.add_penetrating(sim.state(), with_overlaps);
    ASSERT_EQ(std::count(with_overlaps.begin(), with_overlaps.end(), true), search.penetrating(sim.state()));
    if (search.has_rod_pairs()) {
      ASSERT_EQ(search.min_rod_separation(sim.state()), edges.min_separation(sim.state())) << k;
    }
  }
  EXPECT_GE(touching, min_touching) << scene_file;  // the runs did bring objects within reach
}

TEST(ContactSearch, FindsWhatTestingEveryCandidateFindsOnTheRopeCoil) {
  expect_search_matches_every_pair("contact/rod_coil.json", 300, 1000);
}

TEST(ContactSearch, FindsWhatTestingEveryCandidateFindsOnTheBoxTower) {
  expect_search_matches_every_pair("contact/box_tower.json", 100, 100);
}

TEST(ContactSearch, FindsWhatTestingEveryCandidateFindsOnTheRodAndPolyp) {
  expect_search_matches_every_pair("contact/polyp.json", 1000, 200);
}

TEST(ContactSearch, FindsWhatTestingEveryCandidateFindsOnTheBilliard) {
  expect_search_matches_every_pair("optimization/billiard.json", 1000, 1);
}

}  // namespace
}  // namespace liedyn

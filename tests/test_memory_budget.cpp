// Memory admitted up front (problems/memory_budget.hpp) and the scene budget of rod nodes.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "../problems/memory_budget.hpp"
#include "../problems/scene.hpp"
#include "cli_fixture.hpp"

namespace liedyn {
namespace {

std::string cantilever_scene(int edges, int frames, bool optimization) {
  nlohmann::json s = {
      {"time_step", 0.001},
      {"frames", frames},
      {"rods",
       {{{"name", "rod"},
         {"shape", {{"type", "line"}, {"start", {0, 0, 0}}, {"end", {1, 0, 0}}, {"edges", edges}}},
         {"mass", 0.3},
         {"radius", 0.01},
         {"stretch_stiffness", 3000},
         {"shear_stiffness", 1200},
         {"bending_stiffness", {0.08, 0.08, 0.06}},
         {"fixed_nodes", {0}},
         {"fixed_edges", {0}}}}}};
  if (optimization) {
    s["optimization"] = {{"parameters", {{{"kind", "node_force"}, {"rod", "rod"}, {"node_force", 0}}}},
                         {"objective", {{{"term", "effort"}}}}};
    s["rods"][0]["node_forces"] = {{{"node", edges}, {"force", {0, 0, -0.01}}}};
  }
  return s.dump();
}

TEST(MemoryBudget, EstimateFollowsDofsAndKeptFrames) {
  const Scene scene = parse_scene(cantilever_scene(20000, 1000, false), "rod.json");
  const MemoryEstimate step_only = estimate_memory(scene, 0);
  EXPECT_EQ(step_only.trajectory, 0u);
  // 20001 points and 20000 rotations: 120003 DOFs at 480 bytes above 16 MB.
  EXPECT_NEAR(static_cast<double>(step_only.working_set), 16e6 + 480.0 * 120003, 1.0);
  const MemoryEstimate kept = estimate_memory(scene, 1);
  EXPECT_NEAR(static_cast<double>(kept.trajectory), 1001.0 * (24 * 20001 + 72 * 20000 + 48), 1.0);
  EXPECT_EQ(estimate_memory(scene, 2).trajectory, 2 * kept.trajectory);
}

TEST(MemoryBudget, ARunOverTheLimitIsRefusedNamingTheEstimate) {
  const Scene scene = parse_scene(cantilever_scene(20000, 1000000, true), "big.json");
  try {
    admit_memory(scene, 1, std::uint64_t{24} << 30);
    ADD_FAILURE() << "1e6 frames of a 20001-node rod must not be admitted in 24 GiB";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "--memory-limit");
    const std::string what = e.what();
    EXPECT_NE(what.find("for the trajectory kept for the adjoint: 1000000 frames"), std::string::npos) << what;
    EXPECT_NE(what.find("--memory-limit SIZE raises the limit"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(admit_memory(scene, 0, std::uint64_t{24} << 30)) << "simulate keeps no trajectory";
}

TEST(MemoryBudget, ByteSizes) {
  EXPECT_EQ(parse_byte_size("1000"), 1000u);
  EXPECT_EQ(parse_byte_size("4K"), 4096u);
  EXPECT_EQ(parse_byte_size("512M"), 512u << 20);
  EXPECT_EQ(parse_byte_size("1.5G"), 3u << 29);
  for (const char* bad : {"", "G", "-1G", "0", "4X", "4 G", "nan", "1e30T"}) {
    EXPECT_THROW(parse_byte_size(bad), std::invalid_argument) << bad;
  }
}

TEST(MemoryBudget, ExplicitNodesDrawOnTheRodBudget) {
  // Two generated rods of 1e6 edges take the whole budget; three explicit nodes more used to
  // pass (explicit node arrays bypassed it).
  nlohmann::json s = nlohmann::json::parse(cantilever_scene(1000000, 1, false));
  nlohmann::json second = s["rods"][0];
  second["name"] = "second";
  s["rods"].push_back(second);
  nlohmann::json third = s["rods"][0];
  third.erase("shape");
  third["name"] = "third";
  third["nodes"] = {{0, 1, 0}, {1, 1, 0}, {2, 1, 0}};
  s["rods"].push_back(third);
  try {
    parse_scene(s.dump(), "many.json");
    ADD_FAILURE() << "the explicit nodes must be counted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "rods[2].nodes");
    EXPECT_NE(std::string(e.what()).find("would bring the nodes of the scene's rods beyond"),
              std::string::npos)
        << e.what();
  }
}

class MemoryCli : public test::CliFixture {
 protected:
  MemoryCli() : CliFixture("liedyn_memory_test_") {}
};

TEST_F(MemoryCli, OptimizeRefusesWhatCannotFit) {
  { std::ofstream(dir_ / "big.json") << cantilever_scene(20000, 1000000, true); }
  const Result r = run({"optimize", "big.json", "--out", "out", "--memory-limit", "8G"});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("big.json: --memory-limit: the run needs about"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out"));
  const Result bad = run({"simulate", "big.json", "--out", "out", "--memory-limit", "lots"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--memory-limit: \"lots\" is not a size"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace liedyn

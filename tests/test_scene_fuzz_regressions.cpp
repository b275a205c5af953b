// Regressions found by fuzzing the scene loader (tests/fuzz/scene_fuzzer.cpp,
// docs/fuzzing.md): each input once crashed the fuzzer (undefined behaviour, or an allocation
// of gigabytes from a few bytes of JSON) and must now be a SceneError naming the field.

#include <gtest/gtest.h>

#include <string>

#include "problems/scene.hpp"

namespace liedyn::scene_fuzz_regressions_tests {
namespace {

// The field named by the SceneError that rejects `text`. Any other exception escapes and
// fails the test; an accepted scene fails it here.
std::string rejected_field(const std::string& text, std::string* reason = nullptr) {
  try {
    parse_scene(text, "fuzz_regression.json");
  } catch (const SceneError& e) {
    if (reason != nullptr) *reason = e.reason();
    return e.field();
  }
  ADD_FAILURE() << "scene was accepted:\n" << text.substr(0, 500);
  return "";
}

// A straight rod named `name` generated with `edges` edges, and further members `extra`
// (starting with ", " when not empty).
std::string line_rod(const std::string& name, int edges, const std::string& extra = "") {
  return R"({"name": ")" + name +
         R"(", "shape": {"type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": )" +
         std::to_string(edges) +
         R"(}, "mass": 1, "radius": 0.01, "stretch_stiffness": 1, "shear_stiffness": 1,
             "bending_stiffness": [1, 1, 1])" +
         extra + "}";
}

std::string rod_scene(const std::string& rods, const std::string& top = R"("frames": 2)") {
  return R"({"time_step": 0.01, )" + top + R"(, "rods": [)" + rods + "]}";
}

const std::string kBody = R"("bodies": [{"name": "b", "mass": 1, "inertia": [1, 1, 1]}])";

// Crash: UBSan "1e+300 is outside the range of representable values of type 'int'": cable
// edges were converted to int before their range was checked.
TEST(SceneFuzzRegressions, CableEdgesBeyondIntRange) {
  for (const char* edges : {"[1e300, 2]", "[0, 1e300]", "[-1e300, 2]", "[0, 2147483648]"}) {
    SCOPED_TRACE(edges);
    EXPECT_EQ(rejected_field(rod_scene(line_rod(
                  "r", 4, std::string(R"(, "cables": [{"edges": )") + edges + "}]"))),
              "rods[0].cables[0].edges");
  }
}

// Crash: UBSan "signed integer overflow: 3 * 2147483647 cannot be represented in type 'int'"
// in ParameterSet::block_size (a per-step force over INT_MAX frames). Optimisations now keep
// at most 10⁶ frames …
TEST(SceneFuzzRegressions, OptimizationFramesLimited) {
  const std::string optimization =
      R"("optimization": {"parameters": [{"kind": "force", "index": 0}],
         "objective": [{"term": "body_pose", "body": "b", "position": [0, 0, 0]}]})";
  const std::string forces = R"("forces": [{"body": "b", "force": [0, 0, 1]}])";
  std::string reason;
  EXPECT_EQ(rejected_field(R"({"time_step": 0.01, "frames": 2147483647, )" + kBody + ", " +
                               forces + ", " + optimization + "}",
                           &reason),
            "frames");
  EXPECT_NE(reason.find("1000000"), std::string::npos) << reason;
  EXPECT_NO_THROW(parse_scene(R"({"time_step": 0.01, "frames": 1000000, )" + kBody + ", " +
                                  forces + ", " + optimization + "}",
                              "fuzz_regression.json"));
}

// … and γ at most ParameterSet::kMaxSize numbers: 3 · (nodes − 2) · frames overflowed int
// for per-step rest Darboux vectors of a long rod.
TEST(SceneFuzzRegressions, ParameterVectorLimited) {
  const std::string optimization =
      R"("optimization": {"parameters": [{"kind": "rest_darboux_per_frame", "rod": "r"}],
         "objective": [{"term": "effort"}]})";
  std::string reason;
  EXPECT_EQ(rejected_field(rod_scene(line_rod("r", 1000), R"("frames": 1000000, )" + optimization),
                           &reason),
            "optimization.parameters[0]");
  EXPECT_NE(reason.find("10000000"), std::string::npos) << reason;
}

// OOM: "allocator is out of memory trying to allocate 0xbffffffe8 bytes": a
// projected_trajectory curve was resampled to one point per frame, for INT_MAX frames.
TEST(SceneFuzzRegressions, ProjectedTrajectoryOverTooManyFrames) {
  EXPECT_EQ(rejected_field(R"({"time_step": 0.01, "frames": 2147483647, )" + kBody + R"(,
      "optimization": {"parameters": [{"kind": "body_position", "body": "b"}],
        "objective": [{"term": "projected_trajectory", "body": "b",
                       "curve": [[0, 0], [1, 1], [2, 2]]}]}})"),
            "frames");
}

// OOM/timeout: each rod (or rest shape) could generate 10⁶ edges, so a few kB of JSON asked
// for 10⁸ nodes. The generators of a scene now produce at most 2·10⁶ edges together.
TEST(SceneFuzzRegressions, GeneratedEdgesLimitedPerScene) {
  const std::string big = line_rod("a", 1000000);
  const std::string rest =
      R"(, "rest_shape": {"type": "line", "start": [0, 0, 0], "end": [2, 0, 0], "edges": 1000000})";
  std::string reason;
  EXPECT_EQ(rejected_field(rod_scene(line_rod("a", 1000000, rest) + ", " + line_rod("b", 1)),
                           &reason),
            "rods[1].shape.edges");
  EXPECT_NE(reason.find("2000000"), std::string::npos) << reason;
  const std::string two_big = big + ", " + line_rod("b", 1000000);
  EXPECT_EQ(rejected_field(rod_scene(two_big + ", " + line_rod("c", 1))), "rods[2].shape.edges");
}

// OOM: every cable stores one route point per edge it spans, so a hundred cables along a rod
// of 10⁶ edges took gigabytes. The cables of a scene now route through at most 10⁶ points.
TEST(SceneFuzzRegressions, CablePointsLimitedPerScene) {
  const auto cables = [](int count) {
    std::string list;
    for (int i = 0; i < count; ++i) list += std::string(i ? ", " : "") + R"({"edges": [0, 999]})";
    return R"(, "cables": [)" + list + "]";
  };
  EXPECT_NO_THROW(parse_scene(rod_scene(line_rod("r", 1000, cables(1000))), "ok.json"));
  std::string reason;
  EXPECT_EQ(rejected_field(rod_scene(line_rod("r", 1000, cables(1001))), &reason),
            "rods[0].cables[1000].edges");
  EXPECT_NE(reason.find("1000000"), std::string::npos) << reason;
}

// Crash: "terminate called after throwing an instance of 'std::invalid_argument', what():
// psd_sqrt: the matrix has non-finite entries" when the Simulator was built: finite inputs whose
// inertia terms m/h², J/h² overflow (Model::validate now checks them, in dynamic mode).
TEST(SceneFuzzRegressions, InertiaOverTimeStepSquaredOverflows) {
  const auto rod = [](const std::string& nodes, const std::string& radius) {
    return R"({"name": "r", "nodes": )" + nodes + R"(, "mass": 1, "radius": )" + radius +
           R"(, "stretch_stiffness": 1, "shear_stiffness": 1, "bending_stiffness": [1, 1, 1]})";
  };
  std::string reason;
  EXPECT_EQ(rejected_field(rod_scene(rod("[[1e308, 0, 0], [-1e308, 0, 0]]", "0.01")), &reason),
            "rods[0].nodes[1]");
  EXPECT_NE(reason.find("overflows"), std::string::npos) << reason;
  EXPECT_EQ(rejected_field(rod_scene(rod("[[0, 0, 0], [1e200, 0, 0]]", "0.01"))),
            "rods[0].nodes[1]");  // ‖e‖ = √(e·e) overflows from about 1e154
  // A long edge or a thick rod: the edge inertia m (3r² + l²)/12 over h² = 1e-4 overflows.
  EXPECT_EQ(rejected_field(rod_scene(rod("[[0, 0, 0], [1e153, 0, 0]]", "0.01"))), "rods[0]");
  EXPECT_EQ(rejected_field(rod_scene(rod("[[0, 0, 0], [1, 0, 0]]", "1e200"))), "rods[0]");
  const std::string body = R"("bodies": [{"name": "b", "mass": 1e300, "inertia": [1, 1, 1]}])";
  EXPECT_EQ(rejected_field(R"({"time_step": 1e-10, "frames": 1, )" + body + "}"), "bodies[0]");
  EXPECT_EQ(rejected_field(R"({"time_step": 1e-200, "frames": 1, )" + kBody + "}"), "time_step");
  // Static mode has no inertia terms: the same time step only labels the frames there.
  EXPECT_NO_THROW(parse_scene(R"({"time_step": 1e-200, "frames": 1, "mode": "static", )" + kBody +
                                  R"(, "springs": [{"body_b": "b", "stiffness": 1}]})",
                              "fuzz_regression.json"));
}

}  // namespace
}  // namespace liedyn::scene_fuzz_regressions_tests

// scene_warnings (problems/scene_checks.hpp): each warning on a scene made to trigger it, and
// none on the bundled scenes.

#include <gtest/gtest.h>

#include <filesystem>

#include "../problems/scene.hpp"
#include "../problems/scene_checks.hpp"

namespace liedyn {
namespace {

const std::string kFloor = R"("colliders": [{"name": "floor", "type": "plane"}],)";

std::vector<std::string> warnings_of(const std::string& body_json, const std::string& extra = "") {
  return scene_warnings(parse_scene(
      R"({"time_step": 0.001, "frames": 1, )" + kFloor + extra + R"("bodies": [)" + body_json + "]}",
      "checks.json"));
}

std::string box_body(const std::string& name, double z, bool contact = true) {
  return R"({"name": ")" + name + R"(", "mass": 1, "inertia": [1, 1, 1], "position": [0, 0, )" +
         std::to_string(z) + "]" +
         (contact ? R"(, "contact": {"stiffness": 1e4, "radius": 0.01, "points": [[0, 0, -0.1], [0, 0, 0.1]]})"
                  : "") +
         "}";
}

TEST(SceneChecks, ASampleStartingInsideAColliderIsNamed) {
  EXPECT_TRUE(warnings_of(box_body("box", 0.2)).empty());
  EXPECT_TRUE(warnings_of(box_body("box", 0.105)).empty()) << "within its radius: an ordinary contact";
  const auto w = warnings_of(box_body("box", -0.45));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("bodies[0] (\"box\"): contact sample 0 starts 0.56 m inside colliders[0] (\"floor\")"),
            std::string::npos)
      << w[0];
}

TEST(SceneChecks, CollidersThatTouchNothing) {
  const auto w = warnings_of(box_body("box", 1.0, false));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("1 collider(s) touch nothing"), std::string::npos) << w[0];
}

TEST(SceneChecks, OverlappingBodies) {
  EXPECT_TRUE(warnings_of(box_body("a", 1.0) + "," + box_body("b", 1.5)).empty());
  const auto w = warnings_of(box_body("a", 1.0) + "," + box_body("b", 1.1));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("bodies[0] (\"a\") and bodies[1] (\"b\") start with overlapping contact samples"),
            std::string::npos)
      << w[0];
}

// Bodies with shapes touch each other: overlapping bounding boxes are ordinary, but a sample
// that starts inside the other's shape is named.
TEST(SceneChecks, BodiesWithShapesWarnOnlyWhenOneStartsInsideTheOther) {
  const auto ball = [](const std::string& name, double z) {
    return R"({"name": ")" + name + R"(", "mass": 1, "inertia": [1, 1, 1], "position": [0, 0, )" + std::to_string(z) +
           R"(], "contact": {"stiffness": 1e4, "radius": 0.01, "shape": {"type": "sphere", "radius": 0.1},
               "sample_spacing": 0.05}})";
  };
  EXPECT_TRUE(warnings_of(ball("a", 1.0) + "," + ball("b", 1.205)).empty());
  const auto w = warnings_of(ball("a", 1.0) + "," + ball("b", 1.15));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("bodies[0] (\"a\") and bodies[1] (\"b\"): contact sample ", 0), 0u) << w[0];
  EXPECT_NE(w[0].find("inside the shape of \"b\""), std::string::npos) << w[0];
}

TEST(SceneChecks, BundledScenesWarnOfNothing) {
  int scenes = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(
           std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes")) {
    if (entry.path().extension() != ".json") continue;
    ++scenes;
    const std::vector<std::string> w = scene_warnings(load_scene(entry.path()));
    EXPECT_TRUE(w.empty()) << entry.path() << ": " << (w.empty() ? "" : w.front());
  }
  EXPECT_GT(scenes, 20);
}

}  // namespace
}  // namespace liedyn

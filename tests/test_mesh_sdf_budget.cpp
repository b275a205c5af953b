// The work budget of GridSdf (lib/mesh_sdf.hpp, "Work budget"; issue 17, item 11): the build's
// point-triangle distances are estimated before the build, a grid beyond max_build_work is
// refused at once (GridSdfTooCostly, naming the estimate and what to change), and in a scene
// that refusal is a SceneError on the collider's cell_size. The case of the issue, a
// 327680-triangle mesh at 0.8 mm cells, took minutes to load; it is generated here.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "lib/mesh_sdf.hpp"
#include "problems/scene.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;

// Unit icosahedron subdivided `level` times, projected to the sphere of radius r: 20·4^level
// triangles, outward (as tests/test_mesh_sdf.cpp).
TriangleMesh icosphere(int level, double r) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vector3> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                            {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                            {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (Vector3& x : v) x.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      const int id = static_cast<int>(v.size()) - 1;
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<int, 3>> next;
    next.reserve(4 * f.size());
    for (const auto& t : f) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
  TriangleMesh m;
  for (const Vector3& x : v) m.vertices.push_back(r * x);
  m.triangles = f;
  return m;
}

// The axis-aligned box [0, a] (12 triangles, outward).
TriangleMesh box(const Vector3& a) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1) ? a.x() : 0.0, (i & 2) ? a.y() : 0.0, (i & 4) ? a.z() : 0.0);
  }
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

std::string what_of(const TriangleMesh& mesh, double h, double padding, double max_work) {
  try {
    GridSdf g(mesh, h, padding, 20000000, max_work);
  } catch (const GridSdfTooCostly& e) {
    return e.what();
  }
  return "";
}

TEST(GridSdfBudget, TheEstimateIsCloseToTheWorkDone) {
  struct Case {
    const char* name;
    TriangleMesh mesh;
    double h, budget;  // a budget below 3 N T, so that the work is estimated
  };
  const Case cases[] = {
      {"icosphere 5120, 64^3", icosphere(4, 1.0), 2.06 / 63.0, kDefaultMaxBuildWork},
      {"icosphere 20480, 35^3", icosphere(5, 1.0), 0.065, kDefaultMaxBuildWork},
      {"box 12, 203 x 103 x 53", box(Vector3(2.0, 1.0, 0.5)), 0.01, 2e7},
  };
  for (const Case& c : cases) {
    const GridSdf g(c.mesh, c.h, 0.03, 20000000, c.budget);
    ASSERT_GT(g.estimated_build_work(), 0.0) << c.name << ": 3 N T is within the budget";
    EXPECT_NEAR(g.estimated_build_work() / g.build_work(), 1.0, 0.25)
        << c.name << ": estimated " << g.estimated_build_work() << ", done " << g.build_work();
    EXPECT_LE(g.build_work(), c.budget) << c.name;
  }
  // Where 3 N T is within the budget nothing is estimated.
  const GridSdf small(box(Vector3::Ones()), 0.1, 0.1);
  EXPECT_EQ(small.estimated_build_work(), 0.0);
  EXPECT_GT(small.build_work(), 0.0);
  EXPECT_LE(small.build_work(), 3.0 * 13 * 13 * 13 * 12);
}

TEST(GridSdfBudget, BeyondTheBudgetTheGridIsRefusedWithWhatToChange) {
  const TriangleMesh sphere = icosphere(4, 1.0);  // ~3e7 distances at 64³ nodes
  const double h = 2.06 / 63.0;
  const std::string msg = what_of(sphere, h, 0.03, 1e7);
  EXPECT_NE(msg.find("GridSdf: building the grid of 64 x 64 x 64 nodes for 5120 triangles "
                     "needs about "),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("point-triangle distances (estimated from"), std::string::npos) << msg;
  EXPECT_NE(msg.find("more than max_build_work = 1e+07"), std::string::npos) << msg;
  EXPECT_NE(msg.find("increase cell_size = "), std::string::npos) << msg;
  EXPECT_NE(msg.find("or use a mesh with fewer triangles"), std::string::npos) << msg;
  // The same grid within a budget builds.
  EXPECT_EQ(what_of(sphere, h, 0.03, 1e8), "");
  // A budget below 1 is bad input, not a too costly grid.
  try {
    GridSdf g(sphere, 0.1, 0.1, 20000000, 0.5);
    ADD_FAILURE() << "no error";
  } catch (const GridSdfTooCostly& e) {
    ADD_FAILURE() << e.what();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_build_work must be >= 1"), std::string::npos);
  }
  // The cell cap is a GridSdfTooCostly too.
  EXPECT_NE(what_of(sphere, 0.0012, 0.1, 1e9).find("more than max_cells"), std::string::npos);
}

// The issue's mesh: 327680 triangles on a sphere of radius 0.1 m, 0.8 mm cells (255³ nodes,
// ~2e10 distances, minutes to build). In a scene, refused at once naming cell_size.
TEST(GridSdfBudget, TheIssuesMeshInASceneIsRefusedNamingCellSize) {
  std::random_device rd;
  const fs::path dir = fs::temp_directory_path() / ("liedyn_test_budget_" + std::to_string(rd()));
  fs::create_directories(dir);
  {
    const TriangleMesh m = icosphere(7, 0.1);
    ASSERT_EQ(m.triangles.size(), 327680u);
    std::ofstream obj(dir / "sphere.obj");
    obj.precision(12);
    for (const Vector3& x : m.vertices) obj << "v " << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
    for (const auto& t : m.triangles) obj << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
  const std::string text = R"({"time_step": 0.01, "frames": 5, "colliders": [
      {"type": "mesh", "file": "sphere.obj", "cell_size": 0.0008}],
      "bodies": [{"name": "a", "mass": 2, "inertia": [1, 2, 2.5]}]})";
  const std::string source = (dir / "scene.json").string();
  try {
    parse_scene(text, source);
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), source);
    EXPECT_EQ(e.field(), "colliders[0].cell_size");
    EXPECT_NE(e.reason().find("255 x 255 x 255 nodes for 327680 triangles needs about"),
              std::string::npos)
        << e.reason();
    EXPECT_NE(e.reason().find("increase cell_size = 0.0008 to about"), std::string::npos)
        << e.reason();
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace liedyn

// Seeing a run (problems/shapes.hpp, problems/view.hpp): the shapes written beside a
// trajectory, the tessellated surfaces, `liedyn simulate --every`, and `liedyn view` — the
// page's data decoded back and checked against the run, its errors, and the page itself
// loaded and drawn by headless Chromium.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "problems/scene.hpp"
#include "problems/shapes.hpp"
#include "problems/view.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Signed volume by the divergence theorem (positive for outward triangles), and whether every
// edge is shared by exactly two triangles that run along it in opposite directions (closed and
// consistently oriented).
double signed_volume(const TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles) {
    v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
  }
  return v;
}
bool closed_and_oriented(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1) return false;
    const auto back = directed.find({edge.second, edge.first});
    if (back == directed.end() || back->second != 1) return false;
  }
  return true;
}

TEST(Tessellate, SurfacesAreClosedFaceOutwardsAndHoldTheirVolume) {
  // A regular 24-gon holds (24/2π) sin(2π/24) = 98.9 % of its circle's area; a torus's
  // surface is two such circles deep: 3 % covers both.
  struct Case {
    const char* name;
    Shape shape;
    double volume;
  };
  const double pi = M_PI;
  // The shapes of an export besides (problems/export_geometry.hpp): a rounded box is its inner
  // box, its faces' slabs, its edges' quarter cylinders and its corners' sphere octants; a tube
  // along a straight line is a capsule.
  const Vector3 b(0.4, 0.3, 0.2);  // a box of half extents 0.5, 0.4, 0.3 rounded by 0.1
  const double rounded_box = 8 * b.prod() + 8 * 0.1 * (b.x() * b.y() + b.y() * b.z() + b.z() * b.x()) +
                             2 * pi * 0.01 * b.sum() + 4.0 / 3 * pi * 0.001;
  for (const Case& c : {Case{"torus", TorusShape{1.0, 0.25}, 2 * pi * pi * 1.0 * 0.0625},
                        Case{"link", LinkShape{0.5, 0.5, 0.1}, 2 * pi * pi * 0.5 * 0.01 + 2 * 1.0 * pi * 0.01},
                        Case{"cylinder", CylinderShape{0.5, 1.0}, pi * 0.25 * 2.0},
                        Case{"sphere", SphereShape{0.5}, 4.0 / 3 * pi * 0.125},
                        Case{"capsule", CapsuleShape{1.0, 0.5}, pi * 0.25 * 2.0 + 4.0 / 3 * pi * 0.125},
                        Case{"box", BoxShape{Vector3(0.5, 0.4, 0.3), 0.0}, 8 * 0.06},
                        Case{"rounded box", BoxShape{Vector3(0.5, 0.4, 0.3), 0.1}, rounded_box},
                        Case{"tube", TubeShape{{Vector3(0, 0, 0), Vector3(1, 1, 0), Vector3(2, 2, 0)}, 0.5},
                             pi * 0.25 * 2 * std::sqrt(2.0) + 4.0 / 3 * pi * 0.125}}) {
    SCOPED_TRACE(c.name);
    const TriangleMesh m = tessellate(c.shape, 24);
    EXPECT_TRUE(closed_and_oriented(m));
    const double v = signed_volume(m);
    std::printf("%s: volume %.5f, exact %.5f (%.2f %%)\n", c.name, v, c.volume, 100 * (v / c.volume - 1));
    EXPECT_GT(v, 0.97 * c.volume);
    EXPECT_LE(v, 1.0001 * c.volume);
  }
  // A bent tube: closed and outward too (its volume is not a formula's).
  const TriangleMesh bent = tessellate(TubeShape{{Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(1, 1, 0.5)}, 0.1}, 12);
  EXPECT_TRUE(closed_and_oriented(bent));
  EXPECT_GT(signed_volume(bent), 0.0);
  EXPECT_THROW(tessellate(PlaneShape{}, 24), std::invalid_argument);
  EXPECT_THROW(tessellate(TorusShape{}, 2), std::invalid_argument);
}

constexpr const char* kShapesScene = R"({
  "time_step": 0.01, "frames": 10, "gravity": [0, 0, -9.81],
  "bodies": [
    { "name": "ball", "mass": 1, "inertia": [0.004, 0.004, 0.004], "position": [0, 0, 1],
      "contact": { "shape": { "type": "sphere", "radius": 0.1 }, "sample_spacing": 0.05, "stiffness": 1e4 } },
    { "name": "brick", "mass": 1, "inertia": [0.004, 0.004, 0.004], "position": [1, 0, 1],
      "contact": { "shape": { "type": "box", "half_extents": [0.1, 0.2, 0.3], "rounding": 0.01 },
                   "sample_spacing": 0.05, "stiffness": 1e4 } },
    { "name": "link", "mass": 1, "inertia": [0.004, 0.004, 0.004], "position": [2, 0, 1],
      "contact": { "shape": { "type": "link", "half_length": 0.1, "major_radius": 0.1, "minor_radius": 0.02 },
                   "sample_spacing": 0.02, "stiffness": 1e4 } },
    { "name": "bare", "mass": 2, "inertia": [0.02, 0.02, 0.02], "position": [3, 0, 1] } ],
  "rods": [ { "name": "cable", "shape": { "type": "line", "start": [0, 1, 1], "end": [1, 1, 1], "edges": 4 },
              "mass": 0.1, "radius": 0.01, "stretch_stiffness": 100, "shear_stiffness": 100,
              "bending_stiffness": [0.01, 0.01, 0.01] } ],
  "colliders": [
    { "name": "floor", "type": "plane", "position": [0, 0, 0], "normal": [0, 0, 1] },
    { "name": "ring", "type": "torus", "position": [0, 0, 3], "major_radius": 1, "minor_radius": 0.1 },
    { "name": "pipe", "type": "tube", "points": [[0, 0, 5], [1, 0, 5], [2, 1, 5]], "radius": 0.2, "inside": true } ] })";

TEST(SceneShapes, EveryObjectWithWhatItTakesToDrawIt) {
  const Scene scene = parse_scene(kShapesScene, "shapes.json");
  const json j = json::parse(scene_shapes(scene, 3).dump());
  EXPECT_EQ(j["title"], "shapes.json");
  EXPECT_EQ(j["time_step"], 0.01);
  EXPECT_EQ(j["trajectory_every"], 3);
  ASSERT_EQ(j["bodies"].size(), 4u);
  EXPECT_EQ(j["bodies"][0]["shape"], (json{{"type", "sphere"}, {"radius", 0.1}}));
  EXPECT_EQ(j["bodies"][1]["shape"]["type"], "box");
  EXPECT_EQ(j["bodies"][1]["shape"]["half_extents"], (json{0.1, 0.2, 0.3}));
  EXPECT_EQ(j["bodies"][1]["shape"]["rounding"], 0.01);
  EXPECT_EQ(j["bodies"][2]["shape"]["type"], "mesh");  // a link: its surface
  EXPECT_EQ(j["bodies"][2]["shape"]["vertices"].size() % 3, 0u);
  EXPECT_GT(j["bodies"][2]["shape"]["triangles"].size(), 100u);
  // No solid, no samples: a triad the size of the ball with its inertia (tr I = 6/5 m r²).
  EXPECT_EQ(j["bodies"][3]["shape"]["type"], "axes");
  EXPECT_NEAR(j["bodies"][3]["shape"]["size"].get<double>(), std::sqrt(5 * 0.06 / 12), 1e-12);
  EXPECT_EQ(j["rods"][0], (json{{"name", "cable"}, {"nodes", 5}, {"radius", 0.01}}));
  ASSERT_EQ(j["colliders"].size(), 3u);
  EXPECT_EQ(j["colliders"][0]["type"], "plane");
  EXPECT_EQ(j["colliders"][0]["normal"], (json{0, 0, 1}));
  EXPECT_EQ(j["colliders"][1]["type"], "mesh");  // a torus collider: its surface, in the world
  EXPECT_NEAR(j["colliders"][1]["vertices"][2].get<double>(), 3.0, 0.11);
  EXPECT_EQ(j["colliders"][2]["type"], "tube");
  EXPECT_EQ(j["colliders"][2]["inside"], true);
  EXPECT_EQ(j["colliders"][2]["points"], (json{0, 0, 5, 1, 0, 5, 2, 1, 5}));
}

// ---------------------------------------------------------------------------------------
// simulate --every, liedyn view
// ---------------------------------------------------------------------------------------

class ViewCli : public test::CliFixture {
 protected:
  ViewCli() : CliFixture("liedyn_view_") {}
  void SetUp() override {
    CliFixture::SetUp();
    std::ofstream(dir_ / "scene.json") << kShapesScene;
  }

  // The page's metadata and decoded poses.
  struct Page {
    std::string html;
    json meta;
    std::vector<float> poses;
  };
  Page page(const fs::path& file) {
    Page p;
    p.html = test::read_file(file);
    const auto between = [&](const std::string& open, const std::string& close) {
      const std::size_t a = p.html.find(open);
      EXPECT_NE(a, std::string::npos) << open;
      const std::size_t start = p.html.find('>', a) + 1;
      return p.html.substr(start, p.html.find(close, start) - start);
    };
    p.meta = json::parse(between("<script id=\"liedyn-meta\"", "</script>"));
    std::string b64 = between("<script id=\"liedyn-frames\"", "</script>");
    b64.erase(std::remove_if(b64.begin(), b64.end(), ::isspace), b64.end());
    std::string bytes;
    int bits = 0;
    unsigned value = 0;
    for (const char c : b64) {
      const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
      if (c == '=') break;
      value = (value << 6) | static_cast<unsigned>(alphabet.find(c));
      bits += 6;
      if (bits >= 8) {
        bits -= 8;
        bytes += static_cast<char>((value >> bits) & 0xFF);
      }
    }
    p.poses.resize(bytes.size() / 4);
    std::memcpy(p.poses.data(), bytes.data(), p.poses.size() * 4);
    return p;
  }
};

TEST_F(ViewCli, EveryNthFrameAndTheLastAndAPageThatHoldsThem) {
  const Result sim = run({"simulate", "scene.json", "--out", "out", "--every", "4", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  // trajectory.csv: frames 0, 4, 8 and the last (10); frames.csv: all 11.
  std::vector<int> written;
  std::istringstream trajectory(test::read_file(dir_ / "out" / "trajectory.csv"));
  std::string line;
  std::getline(trajectory, line);
  while (std::getline(trajectory, line)) {
    const int frame = std::stoi(line.substr(0, line.find(',')));
    if (written.empty() || written.back() != frame) written.push_back(frame);
  }
  EXPECT_EQ(written, (std::vector<int>{0, 4, 8, 10}));
  std::istringstream frames(test::read_file(dir_ / "out" / "frames.csv"));
  int rows = -1;
  while (std::getline(frames, line)) ++rows;
  EXPECT_EQ(rows, 11);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "shapes.json"));

  const Result v = run({"view", "out"});
  ASSERT_EQ(v.exit_code, 0) << v.err;
  EXPECT_NE(v.out.find("view: 4 frames, 8 objects"), std::string::npos) << v.out;
  const Page p = page(dir_ / "out" / "view.html");
  EXPECT_EQ(p.html.find("/*LIEDYN_"), std::string::npos);  // every placeholder filled
  EXPECT_EQ(p.meta["frame_numbers"], (json{0, 4, 8, 10}));
  EXPECT_NEAR(p.meta["times"][3].get<double>(), 0.1, 1e-12);
  EXPECT_EQ(p.meta["series"]["iterations"].size(), 4u);
  // 4 bodies × 7 floats, the rod's 5 nodes × 3 and 4 edges × 4.
  const std::size_t stride = 4 * 7 + 5 * 3 + 4 * 4;
  ASSERT_EQ(p.poses.size(), 4 * stride);
  // The last frame's ball: its position and unit quaternion as trajectory.csv has them.
  const float* last = p.poses.data() + 3 * stride;
  std::istringstream again(test::read_file(dir_ / "out" / "trajectory.csv"));
  std::string row, last_ball;
  while (std::getline(again, row)) {
    if (row.rfind("10,", 0) == 0 && row.find(",ball,") != std::string::npos) last_ball = row;
  }
  ASSERT_FALSE(last_ball.empty());
  std::vector<double> fields;
  std::istringstream f(last_ball);
  for (std::string v; std::getline(f, v, ',');) fields.push_back(std::atof(v.c_str()));
  for (int c = 0; c < 7; ++c) EXPECT_FLOAT_EQ(last[c], static_cast<float>(fields[5 + c])) << c;
  EXPECT_NEAR(std::hypot(std::hypot(last[3], last[4]), std::hypot(last[5], last[6])), 1.0, 1e-6);
}

TEST_F(ViewCli, RunsThatDoNotHangTogetherAreRefusedNamingTheFileAndLine) {
  ASSERT_EQ(run({"simulate", "scene.json", "--out", "out", "--quiet"}).exit_code, 0);
  // Another run's shapes.json beside this trajectory.
  std::string shapes = test::read_file(dir_ / "out" / "shapes.json");
  const std::string renamed = std::regex_replace(shapes, std::regex("\"ball\""), "\"bowl\"");
  std::ofstream(dir_ / "out" / "shapes.json") << renamed;
  Result r = run({"view", "out"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("trajectory.csv: line 2: is ball body 0 where shapes.json has bowl body 0"),
            std::string::npos) << r.err;
  std::ofstream(dir_ / "out" / "shapes.json") << shapes;
  // A trajectory cut within a frame.
  std::string trajectory = test::read_file(dir_ / "out" / "trajectory.csv");
  trajectory.resize(trajectory.rfind('\n', trajectory.size() - 2) + 1);
  std::ofstream(dir_ / "out" / "trajectory.csv") << trajectory;
  r = run({"view", "out"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("ends within a frame"), std::string::npos) << r.err;
  // shapes.json edited into nonsense: errors naming it, never a crash.
  for (const auto& [text, field] : std::vector<std::pair<std::string, std::string>>{
           {R"({"bodies": [], "rods": []})", "bodies"},
           {R"({"title": 3, "bodies": [], "rods": []})", "title"},
           {R"({"bodies": [], "rods": [{"name": "r", "nodes": 2000000000, "radius": 1}]})", "rods"}}) {
    std::ofstream(dir_ / "out" / "shapes.json") << text;
    r = run({"view", "out"});
    EXPECT_EQ(r.exit_code, 2) << text;
    EXPECT_NE(r.err.find("shapes.json: " + field + ":"), std::string::npos) << r.err;
  }
  std::ofstream(dir_ / "out" / "shapes.json") << shapes;
  // No run here at all.
  r = run({"view", "nowhere"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nowhere/shapes.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "view.html"));
}

TEST_F(ViewCli, InlinedTextCannotCloseItsScriptElement) {
  ASSERT_EQ(run({"simulate", "scene.json", "--out", "out", "--quiet"}).exit_code, 0);
  // A three.js whose text holds a closing tag: inlined as is, the page would end there.
  fs::create_directories(dir_ / "three" / "examples" / "js" / "controls");
  std::ofstream(dir_ / "three" / "three.min.js") << "var THREE = {}; // </script><b>oops</b>\n";
  std::ofstream(dir_ / "three" / "examples" / "js" / "controls" / "OrbitControls.js") << "// </SCRIPT>\n";
  write_view(dir_ / "out", ViewOptions{dir_ / "three"});
  const std::string html = test::read_file(dir_ / "out" / "view.html");
  EXPECT_NE(html.find("// <\\/script><b>oops</b>"), std::string::npos);
  EXPECT_EQ(html.find("</script><b>oops"), std::string::npos);
  EXPECT_NE(html.find("// <\\/SCRIPT>"), std::string::npos);
  // A missing three.js: SceneError naming it and the package.
  try {
    write_view(dir_ / "out", ViewOptions{dir_ / "no-three"});
    ADD_FAILURE() << "wrote a page without three.js";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("libjs-three"), std::string::npos) << e.what();
  }
}

// The page in a real browser: scripts/viewer/check_view.sh runs Debian's Chromium headless on
// a page (with its fragment) and writes its report to check.txt; `options` go before the page,
// `counts` (expected frames and objects) after the picture.
class ViewCliChromium : public ViewCli {
 protected:
  void SetUp() override {
    ViewCli::SetUp();
    if (std::system("command -v chromium > /dev/null 2>&1") != 0) {
      GTEST_SKIP() << "chromium is not installed (scripts/install-deps.sh installs it)";
    }
  }
  // check_view.sh's exit status; its output in `report`.
  int check(const std::string& options, const std::string& page, std::string& report,
            const std::string& counts = "") {
    const std::string command = "bash '" + std::string(LIEDYN_SOURCE_DIR) + "/scripts/viewer/check_view.sh' " +
                                options + " '" + (dir_ / page).string() + "' '" + (dir_ / "shot.png").string() +
                                "' " + counts + " > '" + (dir_ / "check.txt").string() + "' 2>&1";
    const int status = std::system(command.c_str());
    report = test::read_file(dir_ / "check.txt");
    return status == -1 || !WIFEXITED(status) ? -1 : WEXITSTATUS(status);
  }
};

// It loads the poses, reports them, and draws (pixels that are not the background).
TEST_F(ViewCliChromium, LoadsThePageAndDrawsTheScene) {
  ASSERT_EQ(run({"simulate", "scene.json", "--out", "out", "--quiet"}).exit_code, 0);
  ASSERT_EQ(run({"view", "out"}).exit_code, 0);
  std::string report;
  EXPECT_EQ(check("", "out/view.html", report, "11 8"), 0) << report;
  EXPECT_NE(report.find("page drew frame 0 (t = 0 s)"), std::string::npos) << report;
}

// The fragment chooses the frame to show (by number or time; with --every 4 the written frames
// are 0, 4, 8 and 10) and the page says when it has drawn it; bad options are warned about and
// ignored, never an error.
TEST_F(ViewCliChromium, TheFragmentChoosesTheFrameAndBadOptionsAreIgnored) {
  ASSERT_EQ(run({"simulate", "scene.json", "--out", "out", "--every", "4", "--quiet"}).exit_code, 0);
  ASSERT_EQ(run({"view", "out"}).exit_code, 0);
  std::string report;
  EXPECT_EQ(check("--size 480x360 --drawn 10", "out/view.html#frame=last&paused&hide=panel,ui", report), 0)
      << report;
  EXPECT_NE(report.find("screenshot 480x360"), std::string::npos) << report;
  EXPECT_EQ(report.find("page warning"), std::string::npos) << report;
  EXPECT_EQ(check("--drawn 8", "out/view.html#t=0.075&paused&edges&camera=30,60&fit=frame&zoom=0.5", report), 0) << report;
  // Frame 5 was not written: the nearest that was, with a warning.
  EXPECT_EQ(check("--drawn 4", "out/view.html#frame=5&paused", report), 0) << report;
  EXPECT_NE(report.find("page warning: #frame=5: frame 5 was not written: showing frame 4"), std::string::npos)
      << report;
  // Each bad option warned about; the page still opens, at frame 0, and draws.
  EXPECT_EQ(check("--drawn 0",
                  "out/view.html#frame=11&t=x&paused=maybe&hide=panel,menu&camera=0,90&fit=all&zoom=0&colour=red",
                  report),
            0)
      << report;
  for (const char* warning : {"#frame=11: the run has frames 0 to 10; ignored", "#t=x: expected a time",
                              "#paused=maybe: expected no value, 1 or 0", "\"menu\" is none of panel, ui, title",
                              "#camera=0,90: expected AZ,EL", "#fit=all: expected run or frame", "#zoom=0: expected a number > 0",
                              "#colour=red: unknown option"}) {
    EXPECT_NE(report.find(warning), std::string::npos) << warning << "\n" << report;
  }
}

// The first view holds the whole run: a solid placed off its body's origin (its shape's
// "position") and a collider of finite size on the other side, nothing cut off at the edges.
// (Bounded about the body's origin instead, the ball would stick out on the right.)
TEST_F(ViewCliChromium, TheFirstViewHoldsOffsetSolidsAndFiniteColliders) {
  std::ofstream(dir_ / "apart.json") << R"({
    "time_step": 0.01, "frames": 4, "gravity": [0, 0, 0],
    "bodies": [ { "name": "weight", "mass": 1, "inertia": [0.1, 0.1, 0.1], "position": [0, 0, 0],
                  "contact": { "shape": { "type": "sphere", "radius": 1, "position": [1.8, 0, 0] },
                               "sample_spacing": 0.5, "stiffness": 1e4 } } ],
    "colliders": [ { "name": "post", "type": "sphere", "radius": 0.5, "position": [-3, 0, 0] } ] })";
  const Result sim = run({"simulate", "apart.json", "--out", "out", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  ASSERT_EQ(run({"view", "out"}).exit_code, 0);
  std::string report;
  EXPECT_EQ(check("--clear-edges --drawn 4", "out/view.html#frame=last&paused&hide=panel,ui,title", report), 0)
      << report;
  EXPECT_NE(report.find("nothing drawn within 2 pixels of the edges"), std::string::npos) << report;
}

}  // namespace
}  // namespace liedyn

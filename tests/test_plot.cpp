// Plots (problems/plot.hpp): pareto_front against its definition on hand-made and random sets;
// write_png writes a PNG of the requested size (read back with Cairo) with the data drawn,
// copes with degenerate inputs (nothing drawable: the note instead), and fails naming the file
// without leaving a temporary file behind.

#include <cairo.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "problems/plot.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<PlotPoint> points(const std::vector<std::pair<double, double>>& xy) {
  std::vector<PlotPoint> out;
  for (const auto& [x, y] : xy) out.push_back({x, y});
  return out;
}

using Indices = std::vector<std::size_t>;

TEST(ParetoFront, EmptyAndSingle) {
  EXPECT_EQ(pareto_front({}), Indices{});
  EXPECT_EQ(pareto_front(points({{3, 4}})), Indices{0});
}

TEST(ParetoFront, DominatedPointsAreDroppedAndTheFrontIsSortedByX) {
  // Front: (1, 9), (2, 5), (6, 1); (3, 6) and (7, 7) are dominated by (2, 5).
  EXPECT_EQ(pareto_front(points({{6, 1}, {3, 6}, {2, 5}, {7, 7}, {1, 9}})), (Indices{4, 2, 0}));
}

TEST(ParetoFront, TiesOnOneCoordinateKeepOnlyTheBetterPoint) {
  // Same x: the larger y is dominated; same y: the larger x is.
  EXPECT_EQ(pareto_front(points({{2, 5}, {2, 3}})), Indices{1});
  EXPECT_EQ(pareto_front(points({{4, 3}, {2, 3}})), Indices{1});
  // A staircase with a shared x and a shared y.
  EXPECT_EQ(pareto_front(points({{1, 4}, {1, 6}, {3, 2}, {5, 2}, {3, 3}})), (Indices{0, 2}));
}

TEST(ParetoFront, DuplicatesDoNotDominateEachOther) {
  EXPECT_EQ(pareto_front(points({{2, 2}, {1, 3}, {2, 2}, {2, 2}})), (Indices{1, 0, 2, 3}));
  // ... but a dominated duplicate pair stays dominated.
  EXPECT_EQ(pareto_front(points({{3, 3}, {3, 3}, {1, 1}})), Indices{2});
  // 0 and -0 are equal.
  EXPECT_EQ(pareto_front(points({{0.0, 1}, {-0.0, 1}})), (Indices{0, 1}));
}

TEST(ParetoFront, NonFinitePointsAreNeverOnTheFrontNorDominate) {
  EXPECT_EQ(pareto_front(points({{kNaN, 1}, {1, kNaN}, {kInf, 1}, {1, kInf}})), Indices{});
  // -inf would dominate everything if it counted.
  EXPECT_EQ(pareto_front(points({{-kInf, -kInf}, {2, 2}, {kNaN, kNaN}, {1, 3}, {3, -kInf}})),
            (Indices{3, 1}));
  // Zero and negative values are ordinary numbers here.
  EXPECT_EQ(pareto_front(points({{0, 5}, {-1, 7}, {2, 0}, {3, -1}})), (Indices{1, 0, 2, 3}));
}

TEST(ParetoFront, MatchesTheDefinitionOnRandomSets) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coordinate(0, 6);  // small range: many ties and duplicates
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<PlotPoint> set;
    const int n = trial % 15;
    for (int i = 0; i < n; ++i) {
      set.push_back({static_cast<double>(coordinate(rng)), static_cast<double>(coordinate(rng))});
      if (coordinate(rng) == 0) set.back().y = kNaN;
    }
    Indices expected;
    for (std::size_t i = 0; i < set.size(); ++i) {
      const PlotPoint& p = set[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
      bool dominated = false;
      for (const PlotPoint& q : set) {
        dominated = dominated || (q.x <= p.x && q.y <= p.y && (q.x < p.x || q.y < p.y));
      }
      if (!dominated) expected.push_back(i);
    }
    std::stable_sort(expected.begin(), expected.end(), [&](std::size_t a, std::size_t b) {
      return set[a].x < set[b].x || (set[a].x == set[b].x && set[a].y < set[b].y);
    });
    EXPECT_EQ(pareto_front(set), expected) << "trial " << trial;
  }
}

// A PNG read back with Cairo.
class Image {
 public:
  explicit Image(const fs::path& file)
      : surface_(cairo_image_surface_create_from_png(file.c_str()), cairo_surface_destroy) {}
  cairo_status_t status() const { return cairo_surface_status(surface_.get()); }
  int width() const { return cairo_image_surface_get_width(surface_.get()); }
  int height() const { return cairo_image_surface_get_height(surface_.get()); }
  // 0xAARRGGBB.
  std::uint32_t pixel(int x, int y) const {
    const unsigned char* row = cairo_image_surface_get_data(surface_.get()) +
                               static_cast<std::ptrdiff_t>(y) *
                                   cairo_image_surface_get_stride(surface_.get());
    return reinterpret_cast<const std::uint32_t*>(row)[x];
  }
  // Pixels in [x0, x1) × [y0, y1) (fractions of the size) for which `test(r, g, b)` holds.
  int count(double x0, double x1, double y0, double y1,
            const std::function<bool(int, int, int)>& test) const {
    cairo_surface_flush(surface_.get());
    int n = 0;
    for (int y = static_cast<int>(y0 * height()); y < static_cast<int>(y1 * height()); ++y) {
      for (int x = static_cast<int>(x0 * width()); x < static_cast<int>(x1 * width()); ++x) {
        const std::uint32_t p = pixel(x, y);
        n += test((p >> 16) & 0xff, (p >> 8) & 0xff, p & 0xff) ? 1 : 0;
      }
    }
    return n;
  }

 private:
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface_;
};

bool non_white(int r, int g, int b) { return r < 240 || g < 240 || b < 240; }
bool blue(int r, int, int b) { return b > r + 80; }  // series 0's markers
bool red(int r, int g, int) { return r > g + 60; }   // the note about hidden runs

class Plot : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("liedyn_test_plot_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Files in the test directory that look like AtomicFile temporaries.
  int temporaries() const {
    int n = 0;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      n += entry.path().filename().string().find(".liedyn-") != std::string::npos ? 1 : 0;
    }
    return n;
  }

  static ScatterPlot sweep() {
    ScatterPlot plot;
    plot.title = "error against cost";
    plot.x_label = "cost (s)";
    plot.y_label = "error";
    plot.series_names = {"newton", "ceres"};
    for (int i = 0; i < 6; ++i) {
      const double h = std::pow(2.0, -i);
      plot.points.push_back({0.1 / h, 1e-2 * h * h, i == 0 ? "h=1" : "", 0});
      plot.points.push_back({0.3 / h, 3e-2 * h * h, "", 1});
    }
    return plot;
  }

  fs::path dir_;
};

TEST_F(Plot, WritesAPngOfTheRequestedSizeWithTheDataDrawn) {
  const fs::path file = dir_ / "sweep.png";
  write_png(sweep(), file, 640, 480);
  {
    std::ifstream in(file, std::ios::binary);
    std::string signature(8, '\0');
    in.read(signature.data(), 8);
    EXPECT_EQ(signature, "\x89PNG\r\n\x1a\n");
  }
  const Image image(file);
  ASSERT_EQ(image.status(), CAIRO_STATUS_SUCCESS);
  EXPECT_EQ(image.width(), 640);
  EXPECT_EQ(image.height(), 480);
  EXPECT_GT(image.count(0.2, 0.9, 0.15, 0.85, non_white), 1000);
  EXPECT_GT(image.count(0.1, 0.95, 0.1, 0.9, blue), 50);
  EXPECT_EQ(image.count(0, 0.5, 0.9, 1, red), 0) << "no note: every run is shown";
  EXPECT_EQ(temporaries(), 0);

  // The default size, replacing the file.
  write_png(sweep(), file);
  EXPECT_EQ(Image(file).width(), 900);
  EXPECT_EQ(Image(file).height(), 600);
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Plot, LinearAxesAndWithoutTheFront) {
  ScatterPlot plot = sweep();
  plot.log_x = plot.log_y = false;
  plot.mark_pareto_front = false;
  plot.points.push_back({-3, 0, "", 1});  // fine on linear axes
  const fs::path file = dir_ / "linear.png";
  write_png(plot, file);
  const Image image(file);
  ASSERT_EQ(image.status(), CAIRO_STATUS_SUCCESS);
  EXPECT_GT(image.count(0.1, 0.95, 0.1, 0.9, blue), 50);
  EXPECT_EQ(image.count(0, 0.5, 0.9, 1, red), 0);
}

TEST_F(Plot, DegenerateInputsGiveAPlotAndTheNote) {
  struct Case {
    std::string name;
    std::vector<PlotPoint> points;
    bool log = true;
    bool note = false;  // some runs not shown
  };
  const std::vector<Case> cases = {
      {"empty", {}},
      {"one", {{2.5, 1e-4, "only"}}},
      {"equal", {{2, 3}, {2, 3}, {2, 3}}},
      {"equal_linear", {{2, 3}, {2, 3}}, false},
      {"zero_linear", {{0, 0}}, false},
      {"tiny_span_linear", {{1, 1}, {1 + 1e-15, 1}}, false},
      {"failed", {{kNaN, 1}, {1, kInf}, {-kInf, kNaN}}, true, true},
      {"zero_error", {{1, 0}, {2, 0}}, true, true},
      {"zero_error_linear", {{1, 0}, {kNaN, 0}}, false, true},
      {"mixed", {{1, 1e-3}, {2, 0}, {kNaN, 1}, {-1, 1e-2}}, true, true},
      {"huge_range", {{1e-300, 1e-300}, {1e300, 1e300}, {1, 1}}},
      {"huge_linear", {{-1e300, 1e300}, {1e300, -1e300}}, false},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    ScatterPlot plot;
    plot.title = c.name;
    plot.x_label = "cost";
    plot.y_label = "error";
    plot.series_names = {"runs"};
    plot.points = c.points;
    plot.log_x = plot.log_y = c.log;
    const fs::path file = dir_ / (c.name + ".png");
    ASSERT_NO_THROW(write_png(plot, file, 480, 320));
    const Image image(file);
    ASSERT_EQ(image.status(), CAIRO_STATUS_SUCCESS);
    EXPECT_EQ(image.width(), 480);
    EXPECT_EQ(image.height(), 320);
    EXPECT_GT(image.count(0, 1, 0, 1, non_white), 500);  // frame, ticks, labels, title
    // The note sits at the bottom left.
    EXPECT_EQ(image.count(0, 0.5, 0.9, 1, red) > 10, c.note);
  }
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Plot, AnUnwritablePathThrowsNamingTheFileAndLeavesNoTemporary) {
  const auto message = [](const ScatterPlot& plot, const fs::path& file, int width = 900) {
    try {
      write_png(plot, file, width);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    ADD_FAILURE() << "no exception for " << file;
    return std::string();
  };
  // No such directory.
  const fs::path missing = dir_ / "missing" / "plot.png";
  EXPECT_NE(message(sweep(), missing).find(missing.string()), std::string::npos);
  // The target is a directory: the temporary is written, the rename fails, the temporary goes.
  const fs::path directory = dir_ / "taken.png";
  fs::create_directory(directory);
  EXPECT_NE(message(sweep(), directory).find(directory.string()), std::string::npos);
  EXPECT_TRUE(fs::is_directory(directory));
  EXPECT_EQ(temporaries(), 0);
  // A size out of range.
  const fs::path tiny = dir_ / "tiny.png";
  EXPECT_NE(message(sweep(), tiny, 10).find(tiny.string()), std::string::npos);
  EXPECT_FALSE(fs::exists(tiny));
  EXPECT_EQ(temporaries(), 0);
}

}  // namespace
}  // namespace liedyn

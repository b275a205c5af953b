// Plots (problems/plot.hpp): pareto_front against its definition on hand-made and random sets;
// write_png writes a PNG of the requested size (read back with Cairo) with the data drawn,
// copes with degenerate inputs (nothing drawable: the note instead), and fails naming the file
// without leaving a temporary file behind.

#include <cairo.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
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

#include "png_image.hpp"
#include "problems/plot.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;
using test::Image;

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

// ---- Line plots.

bool orange(int r, int g, int b) { return r > 180 && g > 60 && g < 150 && b < 60; }  // series 1

// A pixel of neutral grey from lo to hi (crisp lines in the frame's and the grid's colours).
bool grey(std::uint32_t pixel, int lo, int hi) {
  const int r = (pixel >> 16) & 0xff, g = (pixel >> 8) & 0xff, b = pixel & 0xff;
  return r == g && g == b && r >= lo && r <= hi;
}

// The plot area of a rendered plot: its frame is the one long run of crisp dark grey
// (0.25·255 ≈ 64) pixels along each side.
struct Area {
  int left = -1, top = -1, right = -1, bottom = -1;
};
Area area_of(const Image& image) {
  const auto frame = [&](int x, int y) { return grey(image.pixel(x, y), 60, 68); };
  const auto column = [&](int x) {
    int n = 0;
    for (int y = image.height() / 3; y < 2 * image.height() / 3; ++y) n += frame(x, y) ? 1 : 0;
    return n > image.height() / 4;
  };
  const auto row = [&](int y) {
    int n = 0;
    for (int x = image.width() / 3; x < 2 * image.width() / 3; ++x) n += frame(x, y) ? 1 : 0;
    return n > image.width() / 4;
  };
  Area a;
  for (int x = 0; x < image.width(); ++x) {
    if (column(x)) (a.left < 0 ? a.left : a.right) = x;
  }
  for (int y = 0; y < image.height(); ++y) {
    if (row(y)) (a.top < 0 ? a.top : a.bottom) = y;
  }
  return a;
}

// Pixels in [x0, x1) × [y0, y1) (pixels) for which `test` holds.
int count_pixels(const Image& image, double x0, double x1, double y0, double y1,
                 const std::function<bool(int, int, int)>& test) {
  return image.count(x0 / image.width(), x1 / image.width(), y0 / image.height(),
                     y1 / image.height(), test);
}

// Where a data x falls on a linear axis over [lo, hi] padded by 5 % (plot.hpp).
double pixel_x(const Area& a, double x, double lo, double hi) {
  const double pad = 0.05 * (hi - lo);
  return a.left + (x - (lo - pad)) / (hi - lo + 2 * pad) * (a.right - a.left);
}

// Series 0's (blue) pixels over the plot area's height between data x0 and x1, the x axis
// spanning lo … hi.
int blue_between(const Image& image, const Area& a, double x0, double x1, double lo, double hi) {
  return count_pixels(image, pixel_x(a, x0, lo, hi), pixel_x(a, x1, lo, hi), a.top + 1, a.bottom, blue);
}

LinePlot line_plot(const std::vector<double>& x) {
  LinePlot plot;
  plot.title = "line plot";
  plot.x_label = "time [s]";
  plot.y_label = "value";
  plot.log_x = plot.log_y = false;
  plot.x = x;
  return plot;
}

std::vector<double> range(int n) {
  std::vector<double> x;
  for (int i = 0; i < n; ++i) x.push_back(i);
  return x;
}

TEST_F(Plot, LinesRiseAndFallWhereTheirValuesDo) {
  // Series 0 (blue) rises, series 1 (orange) falls: each in its own half of the left and the
  // right of the area. An axis drawn flipped, or a series not drawn, would show elsewhere.
  LinePlot plot = line_plot(range(21));
  LineSeries rising{"rising", range(21)}, falling{"falling", {}};
  for (const double x : plot.x) falling.y.push_back(20 - x);
  plot.series = {rising, falling};
  const fs::path file = dir_ / "lines.png";
  write_png(plot, file, 640, 480);
  const Image image(file);
  ASSERT_EQ(image.status(), CAIRO_STATUS_SUCCESS);
  EXPECT_EQ(image.width(), 640);
  EXPECT_EQ(image.height(), 480);
  const Area a = area_of(image);
  ASSERT_GT(a.left, 0);
  ASSERT_GT(a.right, a.left + 300);
  ASSERT_GT(a.bottom, a.top + 200);
  const double w = a.right - a.left, h = a.bottom - a.top;
  // Left fifth (x ≈ 1 … 4) and right fifth (x ≈ 16 … 19), each split into upper and lower
  // halves; the legend's corner boxes stay within the outer 15 % of the height.
  const double left0 = a.left + 0.1 * w, left1 = a.left + 0.25 * w;
  const double right0 = a.left + 0.75 * w, right1 = a.left + 0.9 * w;
  const double upper0 = a.top + 0.15 * h, middle = a.top + 0.5 * h, lower1 = a.bottom - 0.15 * h;
  EXPECT_GT(count_pixels(image, left0, left1, middle, lower1, blue), 100);
  EXPECT_EQ(count_pixels(image, left0, left1, upper0, middle, blue), 0);
  EXPECT_GT(count_pixels(image, right0, right1, upper0, middle, blue), 100);
  EXPECT_EQ(count_pixels(image, right0, right1, middle, lower1, blue), 0);
  EXPECT_GT(count_pixels(image, left0, left1, upper0, middle, orange), 40);  // dashed
  EXPECT_EQ(count_pixels(image, left0, left1, middle, lower1, orange), 0);
  EXPECT_GT(count_pixels(image, right0, right1, middle, lower1, orange), 40);
  EXPECT_EQ(count_pixels(image, right0, right1, upper0, middle, orange), 0);
  EXPECT_EQ(image.count(0, 0.5, 0.9, 1, red), 0) << "no note: every point is drawn";
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Plot, NaNsAreGapsInTheLineAndNotReported) {
  // y = x for x = 0 … 99 but NaN at 40 … 59 and at 79 and 81: a gap from 39 to 60 and the
  // lone point 80, which gets a marker (100 points are too dense for markers otherwise).
  LinePlot plot = line_plot(range(100));
  LineSeries series{"y", range(100)};
  for (int i = 40; i < 60; ++i) series.y[i] = kNaN;
  series.y[79] = series.y[81] = kNaN;
  plot.series = {series};
  const fs::path file = dir_ / "gaps.png";
  write_png(plot, file);
  const Image image(file);
  ASSERT_EQ(image.status(), CAIRO_STATUS_SUCCESS);
  const Area a = area_of(image);
  ASSERT_GT(a.right, a.left + 300);
  const auto blue_between = [&](double x0, double x1) { return liedyn::blue_between(image, a, x0, x1, 0, 99); };
  EXPECT_GT(blue_between(10, 30), 100);
  EXPECT_EQ(blue_between(40, 59), 0) << "a segment across the gap";
  EXPECT_GT(blue_between(61, 77), 100);
  EXPECT_EQ(blue_between(78.3, 79.2), 0) << "a segment to the lone point";
  EXPECT_GT(blue_between(79.8, 80.2), 10) << "the lone point's marker";
  EXPECT_EQ(blue_between(80.8, 81.7), 0) << "a segment from the lone point";
  EXPECT_EQ(image.count(0, 0.5, 0.9, 1, red), 0) << "gaps are not points that were not drawn";
}

TEST_F(Plot, ValuesALogAxisCannotShowAreReportedNotDrawn) {
  // 0 and −1 on a log axis, and +∞: reported in the note, and the line broken around them.
  LinePlot plot = line_plot(range(7));
  plot.log_y = true;
  plot.series = {{"y", {1, 10, 0, -1, kInf, 100, 1000}}};
  const fs::path log_file = dir_ / "log.png";
  write_png(plot, log_file);
  const Image log_image(log_file);
  ASSERT_EQ(log_image.status(), CAIRO_STATUS_SUCCESS);
  const Area a = area_of(log_image);
  ASSERT_GT(a.right, a.left + 300);
  const auto blue_between = [&](const Image& image, double x0, double x1) {
    return liedyn::blue_between(image, a, x0, x1, 0, 6);
  };
  EXPECT_GT(log_image.count(0, 0.5, 0.9, 1, red), 10) << "the note";
  EXPECT_GT(blue_between(log_image, 0.2, 0.8), 20);
  EXPECT_EQ(blue_between(log_image, 1.2, 4.8), 0);
  EXPECT_GT(blue_between(log_image, 5.2, 5.8), 20);

  // On a linear axis only +∞ is left out (still noted); 1 → 10 → 0 → −1 is drawn.
  plot.log_y = false;
  const fs::path linear_file = dir_ / "linear_line.png";
  write_png(plot, linear_file);
  const Image linear_image(linear_file);
  EXPECT_GT(linear_image.count(0, 0.5, 0.9, 1, red), 10);
  EXPECT_GT(blue_between(linear_image, 1.2, 2.8), 20);
}

TEST_F(Plot, WholeAxesHaveTicksAtWholeNumbersOnly) {
  // x = 0, 1, 2 spans 2.2 after padding: steps of 0.2 on a plain axis, of 1 on a whole one.
  // Counted as the vertical grid lines (0.86·255 ≈ 219 grey) crossing a row of the area.
  const auto grid_lines = [&](bool whole) {
    LinePlot plot = line_plot(range(3));
    plot.whole_x = whole;
    plot.series = {{"y", {0, 0, 0}}};  // a line across the middle, clear of the rows counted
    const fs::path file = dir_ / (whole ? "whole.png" : "fractional.png");
    write_png(plot, file);
    const Image image(file);
    const Area a = area_of(image);
    int most = 0;  // rows on a horizontal grid line are grey throughout: the most crossings
    for (int y = a.top + 5; y < a.top + (a.bottom - a.top) / 3; ++y) {
      int lines = 0;
      bool previous = false;
      for (int x = a.left + 1; x < a.right; ++x) {
        const bool line = grey(image.pixel(x, y), 215, 224);
        lines += line && !previous ? 1 : 0;
        previous = line;
      }
      most = std::max(most, lines);
    }
    return most;
  };
  EXPECT_EQ(grid_lines(true), 3);
  EXPECT_GT(grid_lines(false), 5);
}

TEST_F(Plot, ARightAxisShowsTheScaledValues) {
  LinePlot plot = line_plot(range(10));
  plot.log_y = true;
  plot.series = {{"loss", {1, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01, 5e-3, 2e-3, 1e-3}}};
  const fs::path without = dir_ / "without.png";
  write_png(plot, without);
  plot.right_label = "normalized loss";
  plot.right_factor = 1e3;
  const fs::path with = dir_ / "with.png";
  write_png(plot, with);
  // Labels and their axis title right of the area; the area narrower for them.
  const Image plain(without), right(with);
  const Area a = area_of(plain), b = area_of(right);
  EXPECT_LT(b.right, a.right - 20);
  EXPECT_GT(count_pixels(right, b.right + 8, right.width(), b.top, b.bottom, non_white), 200);
  EXPECT_LT(count_pixels(plain, a.right + 8, plain.width(), a.top, a.bottom, non_white), 20);
}

TEST_F(Plot, LinePlotsThatMakeNoSenseAreRefused) {
  LinePlot plot = line_plot(range(3));
  plot.series = {{"short", {1, 2}}};
  const fs::path file = dir_ / "refused.png";
  EXPECT_THROW(write_png(plot, file), std::invalid_argument);
  plot.series = {{"y", {1, 2, 3}}};
  plot.right_label = "scaled";
  plot.right_factor = 0;
  EXPECT_THROW(write_png(plot, file), std::invalid_argument);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_EQ(temporaries(), 0);
  // Nothing at all to draw is a plot saying so, not an error.
  plot.right_label.clear();
  plot.x.clear();
  plot.series = {{"y", {}}};
  EXPECT_NO_THROW(write_png(plot, file));
}

}  // namespace
}  // namespace liedyn

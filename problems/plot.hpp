#pragma once
// Scatter plots of error against cost (`liedyn sweep`), rendered in-process to PNG with Cairo.
//
// Pareto front (both coordinates minimised): point p is dominated when another point q has
// q.x <= p.x and q.y <= p.y with at least one inequality strict; the front is the set of
// points that are not dominated. Identical points do not dominate each other, so duplicates
// on the front are all on it. Points with a NaN or infinite coordinate are never on it.
//
// Rendering: log axes (the default) carry decade ticks labelled 10ⁿ, plus minor ticks at 2…9·10ⁿ
// when few decades are shown (labelled at 2·10ⁿ and 5·10ⁿ when the range is under 2.5 decades);
// linear axes carry 1/2/5·10ⁿ ticks. Each range is the data's padded by 5 % (in log₁₀ on a log
// axis); a range narrower than a decade on a log axis is widened to one decade, and a single value
// on a linear axis to ±10 % (±1 around 0), so a lone point or all-equal values are centred. A
// point is not drawn when a coordinate is non-finite (a failed run), non-positive on a log axis
// (e.g. zero error) or beyond ±1e300 on a linear one; those are counted in a note at the bottom
// left ("3 of 12 runs not shown: 2 failed (non-finite), 1 zero or negative (log axis)"). The front
// is that of the points drawn: a staircase through them (the boundary of the region they dominate)
// and a ring around each. Point labels go above the point, front points' first; one that would
// overlap another or leave the plot area is left out. The legend (one colour and marker per
// series, then the front) goes in the corner of the plot area that covers the fewest points. Text
// uses Cairo's toy font API with "DejaVu Sans" (fonts-dejavu-core).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace liedyn {

struct PlotPoint {
  double x = 0, y = 0;
  std::string label = {};  // drawn beside the point when not empty; keep it short
  int series = 0;          // index into ScatterPlot::series_names: colour and marker
};

struct ScatterPlot {
  std::string title, x_label, y_label;
  std::vector<std::string> series_names;  // the legend, one colour/marker per series
  std::vector<PlotPoint> points;
  bool log_x = true, log_y = true;
  bool mark_pareto_front = true;  // minimising both x and y
};

// Indices of the points on the Pareto front, sorted by x (then y, then index).
std::vector<std::size_t> pareto_front(const std::vector<PlotPoint>& points);

// Renders `plot` as a width × height PNG onto `out` (a binary stream: an AtomicFile's or an
// OutputFolder's). Throws std::runtime_error naming `what` (the file) when it cannot be
// rendered or the size is outside 320×240 … 8192×8192.
void write_png(const ScatterPlot& plot, std::ostream& out, const std::string& what,
               int width = 900, int height = 600);
// The same, written atomically to `file` (AtomicFile, problems/output.hpp).
void write_png(const ScatterPlot& plot, const std::filesystem::path& file, int width = 900,
               int height = 600);

}  // namespace liedyn

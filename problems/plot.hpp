#pragma once
// Plots rendered in-process to PNG with Cairo: scatter plots of error against cost (`liedyn
// sweep`, with the Pareto front) and line plots of series against a shared x (`liedyn plot`,
// `liedyn optimize`'s loss.png). Both kinds share one frame: title, axes, ticks, grid, legend
// and the note about points not drawn; only what is drawn inside the frame differs.
//
// Pareto front (both coordinates minimised): point p is dominated when another point q has
// q.x <= p.x and q.y <= p.y with at least one inequality strict; the front is the set of
// points that are not dominated. Identical points do not dominate each other, so duplicates
// on the front are all on it. Points with a NaN or infinite coordinate are never on it.
//
// Axes: log axes carry decade ticks labelled 10ⁿ, plus minor ticks at 2…9·10ⁿ when few decades
// are shown (labelled at 2·10ⁿ and 5·10ⁿ when the range is under 2.5 decades); linear axes
// carry 1/2/5·10ⁿ ticks, at least 1 apart on a `whole` axis (iterations, start numbers: no
// tick at 0.5). Each range is the data's padded by 5 % (in log₁₀ on a log axis); a range
// narrower than a decade on a log axis is widened to one decade, and a single value on a linear
// axis to ±10 % (±1 around 0, and at least ±1 on a whole axis), so a lone point or all-equal
// values are centred. A right-hand axis, when asked for, shows y·factor for the same points
// (the normalised loss beside the loss): on a log axis its range is the left one shifted by
// log₁₀ factor, on a linear one scaled by it, so each of its ticks sits where the left axis
// has tick/factor.
//
// Points not drawn: a point is not drawn when a coordinate is non-finite (a failed run; on a
// line, ±∞), non-positive on a log axis (e.g. zero error) or beyond ±1e300 on a linear one;
// those are counted in a note at the bottom left ("3 of 12 runs not shown: 2 failed
// (non-finite), 1 zero or negative (log axis)"). On a line a NaN is a gap, not a point (a
// value that does not exist, such as min_rod_separation where rods cannot touch): it is not
// counted. A point not drawn breaks its line like a gap, so no segment ever stands for values
// that are not there.
//
// Scatter plots: the front is that of the points drawn: a staircase through them (the boundary
// of the region they dominate) and a ring around each. Point labels go above the point, front
// points' first; one that would overlap another or leave the plot area is left out.
//
// Line plots: series i in colour i, joining its consecutive drawn points in the order of x;
// solid, then dashed, dotted and dash-dotted, so that a series lying on an earlier one leaves
// it showing. Each point also gets series i's marker when the points are sparse (at most one x
// value per 25 px of the plot area's width, scaled with the image), and a point whose
// neighbours are both missing always does, so that it shows at all. A legend when there is
// more than one series.
//
// The legend (one colour and marker or line per series, then the front) goes in the corner of
// the plot area that covers the fewest points (for lines, points along the segments too), or
// in the middle of an edge when that covers fewer still. Text uses Cairo's toy font API with
// "DejaVu Sans" (fonts-dejavu-core).

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace liedyn {

// What every plot has around its data.
struct PlotFrame {
  std::string title, x_label, y_label;
  bool log_x = true, log_y = true;
  bool whole_x = false, whole_y = false;  // the values are whole numbers: ticks 1 apart at least
  // A right-hand y axis labelled `right_label` showing y · right_factor (finite, > 0); none
  // when the label is empty.
  std::string right_label = {};
  double right_factor = 1;
};

struct PlotPoint {
  double x = 0, y = 0;
  std::string label = {};  // drawn beside the point when not empty; keep it short
  int series = 0;          // index into ScatterPlot::series_names: colour and marker
};

struct ScatterPlot : PlotFrame {
  std::vector<std::string> series_names;  // the legend, one colour/marker per series
  std::vector<PlotPoint> points;
  bool mark_pareto_front = true;  // minimising both x and y
};

struct LineSeries {
  std::string name;       // its legend entry
  std::vector<double> y;  // one per LinePlot::x; NaN: a gap
};

struct LinePlot : PlotFrame {
  std::vector<double> x;  // shared by every series; NaN: a gap in all of them
  std::vector<LineSeries> series;
};

// Indices of the points on the Pareto front, sorted by x (then y, then index).
std::vector<std::size_t> pareto_front(const std::vector<PlotPoint>& points);

// Renders `plot` as a width × height PNG onto `out` (a binary stream: an AtomicFile's or an
// OutputFolder's). Throws std::runtime_error naming `what` (the file) when it cannot be
// rendered or the size is outside 320×240 … 8192×8192, std::invalid_argument when a line
// series has not one y per x or the right axis's factor is not finite and positive.
void write_png(const ScatterPlot& plot, std::ostream& out, const std::string& what,
               int width = 900, int height = 600);
void write_png(const LinePlot& plot, std::ostream& out, const std::string& what, int width = 900,
               int height = 600);
// The same, written atomically to `file` (AtomicFile, problems/output.hpp).
void write_png(const ScatterPlot& plot, const std::filesystem::path& file, int width = 900,
               int height = 600);
void write_png(const LinePlot& plot, const std::filesystem::path& file, int width = 900,
               int height = 600);

}  // namespace liedyn

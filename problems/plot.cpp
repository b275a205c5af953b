#include "plot.hpp"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>

#include "output.hpp"

namespace liedyn {

std::vector<std::size_t> pareto_front(const std::vector<PlotPoint>& points) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (std::isfinite(points[i].x) && std::isfinite(points[i].y)) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const PlotPoint& p = points[a];
    const PlotPoint& q = points[b];
    if (p.x != q.x) return p.x < q.x;
    if (p.y != q.y) return p.y < q.y;
    return a < b;
  });
  // In this order only earlier points can dominate a later one, so a point is on the front
  // iff its y is below every earlier y, or equal to the lowest and the front point that has
  // it is identical (x equal too; identical points do not dominate each other).
  std::vector<std::size_t> front;
  for (const std::size_t i : order) {
    const PlotPoint& p = points[i];
    if (front.empty() || p.y < points[front.back()].y ||
        (p.y == points[front.back()].y && p.x == points[front.back()].x)) {
      front.push_back(i);
    }
  }
  return front;
}

namespace {

// ---- Text: runs of UTF-8, some of them superscripts (tick labels 10⁻⁶), with Cairo's toy API.

constexpr const char* kFont = "DejaVu Sans";
constexpr const char* kMinus = "\xE2\x88\x92";  // U+2212
constexpr const char* kTimes = "\xC3\x97";      // U+00D7
constexpr double kSuperscriptSize = 0.7;        // of the base size
constexpr double kSuperscriptRise = 0.55;       // of the base cap height

struct Run {
  std::string text;
  bool superscript = false;
};
using Text = std::vector<Run>;

// ASCII '-' replaced by the typographic minus.
std::string with_minus(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    if (ch == '-') {
      out += kMinus;
    } else {
      out += ch;
    }
  }
  return out;
}

struct Rgb {
  double r, g, b;
};

enum class Style { regular, bold, italic };

class Painter {
 public:
  Painter(cairo_t* cr, double scale) : cr_(cr), scale_(scale) {}

  cairo_t* cr() const { return cr_; }
  double scale() const { return scale_; }

  // `size` in points at 900×600; scaled with the image.
  void font(double size, Style style = Style::regular) {
    cairo_select_font_face(cr_, kFont,
                           style == Style::italic ? CAIRO_FONT_SLANT_ITALIC : CAIRO_FONT_SLANT_NORMAL,
                           style == Style::bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    size_ = size * scale_;
    cairo_set_font_size(cr_, size_);
    cairo_text_extents_t zero;
    cairo_text_extents(cr_, "0", &zero);
    cap_ = -zero.y_bearing;
    cairo_font_extents_t extents;
    cairo_font_extents(cr_, &extents);
    descent_ = extents.descent;
  }
  double cap() const { return cap_; }
  double descent() const { return descent_; }

  struct Extent {
    double width, ascent;  // ascent: baseline to the top of the caps or of a superscript
  };
  Extent measure(const Text& text) {
    Extent extent{0, cap_};
    for (const Run& run : text) {
      extent.width += advance(run);
      if (run.superscript) {
        extent.ascent = std::max(extent.ascent, cap_ * (kSuperscriptRise + kSuperscriptSize));
      }
    }
    return extent;
  }
  Extent measure(const std::string& text) { return measure(Text{{text}}); }

  // Draws `text` with its anchor at (x, y): ax = 0, 0.5, 1 for left, centre, right; ay = 0
  // for the top of the ascent, 0.5 for its middle, 1 for the baseline.
  void show(const Text& text, double x, double y, double ax, double ay) {
    const Extent extent = measure(text);
    double pen = x - ax * extent.width;
    const double baseline = y + (1 - ay) * extent.ascent;
    for (const Run& run : text) {
      if (run.superscript) cairo_set_font_size(cr_, size_ * kSuperscriptSize);
      cairo_move_to(cr_, pen, baseline - (run.superscript ? kSuperscriptRise * cap_ : 0));
      cairo_show_text(cr_, run.text.c_str());
      pen += advance(run);
      cairo_set_font_size(cr_, size_);
    }
  }
  void show(const std::string& text, double x, double y, double ax, double ay) {
    show(Text{{text}}, x, y, ax, ay);
  }

  void colour(const Rgb& c, double alpha = 1) { cairo_set_source_rgba(cr_, c.r, c.g, c.b, alpha); }

 private:
  double advance(const Run& run) {
    if (run.superscript) cairo_set_font_size(cr_, size_ * kSuperscriptSize);
    cairo_text_extents_t extents;
    cairo_text_extents(cr_, run.text.c_str(), &extents);
    cairo_set_font_size(cr_, size_);
    return extents.x_advance;
  }

  cairo_t* cr_;
  double scale_;
  double size_ = 10, cap_ = 7, descent_ = 2;
};

// ---- Axes: ranges and ticks in axis coordinates (log₁₀ of the value on a log axis).

struct Tick {
  double at;   // axis coordinate
  bool major;  // a decade on a log axis; every tick on a linear one
  Text label;  // empty: unlabelled
};

struct Axis {
  bool log = true;
  bool whole = false;  // whole-number values: linear ticks at least 1 apart
  double lo = 0, hi = 1;
  std::vector<Tick> ticks;

  double coordinate(double value) const { return log ? std::log10(value) : value; }
  // 0 at lo, 1 at hi, of an axis coordinate (a tick's) or of a value.
  double at(double axis_coordinate) const { return (axis_coordinate - lo) / (hi - lo); }
  double fraction(double value) const { return at(coordinate(value)); }
};

// Beyond ±kLargest a linear axis's span would overflow.
constexpr double kLargest = 1e300;
bool drawable(double value, bool log) {
  return std::isfinite(value) && (log ? value > 0 : std::abs(value) <= kLargest);
}

// The data's range (axis coordinates of the drawable points), padded; see plot.hpp.
void set_range(Axis& axis, const std::vector<double>& values) {
  const std::vector<double> none = {axis.log ? 1.0 : 0.0, axis.log ? 10.0 : 1.0};
  const auto [low, high] = std::minmax_element(values.empty() ? none.begin() : values.begin(),
                                               values.empty() ? none.end() : values.end());
  double lo = axis.coordinate(*low);
  double hi = axis.coordinate(*high);
  if (axis.log) {
    if (hi - lo < 1) {
      const double centre = 0.5 * (lo + hi);
      lo = centre - 0.5;
      hi = centre + 0.5;
    }
  } else if (!(hi - lo > 1e-12 * std::max(std::abs(lo), std::abs(hi)))) {
    double half = lo == 0 ? 1 : 0.1 * std::abs(lo);
    if (axis.whole) half = std::max(half, 1.0);  // room for a whole tick either side
    lo -= half;
    hi += half;
  }
  const double pad = 0.05 * (hi - lo);
  axis.lo = lo - pad;
  axis.hi = hi + pad;
}

Text power_of_ten(int mantissa, int exponent) {
  if (mantissa != 1 && exponent == 0) return {{std::to_string(mantissa)}};
  std::string base = mantissa == 1 ? "10" : std::to_string(mantissa) + kTimes + "10";
  return {{base}, {with_minus(std::to_string(exponent)), true}};
}

// Decade ticks, every `stride`-th one major and labelled so that at most `max_labels` are (the
// others minor, or left out when stride > 3); minor ticks at 2…9 per decade when at most 6
// decades are shown, labelled at 2 and 5 when under 2.5 are.
void log_ticks(Axis& axis, int max_labels) {
  const double span = axis.hi - axis.lo;
  const int first = static_cast<int>(std::ceil(axis.lo));
  const int last = static_cast<int>(std::floor(axis.hi));
  // 1, 2, 3 or 5 × 10ⁿ decades.
  const double wanted = span / std::max(1, max_labels);
  int stride = 1;
  for (int unit = 1; stride < wanted; unit *= 10) {
    for (const int m : {1, 2, 3, 5, 10}) {
      stride = m * unit;
      if (stride >= wanted) break;
    }
  }
  const bool label_minor = span < 2.5;
  for (int k = first - 1; k <= last; ++k) {
    if (k >= first && k % stride == 0) {
      axis.ticks.push_back({static_cast<double>(k), true, power_of_ten(1, k)});
    } else if (k >= first && stride <= 3) {
      axis.ticks.push_back({static_cast<double>(k), false, {}});
    }
    if (span > 6) continue;
    for (int m = 2; m <= 9; ++m) {
      const double at = k + std::log10(m);
      if (at < axis.lo || at > axis.hi) continue;
      const bool labelled = label_minor && (m == 2 || m == 5);
      axis.ticks.push_back({at, false, labelled ? power_of_ten(m, k) : Text{}});
    }
  }
}

// 1, 2 or 5 × 10ⁿ steps, about one per `max_labels`-th of the range (at least 1 on a whole
// axis). Labels are plain decimals, or m×10ⁿ when the values are ≥ 10⁵ or < 10⁻².
void linear_ticks(Axis& axis, int max_labels) {
  double raw = (axis.hi - axis.lo) / std::max(2, max_labels);
  if (axis.whole) raw = std::max(raw, 1.0);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / magnitude;
  const double step = (r < 1.5 ? 1 : r < 3 ? 2 : r < 7 ? 5 : 10) * magnitude;
  if (!std::isfinite(step) || step <= 0) return;
  const double first = std::ceil(axis.lo / step);
  const double last = std::floor(axis.hi / step);
  if (!(last - first < 1000)) return;
  double largest = 0;
  for (double i = first; i <= last; ++i) largest = std::max(largest, std::abs(i * step));
  const int exponent = largest > 0 ? static_cast<int>(std::floor(std::log10(largest))) : 0;
  const bool scientific = exponent >= 5 || exponent < -2;
  const double unit = scientific ? std::pow(10.0, exponent) : 1;
  const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step / unit) + 1e-9)));
  for (double i = first; i <= last; ++i) {
    const double value = i == 0 ? 0 : i * step;
    char digits[64];
    std::snprintf(digits, sizeof digits, "%.*f", decimals, value / unit);
    Text label{{value == 0 ? "0" : with_minus(digits)}};
    if (scientific && value != 0) {
      label[0].text += std::string(kTimes) + "10";
      label.push_back({with_minus(std::to_string(exponent)), true});
    }
    axis.ticks.push_back({value, true, label});
  }
}

void set_ticks(Axis& axis, double pixels, double label_pixels) {
  const int max_labels = std::max(2, static_cast<int>(pixels / label_pixels));
  if (axis.log) {
    log_ticks(axis, max_labels);
  } else {
    linear_ticks(axis, max_labels);
  }
}

// ---- Markers and colours.

// Okabe–Ito colour-blind-safe palette (yellow dropped: too light on white), then dark grey.
constexpr std::array<Rgb, 7> kPalette{{{0.000, 0.447, 0.698},
                                       {0.835, 0.369, 0.000},
                                       {0.000, 0.620, 0.451},
                                       {0.800, 0.475, 0.655},
                                       {0.902, 0.624, 0.000},
                                       {0.337, 0.706, 0.914},
                                       {0.350, 0.350, 0.350}}};
constexpr int kMarkers = 5;  // circle, square, triangle up, diamond, triangle down
constexpr Rgb kInk{0.15, 0.15, 0.15};
constexpr Rgb kFrontInk{0.05, 0.05, 0.05};

std::size_t series_index(int series) { return series < 0 ? 0 : static_cast<std::size_t>(series); }

void marker(Painter& painter, std::size_t series, double x, double y) {
  cairo_t* cr = painter.cr();
  const double r = 4.5 * painter.scale();
  const Rgb c = kPalette[series % kPalette.size()];
  switch (series % kMarkers) {
    case 0:
      cairo_new_sub_path(cr);
      cairo_arc(cr, x, y, r, 0, 2 * std::numbers::pi);
      break;
    case 1:
      cairo_rectangle(cr, x - 0.85 * r, y - 0.85 * r, 1.7 * r, 1.7 * r);
      break;
    case 2:
      cairo_move_to(cr, x, y - 1.15 * r);
      cairo_line_to(cr, x + r, y + 0.75 * r);
      cairo_line_to(cr, x - r, y + 0.75 * r);
      cairo_close_path(cr);
      break;
    case 3:
      cairo_move_to(cr, x, y - 1.2 * r);
      cairo_line_to(cr, x + 1.2 * r, y);
      cairo_line_to(cr, x, y + 1.2 * r);
      cairo_line_to(cr, x - 1.2 * r, y);
      cairo_close_path(cr);
      break;
    default:
      cairo_move_to(cr, x, y + 1.15 * r);
      cairo_line_to(cr, x + r, y - 0.75 * r);
      cairo_line_to(cr, x - r, y - 0.75 * r);
      cairo_close_path(cr);
      break;
  }
  painter.colour(c, 0.85);
  cairo_fill_preserve(cr);
  painter.colour({0.6 * c.r, 0.6 * c.g, 0.6 * c.b});
  cairo_set_line_width(cr, 1.0 * painter.scale());
  cairo_stroke(cr);
}

void ring(Painter& painter, double x, double y) {
  cairo_t* cr = painter.cr();
  cairo_new_sub_path(cr);
  cairo_arc(cr, x, y, 8 * painter.scale(), 0, 2 * std::numbers::pi);
  painter.colour(kFrontInk);
  cairo_set_line_width(cr, 1.4 * painter.scale());
  cairo_stroke(cr);
}

// The staircase through front points sorted by x: right along y_i to x_{i+1}, then down.
void staircase(Painter& painter, const std::vector<std::array<double, 2>>& front) {
  if (front.size() < 2) return;
  cairo_t* cr = painter.cr();
  cairo_move_to(cr, front[0][0], front[0][1]);
  for (std::size_t i = 1; i < front.size(); ++i) {
    cairo_line_to(cr, front[i][0], front[i - 1][1]);
    cairo_line_to(cr, front[i][0], front[i][1]);
  }
  painter.colour(kFrontInk, 0.75);
  cairo_set_line_width(cr, 1.6 * painter.scale());
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_MITER);
  cairo_stroke(cr);
}

// ---- The frame every plot shares.

struct Box {
  double left, top, right, bottom;
  double width() const { return right - left; }
  double height() const { return bottom - top; }
  bool contains(double x, double y) const {
    return x >= left && x <= right && y >= top && y <= bottom;
  }
};

// Pixel centre for a crisp one-pixel line.
double crisp(double v) { return std::floor(v) + 0.5; }

using Pixel = std::array<double, 2>;

// Why a point is not drawn (plot.hpp); kDrawn when it is.
enum Fate : std::size_t { kNonFinite, kNonPositive, kHuge, kDrawn };

// Renders one plot: the frame (title, axes, ticks, grid, legend box, the note about points not
// drawn) here, the data in a subclass. render() asks the subclass to admit() its points (which
// sets the ranges), lays out the frame around the tick labels that result, and draws the data
// clipped to the plot area.
class Chart {
 public:
  // `noun`: what a point is, singular and plural, for the note ("run", "runs");
  // `non_finite`: why a non-finite one is not drawn ("failed (non-finite)").
  Chart(cairo_t* cr, const PlotFrame& frame, int width, int height, std::array<std::string, 2> noun,
        std::string non_finite)
      : painter_(cr, std::clamp(std::min(width / 900.0, height / 600.0), 0.8, 4.0)),
        frame_(frame),
        width_(width),
        height_(height),
        noun_(std::move(noun)),
        non_finite_(std::move(non_finite)) {
    x_.log = frame.log_x;
    y_.log = frame.log_y;
    x_.whole = frame.whole_x;
    y_.whole = frame.whole_y;
  }
  virtual ~Chart() = default;
  Chart(const Chart&) = delete;
  Chart& operator=(const Chart&) = delete;

  void render() {
    select();
    set_range(x_, xs_);
    set_range(y_, ys_);
    layout();
    cairo_t* cr = painter_.cr();
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    grid();
    cairo_save(cr);
    cairo_rectangle(cr, area_.left, area_.top, area_.width(), area_.height());
    cairo_clip(cr);
    data();
    if (xs_.empty()) {
      painter_.font(14, Style::italic);
      painter_.colour({0.45, 0.45, 0.45});
      painter_.show("no " + noun_[1] + " to show", 0.5 * (area_.left + area_.right),
                    0.5 * (area_.top + area_.bottom), 0.5, 0.5);
    }
    cairo_restore(cr);
    axes();
    legend();
    note();
  }

 protected:
  // admit()s every point of the data (before the layout: the ranges come from them).
  virtual void select() = 0;
  // Draws the data, clipped to the plot area.
  virtual void data() = 0;
  // Draws the legend, with draw_legend.
  virtual void legend() = 0;

  // Counts the point (x, y); true, with its coordinates kept for the ranges, if it can be drawn.
  bool admit(double x, double y) {
    ++points_;
    Fate fate = kDrawn;
    if (!std::isfinite(x) || !std::isfinite(y)) {
      fate = kNonFinite;
    } else if ((x_.log && x <= 0) || (y_.log && y <= 0)) {
      fate = kNonPositive;
    } else if (!drawable(x, x_.log) || !drawable(y, y_.log)) {
      fate = kHuge;
    }
    if (fate != kDrawn) {
      ++hidden_[fate];
      return false;
    }
    xs_.push_back(x);
    ys_.push_back(y);
    return true;
  }

  double s() const { return painter_.scale(); }
  double px(double x) const { return area_.left + x_.fraction(x) * area_.width(); }
  double py(double y) const { return area_.bottom - y_.fraction(y) * area_.height(); }

  // A legend of `names` (nothing when empty) in the corner of the plot area, or else the
  // middle of an edge, whose surroundings hold the fewest `obstacles` (a corner when it ties);
  // `sample(row, x, y, width)` draws row's sample centred vertically on y from x to x + width.
  void draw_legend(const std::vector<std::string>& names, const std::vector<Pixel>& obstacles,
                   const std::function<void(std::size_t, double, double, double)>& sample) {
    if (names.empty()) return;
    painter_.font(12);
    const double pad = 8 * s();
    const double sample_width = 26 * s();
    const double row = 1.9 * painter_.cap();
    double widest = 0;
    for (const std::string& name : names) widest = std::max(widest, painter_.measure(name).width);
    const double w = pad + sample_width + pad + widest + pad;
    const double h = pad + names.size() * row + pad - (row - painter_.cap()) + 2 * s();
    const double inset = 10 * s();
    const double middle_x = 0.5 * (area_.left + area_.right - w);
    const double middle_y = 0.5 * (area_.top + area_.bottom - h);
    const std::array<Box, 8> places{{
        {area_.right - inset - w, area_.top + inset, area_.right - inset, area_.top + inset + h},
        {area_.left + inset, area_.top + inset, area_.left + inset + w, area_.top + inset + h},
        {area_.right - inset - w, area_.bottom - inset - h, area_.right - inset,
         area_.bottom - inset},
        {area_.left + inset, area_.bottom - inset - h, area_.left + inset + w,
         area_.bottom - inset},
        {area_.right - inset - w, middle_y, area_.right - inset, middle_y + h},
        {area_.left + inset, middle_y, area_.left + inset + w, middle_y + h},
        {middle_x, area_.top + inset, middle_x + w, area_.top + inset + h},
        {middle_x, area_.bottom - inset - h, middle_x + w, area_.bottom - inset},
    }};
    const Box* best = &places[0];
    std::size_t fewest = std::numeric_limits<std::size_t>::max();
    for (const Box& box : places) {
      const Box grown{box.left - inset, box.top - inset, box.right + inset, box.bottom + inset};
      const auto covered = static_cast<std::size_t>(
          std::count_if(obstacles.begin(), obstacles.end(),
                        [&](const Pixel& o) { return grown.contains(o[0], o[1]); }));
      if (covered < fewest) {
        fewest = covered;
        best = &box;
      }
    }
    cairo_t* cr = painter_.cr();
    cairo_rectangle(cr, crisp(best->left), crisp(best->top), std::round(w), std::round(h));
    cairo_set_source_rgba(cr, 1, 1, 1, 0.9);
    cairo_fill_preserve(cr);
    painter_.colour({0.7, 0.7, 0.7});
    cairo_set_line_width(cr, 1);
    cairo_stroke(cr);
    double y = best->top + pad + 0.5 * painter_.cap() + 1 * s();
    const double x = best->left + pad;
    for (std::size_t i = 0; i < names.size(); ++i, y += row) {
      sample(i, x, y, sample_width);
      painter_.font(12);
      painter_.colour(kInk);
      painter_.show(names[i], x + sample_width + pad, y, 0, 0.5);
    }
  }

  Painter painter_;
  Box area_{};

 private:
  bool right_axis() const { return !frame_.right_label.empty(); }

  void layout() {
    const double pad = 14 * s();
    const double gap = 6 * s();
    tick_length_ = 5 * s();
    double top = pad;
    if (!frame_.title.empty()) {
      // Shrink a title that does not fit.
      title_size_ = 16;
      painter_.font(title_size_, Style::bold);
      const double fits = (width_ - 2 * pad) / std::max(1.0, painter_.measure(frame_.title).width);
      if (fits < 1) title_size_ = std::max(8.0, title_size_ * fits);
      painter_.font(title_size_, Style::bold);
      title_baseline_ = top + painter_.cap();
      top = title_baseline_ + painter_.descent() + 1.2 * pad;
    } else {
      top += 0.5 * pad;
    }
    painter_.font(12);
    const double tick_text = painter_.cap() * (kSuperscriptRise + kSuperscriptSize);
    const double tick_descent = painter_.descent();
    double bottom = height_ - pad;
    if (hidden() > 0) {
      painter_.font(11, Style::italic);
      note_baseline_ = bottom - painter_.descent();
      bottom = note_baseline_ - painter_.cap() - gap;
    }
    painter_.font(13);
    if (!frame_.x_label.empty()) {
      x_label_baseline_ = bottom - painter_.descent();
      bottom = x_label_baseline_ - painter_.cap() - gap;
    }
    bottom -= tick_length_ + gap + tick_text + tick_descent;
    set_ticks(y_, bottom - top, 36 * s());
    double left = pad;
    painter_.font(13);
    if (!frame_.y_label.empty()) {
      y_label_x_ = left + painter_.cap();
      left = y_label_x_ + painter_.descent() + gap;
    }
    left += widest_label(y_) + gap + tick_length_;
    double right = width_ - 2.5 * pad;
    if (right_axis()) {
      // The same points, y · factor: an affine image of the left axis's range.
      y2_.log = y_.log;
      const double shift = y_.log ? std::log10(frame_.right_factor) : 0;
      const double scale = y_.log ? 1 : frame_.right_factor;
      y2_.lo = y_.lo * scale + shift;
      y2_.hi = y_.hi * scale + shift;
      set_ticks(y2_, bottom - top, 36 * s());
      painter_.font(13);
      right_label_x_ = width_ - pad - painter_.descent();
      right = right_label_x_ - painter_.cap() - gap - widest_label(y2_) - gap - tick_length_;
    }
    area_ = {std::round(left), std::round(top), std::round(right), std::round(bottom)};
    set_ticks(x_, area_.width(), 70 * s());
  }

  double widest_label(const Axis& axis) {
    painter_.font(12);
    double widest = 0;
    for (const Tick& tick : axis.ticks) {
      widest = std::max(widest, painter_.measure(tick.label).width);
    }
    return widest;
  }

  double tick_x(const Tick& t) const { return crisp(area_.left + x_.at(t.at) * area_.width()); }
  double tick_y(const Axis& axis, const Tick& t) const {
    return crisp(area_.bottom - axis.at(t.at) * area_.height());
  }

  void grid() {
    cairo_t* cr = painter_.cr();
    cairo_set_line_width(cr, 1);
    for (const Tick& t : x_.ticks) {
      painter_.colour(t.major ? Rgb{0.86, 0.86, 0.86} : Rgb{0.95, 0.95, 0.95});
      cairo_move_to(cr, tick_x(t), area_.top);
      cairo_line_to(cr, tick_x(t), area_.bottom);
      cairo_stroke(cr);
    }
    for (const Tick& t : y_.ticks) {
      painter_.colour(t.major ? Rgb{0.86, 0.86, 0.86} : Rgb{0.95, 0.95, 0.95});
      cairo_move_to(cr, area_.left, tick_y(y_, t));
      cairo_line_to(cr, area_.right, tick_y(y_, t));
      cairo_stroke(cr);
    }
  }

  // Frame, ticks, tick labels (a label overlapping the previous one is skipped), axis labels
  // and the title. Without a right axis the right edge repeats the left one's ticks, unlabelled.
  void axes() {
    cairo_t* cr = painter_.cr();
    painter_.colour({0.25, 0.25, 0.25});
    cairo_set_line_width(cr, 1);
    cairo_rectangle(cr, crisp(area_.left), crisp(area_.top),
                    std::floor(area_.right) - std::floor(area_.left),
                    std::floor(area_.bottom) - std::floor(area_.top));
    cairo_stroke(cr);
    const double gap = 5 * s();
    painter_.font(12);
    double previous = -std::numeric_limits<double>::infinity();
    for (const Tick& t : x_.ticks) {
      const double x = tick_x(t);
      tick(x, area_.bottom, x, area_.bottom - (t.major ? 1 : 0.5) * tick_length_);
      tick(x, area_.top, x, area_.top + (t.major ? 1 : 0.5) * tick_length_);
      if (t.label.empty()) continue;
      const double half = 0.5 * painter_.measure(t.label).width;
      if (x - half < previous + 2 * gap) continue;
      painter_.colour(kInk);
      painter_.show(t.label, x, area_.bottom + gap, 0.5, 0);
      previous = x + half;
    }
    y_ticks(y_, area_.left, 1, true);
    y_ticks(right_axis() ? y2_ : y_, area_.right, -1, right_axis());
    painter_.font(13);
    painter_.colour(kInk);
    if (!frame_.x_label.empty()) {
      painter_.show(frame_.x_label, 0.5 * (area_.left + area_.right), x_label_baseline_, 0.5, 1);
    }
    for (const auto& [label, x] :
         {std::pair{&frame_.y_label, y_label_x_}, std::pair{&frame_.right_label, right_label_x_}}) {
      if (label->empty()) continue;
      cairo_save(cr);
      cairo_translate(cr, x, 0.5 * (area_.top + area_.bottom));
      cairo_rotate(cr, -0.5 * std::numbers::pi);
      painter_.show(*label, 0, 0, 0.5, 1);
      cairo_restore(cr);
    }
    if (!frame_.title.empty()) {
      painter_.font(title_size_, Style::bold);
      painter_.show(frame_.title, 0.5 * width_, title_baseline_, 0.5, 1);
    }
  }

  // The ticks of `axis` along the vertical edge at `edge`, pointing `inward` (+1 right, −1
  // left), with their labels outside the edge if `labelled`.
  void y_ticks(const Axis& axis, double edge, double inward, bool labelled) {
    const double gap = 5 * s();
    painter_.font(12);
    double previous = std::numeric_limits<double>::infinity();
    for (const Tick& t : axis.ticks) {
      const double y = tick_y(axis, t);
      tick(edge, y, edge + inward * (t.major ? 1 : 0.5) * tick_length_, y);
      if (!labelled || t.label.empty()) continue;
      const double half = 0.5 * painter_.measure(t.label).ascent;
      if (y + half > previous - gap) continue;
      painter_.colour(kInk);
      painter_.show(t.label, edge - inward * gap, y, inward > 0 ? 1 : 0, 0.5);
      previous = y - half;
    }
  }

  void tick(double x0, double y0, double x1, double y1) {
    cairo_t* cr = painter_.cr();
    painter_.colour({0.25, 0.25, 0.25});
    cairo_move_to(cr, x0, y0);
    cairo_line_to(cr, x1, y1);
    cairo_stroke(cr);
  }

  std::size_t hidden() const {
    return hidden_[kNonFinite] + hidden_[kNonPositive] + hidden_[kHuge];
  }

  void note() {
    if (hidden() == 0) return;
    std::string text = std::to_string(hidden()) + " of " + std::to_string(points_) + " " +
                       noun_[points_ == 1 ? 0 : 1] + " not shown: ";
    const std::array<std::string, 3> reasons{non_finite_, "zero or negative (log axis)",
                                             "beyond ±1e300"};
    const char* separator = "";
    for (std::size_t fate = 0; fate < reasons.size(); ++fate) {
      if (hidden_[fate] == 0) continue;
      text += separator + std::to_string(hidden_[fate]) + " " + reasons[fate];
      separator = ", ";
    }
    painter_.font(11, Style::italic);
    painter_.colour({0.65, 0.1, 0.1});
    painter_.show(text, 14 * s(), note_baseline_, 0, 1);
  }

  const PlotFrame& frame_;
  int width_, height_;
  std::array<std::string, 2> noun_;
  std::string non_finite_;
  Axis x_, y_, y2_;
  std::vector<double> xs_, ys_;  // the drawable points' coordinates
  std::size_t points_ = 0;
  std::array<std::size_t, 3> hidden_{};  // by Fate
  double tick_length_ = 5, title_size_ = 16, title_baseline_ = 0, x_label_baseline_ = 0,
         y_label_x_ = 0, right_label_x_ = 0, note_baseline_ = 0;
};

// ---- Scatter plots.

class ScatterChart : public Chart {
 public:
  ScatterChart(cairo_t* cr, const ScatterPlot& plot, int width, int height)
      : Chart(cr, plot, width, height, {"run", "runs"}, "failed (non-finite)"), plot_(plot) {}

 private:
  void select() override {
    for (const PlotPoint& p : plot_.points) {
      if (admit(p.x, p.y)) shown_.push_back(p);
    }
    if (plot_.mark_pareto_front) front_ = pareto_front(shown_);
  }

  void data() override {
    std::vector<Pixel> front;
    for (const std::size_t i : front_) front.push_back({px(shown_[i].x), py(shown_[i].y)});
    staircase(painter_, front);
    for (const PlotPoint& p : shown_) marker(painter_, series_index(p.series), px(p.x), py(p.y));
    for (const auto& [x, y] : front) ring(painter_, x, y);
    labels();
  }

  // Point labels above right of the point (clear of the ring and of the staircase, which
  // leaves a front point to the right and below), else above left; front points' first, and
  // a label that would overlap an earlier one or leave the plot area is left out.
  void labels() {
    painter_.font(10);
    painter_.colour(kInk);
    std::vector<std::size_t> order = front_;
    for (std::size_t i = 0; i < shown_.size(); ++i) {
      if (std::find(front_.begin(), front_.end(), i) == front_.end()) order.push_back(i);
    }
    const double offset = 7 * s();
    const double margin = 2 * s();
    std::vector<Box> taken;
    for (const std::size_t i : order) {
      const PlotPoint& p = shown_[i];
      if (p.label.empty()) continue;
      const Painter::Extent extent = painter_.measure(p.label);
      const double x = px(p.x);
      const double baseline = py(p.y) - offset;
      for (const bool right : {true, false}) {
        const double left = right ? x + offset : x - offset - extent.width;
        const Box box{left - margin, baseline - extent.ascent - margin,
                      left + extent.width + margin, baseline + painter_.descent() + margin};
        const bool inside = box.left >= area_.left && box.right <= area_.right &&
                            box.top >= area_.top && box.bottom <= area_.bottom;
        const bool clear = std::none_of(taken.begin(), taken.end(), [&](const Box& other) {
          return box.left < other.right && other.left < box.right && box.top < other.bottom &&
                 other.top < box.bottom;
        });
        if (!inside || !clear) continue;
        painter_.show(p.label, left, baseline, 0, 1);
        taken.push_back(box);
        break;
      }
    }
  }

  // The series, then the front; clear of the points and the staircase's corners.
  void legend() override {
    std::vector<std::string> names = plot_.series_names;
    if (!front_.empty()) names.push_back("Pareto front");
    std::vector<Pixel> obstacles;
    for (const PlotPoint& p : shown_) obstacles.push_back({px(p.x), py(p.y)});
    for (std::size_t i = 1; i < front_.size(); ++i) {
      obstacles.push_back({px(shown_[front_[i]].x), py(shown_[front_[i - 1]].y)});
    }
    draw_legend(names, obstacles, [&](std::size_t row, double x, double y, double width) {
      if (row < plot_.series_names.size()) {
        marker(painter_, row, x + 0.5 * width, y);
      } else {
        staircase(painter_, {{x, y}, {x + width, y}});
        ring(painter_, x + 0.5 * width, y);
      }
    });
  }

  const ScatterPlot& plot_;
  std::vector<PlotPoint> shown_;
  std::vector<std::size_t> front_;  // indices into shown_
};

// ---- Line plots.

class LineChart : public Chart {
 public:
  LineChart(cairo_t* cr, const LinePlot& plot, int width, int height)
      : Chart(cr, plot, width, height, {"point", "points"}, "infinite"), plot_(plot) {}

 private:
  // Each series' runs of consecutive drawable points; a gap or a point not drawn ends a run.
  void select() override {
    runs_.assign(plot_.series.size(), {});
    for (std::size_t k = 0; k < plot_.series.size(); ++k) {
      std::vector<std::vector<std::array<double, 2>>>& runs = runs_[k];
      runs.emplace_back();
      for (std::size_t i = 0; i < plot_.x.size(); ++i) {
        const double x = plot_.x[i], y = plot_.series[k].y[i];
        if (!std::isnan(x) && !std::isnan(y) && admit(x, y)) {
          runs.back().push_back({x, y});
        } else if (!runs.back().empty()) {
          runs.emplace_back();
        }
      }
    }
  }

  // Sparse points get markers: at most one per 25 px of the plot area's width (a marker is
  // 9 px wide).
  bool markers() const { return static_cast<double>(plot_.x.size()) <= area_.width() / (25 * s()); }

  void data() override {
    cairo_t* cr = painter_.cr();
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    for (std::size_t k = 0; k < runs_.size(); ++k) {
      for (const auto& run : runs_[k]) {
        if (run.size() < 2) continue;
        cairo_move_to(cr, px(run[0][0]), py(run[0][1]));
        for (std::size_t i = 1; i < run.size(); ++i) {
          cairo_line_to(cr, px(run[i][0]), py(run[i][1]));
        }
        stroke_series(k);
      }
      for (const auto& run : runs_[k]) {
        if (run.size() != 1 && !markers()) continue;
        for (const auto& [x, y] : run) marker(painter_, k, px(x), py(y));
      }
    }
  }

  // Solid, dashed, dotted, dash-dotted, again: a series lying on an earlier one (angular
  // momentum x and z both 0) still shows it between its dashes.
  void stroke_series(std::size_t series) {
    static const std::array<std::vector<double>, 4> kDashes{{{}, {8, 4}, {2, 3}, {8, 3, 2, 3}}};
    cairo_t* cr = painter_.cr();
    std::vector<double> dashes = kDashes[series % kDashes.size()];
    for (double& d : dashes) d *= s();
    cairo_set_dash(cr, dashes.data(), static_cast<int>(dashes.size()), 0);
    painter_.colour(kPalette[series % kPalette.size()]);
    cairo_set_line_width(cr, 1.8 * s());
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);  // markers' outlines are solid
  }

  // One row per series when there are several, clear of the points and of the segments
  // (sampled every 8 px).
  void legend() override {
    if (plot_.series.size() < 2) return;
    std::vector<std::string> names;
    for (const LineSeries& series : plot_.series) names.push_back(series.name);
    std::vector<Pixel> obstacles;
    const double step = 8 * s();
    for (const auto& runs : runs_) {
      for (const auto& run : runs) {
        for (std::size_t i = 0; i < run.size(); ++i) {
          const Pixel a{px(run[i][0]), py(run[i][1])};
          obstacles.push_back(a);
          if (i + 1 == run.size()) continue;
          const Pixel b{px(run[i + 1][0]), py(run[i + 1][1])};
          const int pieces =
              static_cast<int>(std::min(1e4, std::hypot(b[0] - a[0], b[1] - a[1]) / step));
          for (int k = 1; k < pieces; ++k) {
            const double t = static_cast<double>(k) / pieces;
            obstacles.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
          }
        }
      }
    }
    draw_legend(names, obstacles, [&](std::size_t row, double x, double y, double width) {
      cairo_t* cr = painter_.cr();
      cairo_move_to(cr, x, y);
      cairo_line_to(cr, x + width, y);
      stroke_series(row);
      if (markers()) marker(painter_, row, x + 0.5 * width, y);
    });
  }

  const LinePlot& plot_;
  std::vector<std::vector<std::vector<std::array<double, 2>>>> runs_;  // [series][run][point]
};

cairo_status_t write_to_stream(void* closure, const unsigned char* data, unsigned int length) {
  auto& out = *static_cast<std::ostream*>(closure);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(length));
  return out ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

void check_frame(const PlotFrame& frame, const std::string& what) {
  if (!frame.right_label.empty() &&
      !(std::isfinite(frame.right_factor) && frame.right_factor > 0)) {
    throw std::invalid_argument(what + ": the right axis's factor must be finite and positive");
  }
}

template <class ChartOf, class Plot>
void render_png(const Plot& plot, std::ostream& out, const std::string& what, int width,
                int height) {
  if (width < 320 || height < 240 || width > 8192 || height > 8192) {
    throw std::runtime_error(what + ": plot size " + std::to_string(width) + "x" +
                             std::to_string(height) + " outside 320x240 ... 8192x8192");
  }
  check_frame(plot, what);
  const std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width, height), cairo_surface_destroy);
  {
    const std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()),
                                                                cairo_destroy);
    ChartOf(cr.get(), plot, width, height).render();
    const cairo_status_t status = cairo_status(cr.get());
    if (status != CAIRO_STATUS_SUCCESS) {
      throw std::runtime_error(what + ": cannot render the plot: " +
                               cairo_status_to_string(status));
    }
  }
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface.get(), write_to_stream, &out);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(what + ": cannot write the PNG: " + cairo_status_to_string(status));
  }
}

template <class Plot>
void write_png_file(const Plot& plot, const std::filesystem::path& file, int width, int height) {
  AtomicFile out(file);
  write_png(plot, out.stream(), file.string(), width, height);
  out.commit();
}

}  // namespace

void write_png(const ScatterPlot& plot, std::ostream& out, const std::string& what, int width,
               int height) {
  render_png<ScatterChart>(plot, out, what, width, height);
}

void write_png(const LinePlot& plot, std::ostream& out, const std::string& what, int width,
               int height) {
  for (const LineSeries& series : plot.series) {
    if (series.y.size() != plot.x.size()) {
      throw std::invalid_argument(what + ": series \"" + series.name + "\" has " +
                                  std::to_string(series.y.size()) + " values for " +
                                  std::to_string(plot.x.size()) + " x values");
    }
  }
  render_png<LineChart>(plot, out, what, width, height);
}

void write_png(const ScatterPlot& plot, const std::filesystem::path& file, int width, int height) {
  write_png_file(plot, file, width, height);
}

void write_png(const LinePlot& plot, const std::filesystem::path& file, int width, int height) {
  write_png_file(plot, file, width, height);
}

}  // namespace liedyn

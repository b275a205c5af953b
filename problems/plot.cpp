#include "plot.hpp"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>

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
  double lo = 0, hi = 1;
  std::vector<Tick> ticks;

  double coordinate(double value) const { return log ? std::log10(value) : value; }
  double fraction(double value) const { return (coordinate(value) - lo) / (hi - lo); }
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
    const double half = lo == 0 ? 1 : 0.1 * std::abs(lo);
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

// 1, 2 or 5 × 10ⁿ steps, about one per `max_labels`-th of the range. Labels are plain decimals,
// or m×10ⁿ when the values are ≥ 10⁵ or < 10⁻².
void linear_ticks(Axis& axis, int max_labels) {
  const double raw = (axis.hi - axis.lo) / std::max(2, max_labels);
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

// ---- The plot.

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

class Renderer {
 public:
  Renderer(cairo_t* cr, const ScatterPlot& plot, int width, int height)
      : painter_(cr, std::clamp(std::min(width / 900.0, height / 600.0), 0.8, 4.0)),
        plot_(plot),
        width_(width),
        height_(height) {
    x_.log = plot.log_x;
    y_.log = plot.log_y;
  }

  void render() {
    select_points();
    layout();
    cairo_t* cr = painter_.cr();
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    grid();
    data();
    axes();
    legend();
    note();
  }

 private:
  double s() const { return painter_.scale(); }
  double px(double x) const { return area_.left + x_.fraction(x) * area_.width(); }
  double py(double y) const { return area_.bottom - y_.fraction(y) * area_.height(); }

  void select_points() {
    std::vector<double> xs, ys;
    for (std::size_t i = 0; i < plot_.points.size(); ++i) {
      const PlotPoint& p = plot_.points[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
        ++failed_;
      } else if ((x_.log && p.x <= 0) || (y_.log && p.y <= 0)) {
        ++non_positive_;
      } else if (!drawable(p.x, x_.log) || !drawable(p.y, y_.log)) {
        ++huge_;
      } else {
        shown_.push_back(p);
        xs.push_back(p.x);
        ys.push_back(p.y);
      }
    }
    set_range(x_, xs);
    set_range(y_, ys);
    if (plot_.mark_pareto_front) front_ = pareto_front(shown_);
  }

  void layout() {
    const double pad = 14 * s();
    const double gap = 6 * s();
    tick_length_ = 5 * s();
    double top = pad;
    if (!plot_.title.empty()) {
      // Shrink a title that does not fit.
      title_size_ = 16;
      painter_.font(title_size_, Style::bold);
      const double fits = (width_ - 2 * pad) / std::max(1.0, painter_.measure(plot_.title).width);
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
    if (!plot_.x_label.empty()) {
      x_label_baseline_ = bottom - painter_.descent();
      bottom = x_label_baseline_ - painter_.cap() - gap;
    }
    bottom -= tick_length_ + gap + tick_text + tick_descent;
    set_ticks(y_, bottom - top, 36 * s());
    painter_.font(12);
    double widest = 0;
    for (const Tick& tick : y_.ticks) widest = std::max(widest, painter_.measure(tick.label).width);
    double left = pad;
    painter_.font(13);
    if (!plot_.y_label.empty()) {
      y_label_x_ = left + painter_.cap();
      left = y_label_x_ + painter_.descent() + gap;
    }
    left += widest + gap + tick_length_;
    area_ = {std::round(left), std::round(top), std::round(width_ - 2.5 * pad), std::round(bottom)};
    set_ticks(x_, area_.width(), 70 * s());
  }

  void grid() {
    cairo_t* cr = painter_.cr();
    cairo_set_line_width(cr, 1);
    for (const Tick& t : x_.ticks) {
      const double x = crisp(area_.left + (t.at - x_.lo) / (x_.hi - x_.lo) * area_.width());
      painter_.colour(t.major ? Rgb{0.86, 0.86, 0.86} : Rgb{0.95, 0.95, 0.95});
      cairo_move_to(cr, x, area_.top);
      cairo_line_to(cr, x, area_.bottom);
      cairo_stroke(cr);
    }
    for (const Tick& t : y_.ticks) {
      const double y = crisp(area_.bottom - (t.at - y_.lo) / (y_.hi - y_.lo) * area_.height());
      painter_.colour(t.major ? Rgb{0.86, 0.86, 0.86} : Rgb{0.95, 0.95, 0.95});
      cairo_move_to(cr, area_.left, y);
      cairo_line_to(cr, area_.right, y);
      cairo_stroke(cr);
    }
  }

  void data() {
    cairo_t* cr = painter_.cr();
    cairo_save(cr);
    cairo_rectangle(cr, area_.left, area_.top, area_.width(), area_.height());
    cairo_clip(cr);
    std::vector<std::array<double, 2>> front;
    for (const std::size_t i : front_) front.push_back({px(shown_[i].x), py(shown_[i].y)});
    staircase(painter_, front);
    for (const PlotPoint& p : shown_) marker(painter_, series_index(p.series), px(p.x), py(p.y));
    for (const auto& [x, y] : front) ring(painter_, x, y);
    painter_.font(10);
    painter_.colour(kInk);
    labels();
    if (shown_.empty()) {
      painter_.font(14, Style::italic);
      painter_.colour({0.45, 0.45, 0.45});
      painter_.show("no runs to show", 0.5 * (area_.left + area_.right),
                    0.5 * (area_.top + area_.bottom), 0.5, 0.5);
    }
    cairo_restore(cr);
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

  // Frame, ticks, tick labels (a label overlapping the previous one is skipped), axis labels
  // and the title.
  void axes() {
    cairo_t* cr = painter_.cr();
    painter_.colour({0.25, 0.25, 0.25});
    cairo_set_line_width(cr, 1);
    cairo_rectangle(cr, crisp(area_.left), crisp(area_.top), std::floor(area_.right) - std::floor(area_.left),
                    std::floor(area_.bottom) - std::floor(area_.top));
    cairo_stroke(cr);
    const double gap = 5 * s();
    painter_.font(12);
    double previous = -std::numeric_limits<double>::infinity();
    for (const Tick& t : x_.ticks) {
      const double x = crisp(area_.left + (t.at - x_.lo) / (x_.hi - x_.lo) * area_.width());
      tick(x, area_.bottom, x, area_.bottom - (t.major ? 1 : 0.5) * tick_length_);
      tick(x, area_.top, x, area_.top + (t.major ? 1 : 0.5) * tick_length_);
      if (t.label.empty()) continue;
      const double half = 0.5 * painter_.measure(t.label).width;
      if (x - half < previous + 2 * gap) continue;
      painter_.colour(kInk);
      painter_.show(t.label, x, area_.bottom + gap, 0.5, 0);
      previous = x + half;
    }
    previous = std::numeric_limits<double>::infinity();
    for (const Tick& t : y_.ticks) {
      const double y = crisp(area_.bottom - (t.at - y_.lo) / (y_.hi - y_.lo) * area_.height());
      tick(area_.left, y, area_.left + (t.major ? 1 : 0.5) * tick_length_, y);
      tick(area_.right, y, area_.right - (t.major ? 1 : 0.5) * tick_length_, y);
      if (t.label.empty()) continue;
      const double half = 0.5 * painter_.measure(t.label).ascent;
      if (y + half > previous - gap) continue;
      painter_.colour(kInk);
      painter_.show(t.label, area_.left - gap, y, 1, 0.5);
      previous = y - half;
    }
    painter_.font(13);
    painter_.colour(kInk);
    if (!plot_.x_label.empty()) {
      painter_.show(plot_.x_label, 0.5 * (area_.left + area_.right), x_label_baseline_, 0.5, 1);
    }
    if (!plot_.y_label.empty()) {
      cairo_save(cr);
      cairo_translate(cr, y_label_x_, 0.5 * (area_.top + area_.bottom));
      cairo_rotate(cr, -0.5 * std::numbers::pi);
      painter_.show(plot_.y_label, 0, 0, 0.5, 1);
      cairo_restore(cr);
    }
    if (!plot_.title.empty()) {
      painter_.font(title_size_, Style::bold);
      painter_.show(plot_.title, 0.5 * width_, title_baseline_, 0.5, 1);
    }
  }

  void tick(double x0, double y0, double x1, double y1) {
    cairo_t* cr = painter_.cr();
    painter_.colour({0.25, 0.25, 0.25});
    cairo_move_to(cr, x0, y0);
    cairo_line_to(cr, x1, y1);
    cairo_stroke(cr);
  }

  // In the corner of the plot area covering the fewest points and front corners.
  void legend() {
    const bool front = !front_.empty();
    const std::size_t rows = plot_.series_names.size() + (front ? 1 : 0);
    if (rows == 0) return;
    painter_.font(12);
    const double pad = 8 * s();
    const double sample = 26 * s();
    const double row = 1.9 * painter_.cap();
    double widest = front ? painter_.measure("Pareto front").width : 0;
    for (const std::string& name : plot_.series_names) {
      widest = std::max(widest, painter_.measure(name).width);
    }
    const double w = pad + sample + pad + widest + pad;
    const double h = pad + rows * row + pad - (row - painter_.cap()) + 2 * s();
    const double inset = 10 * s();
    const std::array<Box, 4> corners{{
        {area_.right - inset - w, area_.top + inset, area_.right - inset, area_.top + inset + h},
        {area_.left + inset, area_.top + inset, area_.left + inset + w, area_.top + inset + h},
        {area_.right - inset - w, area_.bottom - inset - h, area_.right - inset, area_.bottom - inset},
        {area_.left + inset, area_.bottom - inset - h, area_.left + inset + w, area_.bottom - inset},
    }};
    std::vector<std::array<double, 2>> obstacles;
    for (const PlotPoint& p : shown_) obstacles.push_back({px(p.x), py(p.y)});
    for (std::size_t i = 1; i < front_.size(); ++i) {
      obstacles.push_back({px(shown_[front_[i]].x), py(shown_[front_[i - 1]].y)});
    }
    const Box* best = &corners[0];
    std::size_t fewest = std::numeric_limits<std::size_t>::max();
    for (const Box& box : corners) {
      const Box grown{box.left - inset, box.top - inset, box.right + inset, box.bottom + inset};
      const auto covered = static_cast<std::size_t>(std::count_if(
          obstacles.begin(), obstacles.end(), [&](const auto& o) { return grown.contains(o[0], o[1]); }));
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
    for (std::size_t i = 0; i < plot_.series_names.size(); ++i, y += row) {
      marker(painter_, i, x + 0.5 * sample, y);
      painter_.colour(kInk);
      painter_.show(plot_.series_names[i], x + sample + pad, y, 0, 0.5);
    }
    if (front) {
      staircase(painter_, {{x, y}, {x + sample, y}});
      ring(painter_, x + 0.5 * sample, y);
      painter_.colour(kInk);
      painter_.show("Pareto front", x + sample + pad, y, 0, 0.5);
    }
  }

  std::size_t hidden() const { return failed_ + non_positive_ + huge_; }

  void note() {
    if (hidden() == 0) return;
    std::string text = std::to_string(hidden()) + " of " + std::to_string(plot_.points.size()) +
                       (plot_.points.size() == 1 ? " run" : " runs") + " not shown: ";
    const std::array<std::pair<std::size_t, const char*>, 3> reasons{{
        {failed_, " failed (non-finite)"},
        {non_positive_, " zero or negative (log axis)"},
        {huge_, " beyond \xC2\xB1" "1e300"},
    }};
    const char* separator = "";
    for (const auto& [count, reason] : reasons) {
      if (count == 0) continue;
      text += separator + std::to_string(count) + reason;
      separator = ", ";
    }
    painter_.font(11, Style::italic);
    painter_.colour({0.65, 0.1, 0.1});
    painter_.show(text, 14 * s(), note_baseline_, 0, 1);
  }

  Painter painter_;
  const ScatterPlot& plot_;
  int width_, height_;
  Axis x_, y_;
  std::vector<PlotPoint> shown_;
  std::vector<std::size_t> front_;  // indices into shown_
  std::size_t failed_ = 0, non_positive_ = 0, huge_ = 0;
  Box area_{};
  double tick_length_ = 5, title_size_ = 16, title_baseline_ = 0, x_label_baseline_ = 0,
         y_label_x_ = 0, note_baseline_ = 0;
};

cairo_status_t write_to_stream(void* closure, const unsigned char* data, unsigned int length) {
  auto& out = *static_cast<std::ostream*>(closure);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(length));
  return out ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

}  // namespace

void write_png(const ScatterPlot& plot, std::ostream& out, const std::string& what, int width,
               int height) {
  if (width < 320 || height < 240 || width > 8192 || height > 8192) {
    throw std::runtime_error(what + ": plot size " + std::to_string(width) + "x" +
                             std::to_string(height) + " outside 320x240 ... 8192x8192");
  }
  const std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width, height), cairo_surface_destroy);
  {
    const std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()),
                                                                cairo_destroy);
    Renderer(cr.get(), plot, width, height).render();
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

void write_png(const ScatterPlot& plot, const std::filesystem::path& file, int width, int height) {
  AtomicFile out(file);
  write_png(plot, out.stream(), file.string(), width, height);
  out.commit();
}

}  // namespace liedyn

#include "letters.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace liedyn {
namespace {

// Expansion limits (letters.hpp): straight strokes in segments ≤ 0.25, arcs every 7.5°.
constexpr double kMaxLineSegment = 0.25;
constexpr double kArcStepDegrees = 7.5;

// One piece of a letter's path, in em units. A point is a line from the current end to it
// (the first piece's point is the start). An arc runs along the ellipse centred at (x, y)
// with radii (rx, ry) from angle `from` to `to` (degrees, counter-clockwise from +x; to < from
// runs clockwise); it is joined to the current end by a straight line if its start differs.
struct Piece {
  bool is_arc = false;
  double x = 0.0, y = 0.0;
  double rx = 0.0, ry = 0.0, from = 0.0, to = 0.0;
};

constexpr Piece point(double x, double y) { return {false, x, y}; }
constexpr Piece arc(double cx, double cy, double rx, double ry, double from, double to) {
  return {true, cx, cy, rx, ry, from, to};
}

// The font. Paths of the letters with junctions (where strokes meet or retrace) are commented.
std::vector<Piece> letter_pieces(char c) {
  switch (c) {
    // Left leg up, right leg down, back up the right leg to the bar, across (retraces 0.37).
    case 'A':
      return {point(0, 0), point(0.4, 1), point(0.8, 0), point(0.66, 0.35), point(0.14, 0.35)};
    // From mid-stem: up, upper bowl, bar back to the stem, down, lower bowl up to the bar's end
    // (no retrace: only the mid-stem and the bowls' junction have an odd number of strokes).
    case 'B':
      return {point(0, 0.5), point(0, 1), point(0.3, 1), arc(0.3, 0.75, 0.25, 0.25, 90, -90),
              point(0, 0.5), point(0, 0), point(0.3, 0), arc(0.3, 0.25, 0.3, 0.25, -90, 90)};
    case 'C':
      return {arc(0.4, 0.5, 0.4, 0.5, 45, 315)};
    // Stem up, top bar, bowl, bottom bar back to the start (closed).
    case 'D':
      return {point(0, 0), point(0, 1), point(0.25, 1), arc(0.25, 0.5, 0.45, 0.5, 90, -90),
              point(0, 0)};
    // Top arm in, stem down to the middle, middle arm out and back, stem down, bottom arm out.
    case 'E':
      return {point(0.6, 1), point(0, 1), point(0, 0.5), point(0.5, 0.5),
              point(0, 0.5), point(0, 0), point(0.6, 0)};
    // As E without the bottom arm.
    case 'F':
      return {point(0.6, 1),   point(0, 1),   point(0, 0.5),
              point(0.5, 0.5), point(0, 0.5), point(0, 0)};
    // Arc from upper right anticlockwise round to the middle of the right side, bar inwards.
    case 'G':
      return {arc(0.4, 0.5, 0.4, 0.5, 45, 360), point(0.45, 0.5)};
    // Left stem up, back down to the middle, across, right stem up, all the way down
    // (retraces two half stems: all six stroke ends and junctions are odd).
    case 'H':
      return {point(0, 0),     point(0, 1),   point(0, 0.5),
              point(0.7, 0.5), point(0.7, 1), point(0.7, 0)};
    case 'I':
      return {point(0, 0), point(0, 1)};
    // Top serif, stem down, hook to the left.
    case 'J':
      return {point(0.25, 1), point(0.6, 1), point(0.6, 0.3), arc(0.3, 0.3, 0.3, 0.3, 0, -180)};
    // Upper arm in to mid-stem, up the stem, all the way down, back up to the middle, leg out
    // (retraces the stem once, 1.0: less than stem half + arm).
    case 'K':
      return {point(0.6, 1), point(0, 0.5), point(0, 1), point(0, 0), point(0, 0.5), point(0.6, 0)};
    case 'L':
      return {point(0, 1), point(0, 0), point(0.6, 0)};
    case 'M':
      return {point(0, 0), point(0, 1), point(0.4, 0.4), point(0.8, 1), point(0.8, 0)};
    case 'N':
      return {point(0, 0), point(0, 1), point(0.7, 0), point(0.7, 1)};
    // Closed ellipse from the top, anticlockwise.
    case 'O':
      return {arc(0.4, 0.5, 0.4, 0.5, 90, 450)};
    // Stem up, top bar, bowl, back to mid-stem (no retrace).
    case 'P':
      return {point(0, 0), point(0, 1), point(0.35, 1), arc(0.35, 0.75, 0.25, 0.25, 90, -90),
              point(0, 0.5)};
    // Tail from inside out to the ellipse at −45°, the full ellipse, then the tail on outwards.
    case 'Q':
      return {point(0.5, 0.3), arc(0.4, 0.5, 0.4, 0.5, -45, 315), point(0.857, 0)};
    // P, then the leg from where the bowl meets the stem (no retrace).
    case 'R':
      return {point(0, 0),   point(0, 1),   point(0.35, 1), arc(0.35, 0.75, 0.25, 0.25, 90, -90),
              point(0, 0.5), point(0.65, 0)};
    // Upper bowl anticlockwise from upper right to the centre, lower bowl clockwise to lower left.
    case 'S':
      return {arc(0.3, 0.75, 0.3, 0.25, 30, 270), arc(0.3, 0.25, 0.3, 0.25, 90, -150)};
    // Stem up, left half of the bar, then the whole bar (retraces 0.35).
    case 'T':
      return {point(0.35, 0), point(0.35, 1), point(0, 1), point(0.7, 1)};
    case 'U':
      return {point(0, 1), point(0, 0.35), arc(0.35, 0.35, 0.35, 0.35, 180, 360), point(0.7, 1)};
    case 'V':
      return {point(0, 1), point(0.35, 0), point(0.7, 1)};
    case 'W':
      return {point(0, 1), point(0.22, 0), point(0.45, 0.7), point(0.68, 0), point(0.9, 1)};
    // Upper left to lower right, back to the centre, to lower left, back, to upper right
    // (retraces the two lower half diagonals).
    case 'X':
      return {point(0, 1), point(0.35, 0.5), point(0.7, 0), point(0.35, 0.5),
              point(0, 0), point(0.35, 0.5), point(0.7, 1)};
    // Left arm to the fork, stem down and back up, right arm (retraces the stem).
    case 'Y':
      return {point(0, 1), point(0.35, 0.5), point(0.35, 0), point(0.35, 0.5), point(0.7, 1)};
    case 'Z':
      return {point(0, 1), point(0.7, 1), point(0, 0), point(0.7, 0)};
    default:
      return {};
  }
}

// Appends p unless it repeats the last point.
void append(std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& p) {
  if (points.empty() || (p - points.back()).norm() > 1e-12) points.push_back(p);
}

// Appends the straight stroke from the last point to p, cut into segments ≤ kMaxLineSegment.
void line_to(std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& p) {
  if (points.empty()) {
    points.push_back(p);
    return;
  }
  const Eigen::Vector3d a = points.back();
  const int parts = std::max(1, static_cast<int>(std::ceil((p - a).norm() / kMaxLineSegment)));
  for (int k = 1; k < parts; ++k) append(points, a + (p - a) * (static_cast<double>(k) / parts));
  append(points, p);  // exactly p, not a rounded interpolation
}

std::string describe(char c) {
  const auto code = static_cast<unsigned char>(c);
  if (code >= 0x20 && code < 0x7f) return std::string("'") + c + "'";
  return "character code " + std::to_string(code);
}

}  // namespace

std::vector<Eigen::Vector3d> letter_polyline(char letter) {
  const char upper =
      (letter >= 'a' && letter <= 'z') ? static_cast<char>(letter - 'a' + 'A') : letter;
  const std::vector<Piece> pieces = letter_pieces(upper);
  if (pieces.empty()) {
    throw std::invalid_argument("letter_polyline: " + describe(letter) +
                                " is not a letter A-Z (or a-z)");
  }
  std::vector<Eigen::Vector3d> points;
  for (const Piece& piece : pieces) {
    if (!piece.is_arc) {
      line_to(points, Eigen::Vector3d(piece.x, piece.y, 0.0));
      continue;
    }
    // (x, y) = centre + (rx cos φ, ry sin φ), φ from `from` to `to` in equal steps ≤ 7.5°.
    const double sweep = piece.to - piece.from;
    const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / kArcStepDegrees)));
    for (int k = 0; k <= steps; ++k) {
      const double phi = (piece.from + sweep * k / steps) * std::numbers::pi / 180.0;
      const Eigen::Vector3d p(piece.x + piece.rx * std::cos(phi),
                              piece.y + piece.ry * std::sin(phi), 0.0);
      if (k == 0) {
        line_to(points, p);  // joins the arc to the current end, if apart
      } else {
        append(points, p);
      }
    }
  }
  return points;
}

double polyline_length(const std::vector<Eigen::Vector3d>& polyline) {
  double length = 0.0;
  for (std::size_t i = 1; i < polyline.size(); ++i)
    length += (polyline[i] - polyline[i - 1]).norm();
  return length;
}

std::vector<Eigen::Vector3d> resample_polyline(const std::vector<Eigen::Vector3d>& polyline,
                                               int count) {
  if (count < 2) {
    throw std::invalid_argument("resample_polyline: count = " + std::to_string(count) +
                                ", must be >= 2");
  }
  if (polyline.size() < 2) {
    throw std::invalid_argument("resample_polyline: the polyline has " +
                                std::to_string(polyline.size()) + " points, needs >= 2");
  }
  // cumulative[i]: arc length from the first point to point i.
  std::vector<double> cumulative(polyline.size(), 0.0);
  for (std::size_t i = 0; i < polyline.size(); ++i) {
    if (!polyline[i].allFinite()) {
      throw std::invalid_argument("resample_polyline: point " + std::to_string(i) +
                                  " is not finite");
    }
    if (i > 0) cumulative[i] = cumulative[i - 1] + (polyline[i] - polyline[i - 1]).norm();
  }
  const double length = cumulative.back();
  // Finite points can still be too far apart for their distance (±1e308): an infinite length
  // would make every resampled point inf/inf = NaN, so reject it like a non-finite point.
  if (!std::isfinite(length)) {
    throw std::invalid_argument("resample_polyline: the polyline's length overflows a double");
  }
  if (!(length > 0.0)) {
    throw std::invalid_argument("resample_polyline: the polyline has zero length");
  }

  std::vector<Eigen::Vector3d> result;
  result.reserve(static_cast<std::size_t>(count));
  result.push_back(polyline.front());
  std::size_t segment = 0;  // from point `segment` to `segment + 1`
  for (int k = 1; k + 1 < count; ++k) {
    const double s = length * k / (count - 1);
    // The segment with cumulative[segment] ≤ s ≤ cumulative[segment + 1] (s increases with k).
    while (segment + 2 < polyline.size() && cumulative[segment + 1] < s) ++segment;
    const double segment_length = cumulative[segment + 1] - cumulative[segment];
    const double t = segment_length > 0.0
                         ? std::clamp((s - cumulative[segment]) / segment_length, 0.0, 1.0)
                         : 0.0;
    result.push_back(polyline[segment] + t * (polyline[segment + 1] - polyline[segment]));
  }
  result.push_back(polyline.back());
  return result;
}

std::vector<Eigen::Vector3d> letter_target(char letter, double height,
                                           const Eigen::Vector3d& origin, int count) {
  if (!(std::isfinite(height) && height > 0.0)) {
    throw std::invalid_argument("letter_target: height = " + std::to_string(height) +
                                ", must be finite and > 0");
  }
  if (!origin.allFinite()) throw std::invalid_argument("letter_target: origin is not finite");
  std::vector<Eigen::Vector3d> points = letter_polyline(letter);
  for (Eigen::Vector3d& p : points) p = origin + height * p;
  return resample_polyline(points, count);
}

}  // namespace liedyn

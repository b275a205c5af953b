// Letter shapes for the "rods spell letters" problem (problems/letters.hpp): every letter A–Z
// is one connected polyline in the em box, fine enough to resample; resampling spaces points
// equally by arc length and keeps them on the polyline; letter_target scales and translates.
// A failing letter test shows the letter drawn in characters (SCOPED_TRACE), nothing otherwise.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "problems/letters.hpp"

namespace liedyn {
namespace {

using Polyline = std::vector<Eigen::Vector3d>;

constexpr double kTol = 1e-12;

std::string all_letters() {
  std::string letters;
  for (char c = 'A'; c <= 'Z'; ++c) letters += c;
  return letters;
}

// Distance from p to the segment [a, b].
double distance_to_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double t =
      d.squaredNorm() > 0.0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

double distance_to_polyline(const Eigen::Vector3d& p, const Polyline& polyline) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < polyline.size(); ++i) {
    best = std::min(best, distance_to_segment(p, polyline[i], polyline[i + 1]));
  }
  return best;
}

// Every arc length s at which the polyline passes within kTol of p (several on retraced parts).
std::vector<double> arc_lengths_at(const Eigen::Vector3d& p, const Polyline& polyline) {
  std::vector<double> result;
  double start = 0.0;  // arc length at polyline[i]
  for (std::size_t i = 0; i + 1 < polyline.size(); ++i) {
    const Eigen::Vector3d d = polyline[i + 1] - polyline[i];
    const double length = d.norm();
    if (distance_to_segment(p, polyline[i], polyline[i + 1]) < kTol) {
      result.push_back(start + std::clamp((p - polyline[i]).dot(d) / length, 0.0, length));
    }
    start += length;
  }
  return result;
}

// The polyline drawn on a character grid (rows top to bottom), for failure messages.
std::string drawing(const Polyline& polyline) {
  constexpr int kRows = 11, kColumns = 21;  // cells of 0.1 × 0.05 em
  std::vector<std::string> grid(kRows, std::string(kColumns, '.'));
  for (std::size_t i = 0; i + 1 < polyline.size(); ++i) {
    for (int k = 0; k <= 20; ++k) {
      const Eigen::Vector3d p = polyline[i] + (polyline[i + 1] - polyline[i]) * (k / 20.0);
      const int row = kRows - 1 - static_cast<int>(std::lround(p.y() * (kRows - 1)));
      const int column = static_cast<int>(std::lround(p.x() * (kColumns - 1)));
      if (row >= 0 && row < kRows && column >= 0 && column < kColumns) grid[row][column] = '#';
    }
  }
  std::string text = "\n";
  for (const std::string& line : grid) text += line + "\n";
  return text;
}

TEST(Letters, EveryLetterIsOneFinePolylineInTheEmBox) {
  for (const char c : all_letters()) {
    const Polyline polyline = letter_polyline(c);
    SCOPED_TRACE(std::string("letter ") + c + drawing(polyline));
    ASSERT_GE(polyline.size(), 2u);
    double min_y = 1.0, max_y = 0.0, longest = 0.0;
    for (std::size_t i = 0; i < polyline.size(); ++i) {
      const Eigen::Vector3d& p = polyline[i];
      ASSERT_TRUE(p.allFinite()) << "point " << i;
      EXPECT_EQ(p.z(), 0.0) << "point " << i;
      EXPECT_GE(p.x(), -kTol) << "point " << i;
      EXPECT_LE(p.x(), 1.0 + kTol) << "point " << i;
      EXPECT_GE(p.y(), -kTol) << "point " << i;
      EXPECT_LE(p.y(), 1.0 + kTol) << "point " << i;
      min_y = std::min(min_y, p.y());
      max_y = std::max(max_y, p.y());
      if (i > 0) {
        const double segment = (p - polyline[i - 1]).norm();
        EXPECT_GT(segment, kTol) << "points " << i - 1 << " and " << i << " coincide";
        longest = std::max(longest, segment);
      }
    }
    // Every capital reaches from the baseline to the cap height.
    EXPECT_NEAR(min_y, 0.0, kTol);
    EXPECT_NEAR(max_y, 1.0, kTol);
    EXPECT_LE(longest, 0.35);
    EXPECT_GT(polyline_length(polyline), 0.9);
  }
}

TEST(Letters, LowerCaseIsUpperCase) {
  for (const char c : all_letters()) {
    const Polyline upper = letter_polyline(c);
    const Polyline lower = letter_polyline(static_cast<char>(c - 'A' + 'a'));
    ASSERT_EQ(upper.size(), lower.size()) << c;
    for (std::size_t i = 0; i < upper.size(); ++i) EXPECT_EQ(upper[i], lower[i]) << c << " " << i;
  }
}

TEST(Letters, SiggraphLettersExistAndIIsAVerticalStroke) {
  for (const char c : std::string("SIGGRAPH")) {
    EXPECT_NO_THROW(EXPECT_GE(letter_polyline(c).size(), 2u)) << c;
  }
  const Polyline i = letter_polyline('I');
  for (const Eigen::Vector3d& p : i) {
    EXPECT_EQ(p.x(), i.front().x());
    EXPECT_EQ(p.z(), 0.0);
  }
  for (std::size_t k = 1; k < i.size(); ++k) EXPECT_GT(i[k].y(), i[k - 1].y()) << k;
  EXPECT_EQ(i.front().y(), 0.0);
  EXPECT_EQ(i.back().y(), 1.0);
  EXPECT_DOUBLE_EQ(polyline_length(i), 1.0);
}

TEST(Letters, PolylineLength) {
  EXPECT_EQ(polyline_length({}), 0.0);
  EXPECT_EQ(polyline_length({Eigen::Vector3d(1, 2, 3)}), 0.0);
  // 3-4-5 out, then back 5: retraced parts count.
  const Polyline there_and_back = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 4, 0),
                                   Eigen::Vector3d(0, 0, 0)};
  EXPECT_DOUBLE_EQ(polyline_length(there_and_back), 10.0);
}

TEST(Letters, ResampleSpacesPointsEquallyAlongEveryLetter) {
  for (const char c : all_letters()) {
    const Polyline polyline = letter_polyline(c);
    const double length = polyline_length(polyline);
    for (const int count : {2, 3, 7, 40, 101}) {
      SCOPED_TRACE(std::string("letter ") + c + ", count " + std::to_string(count));
      const Polyline points = resample_polyline(polyline, count);
      ASSERT_EQ(points.size(), static_cast<std::size_t>(count));
      EXPECT_EQ(points.front(), polyline.front());
      EXPECT_EQ(points.back(), polyline.back());
      // Point k lies on the polyline, at arc length s_k = k L / (count − 1).
      const double spacing = length / (count - 1);
      std::vector<double> s(static_cast<std::size_t>(count));
      for (int k = 0; k < count; ++k) {
        EXPECT_LT(distance_to_polyline(points[k], polyline), kTol) << "point " << k;
        const std::vector<double> candidates = arc_lengths_at(points[k], polyline);
        ASSERT_FALSE(candidates.empty()) << "point " << k;
        s[k] = *std::min_element(candidates.begin(), candidates.end(), [&](double a, double b) {
          return std::abs(a - k * spacing) < std::abs(b - k * spacing);
        });
        EXPECT_NEAR(s[k], k * spacing, kTol) << "point " << k;
      }
      // The spacings s_{k+1} − s_k: their mean is L / (count − 1), their variance ~0.
      double mean = 0.0, variance = 0.0;
      for (int k = 0; k + 1 < count; ++k) mean += (s[k + 1] - s[k]) / (count - 1);
      for (int k = 0; k + 1 < count; ++k) {
        variance += std::pow(s[k + 1] - s[k] - mean, 2) / (count - 1);
      }
      EXPECT_NEAR(mean, spacing, kTol);
      EXPECT_LT(variance, 1e-24);
    }
  }
}

TEST(Letters, ResampledCurvesKeepTheirShape) {
  // On the finely sampled ellipse of "O" (turns of 7.5° per vertex) the chords between 40
  // resampled points are nearly equal: a corner shortens a chord by at most 1 − cos 3.75°.
  const Polyline points = resample_polyline(letter_polyline('O'), 40);
  double shortest = std::numeric_limits<double>::infinity(), longest = 0.0;
  for (std::size_t k = 1; k < points.size(); ++k) {
    shortest = std::min(shortest, (points[k] - points[k - 1]).norm());
    longest = std::max(longest, (points[k] - points[k - 1]).norm());
  }
  EXPECT_GT(shortest, (1.0 - 3e-3) * longest);
}

TEST(Letters, ResamplingAStraightLineInterpolatesLinearly) {
  const Eigen::Vector3d a(1.0, -2.0, 0.5), b(4.0, 2.0, -0.5);
  // Unevenly spaced vertices along the line, which resampling must not see.
  const Polyline line = {a, a + 0.05 * (b - a), a + 0.6 * (b - a), a + 0.65 * (b - a), b};
  for (const int count : {2, 3, 5, 17}) {
    const Polyline points = resample_polyline(line, count);
    ASSERT_EQ(points.size(), static_cast<std::size_t>(count));
    for (int k = 0; k < count; ++k) {
      const Eigen::Vector3d expected = a + (static_cast<double>(k) / (count - 1)) * (b - a);
      EXPECT_LT((points[k] - expected).norm(), kTol) << "count " << count << ", point " << k;
    }
  }
}

TEST(Letters, ResampleSkipsRepeatedPoints) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(1, 1, 0);
  const Polyline points = resample_polyline({a, a, b, b, b, c, c}, 5);
  const Polyline expected = {a, Eigen::Vector3d(0.5, 0, 0), b, Eigen::Vector3d(1, 0.5, 0), c};
  for (int k = 0; k < 5; ++k) EXPECT_LT((points[k] - expected[k]).norm(), kTol) << k;
}

TEST(Letters, LetterTargetScalesAndTranslates) {
  const Eigen::Vector3d origin(0.3, -1.0, 2.0);
  const double height = 0.25;
  for (const char c : std::string("SIGRAPH")) {
    const Polyline unit = resample_polyline(letter_polyline(c), 50);
    const Polyline target = letter_target(c, height, origin, 50);
    ASSERT_EQ(target.size(), 50u);
    for (std::size_t k = 0; k < target.size(); ++k) {
      EXPECT_LT((target[k] - (origin + height * unit[k])).norm(), kTol) << c << " " << k;
      EXPECT_NEAR(target[k].z(), origin.z(), kTol);
    }
    EXPECT_NEAR(polyline_length(target), height * polyline_length(unit), kTol);
  }
  // "I" runs from the origin straight up to origin + height ŷ.
  const Polyline i = letter_target('I', height, origin, 5);
  EXPECT_LT((i.front() - origin).norm(), kTol);
  EXPECT_LT((i.back() - (origin + Eigen::Vector3d(0, height, 0))).norm(), kTol);
}

// Runs f, which must throw std::invalid_argument with `fragment` in its message.
template <typename F>
void expect_invalid(F f, const std::string& fragment) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one mentioning " << fragment;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Letters, BadInputThrows) {
  expect_invalid([] { letter_polyline('1'); }, "'1'");
  expect_invalid([] { letter_polyline('?'); }, "'?'");
  expect_invalid([] { letter_polyline(' '); }, "' '");
  expect_invalid([] { letter_polyline('\0'); }, "character code 0");
  expect_invalid([] { letter_target('!', 1.0, Eigen::Vector3d::Zero(), 10); }, "'!'");

  const Polyline line = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  expect_invalid([&] { resample_polyline(line, 1); }, "count = 1");
  expect_invalid([&] { resample_polyline(line, 0); }, "count = 0");
  expect_invalid([] { resample_polyline({}, 10); }, "0 points");
  expect_invalid([] { resample_polyline({Eigen::Vector3d(1, 2, 3)}, 10); }, "1 points");
  expect_invalid(
      [] {
        resample_polyline({Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 2, 3)}, 10);
      },
      "zero length");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_invalid(
      [&] {
        resample_polyline({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(nan, 0, 0)}, 3);
      },
      "point 1");
  expect_invalid([] { letter_target('A', 0.0, Eigen::Vector3d::Zero(), 10); }, "height");
  expect_invalid([] { letter_target('A', -1.0, Eigen::Vector3d::Zero(), 10); }, "height");
  expect_invalid([&] { letter_target('A', 1.0, Eigen::Vector3d(nan, 0, 0), 10); }, "origin");
  expect_invalid([] { letter_target('A', 1.0, Eigen::Vector3d::Zero(), 1); }, "count = 1");
}

}  // namespace
}  // namespace liedyn

// Contact between two rod edges (lib/edge_contact.hpp): the Gauss–Legendre rule; the
// point–segment distance's gradient and Hessian (interior and both ends); the closest
// distance between segments against brute force; and the edge–edge penalty term's value vs
// gradient vs Hessian by central differences (tests/fd_check.hpp) on random overlapping
// pairs and on the configurations that break closest-point formulations — parallel,
// collinear end to end, touching at the ends at an angle, crossing at right angles, one edge
// much shorter, nearly parallel — over stiffnesses from tiny to huge; both sides of each
// switch of the Hessian; the residual form; the balance of the internal forces; and the
// symmetry between a and b. Then friction between the edges (EdgeFriction): its derivatives
// in stick and slip on the same configurations, at tiny and huge stiffnesses and time steps,
// the sliding force against the closed form, its residual form, and the mixed block of the
// lagged step that the adjoint needs.
//
// Geometry is O(1): edges 0.3–1.5 m, radii 0.12 + 0.08 m, gaps ≥ 1e-3 m. V is C¹ and
// piecewise smooth; its Hessian jumps where a sample's gap reaches 0 and where its
// projection reaches an end of the other segment. The FD checks use the fd_check defaults
// (steps 1e-6 for first differences, 1e-4 for second differences of the value) only at
// points whose margin to every switch (switch_margin: the node displacement that reaches
// one, to first order) is ≥ 1e-3, ten times the largest displacement of a second
// difference (√2 · 1e-4), so no difference straddles one; where a test is nearer a switch
// it says how its steps are chosen. A sample deep in contact, near the other segment's
// axis, curves its distance on the scale d: the value's second differences then take a
// step ≤ 3e-3 d (check below).

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fd_check.hpp"
#include "lib/edge_contact.hpp"
#include "lib/so3.hpp"
#include "lib/term.hpp"

namespace liedyn::edge_contact_tests {
namespace {

using fd::trace;

static_assert(Term<EdgeContact> && HasResidual<EdgeContact> && EnergyOfState<EdgeContact>);
static_assert(!BeginsStep<EdgeContact> && !ReadsPreviousStep<EdgeContact>);
static_assert(EdgeContact::kQuadraturePoints == 4 && EdgeContact::kResiduals == 8);
static_assert(BasicEdgeContact<8>::kResiduals == 16);
static_assert(Term<EdgeFriction> && HasResidual<EdgeFriction> && BeginsStep<EdgeFriction> &&
              ReadsPreviousStep<EdgeFriction> && !EnergyOfState<EdgeFriction>);

constexpr double kRadiusA = 0.12;
constexpr double kRadiusB = 0.08;
constexpr double kReach = kRadiusA + kRadiusB;

using Points = std::array<Vector3, 4>;  // a0, a1, b0, b1

// The same rigid motion of all four points, so that no test relies on axis-aligned edges.
Points moved(const Points& x, std::mt19937& rng) {
  const Matrix3 R = fd::rotation_at(1.3, rng);
  const Vector3 T = fd::random_vector(rng, 1.0);
  Points y;
  for (int i = 0; i < 4; ++i) y[i] = R * x[i] + T;
  return y;
}

template <int N>
struct Pair {
  BasicEdgeContact<N> term;
  State q;
};

// The nodes sit among other points and out of order, so that the term must read its own.
// Rest lengths differ from the current ones: they are constants of the term.
template <int N = 4>
Pair<N> edge_pair(const Points& x, double stiffness = 1e4) {
  Pair<N> c;
  c.q.points = {Vector3(7.0, 7.0, 7.0), x[0], x[1], x[3], x[2]};
  c.term.nodes = {1, 2, 4, 3};
  c.term.offsets = {3, 6, 12, 9};
  c.term.stiffness = stiffness;
  c.term.radius_a = kRadiusA;
  c.term.radius_b = kRadiusB;
  c.term.rest_length_a = 0.9 * (x[1] - x[0]).norm();
  c.term.rest_length_b = 1.1 * (x[3] - x[2]).norm();
  return c;
}

fd::Dofs dofs_of(const EdgeEdgeSample& term) {
  return {fd::point_dof(term.nodes[0]), fd::point_dof(term.nodes[1]), fd::point_dof(term.nodes[2]),
          fd::point_dof(term.nodes[3])};
}

template <int N>
Points points_of(const Pair<N>& c) {
  return {c.q.points[c.term.nodes[0]], c.q.points[c.term.nodes[1]], c.q.points[c.term.nodes[2]],
          c.q.points[c.term.nodes[3]]};
}

// A sample's data, recomputed here from its definition (edge_contact.hpp).
struct Sample {
  Vector3 p;      // the sample
  double s;       // its node on its edge
  double weight;  // w_k
  double distance;
  double t_hat;     // unclamped projection onto the other segment
  double off_line;  // distance from the other segment's line
  double length;    // the other segment's length
};

template <int N>
Sample sample(const Points& x, int side, int k) {
  const QuadratureRule& rule = gauss_legendre(N);
  const Vector3& p0 = x[2 * side];
  const Vector3& p1 = x[2 * side + 1];
  const Vector3& s0 = x[2 - 2 * side];
  const Vector3& s1 = x[3 - 2 * side];
  Sample out;
  out.s = rule.nodes[k];
  out.weight = rule.weights[k];
  out.p = (1.0 - out.s) * p0 + out.s * p1;
  out.distance = point_segment_distance(out.p, s0, s1);
  const Vector3 e = s1 - s0;
  out.length = e.norm();
  out.t_hat = (out.p - s0).dot(e) / e.squaredNorm();
  out.off_line = (out.p - s0 - out.t_hat * e).norm();
  return out;
}

// The node displacement, to first order, that brings some sample to a switch of V's Hessian:
// its gap |δ − d| reaching 0, and, for a sample in contact, its projection reaching an end
// of the other segment (along-segment distance |t̂| ℓ or |t̂ − 1| ℓ, which moves at a rate of up
// to 1 + (distance from the line)/ℓ as the nodes move: the segment turns about its other
// end) or its distance reaching 0 (the curvature 1/d).
template <int N>
double switch_margin(const Pair<N>& c) {
  const Points x = points_of(c);
  double margin = std::numeric_limits<double>::infinity();
  for (int side = 0; side < 2; ++side) {
    for (int k = 0; k < N; ++k) {
      const Sample smp = sample<N>(x, side, k);
      const double gap = kReach - smp.distance;
      margin = std::min(margin, std::abs(gap));
      if (gap > 0.0) {
        const double rate = 1.0 + smp.off_line / smp.length;
        margin = std::min({margin, smp.distance, std::abs(smp.t_hat) * smp.length / rate,
                           std::abs(smp.t_hat - 1.0) * smp.length / rate});
      }
    }
  }
  return margin;
}

// The smallest distance of a sample in contact to the other segment.
template <int N>
double closest_contact(const Pair<N>& c) {
  const Points x = points_of(c);
  double closest = std::numeric_limits<double>::infinity();
  for (int side = 0; side < 2; ++side) {
    for (int k = 0; k < N; ++k) {
      const double d = sample<N>(x, side, k).distance;
      if (d < kReach) closest = std::min(closest, d);
    }
  }
  return closest;
}

// fd::check_term at a point in contact and at least `min_margin` from every switch. A
// sample's distance d has derivatives of order k of size ~ 1/d^(k−1), so the value's second
// differences have a truncation ~ (step/d)² relative: their step is at most 3e-3 d (≤ 1e-5,
// the check's rtol) for the sample in contact nearest the other segment's axis.
template <int N>
::testing::AssertionResult check(const Pair<N>& c, double min_margin = 1e-3,
                                 fd::TermCheckOptions options = {}) {
  const double margin = switch_margin(c);
  if (!(margin >= min_margin)) {
    return ::testing::AssertionFailure()
           << "test point is " << margin << " from a switch (want ≥ " << min_margin << ")";
  }
  if (!(c.term.evaluate(c.q, nullptr, nullptr) > 0.0)) {
    return ::testing::AssertionFailure() << "test point is not in contact";
  }
  options.hessian_from_value.step =
      std::min(options.hessian_from_value.step, 3e-3 * closest_contact(c));
  return fd::check_term(c.term, c.q, dofs_of(c.term), options);
}

template <int N>
LocalGradient<4> gradient(const Pair<N>& c) {
  LocalGradient<4> g;
  c.term.evaluate(c.q, &g, nullptr);
  return g;
}

template <int N>
LocalHessian<4> hessian(const Pair<N>& c) {
  LocalHessian<4> H;
  c.term.evaluate(c.q, nullptr, &H);
  return H;
}

// Edges of length 1 (a, along x from the origin) and `length_b` (b, along x from x = start),
// `offset` apart along y: parallel, side by side, overlapping in projection.
Points parallel(double start, double length_b, double offset) {
  return {Vector3(0.0, 0.0, 0.0), Vector3(1.0, 0.0, 0.0), Vector3(start, offset, 0.0),
          Vector3(start + length_b, offset, 0.0)};
}

// a random pair with some sample of a near a random point of b.
Points random_overlapping(std::mt19937& rng) {
  std::uniform_real_distribution<double> length(0.3, 1.5), inner(0.1, 0.9);
  Points x;
  x[0] = fd::random_vector(rng, 1.0);
  x[1] = x[0] + length(rng) * fd::random_unit(rng);
  const Vector3 contact = x[0] + inner(rng) * (x[1] - x[0]) + fd::random_vector(rng, 0.15);
  const Vector3 direction = length(rng) * fd::random_unit(rng);
  x[2] = contact - inner(rng) * direction;
  x[3] = x[2] + direction;
  return x;
}

// ---------------------------------------------------------------------------------------

TEST(EdgeContactQuadrature, GaussLegendreIsExactToDegreeTwoNMinusOne) {
  for (int n = 1; n <= kMaxEdgeQuadraturePoints; ++n) {
    SCOPED_TRACE(trace("points", n));
    const QuadratureRule& rule = gauss_legendre(n);
    ASSERT_EQ(rule.size, n);
    double previous = 0.0;
    for (int k = 0; k < n; ++k) {
      EXPECT_GT(rule.nodes[k], previous);
      EXPECT_LT(rule.nodes[k], 1.0);
      EXPECT_GT(rule.weights[k], 0.0);
      EXPECT_NEAR(rule.nodes[k] + rule.nodes[n - 1 - k], 1.0, 1e-15);  // symmetric about ½
      previous = rule.nodes[k];
    }
    // ∫₀¹ s^m ds = 1/(m + 1): exact (to round-off) up to m = 2n − 1 (m = 0: weights sum to
    // 1), and not for m = 2n, whose error is the rule's (n!)⁴/((2n+1)((2n)!)³) ≥ 1e-16 ·
    // 1e3 for n ≤ 8 (n = 8: 1.1e-13).
    for (int m = 0; m <= 2 * n; ++m) {
      double sum = 0.0;
      for (int k = 0; k < n; ++k) sum += rule.weights[k] * std::pow(rule.nodes[k], m);
      if (m < 2 * n) {
        EXPECT_NEAR(sum, 1.0 / (m + 1), 2e-16 * n) << "degree " << m;
      } else {
        EXPECT_GT(std::abs(sum - 1.0 / (m + 1)), 1e-14) << "degree " << m;
      }
    }
  }
  EXPECT_THROW(gauss_legendre(0), std::out_of_range);
  EXPECT_THROW(gauss_legendre(kMaxEdgeQuadraturePoints + 1), std::out_of_range);
}

// ---------------------------------------------------------------------------------------

TEST(EdgeContactPointSegment, DerivativesInTheInteriorAndAtBothEndsMatchFiniteDifferences) {
  std::mt19937 rng(51);
  const fd::Dofs dofs = {fd::point_dof(0), fd::point_dof(1), fd::point_dof(2)};
  const fd::ScalarFunction f = [](const State& s) {
    return point_segment_distance(s.points[0], s.points[1], s.points[2]);
  };
  const fd::GradientFunction grad = [](const State& s) {
    LocalGradient<3> g;
    point_segment_distance(s.points[0], s.points[1], s.points[2], &g);
    return Eigen::VectorXd(g);
  };
  int checked[3] = {0, 0, 0};  // t̂ < 0, interior, t̂ > 1
  for (int trial = 0; trial < 60; ++trial) {
    State q;
    const Vector3 b0 = fd::random_vector(rng, 1.0);
    const Vector3 b1 = b0 + std::uniform_real_distribution<double>(0.3, 1.5)(rng) * fd::random_unit(rng);
    // t̂ in three bands ≥ 0.05 from the ends (|e| ≥ 0.3: ≥ 1.5e-2 m), at 0.1–1 from the line.
    const double t_hat = std::array{-0.6, 0.3, 0.8, 1.4}[trial % 4] +
                         std::uniform_real_distribution<double>(-0.1, 0.1)(rng);
    const Vector3 e = b1 - b0;
    const double off = std::uniform_real_distribution<double>(0.1, 1.0)(rng);
    q.points = {b0 + t_hat * e + off * fd::random_perpendicular(e.normalized(), rng), b0, b1};
    SCOPED_TRACE(trace("t̂", t_hat));
    LocalGradient<3> g;
    LocalHessian<3> H;
    const double d = point_segment_distance(q.points[0], b0, b1, &g, &H);
    const Vector3 closest = b0 + std::clamp(t_hat, 0.0, 1.0) * e;
    EXPECT_NEAR(d, (q.points[0] - closest).norm(), 1e-14);
    // An end's derivatives leave the other end out: at t̂ < 0 nothing depends on b1.
    fd::FdOptions go;
    if (t_hat < 0.0 || t_hat > 1.0) go.require_nonzero = fd::NonZero::kAny;
    if (t_hat < 0.0) {
      EXPECT_TRUE(g.segment<3>(6).isZero(0.0));
    }
    if (t_hat > 1.0) {
      EXPECT_TRUE(g.segment<3>(3).isZero(0.0));
    }
    EXPECT_TRUE(fd::check_lie_gradient(f, q, dofs, g, go));
    EXPECT_TRUE(fd::check_lie_hessian(grad, q, dofs, H));
    EXPECT_TRUE(fd::check_lie_hessian_from_value(f, q, dofs, H));
    ++checked[t_hat < 0.0 ? 0 : t_hat < 1.0 ? 1 : 2];
  }
  EXPECT_EQ(checked[0], 15);
  EXPECT_EQ(checked[1], 30);
  EXPECT_EQ(checked[2], 15);
}

TEST(EdgeContactPointSegment, DegenerateCases) {
  LocalGradient<3> g;
  LocalHessian<3> H;
  // p on the segment: distance 0, no direction, derivatives taken as 0 (exact binary
  // fractions, so that p is on it to the last bit).
  const Vector3 b0(0.25, 0.5, -0.75), b1(1.25, -0.5, 0.25);
  EXPECT_EQ(point_segment_distance(Vector3(0.5, 0.25, -0.5), b0, b1, &g, &H), 0.0);
  EXPECT_TRUE(g.isZero(0.0));
  EXPECT_TRUE(H.isZero(0.0));
  // A segment of zero length is its point: t = 0, the end formulas (b1's block is 0).
  const Vector3 p(0.4, -0.3, 0.9);
  EXPECT_DOUBLE_EQ(point_segment_distance(p, b0, b0, &g, &H), (p - b0).norm());
  EXPECT_TRUE(g.head<3>().isApprox((p - b0).normalized(), 1e-15));
  EXPECT_TRUE(g.segment<3>(3).isApprox(-(p - b0).normalized(), 1e-15));
  EXPECT_TRUE(g.segment<3>(6).isZero(0.0));
}

// ---------------------------------------------------------------------------------------

// The closest distance between [a0, a1] and [b0, b1] by brute force, two ways:
//   * sampling both parameters on a 401 × 401 grid gives an upper bound U, and the true
//     distance is ≥ U − (|a1 − a0| + |b1 − b0|)/800 (each parameter is within 1/800 of a
//     grid point, and the distance is 1-Lipschitz in each point);
//   * nested golden-section searches: s ↦ min_t |a(s) − b(t)| and t ↦ |a(s) − b(t)| are
//     convex (distances of an affine path to a convex set), so each search converges to
//     the minimum, to ~1e-16 relative after 80 iterations.
struct BruteForce {
  double upper, lower, reference;
};

double golden_minimum(const std::function<double(double)>& f) {
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = 0.0, hi = 1.0;
  double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < 80; ++i) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - r * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + r * (hi - lo);
      f2 = f(x2);
    }
  }
  return std::min({f1, f2, f(0.0), f(1.0)});
}

BruteForce brute_force(const Points& x) {
  const auto at = [&x](double s, double t) {
    return ((x[0] + s * (x[1] - x[0])) - (x[2] + t * (x[3] - x[2]))).norm();
  };
  constexpr int kGrid = 400;
  double upper = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kGrid; ++i) {
    for (int j = 0; j <= kGrid; ++j) upper = std::min(upper, at(double(i) / kGrid, double(j) / kGrid));
  }
  const double slack = ((x[1] - x[0]).norm() + (x[3] - x[2]).norm()) / (2.0 * kGrid);
  const double reference = golden_minimum(
      [&](double s) { return golden_minimum([&](double t) { return at(s, t); }); });
  return {upper, upper - slack, reference};
}

::testing::AssertionResult agrees_with_brute_force(const Points& x) {
  const double d = segment_distance(x[0], x[1], x[2], x[3]);
  const BruteForce b = brute_force(x);
  double scale = 0.0;
  for (const Vector3& p : x) scale = std::max(scale, p.norm());
  const double tol = 1e-13 * (1.0 + scale);
  if (d > b.upper + tol || d < b.lower - tol || std::abs(d - b.reference) > tol) {
    return ::testing::AssertionFailure()
           << "segment_distance " << d << ", grid bounds [" << b.lower << ", " << b.upper
           << "], golden-section " << b.reference << " (difference " << d - b.reference << ")";
  }
  return ::testing::AssertionSuccess();
}

TEST(EdgeContactSegmentDistance, MatchesBruteForceOnRandomSegments) {
  std::mt19937 rng(52);
  for (int trial = 0; trial < 150; ++trial) {
    Points x;
    for (Vector3& p : x) p = fd::random_vector(rng, 1.0);
    EXPECT_TRUE(agrees_with_brute_force(x)) << "trial " << trial;
  }
}

TEST(EdgeContactSegmentDistance, MatchesBruteForceOnDegenerateSegments) {
  std::mt19937 rng(53);
  const Vector3 o(0, 0, 0), ex(1, 0, 0);
  struct Case {
    const char* name;
    Points x;
    double exact;  // the known distance
  };
  // Skew lines nearly parallel, 0.15 apart, crossing in projection at x = c: the 2 × 2
  // system for the lines' closest pair is as ill-conditioned as it gets at 1e-9, and the
  // ends are not close enough (by ~ angle²/(8 · 0.15)) at 1e-4 … 1e-6.
  const auto nearly_parallel = [&](double angle, double c) -> Points {
    return {o, ex, Vector3(c - 0.6 * std::cos(angle), 0.15, -0.6 * std::sin(angle)),
            Vector3(c + 0.6 * std::cos(angle), 0.15, 0.6 * std::sin(angle))};
  };
  std::vector<Case> cases = {
      {"parallel overlapping", parallel(0.3, 1.0, 0.15), 0.15},
      {"parallel disjoint", parallel(1.5, 1.0, 0.15), std::hypot(0.5, 0.15)},
      {"antiparallel", {o, ex, Vector3(1.3, 0.15, 0), Vector3(0.3, 0.15, 0)}, 0.15},
      {"collinear overlapping", {o, ex, Vector3(0.5, 0, 0), Vector3(1.5, 0, 0)}, 0.0},
      {"collinear apart", {o, ex, Vector3(1.05, 0, 0), Vector3(2.05, 0, 0)}, 0.05},
      {"collinear contained", {o, ex, Vector3(0.2, 0, 0), Vector3(0.4, 0, 0)}, 0.0},
      {"crossing", {Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(0.1, -0.5, 0), Vector3(0.1, 0.5, 0)}, 0.0},
      {"skew right angle", {Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(0.1, -0.5, 0.2), Vector3(0.1, 0.5, 0.2)}, 0.2},
      {"ends touching", {o, ex, ex, Vector3(1.5, 0.8, 0)}, 0.0},
      {"T junction", {o, ex, Vector3(0.4, 0.3, 0), Vector3(0.4, 1.3, 0)}, 0.3},
      {"a is a point", {Vector3(0.4, 0.3, 0.1), Vector3(0.4, 0.3, 0.1), o, ex}, std::hypot(0.3, 0.1)},
      {"b is a point", {o, ex, Vector3(1.3, 0.4, 0), Vector3(1.3, 0.4, 0)}, 0.5},
      {"both points", {o, o, ex, ex}, 1.0},
      {"long and short", {Vector3(-1e3, 0, 0), Vector3(1e3, 0, 0), Vector3(3.0, 0.2, 1e-3), Vector3(3.0, 0.2, -1e-3)}, 0.2},
  };
  for (double angle : {1e-4, 1e-5, 1e-6, 1e-7, 1e-9}) {
    for (double c : {0.5, 0.1}) cases.push_back({"nearly parallel", nearly_parallel(angle, c), 0.15});
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    EXPECT_TRUE(agrees_with_brute_force(c.x));
    double scale = 0.0;
    for (const Vector3& p : c.x) scale = std::max(scale, p.norm());
    EXPECT_NEAR(segment_distance(c.x[0], c.x[1], c.x[2], c.x[3]), c.exact, 1e-15 * (1.0 + scale));
    // Symmetric in the two segments and in each one's direction.
    const double d = segment_distance(c.x[0], c.x[1], c.x[2], c.x[3]);
    EXPECT_NEAR(segment_distance(c.x[2], c.x[3], c.x[0], c.x[1]), d, 1e-14);
    EXPECT_NEAR(segment_distance(c.x[1], c.x[0], c.x[3], c.x[2]), d, 1e-14);
    // And under a rigid motion (which rounds the coordinates: a few ulps of the scale).
    const Points y = moved(c.x, rng);
    EXPECT_TRUE(agrees_with_brute_force(y));
    EXPECT_NEAR(segment_distance(y[0], y[1], y[2], y[3]), c.exact, 1e-15 * (3.0 + scale));
  }
}

// ---------------------------------------------------------------------------------------

// A test point: in contact, ≥ 1e-3 from every switch, and with every node pushed (each
// block of the gradient well above the checks' floor: fd_check's kEveryBlock).
template <int N>
bool acceptable(const Pair<N>& c) {
  if (!(c.term.evaluate(c.q, nullptr, nullptr) > 0.0) || switch_margin(c) < 1e-3) return false;
  const LocalGradient<4> g = gradient(c);
  for (int b = 0; b < 4; ++b) {
    if (!(g.segment<3>(3 * b).norm() > 1e-3 * g.norm())) return false;
  }
  return true;
}

template <int N = 4>
Pair<N> random_pair(std::mt19937& rng, double stiffness = 1e4) {
  for (int attempt = 0; attempt < 100000; ++attempt) {
    const Pair<N> c = edge_pair<N>(random_overlapping(rng), stiffness);
    if (acceptable(c)) return c;
  }
  throw std::runtime_error("no acceptable random pair");
}

TEST(EdgeContact, RandomOverlappingPairsMatchFiniteDifferences) {
  std::mt19937 rng(54);
  for (int trial = 0; trial < 60; ++trial) EXPECT_TRUE(check(random_pair<4>(rng))) << trial;
  // Other rules: one sample per edge (at the middle), two, and the largest.
  for (int trial = 0; trial < 15; ++trial) {
    EXPECT_TRUE(check(random_pair<1>(rng))) << trial;
    EXPECT_TRUE(check(random_pair<2>(rng))) << trial;
    EXPECT_TRUE(check(random_pair<8>(rng))) << trial;
  }
}

TEST(EdgeContact, ParallelSideBySide) {
  std::mt19937 rng(55);
  // b from x = 0.3 to 1.6, 0.15 beside a: some samples project inside the other segment,
  // some beyond its end (and are then out of reach), ≥ 0.03 from a switch.
  for (double offset : {0.15, 0.05}) {
    SCOPED_TRACE(trace("offset", offset));
    EXPECT_TRUE(check(edge_pair(moved(parallel(0.3, 1.3, offset), rng))));
  }
  // Fully overlapping equal parallel edges: every sample is at the offset h, so V is the
  // line contact's ½ k γ² per unit length over the mean rest length, for any rule:
  //   V = ½ ℓ̄_a · ½ k γ² + ½ ℓ̄_b · ½ k γ² = ½ k γ² (ℓ̄_a + ℓ̄_b)/2,
  // and the force on a's nodes is k γ (ℓ̄_a + ℓ̄_b)/2 away from b.
  const double h = 0.15, gap = kReach - h, k = 1e4;
  const Points x = moved(parallel(0.0, 1.0, h), rng);
  const Vector3 away = ((x[0] - x[2]) - (x[0] - x[2]).dot(x[1] - x[0]) * (x[1] - x[0])).normalized();
  const auto expect_line_contact = [&](auto c) {
    c.term.rest_length_a = 0.8;
    c.term.rest_length_b = 1.2;
    const double mean = 1.0;
    LocalGradient<4> g;
    EXPECT_NEAR(c.term.evaluate(c.q, &g, nullptr), 0.5 * k * gap * gap * mean, 1e-12 * k);
    EXPECT_TRUE((-(g.segment<3>(0) + g.segment<3>(3))).isApprox(k * gap * mean * away, 1e-12));
    EXPECT_TRUE(check(c, 1e-2));  // the outer samples of 8 points are 0.02 from the ends
  };
  expect_line_contact(edge_pair<1>(x, k));
  expect_line_contact(edge_pair<4>(x, k));
  expect_line_contact(edge_pair<8>(x, k));
}

TEST(EdgeContact, CollinearEndToEndWithAGapBelowTheRadii) {
  std::mt19937 rng(56);
  // a = [0, 1], b = [1 + gap, 2 + gap] on one line: the samples near the facing ends reach
  // the other's end (t clamped), 0.12 or more beyond it; the gap is < ρ_a + ρ_b = 0.2.
  for (double gap : {0.05, 0.01}) {
    SCOPED_TRACE(trace("gap", gap));
    const Points x = {Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(1 + gap, 0, 0),
                      Vector3(2 + gap, 0, 0)};
    const Pair<4> c = edge_pair(moved(x, rng));
    EXPECT_NEAR(segment_distance(points_of(c)[0], points_of(c)[1], points_of(c)[2], points_of(c)[3]),
                gap, 1e-14);
    EXPECT_TRUE(check(c));
    // The force is along the line: the edges push each other apart, end on end.
    const LocalGradient<4> g = gradient(c);
    const Vector3 line = (points_of(c)[1] - points_of(c)[0]).normalized();
    for (int b = 0; b < 4; ++b) {
      EXPECT_LT((g.segment<3>(3 * b) - g.segment<3>(3 * b).dot(line) * line).norm(), 1e-12 * g.norm());
    }
    EXPECT_GT(g.segment<3>(3).dot(line), 0.0);  // a1 pushed back (−g along −line)
  }
}

TEST(EdgeContact, TouchingAtTheEndsAtAnAngle) {
  std::mt19937 rng(57);
  // b starts 0.06 past a1 and leaves at 60° (opening) or 120° (folding back over a).
  for (double angle : {std::numbers::pi / 3.0, 2.0 * std::numbers::pi / 3.0}) {
    SCOPED_TRACE(trace("angle", angle));
    const Vector3 b0(1.04, 0.03, 0.04);
    const Points x = {Vector3(0, 0, 0), Vector3(1, 0, 0), b0,
                      b0 + 0.9 * Vector3(std::cos(angle), std::sin(angle), 0.0)};
    EXPECT_TRUE(check(edge_pair(moved(x, rng))));
  }
}

TEST(EdgeContact, CrossingAtRightAngles) {
  std::mt19937 rng(58);
  // a along x, b along y at x = 0.1 and height h: h = 0 is intersecting segments (no
  // sample lies on the other segment, so every distance is > 0).
  for (double h : {0.1, 0.0}) {
    SCOPED_TRACE(trace("height", h));
    const Points x = {Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(0.1, -0.45, h),
                      Vector3(0.1, 0.55, h)};
    EXPECT_TRUE(check(edge_pair(moved(x, rng))));
  }
}

TEST(EdgeContact, OneEdgeMuchShorterThanTheOther) {
  // b of length ℓ (1e-2 and 1e-3 m; a is 1 m) 0.1 above a, either tilted so that a's samples
  // project beyond its ends (t clamped), or across a so that they all project onto its
  // middle (t̂ = ½). A short segment turns fast: moving an end by δ turns it by δ/ℓ and moves
  // a sample's projection along it by ~ |w| δ/ℓ, so the projections' switches are near:
  // ~ ℓ²/(2|w|) for the middle (5e-6 m at ℓ = 1e-3), ~ |t̂| ℓ²/|w| beyond the ends
  // (switch_margin's m). There the Hessian's u uᵀ/d is (|w|/ℓ)² times the rest and varies
  // on the scale m. So the steps are fractions of m: 1e-4 m for first differences
  // (truncation ~ 1e-8 relative) and 3e-3 m for second differences of the value (~ 1e-5,
  // the rtol), whose round-off eps·V/step² the check computes.
  std::mt19937 rng(59);
  for (double length : {1e-2, 1e-3}) {
    for (const Vector3& along : {Vector3(0.3, 1.0, 0.2).normalized(), Vector3(0.0, 1.0, 0.0)}) {
      SCOPED_TRACE(trace("length, along x", length, along.x()));
      const Vector3 centre(0.37, along.x() == 0.0 ? 0.0 : 0.02, 0.1);
      const Points x = {Vector3(0, 0, 0), Vector3(1, 0, 0), centre - 0.5 * length * along,
                        centre + 0.5 * length * along};
      const Pair<4> c = edge_pair(moved(x, rng));
      const double m = switch_margin(c);
      EXPECT_LT(m, 0.5 * length);  // the switches are as near as said
      fd::TermCheckOptions o;
      o.gradient.step = o.hessian.step = 1e-4 * m;
      o.hessian_from_value.step = 3e-3 * m;
      EXPECT_TRUE(check(c, m, o));
    }
  }
}

TEST(EdgeContact, NearlyParallelIsSmoothThroughParallel) {
  std::mt19937 rng(60);
  // b (0.3 to 1.6, 0.15 beside a) turned by θ about its midpoint, about the offset (the
  // lines become skew: the closest pair of the lines runs off along them as θ → 0) and about
  // the normal of their plane. A closest-point formulation jumps there; this one's gradient
  // moves by at most ‖H‖ times the nodes' displacement, ≤ 0.65 θ for each of b's ends.
  const Points flat = parallel(0.3, 1.3, 0.15);
  const Vector3 middle = 0.5 * (flat[2] + flat[3]);
  for (const Vector3& axis : {Vector3(0, 1, 0), Vector3(0, 0, 1)}) {
    const Matrix3 R = fd::rotation_at(0.8, rng);
    const Vector3 T = fd::random_vector(rng, 1.0);
    const auto posed = [&](double theta) {
      Points x = flat;
      const Matrix3 turn = so3::exp(theta * axis);
      for (int i = 2; i < 4; ++i) x[i] = middle + turn * (flat[i] - middle);
      for (Vector3& p : x) p = R * p + T;
      return edge_pair(x);
    };
    const Pair<4> parallel_pair = posed(0.0);
    const LocalGradient<4> g0 = gradient(parallel_pair);
    const double bound = 2.0 * hessian(parallel_pair).norm() * std::sqrt(2.0) * 0.65;
    for (double theta : {1e-9, 1e-4}) {
      SCOPED_TRACE(trace("axis, angle", axis.y(), theta));
      const Pair<4> c = posed(theta);
      EXPECT_TRUE(check(c));
      EXPECT_LE((gradient(c) - g0).norm(), bound * theta);
      EXPECT_GT(g0.norm(), 100.0);
    }
  }
}

TEST(EdgeContact, TinyAndHugeStiffnesses) {
  std::mt19937 rng(61);
  const Points crossing = {Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(0.1, -0.45, 0.1),
                           Vector3(0.1, 0.55, 0.1)};
  for (double k : {1e-3, 1.0, 1e9}) {
    SCOPED_TRACE(trace("stiffness", k));
    EXPECT_TRUE(check(edge_pair(moved(crossing, rng), k)));
    EXPECT_TRUE(check(edge_pair(moved(parallel(0.3, 1.3, 0.1), rng), k)));
    EXPECT_TRUE(check(random_pair(rng, k)));
  }
}

TEST(EdgeContact, IsExactlyZeroWhenApart) {
  std::mt19937 rng(62);
  const Points cases[] = {
      parallel(0.3, 1.3, 0.25),
      {Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(1.25, 0, 0), Vector3(2.25, 0, 0)},
      {Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(0.1, -0.45, 0.3), Vector3(0.1, 0.55, 0.3)},
  };
  for (const Points& x : cases) {
    const Pair<4> c = edge_pair(moved(x, rng));
    const Points y = points_of(c);
    ASSERT_GT(segment_distance(y[0], y[1], y[2], y[3]), kReach + 0.04);
    LocalGradient<4> g;
    LocalHessian<4> H;
    g.setConstant(1.0);  // evaluate writes, it does not add
    H.setConstant(1.0);
    EXPECT_EQ(c.term.evaluate(c.q, &g, &H), 0.0);
    EXPECT_TRUE(g.isZero(0.0));
    EXPECT_TRUE(H.isZero(0.0));
    EdgeContact::Residual r;
    EdgeContact::ResidualJacobian J;
    r.setConstant(1.0);
    J.setConstant(1.0);
    c.term.residual(c.q, r, &J);
    EXPECT_TRUE(r.isZero(0.0));
    EXPECT_TRUE(J.isZero(0.0));
    EXPECT_LT(c.term.penetration(c.q), -0.04);
  }
}

TEST(EdgeContact, SeesContactOnlyAtItsSamples) {
  // Segments crossing at right angles 0.01 apart, at a's middle, between its samples (4
  // points: ±0.17 from the middle) and at b's, between its own. With ρ_a + ρ_b = 0.02 the
  // capsules overlap but no sample is within reach: V = 0 (the documented limitation: N
  // must resolve the edges at the scale of the radii). With radii 0.1 the samples see it.
  const Points x = {Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(0, -0.5, 0.01),
                    Vector3(0, 0.5, 0.01)};
  Pair<4> c = edge_pair(x);
  c.term.radius_a = c.term.radius_b = 0.01;
  EXPECT_NEAR(segment_distance(x[0], x[1], x[2], x[3]), 0.01, 1e-15);
  EXPECT_EQ(c.term.evaluate(c.q, nullptr, nullptr), 0.0);
  EXPECT_LT(c.term.penetration(c.q), 0.0);
  c.term.radius_a = c.term.radius_b = 0.1;
  EXPECT_GT(c.term.evaluate(c.q, nullptr, nullptr), 0.0);
  EXPECT_GT(c.term.penetration(c.q), 0.0);
}

TEST(EdgeContact, PenetrationIsTheDeepestSample) {
  std::mt19937 rng(63);
  for (int trial = 0; trial < 20; ++trial) {
    const Pair<4> c = random_pair(rng);
    const Points x = points_of(c);
    double closest = std::numeric_limits<double>::infinity();
    for (int side = 0; side < 2; ++side) {
      for (int k = 0; k < 4; ++k) closest = std::min(closest, sample<4>(x, side, k).distance);
    }
    EXPECT_DOUBLE_EQ(c.term.penetration(c.q), kReach - closest);
    // Samples are points of the segments: never closer than the segments are.
    EXPECT_LE(c.term.penetration(c.q), kReach - segment_distance(x[0], x[1], x[2], x[3]) + 1e-15);
    EXPECT_GT(c.term.penetration(c.q), 0.0);
  }
}

TEST(EdgeContact, ResidualFormReproducesValueAndGradient) {
  std::mt19937 rng(64);
  for (int trial = 0; trial < 20; ++trial) {
    const Pair<4> c = trial == 0   ? edge_pair(moved(parallel(0.3, 1.3, 0.15), rng))
                      : trial == 1 ? edge_pair(moved({Vector3(0, 0, 0), Vector3(1, 0, 0),
                                                      Vector3(1.05, 0, 0), Vector3(2.05, 0, 0)},
                                                     rng))
                                   : random_pair(rng);
    ASSERT_GE(switch_margin(c), 1e-3);
    LocalGradient<4> g;
    const double value = c.term.evaluate(c.q, &g, nullptr);
    EdgeContact::Residual r;
    EdgeContact::ResidualJacobian J;
    c.term.residual(c.q, r, &J);
    EXPECT_NEAR(0.5 * r.squaredNorm(), value, 1e-14 * value);
    EXPECT_LT((J.transpose() * r - g).norm(), 1e-13 * g.norm());
    // One residual per sample, √(w ℓ̄ k/2) γ where the sample is in contact, else 0.
    const Points x = points_of(c);
    int in_contact = 0;
    for (int side = 0; side < 2; ++side) {
      for (int k = 0; k < 4; ++k) {
        const Sample smp = sample<4>(x, side, k);
        const double length = side == 0 ? c.term.rest_length_a : c.term.rest_length_b;
        const double gap = std::max(0.0, kReach - smp.distance);
        EXPECT_NEAR(r(4 * side + k), std::sqrt(smp.weight * length * c.term.stiffness / 2.0) * gap,
                    1e-13 * r.norm());
        in_contact += gap > 0.0;
      }
    }
    EXPECT_GT(in_contact, 0);
    const fd::VectorFunction F = fd::residual_of(c.term);
    EXPECT_TRUE(fd::check_vector_jacobian(F, c.q, dofs_of(c.term), J));
  }
}

TEST(EdgeContact, InternalForcesBalance) {
  // V depends on relative positions only, invariant under rotation about the origin:
  //   Σ_i g_i = 0,   Σ_i x_i × g_i = 0,
  // and, differentiated once more, the Hessian is zero along translations, H (v, v, v, v) = 0,
  // and along rotations it turns the gradient with them: (H (ω × x_j)_j)_i = ω × g_i.
  // The points are put up to 3 m from the origin so that the torques' lever arms matter.
  std::mt19937 rng(65);
  for (int trial = 0; trial < 20; ++trial) {
    Pair<4> c = random_pair(rng);
    const Vector3 shift = fd::random_vector(rng, 3.0);
    for (int n : c.term.nodes) c.q.points[n] += shift;
    const Points x = points_of(c);
    LocalGradient<4> g;
    LocalHessian<4> H;
    c.term.evaluate(c.q, &g, &H);
    double lever = 0.0;
    for (const Vector3& p : x) lever = std::max(lever, p.norm());
    Vector3 force = Vector3::Zero(), torque = Vector3::Zero();
    for (int i = 0; i < 4; ++i) {
      force += g.segment<3>(3 * i);
      torque += x[i].cross(Vector3(g.segment<3>(3 * i)));
    }
    EXPECT_LT(force.norm(), 1e-13 * g.norm());
    EXPECT_LT(torque.norm(), 1e-13 * g.norm() * lever);
    EXPECT_GT(g.norm(), 1.0);
    for (int axis = 0; axis < 3; ++axis) {
      LocalGradient<4> translation, rotation, turned;
      const Vector3 omega = Vector3::Unit(axis);
      for (int i = 0; i < 4; ++i) {
        translation.segment<3>(3 * i) = omega;
        rotation.segment<3>(3 * i) = omega.cross(x[i]);
        turned.segment<3>(3 * i) = omega.cross(Vector3(g.segment<3>(3 * i)));
      }
      EXPECT_LT((H * translation).norm(), 1e-13 * H.norm());
      EXPECT_LT((H * rotation - turned).norm(), 1e-13 * H.norm() * lever);
    }
  }
}

TEST(EdgeContact, IsSymmetricInTheTwoEdges) {
  std::mt19937 rng(66);
  for (int trial = 0; trial < 20; ++trial) {
    const Pair<4> c = random_pair(rng);
    Pair<4> swapped = c;
    swapped.term.nodes = {c.term.nodes[2], c.term.nodes[3], c.term.nodes[0], c.term.nodes[1]};
    swapped.term.offsets = {c.term.offsets[2], c.term.offsets[3], c.term.offsets[0], c.term.offsets[1]};
    std::swap(swapped.term.radius_a, swapped.term.radius_b);
    std::swap(swapped.term.rest_length_a, swapped.term.rest_length_b);
    LocalGradient<4> g, gs;
    LocalHessian<4> H, Hs;
    const double value = c.term.evaluate(c.q, &g, &H);
    // The two edges' halves are summed separately and added last, and ρ_a + ρ_b = ρ_b + ρ_a:
    // the same operations on the same numbers, so the value is the same to the last bit.
    EXPECT_EQ(swapped.term.evaluate(swapped.q, &gs, &Hs), value);
    // The derivatives are the same with the blocks swapped (summed in another order).
    Eigen::PermutationMatrix<12> swap_blocks;
    swap_blocks.indices() << 6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 5;
    EXPECT_LT((swap_blocks * gs - g).norm(), 1e-14 * g.norm());
    EXPECT_LT((swap_blocks * Hs * swap_blocks.transpose() - H).norm(), 1e-14 * H.norm());
    // Reversing an edge's direction mirrors its samples (the rule is symmetric about ½).
    Pair<4> reversed = c;
    std::swap(reversed.term.nodes[0], reversed.term.nodes[1]);
    EXPECT_NEAR(reversed.term.evaluate(reversed.q, nullptr, nullptr), value, 1e-13 * value);
  }
}

// One side of a switch of the Hessian, with the test's steps (see its comment).
template <int N>
::testing::AssertionResult check_near_switch(const Pair<N>& c, double distance) {
  fd::TermCheckOptions o;
  o.hessian_from_value.step = 0.1 * distance;
  return check(c, 0.5 * distance, o);
}

TEST(EdgeContact, ProjectionReachingAnEndIsC1WithAHessianJump) {
  // a = [0, 1] along x, b = [x_b, x_b + 1.3] 0.15 beside it, x_b = s₁ − τ with s₁ a's second
  // sample: that sample projects onto b at t̂ = τ/1.3 — inside b for τ > 0, beyond b0 (t = 0)
  // for τ < 0. Every other sample is ≥ 0.03 from a switch. At τ = ±2e-4 the first
  // differences (step 1e-6) and the value's second differences (step 2e-5, moving the
  // switch by ≤ 2 · 2e-5 · 1.15, a quarter of τ) stay on one side: both sides' derivatives
  // are exact. Across it the gradient is continuous and the Hessian jumps by the sample's
  // −(ψ'/d) u uᵀ (edge_contact.hpp), found here to O(τ/d).
  std::mt19937 rng(67);
  const double tau = 2e-4, h = 0.15, k = 1e4;
  const double s1 = gauss_legendre(4).nodes[1];
  const Matrix3 R = fd::rotation_at(0.9, rng);
  const Vector3 T = fd::random_vector(rng, 1.0);
  const auto posed = [&](double shift) {
    Points x = parallel(s1 - shift, 1.3, h);
    for (Vector3& p : x) p = R * p + T;
    return edge_pair(x, k);
  };
  const Pair<4> inside = posed(tau), beyond = posed(-tau);
  EXPECT_TRUE(check_near_switch(inside, tau));
  EXPECT_TRUE(check_near_switch(beyond, tau));
  // The jump at τ = 0: t = 0, w = p − b0 = −h ŷ (turned), d = h, e = 1.3 x̂.
  const Pair<4> at = posed(0.0);
  const Points x = points_of(at);
  const double c_k = 0.5 * gauss_legendre(4).weights[1] * at.term.rest_length_a * k;
  const double lateral = -c_k * (kReach - h) / h;  // ψ'/d
  const Vector3 w = (1.0 - s1) * x[0] + s1 * x[1] - x[2], e = x[3] - x[2];
  const std::array<double, 4> alpha = {1.0 - s1, s1, -1.0, 0.0}, beta = {0.0, 0.0, -1.0, 1.0};
  LocalHessian<4> jump;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const Vector3 ui = (alpha[i] * e + beta[i] * w) / e.norm();
      const Vector3 uj = (alpha[j] * e + beta[j] * w) / e.norm();
      jump.block<3, 3>(3 * i, 3 * j) = -lateral * ui * uj.transpose();
    }
  }
  const LocalHessian<4> H_in = hessian(inside), H_out = hessian(beyond);
  EXPECT_GT(jump.norm(), 0.05 * H_in.norm());  // a jump worth testing
  EXPECT_LT((H_in - H_out - jump).norm(), 0.01 * jump.norm());
  // C¹: the gradient moves only by the Hessian times the displacement (b's ends by 2τ, with
  // a factor 2 for the Hessian's change between them), a few % of the gradient: a jump of
  // the gradient that size would be seen.
  const double bound = 2.0 * H_in.norm() * std::sqrt(2.0) * 2.0 * tau;
  EXPECT_LE((gradient(inside) - gradient(beyond)).norm(), bound);
  EXPECT_LT(bound, 0.05 * gradient(inside).norm());
}

TEST(EdgeContact, GapReachingZeroIsC1WithAHessianJump) {
  // Crossing at right angles in a plane: a = [−0.5, 0.5] along x, b along y at x_b =
  // x₂ − (δ ∓ τ) with x₂ a's third sample, which is then at distance δ ∓ τ from b: in
  // contact by τ, or out of reach by τ. Every other sample is ≥ 0.02 from a switch. Steps as
  // in the test above (the gap moves at a rate ≤ 1 with each node). Across the switch the
  // gradient is continuous (it vanishes with the gap) and the Hessian jumps by the sample's
  // ψ'' α αᵀ ⊗ n nᵀ = c k α αᵀ ⊗ x̂ x̂ᵀ.
  std::mt19937 rng(68);
  const double tau = 2e-4, k = 1e4;
  const double x2 = -0.5 + gauss_legendre(4).nodes[2];
  const Matrix3 R = fd::rotation_at(2.1, rng);
  const Vector3 T = fd::random_vector(rng, 1.0);
  const auto posed = [&](double distance) {
    const double xb = x2 - distance;
    Points x = {Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(xb, -0.45, 0), Vector3(xb, 0.55, 0)};
    for (Vector3& p : x) p = R * p + T;
    return edge_pair(x, k);
  };
  const Pair<4> touching = posed(kReach - tau), apart = posed(kReach + tau);
  EXPECT_TRUE(check_near_switch(touching, tau));
  EXPECT_TRUE(check_near_switch(apart, tau));
  const double s2 = gauss_legendre(4).nodes[2];
  const double t = 0.45;  // the sample projects onto b at y = 0
  const double c_k = 0.5 * gauss_legendre(4).weights[2] * touching.term.rest_length_a * k;
  const std::array<double, 4> alpha = {1.0 - s2, s2, -(1.0 - t), -t};
  const Vector3 n = R * Vector3::UnitX();
  LocalHessian<4> jump;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) jump.block<3, 3>(3 * i, 3 * j) = c_k * alpha[i] * alpha[j] * n * n.transpose();
  }
  const LocalHessian<4> H_in = hessian(touching), H_out = hessian(apart);
  EXPECT_GT(jump.norm(), 0.05 * H_in.norm());
  EXPECT_LT((H_in - H_out - jump).norm(), 0.01 * jump.norm());
  // The displacement between the two is 2τ for each of b's ends; other samples are in
  // contact on both sides, so the gradient is not small beside the bound.
  const double bound = 2.0 * H_in.norm() * std::sqrt(2.0) * 2.0 * tau;
  EXPECT_LE((gradient(touching) - gradient(apart)).norm(), bound);
  EXPECT_LT(bound, 0.05 * gradient(apart).norm());
}

// ---------------------------------------------------------------------------------------
// Friction between the edges (EdgeFriction).

template <class Term>
struct LaggedEdgePair {
  Term term;
  State previous, q;
};
using FrictionPair = LaggedEdgePair<EdgeFriction>;
using DampingPair = LaggedEdgePair<EdgeDamping>;

// The sliding-regime slip y_q = ‖P W_q‖ of every sample with a lagged normal force, from the
// header's definitions (W = Σ_i α_i(t̄) x_i − ŵ).
std::vector<double> slips(const FrictionPair& f) {
  std::vector<double> out;
  const QuadratureRule& rule = gauss_legendre(4);
  std::array<Vector3, 4> x;
  for (int i = 0; i < 4; ++i) x[i] = f.q.points[f.term.nodes[i]];
  for (int side = 0; side < 2; ++side) {
    for (int k = 0; k < 4; ++k) {
      const LaggedEdgeSample& l = f.term.lagged[4 * side + k];
      if (l.normal_force == 0.0) continue;
      const double s = rule.nodes[k];
      const Vector3 sample = side == 0 ? Vector3((1.0 - s) * x[0] + s * x[1]) : Vector3((1.0 - s) * x[2] + s * x[3]);
      const Vector3 touched = side == 0 ? Vector3((1.0 - l.t) * x[2] + l.t * x[3]) : Vector3((1.0 - l.t) * x[0] + l.t * x[1]);
      const Vector3 W = sample - touched - l.separation;
      out.push_back((W - l.normal.dot(W) * l.normal).norm());
    }
  }
  return out;
}

// c's contact lagged at its state (q_{k−1}) under the laws `law` (a's samples', b's); then the
// four nodes carried by a small rigid motion (which alone makes each sample slip a little,
// its lagged normal staying put), and a's two nodes moved by `slip` ⟂ the first touching
// sample's normal and `normal_move` along it.
template <class Term, class Law>
LaggedEdgePair<Term> lagged_edge_pair(const Pair<4>& c, double slip, const std::array<Law, 2>& law, std::mt19937& rng,
                                      double turn_angle = 0.02, double normal_move = 1e-3) {
  LaggedEdgePair<Term> f;
  static_cast<EdgeEdgeSample&>(f.term) = c.term;
  f.term.law = law;
  f.previous = c.q;
  f.term.begin_step(f.previous, Step{});
  Vector3 n = Vector3::UnitZ();
  for (const LaggedEdgeSample& l : f.term.lagged) {
    if (l.normal_force > 0.0) {
      n = l.normal;
      break;
    }
  }
  f.q = f.previous;
  const Matrix3 turn = so3::exp(turn_angle * fd::random_unit(rng));
  const Vector3 centre = f.previous.points[c.term.nodes[0]];
  const Vector3 shift = fd::random_vector(rng, 0.05 * turn_angle / 0.02);
  for (int node : c.term.nodes) f.q.points[node] = centre + turn * (f.previous.points[node] - centre) + shift;
  const Vector3 move = slip * fd::random_perpendicular(n, rng) + normal_move * n;
  for (int i : {0, 1}) f.q.points[c.term.nodes[i]] += move;
  return f;
}

// μ 0.4 for a's samples and 0.25 for b's.
FrictionPair friction_pair(const Pair<4>& c, double slip, double epsilon, std::mt19937& rng,
                           double turn_angle = 0.02, double normal_move = 1e-3) {
  return lagged_edge_pair<EdgeFriction>(c, slip, std::array{SlipFriction{0.4, epsilon}, SlipFriction{0.25, epsilon}},
                                        rng, turn_angle, normal_move);
}

// friction_pair on `c`, drawn again until every touching sample's slip is on the side of the
// switch y = ε that `slip` is, 2 % clear of it.
FrictionPair clear_of_switch(const Pair<4>& c, double slip, double epsilon, std::mt19937& rng) {
  for (int attempt = 0; attempt < 200; ++attempt) {
    const FrictionPair f = friction_pair(c, slip, epsilon, rng);
    const std::vector<double> y = slips(f);
    if (!y.empty() && std::all_of(y.begin(), y.end(), [&](double yq) {
          return (yq < epsilon) == (slip < epsilon) && std::abs(yq - epsilon) > 0.02 * epsilon;
        })) {
      return f;
    }
  }
  ADD_FAILURE() << "no placement clear of the switch";
  return friction_pair(c, slip, epsilon, rng);
}

// The configurations of the contact tests above, each ≥ 1e-3 from a switch of the lagged
// projection (the mixed block's FD moves q_{k−1}).
std::vector<std::pair<std::string, Pair<4>>> friction_configurations(std::mt19937& rng) {
  std::vector<std::pair<std::string, Pair<4>>> out;
  out.push_back({"parallel", edge_pair(moved(parallel(0.3, 1.3, 0.15), rng))});
  out.push_back({"collinear end to end", edge_pair(moved({Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(1.05, 0, 0),
                                                          Vector3(2.05, 0, 0)},
                                                         rng))});
  const Vector3 b0(1.04, 0.03, 0.04);
  const double angle = 2.0 * std::numbers::pi / 3.0;
  out.push_back({"touching at the ends at an angle",
                 edge_pair(moved({Vector3(0, 0, 0), Vector3(1, 0, 0), b0,
                                  b0 + 0.9 * Vector3(std::cos(angle), std::sin(angle), 0.0)},
                                 rng))});
  out.push_back({"crossing at right angles",
                 edge_pair(moved({Vector3(-0.5, 0, 0), Vector3(0.5, 0, 0), Vector3(0.1, -0.45, 0.1),
                                  Vector3(0.1, 0.55, 0.1)},
                                 rng))});
  for (int i = 0; i < 4; ++i) out.push_back({"random", random_pair(rng)});
  for (const auto& [name, c] : out) {
    EXPECT_GE(switch_margin(c), 1e-3) << name;
  }
  return out;
}

// fd::stick_zone's steps. Only some block need be non-zero: a node whose weights α vanish at
// a sample's clamped projection gets no force from it.
fd::TermCheckOptions friction_options() {
  fd::TermCheckOptions options = fd::stick_zone();
  options.gradient.require_nonzero = fd::NonZero::kAny;
  options.hessian.require_nonzero = fd::NonZero::kAny;
  return options;
}

TEST(EdgeFriction, DerivativesInStickAndSlipMatchFiniteDifferences) {
  std::mt19937 rng(70);
  const double epsilon = 1e-2;
  int checked = 0;
  for (const auto& [name, c] : friction_configurations(rng)) {
    // Deep in the stick regime, near the switch on both sides, and sliding.
    for (const double slip : {0.3 * epsilon, 0.9 * epsilon, 1.1 * epsilon, 20.0 * epsilon}) {
      SCOPED_TRACE(name + trace(", slip", slip));
      const FrictionPair f = clear_of_switch(c, slip, epsilon, rng);
      EXPECT_TRUE(fd::check_term(f.term, f.q, dofs_of(f.term), friction_options()));
      // The Hessian is positive semi-definite (header).
      LocalHessian<4> H;
      f.term.evaluate(f.q, nullptr, &H);
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<LocalHessian<4>>(H).eigenvalues().minCoeff(), -1e-12 * H.norm());
      ++checked;
    }
  }
  EXPECT_EQ(checked, 8 * 4);
}

TEST(EdgeFriction, TinyAndHugeStiffnessesAndTimeSteps) {
  std::mt19937 rng(71);
  // k from 1e-3 to 1e9 at ε = 1e-2: λ scales the term, the checks are relative.
  for (const double k : {1e-3, 1e9}) {
    Pair<4> c = random_pair(rng);
    c.term.stiffness = k;
    for (const double slip : {0.3e-2, 0.2}) {
      SCOPED_TRACE(trace("k, slip", k, slip));
      const FrictionPair f = clear_of_switch(c, slip, 1e-2, rng);
      EXPECT_TRUE(fd::check_term(f.term, f.q, dofs_of(f.term), friction_options()));
    }
  }
  // ε = ε_v h for h from 1e-6 to 1 s at ε_v = 1e-3 m/s: parallel edges side by side (every
  // sample's normal the same, so a's slip is every sample's) scaled to 50 ε (a power of two
  // near it, so that the scaling is exact) so that the state's round-off stays far below FD
  // steps that fit in the quadratic zone (fd::within_zone).
  for (const double h : {1e-6, 1e-3, 1.0}) {
    const double epsilon = 1e-3 * h;
    const double scale = fd::power_of_two_near(50.0 * epsilon);
    Pair<4> c = edge_pair(moved(parallel(0.0, 1.0, 0.15), rng));
    for (Vector3& p : c.q.points) p *= scale;
    c.term.radius_a *= scale;
    c.term.radius_b *= scale;
    c.term.rest_length_a *= scale;
    c.term.rest_length_b *= scale;
    for (const double factor : {0.5, 3.0}) {
      SCOPED_TRACE(trace("h, slip/ε", h, factor));
      FrictionPair f = friction_pair(c, factor * epsilon, epsilon, rng, 0.0, 0.0);
      const std::vector<double> y = slips(f);
      ASSERT_FALSE(y.empty());
      for (double yq : y) ASSERT_NEAR(yq, factor * epsilon, 1e-9 * epsilon);  // a's nodes slip, b's stay
      EXPECT_TRUE(fd::check_term(f.term, f.q, dofs_of(f.term), fd::within_zone(epsilon)));
    }
  }
}

TEST(EdgeFriction, SlidingForceIsMuLambdaAgainstTheSlipOnEachSideAndEqualAndOpposite) {
  // Equal parallel edges 0.15 apart, fully overlapping: every sample has gap γ = 0.05 and the
  // same normal, so Σ_q λ_q = ½ ℓ̄ k γ per side. a slides along its length by 20 ε relative to b
  // (sliding: f₁ = 1), so the force on a is μ_a ½ ℓ̄_a k γ + μ_b ½ ℓ̄_b k γ against its slip
  // (a's samples with a's μ, b's with b's), and b feels the opposite.
  std::mt19937 rng(72);
  const double epsilon = 1e-3, k = 1e4, gap = kReach - 0.15;
  Pair<4> c = edge_pair(moved(parallel(0.0, 1.0, 0.15), rng), k);
  c.term.rest_length_a = 0.8;
  c.term.rest_length_b = 1.2;
  FrictionPair f = friction_pair(c, 0.0, epsilon, rng, 0.0, 0.0);
  const Vector3 along = (f.q.points[c.term.nodes[1]] - f.q.points[c.term.nodes[0]]).normalized();
  for (int i : {0, 1}) f.q.points[c.term.nodes[i]] += 20.0 * epsilon * along;
  LocalGradient<4> g;
  f.term.evaluate(f.q, &g, nullptr);
  const Vector3 on_a = -(g.segment<3>(0) + g.segment<3>(3));
  const Vector3 on_b = -(g.segment<3>(6) + g.segment<3>(9));
  const double expected = 0.4 * 0.5 * 0.8 * k * gap + 0.25 * 0.5 * 1.2 * k * gap;
  EXPECT_TRUE(on_a.isApprox(-expected * along, 1e-12)) << on_a.transpose();
  EXPECT_LT((on_a + on_b).norm(), 1e-12 * expected);
  // Without μ on b's side, only a's samples rub.
  f.term.law[1].coefficient = 0.0;
  f.term.evaluate(f.q, &g, nullptr);
  EXPECT_TRUE((-(g.segment<3>(0) + g.segment<3>(3))).isApprox(-0.4 * 0.5 * 0.8 * k * gap * along, 1e-12));
}

TEST(EdgeFriction, NoLaggedContactNoFrictionAndNoneOnTheAxis) {
  std::mt19937 rng(73);
  // Apart at q_{k−1}: nothing, whatever q_k.
  const Pair<4> apart = edge_pair(moved(parallel(0.0, 1.0, 0.5), rng));
  // One edge on the other (exact coordinates, not moved: a rigid motion's round-off would put
  // the samples 1e-16 off the axis, with a normal of noise): every sample lies on the other
  // segment's axis (d̂ = 0), where the lagged normal is undefined and the header gives λ = 0.
  const Pair<4> on_axis = edge_pair(parallel(0.0, 1.0, 0.0));
  for (const Pair<4>* c : {&apart, &on_axis}) {
    const FrictionPair f = friction_pair(*c, 0.05, 1e-3, rng);
    for (const LaggedEdgeSample& l : f.term.lagged) EXPECT_EQ(l.normal_force, 0.0);
    LocalGradient<4> g;
    LocalHessian<4> H;
    EXPECT_EQ(f.term.evaluate(f.q, &g, &H), 0.0);
    EXPECT_TRUE(g.isZero(0.0));
    EXPECT_TRUE(H.isZero(0.0));
    EXPECT_TRUE(f.term.previous_jacobian(f.q, f.previous).isZero(0.0));
    EdgeFriction::Residual r;
    EdgeFriction::ResidualJacobian J;
    f.term.residual(f.q, r, &J);
    EXPECT_EQ(r(0), 0.0);
    EXPECT_TRUE(J.isZero(0.0));
  }
}

TEST(EdgeFriction, ResidualFormReproducesValueAndGradient) {
  std::mt19937 rng(74);
  for (const auto& [name, c] : friction_configurations(rng)) {
    for (const double slip : {0.3e-2, 5e-2}) {
      SCOPED_TRACE(name + trace(", slip", slip));
      const FrictionPair f = clear_of_switch(c, slip, 1e-2, rng);
      LocalGradient<4> g;
      const double D = f.term.evaluate(f.q, &g, nullptr);
      EdgeFriction::Residual r;
      EdgeFriction::ResidualJacobian J;
      f.term.residual(f.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * D);
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12));
      const fd::VectorFunction F = fd::residual_of(f.term);
      fd::FdOptions o;
      o.require_nonzero = fd::NonZero::kAny;
      EXPECT_TRUE(fd::check_vector_jacobian(F, f.q, dofs_of(f.term), J, o));
    }
  }
}

TEST(EdgeFriction, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  // C(q; q_{k−1}): the local gradient at the fixed current state as a function of the four
  // nodes' previous positions, through every sample's t̄, ŵ, λ and n (begin_step re-run at
  // every perturbed q_{k−1}).
  std::mt19937 rng(75);
  int checked = 0;
  for (const auto& [name, c] : friction_configurations(rng)) {
    for (const double slip : {0.3e-2, 5e-2}) {
      SCOPED_TRACE(name + trace(", slip", slip));
      const FrictionPair f = clear_of_switch(c, slip, 1e-2, rng);
      const fd::VectorFunction C = fd::lagged_gradient(f.term, f.q);
      const Eigen::MatrixXd J = f.term.previous_jacobian(f.q, f.previous);
      fd::FdOptions o;
      o.step = 2e-7;  // the stick zone's truncation, as in the derivatives' test
      o.require_nonzero = fd::NonZero::kAny;
      EXPECT_TRUE(fd::check_vector_jacobian(C, f.previous, dofs_of(f.term), J, o));
      // Mutations a wrong mapping would make: a's two columns swapped, b's previous motion
      // ignored. The check must see both.
      Eigen::MatrixXd swapped = J;
      swapped.middleCols<3>(0) = J.middleCols<3>(3);
      swapped.middleCols<3>(3) = J.middleCols<3>(0);
      Eigen::MatrixXd still_b = J;
      still_b.rightCols<6>().setZero();
      EXPECT_FALSE(fd::check_vector_jacobian(C, f.previous, dofs_of(f.term), swapped, o));
      EXPECT_FALSE(fd::check_vector_jacobian(C, f.previous, dofs_of(f.term), still_b, o));
      // add_step_adjoint puts (∂C/∂q̂)ᵀ z at the four nodes' entries of the whole-state layout.
      const LocalGradient<4> z = LocalGradient<4>::Random();
      Eigen::VectorXd a = Eigen::VectorXd::Zero(tangent_size(f.q)), da = a;
      f.term.add_step_adjoint(f.q, f.previous, Step{}, z, a, da);
      const LocalGradient<4> expected = J.transpose() * z;
      for (int b = 0; b < 4; ++b) {
        EXPECT_TRUE(a.segment<3>(tangent_point(f.term.nodes[b])).isApprox(expected.segment<3>(3 * b), 1e-14));
      }
      EXPECT_TRUE(da.isZero(0.0));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 8 * 2);
}

// ---------------------------------------------------------------------------------------
// Damping between the edges (EdgeDamping: the dashpot law of lib/dissipation_law.hpp per
// sample, on the same relative displacement W as friction).

// τ = 3 ms for a's samples and 1 ms for b's (c = τ k), h = 1 ms unless given.
DampingPair damping_pair(const Pair<4>& c, std::mt19937& rng, double normal_move = -1e-3, double h = 1e-3,
                         double scale = 1.0) {
  return lagged_edge_pair<EdgeDamping>(c, 0.01, std::array{NormalDashpot{3e-3 * scale, h}, NormalDashpot{1e-3 * scale, h}},
                                       rng, 0.02, normal_move);
}

TEST(EdgeDamping, DerivativesMatchFiniteDifferencesInEveryConfiguration) {
  // Parallel, collinear end to end, touching at the ends at an angle, crossing, random;
  // approaching and receding.
  std::mt19937 rng(170);
  int checked = 0;
  fd::TermCheckOptions options;
  options.gradient.require_nonzero = fd::NonZero::kAny;
  options.hessian.require_nonzero = fd::NonZero::kAny;
  for (const auto& [name, c] : friction_configurations(rng)) {
    for (const double normal_move : {-1e-3, 2e-3}) {
      SCOPED_TRACE(name + trace(", normal move", normal_move));
      const DampingPair f = damping_pair(c, rng, normal_move);
      EXPECT_TRUE(fd::check_term(f.term, f.q, dofs_of(f.term), options));
      // The Hessian Σ α_i α_j r n nᵀ is positive semi-definite.
      LocalHessian<4> H;
      f.term.evaluate(f.q, nullptr, &H);
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<LocalHessian<4>>(H).eigenvalues().minCoeff(), -1e-12 * H.norm());
      ++checked;
    }
  }
  EXPECT_EQ(checked, 8 * 2);
}

TEST(EdgeDamping, ParallelEdgesApproachingFeelBothSidesDashpotsEqualAndOpposite) {
  // Equal parallel edges 0.15 apart, fully overlapping, a moved δ = 1 mm towards b: every
  // sample's normal is the same and its W has n·W = δ, so with Σ_q w_q = 1 the force on a is
  // (τ_a ½ ℓ̄_a + τ_b ½ ℓ̄_b) k δ/h away from b (each side's samples with its own τ), and b
  // feels the opposite.
  std::mt19937 rng(171);
  const double k = 1e4, delta = 1e-3, h = 1e-3;
  Pair<4> c = edge_pair(moved(parallel(0.0, 1.0, 0.15), rng), k);
  c.term.rest_length_a = 0.8;
  c.term.rest_length_b = 1.2;
  DampingPair f = lagged_edge_pair<EdgeDamping>(c, 0.0, std::array{NormalDashpot{3e-3, h}, NormalDashpot{1e-3, h}}, rng,
                                                0.0, 0.0);
  const Vector3 n = f.term.lagged[0].normal;  // from b's axis to a's sample
  for (int i : {0, 1}) f.q.points[c.term.nodes[i]] -= delta * n;
  LocalGradient<4> g;
  f.term.evaluate(f.q, &g, nullptr);
  const Vector3 on_a = -(g.segment<3>(0) + g.segment<3>(3));
  const Vector3 on_b = -(g.segment<3>(6) + g.segment<3>(9));
  const double expected = (3e-3 * 0.5 * 0.8 + 1e-3 * 0.5 * 1.2) * k * delta / h;
  EXPECT_TRUE(on_a.isApprox(expected * n, 1e-12)) << on_a.transpose();
  EXPECT_LT((on_a + on_b).norm(), 1e-12 * expected);
  // Sliding along each other (n·W = 0) costs nothing: the dashpot is normal only.
  f.q = f.previous;
  const Vector3 along = (f.q.points[c.term.nodes[1]] - f.q.points[c.term.nodes[0]]).normalized();
  for (int i : {0, 1}) f.q.points[c.term.nodes[i]] += 0.05 * along;
  EXPECT_NEAR(f.term.evaluate(f.q, &g, nullptr), 0.0, 1e-18);
  EXPECT_LT(g.norm(), 1e-12 * expected);
}

TEST(EdgeDamping, NoLaggedContactNoDampingAndNoneOnTheAxis) {
  std::mt19937 rng(172);
  const Pair<4> apart = edge_pair(moved(parallel(0.0, 1.0, 0.5), rng));
  const Pair<4> on_axis = edge_pair(parallel(0.0, 1.0, 0.0));
  for (const Pair<4>* c : {&apart, &on_axis}) {
    const DampingPair f = damping_pair(*c, rng);
    for (const LaggedEdgeSample& l : f.term.lagged) EXPECT_EQ(l.normal_force, 0.0);
    LocalGradient<4> g;
    LocalHessian<4> H;
    EXPECT_EQ(f.term.evaluate(f.q, &g, &H), 0.0);
    EXPECT_TRUE(g.isZero(0.0));
    EXPECT_TRUE(H.isZero(0.0));
    EXPECT_TRUE(f.term.previous_jacobian(f.q, f.previous).isZero(0.0));
    EdgeDamping::Residual r;
    EdgeDamping::ResidualJacobian J;
    f.term.residual(f.q, r, &J);
    EXPECT_TRUE(r.isZero(0.0));
    EXPECT_TRUE(J.isZero(0.0));
  }
}

TEST(EdgeDamping, ResidualFormHasOneResidualPerSample) {
  std::mt19937 rng(173);
  static_assert(EdgeDamping::kResiduals == 8);
  for (const auto& [name, c] : friction_configurations(rng)) {
    SCOPED_TRACE(name);
    const DampingPair f = damping_pair(c, rng);
    LocalGradient<4> g;
    const double D = f.term.evaluate(f.q, &g, nullptr);
    EdgeDamping::Residual r;
    EdgeDamping::ResidualJacobian J;
    f.term.residual(f.q, r, &J);
    EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * D);
    EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12));
    fd::FdOptions o;
    o.require_nonzero = fd::NonZero::kAny;
    EXPECT_TRUE(fd::check_vector_jacobian(fd::residual_of(f.term), f.q, dofs_of(f.term), J, o));
  }
}

TEST(EdgeDamping, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  // Through every sample's t̄, ŵ and n at q_{k−1}, in every configuration, and at tiny and huge
  // time steps and dampings (D is quadratic in the state for any τ/h: relative checks).
  std::mt19937 rng(174);
  int checked = 0;
  fd::FdOptions o;
  o.require_nonzero = fd::NonZero::kAny;
  for (const auto& [name, c] : friction_configurations(rng)) {
    SCOPED_TRACE(name);
    const DampingPair f = damping_pair(c, rng);
    const Eigen::MatrixXd J = f.term.previous_jacobian(f.q, f.previous);
    EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(f.term, f.q), f.previous, dofs_of(f.term), J, o));
    Eigen::MatrixXd still_b = J;
    still_b.rightCols<6>().setZero();
    EXPECT_FALSE(fd::check_vector_jacobian(fd::lagged_gradient(f.term, f.q), f.previous, dofs_of(f.term), still_b, o));
    ++checked;
  }
  EXPECT_EQ(checked, 8);
  const Pair<4> c = edge_pair(moved(parallel(0.3, 1.3, 0.15), rng));
  for (const double h : {1e-6, 1e-3, 1.0}) {
    for (const double scale : {1e-6, 1.0, 1e3}) {
      SCOPED_TRACE(trace("h, τ scale", h, scale));
      const DampingPair f = damping_pair(c, rng, -1e-3, h, scale);
      EXPECT_TRUE(fd::check_term(f.term, f.q, dofs_of(f.term), fd::TermCheckOptions{}));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(f.term, f.q), f.previous, dofs_of(f.term),
                                            f.term.previous_jacobian(f.q, f.previous), o));
    }
  }
}

}  // namespace
}  // namespace liedyn::edge_contact_tests

// Signed distance fields (lib/sdf.hpp): gradient and Hessian against finite differences in
// every region of every shape, with and without `inside`, at random collider poses; exact
// values at hand-computed points; continuity across region boundaries; the documented
// choices at non-differentiable points; accuracy far away and very close to the surface;
// validate(); catmull_rom_polyline.
//
// Finite differences (tests/fd_check.hpp, one point DOF, defaults): ε = 1e-6, rtol = 1e-6,
// floor = 1e-9 × (largest entry), plus the computed round-off floor 16 eps·max|f|/ε ≈ 4e-9
// for the unit gradient. Test points keep
//   * ≥ kCoreMargin = 1e-2 from the core sets (sphere centre, segments, polyline) where ∇²φ
//     grows as 1/d: the FD truncation ε²/6·|∂⁴φ| ~ ε²/d³ is then ≤ 1e-6, i.e. ≤ 1e-8 relative
//     to |∇²φ| ~ 1/d (and ~ε²/d² ≤ 1e-8 for the gradient), far inside rtol;
//   * ≥ kSeamMargin = 1e-3 from the sets where ∇²φ jumps (box planes q_i = 0, capsule and
//     tube end planes) or ∇φ is not unique (box and tube medial sets): 1000 FD steps, so no
//     difference straddles them.
// Both margins are computed by the test's own reference geometry (Probe below), not by the
// code under test. Where ∇²φ = 0 by construction (plane, box near a face or inside) the
// Hessian check does not require a non-zero Hessian (it compares the FD of a constant
// gradient with exactly 0: still a check); the gradient check always requires ∇φ ≠ 0.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <variant>
#include <vector>

#include "fd_check.hpp"
#include "lib/model.hpp"
#include "lib/sdf.hpp"
#include "lib/so3.hpp"

namespace liedyn::sdf_tests {
namespace {

using fd::random_unit;
using fd::random_vector;
using fd::rotation_at;
using fd::kEps;
using fd::kInf;

constexpr double kCoreMargin = 1e-2;
constexpr double kSeamMargin = 1e-3;

// ---------------------------------------------------------------------------------------
// Reference geometry, written independently of lib/sdf.cpp (literal formulas).

struct Probe {
  double distance = 0.0;  // φ_loc(x)
  std::string region;     // e.g. "edge/solid"
  bool zero_hessian = false;
  double core = kInf;  // distance to the set where φ is not differentiable
  double seam = kInf;  // distance to the sets where ∇²φ jumps or ∇φ is not unique (lower bound)
};

std::string with_side(const std::string& region, double distance) {
  return region + (distance < 0.0 ? "/solid" : "/free");
}

Probe probe_plane(const Vector3& x) {
  Probe p;
  p.distance = x.z();
  p.region = with_side("half-space", p.distance);
  p.zero_hessian = true;
  return p;
}

Probe probe_sphere(const SphereShape& s, const Vector3& x) {
  Probe p;
  p.distance = x.norm() - s.radius;
  p.region = with_side("ball", p.distance);
  p.core = x.norm();
  return p;
}

Probe probe_box(const BoxShape& s, const Vector3& x) {
  const Vector3 b = (s.half_extents.array() - s.rounding).matrix();
  const Vector3 q = x.cwiseAbs() - b;
  Probe p;
  // Inigo Quilez: ‖max(q, 0)‖ + min(max q, 0) − r.
  p.distance = q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0) - s.rounding;
  const auto active = static_cast<int>((q.array() > 0.0).count());
  static const char* const kNames[] = {"inner", "face", "edge", "corner"};
  p.region = with_side(kNames[active], p.distance);
  p.zero_hessian = active <= 1;
  p.seam = q.cwiseAbs().minCoeff();  // the planes |x_i| = b_i
  if (active == 0) {
    // Medial sets: the two largest q_i tie, or x_k = 0 for the largest.
    Eigen::Index k = 0;
    const double first = q.maxCoeff(&k);
    double second = -kInf;
    for (int i = 0; i < 3; ++i) {
      if (i != k) second = std::max(second, q(i));
    }
    p.seam = std::min({p.seam, (first - second) / std::sqrt(2.0), std::abs(x(k))});
  }
  return p;
}

Probe probe_capsule(const CapsuleShape& s, const Vector3& x) {
  const double L = s.half_length;
  const Vector3 c(0.0, 0.0, std::clamp(x.z(), -L, L));
  Probe p;
  p.core = (x - c).norm();
  p.distance = p.core - s.radius;
  p.region = with_side(std::abs(x.z()) < L ? "side" : "cap", p.distance);
  p.seam = std::min(std::abs(x.z() - L), std::abs(x.z() + L));
  return p;
}

Probe probe_tube(const TubeShape& s, const Vector3& x) {
  const std::vector<Vector3>& v = s.polyline;
  const std::size_t m = v.size() - 1;  // segments
  std::vector<Vector3> nearest(m);
  std::vector<double> dist(m);
  Probe p;
  std::size_t best = 0;
  std::string kind;
  for (std::size_t j = 0; j < m; ++j) {
    const double l = (v[j + 1] - v[j]).norm();
    const Vector3 e = (v[j + 1] - v[j]) / l;
    const double t = (x - v[j]).dot(e);  // arc length along segment j
    nearest[j] = v[j] + std::clamp(t, 0.0, l) * e;
    dist[j] = (x - nearest[j]).norm();
    p.seam = std::min({p.seam, std::abs(t), std::abs(t - l)});  // all end planes (conservative)
    if (dist[j] < dist[best]) best = j;
    if (j == best) {
      const bool first_end = t <= 0.0 && j == 0, last_end = t >= l && j + 1 == m;
      kind = t > 0.0 && t < l ? "interior" : (first_end || last_end ? "end" : "joint");
    }
  }
  // Medial sets: another segment almost as near, at a different point.
  for (std::size_t j = 0; j < m; ++j) {
    if ((nearest[j] - nearest[best]).norm() > 1e-9) {
      p.seam = std::min(p.seam, dist[j] - dist[best]);
    }
  }
  p.core = dist[best];
  p.distance = p.core - s.radius;
  p.region = with_side(kind, p.distance);
  return p;
}

// Link (torus: L = 0): the planar distance s to the segment [−L, L] on the x axis, then the
// distance to the curve s = R in the half-plane through x and the z axis.
Probe probe_link(double L, double R, double r, const Vector3& x) {
  const double s = std::hypot(x.x() - std::clamp(x.x(), -L, L), x.y());
  const double D = std::hypot(s - R, x.z());
  Probe p;
  p.distance = D - r;
  p.region = with_side(
      std::string(std::abs(x.x()) < L ? "straight" : "arc") + (s < R ? "-hole" : "-outer"),
      p.distance);
  // ∇²φ grows as 1/D at the core curve; as 1/s at a torus's axis (a link's strip s = 0 is
  // where ∇φ jumps: kept as far).
  p.core = std::min(D, s);
  if (L > 0.0) p.seam = std::min(std::abs(x.x() - L), std::abs(x.x() + L));  // straight | arc
  return p;
}

// Cylinder: the rectangle (s, z) ∈ [0, ρ] × [−h, h] of the half-plane through x and the z axis.
Probe probe_cylinder(const CylinderShape& c, const Vector3& x) {
  const double s = std::hypot(x.x(), x.y());
  const Eigen::Vector2d q(s - c.radius, std::abs(x.z()) - c.half_length);
  Probe p;
  p.distance = q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  const bool rim = q.minCoeff() > 0.0, side = !rim && q(0) >= q(1);
  p.region = with_side(rim ? "rim" : (side ? "side" : "cap"), p.distance);
  p.zero_hessian = !rim && !side;
  p.core = std::min(s, std::hypot(q(0), q(1)));  // the axis, the rim
  if (q(1) > 0.0) p.seam = std::abs(q(0));       // s = ρ beyond a cap (cap | rim)
  if (q(0) > 0.0)
    p.seam = std::min(p.seam, std::abs(q(1)));  // |z| = h beside the side (side | rim)
  if (q.maxCoeff() <= 0.0) {  // inside: the cone q_1 = q_2, the disc z = 0 under the caps
    p.seam = std::min(p.seam, std::abs(q(0) - q(1)) / std::sqrt(2.0));
    if (!side) p.seam = std::min(p.seam, std::abs(x.z()));
  }
  return p;
}

Probe probe(const Shape& shape, const Vector3& x) {
  return std::visit(
      [&](const auto& s) -> Probe {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, PlaneShape>) return probe_plane(x);
        if constexpr (std::is_same_v<S, SphereShape>) return probe_sphere(s, x);
        if constexpr (std::is_same_v<S, BoxShape>) return probe_box(s, x);
        if constexpr (std::is_same_v<S, CapsuleShape>) return probe_capsule(s, x);
        if constexpr (std::is_same_v<S, TubeShape>) return probe_tube(s, x);
        if constexpr (std::is_same_v<S, TorusShape>) {
          return probe_link(0.0, s.major_radius, s.minor_radius, x);
        }
        if constexpr (std::is_same_v<S, CylinderShape>) return probe_cylinder(s, x);
        if constexpr (std::is_same_v<S, LinkShape>) {
          return probe_link(s.half_length, s.major_radius, s.minor_radius, x);
        }
        // Grid SDFs of meshes have their own suite (test_mesh_sdf.cpp).
        if constexpr (std::is_same_v<S, MeshShape>) throw std::logic_error("not an analytic shape");
      },
      shape);
}

// ---------------------------------------------------------------------------------------
// Shapes under test, with a proposal distribution of local points that reaches every region.

struct Fixture {
  std::string name;
  Shape shape;
  std::vector<std::string> regions;  // each must receive kPointsPerRegion accepted points
  std::function<Vector3(std::mt19937&)> propose;
};

double uniform(std::mt19937& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

// A point near a random vertex or segment point of the polyline.
Vector3 near_polyline(const std::vector<Vector3>& v, double reach, std::mt19937& rng) {
  const auto j = std::uniform_int_distribution<std::size_t>(0, v.size() - 2)(rng);
  const double t = uniform(rng, -0.3, 1.3);
  const Vector3 c = v[j] + std::clamp(t, 0.0, 1.0) * (v[j + 1] - v[j]);
  return c + uniform(rng, 0.0, reach) * random_unit(rng);
}

// A point on the convex side of the joint at a random interior vertex: the joint region
// (nearest point = the vertex) is a thin wedge where the polyline bends little.
Vector3 near_joint(const std::vector<Vector3>& v, double reach, std::mt19937& rng) {
  const auto j = std::uniform_int_distribution<std::size_t>(1, v.size() - 2)(rng);
  const Vector3 e1 = (v[j] - v[j - 1]).normalized(), e2 = (v[j + 1] - v[j]).normalized();
  const Vector3 out = (e1 - e2).normalized(), binormal = e1.cross(e2).normalized();
  return v[j] + uniform(rng, 0.0, reach) * (out + uniform(rng, -2.0, 2.0) * binormal).normalized();
}

std::vector<Vector3> curved_polyline() {
  std::vector<Vector3> control;
  for (int i = 0; i < 6; ++i) {
    const double a = 0.9 * i;
    control.emplace_back(std::cos(a), std::sin(a), 0.35 * i);  // a helix
  }
  return catmull_rom_polyline(control, 8);
}

// A point within `reach` of the stadium curve at distance R from [−L, L] (L = 0: a circle):
// half the time about an arc (past its ends, across the planes x = ±L), else beside a side.
Vector3 near_stadium(double L, double R, double reach, std::mt19937& rng) {
  const double side = std::bernoulli_distribution(0.5)(rng) ? 1.0 : -1.0;
  Vector3 c;
  if (L == 0.0 || std::bernoulli_distribution(0.5)(rng)) {
    const double theta = uniform(rng, -0.5 * std::numbers::pi - 0.3, 0.5 * std::numbers::pi + 0.3);
    c = Vector3(side * (L + R * std::cos(theta)), R * std::sin(theta), 0.0);
  } else {
    c = Vector3(uniform(rng, -L, L), side * R, 0.0);
  }
  return c + uniform(rng, 0.0, reach) * random_unit(rng);
}

std::vector<Fixture> fixtures() {
  std::vector<Fixture> out;
  out.push_back(
      {"plane", PlaneShape{}, {"half-space/free", "half-space/solid"}, [](std::mt19937& rng) {
         return random_vector(rng, 2.0);
       }});
  out.push_back({"sphere", SphereShape{0.7}, {"ball/free", "ball/solid"}, [](std::mt19937& rng) {
                   return random_vector(rng, 1.5);
                 }});
  const Vector3 h(0.5, 0.8, 1.1);
  out.push_back(
      {"sharp box",
       BoxShape{h, 0.0},
       {"inner/solid", "face/free", "edge/free", "corner/free"},
       [h](std::mt19937& rng) -> Vector3 { return h.cwiseProduct(random_vector(rng, 1.6)); }});
  const BoxShape rounded{h, 0.25};
  out.push_back({"rounded box",
                 rounded,
                 {"inner/solid", "face/solid", "face/free", "edge/solid", "edge/free",
                  "corner/solid", "corner/free"},
                 [rounded](std::mt19937& rng) -> Vector3 {
                   // Half uniform, half near the inner box's surface (edges and corners).
                   const Vector3 y = rounded.half_extents.cwiseProduct(random_vector(rng, 1.3));
                   if (std::bernoulli_distribution(0.5)(rng)) return y;
                   const Vector3 b = (rounded.half_extents.array() - rounded.rounding).matrix();
                   return y.cwiseMax(-b).cwiseMin(b) + uniform(rng, 0.0, 0.5) * random_unit(rng);
                 }});
  out.push_back({"capsule",
                 CapsuleShape{0.6, 0.3},
                 {"side/solid", "side/free", "cap/solid", "cap/free"},
                 [](std::mt19937& rng) -> Vector3 {
                   return Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1),
                                  uniform(rng, -1.5, 1.5));
                 }});
  const std::vector<Vector3> bent = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {0.2, 1.3, 1.4}};
  const std::vector<std::string> tube_regions = {"interior/solid", "interior/free", "joint/solid",
                                                 "joint/free",     "end/solid",     "end/free"};
  out.push_back({"bent tube", TubeShape{bent, 0.15}, tube_regions,
                 [bent](std::mt19937& rng) { return near_polyline(bent, 0.6, rng); }});
  const std::vector<Vector3> curved = curved_polyline();
  out.push_back({"curved tube", TubeShape{curved, 0.2}, tube_regions, [curved](std::mt19937& rng) {
                   return std::bernoulli_distribution(0.5)(rng) ? near_polyline(curved, 0.6, rng)
                                                                : near_joint(curved, 0.4, rng);
                 }});
  // Tori and links: both sides of the core curve (the hole and the outside), in and out of
  // the solid, about the arcs and beside the straight sides; far points now and then.
  const std::vector<std::string> arc_regions = {"arc-outer/solid", "arc-outer/free",
                                                "arc-hole/solid", "arc-hole/free"};
  out.push_back({"torus", TorusShape{0.6, 0.2}, arc_regions, [](std::mt19937& rng) -> Vector3 {
                   if (std::bernoulli_distribution(0.1)(rng)) return random_vector(rng, 2.0);
                   return near_stadium(0.0, 0.6, 0.55, rng);
                 }});
  std::vector<std::string> link_regions = arc_regions;
  for (const char* r : {"straight-outer/solid", "straight-outer/free", "straight-hole/solid",
                        "straight-hole/free"}) {
    link_regions.push_back(r);
  }
  out.push_back({"link", LinkShape{0.5, 0.4, 0.12}, link_regions, [](std::mt19937& rng) -> Vector3 {
                   if (std::bernoulli_distribution(0.1)(rng)) return random_vector(rng, 2.0);
                   return near_stadium(0.5, 0.4, 0.38, rng);
                 }});
  // Cylinders longer than wide (the side is nearest on a stretch of the axis) and flat (the
  // caps are nearest about the centre).
  const std::vector<std::string> cylinder_regions = {"side/solid", "side/free", "cap/solid",
                                                     "cap/free", "rim/free"};
  for (const CylinderShape& cylinder : {CylinderShape{0.5, 0.8}, CylinderShape{0.7, 0.3}}) {
    out.push_back(
        {"cylinder", cylinder, cylinder_regions, [cylinder](std::mt19937& rng) -> Vector3 {
           const double a = 1.5 * cylinder.radius, b = cylinder.half_length + 0.6;
           return Vector3(uniform(rng, -a, a), uniform(rng, -a, a), uniform(rng, -b, b));
         }});
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Checks at one world point.

State at_point(const Vector3& p) {
  State q;
  q.points = {p};
  return q;
}

const fd::Dofs kPointDof = {fd::point_dof(0)};

::testing::AssertionResult check_derivatives(const Collider& c, const Vector3& p,
                                             bool zero_hessian) {
  const SdfValue v = c.evaluate(p);
  const fd::ScalarFunction f = [&c](const State& s) {
    return c.evaluate(s.points[0], false).distance;
  };
  const fd::GradientFunction g = [&c](const State& s) {
    return Eigen::VectorXd(c.evaluate(s.points[0], false).gradient);
  };
  ::testing::AssertionResult r =
      fd::check_lie_gradient(f, at_point(p), kPointDof, v.gradient);  // requires ∇φ ≠ 0
  if (!r) return r;
  fd::FdOptions hessian;
  if (zero_hessian) {
    if (!v.hessian.isZero(0.0)) {
      return ::testing::AssertionFailure() << "∇²φ must be exactly 0 here:\n" << v.hessian;
    }
    hessian.require_nonzero = fd::NonZero::kNone;
  }
  return fd::check_lie_hessian(g, at_point(p), kPointDof, v.hessian, hessian);
}

// Identities that hold at every point where φ is differentiable.
void expect_identities(const Collider& c, const Vector3& p, double reference_distance) {
  const SdfValue v = c.evaluate(p);
  const SdfValue cheap = c.evaluate(p, false);
  EXPECT_EQ(cheap.distance, v.distance);
  EXPECT_EQ(cheap.gradient, v.gradient);
  EXPECT_TRUE(cheap.hessian.isZero(0.0)) << "hessian written although not requested";
  EXPECT_NEAR(v.gradient.norm(), 1.0, 1e-12);
  EXPECT_EQ(v.hessian, v.hessian.transpose());
  // ∇²φ ∇φ = 0: φ grows linearly along its gradient.
  EXPECT_LE((v.hessian * v.gradient).norm(), 1e-12 * std::max(1.0, v.hessian.norm()));
  const double sign = c.inside ? -1.0 : 1.0;
  EXPECT_NEAR(v.distance, sign * reference_distance, 1e-12);

  Collider flipped = c;
  flipped.inside = !c.inside;
  const SdfValue w = flipped.evaluate(p);
  EXPECT_EQ(w.distance, -v.distance);
  EXPECT_EQ(w.gradient, -v.gradient);
  EXPECT_EQ(w.hessian, -v.hessian);
}

constexpr int kPointsPerRegion = 12;

TEST(Sdf, DerivativesMatchFiniteDifferencesInEveryRegion) {
  std::mt19937 rng(8);
  const std::vector<double> angles = {0.0, 1.0, 2.5, std::numbers::pi};
  for (const Fixture& fx : fixtures()) {
    for (const bool inside : {false, true}) {
      for (const double angle : angles) {
        Collider c;
        c.name = fx.name;
        c.shape = fx.shape;
        c.inside = inside;
        c.position = random_vector(rng, 2.0);
        c.orientation = rotation_at(angle, rng);
        ASSERT_NO_THROW(c.validate("colliders[0]"));
        std::map<std::string, int> count;
        int rejected = 0, tries = 0;
        std::size_t done = 0;
        while (done < fx.regions.size() && tries < 200000) {
          ++tries;
          const Vector3 x = fx.propose(rng);
          const Probe pr = probe(fx.shape, x);
          if (pr.core < kCoreMargin || pr.seam < kSeamMargin) {
            ++rejected;
            continue;
          }
          int& n = count[pr.region];
          if (n >= kPointsPerRegion) continue;
          if (std::find(fx.regions.begin(), fx.regions.end(), pr.region) == fx.regions.end()) {
            ADD_FAILURE() << fx.name << ": unexpected region " << pr.region;
            n = kPointsPerRegion;  // report it once
            continue;
          }
          if (++n == kPointsPerRegion) ++done;
          const Vector3 p = c.position + c.orientation * x;
          SCOPED_TRACE(fx.name + (inside ? " (inside)" : "") + ", " + pr.region +
                       fd::trace(", local point", x.x(), x.y(), x.z()) +
                       fd::trace(", angle", angle));
          EXPECT_TRUE(check_derivatives(c, p, pr.zero_hessian));
          expect_identities(c, p, pr.distance);
        }
        for (const std::string& region : fx.regions) {
          EXPECT_EQ(count[region], kPointsPerRegion)
              << fx.name << ": region " << region << " not reached (" << tries << " tries, "
              << rejected << " too near a non-smooth set)";
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// Exact values at hand-computed points (identity pose unless stated).

Collider make(Shape shape, bool inside = false) {
  Collider c;
  c.shape = std::move(shape);
  c.inside = inside;
  return c;
}

void expect_vector(const Vector3& a, const Vector3& b, double tol = 1e-15) {
  EXPECT_LE((a - b).norm(), tol) << a.transpose() << " vs " << b.transpose();
}

TEST(Sdf, PlaneValues) {
  Collider c = make(PlaneShape{});
  c.position = Vector3(0, 0, 1);
  c.orientation = so3::exp(Vector3(std::numbers::pi / 2, 0, 0));  // e_z → −e_y
  const SdfValue v = c.evaluate(Vector3(5, -3, 7));               // n·(p − o), n = −e_y
  EXPECT_NEAR(v.distance, 3.0, 1e-15);
  expect_vector(v.gradient, Vector3(0, -1, 0));
  EXPECT_TRUE(v.hessian.isZero(0.0));
}

TEST(Sdf, SphereValues) {
  Collider c = make(SphereShape{2.0});
  c.position = Vector3(1, 2, 3);
  const SdfValue v = c.evaluate(Vector3(1, 2, 6));
  EXPECT_EQ(v.distance, 1.0);
  expect_vector(v.gradient, Vector3::UnitZ());
  Matrix3 H = Matrix3::Identity() / 3.0;
  H(2, 2) = 0.0;  // (I − e_z e_zᵀ)/3
  EXPECT_LE((v.hessian - H).norm(), 1e-15);
  EXPECT_EQ(c.evaluate(Vector3(4, 6, 3)).distance, 3.0);  // ‖(3, 4, 0)‖ − 2
  EXPECT_EQ(c.evaluate(Vector3(1, 2, 3.5)).distance, -1.5);
  // A bowl: inside, the solid is outside the ball.
  const Collider bowl = make(SphereShape{2.0}, true);
  EXPECT_EQ(bowl.evaluate(Vector3(0, 0, -1.5)).distance, 0.5);
  expect_vector(bowl.evaluate(Vector3(0, 0, -1.5)).gradient, Vector3::UnitZ());  // towards centre
}

TEST(Sdf, BoxValuesAndRoundingKeepsTheOuterSize) {
  const Collider sharp = make(BoxShape{Vector3(1, 2, 3), 0.0});
  EXPECT_EQ(sharp.evaluate(Vector3(2, 0, 0)).distance, 1.0);  // face
  expect_vector(sharp.evaluate(Vector3(2, 0, 0)).gradient, Vector3::UnitX());
  EXPECT_TRUE(sharp.evaluate(Vector3(2, 0, 0)).hessian.isZero(0.0));
  EXPECT_NEAR(sharp.evaluate(Vector3(2, -3, 0)).distance, std::sqrt(2.0), 1e-15);  // edge
  expect_vector(sharp.evaluate(Vector3(2, -3, 0)).gradient, Vector3(1, -1, 0) / std::sqrt(2.0));
  // Edge Hessian: a cylinder about the edge ∥ e_z, (I − e_z e_zᵀ − u uᵀ)/√2.
  const Vector3 u = Vector3(1, -1, 0) / std::sqrt(2.0);
  const Matrix3 He =
      (Matrix3::Identity() - Vector3::UnitZ() * Vector3::UnitZ().transpose() - u * u.transpose()) /
      std::sqrt(2.0);
  EXPECT_LE((sharp.evaluate(Vector3(2, -3, 0)).hessian - He).norm(), 1e-15);
  EXPECT_NEAR(sharp.evaluate(Vector3(-2, 3, -4)).distance, std::sqrt(3.0), 1e-15);  // corner
  EXPECT_EQ(sharp.evaluate(Vector3(0.5, 0, 0)).distance, -0.5);  // inside: nearest face x
  expect_vector(sharp.evaluate(Vector3(0.5, 0, 0)).gradient, Vector3::UnitX());
  expect_vector(sharp.evaluate(Vector3(0, -1.5, 0.2)).gradient, -Vector3::UnitY());
  EXPECT_EQ(sharp.evaluate(Vector3(0, -1.5, 0.2)).distance, -0.5);

  const double r = 0.5;
  const Collider rounded = make(BoxShape{Vector3(1, 2, 3), r});
  // The outer size stays half_extents: face centres and face points away from the rounded
  // edges are on the surface, face distances are unchanged.
  for (const Vector3& s : {Vector3(1, 0, 0), Vector3(0, -2, 0), Vector3(0, 0, 3),
                           Vector3(1, 1.2, -2.1), Vector3(-0.3, 0.6, -3)}) {
    EXPECT_NEAR(rounded.evaluate(s).distance, 0.0, 1e-15) << s.transpose();
  }
  EXPECT_NEAR(rounded.evaluate(Vector3(2, 0, 0)).distance, 1.0, 1e-15);
  EXPECT_NEAR(rounded.evaluate(Vector3(0, 0, 0)).distance, -1.0, 1e-15);  // −min half extent
  // Edges and corners are rounded: the sharp corner is r(√3 − 1) outside, the edge r(√2 − 1).
  EXPECT_NEAR(rounded.evaluate(Vector3(1, 2, 3)).distance, r * (std::sqrt(3.0) - 1.0), 1e-15);
  EXPECT_NEAR(rounded.evaluate(Vector3(1, 2, 0)).distance, r * (std::sqrt(2.0) - 1.0), 1e-15);
  // b = (0.5, 1.5, 2.5); (2, 3, 0): q = (1.5, 1.5, −2.5), φ = 1.5√2 − r.
  EXPECT_NEAR(rounded.evaluate(Vector3(2, 3, 0)).distance, 1.5 * std::sqrt(2.0) - r, 1e-15);
}

TEST(Sdf, CapsuleValues) {
  const Collider c = make(CapsuleShape{1.0, 0.5});
  const SdfValue side = c.evaluate(Vector3(1, 0, 0.3));
  EXPECT_EQ(side.distance, 0.5);
  expect_vector(side.gradient, Vector3::UnitX());
  Matrix3 H = Matrix3::Zero();
  H(1, 1) = 1.0;  // (I − e_z e_zᵀ − e_x e_xᵀ)/1
  EXPECT_LE((side.hessian - H).norm(), 1e-15);
  EXPECT_EQ(c.evaluate(Vector3(0, 0, 3)).distance, 1.5);  // above the top cap
  EXPECT_EQ(c.evaluate(Vector3(3, 0, 5)).distance, 4.5);  // ‖(3, 0, 4)‖ − 0.5
  EXPECT_EQ(c.evaluate(Vector3(0, -3, -5)).distance, 4.5);  // bottom cap: ‖(0, −3, −4)‖ − 0.5
  const SdfValue cap = c.evaluate(Vector3(0, 0, 3));
  Matrix3 Hs = Matrix3::Identity() / 2.0;
  Hs(2, 2) = 0.0;  // (I − e_z e_zᵀ)/2
  EXPECT_LE((cap.hessian - Hs).norm(), 1e-15);
  EXPECT_NEAR(c.evaluate(Vector3(0.2, 0, 0.9)).distance, -0.3, 1e-15);
}

TEST(Sdf, TubeValuesAndTieRule) {
  const Collider c = make(TubeShape{{{0, 0, 0}, {2, 0, 0}, {2, 2, 0}}, 0.25});
  // (1, 1, 0) is equally near both segments (the medial plane of the bend): the first one
  // wins, so ∇φ points away from (1, 0, 0) on segment 0, not from (2, 1, 0) on segment 1.
  const SdfValue tie = c.evaluate(Vector3(1, 1, 0));
  EXPECT_EQ(tie.distance, 0.75);
  expect_vector(tie.gradient, Vector3::UnitY());
  // Outside the joint: the vertex (2, 0, 0) is nearest, for both segments (a sphere).
  const SdfValue joint = c.evaluate(Vector3(3, -1, 0));
  EXPECT_NEAR(joint.distance, std::sqrt(2.0) - 0.25, 1e-15);
  const Vector3 u = Vector3(1, -1, 0) / std::sqrt(2.0);
  EXPECT_LE((joint.hessian - (Matrix3::Identity() - u * u.transpose()) / std::sqrt(2.0)).norm(),
            1e-15);
  // Segment interior: a cylinder.
  const SdfValue mid = c.evaluate(Vector3(1, -0.5, 0.5));
  EXPECT_NEAR(mid.distance, std::sqrt(0.5) - 0.25, 1e-15);
  const Vector3 w = Vector3(0, -1, 1) / std::sqrt(2.0);
  EXPECT_LE((mid.hessian - (Matrix3::Identity() - Vector3::UnitX() * Vector3::UnitX().transpose() -
                            w * w.transpose()) /
                               std::sqrt(0.5))
                .norm(),
            1e-15);
  EXPECT_EQ(c.evaluate(Vector3(-1, 0, 0)).distance, 0.75);  // hemispherical end
  EXPECT_EQ(c.evaluate(Vector3(2, 3, 0)).distance, 0.75);   // the other end
  EXPECT_NEAR(c.evaluate(Vector3(1.9, 1.0, 0)).distance, -0.15, 1e-15);
  // The lumen of the pipe: inside, the solid is everything outside the tube.
  const Collider pipe = make(TubeShape{{{0, 0, 0}, {2, 0, 0}, {2, 2, 0}}, 0.25}, true);
  EXPECT_NEAR(pipe.evaluate(Vector3(1, 0.05, 0)).distance, 0.2, 1e-15);
  expect_vector(pipe.evaluate(Vector3(1, 0.05, 0)).gradient, -Vector3::UnitY());  // to the axis
}

TEST(Sdf, TorusLinkAndCylinderValues) {
  const auto diagonal = [](double a, double b, double c) {
    return Matrix3(Vector3(a, b, c).asDiagonal());
  };
  // Torus R = 2, r = 0.5: on the outer equator 1 beyond the surface, D = 1.5, and the
  // curvature along the parallel is 1/(distance from the axis) = 1/3.5.
  const Collider torus = make(TorusShape{2.0, 0.5});
  SdfValue v = torus.evaluate(Vector3(3.5, 0, 0));
  EXPECT_EQ(v.distance, 1.0);
  expect_vector(v.gradient, Vector3::UnitX());
  EXPECT_LE((v.hessian - diagonal(0, 1 / 3.5, 1 / 1.5)).norm(), 1e-15);
  // In the hole, 1 from the axis: D = 1, ∇φ towards the axis; the parallel curves the other
  // way, a/(s D) = −1.
  v = torus.evaluate(Vector3(0, -1, 0));
  EXPECT_EQ(v.distance, 0.5);
  expect_vector(v.gradient, Vector3::UnitY());
  EXPECT_LE((v.hessian - diagonal(-1, 0, 1)).norm(), 1e-15);
  // Above the tube: (2, 0, 3), D = 3; inside the tube: (2.3, 0, 0.4), D = 0.5.
  EXPECT_EQ(torus.evaluate(Vector3(0, 2, 3)).distance, 2.5);
  expect_vector(torus.evaluate(Vector3(0, 2, 3)).gradient, Vector3::UnitZ());
  EXPECT_NEAR(torus.evaluate(Vector3(2.3, 0, 0.4)).distance, 0.0, 1e-15);
  EXPECT_NEAR(torus.evaluate(Vector3(-2.15, 0, 0.2)).distance, -0.25, 1e-15);
  // Off the planes: (3, 4, 12)·k with s = 5: D = ‖(3, 12)‖... (s − R, z) = (3, 12).
  EXPECT_NEAR(torus.evaluate(Vector3(3, 4, 12)).distance, std::hypot(3.0, 12.0) - 0.5, 1e-14);

  // Link L = 1, R = 2, r = 0.5: beside a straight side a cylinder about it, about an arc a
  // torus about (±1, 0, 0).
  const Collider link = make(LinkShape{1.0, 2.0, 0.5});
  v = link.evaluate(Vector3(0.3, 3.5, 0));
  EXPECT_EQ(v.distance, 1.0);
  expect_vector(v.gradient, Vector3::UnitY());
  EXPECT_LE((v.hessian - diagonal(0, 0, 1 / 1.5)).norm(), 1e-15);
  v = link.evaluate(Vector3(-0.7, -1, 0));  // in the hole beside the lower side: D = 1
  EXPECT_EQ(v.distance, 0.5);
  expect_vector(v.gradient, Vector3::UnitY());
  EXPECT_LE((v.hessian - diagonal(0, 0, 1)).norm(), 1e-15);
  v = link.evaluate(Vector3(4.5, 0, 0));  // beyond the right arc: as the torus at (3.5, 0, 0)
  EXPECT_EQ(v.distance, 1.0);
  EXPECT_LE((v.hessian - diagonal(0, 1 / 3.5, 1 / 1.5)).norm(), 1e-15);
  EXPECT_NEAR(link.evaluate(Vector3(-1 - 3, -4, 12)).distance, std::hypot(3.0, 12.0) - 0.5, 1e-14);
  EXPECT_NEAR(link.evaluate(Vector3(0.9, 2.2, 0)).distance, -0.3, 1e-15);

  // Cylinder ρ = 1, h = 2.
  const Collider cylinder = make(CylinderShape{1.0, 2.0});
  v = cylinder.evaluate(Vector3(0, -2, 1.5));  // beside the side
  EXPECT_EQ(v.distance, 1.0);
  expect_vector(v.gradient, -Vector3::UnitY());
  EXPECT_LE((v.hessian - diagonal(0.5, 0, 0)).norm(), 1e-15);
  v = cylinder.evaluate(Vector3(0.3, 0.4, -5));  // below the bottom cap
  EXPECT_EQ(v.distance, 3.0);
  expect_vector(v.gradient, -Vector3::UnitZ());
  EXPECT_TRUE(v.hessian.isZero(0.0));
  v = cylinder.evaluate(Vector3(4, 0, 6));  // beyond the top rim: q = (3, 4)
  EXPECT_EQ(v.distance, 5.0);
  expect_vector(v.gradient, Vector3(0.6, 0, 0.8));
  const Vector3 u(0.6, 0, 0.8);
  const Matrix3 rim =
      (Matrix3::Identity() - Vector3::UnitY() * Vector3::UnitY().transpose() - u * u.transpose()) /
          5 +
      diagonal(0, 3.0 / (4 * 5), 0);
  EXPECT_LE((v.hessian - rim).norm(), 1e-15);
  // Inside: nearer the side (a curved wall: ∇²φ = (I − e_z e_zᵀ − n nᵀ)/s) or a cap.
  v = cylinder.evaluate(Vector3(0.5, 0, 0.2));
  EXPECT_EQ(v.distance, -0.5);
  EXPECT_LE((v.hessian - diagonal(0, 2, 0)).norm(), 1e-15);
  v = cylinder.evaluate(Vector3(0.25, 0, 1.5));
  EXPECT_EQ(v.distance, -0.5);
  expect_vector(v.gradient, Vector3::UnitZ());
  EXPECT_TRUE(v.hessian.isZero(0.0));
}

// ---------------------------------------------------------------------------------------
// Continuity across region boundaries: φ and ∇φ (C¹) agree on both sides of a plane where
// the formula changes, at δ = 1e-13 on either side.

void expect_continuous(const Collider& c, const Vector3& on, const Vector3& across,
                       bool gradient_continuous = true) {
  constexpr double kDelta = 1e-13;
  const SdfValue a = c.evaluate(on - kDelta * across), b = c.evaluate(on + kDelta * across);
  EXPECT_NEAR(a.distance, b.distance, 1e-12) << on.transpose();
  if (gradient_continuous) {
    EXPECT_LE((a.gradient - b.gradient).norm(), 1e-12) << on.transpose();
  }
}

TEST(Sdf, ContinuousAcrossRegionBoundaries) {
  std::mt19937 rng(3);
  for (const double r : {0.0, 0.25}) {
    Collider c = make(BoxShape{Vector3(1, 2, 3), r});
    c.position = random_vector(rng, 1.0);
    c.orientation = rotation_at(2.0, rng);
    const Matrix3& R = c.orientation;
    const Vector3 b = (Vector3(1, 2, 3).array() - r).matrix();
    const auto world = [&](const Vector3& x) -> Vector3 { return c.position + R * x; };
    // Face (z) | edge (x, z): the plane x = b_x above the top face.
    expect_continuous(c, world(Vector3(b.x(), 0.3, b.z() + 0.4)), R * Vector3::UnitX());
    // Edge (x, z) | corner: y = b_y.
    expect_continuous(c, world(Vector3(b.x() + 0.2, b.y(), b.z() + 0.4)), R * Vector3::UnitY());
    // Inner box | face: z = b_z (also the solid's surface when r = 0).
    expect_continuous(c, world(Vector3(0.1, -0.2, b.z())), R * Vector3::UnitZ());
    // Inner medial plane q_x = q_y (φ continuous, ∇φ jumps): x − b_x = y − b_y.
    expect_continuous(c, world(Vector3(b.x() - 0.3, b.y() - 0.3, 0.1)),
                      R * Vector3(1, -1, 0).normalized(), false);
  }
  Collider capsule = make(CapsuleShape{0.6, 0.3});
  capsule.orientation = rotation_at(1.0, rng);
  for (const double z : {0.6, -0.6}) {  // side | cap
    expect_continuous(capsule, capsule.orientation * Vector3(0.4, 0.1, z),
                      capsule.orientation * Vector3::UnitZ());
  }
  const Collider tube = make(TubeShape{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, 0.15});
  expect_continuous(tube, Vector3(1, -0.3, 0.2), Vector3::UnitX());  // interior | joint
  expect_continuous(tube, Vector3(1.3, 0, 0.2), Vector3::UnitY());   // joint | interior
  expect_continuous(tube, Vector3(0, 0.3, 0.2), Vector3::UnitX());   // end | interior

  // Link: straight | arc at x = ±L, in the hole and outside, in and out of the solid.
  Collider link = make(LinkShape{0.5, 0.4, 0.12});
  link.orientation = rotation_at(2.0, rng);
  for (const double x : {0.5, -0.5}) {
    for (const Vector3& y : {Vector3(0, 0.45, 0.1), Vector3(0, 0.2, -0.05), Vector3(0, -0.35, 0.02),
                             Vector3(0, -0.9, 0.3)}) {
      expect_continuous(link, link.orientation * (Vector3(x, 0, 0) + y),
                        link.orientation * Vector3::UnitX());
    }
  }
  // Cylinder: side | rim at |z| = h, cap | rim at s = ρ (C¹); inside, the cone and the disc
  // where the nearest face changes (φ continuous, ∇φ jumps).
  Collider cylinder = make(CylinderShape{0.7, 0.3});
  cylinder.orientation = rotation_at(1.5, rng);
  const Matrix3& R = cylinder.orientation;
  for (const double z : {0.3, -0.3})
    expect_continuous(cylinder, R * Vector3(0.9, 0.2, z), R * Vector3::UnitZ());
  expect_continuous(cylinder, R * Vector3(0, 0.7, 0.5), R * Vector3::UnitY());
  expect_continuous(cylinder, R * Vector3(0.6, 0, 0.2), R * Vector3(1, 0, -1).normalized(), false);
  expect_continuous(cylinder, R * Vector3(0.1, 0.2, 0), R * Vector3::UnitZ(), false);
}

// ---------------------------------------------------------------------------------------
// Non-differentiable points: the documented finite choices.

void expect_finite(const SdfValue& v) {
  EXPECT_TRUE(std::isfinite(v.distance));
  EXPECT_TRUE(v.gradient.allFinite());
  EXPECT_TRUE(v.hessian.allFinite());
  EXPECT_NEAR(v.gradient.norm(), 1.0, 1e-12);
}

TEST(Sdf, NonDifferentiablePointsAreFinite) {
  // An exactly representable pose (a cyclic permutation: e_x → e_y → e_z → e_x), so that the
  // local point is exactly on the core set and the documented choices can be compared.
  Matrix3 P;
  P << 0, 0, 1,  //
      1, 0, 0,   //
      0, 1, 0;
  for (const bool inside : {false, true}) {
    const double s = inside ? -1.0 : 1.0;
    Collider c;
    c.inside = inside;
    c.position = Vector3(1, -2, 0.5);
    c.orientation = P;
    const auto local = [&](const Vector3& x) { return c.evaluate(c.position + P * x); };

    c.shape = SphereShape{0.7};  // centre: ∇φ = e_z, ∇²φ = 0
    SdfValue v = local(Vector3::Zero());
    expect_finite(v);
    EXPECT_EQ(v.distance, -0.7 * s);
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitZ()));
    EXPECT_TRUE(v.hessian.isZero(0.0));

    // Box centre: q = −b, the largest q is the axis of the smallest b (y), with sign(0) = +1.
    // b = h − r = (0.875, 0.375, 0.625), exact.
    c.shape = BoxShape{Vector3(1, 0.5, 0.75), 0.125};
    v = local(Vector3::Zero());
    expect_finite(v);
    EXPECT_EQ(v.distance, -0.5 * s);
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitY()));
    EXPECT_TRUE(v.hessian.isZero(0.0));
    // Off-centre on the medial plane y = 0 between the two nearest faces: sign(0) = +1.
    EXPECT_EQ(local(Vector3(0.2, 0, 0.1)).gradient, s * (P * Vector3::UnitY()));
    // On the medial plane q_x = q_y = −0.125 (exact): the lower index, x.
    EXPECT_EQ(local(Vector3(0.75, 0.25, 0)).gradient, s * (P * Vector3::UnitX()));
    EXPECT_EQ(local(Vector3(0.75, -0.25, 0)).distance, -0.25 * s);

    // On the segment and at its ends: ∇φ = e_x, ∇²φ = 0 (z values chosen so that p − o is
    // exact: 1.6 − 1 would put the point 1e-16 beyond the end, on the cap).
    c.shape = CapsuleShape{0.625, 0.3};
    for (const double z : {0.0, 0.375, 0.625, -0.625}) {
      v = local(Vector3(0, 0, z));
      expect_finite(v);
      EXPECT_NEAR(v.distance, -0.3 * s, 1e-15);
      EXPECT_EQ(v.gradient, s * (P * Vector3::UnitX()));
      EXPECT_TRUE(v.hessian.isZero(0.0));
    }

    // Tube axis: the coordinate axis least aligned with the segment, made perpendicular.
    c.shape = TubeShape{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}}, 0.15};
    v = local(Vector3(0.5, 0, 0));  // segment ∥ e_x: e_y (first of the tie y, z)
    expect_finite(v);
    EXPECT_NEAR(v.distance, -0.15 * s, 1e-15);
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitY()));
    EXPECT_TRUE(v.hessian.isZero(0.0));
    EXPECT_EQ(local(Vector3(1, 1, 0.5)).gradient, s * (P * Vector3::UnitX()));  // ∥ e_z: e_x
    // Vertices: the first of the two segments meeting there (the joint (1, 0, 0): segment 0).
    EXPECT_EQ(local(Vector3(1, 0, 0)).gradient, s * (P * Vector3::UnitY()));
    EXPECT_EQ(local(Vector3(1, 1, 0)).gradient, s * (P * Vector3::UnitX()));  // segment 1 ∥ e_y
    for (const Vector3& x : {Vector3(0, 0, 0), Vector3(1, 1, 1)}) {
      v = local(x);
      expect_finite(v);
      EXPECT_NEAR(v.distance, -0.15 * s, 1e-15);
      EXPECT_TRUE(v.hessian.isZero(0.0));
    }
    // d = 1e-160 (d² underflows): counts as on the axis (o = 0 keeps the 1e-160 in p − o).
    c.position.setZero();
    v = local(Vector3(0.5, 1e-160, 0));
    expect_finite(v);
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitY()));
    EXPECT_TRUE(v.hessian.isZero(0.0));
    v = local(Vector3(0.5, 1e-140, 0));  // above kCoreDistance: the true (huge) curvature
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitY()));
    EXPECT_NEAR(v.hessian.norm(), 1e140, 1e126);

    // Torus and link, on the core curve: φ = −r, ∇φ = n (away from the segment), ∇²φ = 0.
    c.position = Vector3(1, -2, 0.5);
    struct OnCurve {
      Shape shape;
      Vector3 x, n;
    };
    for (const OnCurve& k :
         {OnCurve{TorusShape{0.75, 0.25}, Vector3(0.75, 0, 0), Vector3::UnitX()},
          OnCurve{TorusShape{0.75, 0.25}, Vector3(0, -0.75, 0), -Vector3::UnitY()},
          OnCurve{LinkShape{0.5, 0.75, 0.25}, Vector3(0.25, 0.75, 0), Vector3::UnitY()},
          OnCurve{LinkShape{0.5, 0.75, 0.25}, Vector3(-1.25, 0, 0), -Vector3::UnitX()},
          OnCurve{LinkShape{0.5, 0.75, 0.25}, Vector3(-0.5, -0.75, 0), -Vector3::UnitY()}}) {
      c.shape = k.shape;
      v = local(k.x);
      expect_finite(v);
      EXPECT_EQ(v.distance, -0.25 * s);
      EXPECT_EQ(v.gradient, s * (P * k.n));
      EXPECT_TRUE(v.hessian.isZero(0.0));
    }
    // On a torus's axis and a link's strip s = 0 across its hole: n = e_y, ∇²s = 0, so
    // ∇φ = (−R e_y + z e_z)/D, ∇²φ = (I − e_x e_xᵀ − u uᵀ)/D with D = ‖(R, z)‖ = 1.25.
    for (const Shape& shape : {Shape(TorusShape{0.75, 0.25}), Shape(LinkShape{0.5, 0.75, 0.25})}) {
      c.shape = shape;
      for (const Vector3& x : {Vector3(0, 0, 1), Vector3(0.5, 0, -1), Vector3(-0.25, 0, 1)}) {
        if (std::holds_alternative<TorusShape>(shape) && x.x() != 0.0) continue;  // off its axis
        v = local(x);
        expect_finite(v);
        EXPECT_EQ(v.distance, s * 1.0);
        const Vector3 u = Vector3(0, -0.75, x.z()) / 1.25;
        EXPECT_LE((v.gradient - s * (P * u)).norm(), 1e-15);
        const Matrix3 H = (Matrix3::Identity() - Vector3::UnitX() * Vector3::UnitX().transpose() -
                           u * u.transpose()) /
                          1.25;
        EXPECT_LE((v.hessian - s * (P * H * P.transpose())).norm(), 1e-15);
      }
      // The centre: D = R, ∇φ = −e_y, ∇²φ = (I − e_x e_xᵀ − e_y e_yᵀ)/R.
      v = local(Vector3::Zero());
      expect_finite(v);
      EXPECT_EQ(v.distance, 0.5 * s);
      EXPECT_EQ(v.gradient, s * (P * -Vector3::UnitY()));
      EXPECT_LE((v.hessian - s * (P * Vector3(0, 0, 1 / 0.75).asDiagonal() * P.transpose())).norm(),
                1e-15);
    }
    // Cylinder: its axis where the side is nearest (∇φ = e_y, ∇²φ = 0), the cone from the
    // rim (side: n), the rim circle itself (side), the disc z = 0 between the caps (+e_z).
    c.shape = CylinderShape{0.5, 0.75};
    v = local(Vector3(0, 0, 0.125));
    expect_finite(v);
    EXPECT_EQ(v.distance, -0.5 * s);
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitY()));
    EXPECT_TRUE(v.hessian.isZero(0.0));
    v = local(Vector3(0.25, 0, 0.5));  // q = (−0.25, −0.25)
    EXPECT_EQ(v.distance, -0.25 * s);
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitX()));
    v = local(Vector3(0, -0.5, -0.75));  // the rim
    expect_finite(v);
    EXPECT_EQ(v.distance, 0.0);
    EXPECT_EQ(v.gradient, s * (P * -Vector3::UnitY()));
    c.shape = CylinderShape{0.75, 0.5};
    v = local(Vector3(0.125, 0, 0));
    EXPECT_EQ(v.distance, -0.5 * s);
    EXPECT_EQ(v.gradient, s * (P * Vector3::UnitZ()));
    EXPECT_TRUE(v.hessian.isZero(0.0));
  }

  // At a general pose the transformed point is only within round-off (~1e-16) of the core
  // set: huge but finite curvature, unit gradient.
  std::mt19937 rng(5);
  for (const Fixture& fx : fixtures()) {
    Collider c;
    c.shape = fx.shape;
    c.position = random_vector(rng, 2.0);
    c.orientation = rotation_at(2.5, rng);
    std::vector<Vector3> cores = {Vector3::Zero(), Vector3(0, 0, 0.6), Vector3(0, 0, 0.2)};
    if (const auto* t = std::get_if<TubeShape>(&fx.shape)) {
      cores = t->polyline;
      cores.push_back(0.5 * (t->polyline[0] + t->polyline[1]));
    }
    if (const auto* t = std::get_if<TorusShape>(&fx.shape)) {  // the circle
      cores.insert(cores.end(), {Vector3(t->major_radius, 0, 0), Vector3(0, -t->major_radius, 0)});
    }
    if (const auto* l = std::get_if<LinkShape>(&fx.shape)) {  // the stadium, its strip
      cores.insert(
          cores.end(),
          {Vector3(0.1, l->major_radius, 0), Vector3(l->half_length + l->major_radius, 0, 0),
           Vector3(l->half_length, -l->major_radius, 0), Vector3(0.3, 0, 0.1)});
    }
    if (const auto* y = std::get_if<CylinderShape>(&fx.shape)) {  // the rims
      cores.insert(cores.end(), {Vector3(y->radius, 0, y->half_length),
                                 Vector3(0, -y->radius, -y->half_length)});
    }
    for (const Vector3& x : cores) {
      SCOPED_TRACE(fx.name);
      expect_finite(c.evaluate(c.position + c.orientation * x));
    }
  }
}

// ---------------------------------------------------------------------------------------
// Far (1e6) and very close (1e-9) points against an 80-bit long double reference of the
// same formulas; error allowed: a few ulps of the coordinates, 8 eps·(‖p − o‖ + size).

using LongVector = Eigen::Matrix<long double, 3, 1>;

long double link_distance(long double L, long double R, long double r, const LongVector& x) {
  const long double planar = std::hypot(x.x() - std::clamp(x.x(), -L, L), x.y());
  return std::hypot(planar - R, x.z()) - r;
}

long double reference_distance(const Collider& c, const Vector3& p) {
  const LongVector x = c.orientation.cast<long double>().transpose() *
                       (p.cast<long double>() - c.position.cast<long double>());
  const auto segment = [&x](const LongVector& a, const LongVector& b) {
    const LongVector ab = b - a;
    const long double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0L, 1.0L);
    return (x - a - t * ab).norm();
  };
  return std::visit(
      [&](const auto& s) -> long double {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, PlaneShape>) return x.z();
        if constexpr (std::is_same_v<S, SphereShape>) return x.norm() - s.radius;
        if constexpr (std::is_same_v<S, BoxShape>) {
          const LongVector q =
              x.cwiseAbs() -
              (s.half_extents.array() - s.rounding).matrix().template cast<long double>();
          return q.cwiseMax(0.0L).norm() + std::min(q.maxCoeff(), 0.0L) - s.rounding;
        }
        if constexpr (std::is_same_v<S, CapsuleShape>) {
          return segment(LongVector(0, 0, -s.half_length), LongVector(0, 0, s.half_length)) -
                 s.radius;
        }
        if constexpr (std::is_same_v<S, TubeShape>) {
          long double d = std::numeric_limits<long double>::infinity();
          for (std::size_t j = 0; j + 1 < s.polyline.size(); ++j) {
            d = std::min(d, segment(s.polyline[j].template cast<long double>(),
                                    s.polyline[j + 1].template cast<long double>()));
          }
          return d - s.radius;
        }
        if constexpr (std::is_same_v<S, TorusShape>) {
          return link_distance(0.0L, s.major_radius, s.minor_radius, x);
        }
        if constexpr (std::is_same_v<S, LinkShape>) {
          return link_distance(s.half_length, s.major_radius, s.minor_radius, x);
        }
        if constexpr (std::is_same_v<S, CylinderShape>) {
          const long double q1 = std::hypot(x.x(), x.y()) - s.radius;
          const long double q2 = std::abs(x.z()) - s.half_length;
          return std::hypot(std::max(q1, 0.0L), std::max(q2, 0.0L)) +
                 std::min(std::max(q1, q2), 0.0L);
        }
        if constexpr (std::is_same_v<S, MeshShape>) throw std::logic_error("not an analytic shape");
      },
      c.shape);
}

TEST(Sdf, AccurateFarAwayAndVeryClose) {
  std::mt19937 rng(13);
  for (const Fixture& fx : fixtures()) {
    int landed = 0;
    for (int trial = 0; trial < 20; ++trial) {
      Collider c;
      c.shape = fx.shape;
      c.inside = trial % 2 == 1;
      c.position = random_vector(rng, 2.0);
      c.orientation = rotation_at(1.0 + 0.1 * trial, rng);
      const double s = c.inside ? -1.0 : 1.0;
      // Far: 1e6 in a random direction.
      const Vector3 far = c.position + 1e6 * random_unit(rng);
      const SdfValue v = c.evaluate(far);
      const double tol_far = 8 * kEps * (1e6 + 4.0);
      EXPECT_NEAR(v.distance, s * static_cast<double>(reference_distance(c, far)), tol_far)
          << fx.name;
      EXPECT_NEAR(v.gradient.norm(), 1.0, 1e-12);
      EXPECT_TRUE(v.hessian.allFinite());
      // Close: step 1e-9 off a surface point along the (world) normal, to either side.
      const Vector3 x = fx.propose(rng);
      const Probe pr = probe(fx.shape, x);
      if (pr.core < kCoreMargin || pr.seam < kSeamMargin) continue;
      const Vector3 p0 = c.position + c.orientation * x;
      const SdfValue at = c.evaluate(p0);
      for (const double gap : {1e-9, -1e-9}) {
        // Walk to the surface (exact along ∇φ in a region), then 1e-9 off it.
        const Vector3 p = p0 - (at.distance - s * gap) * at.gradient;
        const SdfValue w = c.evaluate(p);
        const double ref = s * static_cast<double>(reference_distance(c, p));
        const double tol = 8 * kEps * ((p - c.position).norm() + 4.0);
        EXPECT_NEAR(w.distance, ref, tol) << fx.name;
        // The walk along ∇φ lands 1e-9 off the surface unless it crosses a medial set (the
        // inside of a tube's bend); it rounds by ~eps·‖p‖.
        if (std::abs(ref - s * gap) <= 1e-14) ++landed;
      }
    }
    EXPECT_GE(landed, 10) << fx.name << ": too few points 1e-9 from the surface were tested";
  }
}

// ---------------------------------------------------------------------------------------
// Torus, link and cylinder against brute-force distances to dense samplings of their core
// curve and of their surface (not the formulas above), and their derivatives 1e-9 from the
// surface, 1e6 away and on both sides of every plane where ∇²φ jumps.

// The stadium curve at distance R from [−L, L] on the x axis, as a closed polyline of about
// n points (the same point starts and ends it).
std::vector<Vector3> stadium_polyline(double L, double R, int n) {
  const double pi = std::numbers::pi, length = 4 * L + 2 * pi * R;
  std::vector<Vector3> out;
  for (const double side : {1.0, -1.0}) {
    const int arc = static_cast<int>(n * pi * R / length) + 1;
    for (int k = 0; k < arc; ++k) {
      const double theta = -pi / 2 + pi * k / arc;
      out.emplace_back(side * (L + R * std::cos(theta)), side * R * std::sin(theta), 0.0);
    }
    const int straight = static_cast<int>(n * 2 * L / length) + 1;
    for (int k = 0; k < straight; ++k)
      out.emplace_back(side * (L - 2 * L * k / straight), side * R, 0.0);
  }
  out.push_back(out.front());
  return out;
}

double polyline_distance(const std::vector<Vector3>& v, const Vector3& x) {
  double best = kInf;
  for (std::size_t j = 0; j + 1 < v.size(); ++j) {
    const Vector3 ab = v[j + 1] - v[j];
    const double t = std::clamp((x - v[j]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (x - v[j] - t * ab).norm());
  }
  return best;
}

TEST(Sdf, TorusLinkAndCylinderAgreeWithBruteForceDistances) {
  std::mt19937 rng(17);
  for (const auto& [L, R, r] : {std::tuple{0.0, 0.6, 0.2}, std::tuple{0.5, 0.4, 0.12}}) {
    SCOPED_TRACE(fd::trace("link L R r", L, R, r));
    Collider c = make(LinkShape{L, R, r});
    if (L == 0.0) c.shape = TorusShape{R, r};
    // The core curve, 40000 chords: their sag (≤ (arc step)²/8R ≈ 1e-8) bounds the error of
    // the distance to it.
    const std::vector<Vector3> core = stadium_polyline(L, R, 40000);
    // The surface: rings of 600 points about 6000 core points, within ~1.5e-3 of every
    // surface point (outside the solid: r < R, so no ring point is inside another part).
    std::vector<Vector3> surface;
    const std::vector<Vector3> rings = stadium_polyline(L, R, 6000);
    for (std::size_t i = 0; i + 1 < rings.size(); ++i) {
      const Vector3 n = (rings[i] - Vector3(std::clamp(rings[i].x(), -L, L), 0, 0)).normalized();
      for (int j = 0; j < 600; ++j) {
        const double v = 2 * std::numbers::pi * j / 600;
        surface.push_back(rings[i] + r * (std::cos(v) * n + std::sin(v) * Vector3::UnitZ()));
      }
    }
    for (int i = 0; i < 60; ++i) {
      const Vector3 x =
          i % 3 == 0 ? random_vector(rng, L + R + 2 * r) : near_stadium(L, R, 1.5 * r, rng);
      const SdfValue v = c.evaluate(x, false);
      const double to_core = polyline_distance(core, x);
      EXPECT_NEAR(v.distance, to_core - r, 1e-8) << x.transpose();
      double to_surface = kInf;
      for (const Vector3& y : surface) to_surface = std::min(to_surface, (x - y).norm());
      EXPECT_NEAR(std::abs(v.distance), to_surface, 1.5e-3) << x.transpose();
      EXPECT_EQ(v.distance < 0.0, to_core < r) << x.transpose();
    }
  }
  // Cylinder ρ = 0.5, h = 0.8: a 1.5e-3 grid on its side and caps (every surface point within
  // ~1.1e-3 of it).
  const double rho = 0.5, h = 0.8, step = 1.5e-3;
  const Collider c = make(CylinderShape{rho, h});
  std::vector<Vector3> surface;
  const int around = static_cast<int>(2 * std::numbers::pi * rho / step);
  const int rows = static_cast<int>(std::ceil(2 * h / step));
  for (int i = 0; i <= rows; ++i) {  // the rims included
    for (int j = 0; j < around; ++j) {
      const double a = 2 * std::numbers::pi * j / around;
      surface.emplace_back(rho * std::cos(a), rho * std::sin(a), -h + 2 * h * i / rows);
    }
  }
  for (double x = -rho; x <= rho; x += step) {
    for (double y = -rho; y <= rho; y += step) {
      if (std::hypot(x, y) <= rho)
        surface.insert(surface.end(), {Vector3(x, y, h), Vector3(x, y, -h)});
    }
  }
  for (int i = 0; i < 60; ++i) {
    const Vector3 x(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1.4, 1.4));
    double to_surface = kInf;
    for (const Vector3& y : surface) to_surface = std::min(to_surface, (x - y).norm());
    const SdfValue v = c.evaluate(x, false);
    EXPECT_NEAR(std::abs(v.distance), to_surface, 1.5e-3) << x.transpose();
    EXPECT_EQ(v.distance < 0.0, std::hypot(x.x(), x.y()) < rho && std::abs(x.z()) < h)
        << x.transpose();
  }
}

TEST(Sdf, TorusLinkAndCylinderDerivativesAtTheSurfaceFarAwayAndAcrossSeams) {
  std::mt19937 rng(29);
  for (const Fixture& fx : fixtures()) {
    if (std::holds_alternative<PlaneShape>(fx.shape) ||
        std::holds_alternative<SphereShape>(fx.shape) ||
        std::holds_alternative<BoxShape>(fx.shape) ||
        std::holds_alternative<CapsuleShape>(fx.shape) ||
        std::holds_alternative<TubeShape>(fx.shape)) {
      continue;
    }
    Collider c;
    c.shape = fx.shape;
    c.position = random_vector(rng, 1.0);
    c.orientation = rotation_at(2.0, rng);
    int tested = 0;
    for (int trial = 0; trial < 60; ++trial) {
      const Vector3 x = fx.propose(rng);
      const Probe pr = probe(fx.shape, x);
      if (pr.core < kCoreMargin || pr.seam < kSeamMargin) continue;
      // 1e-9 on either side of the surface, along the (exact) normal: the surface is no seam.
      const Vector3 p0 = c.position + c.orientation * x;
      const SdfValue at = c.evaluate(p0);
      for (const double gap : {1e-9, -1e-9}) {
        const Vector3 p = p0 - (at.distance - gap) * at.gradient;
        const Probe close = probe(fx.shape, c.orientation.transpose() * (p - c.position));
        if (close.core < kCoreMargin || close.seam < kSeamMargin) continue;  // walked to a rim
        SCOPED_TRACE(fx.name + ", " + close.region + fd::trace(", gap", gap));
        EXPECT_NEAR(c.evaluate(p).distance, gap, 1e-14);
        EXPECT_TRUE(check_derivatives(c, p, close.zero_hessian));
        expect_identities(c, p, close.distance);
        ++tested;
      }
    }
    EXPECT_GE(tested, 40) << fx.name;
    // 1e6 away: a larger step (the curvature is ~1e-6; its FD truncation ε²|∂⁴φ| ~ 1e-22).
    fd::FdOptions far;
    far.step = 1e-2;
    for (int i = 0; i < 10; ++i) {
      const Vector3 p = c.position + 1e6 * random_unit(rng);
      const SdfValue v = c.evaluate(p);
      SCOPED_TRACE(fx.name + fd::trace(", far", p.x(), p.y(), p.z()));
      EXPECT_NEAR(v.gradient.norm(), 1.0, 1e-12);
      EXPECT_LE((v.hessian * v.gradient).norm(), 1e-12 * v.hessian.norm());
      EXPECT_TRUE(fd::check_lie_gradient(
          [&c](const State& q) { return c.evaluate(q.points[0], false).distance; }, at_point(p),
          kPointDof, v.gradient, far));
      const bool cap = probe(fx.shape, c.orientation.transpose() * (p - c.position)).zero_hessian;
      if (cap) far.require_nonzero = fd::NonZero::kNone;
      EXPECT_TRUE(fd::check_lie_hessian(
          [&c](const State& q) { return Eigen::VectorXd(c.evaluate(q.points[0], false).gradient); },
          at_point(p), kPointDof, v.hessian, far));
      far.require_nonzero = fd::NonZero::kEveryBlock;
    }
  }
  // Both sides of each plane where ∇²φ jumps, 2e-3 off it (FD steps of 1e-6 stay on a side):
  // link x = ±L; cylinder |z| = h beside the side, s = ρ above a cap.
  const Collider link = make(LinkShape{0.5, 0.4, 0.12});
  const Collider cylinder = make(CylinderShape{0.7, 0.3});
  for (const double side : {2e-3, -2e-3}) {
    for (const Vector3& x : {Vector3(0.5 + side, 0.45, 0.1), Vector3(-0.5 - side, 0.2, -0.05),
                             Vector3(0.5 - side, -0.35, 0.02), Vector3(-0.5 + side, -0.9, 0.3)}) {
      SCOPED_TRACE(fd::trace("link", x.x(), x.y(), x.z()));
      EXPECT_TRUE(check_derivatives(link, x, false));
    }
    for (const Vector3& x : {Vector3(0.9, 0.2, 0.3 + side), Vector3(0.5, -0.8, -0.3 - side)}) {
      SCOPED_TRACE(fd::trace("cylinder side | rim", x.x(), x.y(), x.z()));
      EXPECT_TRUE(check_derivatives(cylinder, x, false));
    }
    const Vector3 above(0, 0.7 + side, 0.5);
    SCOPED_TRACE(fd::trace("cylinder cap | rim", above.x(), above.y(), above.z()));
    EXPECT_TRUE(check_derivatives(cylinder, above, side < 0.0));
  }
}

// ---------------------------------------------------------------------------------------
// validate()

std::string rejected_field(const Collider& c) {
  try {
    c.validate("colliders[0]");
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(e.field(), 0), 0u) << e.what();  // message names it
    return e.field();
  }
  return "(accepted)";
}

TEST(Sdf, ValidateRejectsEachBadField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto with = [](Shape s) { return make(std::move(s)); };
  EXPECT_EQ(rejected_field(with(PlaneShape{})), "(accepted)");
  EXPECT_EQ(rejected_field(with(SphereShape{1.0})), "(accepted)");
  EXPECT_EQ(rejected_field(with(BoxShape{Vector3(1, 2, 3), 0.99})), "(accepted)");
  EXPECT_EQ(rejected_field(with(CapsuleShape{0.0, 0.1})), "(accepted)");  // a sphere
  EXPECT_EQ(rejected_field(with(TubeShape{{{0, 0, 0}, {1, 0, 0}}, 0.1})), "(accepted)");
  EXPECT_EQ(rejected_field(with(TubeShape{curved_polyline(), 0.1})), "(accepted)");

  for (const double bad : {0.0, -1.0, nan, kInf}) {
    EXPECT_EQ(rejected_field(with(SphereShape{bad})), "colliders[0].radius") << bad;
    EXPECT_EQ(rejected_field(with(CapsuleShape{1.0, bad})), "colliders[0].radius") << bad;
    EXPECT_EQ(rejected_field(with(TubeShape{{{0, 0, 0}, {1, 0, 0}}, bad})), "colliders[0].radius");
    EXPECT_EQ(rejected_field(with(BoxShape{Vector3(1, bad, 1), 0.0})), "colliders[0].half_extents");
  }
  for (const double bad : {-0.1, 1.0, 1.5, nan, kInf}) {  // min half extent 1
    EXPECT_EQ(rejected_field(with(BoxShape{Vector3(2, 1, 3), bad})), "colliders[0].rounding");
  }
  for (const double bad : {-1.0, nan, kInf}) {
    EXPECT_EQ(rejected_field(with(CapsuleShape{bad, 0.1})), "colliders[0].half_length");
  }
  EXPECT_EQ(rejected_field(with(TubeShape{{{0, 0, 0}}, 0.1})), "colliders[0].polyline");
  EXPECT_EQ(rejected_field(with(TubeShape{{}, 0.1})), "colliders[0].polyline");
  EXPECT_EQ(rejected_field(with(TubeShape{{{0, 0, 0}, {1, 0, 0}, {1, 0, 0}}, 0.1})),
            "colliders[0].polyline[2]");  // zero-length segment
  EXPECT_EQ(rejected_field(with(TubeShape{{{0, 0, 0}, {1, nan, 0}}, 0.1})),
            "colliders[0].polyline[1]");
  EXPECT_EQ(rejected_field(with(TubeShape{{{0, 0, 0}, {1e300, 0, 0}}, 0.1})),
            "colliders[0].polyline[1]");  // ‖segment‖² overflows

  Collider c = with(SphereShape{1.0});
  c.position = Vector3(0, kInf, 0);
  EXPECT_EQ(rejected_field(c), "colliders[0].position");
  c.position.setZero();
  c.orientation(0, 0) = nan;
  EXPECT_EQ(rejected_field(c), "colliders[0].orientation");
  c.orientation = 1.01 * Matrix3::Identity();
  EXPECT_EQ(rejected_field(c), "colliders[0].orientation");
  c.orientation = Vector3(1, 1, -1).asDiagonal();  // a reflection
  EXPECT_EQ(rejected_field(c), "colliders[0].orientation");
  c.orientation = so3::exp(Vector3(0.3, -1, 2));
  EXPECT_EQ(rejected_field(c), "(accepted)");

  EXPECT_EQ(rejected_field(with(TorusShape{1.0, 0.999})), "(accepted)");
  EXPECT_EQ(rejected_field(with(LinkShape{0.0, 1.0, 0.5})), "(accepted)");  // a torus
  EXPECT_EQ(rejected_field(with(CylinderShape{1.0, 1e-3})), "(accepted)");
  for (const double bad : {0.0, -1.0, nan, kInf}) {
    EXPECT_EQ(rejected_field(with(TorusShape{bad, 0.1})), "colliders[0].major_radius") << bad;
    EXPECT_EQ(rejected_field(with(TorusShape{1.0, bad})), "colliders[0].minor_radius") << bad;
    EXPECT_EQ(rejected_field(with(LinkShape{0.5, bad, 0.1})), "colliders[0].major_radius") << bad;
    EXPECT_EQ(rejected_field(with(LinkShape{0.5, 1.0, bad})), "colliders[0].minor_radius") << bad;
    EXPECT_EQ(rejected_field(with(CylinderShape{bad, 1.0})), "colliders[0].radius") << bad;
    EXPECT_EQ(rejected_field(with(CylinderShape{1.0, bad})), "colliders[0].half_length") << bad;
  }
  for (const double bad : {-1.0, nan, kInf}) {
    EXPECT_EQ(rejected_field(with(LinkShape{bad, 1.0, 0.1})), "colliders[0].half_length") << bad;
  }
  // The shapes a body may have: solids, bounded, not complements; a mesh with its triangles.
  const auto body_field = [](const Collider& c) {
    try {
      validate_body_shape(c, "bodies[1].contact.shape");
    } catch (const ModelError& e) {
      return e.field();
    }
    return std::string("(accepted)");
  };
  for (const Shape& shape : {Shape(SphereShape{1.0}), Shape(BoxShape{Vector3(1, 2, 3), 0.5}),
                             Shape(CapsuleShape{1, 0.1}), Shape(TorusShape{1, 0.1}),
                             Shape(CylinderShape{1, 1}), Shape(LinkShape{1, 1, 0.1})}) {
    EXPECT_EQ(body_field(with(shape)), "(accepted)") << shape.index();
    EXPECT_EQ(body_field(make(shape, true)), "bodies[1].contact.shape.inside") << shape.index();
  }
  EXPECT_EQ(body_field(with(PlaneShape{})), "bodies[1].contact.shape.type");
  EXPECT_EQ(body_field(with(TubeShape{{{0, 0, 0}, {1, 0, 0}}, 0.1})), "bodies[1].contact.shape.type");
  EXPECT_EQ(body_field(with(MeshShape{})), "bodies[1].contact.shape.type");  // no triangles

  // The tube may not reach the axis (torus) or the segment (link): minor < major.
  for (const double minor : {1.0, 1.5}) {
    EXPECT_EQ(rejected_field(with(TorusShape{1.0, minor})), "colliders[0].minor_radius") << minor;
    EXPECT_EQ(rejected_field(with(LinkShape{0.5, 1.0, minor})), "colliders[0].minor_radius")
        << minor;
  }
}

// ---------------------------------------------------------------------------------------
// catmull_rom_polyline

TEST(Sdf, CatmullRomPassesThroughControlPointsWithTheRequestedCount) {
  std::mt19937 rng(21);
  std::vector<Vector3> control;
  for (int i = 0; i < 7; ++i) control.push_back(random_vector(rng, 1.0) + Vector3(i, 0, 0));
  for (const int samples : {1, 2, 5, 16}) {
    const std::vector<Vector3> line = catmull_rom_polyline(control, samples);
    ASSERT_EQ(line.size(), (control.size() - 1) * static_cast<std::size_t>(samples) + 1);
    for (std::size_t i = 0; i < control.size(); ++i) {
      EXPECT_EQ(line[i * static_cast<std::size_t>(samples)], control[i]) << i;
    }
    for (std::size_t k = 1; k < line.size(); ++k) EXPECT_GT((line[k] - line[k - 1]).norm(), 0.0);
    EXPECT_EQ(rejected_field(make(TubeShape{line, 0.05})), "(accepted)");
  }
  // Two points: a straight segment, sampled on the line.
  const std::vector<Vector3> two = catmull_rom_polyline({{0, 0, 0}, {2, 0, 0}}, 4);
  ASSERT_EQ(two.size(), 5u);
  for (const Vector3& p : two) EXPECT_LE(std::abs(p.y()) + std::abs(p.z()), 1e-15);
  // Points on a circle: the spline follows it closely (a smooth tube axis).
  std::vector<Vector3> circle;
  for (int i = 0; i < 9; ++i) {
    const double a = i * std::numbers::pi / 4;
    circle.emplace_back(std::cos(a), std::sin(a), 0.0);
  }
  const std::vector<Vector3> arc = catmull_rom_polyline(circle, 10);
  // Equally spaced points: centripetal knots are uniform, and the middle of a span is the
  // uniform Catmull–Rom midpoint (−P₀ + 9P₁ + 9P₂ − P₃)/16 (radius 0.9915 at 45° spacing).
  for (std::size_t span = 1; span + 2 < circle.size(); ++span) {
    const Vector3 mid =
        (-circle[span - 1] + 9 * circle[span] + 9 * circle[span + 1] - circle[span + 2]) / 16;
    expect_vector(arc[10 * span + 5], mid, 1e-15);
  }
  for (std::size_t k = 10; k + 10 < arc.size(); ++k) {  // interior spans (not the phantom ends)
    EXPECT_NEAR(arc[k].norm(), 1.0, 1e-2) << k;
  }
}

TEST(Sdf, CatmullRomRejectsBadInput) {
  EXPECT_THROW(catmull_rom_polyline({{0, 0, 0}}, 4), std::invalid_argument);
  EXPECT_THROW(catmull_rom_polyline({{0, 0, 0}, {1, 0, 0}}, 0), std::invalid_argument);
  EXPECT_THROW(catmull_rom_polyline({{0, 0, 0}, {1, 0, 0}, {1, 0, 0}}, 4), std::invalid_argument);
  EXPECT_THROW(catmull_rom_polyline({{0, 0, 0}, {kInf, 0, 0}}, 4), std::invalid_argument);
}

}  // namespace
}  // namespace liedyn::sdf_tests

// Cable segments (lib/cable.hpp; the point-pair mapping they share with Spring is in
// lib/point_pair.hpp): value vs Lie gradient vs Lie Hessian by finite differences in the
// tangent space (tests/fd_check.hpp) for segments between two (node, edge) frames, with a
// world anchor at either end, and with both routing points on one rotation; rotations at
// every angle of fd::kAngles; tensions 1e-9…1e6 N; segment lengths 1e-6…10 m on levers of a
// rod's size. Plus facts derived by hand: V = T l exactly, the tension derivative, the forces
// of a three-segment cable on its routing points, a rigid pair exerting nothing, the closed
// form of an indefinite Hessian, the degenerate (zero-length) segment, and input checks.
//
// Tolerances. fd_check's defaults assume that V varies on the scale of the FD step's unit
// (1 m, 1 rad) and that its round-off is ~eps·|V|. A short segment breaks both: V = T l
// varies on the scale l, and d = p_b − p_a is a small difference of positions and levers of
// size P ≫ l, so V carries round-off eps·T·P ≫ eps·|V|. fd_options() below sets the steps from
// l and derives the floors from T, l, P and the lever size; each is written out there.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "fd_check.hpp"
#include "lib/cable.hpp"
#include "lib/so3.hpp"

namespace liedyn {
namespace {

using fd::kAngles;
using fd::power_of_two_near;
using fd::random_unit;
using fd::random_vector;
using fd::rotation_at;
using fd::trace;
using fd::kPi;
using fd::kEps;

const std::vector<double> kTensions = {1e-9, 1.0, 1e6};             // N
const std::vector<double> kLengths = {1e-6, 1e-3, 0.1, 1.0, 10.0};  // m

// A routing point's offset in its edge's material frame (paper §7.4): at radius ρ, at one of
// the four cable angles around the cross-section, at s along the edge.
Vector3 routing_offset(double radius, std::mt19937& rng) {
  std::uniform_int_distribution<int> quarter(0, 3);
  std::uniform_real_distribution<double> along(-0.5, 0.5);
  const double phi = 0.5 * kPi * quarter(rng);
  return Vector3(radius * std::cos(phi), radius * std::sin(phi), along(rng));
}

enum class Ends {
  kTwoFrames,    // a on (node 0, edge 0), b on (node 1, edge 1)
  kOneRotation,  // a on (node 0, edge 0), b on (node 1, edge 0): two offsets on one rotation
  kAnchorA,      // a a world anchor, b on (node 1, edge 1)
  kAnchorB,      // a on (node 0, edge 0), b a world anchor
};

struct CableCase {
  CableSegment term;
  State q;
  fd::Dofs dofs;                      // one per distinct DOF
  std::array<int, 4> block_to_dof{};  // the term's block i is dofs[block_to_dof[i]] (−1: none)
  double length = 0.0;                // the designed ‖p_b − p_a‖
};

// A segment of length l along a random direction: node 0 and the rotations are random, b's
// node is placed so that p_b = p_a + l u.
CableCase make_cable(Ends ends, double tension, double l, double angle_a, double angle_b,
                     std::mt19937& rng) {
  CableCase c;
  c.q.points = {random_vector(rng, 1.0), Vector3::Zero()};
  c.q.rotations = {rotation_at(angle_a, rng), rotation_at(angle_b, rng)};
  c.term.tension = tension;
  c.term.a = {0, 0, routing_offset(0.3, rng)};
  c.term.b = {1, 1, routing_offset(0.3, rng)};
  c.dofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1), fd::rotation_dof(1)};
  c.block_to_dof = {0, 1, 2, 3};
  if (ends == Ends::kOneRotation) {
    c.term.b.rotation = 0;
    c.dofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1)};
    c.block_to_dof = {0, 1, 2, 1};
  }
  if (ends == Ends::kAnchorA) {
    c.term.a = {-1, -1, random_vector(rng, 1.0)};
    c.dofs[0] = c.dofs[1] = fd::no_dof();
    c.block_to_dof = {-1, -1, 2, 3};
  }
  const Vector3 p_b = c.term.a.position(c.q) + l * random_unit(rng);
  if (ends == Ends::kAnchorB) {
    c.term.b = {-1, -1, p_b};
    c.dofs[2] = c.dofs[3] = fd::no_dof();
    c.block_to_dof = {0, 1, -1, -1};
  } else {
    c.q.points[1] = p_b - c.term.b.lever(c.q);
  }
  c.length = l;
  return c;
}

// The term's local gradient and Hessian added onto its distinct DOFs, as assembly does with
// offsets (blocks of one rotation are summed).
Eigen::VectorXd fold(const LocalGradient<4>& g, const std::array<int, 4>& map, Eigen::Index n) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < 4; ++i) {
    if (map[i] >= 0) out.segment<3>(3 * map[i]) += g.segment<3>(3 * i);
  }
  return out;
}

Eigen::MatrixXd fold(const LocalHessian<4>& H, const std::array<int, 4>& map, Eigen::Index n) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      if (map[i] >= 0 && map[j] >= 0) {
        out.block<3, 3>(3 * map[i], 3 * map[j]) += H.block<3, 3>(3 * i, 3 * j);
      }
    }
  }
  return out;
}

// Size P of the quantities d = (x_b + r_b) − (x_a + r_a) is computed from, and the largest
// lever R (the rotation blocks' ∂d/∂θ = ±hat(r)).
double quantity_size(const CableCase& c) {
  double P = 0.0;
  for (const AttachedPoint* p : {&c.term.a, &c.term.b}) {
    P = std::max({P, p->position(c.q).norm(), p->lever(c.q).norm()});
    if (p->point >= 0) P = std::max(P, c.q.points[p->point].norm());
  }
  return P;
}

double lever_size(const CableCase& c) {
  return std::max(c.term.a.lever(c.q).norm(), c.term.b.lever(c.q).norm());
}

// FD steps and floors for a segment of length l, levers ≤ R, quantities ≤ P, tension T.
//   Steps: V varies on the scale l, so ε = min(fd default, 1e-3 l) for first differences and
//   min(fd default, 1e-2 l) for second differences of the value.
//   Truncation: the k-th derivative of ‖d‖ is ~1/l^(k−1), and ∂d/∂δ has size ≤ 1 + R, so the
//   k-th derivatives of V along the tangent are ≲ T (1 + R)^k / l^(k−1). Central differences
//   err by ≈ ε²/6 of the next derivative: relative to the compared object (the gradient is at
//   least T/√3 in its largest entry, the Hessian T/l·⅔ in its K block) that is
//   ≲ (ε/l)² (1 + R)⁴ for all three checks: the relative floor, when above fd's default.
//   Round-off: V = T‖d‖ with d in error by ~eps·P per evaluation (not eps·|V|: fd's own noise
//   floor underestimates it for l ≪ P); first differences: 16 eps T P/ε; second
//   differences: 16 eps T P/ε². The gradient T Jdᵀ n has n = d/l in error by ~eps·P/l, so its
//   differences carry 16 eps T (1 + R)(P/l + 1)/ε.
fd::TermCheckOptions fd_options(const CableCase& c) {
  const double T = c.term.tension, l = c.length, P = quantity_size(c);
  const double R = lever_size(c);
  const double R4 = std::pow(1.0 + R, 4);
  fd::TermCheckOptions opt;
  for (fd::FdOptions* o : {&opt.gradient, &opt.hessian}) {
    o->step = std::min(o->step, 1e-3 * l);
    o->floor = std::max(o->floor, (o->step / l) * (o->step / l) * R4);
  }
  opt.gradient.abs_floor = fd::noise_of(T * P, opt.gradient.step);
  opt.hessian.abs_floor = fd::noise_of(T * (1.0 + R) * (P / l + 1.0), opt.hessian.step);
  fd::FdOptions& v = opt.hessian_from_value;
  v.step = std::min(v.step, 1e-2 * l);
  v.floor = std::max(v.floor, (v.step / l) * (v.step / l) * R4);
  v.abs_floor = fd::noise_of(T * P, v.step * v.step);
  return opt;
}

// check_term, on the distinct DOFs (folded blocks) when the term's blocks share one.
::testing::AssertionResult check_cable(const CableCase& c, const fd::TermCheckOptions& opt) {
  if (c.dofs.size() == 4) {  // one DOF per block (or none: anchors)
    return fd::check_term(c.term, c.q, c.dofs, opt);
  }
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(c.dofs.size());
  const fd::ScalarFunction f = [&](const State& s) { return c.term.evaluate(s, nullptr, nullptr); };
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<4> gs;
    c.term.evaluate(s, &gs, nullptr);
    return fold(gs, c.block_to_dof, n);
  };
  LocalGradient<4> g;
  LocalHessian<4> H;
  c.term.evaluate(c.q, &g, &H);
  const Eigen::MatrixXd Hf = fold(H, c.block_to_dof, n);
  ::testing::AssertionResult r =
      fd::check_lie_gradient(f, c.q, c.dofs, fold(g, c.block_to_dof, n), opt.gradient);
  if (!r) return r;
  r = fd::check_lie_hessian(grad, c.q, c.dofs, Hf, opt.hessian);
  if (!r) return r;
  return fd::check_lie_hessian_from_value(f, c.q, c.dofs, Hf, opt.hessian_from_value);
}

// ----------------------------------------------------------------------------------------
// The checks catch the mistakes they are there for.

TEST(CableFdCheck, RejectsTransposedLeversAndWrongCurvatureSign) {
  // A transposed hat(r) in ∂d/∂θ = [hat(r_a), −hat(r_b)] is −hat(r): it negates the rotation
  // blocks of the gradient and the x–θ blocks of the Hessian (the θθ part Jdᵀ K Jd is even in
  // it). The eq. (23) term taken with ∂V/∂p_a = +f instead of −f changes the θ_aθ_a block by
  // 2 C(r_a, f). Each must fail its check, at an ordinary and at a short segment.
  std::mt19937 rng(300);
  for (const double l : {1.0, 1e-3}) {
    SCOPED_TRACE(trace("length", l));
    const CableCase c = make_cable(Ends::kTwoFrames, 2.0, l, 1.0, 2.5, rng);
    const fd::TermCheckOptions opt = fd_options(c);
    ASSERT_TRUE(check_cable(c, opt));
    LocalGradient<4> g;
    LocalHessian<4> H;
    c.term.evaluate(c.q, &g, &H);
    const fd::ScalarFunction f = [&](const State& s) {
      return c.term.evaluate(s, nullptr, nullptr);
    };
    const fd::GradientFunction grad = [&](const State& s) {
      LocalGradient<4> gs;
      c.term.evaluate(s, &gs, nullptr);
      return Eigen::VectorXd(gs);
    };
    LocalGradient<4> g_transposed = g;
    g_transposed.segment<3>(3) *= -1.0;
    g_transposed.segment<3>(9) *= -1.0;
    LocalHessian<4> H_transposed = H;
    for (const int x : {0, 6}) {
      for (const int t : {3, 9}) {
        H_transposed.block<3, 3>(x, t) *= -1.0;
        H_transposed.block<3, 3>(t, x) *= -1.0;
      }
    }
    EXPECT_FALSE(fd::check_lie_gradient(f, c.q, c.dofs, g_transposed, opt.gradient));
    EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, H_transposed, opt.hessian));
    EXPECT_FALSE(
        fd::check_lie_hessian_from_value(f, c.q, c.dofs, H_transposed, opt.hessian_from_value));

    const Vector3 d = c.term.b.position(c.q) - c.term.a.position(c.q);
    const Vector3 f_d = c.term.tension * d.normalized();
    LocalHessian<4> H_sign = H;
    H_sign.block<3, 3>(3, 3) += 2.0 * rotated_point_curvature(c.term.a.lever(c.q), f_d);
    EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, H_sign, opt.hessian));
    EXPECT_FALSE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, H_sign, opt.hessian_from_value));
  }
}

// ----------------------------------------------------------------------------------------
// Value, Lie gradient and Lie Hessian against finite differences.

TEST(CableSegmentTerm, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(301);
  int checked = 0;
  for (const Ends ends : {Ends::kTwoFrames, Ends::kAnchorA, Ends::kAnchorB}) {
    for (const double T : kTensions) {
      for (const double l : kLengths) {
        for (size_t i = 0; i < kAngles.size(); ++i) {
          const double angle_a = kAngles[i], angle_b = kAngles[(i + 4) % kAngles.size()];
          SCOPED_TRACE(trace("ends, T, l", static_cast<double>(ends), T, l));
          SCOPED_TRACE(trace("angles", angle_a, angle_b));
          const CableCase c = make_cable(ends, T, l, angle_a, angle_b, rng);
          EXPECT_TRUE(check_cable(c, fd_options(c)));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * static_cast<int>(kTensions.size() * kLengths.size() * kAngles.size()));
}

TEST(CableSegmentTerm, TwoOffsetsOnOneRotationMatchFiniteDifferences) {
  // Routing points on nodes 0 and 1, both through edge 0's rotation: the term's two θ blocks
  // name one DOF and are summed (as assembly does), then checked against FD of that DOF.
  std::mt19937 rng(302);
  int checked = 0;
  for (const double T : kTensions) {
    for (const double l : kLengths) {
      for (const double angle : kAngles) {
        SCOPED_TRACE(trace("T, l, angle", T, l, angle));
        const CableCase c = make_cable(Ends::kOneRotation, T, l, angle, 0.0, rng);
        ASSERT_EQ(c.dofs.size(), 3u);
        EXPECT_TRUE(check_cable(c, fd_options(c)));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, static_cast<int>(kTensions.size() * kLengths.size() * kAngles.size()));
}

TEST(CableSegmentTerm, RigidPairOnOneFrameExertsNothing) {
  // Both routing points on the same (node, edge): d = R (p̄_b − p̄_a) has a constant length,
  // so V is constant and its folded Lie gradient and Hessian vanish. By hand: the θθ sum is
  // hat(d)ᵀ K hat(d) = T l (I − n nᵀ) from Jdᵀ K Jd, cancelled exactly by the eq. (23) terms
  // C(r_a, −f) + C(r_b, f) = ½(f dᵀ + d fᵀ) − (f·d) I = −T l (I − n nᵀ). A wrong sign of
  // either eq. (23) term leaves 2 C(r, f) ≠ 0. Tolerance: cancellation of entries of size
  // ≤ max|H|, max|g|, a few dozen eps of them.
  std::mt19937 rng(303);
  for (const double T : kTensions) {
    for (const double angle : kAngles) {
      SCOPED_TRACE(trace("T, angle", T, angle));
      CableSegment term;
      term.tension = T;
      term.a = {0, 0, routing_offset(0.3, rng)};
      term.b = {0, 0, routing_offset(0.3, rng) + Vector3(0.0, 0.0, 0.7)};
      State q;
      q.points = {random_vector(rng, 1.0)};
      q.rotations = {rotation_at(angle, rng)};
      LocalGradient<4> g;
      LocalHessian<4> H;
      term.evaluate(q, &g, &H);
      const std::array<int, 4> map = {0, 1, 0, 1};
      const Eigen::VectorXd gf = fold(g, map, 6);
      const Eigen::MatrixXd Hf = fold(H, map, 6);
      ASSERT_GT(g.cwiseAbs().maxCoeff(), 0.1 * T);  // the unfolded blocks are not zero
      ASSERT_GT(H.cwiseAbs().maxCoeff(), 0.1 * T);
      EXPECT_LE(gf.cwiseAbs().maxCoeff(), 32 * kEps * g.cwiseAbs().maxCoeff());
      EXPECT_LE(Hf.cwiseAbs().maxCoeff(), 32 * kEps * H.cwiseAbs().maxCoeff());
    }
  }
}

// ----------------------------------------------------------------------------------------
// Facts derived by hand.

TEST(CableSegmentTerm, ValueIsTensionTimesLength) {
  // V = T ‖p_b − p_a‖ with or without derivatives, bit for bit (same expression), and l is
  // the designed length up to the round-off of placing node 1 (~eps·P).
  std::mt19937 rng(304);
  for (const Ends ends : {Ends::kTwoFrames, Ends::kOneRotation, Ends::kAnchorA, Ends::kAnchorB}) {
    for (const double T : kTensions) {
      for (const double l : kLengths) {
        SCOPED_TRACE(trace("ends, T, l", static_cast<double>(ends), T, l));
        const CableCase c = make_cable(ends, T, l, 1.0, 2.0, rng);
        const double length = (c.term.b.position(c.q) - c.term.a.position(c.q)).norm();
        LocalGradient<4> g;
        LocalHessian<4> H;
        EXPECT_EQ(c.term.evaluate(c.q, nullptr, nullptr), T * length);
        EXPECT_EQ(c.term.evaluate(c.q, &g, &H), T * length);
        EXPECT_EQ(c.term.evaluate(c.q, &g, nullptr), T * length);
        EXPECT_LE(std::abs(length - l), 16 * kEps * quantity_size(c));
      }
    }
  }
}

TEST(CableSegmentTerm, TensionGradientIsGradientPerUnitTension) {
  // V is linear in T, so central differences in T have no truncation error (any step h):
  // they differ from ∂(Lie gradient)/∂T by the round-off of the two gradients only, each
  // ~eps·(T + h)·|∂g/∂T|, over 2h: with h = T/4, ~2.5 eps·|∂g/∂T|. And g = T·tension_gradient
  // exactly when T is a power of two (every scaling by T is then exact), to a few eps
  // otherwise (the rounding of T n, carried through Jdᵀ).
  std::mt19937 rng(305);
  for (const Ends ends : {Ends::kTwoFrames, Ends::kOneRotation, Ends::kAnchorA, Ends::kAnchorB}) {
    for (const double T : kTensions) {
      for (const double l : kLengths) {
        SCOPED_TRACE(trace("ends, T, l", static_cast<double>(ends), T, l));
        CableCase c = make_cable(ends, T, l, 0.5, 2.5, rng);
        const LocalGradient<4> dg_dT = c.term.tension_gradient(c.q);
        // The x blocks are ∓n: the derivative is far from zero.
        ASSERT_GT(dg_dT.cwiseAbs().maxCoeff(), 0.5);

        const double h = 0.25 * T;
        LocalGradient<4> g_plus, g_minus;
        CableSegment shifted = c.term;
        shifted.tension = T + h;
        shifted.evaluate(c.q, &g_plus, nullptr);
        shifted.tension = T - h;
        shifted.evaluate(c.q, &g_minus, nullptr);
        const LocalGradient<4> fd_dT = (g_plus - g_minus) / (2.0 * h);
        EXPECT_LE((fd_dT - dg_dT).cwiseAbs().maxCoeff(), 16 * kEps * dg_dT.cwiseAbs().maxCoeff());

        // g / T, for T a power of two (exact) and for T itself.
        c.term.tension = power_of_two_near(T);
        LocalGradient<4> g;
        c.term.evaluate(c.q, &g, nullptr);
        EXPECT_EQ(g / c.term.tension, dg_dT);
        c.term.tension = T;
        c.term.evaluate(c.q, &g, nullptr);
        EXPECT_LE((g / T - dg_dT).cwiseAbs().maxCoeff(), 8 * kEps * dg_dT.cwiseAbs().maxCoeff());
        // The tension is restored: tension_gradient did not depend on it.
        EXPECT_EQ(c.term.tension_gradient(c.q), dg_dT);
      }
    }
  }
}

TEST(CableSegmentTerm, ThreeSegmentCablePullsRoutingPointsTowardsNeighbours) {
  // Routing points p_0 (a world anchor at the cable's root), p_1, p_2, p_3 on (node j, edge
  // j), j = 1…3, segments (p_0,p_1), (p_1,p_2), (p_2,p_3). The force on a middle point p_j is
  // F_j = T (n_prev + n_next), the unit vectors towards its neighbours, so the summed gradient
  // of its blocks is ∂V/∂x_j = −F_j, DV/DR_j = −r_j × F_j (the torque about x_j, eq. 22); the
  // free end p_3 feels T n towards p_2 only. Tolerance: sums of a few products of O(1)
  // numbers with T: a few dozen eps·T·(1 + |r|).
  std::mt19937 rng(306);
  for (const double T : kTensions) {
    for (const double angle : kAngles) {
      SCOPED_TRACE(trace("T, angle", T, angle));
      State q;
      q.points = {Vector3::Zero()};  // node 0 is not used: p_0 is a world anchor
      q.rotations = {Matrix3::Identity()};
      std::vector<AttachedPoint> route = {{-1, -1, Vector3(0.1, 0.2, -0.3)}};
      for (int j = 1; j <= 3; ++j) {
        q.points.push_back(Vector3(0.0, 0.0, 0.4 * j) + random_vector(rng, 0.1));
        q.rotations.push_back(rotation_at(angle, rng));
        route.push_back({j, j, routing_offset(0.05, rng)});
      }
      // Per-block gradient sums over the 3 nodes and 3 rotations (tangent index 6(j−1) + …).
      Eigen::Matrix<double, 18, 1> grad = Eigen::Matrix<double, 18, 1>::Zero();
      double value = 0.0;
      for (int s = 0; s < 3; ++s) {
        CableSegment seg;
        seg.tension = T;
        seg.a = route[s];
        seg.b = route[s + 1];
        LocalGradient<4> g;
        value += seg.evaluate(q, &g, nullptr);
        for (int end = 0; end < 2; ++end) {
          const int j = s + end;  // routing point index
          if (j == 0) continue;   // the anchor
          grad.segment<3>(6 * (j - 1)) += g.segment<3>(6 * end);
          grad.segment<3>(6 * (j - 1) + 3) += g.segment<3>(6 * end + 3);
        }
      }
      std::vector<Vector3> p;
      for (const AttachedPoint& r : route) p.push_back(r.position(q));
      const auto unit = [](const Vector3& v) { return Vector3(v / v.norm()); };
      EXPECT_NEAR(value, T * ((p[1] - p[0]).norm() + (p[2] - p[1]).norm() + (p[3] - p[2]).norm()),
                  8 * kEps * value);
      for (int j = 1; j <= 3; ++j) {
        Vector3 F = T * unit(p[j - 1] - p[j]);
        if (j < 3) F += T * unit(p[j + 1] - p[j]);
        const Vector3 r = route[j].lever(q);
        const double tol = 32 * kEps * T * (1.0 + r.norm());
        EXPECT_LE((grad.segment<3>(6 * (j - 1)) + F).norm(), tol) << "routing point " << j;
        EXPECT_LE((grad.segment<3>(6 * (j - 1) + 3) + r.cross(F)).norm(), tol)
            << "routing point " << j;
        EXPECT_GT(F.norm(), 0.1 * T);  // the comparison is not between zeros
      }
    }
  }
}

TEST(CableSegmentTerm, LeverAlongTheCableGivesTheClosedFormIndefiniteHessian) {
  // b's lever points along the cable, away from a: r_b = ρ n, n = d/l. Rotating edge b moves
  // p_b on a sphere about x_b on which p_b is the farthest point from p_a: V has a maximum in
  // θ_b's directions ⊥ n (a pulled lever flips). By hand, with hat(r)ᵀ(I − n nᵀ)hat(r) =
  // ρ²(I − n nᵀ) and C(r, T n) = T ρ (n nᵀ − I):
  //   H_θbθb = Jdᵀ K Jd + C = (T ρ²/l − T ρ)(I − n nᵀ),  negative for ρ < l,
  // while the d part Jdᵀ K Jd of the whole Hessian is PSD. So the Lie Hessian is indefinite
  // (cable.hpp: Newton regularises). Tolerance: a few dozen eps of the entries' size.
  std::mt19937 rng(307);
  for (const double angle : kAngles) {
    SCOPED_TRACE(trace("angle", angle));
    const double T = 3.0, l = 0.8, rho = 0.25;
    CableSegment term;
    term.tension = T;
    State q;
    q.points = {random_vector(rng, 1.0), Vector3::Zero()};
    q.rotations = {rotation_at(1.2, rng), rotation_at(angle, rng)};
    term.a = {0, 0, routing_offset(0.3, rng)};
    const Vector3 n = random_unit(rng);
    const Vector3 p_b = term.a.position(q) + l * n;
    term.b = {1, 1, q.rotations[1].transpose() * (rho * n)};  // R_b p̄_b = ρ n
    q.points[1] = p_b - q.rotations[1] * term.b.local;
    LocalHessian<4> H;
    term.evaluate(q, nullptr, &H);
    const Matrix3 P = Matrix3::Identity() - n * n.transpose();
    const Matrix3 expected = (T * rho * rho / l - T * rho) * P;
    EXPECT_LE((H.block<3, 3>(9, 9) - expected).cwiseAbs().maxCoeff(), 32 * kEps * T);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(H)};
    EXPECT_LT(eig.eigenvalues().minCoeff(), -0.1 * T * rho);

    // The K part alone, Jdᵀ K Jd: the Hessian minus the eq. (23) terms, PSD.
    const Vector3 f = T * n;
    LocalHessian<4> HK = H;
    HK.block<3, 3>(3, 3) -= rotated_point_curvature(term.a.lever(q), -f);
    HK.block<3, 3>(9, 9) -= rotated_point_curvature(term.b.lever(q), f);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig_K{Eigen::MatrixXd(HK)};
    EXPECT_GE(eig_K.eigenvalues().minCoeff(), -64 * kEps * HK.cwiseAbs().maxCoeff());
  }
}

TEST(CableSegmentTerm, DegenerateSegmentHasZeroGradientAndFiniteHessian) {
  // l = 0: V = T‖d‖ is a cone, not differentiable. cable.hpp's choice: gradient 0 (the
  // smallest element of the generalised gradient, the ball of radius T) and Hessian 0 (no
  // bounded curvature exists). Exactly coincident points, three ways: one attached point used
  // twice; two different (node, edge) frames in identical states; an anchor on a node.
  // Beside them, a segment 1e-9 m long: the ordinary branch, gradient of size T.
  std::mt19937 rng(308);
  for (const double T : kTensions) {
    for (const double angle : kAngles) {
      SCOPED_TRACE(trace("T, angle", T, angle));
      State q;
      q.rotations = {rotation_at(angle, rng), Matrix3::Identity()};
      q.rotations[1] = q.rotations[0];
      q.points = {random_vector(rng, 1.0), Vector3::Zero()};
      q.points[1] = q.points[0];
      const Vector3 local = routing_offset(0.3, rng);
      std::vector<CableSegment> segments(3);
      segments[0].a = segments[0].b = {0, 0, local};
      segments[1].a = {0, 0, local};
      segments[1].b = {1, 1, local};
      segments[2].a = {-1, -1, q.points[0]};
      segments[2].b = {0, -1, Vector3::Zero()};
      for (CableSegment& s : segments) {
        s.tension = T;
        ASSERT_EQ(s.b.position(q), s.a.position(q));
        LocalGradient<4> g;
        LocalHessian<4> H;
        EXPECT_EQ(s.evaluate(q, &g, &H), 0.0);
        EXPECT_TRUE(g.isZero(0.0));
        EXPECT_TRUE(H.allFinite());
        EXPECT_TRUE(H.isZero(0.0));
        EXPECT_TRUE(s.tension_gradient(q).isZero(0.0));
      }
      CableSegment near = segments[1];
      q.points[1] += 1e-9 * random_unit(rng);
      LocalGradient<4> g;
      LocalHessian<4> H;
      near.evaluate(q, &g, &H);
      EXPECT_NEAR(g.segment<3>(6).norm(), T, 1e-6 * T);  // |T n|, n in error by ~eps/1e-9
      EXPECT_TRUE(H.allFinite());
    }
  }
}

TEST(CableSegment, ValidateRejectsNegativeAndNonFiniteTension) {
  CableSegment s;
  for (const double T : {0.0, 1e-300, 1.0, 1e6}) {
    s.tension = T;
    EXPECT_NO_THROW(s.validate()) << T;
  }
  for (const double T : {-1e-300, -1.0, std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity()}) {
    s.tension = T;
    try {
      s.validate();
      ADD_FAILURE() << "accepted tension " << T;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("tension"), std::string::npos) << what;
      EXPECT_NE(what.find(">= 0"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace liedyn

// Joint limits (lib/joint_limits.hpp): the coordinates HingeAngle ξ = atan2(v·w, u·w) and
// SliderPosition ξ = n·(p_a − p_b) − ξ₀, and the one-sided term JointLimit on g = σ(ξ − bound).
//  * ξ itself: its value against its definition (the turn of a about its axis relative to b,
//    continued across turns from the angle at the start of the step; a's place along the rail),
//    and its Lie gradient and Hessian by central finite differences in the tangent space
//    (tests/fd_check.hpp, left perturbations R ← exp(εe_j)R) — a's rotation at every angle of
//    fd::kAngles, the relative turn at 0, 1e-9, 1e-4, 1, π − 1e-6, π, 2π − 1e-6 and 3π + 0.3
//    (a later turn), b's reference tilted out of a's plane, end b a body or the world (hinge);
//    end b a body, the world or a rod node (slider).
//  * JointLimit, elastic (½k max(0, g)²) and exact (½ρ max(0, g + s)², shift s ≥ 0), upper and
//    lower bound, on both sides of the switch (g = ±1e-2 and ±0.3: inactive exactly zero,
//    active by FD), stiffnesses 1e-6, 1, 1e9; its least-squares form, force, violation
//    |max(g, −s)|, multiplier update and constraint (g where active, its Jacobian by FD); the
//    adjoint Lagrangian λg + ½ρg² (active iff λ > 0; its Hessian taken at g = 0, as the
//    header says).
//  * That the checks reject a Hessian without the BCH half-commutator of the hinge's mixed
//    block, and one without the slider's rotated-axis curvature.
// Tolerances are fd_check.hpp's unless stated next to the check.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "fd_check.hpp"
#include "lib/joint_limits.hpp"
#include "lib/so3.hpp"

namespace liedyn::joint_limits_tests {
namespace {

using fd::random_perpendicular;
using fd::random_unit;
using fd::rotation_at;
using fd::trace;
using fd::kPi;
using fd::kEps;

// Relative turns of the hinge: the extremes of atan2's branch (π) and of a turn (2π), and one
// on the second turn, reached through `previous`.
const std::vector<double> kTurns = {0.0, 1e-9, 1e-4, 1.0, kPi - 1e-6, kPi, 2 * kPi - 1e-6,
                                    3 * kPi + 0.3};
const std::vector<double> kStiffnesses = {1e-6, 1.0, 1e9};

// A coordinate seen as a term (value, Lie gradient, Lie Hessian), for fd::check_term.
template <class Coordinate>
struct CoordinateProbe {
  static constexpr int kBlocks = Coordinate::kBlocks;
  Coordinate coordinate;
  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
    return coordinate.value(q, g, H);
  }
};

template <class Coordinate>
struct Case {
  Coordinate coordinate;
  State q;
  fd::Dofs dofs;
  double expected = 0.0;  // ξ from its definition
};

// Hinge: a is rotation 0 at `angle_a`, b rotation 1 at `angle_b` or the world. b's reference
// w = cos β (cos ψ u + sin ψ v) + sin β n: the turn ψ and the tilt β out of a's plane
// (ρ = cos β). `previous` = ψ picks ψ's turn.
Case<HingeAngle> hinge_case(double angle_a, double angle_b, double turn, double tilt, bool world_b,
                            std::mt19937& rng) {
  Case<HingeAngle> c;
  HingeAngle& h = c.coordinate;
  c.q.rotations = {rotation_at(angle_a, rng)};
  h.rotation_a = 0;
  h.axis_a = random_unit(rng);
  h.reference_a = random_perpendicular(h.axis_a, rng);
  const Matrix3& R_a = c.q.rotations[0];
  const Vector3 n = R_a * h.axis_a, u = R_a * h.reference_a, v = u.cross(n);
  const Vector3 w =
      std::cos(tilt) * (std::cos(turn) * u + std::sin(turn) * v) + std::sin(tilt) * n;
  if (world_b) {
    h.rotation_b = -1;
    h.reference_b = w;
    c.dofs = {fd::rotation_dof(0), fd::no_dof()};
  } else {
    h.rotation_b = 1;
    c.q.rotations.push_back(rotation_at(angle_b, rng));
    h.reference_b = c.q.rotations[1].transpose() * w;
    c.dofs = {fd::rotation_dof(0), fd::rotation_dof(1)};
  }
  h.previous = turn;
  c.expected = turn;
  return c;
}

enum class SliderEndB { kBody, kWorld, kRodNode };

// Slider: a is point 0 with rotation 0 (at `angle_a`), lever 0.5; b point 1 with rotation 1
// (`angle_b`), a world anchor or a rod node. Blocks (x_a, θ_a, x_b, θ_b).
Case<SliderPosition> slider_case(SliderEndB end_b, double angle_a, double angle_b,
                                 std::mt19937& rng) {
  Case<SliderPosition> c;
  SliderPosition& s = c.coordinate;
  c.q.points = {fd::random_vector(rng, 1.0), fd::random_vector(rng, 1.0)};
  c.q.rotations = {rotation_at(angle_a, rng), rotation_at(angle_b, rng)};
  s.a = {0, 0, 0.5 * random_unit(rng)};
  s.axis_a = random_unit(rng);
  s.origin = 0.3;
  c.dofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1), fd::rotation_dof(1)};
  switch (end_b) {
    case SliderEndB::kBody:
      s.b = {1, 1, 0.5 * random_unit(rng)};
      break;
    case SliderEndB::kWorld:
      s.b = {-1, -1, fd::random_vector(rng, 1.0)};
      c.dofs[2] = c.dofs[3] = fd::no_dof();
      break;
    case SliderEndB::kRodNode:
      s.b = {1, -1, 0.5 * random_unit(rng)};
      c.dofs[3] = fd::no_dof();
      break;
  }
  // ξ from the definition p = x + R p̄ (not through AttachedPoint::position).
  const auto p = [&](const AttachedPoint& e) {
    if (e.point < 0) return Vector3(e.local);
    if (e.rotation < 0) return Vector3(c.q.points[e.point] + e.local);
    return Vector3(c.q.points[e.point] + c.q.rotations[e.rotation] * e.local);
  };
  c.expected = (c.q.rotations[0] * s.axis_a).dot(p(s.a) - p(s.b)) - s.origin;
  return c;
}

// Every hinge case: a's rotation over fd::kAngles, b's over the same list shifted, each turn,
// tilts 0, 0.7 and 1.5 (ρ = 0.07: derivatives ~1/ρ, 1/ρ²), b a body or the world.
template <class F>
void for_each_hinge_case(F&& f) {
  std::mt19937 rng(811);
  const std::vector<double>& angles = fd::kAngles;
  for (const bool world_b : {false, true}) {
    for (size_t i = 0; i < angles.size(); ++i) {
      for (const double turn : kTurns) {
        for (const double tilt : {0.0, 0.7, 1.5}) {
          SCOPED_TRACE(trace("angle a, angle b, world b", angles[i],
                             angles[(i + 3) % angles.size()], world_b));
          SCOPED_TRACE(trace("turn, tilt", turn, tilt));
          f(hinge_case(angles[i], angles[(i + 3) % angles.size()], turn, tilt, world_b, rng), tilt);
        }
      }
    }
  }
}

template <class F>
void for_each_slider_case(F&& f) {
  std::mt19937 rng(823);
  const std::vector<double>& angles = fd::kAngles;
  for (const SliderEndB end_b : {SliderEndB::kBody, SliderEndB::kWorld, SliderEndB::kRodNode}) {
    for (size_t i = 0; i < angles.size(); ++i) {
      SCOPED_TRACE(trace("end b, angle a, angle b", static_cast<double>(end_b), angles[i],
                         angles[(i + 4) % angles.size()]));
      f(slider_case(end_b, angles[i], angles[(i + 4) % angles.size()], rng));
    }
  }
}

// ========================================================================================
// The coordinates.

TEST(JointLimitHingeAngle, ValueIsTheTurnAboutTheAxisAndDerivativesMatchFiniteDifferences) {
  int checked = 0;
  for_each_hinge_case([&](const Case<HingeAngle>& c, double) {
    const double xi = c.coordinate.value(c.q, nullptr, nullptr);
    EXPECT_NEAR(xi, c.expected, 64 * kEps * (1.0 + std::abs(c.expected)));
    const CoordinateProbe<HingeAngle> probe{c.coordinate};
    fd::TermCheckOptions opt;
    opt.hessian.require_nonzero = fd::NonZero::kAny;
    EXPECT_TRUE(fd::check_term(probe, c.q, c.dofs, opt));
    ++checked;
  });
  EXPECT_EQ(checked, 2 * 9 * 8 * 3);
}

TEST(JointLimitHingeAngle, ContinuesAcrossTurnsFromTheStartOfEachStep) {
  // A wheel a turning about its axis by 0.3 rad per step relative to a tilted, turned b, for
  // 3.5 turns each way: with begin_step at every step ξ is the accumulated turn (atan2 alone
  // would fall back by 2π at every half turn).
  std::mt19937 rng(829);
  for (const double direction : {1.0, -1.0}) {
    Case<HingeAngle> c = hinge_case(1.0, 2.0, 0.0, 0.4, false, rng);
    const Matrix3 R_a0 = c.q.rotations[0];
    const Vector3 n = R_a0 * c.coordinate.axis_a;
    c.coordinate.begin_step(c.q);
    EXPECT_NEAR(c.coordinate.previous, 0.0, 64 * kEps);
    for (int step = 1; step <= 73; ++step) {
      const double turn = direction * 0.3 * step;
      State q = c.q;
      q.rotations[0] = so3::exp(turn * n) * R_a0;
      EXPECT_NEAR(c.coordinate.value(q, nullptr, nullptr), turn, 1e-12 * (1.0 + std::abs(turn)))
          << "step " << step;
      c.coordinate.begin_step(q);
    }
    EXPECT_NEAR(c.coordinate.previous, direction * 0.3 * 73, 1e-11);
  }
}

TEST(JointLimitSliderPosition, ValueIsThePlaceAlongTheRailAndDerivativesMatchFiniteDifferences) {
  int checked = 0;
  for_each_slider_case([&](const Case<SliderPosition>& c) {
    const double xi = c.coordinate.value(c.q, nullptr, nullptr);
    EXPECT_NEAR(xi, c.expected, 64 * kEps * 4.0);  // entries of size ≤ 2, a few operations
    // Moving a by t along its axis moves ξ by t.
    State moved = c.q;
    moved.points[0] += 0.25 * (c.q.rotations[0] * c.coordinate.axis_a);
    EXPECT_NEAR(c.coordinate.value(moved, nullptr, nullptr) - xi, 0.25, 64 * kEps * 4.0);
    const CoordinateProbe<SliderPosition> probe{c.coordinate};
    fd::TermCheckOptions opt;
    opt.hessian.require_nonzero = fd::NonZero::kAny;
    EXPECT_TRUE(fd::check_term(probe, c.q, c.dofs, opt));
    ++checked;
  });
  EXPECT_EQ(checked, 3 * 9);
}

// A hinge Hessian without the ½ hat(γ) of the mixed block (BCH), and a slider Hessian without
// C(n, d) (the axis turning with a): the checks above must see either.
struct HingeWithoutHalfCommutator {
  static constexpr int kBlocks = 2;
  HingeAngle coordinate;
  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
    LocalGradient<2> gs;
    const double xi = coordinate.value(q, &gs, H);
    if (g != nullptr) *g = gs;
    if (H != nullptr) {
      const Matrix3 half = 0.5 * so3::hat(Vector3(gs.tail<3>()));
      H->block<3, 3>(0, 3) -= half;
      H->block<3, 3>(3, 0) -= half.transpose();
    }
    return xi;
  }
};

struct SliderWithoutAxisCurvature {
  static constexpr int kBlocks = 4;
  SliderPosition coordinate;
  double evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
    const double xi = coordinate.value(q, g, H);
    if (H != nullptr) {
      const Vector3 n = q.rotations[0] * coordinate.axis_a;
      const Vector3 d = coordinate.b.position(q) - coordinate.a.position(q);
      H->block<3, 3>(3, 3) += rotated_point_curvature(n, d);
    }
    return xi;
  }
};

TEST(JointLimitCoordinates, ChecksRejectWrongDerivatives) {
  std::mt19937 rng(839);
  const Case<HingeAngle> h = hinge_case(1.0, 2.0, 0.8, 0.4, false, rng);
  EXPECT_TRUE(fd::check_term(CoordinateProbe<HingeAngle>{h.coordinate}, h.q, h.dofs));
  EXPECT_FALSE(fd::check_term(HingeWithoutHalfCommutator{h.coordinate}, h.q, h.dofs));
  const Case<SliderPosition> s = slider_case(SliderEndB::kBody, 1.0, 2.0, rng);
  EXPECT_TRUE(fd::check_term(CoordinateProbe<SliderPosition>{s.coordinate}, s.q, s.dofs));
  EXPECT_FALSE(fd::check_term(SliderWithoutAxisCurvature{s.coordinate}, s.q, s.dofs));
}

// ========================================================================================
// The limit term.

// A limit on `coordinate` whose gap at q is `gap` (bound = ξ − σ·gap, so g = σ(ξ − bound)).
template <class Coordinate>
JointLimit<Coordinate> limit_at(const Case<Coordinate>& c, double side, double gap, double k) {
  JointLimit<Coordinate> limit;
  limit.coordinate = c.coordinate;
  limit.side = side;
  limit.stiffness = k;
  limit.bound = c.coordinate.value(c.q, nullptr, nullptr) - side * gap;
  return limit;
}

// ½‖r‖² = V, Jᵀr = g (to 64 eps of their size), J against central differences of r, whose
// round-off is absolute at √k·(|ξ| + |bound| + 1), the size r is computed from.
template <class Coordinate>
::testing::AssertionResult check_residual(const JointLimit<Coordinate>& limit,
                                          const Case<Coordinate>& c) {
  using Limit = JointLimit<Coordinate>;
  typename Limit::Residual r, r_only;
  typename Limit::ResidualJacobian J;
  limit.residual(c.q, r, &J);
  limit.residual(c.q, r_only, nullptr);
  if (r != r_only) return ::testing::AssertionFailure() << "r differs with and without J";
  LocalGradient<Limit::kBlocks> g;
  const double value = limit.evaluate(c.q, &g, nullptr);
  const double half = 0.5 * r.squaredNorm();
  if (!(std::abs(half - value) <= 16 * kEps * (half + value))) {
    return ::testing::AssertionFailure() << "½‖r‖² = " << half << ", V = " << value;
  }
  const double err = (J.transpose() * r - g).cwiseAbs().maxCoeff();
  if (!(err <= 64 * kEps * (J.norm() * r.norm() + g.norm()))) {
    return ::testing::AssertionFailure() << "Jᵀr differs from g by " << err;
  }
  const fd::VectorFunction F = fd::residual_of(limit);
  const double scale = std::sqrt(limit.stiffness) * (std::abs(limit.bound) + 2.0);
  return fd::check_vector_jacobian(F, c.q, c.dofs, J, fd::FdOptions{}, scale);
}

// The constraint's Jacobian (row 0) against central differences of constraint() itself.
template <class Coordinate>
::testing::AssertionResult check_constraint_jacobian(const JointLimit<Coordinate>& limit,
                                                     const Case<Coordinate>& c) {
  typename JointLimit<Coordinate>::ConstraintJacobian J;
  limit.constraint(c.q, &J);
  const fd::VectorFunction F = [&](const State& s) {
    return Eigen::VectorXd(limit.constraint(s, nullptr));
  };
  fd::FdOptions opt;
  opt.require_nonzero = fd::NonZero::kAny;
  return fd::check_vector_jacobian(F, c.q, c.dofs, J, opt, std::abs(limit.bound) + 2.0);
}

// Everything a limit term returns is exactly zero: value, gradient, Hessian, residual and its
// Jacobian, force and constraint.
template <class Coordinate>
void expect_inactive(const JointLimit<Coordinate>& limit, const State& q) {
  using Limit = JointLimit<Coordinate>;
  LocalGradient<Limit::kBlocks> g;
  LocalHessian<Limit::kBlocks> H;
  EXPECT_EQ(limit.evaluate(q, &g, &H), 0.0);
  EXPECT_TRUE(g.isZero(0.0));
  EXPECT_TRUE(H.isZero(0.0));
  typename Limit::Residual r;
  typename Limit::ResidualJacobian J;
  limit.residual(q, r, &J);
  EXPECT_EQ(r(0), 0.0);
  EXPECT_TRUE(J.isZero(0.0));
  EXPECT_EQ(limit.force(q), Vector3::Zero());
  typename Limit::ConstraintJacobian C;
  EXPECT_EQ(limit.constraint(q, &C), Vector3::Zero());
  EXPECT_TRUE(C.isZero(0.0));
}

// Elastic and exact (shift 0.05), upper and lower bound, gaps on both sides of the switch and
// the stiffnesses: the closed forms of the header, exact zeros where inactive, FD where active.
// The smallest active m is 1e-2: the value-Hessian's perturbations (2·1e-4 in two DOFs, |∇ξ|
// ≤ ~3 here) move g by < 1e-3, so no FD stencil crosses the switch.
template <class Coordinate>
int check_limit_on_both_sides(const Case<Coordinate>& c) {
  int active_checked = 0;
  for (const double k : kStiffnesses) {
    for (const double side : {1.0, -1.0}) {
      for (const bool exact : {false, true}) {
        for (const double gap : {-0.3, -1e-2, 1e-2, 0.3}) {
          SCOPED_TRACE(trace("k, side, gap", k, side, gap));
          SCOPED_TRACE(exact ? "exact, shift 0.05" : "elastic");
          JointLimit<Coordinate> limit = limit_at(c, side, gap, k);
          limit.exact = exact;
          limit.shift = exact ? 0.05 : 0.0;
          const double m = std::max(0.0, gap + limit.shift);
          const double tol = 64 * kEps * (std::abs(limit.bound) + 2.0);  // round-off of g
          EXPECT_NEAR(limit.violation(c.q), std::abs(std::max(gap, exact ? -0.05 : 0.0)), tol);
          if (m == 0.0) {
            expect_inactive(limit, c.q);
          } else {
            EXPECT_NEAR(limit.evaluate(c.q, nullptr, nullptr), 0.5 * k * m * m, k * m * tol * 2);
            EXPECT_NEAR(limit.force(c.q)(0), k * m, k * tol * 2);
            EXPECT_TRUE(fd::check_term(limit, c.q, c.dofs));
            EXPECT_TRUE(check_residual(limit, c));
            EXPECT_NEAR(limit.constraint(c.q, nullptr)(0), gap, tol);
            EXPECT_TRUE(check_constraint_jacobian(limit, c));
            ++active_checked;
          }
          // The shift's update s ← max(0, s + g).
          JointLimit<Coordinate> updated = limit;
          updated.update_multiplier(c.q);
          EXPECT_NEAR(updated.shift, std::max(0.0, limit.shift + gap), tol);
        }
      }
    }
  }
  return active_checked;
}

// Hinge limits: a subset of the coordinate's cases (tilts 0 and 0.7: |∇ξ| ≤ 1/cos 0.7 ≈ 1.3).
TEST(JointLimitTerm, HingeLimitOnBothSidesOfTheSwitchMatchesFiniteDifferences) {
  int cases = 0, active = 0;
  for_each_hinge_case([&](const Case<HingeAngle>& c, double tilt) {
    if (tilt > 1.0) return;
    active += check_limit_on_both_sides(c);
    ++cases;
  });
  EXPECT_EQ(cases, 2 * 9 * 8 * 2);
  EXPECT_EQ(active, cases * 3 * 2 * (2 + 3));  // per k and side: elastic 2 gaps, exact 3
}

TEST(JointLimitTerm, SliderLimitOnBothSidesOfTheSwitchMatchesFiniteDifferences) {
  int cases = 0, active = 0;
  for_each_slider_case([&](const Case<SliderPosition>& c) {
    active += check_limit_on_both_sides(c);
    ++cases;
  });
  EXPECT_EQ(cases, 3 * 9);
  EXPECT_EQ(active, cases * 3 * 2 * (2 + 3));
}

TEST(JointLimitTerm, AtTheSwitchTheHessianJumpsByKGradGradTransposed) {
  // V is C¹ at m = 0: just past the stop (g = +1e-12) the gradient is k·1e-12·σ∇ξ and the
  // Hessian k(∇ξ∇ξᵀ + m σ∇²ξ) → k∇ξ∇ξᵀ; just inside it everything is zero (expect_inactive).
  std::mt19937 rng(853);
  const Case<HingeAngle> c = hinge_case(1.0, 2.0, 0.8, 0.4, false, rng);
  LocalGradient<2> dxi;
  LocalHessian<2> ddxi;
  c.coordinate.value(c.q, &dxi, &ddxi);
  for (const double side : {1.0, -1.0}) {
    const double k = 3.0;
    const JointLimit<HingeAngle> past = limit_at(c, side, 1e-12, k);
    LocalGradient<2> g;
    LocalHessian<2> H;
    past.evaluate(c.q, &g, &H);
    const double m = side * (c.coordinate.value(c.q, nullptr, nullptr) - past.bound);
    ASSERT_GT(m, 0.0);
    EXPECT_LE((g - k * m * side * dxi).cwiseAbs().maxCoeff(), 16 * kEps * k * m * dxi.norm());
    EXPECT_LE((H - k * dxi * dxi.transpose()).cwiseAbs().maxCoeff(),
              k * 1e-11 * (ddxi.cwiseAbs().maxCoeff() + dxi.squaredNorm()));
    expect_inactive(limit_at(c, side, -1e-12, k), c.q);
  }
}

TEST(JointLimitTerm, AdjointLagrangianIsActiveExactlyWhereTheMultiplierIsPositive) {
  // Adjoint mode (solvers/adjoint.cpp): V_adj = λg + ½ρg² where λ > 0, whatever the sign of g
  // (at the converged step an active stop has g ≈ 0 on either side); nothing where λ = 0.
  // Its Hessian is that of V_adj at g = 0: FD-checked whole there, and elsewhere shown to
  // differ from the FD Hessian by exactly the ρ g σ∇²ξ it leaves out.
  std::mt19937 rng(859);
  const Case<HingeAngle> h = hinge_case(2.5, 1e-4, kPi - 1e-6, 0.4, false, rng);
  const Case<SliderPosition> s = slider_case(SliderEndB::kBody, kPi, 1.0, rng);
  const auto check = [](const auto& c) {
    for (const double side : {1.0, -1.0}) {
      for (const double gap : {-1e-2, 0.0, 1e-2}) {
        for (const double lambda : {0.0, 0.7}) {
          SCOPED_TRACE(trace("side, gap, λ", side, gap, lambda));
          auto limit = limit_at(c, side, gap, 40.0);
          limit.exact = true;
          limit.shift = 0.2;  // ignored by the adjoint's Lagrangian
          limit.adjoint = true;
          limit.multiplier = Vector3(lambda, 0.0, 0.0);
          if (lambda == 0.0) {
            LocalGradient<std::decay_t<decltype(limit)>::kBlocks> g;
            LocalHessian<std::decay_t<decltype(limit)>::kBlocks> H;
            EXPECT_EQ(limit.evaluate(c.q, &g, &H), 0.0);
            EXPECT_TRUE(g.isZero(0.0));
            EXPECT_TRUE(H.isZero(0.0));
            EXPECT_EQ(limit.constraint(c.q, nullptr), Vector3::Zero());
            continue;
          }
          const double tol = 64 * kEps * (std::abs(limit.bound) + 2.0);
          EXPECT_NEAR(limit.evaluate(c.q, nullptr, nullptr), lambda * gap + 20.0 * gap * gap,
                      50.0 * tol);
          if (gap == 0.0) {
            EXPECT_TRUE(fd::check_term(limit, c.q, c.dofs));
          } else {
            // The Hessian is V_adj's at g = 0 (header): FD of the gradient gives it plus
            // ρ g σ∇²ξ, which the term leaves out (g is at the tolerance where it is used).
            constexpr int B = std::decay_t<decltype(limit)>::kBlocks;
            LocalGradient<B> g, dxi;
            LocalHessian<B> H, ddxi;
            limit.evaluate(c.q, &g, &H);
            c.coordinate.value(c.q, &dxi, &ddxi);
            const fd::ScalarFunction f = [&](const State& q) {
              return limit.evaluate(q, nullptr, nullptr);
            };
            const fd::GradientFunction grad = [&](const State& q) {
              LocalGradient<B> gq;
              limit.evaluate(q, &gq, nullptr);
              return Eigen::VectorXd(gq);
            };
            EXPECT_TRUE(fd::check_lie_gradient(f, c.q, c.dofs, g));
            const LocalHessian<B> full = H + limit.stiffness * gap * side * ddxi;
            EXPECT_TRUE(fd::check_lie_hessian(grad, c.q, c.dofs, full));
            EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, H));
          }
          EXPECT_NEAR(limit.constraint(c.q, nullptr)(0), gap, tol);
          EXPECT_TRUE(check_constraint_jacobian(limit, c));
        }
      }
    }
  };
  check(h);
  check(s);
}

}  // namespace
}  // namespace liedyn::joint_limits_tests

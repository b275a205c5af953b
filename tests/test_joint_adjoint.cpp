// The joint terms' pieces of the constrained adjoint (lib/joint_terms.hpp, docs/design.md §8.6):
//   * the constraint c(q) and its Jacobian J = ∂c/∂(blocks), against central differences in
//     the tangent space, at generic states over the angle list (c ≠ 0 too: J is exact there);
//   * the adjoint-mode Lagrangian λᵀc + ½ρ‖c‖², its gradient Jᵀ(λ + ρc) and Hessian
//     ρJᵀJ + ∇²(λᵀc), by fd::check_term at states where the joint holds (c = 0, the only
//     place the adjoint evaluates it; there H_adj is the Lagrangian's exact Hessian), body
//     rotations over the angle list, |λ| from 1e-3 to 1e6 and ρ 1 and 1e6;
//   * force(q) = λ: the penalty's gradient is Jᵀλ where the shifted joint holds, for a
//     non-zero shift.
//   * the slider's line term (JointLine): value, gradient, Hessian, residual and constraint
//     at generic states, its Lagrangian where the line holds, its violation and update.
// Tolerances are fd_check.hpp's defaults.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "fd_check.hpp"
#include "lib/joint_terms.hpp"
#include "lib/so3.hpp"

namespace liedyn::joint_adjoint_tests {
namespace {

using fd::kAngles;
using fd::random_unit;
using fd::random_vector;
using fd::rotation_at;
using fd::trace;

// Ends a (rotation 0, point 0) and b (rotation 1, point 1), or b the world.
struct Ends {
  State q;
  fd::Dofs rotations;  // the two rotation blocks (b: no_dof() for the world)
  fd::Dofs point_pair; // x_a, θ_a, x_b, θ_b
};

Ends ends(double angle_a, double angle_b, bool world_b, std::mt19937& rng) {
  Ends e;
  e.q.points = {random_vector(rng, 1.0), random_vector(rng, 1.0)};
  e.q.rotations = {rotation_at(angle_a, rng), rotation_at(angle_b, rng)};
  const fd::Dof b = world_b ? fd::no_dof() : fd::rotation_dof(1);
  e.rotations = {fd::rotation_dof(0), b};
  e.point_pair = {fd::point_dof(0), fd::rotation_dof(0), world_b ? fd::no_dof() : fd::point_dof(1), b};
  return e;
}

JointPoint point_term(const Ends& e, bool world_b, std::mt19937& rng) {
  JointPoint t;
  t.a = {0, 0, random_vector(rng, 0.5)};
  t.offsets = {0, 3, world_b ? -1 : 6, world_b ? -1 : 9};
  if (world_b) {
    t.b = {-1, -1, t.a.position(e.q)};  // the world, where a's point is: c = 0
  } else {
    t.b = {1, 1, random_vector(rng, 0.5)};
  }
  return t;
}

JointAlignment alignment_term(const Ends&, bool world_b, std::mt19937& rng) {
  JointAlignment t;
  t.rotation_a = 0;
  t.rotation_b = world_b ? -1 : 1;
  t.offsets = {0, world_b ? -1 : 3};
  t.axis_a = random_unit(rng);
  t.axis_b = random_unit(rng);
  return t;
}

JointWeld weld_term(const Ends&, bool world_b, std::mt19937& rng) {
  JointWeld t;
  t.rotation_a = 0;
  t.rotation_b = world_b ? -1 : 1;
  t.offsets = {0, world_b ? -1 : 3};
  t.frame_a = rotation_at(1.3, rng);
  t.frame_b = rotation_at(0.4, rng);
  return t;
}

// Moves end b (or the term's b geometry) so that the joint holds exactly at e.q.
void hold(JointPoint& t, Ends& e) {
  if (t.b.point >= 0) e.q.points[1] += t.a.position(e.q) - t.b.position(e.q);
}
void hold(JointAlignment& t, const Ends& e) {
  const Matrix3 R_b = t.rotation_b < 0 ? Matrix3::Identity() : e.q.rotations[1];
  t.axis_b = R_b.transpose() * e.q.rotations[0] * t.axis_a;
}
void hold(JointWeld& t, const Ends& e) {
  const Matrix3 R_b = t.rotation_b < 0 ? Matrix3::Identity() : e.q.rotations[1];
  t.frame_b = so3::orthonormalize(R_b.transpose() * e.q.rotations[0] * t.frame_a);
}

template <class Term>
::testing::AssertionResult check_constraint_jacobian(const Term& t, const State& q, const fd::Dofs& dofs) {
  typename Term::ConstraintJacobian J;
  t.constraint(q, &J);
  const fd::VectorFunction c = [&](const State& s) { return Eigen::VectorXd(t.constraint(s, nullptr)); };
  return fd::check_vector_jacobian(c, q, dofs, Eigen::MatrixXd(J));
}

// `truncation_length`: for a term whose ‖c(θ)‖² has a third-order term at c = 0 (the slider
// line: 2 c₁·c₂ ≠ 0), the size L of the levers and of d, for the truncation floor ρ L³ ε² of
// the gradient's differences.
template <class Term>
::testing::AssertionResult check_lagrangian(Term t, const State& q, const fd::Dofs& dofs,
                                            const Vector3& lambda, double rho,
                                            double truncation_length = 0.0) {
  t.exact = true;
  t.adjoint = true;
  t.multiplier = lambda;
  t.stiffness = rho;
  if (!(t.constraint(q, nullptr).norm() <= 1e-12)) {
    return ::testing::AssertionFailure() << "the joint does not hold: |c| = " << t.constraint(q, nullptr).norm();
  }
  // An absolute floor that scales with ρ rather than with the (here small) value: V(±ε) is
  // dominated by ½ρε², computed from c = p_b − p_a whose entries carry the absolute round-off
  // eps·L of positions of size L (L = 3 bounds |x| + |lever| here), which the difference
  // turns into ρ·eps·L in the gradient. (The penalty adds no truncation: ‖c(θ)‖² has no
  // third-order term at c = 0, since (θ × r)·(θ × (θ × r)) = 0.) It matters only where
  // ρ ≫ |λ| (ρ = 1e6, |λ| = 1e-3).
  // Likewise λᵀc carries the absolute round-off eps·|λ|·L of c (rotated vectors and log(E)
  // are computed from entries of size 1, whatever the angle), which second differences of
  // the value divide by ε².
  constexpr double kL = 3.0;
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  fd::TermCheckOptions opt;
  if (truncation_length > 0.0) opt.gradient.step = 1e-7;  // the truncation falls as ε²
  opt.gradient.abs_floor = 16.0 * kEps * rho * kL + rho * std::pow(truncation_length, 3) *
                                                        opt.gradient.step * opt.gradient.step;
  const double e = opt.hessian_from_value.step;
  opt.hessian_from_value.abs_floor = 16.0 * kEps * lambda.norm() * kL / (e * e);
  // With |λ| = 1e6 and ρ = 1 that floor (~1) reaches the ρ-sized blocks: the differences of
  // the gradient (which must resolve every block) carry the check there.
  opt.hessian_from_value.require_nonzero = fd::NonZero::kNone;
  return fd::check_term(t, q, dofs, opt);
}

// The three terms at every pair of angles of the list, both ends free and b the world.
template <class Make, class Check>
int for_each_case(std::mt19937& rng, Make make, Check check) {
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double angle_a : kAngles) {
      for (const double angle_b : {0.0, 1e-9, 1.0, std::numbers::pi - 1e-6, std::numbers::pi}) {
        SCOPED_TRACE(trace("world b, angles R_a, R_b", world_b, angle_a, angle_b));
        Ends e = ends(angle_a, angle_b, world_b, rng);
        auto t = make(e, world_b, rng);
        check(t, e, world_b);
        ++checked;
      }
    }
  }
  return checked;
}

const int kCases = 2 * static_cast<int>(kAngles.size()) * 5;

TEST(JointAdjoint, ConstraintJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(2101);
  EXPECT_EQ(for_each_case(rng, point_term, [](const JointPoint& t, Ends& e, bool) {
              EXPECT_TRUE(check_constraint_jacobian(t, e.q, e.point_pair));
            }),
            kCases);
  EXPECT_EQ(for_each_case(rng, alignment_term, [](const JointAlignment& t, Ends& e, bool) {
              EXPECT_TRUE(check_constraint_jacobian(t, e.q, e.rotations));
            }),
            kCases);
  // The weld at a generic relative rotation (below π: at π the log has its cut).
  EXPECT_EQ(for_each_case(rng, weld_term, [](const JointWeld& t, Ends& e, bool) {
              if (t.constraint(e.q, nullptr).norm() > std::numbers::pi - 1e-3) return;
              EXPECT_TRUE(check_constraint_jacobian(t, e.q, e.rotations));
            }),
            kCases);
}

TEST(JointAdjoint, LagrangiansMatchFiniteDifferencesWhereTheJointHolds) {
  std::mt19937 rng(2102);
  for (const double size : {1e-3, 1.0, 1e6}) {
    for (const double rho : {1.0, 1e6}) {
      SCOPED_TRACE(trace("|λ|, ρ", size, rho));
      const Vector3 lambda = size * random_unit(rng);
      EXPECT_EQ(for_each_case(rng, point_term, [&](JointPoint& t, Ends& e, bool) {
                  hold(t, e);
                  EXPECT_TRUE(check_lagrangian(t, e.q, e.point_pair, lambda, rho));
                }),
                kCases);
      EXPECT_EQ(for_each_case(rng, alignment_term, [&](JointAlignment& t, Ends& e, bool) {
                  hold(t, e);
                  EXPECT_TRUE(check_lagrangian(t, e.q, e.rotations, lambda, rho));
                }),
                kCases);
      EXPECT_EQ(for_each_case(rng, weld_term, [&](JointWeld& t, Ends& e, bool) {
                  hold(t, e);
                  EXPECT_TRUE(check_lagrangian(t, e.q, e.rotations, lambda, rho));
                }),
                kCases);
    }
  }
}

// force(q) is the multiplier of the penalty: where the joint holds (c = 0) with a shift s of
// 1e-3, the penalty's gradient is Jᵀ force — although the shifted term's Jacobian J_s differs
// from J (the point's lever is moved by R_a s, the axis is R_a (â + s)), the difference
// meets a force parallel to R_a s (the point) or a cross product with a = b (the axis).
TEST(JointAdjoint, TheWeldsLagrangianIsExactWhereTheWeldDoesNotHold) {
  // λᵀφ (ρ = 0: the multipliers' part Ipopt's Lagrangian Hessian takes from it) at relative
  // angles of E = R_a A Bᵀ R_bᵀ from 1e-9 to π − 1e-3 (J_l⁻¹ grows as cot(t/2) towards π),
  // body rotations over the angle list, end b a body or the world, |λ| 1 and 1e3: value,
  // Lie gradient and Hessian by central differences. And, with λ = kφ and ρ = k, the
  // Lagrangian's Hessian ρJᵀJ + ∇²(λᵀφ) is the elastic weld's k(JᵀJ + ∇²φ·φ), to round-off.
  std::mt19937 rng(977);
  const std::vector<double> relative = {1e-9, 1e-4, 0.1, 0.3, 1.0, 2.5, std::numbers::pi - 1e-3};
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (std::size_t i = 0; i < relative.size(); ++i) {
      for (const double size : {1.0, 1e3}) {
        const double angle_a = kAngles[i % kAngles.size()], angle_b = kAngles[(i + 4) % kAngles.size()];
        SCOPED_TRACE(trace("relative angle, |λ|, world b", relative[i], size, world_b));
        SCOPED_TRACE(trace("angles a, b", angle_a, angle_b));
        Ends e = ends(angle_a, angle_b, world_b, rng);
        JointWeld t = weld_term(e, world_b, rng);
        const Matrix3 R_b = world_b ? Matrix3::Identity() : e.q.rotations[1];
        const Vector3 n = random_unit(rng);
        t.frame_b = so3::orthonormalize(R_b.transpose() * so3::exp(-relative[i] * n) *
                                        e.q.rotations[0] * t.frame_a);
        ASSERT_NEAR(t.constraint(e.q, nullptr).norm(), relative[i], 1e-12);
        t.exact = true;
        t.adjoint = true;
        t.stiffness = 0.0;
        t.multiplier = size * random_unit(rng);
        // λᵀφ carries the absolute round-off eps·|λ| of log(E) (entries of size 1); near π
        // J_l⁻¹ magnifies it by up to |cot(t/2)|·t/2 ~ 2/(π − t).
        fd::TermCheckOptions opt;
        const double roundoff = 16.0 * std::numeric_limits<double>::epsilon() * size *
                                (relative[i] > 3.0 ? 2.0 / (std::numbers::pi - relative[i]) : 1.0);
        opt.gradient.abs_floor = roundoff / opt.gradient.step;
        opt.hessian.abs_floor = roundoff / opt.hessian.step;  // the gradient's round-off, /ε
        // With b the world only θ_a's block is compared, and there ∇²(λᵀφ) = M = O(|λ| t):
        // negligible at the smallest angles, where the check shows it is (near) zero.
        if (world_b && relative[i] < 1e-3) opt.hessian.require_nonzero = fd::NonZero::kNone;
        opt.hessian_from_value.abs_floor =
            roundoff / (opt.hessian_from_value.step * opt.hessian_from_value.step);
        opt.hessian_from_value.require_nonzero = fd::NonZero::kNone;
        EXPECT_TRUE(fd::check_term(t, e.q, e.rotations, opt));

        const double k = 7.0;
        JointWeld elastic = t;
        elastic.exact = false;
        elastic.adjoint = false;
        elastic.stiffness = k;
        JointWeld lagrangian = t;
        lagrangian.stiffness = k;
        lagrangian.multiplier = k * t.constraint(e.q, nullptr);
        LocalHessian<2> He, Hl;
        elastic.evaluate(e.q, nullptr, &He);
        lagrangian.evaluate(e.q, nullptr, &Hl);
        EXPECT_LE((He - Hl).cwiseAbs().maxCoeff(), 1e-12 * k * (1.0 + He.cwiseAbs().maxCoeff()))
            << He << "\n\n" << Hl;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 7 * 2);
}

TEST(JointAdjoint, ThePenaltysGradientIsJTransposeTimesItsForce) {
  std::mt19937 rng(2103);
  const auto check = [](const auto& t, const State& q) {
    using T = std::decay_t<decltype(t)>;
    LocalGradient<T::kBlocks> g;
    t.evaluate(q, &g, nullptr);
    typename T::ConstraintJacobian J;
    t.constraint(q, &J);
    const LocalGradient<T::kBlocks> expected = J.transpose() * t.force(q);
    EXPECT_LE((g - expected).norm(), 1e-9 * (1.0 + g.norm())) << g.transpose() << "\n" << expected.transpose();
  };
  for (int i = 0; i < 20; ++i) {
    Ends e = ends(0.3 * i, 0.2 * i, false, rng);
    JointPoint p = point_term(e, false, rng);
    hold(p, e);
    p.exact = true;
    p.stiffness = 1e6;
    p.shift = 1e-3 * random_unit(rng);
    check(p, e.q);
    JointAlignment a = alignment_term(e, false, rng);
    hold(a, e);
    a.exact = true;
    a.stiffness = 1e6;
    a.shift = 1e-3 * random_unit(rng);
    check(a, e.q);
  }
}

// ----------------------------------------------------------------------------------------
// The slider's line term (JointLine): V = ½ k ‖n × d + R_a s‖², its residual, constraint and
// Lagrangian, over the angle list for both ends, end b a body or the world, with and without
// a shift, k from 1e-6 to 1e9 (the header's derivation, checked term by term).

JointLine line_term(const Ends& e, bool world_b, std::mt19937& rng) {
  JointLine t;
  const JointPoint p = point_term(e, world_b, rng);
  t.a = p.a;
  t.b = p.b;
  t.offsets = p.offsets;
  t.axis_a = random_unit(rng);
  return t;
}

TEST(JointLineTerm, DerivativesResidualAndConstraintMatchFiniteDifferences) {
  std::mt19937 rng(2104);
  for (const double k : {1e-6, 1.0, 1e9}) {
    for (const double shift : {0.0, 0.2}) {
      SCOPED_TRACE(trace("k, |s|", k, shift));
      EXPECT_EQ(for_each_case(rng, line_term, [&](JointLine& t, Ends& e, bool world_b) {
                  t.stiffness = k;
                  t.shift = shift * random_unit(rng);
                  // Off the line (c ≠ 0): move end b, or its world anchor.
                  (world_b ? t.b.local : e.q.points[1]) += random_vector(rng, 0.3);
                  EXPECT_TRUE(fd::check_term(t, e.q, e.point_pair));
                  // Residual: ½‖r‖² = V, Jᵀr = g, J by differences of r.
                  JointLine::Residual r;
                  JointLine::ResidualJacobian J;
                  t.residual(e.q, r, &J);
                  LocalGradient<4> g;
                  const double v = t.evaluate(e.q, &g, nullptr);
                  EXPECT_NEAR(0.5 * r.squaredNorm(), v, 1e-13 * (1.0 + v));
                  for (int b = 0; b < 4; ++b) {
                    if (e.point_pair[b].kind == fd::DofKind::kNone) {
                      J.block<3, 3>(0, 3 * b).setZero();
                      g.segment<3>(3 * b).setZero();
                    }
                  }
                  EXPECT_LE((J.transpose() * r - g).norm(), 1e-12 * (1.0 + g.norm()));
                  const fd::VectorFunction residual = fd::residual_of(t);
                  JointLine::ResidualJacobian J_full;
                  t.residual(e.q, r, &J_full);
                  EXPECT_TRUE(fd::check_vector_jacobian(residual, e.q, e.point_pair, Eigen::MatrixXd(J_full)));
                  EXPECT_TRUE(check_constraint_jacobian(t, e.q, e.point_pair));
                }),
                kCases);
    }
  }
}

TEST(JointLineTerm, LagrangianMatchesFiniteDifferencesWhereTheLineHolds) {
  std::mt19937 rng(2105);
  for (const double size : {1e-3, 1.0, 1e6}) {
    for (const double rho : {1.0, 1e6}) {
      SCOPED_TRACE(trace("|λ|, ρ", size, rho));
      const Vector3 lambda = size * random_unit(rng);
      EXPECT_EQ(for_each_case(rng, line_term, [&](JointLine& t, Ends& e, bool world_b) {
                  // p_b on the line: move b (or its world anchor) along n from p_a.
                  const Vector3 on_line = t.a.position(e.q) + 0.4 * (e.q.rotations[0] * t.axis_a);
                  if (world_b) {
                    t.b.local = on_line;
                  } else {
                    e.q.points[1] += on_line - t.b.position(e.q);
                  }
                  // Levers ≤ 0.5·√3, d = 0.4 along n: L = 1.5 bounds them.
                  EXPECT_TRUE(check_lagrangian(t, e.q, e.point_pair, lambda, rho, 1.5));
                }),
                kCases);
    }
  }
}

// The line's violation is zero along the axis and the distance from it across; its
// multiplier update carries the residual as the others do (s ← s + R_aᵀ c).
TEST(JointLineTerm, ViolationIsTheDistanceFromTheLineTimesItsLength) {
  std::mt19937 rng(2106);
  Ends e = ends(0.7, 1.1, false, rng);
  JointLine t = line_term(e, false, rng);
  const Vector3 n = e.q.rotations[0] * t.axis_a;
  e.q.points[1] += t.a.position(e.q) + 0.5 * n - t.b.position(e.q);
  EXPECT_LE(t.violation(e.q), 1e-15);
  const Vector3 across = n.cross(random_unit(rng)).normalized();
  e.q.points[1] += 1e-3 * across;
  // c = n × d with d = 0.5 n + 1e-3 u: |c| = 1e-3 (n ⊥ u), its largest entry at most that.
  const Vector3 c = n.cross(t.b.position(e.q) - t.a.position(e.q));
  EXPECT_NEAR(c.norm(), 1e-3, 1e-15);
  EXPECT_EQ(t.violation(e.q), c.lpNorm<Eigen::Infinity>());
  t.exact = true;
  t.stiffness = 1e6;
  t.update_multiplier(e.q);
  EXPECT_LE((e.q.rotations[0] * t.shift - c).norm(), 1e-15);
}

}  // namespace
}  // namespace liedyn::joint_adjoint_tests

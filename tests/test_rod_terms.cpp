// Cosserat rod terms (lib/rod_terms.hpp): value vs Lie gradient vs Lie Hessian by finite
// differences in the tangent space over all blocks (tests/fd_check.hpp), at straight, kinked
// (up to 170°) and twisted (up to π) configurations, nearly degenerate edges, rotations from
// the identity to near 2π, stiffnesses 1e-3…1e9 and rest lengths 1e-4…10; plus physical facts
// derived by hand (rest states, objectivity, torque balance, Hooke's law, closed forms).
//
// Length scales. fd_check differences every block with one step ε (1e-6; 1e-4 for second
// differences of the value), which is right for rotations (radians) but not for positions
// when the edge is 1e-4 or 1e-6·l long. Point coordinates are therefore checked in units of
// a power of two s ≈ ‖e‖ (ScaledPoints below): the state y = x/s, and the term's derivatives
// times s per point block. Scaling by a power of two is exact, so this checks the analytic
// derivatives themselves, with an FD step of 1e-6·‖e‖ in x.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "fd_check.hpp"
#include "lib/rod_terms.hpp"
#include "lib/so3.hpp"

namespace liedyn {
namespace {

using fd::kAngles;
using fd::random_unit;
using fd::random_vector;
using fd::rotation_at;
using fd::trace;
using fd::power_of_two_near;
using fd::random_perpendicular;
using fd::kPi;
using fd::kEps;
using fd::kDeg;


// A unit vector perpendicular to n.
// The term seen in point coordinates y = x/s (s a power of two: every scaling is exact):
//   ψ(y, R) = Ψ(s y, R),  ∂ψ/∂y = s ∂Ψ/∂x,  ∂²ψ/∂y² = s² ∂²Ψ/∂x²,  ∂²ψ/∂y∂θ = s ∂²Ψ/∂x∂θ.
template <class Term>
struct ScaledPoints {
  static constexpr int kBlocks = Term::kBlocks;
  const Term* term = nullptr;
  double s = 1.0;
  std::array<bool, kBlocks> point_block{};

  double evaluate(const State& y, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
    State x = y;
    for (Vector3& p : x.points) p *= s;
    const double value = term->evaluate(x, g, H);
    for (int b = 0; b < kBlocks; ++b) {
      if (!point_block[static_cast<size_t>(b)]) continue;
      if (g != nullptr) g->template segment<3>(3 * b) *= s;
      if (H != nullptr) {
        H->template middleRows<3>(3 * b) *= s;
        H->template middleCols<3>(3 * b) *= s;
      }
    }
    return value;
  }
};

State scaled_down(State q, double s) {
  for (Vector3& p : q.points) p /= s;
  return q;
}

// check_term on the scaled term. `value_hessian` = false skips the second differences of the
// value where they cannot resolve the Hessian at all (stated and derived at the call).
template <class Term>
::testing::AssertionResult check_rod_term(const Term& term, const State& q, const fd::Dofs& dofs,
                                          double s, const fd::TermCheckOptions& opt = {},
                                          bool value_hessian = true) {
  ScaledPoints<Term> scaled;
  scaled.term = &term;
  scaled.s = s;
  for (size_t b = 0; b < dofs.size(); ++b) {
    scaled.point_block[b] = dofs[b].kind == fd::DofKind::kPoint;
  }
  const State y = scaled_down(q, s);
  if (value_hessian) return fd::check_term(scaled, y, dofs, opt);
  constexpr int B = Term::kBlocks;
  LocalGradient<B> g;
  LocalHessian<B> H;
  scaled.evaluate(y, &g, &H);
  const fd::ScalarFunction f = [&](const State& st) {
    return scaled.evaluate(st, nullptr, nullptr);
  };
  const fd::GradientFunction grad = [&](const State& st) {
    LocalGradient<B> gs;
    scaled.evaluate(st, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  ::testing::AssertionResult r = fd::check_lie_gradient(f, y, dofs, g, opt.gradient);
  if (!r) return r;
  return fd::check_lie_hessian(grad, y, dofs, H, opt.hessian);
}

// Smallest eigenvalue of a symmetric matrix.
template <class M>
double min_eigenvalue(const M& H) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(H)).eigenvalues()(0);
}

// ----------------------------------------------------------------------------------------
// Stretch  ½ k_s l (1 − ‖e‖/l)².

struct StretchCase {
  RodStretch term;
  State q;
  fd::Dofs dofs{fd::point_dof(0), fd::point_dof(1)};
};

StretchCase make_stretch(double l, double k, double L, std::mt19937& rng) {
  StretchCase c;
  c.term.node0 = 0;
  c.term.node1 = 1;
  c.term.rest_length = l;
  c.term.stiffness = k;
  const Vector3 x0 = random_vector(rng, L);  // coordinates of the edge's own size
  c.q.points = {x0, x0 + L * random_unit(rng)};
  return c;
}

TEST(RodStretchTerm, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(101);
  int checked = 0;
  for (const double l : {1e-4, 1e-2, 1.0, 10.0}) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      for (const double ratio : {1e-6, 0.3, 0.9, 1.5, 3.0}) {  // ‖e‖/l
        SCOPED_TRACE(trace("l, k, |e|/l", l, k, ratio));
        const StretchCase c = make_stretch(l, k, ratio * l, rng);
        const double L = (c.q.points[1] - c.q.points[0]).norm();
        // At ‖e‖ = 1e-6 l the value is ≈ ½k l while, in units of s ≈ ‖e‖, the curvature is
        // s²·(k/l)(l/‖e‖) ≈ 1e-6 k l: second differences of the value (round-off
        // 16 eps·½kl/ε² ≈ 2e-7 k l at ε = 1e-4) cannot resolve it for any admissible ε
        // (truncation ≈ (ε/1)² relative). The gradient-based Hessian check still applies.
        const bool value_hessian = ratio > 1e-3;
        EXPECT_TRUE(check_rod_term(c.term, c.q, c.dofs, power_of_two_near(L), {}, value_hessian));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 4 * 3 * 5);
}

TEST(RodStretchTerm, ValueIsTheBriefsFormulaAndHookesLawHolds) {
  // Ψ_s = ½ k_s l (1 − L/l)² = ½ (k_s/l)(L − l)². Under an axial force F on node i+1 (node i
  // held), equilibrium is ∂Ψ/∂x_{i+1} = F n, i.e. (k_s/l)(L − l) = F: ΔL = F l / k_s.
  std::mt19937 rng(102);
  for (const double l : {1e-4, 1.0, 10.0}) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      for (const double strain : {-0.5, 1e-3, 0.2}) {  // F/k_s
        const double F = strain * k;
        const StretchCase c = make_stretch(l, k, l + F * l / k, rng);
        const Vector3 e = c.q.points[1] - c.q.points[0];
        const double L = e.norm();
        LocalGradient<2> g;
        const double value = c.term.evaluate(c.q, &g, nullptr);
        const double brief = 0.5 * k * l * (1.0 - L / l) * (1.0 - L / l);
        // The brief's form cancels in 1 − L/l: its relative error is ~ eps/|strain|.
        EXPECT_NEAR(value, brief, 8 * kEps / std::abs(strain) * brief) << l << " " << k;
        // The positions carry the length to ~ eps·L, i.e. the force to (k/l)·eps·L.
        const double tol = 16 * kEps * k * L / l;
        EXPECT_LE((Vector3(g.segment<3>(3)) - F * e / L).norm(), tol) << l << " " << k;
        EXPECT_LE((g.segment<3>(0) + g.segment<3>(3)).norm(), 0.0);  // exactly opposite
      }
    }
  }
}

TEST(RodStretchTerm, AtRestGradientVanishesAndHessianIsRankOnePsd) {
  // At L = l: g = 0 and H = (k/l) [n nᵀ, −n nᵀ; −n nᵀ, n nᵀ] (eigenvalues 2k/l and 0 ×5).
  std::mt19937 rng(103);
  for (const double l : {1e-4, 1.0, 10.0}) {
    for (const double k : {1e-3, 1e9}) {
      const StretchCase c = make_stretch(l, k, l, rng);
      LocalGradient<2> g;
      LocalHessian<2> H;
      const double value = c.term.evaluate(c.q, &g, &H);
      // ‖e‖ = l up to a few eps·l (the sum x0 + l n and the norm round).
      EXPECT_LE(value, 0.5 * k / l * std::pow(8 * kEps * l, 2));
      EXPECT_LE(g.norm(), 16 * kEps * k);
      const Eigen::SelfAdjointEigenSolver<LocalHessian<2>> eig(H);
      EXPECT_GE(eig.eigenvalues().minCoeff(), -16 * kEps * k / l);
      EXPECT_NEAR(eig.eigenvalues().maxCoeff(), 2 * k / l, 16 * kEps * k / l);
      EXPECT_EQ((eig.eigenvalues().array().abs() > 1e-9 * k / l).count(), 1);
    }
  }
}

// ----------------------------------------------------------------------------------------
// Shear  ½ k_x l (1 − dᵀ R e_z).

struct ShearCase {
  RodShear term;
  State q;
  fd::Dofs dofs{fd::point_dof(0), fd::point_dof(1), fd::rotation_dof(0)};
};

// Frame R at `angle`, edge of length L at `kink` from R e_z.
ShearCase make_shear(double l, double k, double L, double angle, double kink, std::mt19937& rng) {
  ShearCase c;
  c.term.node0 = 0;
  c.term.node1 = 1;
  c.term.edge = 0;
  c.term.rest_length = l;
  c.term.stiffness = k;
  const Matrix3 R = rotation_at(angle, rng);
  const Vector3 t = R.col(2);
  const Vector3 d = so3::exp(kink * random_perpendicular(t, rng)) * t;
  const Vector3 x0 = random_vector(rng, L);
  c.q.points = {x0, x0 + L * d};
  c.q.rotations = {R};
  return c;
}

TEST(RodShearTerm, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(201);
  int checked = 0;
  for (const double l : {1e-4, 1.0, 10.0}) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      for (const double ratio : {1e-6, 1.0, 2.5}) {  // ‖e‖/l
        for (const double angle : kAngles) {
          for (const double kink : {1e-4, 0.7, 1.6, 2.6, 170 * kDeg}) {
            SCOPED_TRACE(trace("l, k, |e|/l", l, k, ratio));
            SCOPED_TRACE(trace("angle of R, kink", angle, kink));
            const ShearCase c = make_shear(l, k, ratio * l, angle, kink, rng);
            const double L = (c.q.points[1] - c.q.points[0]).norm();
            const double s = power_of_two_near(L);
            // FD truncation of the gradient, ε²/6·|∂³ψ| along one coordinate, is NOT
            // proportional to the gradient, which a small kink suppresses (g ~ c·kink):
            // ψ = c (1 − tᵀ n(e)) with n(e) = e/‖e‖, whose third derivative along a
            // coordinate is at most ~3/L³·2 (1D: s/√(L²+s²) = s/L − s³/2L³ + …), and
            // tᵀ exp(sθ̂) d has third derivative ≤ 1. In units of s (L_y = L/s ∈ [0.7, 1.4]):
            //   truncation ≤ ε² c max(1/L_y³, 1/6).
            // (Checked: at kink 1e-4 the FD error falls as ε², ≈ 1.8 c/L³ · ε²/6.)
            fd::TermCheckOptions opt;
            const double cst = 0.5 * k * l, L_y = L / s;
            opt.gradient.abs_floor = opt.gradient.step * opt.gradient.step * cst *
                                     std::max(1.0 / (L_y * L_y * L_y), 1.0 / 6.0);
            EXPECT_TRUE(check_rod_term(c.term, c.q, c.dofs, s, opt));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 3 * 3 * static_cast<int>(kAngles.size()) * 5);
}

TEST(RodShearTerm, AtRestGradientVanishesAndHessianIsPsd) {
  // t = d: Ψ = 0 is the minimum, g = 0. With P = I − d dᵀ, hat(d) P = hat(d) and
  // u = δx_{i+1} − δx_i, the Hessian's quadratic form is  c ‖P u / L + d × θ‖²:
  // PSD of rank 2 (the plane ⊥ d).
  std::mt19937 rng(202);
  for (const double l : {1e-4, 1.0, 10.0}) {
    for (const double ratio : {1e-6, 1.0}) {
      for (const double angle : kAngles) {
        const double k = 7.0;
        const ShearCase c = make_shear(l, k, ratio * l, angle, 0.0, rng);
        const double L = (c.q.points[1] - c.q.points[0]).norm();
        LocalGradient<3> g;
        LocalHessian<3> H;
        const double value = c.term.evaluate(c.q, &g, &H);
        const double cst = 0.5 * k * l;
        // d = e/L equals t to a few eps·(‖x0‖ + L)/L ≤ a few eps.
        EXPECT_LE(value, cst * std::pow(16 * kEps, 2)) << angle;
        EXPECT_LE(g.segment<6>(0).norm(), 16 * kEps * cst / L) << angle;
        EXPECT_LE(g.segment<3>(6).norm(), 16 * kEps * cst) << angle;
        // PSD in the scaled coordinates (points in units of L), where every block is ~c.
        LocalHessian<3> Hs = H;
        Hs.topRows<6>() *= L;
        Hs.leftCols<6>() *= L;
        EXPECT_GE(min_eigenvalue(Hs), -64 * kEps * cst) << angle;
        const Eigen::SelfAdjointEigenSolver<LocalHessian<3>> eig(Hs);
        EXPECT_EQ((eig.eigenvalues().array() > 1e-9 * cst).count(), 2) << angle;
      }
    }
  }
}

TEST(RodShearTerm, ExertsNoNetForceOrTorque) {
  // Ψ depends on e and R only through dᵀR e_z: invariant under a common translation and
  // under (x_j, R) → (exp(φ)x_j, exp(φ)R). Differentiating at φ = 0:
  //   g_0 + g_1 = 0,   x_0 × g_0 + x_1 × g_1 + g_θ = 0.
  std::mt19937 rng(203);
  for (const double angle : kAngles) {
    for (const double kink : {1e-4, 1.0, 170 * kDeg}) {
      const ShearCase c = make_shear(1.0, 3.0, 0.8, angle, kink, rng);
      LocalGradient<3> g;
      c.term.evaluate(c.q, &g, nullptr);
      ASSERT_GT(g.norm(), 0.0);
      EXPECT_LE((g.segment<3>(0) + g.segment<3>(3)).norm(), 0.0);
      const Vector3 torque = c.q.points[0].cross(Vector3(g.segment<3>(0))) +
                             c.q.points[1].cross(Vector3(g.segment<3>(3))) + g.segment<3>(6);
      // Round-off: P t = t − a d and t × d are differences of O(1) vectors, so the gradient
      // carries an absolute error ~eps·c/L (points) and ~eps·c (θ), however small a kink
      // makes it; the lever arms multiply the former by ‖x_j‖.
      const double cst = 0.5 * c.term.stiffness * c.term.rest_length;
      const double L = (c.q.points[1] - c.q.points[0]).norm();
      const double arms = c.q.points[0].norm() + c.q.points[1].norm();
      EXPECT_LE(torque.norm(), 32 * kEps * cst * (1.0 + arms / L)) << angle << " " << kink;
    }
  }
}

TEST(RodShearTerm, CoincidentNodesAreFiniteAndInert) {
  ShearCase c;
  c.term = {{-1, -1, -1}, 0, 1, 0, 1.0, 2.0};
  c.q.points = {Vector3(1.0, 2.0, 3.0), Vector3(1.0, 2.0, 3.0)};
  c.q.rotations = {Matrix3::Identity()};
  LocalGradient<3> g;
  LocalHessian<3> H;
  EXPECT_EQ(c.term.evaluate(c.q, &g, &H), 1.0);  // ½ k l with d := 0
  EXPECT_TRUE(g.isZero(0.0));
  EXPECT_TRUE(H.isZero(0.0));
}

// ----------------------------------------------------------------------------------------
// Bend / twist  ½ l Δωᵀ K Δω,  ω = vee(R_aᵀ R_b)/l.

struct BendCase {
  RodBendTwist term;
  State q;
  fd::Dofs dofs{fd::rotation_dof(0), fd::rotation_dof(1)};
};

BendCase make_bend(double l, double K_scale, const Matrix3& Ra, const Matrix3& Q,
                   const Vector3& rest_darboux) {
  BendCase c;
  c.term.edge0 = 0;
  c.term.edge1 = 1;
  c.term.rest_length = l;
  c.term.stiffness = K_scale * Vector3(1.0, 1.7, 0.6);  // bend, bend, twist: all distinct
  c.term.rest_darboux = rest_darboux;
  c.q.rotations = {Ra, Ra * Q};
  return c;
}

enum class Axis { kTwist, kBend, kRandom };

TEST(RodBendTwistTerm, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(301);
  // Relative rotation angles: straight (0 up to 1e-9, 1e-4), generic, kinked to 170°, twisted
  // to π − 1e-6 and π, and near 2π (a small rotation the other way).
  const std::vector<double> q_angles = {
      0.0, 1e-9, 1e-4, 1.0, 2.5, 170 * kDeg, kPi - 1e-6, kPi, 2.0 * kPi - 1e-6};
  int checked = 0;
  for (const double l : {1e-4, 1e-2, 1.0, 10.0}) {
    for (const double K : {1e-3, 1.0, 1e9}) {
      for (const double angle : kAngles) {
        for (const Axis axis : {Axis::kTwist, Axis::kBend, Axis::kRandom}) {
          for (const double q_angle : q_angles) {
            for (const bool curved_rest : {true, false}) {
              SCOPED_TRACE(trace("l, K, angle of R_a", l, K, angle));
              SCOPED_TRACE(trace("axis, angle of Q, curved rest", static_cast<double>(axis),
                                 q_angle, curved_rest));
              const Vector3 n = axis == Axis::kTwist  ? Vector3::UnitZ()
                                : axis == Axis::kBend ? random_perpendicular(Vector3::UnitZ(), rng)
                                                      : random_unit(rng);
              const Matrix3 Q = so3::exp(q_angle * n);
              // Rest curvature of a rest shape bent and twisted by 0.4 rad over one edge.
              const Vector3 rest =
                  curved_rest ? darboux_vector(Matrix3::Identity(), rotation_at(0.4, rng), l)
                              : Vector3::Zero();
              if (!curved_rest && q_angle == 0.0) continue;  // at rest: see AtRest below
              const BendCase c = make_bend(l, K, rotation_at(angle, rng), Q, rest);
              fd::TermCheckOptions opt;
              // Round-off. fd's noise floor assumes a value carrying ~eps·|ψ|; here ω = vee(Q)/l
              // is a difference of O(1) entries of Q = R_aᵀR_b, so it carries an ABSOLUTE
              // error δω ~ 16 eps/l however small ω is, and ψ = ½ l ΔωᵀKΔω carries
              //   δψ ≤ l K_max ‖Δω‖ δω = 16 eps K_max ‖Δω‖,
              // i.e. an FD gradient noise δψ/ε, with ‖Δω‖ ≤ ‖Δω(q)‖ + 2ε/l at q ⊕ ±εe_i. Near
              // Δω = 0 that is far above 16 eps|ψ|/ε (at Q ≈ exp(1e-9 n), ω̄ = 0, the FD gradient
              // is off by ~eps/1e-9 relative). Likewise g = Gᵀ R_a KΔω carries
              //   δg ≤ 16 eps K_max (1/l + ‖Δω‖),  an FD Hessian noise δg/ε.
              const Vector3 dw0 = darboux_vector(c.q.rotations[0], c.q.rotations[1], l) - rest;
              const double K_max = c.term.stiffness.maxCoeff();
              const double eps_g = opt.gradient.step, eps_h = opt.hessian.step;
              opt.gradient.abs_floor = 16 * kEps * K_max * (dw0.norm() + 2 * eps_g / l) / eps_g;
              opt.hessian.abs_floor = 16 * kEps * K_max * (1.0 / l + dw0.norm()) / eps_h;
              // ω̄ = 0 and ‖log Q‖ = π: vee(Q) = 0 (Q symmetric), so Δω = 0 and the gradient
              // vanishes (an unstable equilibrium, the rod folded back on itself); the FD
              // gradient is then compared with zero under fd's computed noise floor only.
              // The FD truncation, ε²/6·|∂³ψ|, is then all that is left of the FD gradient:
              // with ψ = ½ l ΔωᵀKΔω, ω = R_aᵀ vee(exp(sβ̂) C)/l, every s-derivative of ω is
              // at most ~1.22/l (vee of a matrix of spectral norm 1), so
              //   |ψ'''| = l |3 ω''ᵀKω' + ω'''ᵀKΔω| ≤ K_max (4.5/l + 1.22 ‖Δω‖),
              //   truncation ≤ ε² K_max (1/l + ‖Δω‖/4).
              if (!curved_rest && q_angle == kPi) {
                opt.gradient.require_nonzero = fd::NonZero::kNone;
                opt.gradient.abs_floor += eps_g * eps_g * K_max * (1.0 / l + dw0.norm() / 4);
              }
              EXPECT_TRUE(check_rod_term(c.term, c.q, c.dofs, 1.0, opt));
              ++checked;
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 4 * 3 * static_cast<int>(kAngles.size()) * 3 *
                         (2 * static_cast<int>(q_angles.size()) - 1));
}

// A splice's frame offset T (RodBendTwist::frame_offset): the term at (R_a, R_b) with T is
// the term without it at (R_a, R_b T), value, gradient and Hessian alike (a left
// perturbation of R_b is one of R_b T), and passes the FD check with T a twist about the edge
// and a generic rotation, over relative angles from 0 to π − 1e-6, also in its residual form.
TEST(RodBendTwistTerm, AFrameOffsetIsAConstantRightFactorOfTheSecondFrame) {
  std::mt19937 rng(302);
  for (const Matrix3& T : {so3::exp(0.7 * Vector3::UnitZ()), so3::exp(Vector3(0.4, -1.1, 2.0))}) {
    for (const double q_angle : {0.0, 1e-4, 1.0, kPi - 1e-6}) {
      SCOPED_TRACE(trace("angle of Q", q_angle, 0.0, 0.0));
      const Vector3 rest = darboux_vector(Matrix3::Identity(), rotation_at(0.4, rng), 0.05);
      BendCase with = make_bend(0.05, 1.0, rotation_at(1.0, rng), so3::exp(q_angle * random_unit(rng)), rest);
      with.term.has_frame_offset = true;
      with.term.frame_offset = T;
      BendCase without = with;
      without.term.has_frame_offset = false;
      without.q.rotations[1] = with.q.rotations[1] * T;
      LocalGradient<2> g1, g2;
      LocalHessian<2> H1, H2;
      EXPECT_EQ(with.term.evaluate(with.q, &g1, &H1), without.term.evaluate(without.q, &g2, &H2));
      EXPECT_EQ(g1, g2);
      EXPECT_EQ(H1, H2);
      RodBendTwist::Residual r1, r2;
      RodBendTwist::ResidualJacobian J1, J2;
      with.term.residual(with.q, r1, &J1);
      without.term.residual(without.q, r2, &J2);
      EXPECT_EQ(r1, r2);
      EXPECT_EQ(J1, J2);
      EXPECT_GT((g1 - [&] {
                   LocalGradient<2> g;
                   BendCase plain = with;
                   plain.term.has_frame_offset = false;
                   plain.term.evaluate(plain.q, &g, nullptr);
                   return g;
                 }()).norm(),
                1e-6);  // the offset matters
      fd::TermCheckOptions opt;
      opt.gradient.abs_floor = 16 * kEps * 1.7 * (1.0 / 0.05) / opt.gradient.step;
      opt.hessian.abs_floor = 16 * kEps * 1.7 * (2.0 / 0.05) / opt.hessian.step;
      EXPECT_TRUE(check_rod_term(with.term, with.q, with.dofs, 1.0, opt));
    }
  }
}

TEST(RodBendTwistTerm, FdCheckSeesTheMixedBlock) {
  // The mixed block H_ab = −S − ½N + (m·c)I is not symmetric; the FD checks must reject its
  // transpose and a version without the second-order cross terms −AB of exp(−α)exp(β).
  std::mt19937 rng(302);
  const BendCase c = make_bend(0.5, 2.0, rotation_at(1.2, rng), rotation_at(1.9, rng),
                               darboux_vector(Matrix3::Identity(), rotation_at(0.7, rng), 0.5));
  LocalGradient<2> g;
  LocalHessian<2> H;
  c.term.evaluate(c.q, &g, &H);
  ASSERT_TRUE(fd::check_term(c.term, c.q, c.dofs));
  const fd::ScalarFunction f = [&](const State& s) { return c.term.evaluate(s, nullptr, nullptr); };
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<2> gs;
    c.term.evaluate(s, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  const Matrix3 H_ab = H.block<3, 3>(0, 3);
  ASSERT_GT((H_ab - H_ab.transpose()).norm(), 1e-3 * H_ab.norm());
  LocalHessian<2> transposed = H;
  transposed.block<3, 3>(0, 3) = H_ab.transpose();
  transposed.block<3, 3>(3, 0) = H_ab;
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, transposed));
  EXPECT_FALSE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, transposed));

  // Without the second-order terms through the mixed block: H_ab = −S (Gauss–Newton-like).
  const Matrix3 C = c.q.rotations[1] * c.q.rotations[0].transpose();
  const Matrix3 G = 0.5 * (C.trace() * Matrix3::Identity() - C);
  const Matrix3 RaG = c.q.rotations[0].transpose() * G;
  const Matrix3 S = RaG.transpose() * c.term.stiffness.asDiagonal() * RaG / c.term.rest_length;
  LocalHessian<2> gauss_newton = H;
  gauss_newton.block<3, 3>(0, 3) = -0.5 * (S + S.transpose());
  gauss_newton.block<3, 3>(3, 0) = -0.5 * (S + S.transpose());
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, gauss_newton));
}

TEST(RodBendTwistTerm, StraightUntwistedRestHessianIsStiffnessOverLength) {
  // R_a = R_b = R, ω̄ = 0: C = I, G = ½(3I − I) = I, m = 0, so
  //   H_aa = H_bb = R K Rᵀ / l,   H_ab = H_ba = −R K Rᵀ / l,   g = 0, Ψ = 0.
  std::mt19937 rng(303);
  for (const double l : {1e-4, 1.0, 10.0}) {
    for (const double angle : kAngles) {
      const Matrix3 R = rotation_at(angle, rng);
      const BendCase c = make_bend(l, 5.0, R, Matrix3::Identity(), Vector3::Zero());
      LocalGradient<2> g;
      LocalHessian<2> H;
      EXPECT_EQ(c.term.evaluate(c.q, &g, &H), 0.0);  // vee(RᵀR) = 0 exactly (RᵀR symmetric)
      EXPECT_TRUE(g.isZero(0.0));
      const Matrix3 expected = R * c.term.stiffness.asDiagonal() * R.transpose() / l;
      const double tol = 16 * kEps * c.term.stiffness.maxCoeff() / l;
      EXPECT_LE((H.block<3, 3>(0, 0) - expected).norm(), tol) << l << " " << angle;
      EXPECT_LE((H.block<3, 3>(3, 3) - expected).norm(), tol) << l << " " << angle;
      EXPECT_LE((H.block<3, 3>(0, 3) + expected).norm(), tol) << l << " " << angle;
      EXPECT_LE((H.block<3, 3>(3, 0) + expected).norm(), tol) << l << " " << angle;
    }
  }
}

TEST(RodBendTwistTerm, AtRestGradientVanishesAndHessianIsPsd) {
  // ω̄ = ω(R_a, R_b): Δω = 0 exactly, so m = 0, g = 0 and H = l JᵀKJ (PSD, rank 3: the common
  // rotation of both frames is a null direction).
  std::mt19937 rng(304);
  for (const double l : {1e-4, 1.0, 10.0}) {
    for (const double angle : kAngles) {
      for (const double q_angle : {0.3, 1.5, 170 * kDeg}) {
        const Matrix3 Ra = rotation_at(angle, rng);
        const Matrix3 Q = rotation_at(q_angle, rng);
        const BendCase c = make_bend(l, 3.0, Ra, Q, darboux_vector(Ra, Ra * Q, l));
        LocalGradient<2> g;
        LocalHessian<2> H;
        EXPECT_EQ(c.term.evaluate(c.q, &g, &H), 0.0);
        EXPECT_TRUE(g.isZero(0.0));
        const Eigen::SelfAdjointEigenSolver<LocalHessian<2>> eig(H);
        const double scale = eig.eigenvalues().cwiseAbs().maxCoeff();
        EXPECT_GE(eig.eigenvalues().minCoeff(), -64 * kEps * scale) << angle << " " << q_angle;
        EXPECT_EQ((eig.eigenvalues().array() > 1e-9 * scale).count(), 3) << angle << " " << q_angle;
      }
    }
  }
}

TEST(RodBendTwistTerm, TorqueBalanceAndCommonRotationNullSpace) {
  // Ψ(exp(φ)R_a, exp(φ)R_b) = Ψ(R_a, R_b) for all φ (Q unchanged). First order: g_a + g_b = 0.
  // Second order, along α = β = φ: [I I] H [I; I] = H_aa + H_ab + H_ba + H_bb = 0. Only that
  // quadratic form must vanish: H [I; I] itself need not, because exp(φ)exp(α) ≠ exp(φ + α)
  // at second order (indeed H_aa + H_ab = ¼ (Nᵀ − N), see rod_terms.hpp).
  std::mt19937 rng(305);
  for (const double angle : kAngles) {
    for (const double q_angle : {1e-4, 1.0, 170 * kDeg, kPi - 1e-6, kPi}) {
      const BendCase c = make_bend(0.3, 2.0, rotation_at(angle, rng), rotation_at(q_angle, rng),
                                   darboux_vector(Matrix3::Identity(), rotation_at(0.6, rng), 0.3));
      LocalGradient<2> g;
      LocalHessian<2> H;
      c.term.evaluate(c.q, &g, &H);
      ASSERT_GT(g.norm(), 0.0);
      EXPECT_TRUE((g.segment<3>(0) + g.segment<3>(3)).isZero(0.0));
      const Matrix3 sum =
          H.block<3, 3>(0, 0) + H.block<3, 3>(0, 3) + H.block<3, 3>(3, 0) + H.block<3, 3>(3, 3);
      EXPECT_LE(sum.norm(), 64 * kEps * H.norm()) << angle << " " << q_angle;
    }
  }
}

TEST(RodBendTwistTerm, PureTwistAndPureBendHaveClosedFormEnergies) {
  // R_b = R_a exp(φ n), n a material axis: Q = exp(φ n) and vee(Q) = sin φ n, so
  //   ω = sin φ / l · n,   Ψ = ½ K_n sin²φ / l   (ω̄ = 0).
  std::mt19937 rng(306);
  const double l = 0.25;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double phi : {1e-4, 0.5, 1.5, 3.0}) {
      const Vector3 n = Vector3::Unit(axis);
      const Matrix3 Ra = rotation_at(1.3, rng);
      const BendCase c = make_bend(l, 4.0, Ra, so3::exp(phi * n), Vector3::Zero());
      const Vector3 omega = darboux_vector(c.q.rotations[0], c.q.rotations[1], l);
      EXPECT_LE((omega - std::sin(phi) / l * n).norm(), 16 * kEps / l) << axis << " " << phi;
      const double K_n = c.term.stiffness(axis);
      const double expected = 0.5 * K_n * std::sin(phi) * std::sin(phi) / l;
      EXPECT_NEAR(c.term.evaluate(c.q, nullptr, nullptr), expected,
                  64 * kEps * K_n / l * std::abs(std::sin(phi)))
          << axis << " " << phi;
    }
  }
}

// ----------------------------------------------------------------------------------------
// Objectivity: a rigid rotation G of the whole configuration (x → G x, R → G R) leaves every
// energy unchanged. Derivatives are covariant: f(exp(δ) G R) = f(G exp(Gᵀδ) R) and
// f(G(x + Gᵀδ)) = f(x + Gᵀδ) for a rotated state, so g' = G g and H' = G H Gᵀ blockwise.

template <int B>
void expect_covariant(const LocalGradient<B>& g, const LocalHessian<B>& H,
                      const LocalGradient<B>& g2, const LocalHessian<B>& H2, const Matrix3& G,
                      const std::string& what) {
  Eigen::Matrix<double, 3 * B, 3 * B> D = Eigen::Matrix<double, 3 * B, 3 * B>::Zero();
  for (int b = 0; b < B; ++b) D.template block<3, 3>(3 * b, 3 * b) = G;
  EXPECT_LE((g2 - D * g).norm(), 1e-12 * g.norm()) << what;
  EXPECT_LE((H2 - D * H * D.transpose()).norm(), 1e-12 * H.norm()) << what;
}

TEST(RodTerms, AreObjective) {
  std::mt19937 rng(401);
  for (const double angle : kAngles) {
    for (const double g_angle : {1e-9, 1.0, kPi - 1e-6, kPi}) {
      const Matrix3 G = rotation_at(g_angle, rng);
      const auto rotate = [&](State q) {
        for (Vector3& x : q.points) x = G * x;
        for (Matrix3& R : q.rotations) R = G * R;
        return q;
      };
      {
        const StretchCase c = make_stretch(0.7, 5.0, 1.1, rng);
        LocalGradient<2> g, g2;
        LocalHessian<2> H, H2;
        const double v = c.term.evaluate(c.q, &g, &H);
        const double v2 = c.term.evaluate(rotate(c.q), &g2, &H2);
        EXPECT_NEAR(v2, v, 1e-13 * v);
        expect_covariant<2>(g, H, g2, H2, G, "stretch");
      }
      {
        const ShearCase c = make_shear(0.7, 5.0, 1.1, angle, 1.2, rng);
        LocalGradient<3> g, g2;
        LocalHessian<3> H, H2;
        const double v = c.term.evaluate(c.q, &g, &H);
        const double v2 = c.term.evaluate(rotate(c.q), &g2, &H2);
        EXPECT_NEAR(v2, v, 1e-13 * v);
        expect_covariant<3>(g, H, g2, H2, G, "shear");
      }
      {
        const BendCase c =
            make_bend(0.7, 5.0, rotation_at(angle, rng), rotation_at(2.0, rng),
                      darboux_vector(Matrix3::Identity(), rotation_at(0.5, rng), 0.7));
        LocalGradient<2> g, g2;
        LocalHessian<2> H, H2;
        const double v = c.term.evaluate(c.q, &g, &H);
        const double v2 = c.term.evaluate(rotate(c.q), &g2, &H2);
        EXPECT_NEAR(v2, v, 1e-13 * v);
        expect_covariant<2>(g, H, g2, H2, G, "bend-twist");
      }
    }
  }
}

}  // namespace
}  // namespace liedyn

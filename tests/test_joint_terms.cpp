// Rotational joint terms (lib/joint_terms.hpp): the hinge's axis alignment
// V = ½k‖R_a â − R_b b̂‖² and the weld V = ½k‖log(R_a A Bᵀ R_bᵀ)‖². Value vs Lie gradient vs Lie
// Hessian by central finite differences in the tangent space (tests/fd_check.hpp, left
// perturbations R ← exp(εe_j)R), both ends free and with end b the world, at the relative
// angles 0, 1e-9, 1e-4, 0.5, 2, π − 1e-6 between generic frames and axes (random rotations,
// fixed seeds) and stiffnesses 1e-6, 1, 1e9; the least-squares forms (½‖r‖² = V, Jᵀr = g, J by
// FD of r); the half turn of the weld (the cut locus of log) and the opposite axes of the
// hinge; and physical facts derived by hand (rest, invariances, the spectrum of the weld's
// Hessian).
//
// Tolerances are fd_check.hpp's (rtol 1e-6, floor 1e-9 of the object, computed round-off
// noise kNoiseUlps·eps·max|f|/ε) unless stated next to the check. Two absolute floors recur,
// both from round-off that is ABSOLUTE rather than relative to the quantity (fd's noise model
// is relative):
//   * the analytic gradients are k times vectors built from unit-size entries (a × b of unit
//     vectors, log of a rotation matrix), with an absolute round-off of a few eps, at most
//     ~π·few eps for log near π: 64 eps·k covers it and dominates only where g ~ eps·k (the
//     relative angle 0);
//   * the Hessian is checked against FD of that gradient, so the same absolute round-off,
//     divided by the step, 64 eps·k/ε: ~1.4e-8·k, below rtol·|H| ~ 1e-6·k for H = O(k); it
//     only matters for the entries of H that vanish.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "fd_check.hpp"
#include "lib/joint_terms.hpp"
#include "lib/so3.hpp"

namespace liedyn {
namespace {

using fd::random_perpendicular;
using fd::random_unit;
using fd::rotation_at;
using fd::trace;

constexpr double kPi = std::numbers::pi;
constexpr double kEps = std::numeric_limits<double>::epsilon();

// The relative angles tested: the weld's angle of E, the hinge's angle between the axes.
const std::vector<double> kRelativeAngles = {0.0, 1e-9, 1e-4, 0.5, 2.0, kPi - 1e-6};
const std::vector<double> kStiffnesses = {1e-6, 1.0, 1e9};

Matrix3 random_rotation(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(0.1, kPi - 0.1);
  return rotation_at(angle(rng), rng);
}

template <class Term>
bool all_finite(const Term& term, const State& q) {
  LocalGradient<2> g;
  LocalHessian<2> H;
  typename Term::Residual r;
  typename Term::ResidualJacobian J;
  const double v = term.evaluate(q, &g, &H);
  term.residual(q, r, &J);
  return std::isfinite(v) && g.allFinite() && H.allFinite() && r.allFinite() && J.allFinite();
}

// A term, its state and its DOFs: rotation 0 is end a; rotation 1 is end b unless b is the
// world (rotation_b = −1, offset −1, no_dof()).
template <class Term>
struct Case {
  Term term;
  State q;
  fd::Dofs dofs;
};

template <class Term>
Case<Term> make_ends(double stiffness, bool world_b, std::mt19937& rng) {
  Case<Term> c;
  c.term.stiffness = stiffness;
  c.term.rotation_a = 0;
  c.q.rotations = {random_rotation(rng)};
  if (world_b) {
    c.term.rotation_b = -1;
    c.term.offsets = {0, -1};
    c.dofs = {fd::rotation_dof(0), fd::no_dof()};
  } else {
    c.term.rotation_b = 1;
    c.term.offsets = {0, 3};
    c.q.rotations.push_back(random_rotation(rng));
    c.dofs = {fd::rotation_dof(0), fd::rotation_dof(1)};
  }
  return c;
}

Matrix3 rotation_b_of(const State& q, int rotation_b) {
  return rotation_b < 0 ? Matrix3::Identity() : q.rotations[rotation_b];
}

// Hinge: generic â, and b̂ chosen so that b = R_b b̂ makes the angle `angle` with a = R_a â
// (b = exp(angle m) a, m ⊥ a random).
Case<JointAlignment> alignment_case(double angle, double stiffness, bool world_b,
                                    std::mt19937& rng) {
  Case<JointAlignment> c = make_ends<JointAlignment>(stiffness, world_b, rng);
  c.term.axis_a = random_unit(rng);
  const Vector3 a = c.q.rotations[0] * c.term.axis_a;
  const Vector3 b = so3::exp(angle * random_perpendicular(a, rng)) * a;
  c.term.axis_b = (rotation_b_of(c.q, c.term.rotation_b).transpose() * b).normalized();
  return c;
}

// Weld: generic A, and B chosen so that E = R_a A Bᵀ R_bᵀ = exp(angle n), n random:
// B = R_bᵀ exp(−angle n) R_a A.
Case<JointWeld> weld_case(double angle, double stiffness, bool world_b, std::mt19937& rng) {
  Case<JointWeld> c = make_ends<JointWeld>(stiffness, world_b, rng);
  c.term.frame_a = random_rotation(rng);
  const Vector3 n = random_unit(rng);
  c.term.frame_b = rotation_b_of(c.q, c.term.rotation_b).transpose() * so3::exp(-angle * n) *
                   c.q.rotations[0] * c.term.frame_a;
  return c;
}

// fd::check_term, or (value_hessian = false) the same checks without the second differences
// of the value.
template <class Term>
::testing::AssertionResult check_derivatives(const Case<Term>& c, const fd::TermCheckOptions& opt,
                                             bool value_hessian) {
  if (value_hessian) return fd::check_term(c.term, c.q, c.dofs, opt);
  LocalGradient<2> g;
  LocalHessian<2> H;
  const double value = c.term.evaluate(c.q, &g, &H);
  if (value != c.term.evaluate(c.q, nullptr, nullptr)) {
    return ::testing::AssertionFailure() << "value depends on whether derivatives are requested";
  }
  const fd::ScalarFunction f = [&](const State& s) { return c.term.evaluate(s, nullptr, nullptr); };
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<2> gs;
    c.term.evaluate(s, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  ::testing::AssertionResult r = fd::check_lie_gradient(f, c.q, c.dofs, g, opt.gradient);
  if (!r) return r;
  return fd::check_lie_hessian(grad, c.q, c.dofs, H, opt.hessian);
}

// The least-squares form (lib/term.hpp): ½‖r‖² = V (no constant) to 16 eps of their size;
// Jᵀr = g to 64 eps·(‖J‖‖r‖ + ‖g‖ + gradient_sigma) (gradient_sigma: evaluate() forms g as a
// small difference of larger terms); J against central differences of r, whose round-off is
// absolute at the scale √k of what r is computed from (r_scale).
template <class Term>
::testing::AssertionResult check_residual(const Case<Term>& c, double gradient_sigma,
                                          const fd::FdOptions& jacobian, bool zero_gradient) {
  typename Term::Residual r, r_only;
  typename Term::ResidualJacobian J;
  c.term.residual(c.q, r, &J);
  c.term.residual(c.q, r_only, nullptr);
  if (r != r_only) return ::testing::AssertionFailure() << "r differs with and without J";
  LocalGradient<2> g;
  const double value = c.term.evaluate(c.q, &g, nullptr);
  const double half = 0.5 * r.squaredNorm();
  if (!(std::abs(half - value) <= 16 * kEps * (half + value))) {
    return ::testing::AssertionFailure() << "½‖r‖² = " << half << ", V = " << value;
  }
  // Only the compared (DOF) blocks: a world end's columns are written but are not DOFs.
  LocalGradient<2> Jtr = J.transpose() * r;
  for (int b = 0; b < 2; ++b) {
    if (c.dofs[b].kind == fd::DofKind::kNone) {
      Jtr.segment<3>(3 * b).setZero();
      g.segment<3>(3 * b).setZero();
    }
  }
  const double tol = 64 * kEps * (J.norm() * r.norm() + g.norm() + gradient_sigma);
  const double err = (Jtr - g).cwiseAbs().maxCoeff();
  if (!(err <= tol)) {
    return ::testing::AssertionFailure() << "Jᵀr = " << Jtr.transpose() << ", g = " << g.transpose()
                                         << ", |error| " << err << " > " << tol;
  }
  if (!zero_gradient && !(g.cwiseAbs().maxCoeff() > 1e3 * tol)) {
    return ::testing::AssertionFailure() << "gradient negligible (" << g.norm() << ", tolerance "
                                         << tol << "): Jᵀr = g would prove nothing";
  }
  const fd::VectorFunction F = [&](const State& s) {
    typename Term::Residual rs;
    c.term.residual(s, rs, nullptr);
    return Eigen::VectorXd(rs);
  };
  return fd::check_vector_jacobian(F, c.q, c.dofs, J, jacobian, std::sqrt(c.term.stiffness));
}

// ========================================================================================
// Hinge axis alignment  V = ½k‖a − b‖²,  a = R_a â,  b = R_b b̂.

// Absolute round-off floors of both joint terms (their round-off is absolute, ~eps·k, not
// relative to entries that may vanish), set after the FD steps: the Hessian's floor scales
// with 1/step. At angle 0 the gradient is round-off itself.
void set_joint_floors(fd::TermCheckOptions& opt, double angle, double k) {
  opt.gradient.abs_floor = 64 * kEps * k;
  opt.hessian.abs_floor = 64 * kEps * k / opt.hessian.step;
  if (angle == 0.0) opt.gradient.require_nonzero = fd::NonZero::kNone;
}

// FD options at a relative angle. Near opposite axes (π − 1e-6) the gradient k·a×b is only
// ~1e-6·k while V ≈ 2k: at ε = 1e-6 the value's round-off, 16 eps·2k/ε ≈ 7e-9·k, would leave
// the gradient only ~80 times above it, less than the 100 fd demands. V is smooth there
// (no cut locus), and along a line exp(s e_j)a its third derivative is k e_j·(a × b) = −g_j
// (a''' = −e_j × a), so the truncation is ε²/6 of the gradient itself: ε = 1e-5 gives a round-off
// floor of 7e-10·k and truncation 2e-11·|g|.
fd::TermCheckOptions alignment_options(double angle, double k) {
  fd::TermCheckOptions opt;
  if (angle > 3.0) opt.gradient.step = 1e-5;
  set_joint_floors(opt, angle, k);
  return opt;
}

TEST(JointTermAlignment, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(101);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double k : kStiffnesses) {
      for (const double angle : kRelativeAngles) {
        SCOPED_TRACE(trace("world b, stiffness, angle", world_b, k, angle));
        const Case<JointAlignment> c = alignment_case(angle, k, world_b, rng);
        const Vector3 a = c.q.rotations[0] * c.term.axis_a;
        const Vector3 b = rotation_b_of(c.q, c.term.rotation_b) * c.term.axis_b;
        EXPECT_NEAR(std::acos(std::clamp(a.dot(b), -1.0, 1.0)), angle, 1e-7);
        // V = k(1 − cos θ) = 2k sin²(θ/2).
        const double expected = 2 * k * std::pow(std::sin(0.5 * angle), 2);
        EXPECT_NEAR(c.term.evaluate(c.q, nullptr, nullptr), expected,
                    16 * kEps * k * (1 + angle) + 1e-12 * expected);
        EXPECT_TRUE(check_derivatives(c, alignment_options(angle, k), true));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 3 * 6);
}

TEST(JointTermAlignment, OppositeAxesAreAMaximumWithZeroGradient) {
  // b = −a: V = ½k‖2a‖² = 2k; g = ∓k a × b = 0; the diagonal blocks −k[½(abᵀ + baᵀ) − (a·b)I]
  // = k(aaᵀ − I) are negative semi-definite (eigenvalues 0, −k, −k): the flipped hinge sits on
  // a maximum, not in a second rest state. V is smooth there: the Hessian is FD-checked too.
  std::mt19937 rng(102);
  for (const bool world_b : {false, true}) {
    for (const double k : kStiffnesses) {
      SCOPED_TRACE(trace("world b, stiffness", world_b, k));
      Case<JointAlignment> c = make_ends<JointAlignment>(k, world_b, rng);
      c.term.axis_a = random_unit(rng);
      const Vector3 a = c.q.rotations[0] * c.term.axis_a;
      // World b: R_b = I, so b = −a exactly and a × b = −(a × a) = 0 exactly.
      c.term.axis_b = -(rotation_b_of(c.q, c.term.rotation_b).transpose() * a);
      LocalGradient<2> g;
      LocalHessian<2> H;
      const double v = c.term.evaluate(c.q, &g, &H);
      EXPECT_NEAR(v, 2 * k, 16 * kEps * k);
      EXPECT_TRUE(all_finite(c.term, c.q));
      if (world_b) {
        EXPECT_TRUE(g.isZero(0.0)) << g.transpose();
      } else {
        EXPECT_LE(g.norm(), 16 * kEps * k) << g.transpose();
      }
      const Matrix3 expected_diagonal = k * (a * a.transpose() - Matrix3::Identity());
      EXPECT_LE((H.topLeftCorner<3, 3>() - expected_diagonal).norm(), 16 * kEps * k);
      const Eigen::SelfAdjointEigenSolver<Matrix3> eig(H.topLeftCorner<3, 3>());
      EXPECT_LE(eig.eigenvalues().maxCoeff(), 16 * kEps * k);
      EXPECT_NEAR(eig.eigenvalues().minCoeff(), -k, 16 * kEps * k);

      fd::TermCheckOptions opt = alignment_options(kPi, k);
      opt.gradient.require_nonzero = fd::NonZero::kNone;  // g = 0 (round-off)
      EXPECT_TRUE(check_derivatives(c, opt, true));
    }
  }
}

TEST(JointTermAlignment, ResidualFormMatchesEvaluate) {
  // r = √k (a − b): ½‖r‖² = V with no constant, Jᵀr = g. evaluate() forms g = −k a × b, whose
  // entries are differences of products of unit-size components: gradient_sigma = k. Also at
  // exactly opposite axes (π), where g = 0.
  std::mt19937 rng(103);
  std::vector<double> angles = kRelativeAngles;
  angles.push_back(kPi);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double k : kStiffnesses) {
      for (const double angle : angles) {
        SCOPED_TRACE(trace("world b, stiffness, angle", world_b, k, angle));
        const Case<JointAlignment> c = alignment_case(angle, k, world_b, rng);
        EXPECT_TRUE(check_residual(c, k, fd::FdOptions{}, angle == 0.0 || angle == kPi));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 3 * 7);
}

TEST(JointTermAlignment, InvariantUnderRotationAboutTheAxes) {
  // A hinge turns freely: rotating body a about its own axis a (or b about b) leaves a (b), so V,
  // unchanged; so does rotating both bodies together (a·b is invariant). Hence the gradient has
  // no component about the body's own axis: a·g_a = −k a·(a × b) = 0. When the axes agree, the
  // common axis is free and V stays 0. No finite differences: a' = exp(ψa)a = a to round-off
  // (a few eps), so |V' − V| ≲ k‖a − b‖·4 eps + eps·V.
  std::mt19937 rng(104);
  for (const bool world_b : {false, true}) {
    for (const double angle : kRelativeAngles) {
      for (const double psi : {0.3, 2.0, kPi}) {
        SCOPED_TRACE(trace("world b, angle, psi", world_b, angle, psi));
        const double k = 3.0;
        const Case<JointAlignment> c = alignment_case(angle, k, world_b, rng);
        const Vector3 a = c.q.rotations[0] * c.term.axis_a;
        const Vector3 b = rotation_b_of(c.q, c.term.rotation_b) * c.term.axis_b;
        LocalGradient<2> g;
        const double v = c.term.evaluate(c.q, &g, nullptr);
        const double tol = 16 * kEps * k * ((a - b).norm() + kEps) + 4 * kEps * v;

        State qa = c.q;  // body a about its own axis
        qa.rotations[0] = so3::exp(psi * a) * qa.rotations[0];
        EXPECT_NEAR(c.term.evaluate(qa, nullptr, nullptr), v, tol);
        EXPECT_LE(std::abs(a.dot(g.head<3>())), 8 * kEps * k);
        if (!world_b) {
          State qb = c.q;  // body b about its own axis
          qb.rotations[1] = so3::exp(psi * b) * qb.rotations[1];
          EXPECT_NEAR(c.term.evaluate(qb, nullptr, nullptr), v, tol);
          EXPECT_LE(std::abs(b.dot(g.tail<3>())), 8 * kEps * k);
          State qc = c.q;  // both together, about any axis
          const Matrix3 Q = so3::exp(psi * random_unit(rng));
          qc.rotations[0] = Q * qc.rotations[0];
          qc.rotations[1] = Q * qc.rotations[1];
          EXPECT_NEAR(c.term.evaluate(qc, nullptr, nullptr), v, 2 * tol);
        }
        if (angle == 0.0) {
          EXPECT_LE(v, 64 * kEps * kEps * k);  // aligned: at rest
        }
      }
    }
  }
}

TEST(JointTermAlignment, ChecksRejectWrongDerivatives) {
  // The checks above would see a wrong sign of the mixed block or a missing ½-symmetrisation.
  std::mt19937 rng(105);
  const Case<JointAlignment> c = alignment_case(0.5, 1.0, false, rng);
  LocalGradient<2> g;
  LocalHessian<2> H;
  c.term.evaluate(c.q, &g, &H);
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<2> gs;
    c.term.evaluate(s, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  const fd::ScalarFunction f = [&](const State& s) { return c.term.evaluate(s, nullptr, nullptr); };
  ASSERT_TRUE(fd::check_lie_hessian(grad, c.q, c.dofs, H));
  LocalHessian<2> wrong = H;
  wrong.topRightCorner<3, 3>() *= -1.0;
  wrong.bottomLeftCorner<3, 3>() *= -1.0;
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, wrong));
  EXPECT_FALSE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, wrong));
  EXPECT_FALSE(fd::check_lie_gradient(f, c.q, c.dofs, Eigen::VectorXd(-g)));
}

// ========================================================================================
// Weld  V = ½k‖φ‖²,  φ = log E,  E = R_a A Bᵀ R_bᵀ.

// FD options at a relative angle. At π − 1e-6 a step must not carry E across the cut locus
// ‖φ‖ = π, where the gradient k φ flips sign: one tangent coordinate of size ε moves log E by
// ε(1 + O(ε)), so ε = 2.5e-7 keeps ‖φ‖ ≤ π − 7e-7 (value round-off 16 eps·5k/ε ≈ 7e-8·k, far
// below g ~ k). The second differences of the value would need two such steps (≤ 2ε < 1e-6)
// and a round-off floor of 16 eps·5k/ε² ≈ 0.3·k, which proves nothing: there the Hessian is
// checked against the FD of the gradient only.
fd::TermCheckOptions weld_options(double angle, double k, bool* value_hessian) {
  fd::TermCheckOptions opt;
  *value_hessian = angle < 3.0;
  if (!*value_hessian) opt.gradient.step = opt.hessian.step = 2.5e-7;
  set_joint_floors(opt, angle, k);
  return opt;
}

TEST(JointTermWeld, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(201);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double k : kStiffnesses) {
      for (const double angle : kRelativeAngles) {
        SCOPED_TRACE(trace("world b, stiffness, angle", world_b, k, angle));
        const Case<JointWeld> c = weld_case(angle, k, world_b, rng);
        const Vector3 phi = c.term.relative_rotation(c.q);
        EXPECT_NEAR(phi.norm(), angle, 64 * kEps);
        EXPECT_NEAR(c.term.evaluate(c.q, nullptr, nullptr), 0.5 * k * angle * angle,
                    64 * kEps * k * (angle + kEps));
        bool value_hessian = true;
        const fd::TermCheckOptions opt = weld_options(angle, k, &value_hessian);
        EXPECT_TRUE(check_derivatives(c, opt, value_hessian));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 3 * 6);
}

TEST(JointTermWeld, AtTheHalfTurnValueIsContinuousAndTheGradientHasNormKPi) {
  // ‖φ‖ = π is the cut locus of log: V = ½kπ² there and is continuous, but its gradient flips
  // from kφ to −kφ (a ridge; no FD across it). Checked: E exactly a half turn (E = 2nnᵀ − I and
  // diag(1, −1, −1), through a world end and identity rotations so that E is exactly that
  // matrix), and E a half turn up to round-off between generic frames; then continuity
  // E = exp((π ± δ)n): V(π − δ) = V(π + δ) = ½k(π − δ)² < ½kπ², g(π + δ) = −g(π − δ).
  std::mt19937 rng(202);
  for (const double k : kStiffnesses) {
    SCOPED_TRACE(trace("stiffness", k));
    std::vector<Case<JointWeld>> cases;
    for (int i = 0; i < 4; ++i) {
      Case<JointWeld> c = make_ends<JointWeld>(k, true, rng);
      c.q.rotations[0] = Matrix3::Identity();
      const Vector3 n = random_unit(rng);
      c.term.frame_a = i == 0 ? Matrix3(Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal())
                              : Matrix3(2.0 * n * n.transpose() - Matrix3::Identity());
      cases.push_back(c);
    }
    for (const bool world_b : {false, true}) {
      for (int i = 0; i < 3; ++i) cases.push_back(weld_case(kPi, k, world_b, rng));
    }
    for (size_t i = 0; i < cases.size(); ++i) {
      SCOPED_TRACE(trace("case", static_cast<double>(i)));
      const Case<JointWeld>& c = cases[i];
      LocalGradient<2> g;
      LocalHessian<2> H;
      const double v = c.term.evaluate(c.q, &g, &H);
      EXPECT_TRUE(all_finite(c.term, c.q));
      EXPECT_NEAR(v, 0.5 * k * kPi * kPi, 64 * kEps * k);
      EXPECT_NEAR(g.head<3>().norm(), k * kPi, 64 * kEps * k);
      EXPECT_LE((g.tail<3>() + g.head<3>()).norm(), 0.0);  // g_b = −g_a exactly
      // The Hessian stays finite and symmetric; its θ_a block k H_φ has eigenvalues k, and
      // k(π/2)cot(π/2) = 0 twice (below).
      EXPECT_LE((H - H.transpose()).cwiseAbs().maxCoeff(), 4 * kEps * H.cwiseAbs().maxCoeff());
      const Eigen::SelfAdjointEigenSolver<Matrix3> eig(H.topLeftCorner<3, 3>());
      EXPECT_GE(eig.eigenvalues().minCoeff(), -64 * kEps * k);
      EXPECT_NEAR(eig.eigenvalues().maxCoeff(), k, 64 * kEps * k);
    }

    // Continuity through π, and the flip of the gradient.
    for (const double delta : {1e-3, 1e-6, 1e-9, 1e-12}) {
      SCOPED_TRACE(trace("delta", delta));
      const Vector3 n = random_unit(rng);
      const Matrix3 R = random_rotation(rng);
      LocalGradient<2> g_below, g_above;
      Case<JointWeld> c = make_ends<JointWeld>(k, true, rng);
      c.q.rotations[0] = R;
      c.term.frame_a = R.transpose() * so3::exp((kPi - delta) * n);
      const double v_below = c.term.evaluate(c.q, &g_below, nullptr);
      c.term.frame_a = R.transpose() * so3::exp((kPi + delta) * n);
      const double v_above = c.term.evaluate(c.q, &g_above, nullptr);
      const double expected = 0.5 * k * (kPi - delta) * (kPi - delta);
      EXPECT_NEAR(v_below, expected, 64 * kEps * k);
      EXPECT_NEAR(v_above, expected, 64 * kEps * k);
      EXPECT_LE(v_below, 0.5 * k * kPi * kPi + 64 * kEps * k);
      EXPECT_LE(std::abs(v_below - 0.5 * k * kPi * kPi), 1.01 * k * kPi * delta + 64 * kEps * k);
      EXPECT_LE((g_above.head<3>() + g_below.head<3>()).norm(), 64 * kEps * k);
      EXPECT_NEAR(g_below.head<3>().dot(n), k * (kPi - delta), 64 * kEps * k);
    }
  }
}

TEST(JointTermWeld, ResidualFormMatchesEvaluate) {
  // r = √k φ: ½‖r‖² = V, Jᵀr = k[J_l⁻¹ᵀφ, −EᵀJ_l⁻¹ᵀφ] = k[φ, −φ] = g (no cancellation in g:
  // gradient_sigma 0), J by FD of r. FD steps as in DerivativesMatchFiniteDifferences (no step
  // across π). At exactly π (through round-off, either side) only the identities, which hold
  // for whichever sign log picks.
  std::mt19937 rng(203);
  std::vector<double> angles = kRelativeAngles;
  angles.push_back(kPi);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double k : kStiffnesses) {
      for (const double angle : angles) {
        SCOPED_TRACE(trace("world b, stiffness, angle", world_b, k, angle));
        const Case<JointWeld> c = weld_case(angle, k, world_b, rng);
        fd::FdOptions jacobian;
        if (angle > 3.0) jacobian.step = 2.5e-7;
        if (angle == kPi) {
          // The half turn: no FD (the residual flips sign across it).
          jacobian.rtol = 1e300;
          jacobian.require_nonzero = fd::NonZero::kNone;
        }
        EXPECT_TRUE(check_residual(c, 0.0, jacobian, angle == 0.0));
        EXPECT_TRUE(all_finite(c.term, c.q));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 3 * 7);
}

TEST(JointTermWeld, ZeroWhenTheFramesAgree) {
  // R_a A = R_b B: E = I, φ = 0, V = 0, g = 0, and the Hessian is k[[I, −E], [−Eᵀ, I]] (H_φ = I):
  // eigenvalues 0 (common rotations) and 2k, each three times. Exactly so for identity frames;
  // to round-off (E = I + O(eps), ‖φ‖ ≲ 8 eps) for generic ones.
  {
    Case<JointWeld> c;
    c.term.stiffness = 5.0;
    c.term.rotation_a = 0;
    c.term.rotation_b = 1;
    c.term.offsets = {0, 3};
    c.q.rotations = {Matrix3::Identity(), Matrix3::Identity()};
    LocalGradient<2> g;
    EXPECT_EQ(c.term.evaluate(c.q, &g, nullptr), 0.0);
    EXPECT_TRUE(g.isZero(0.0));
  }
  std::mt19937 rng(204);
  for (const bool world_b : {false, true}) {
    for (const double k : kStiffnesses) {
      SCOPED_TRACE(trace("world b, stiffness", world_b, k));
      Case<JointWeld> c = make_ends<JointWeld>(k, world_b, rng);
      c.term.frame_a = random_rotation(rng);
      c.term.frame_b =
          rotation_b_of(c.q, c.term.rotation_b).transpose() * c.q.rotations[0] * c.term.frame_a;
      LocalGradient<2> g;
      LocalHessian<2> H;
      const double v = c.term.evaluate(c.q, &g, &H);
      EXPECT_LE(v, 0.5 * k * 64 * kEps * kEps);
      EXPECT_LE(g.norm(), 16 * kEps * k);
      if (world_b) {  // the θ_a block k I only
        const Eigen::SelfAdjointEigenSolver<Matrix3> eig(H.topLeftCorner<3, 3>());
        for (int i = 0; i < 3; ++i) EXPECT_NEAR(eig.eigenvalues()(i), k, 64 * kEps * k) << i;
      } else {
        const Eigen::SelfAdjointEigenSolver<LocalHessian<2>> eig(H);
        for (int i = 0; i < 6; ++i) {
          EXPECT_NEAR(eig.eigenvalues()(i), i < 3 ? 0.0 : 2.0 * k, 64 * kEps * k) << i;
        }
      }
    }
  }
}

TEST(JointTermWeld, InvariantUnderACommonRotationAndMotionsThatKeepE) {
  // Rotating both bodies by the same Q conjugates E (E' = Q E Qᵀ), so V (a function of ‖φ‖ only)
  // is unchanged: frame indifference. In the tangent space that is δ = (s, s); and the motions
  // δ = (x, Eᵀx) keep E itself: exp(x) E exp(−Eᵀx) = exp(x) exp(−x) E = E. Along both lines
  // q ⊕ uδ the value is constant, so the Hessian's quadratic form vanishes on them, δᵀHδ = 0
  // (isotropic directions, not in the kernel: Hδ ≠ 0 in general). The kernel vector (φ, φ)
  // (Eᵀφ = φ) gives H(φ, φ) = k(H_φφ − H_φEφ + ½ hat(φ)Eφ) = 0.
  // No finite differences; round-off: ‖φ‖ to a few eps, so |V' − V| ≲ 64 eps·k(‖φ‖ + eps).
  std::mt19937 rng(205);
  for (const double angle : kRelativeAngles) {
    SCOPED_TRACE(trace("angle", angle));
    const double k = 0.7;
    const Case<JointWeld> c = weld_case(angle, k, false, rng);
    Matrix3 E;
    const Vector3 phi = c.term.relative_rotation(c.q, &E);
    LocalHessian<2> H;
    const double v = c.term.evaluate(c.q, nullptr, &H);
    const double tol = 64 * kEps * k * (phi.norm() + kEps);
    for (const double psi : {0.3, 2.0, kPi}) {
      const Matrix3 Q = so3::exp(psi * random_unit(rng));
      State q = c.q;
      q.rotations[0] = Q * q.rotations[0];
      q.rotations[1] = Q * q.rotations[1];
      EXPECT_NEAR(c.term.evaluate(q, nullptr, nullptr), v, tol) << psi;
    }
    for (int i = 0; i < 3; ++i) {
      const Vector3 x = random_unit(rng);
      Eigen::VectorXd keep(6), common(6);
      keep << x, E.transpose() * x;
      common << x, x;
      for (const double u : {0.5, 2.0}) {
        const Eigen::VectorXd step = u * keep;
        EXPECT_NEAR(c.term.evaluate(fd::perturb(c.q, c.dofs, step), nullptr, nullptr), v, tol);
      }
      EXPECT_LE(std::abs(keep.dot(H * keep)), 64 * kEps * H.norm());
      EXPECT_LE(std::abs(common.dot(H * common)), 64 * kEps * H.norm());
    }
    if (angle > 0.0) {
      Eigen::VectorXd kernel(6);
      kernel << phi.normalized(), phi.normalized();
      EXPECT_LE((H * kernel).norm(), 64 * kEps * H.norm());
    }
  }
}

TEST(JointTermWeld, HessianNearTheHalfTurnIsSymmetricWithTheDerivedSpectrum) {
  // With t = ‖φ‖ and τ = 1 − c(t)t² = (t/2)cot(t/2) (≥ 0 on [0, π], 0 at π), H_φ = I + c hat(φ)²
  // has eigenvalues 1 (along φ) and τ (twice, across).
  //  * One end the world: the Hessian is k H_φ, positive semi-definite up to and at π: the
  //    energy is convex in the chart exp(θ) R_a.
  //  * Both ends free: in the orthogonal coordinates u = (x + y)/√2, d = (x − y)/√2 with
  //    x = θ_a, y = Eθ_b, the quadratic form is k(2dᵀH_φd + dᵀhat(φ)u), so the eigenvalues are
  //    0 (u ∥ φ), 2k (d ∥ φ) and k(τ ± √(τ² + t²/4)) (twice each, across φ). For t > 0 one pair
  //    is NEGATIVE: the joint energy ½ dist(F_a, F_b)² is not convex on SO(3) × SO(3) (positive
  //    curvature: turning both frames the same way about an axis across φ brings them closer to
  //    second order). At t → π the pair tends to ±πk/2.
  std::mt19937 rng(206);
  for (const double angle : {0.5, 2.0, 3.0, kPi - 1e-4, kPi - 1e-6, kPi - 1e-9, kPi}) {
    for (const double k : kStiffnesses) {
      SCOPED_TRACE(trace("angle, stiffness", angle, k));
      for (const bool world_b : {false, true}) {
        const Case<JointWeld> c = weld_case(angle, k, world_b, rng);
        const double t = c.term.relative_rotation(c.q).norm();
        const double tau = 0.5 * t / std::tan(0.5 * t);
        LocalHessian<2> H;
        c.term.evaluate(c.q, nullptr, &H);
        ASSERT_TRUE(H.allFinite());
        const double asym = (H - H.transpose()).cwiseAbs().maxCoeff();
        EXPECT_LE(asym, 4 * kEps * H.cwiseAbs().maxCoeff());
        const double tol = 64 * kEps * H.norm();
        if (world_b) {
          const Eigen::SelfAdjointEigenSolver<Matrix3> eig(H.topLeftCorner<3, 3>());
          const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
          EXPECT_GE(ev(0), -tol);
          EXPECT_NEAR(ev(0), k * tau, tol);
          EXPECT_NEAR(ev(1), k * tau, tol);
          EXPECT_NEAR(ev(2), k, tol);
          if (angle < kPi) {
            EXPECT_GT(ev(0), 0.0);
          }
        } else {
          const Eigen::SelfAdjointEigenSolver<LocalHessian<2>> eig(H);
          const double root = std::sqrt(tau * tau + 0.25 * t * t);
          std::vector<double> expected = {0.0, 2.0, tau - root, tau - root, tau + root, tau + root};
          std::sort(expected.begin(), expected.end());
          for (int i = 0; i < 6; ++i) {
            EXPECT_NEAR(eig.eigenvalues()(i), k * expected[static_cast<size_t>(i)], tol) << i;
          }
          // Indefinite away from rest: τ − √(τ² + t²/4) ≈ −0.031 at t = 0.5, → −π/2 at π.
          EXPECT_LT(eig.eigenvalues()(0), -1e3 * tol);
          EXPECT_NEAR(eig.eigenvalues()(0), k * (tau - root), tol);
        }
      }
    }
  }
}

TEST(JointTermWeld, ChecksRejectWrongDerivatives) {
  // The FD checks see the BCH term ½k hat(φ)E of the mixed block and the curvature c hat(φ)².
  std::mt19937 rng(207);
  const Case<JointWeld> c = weld_case(2.0, 1.0, false, rng);
  Matrix3 E;
  const Vector3 phi = c.term.relative_rotation(c.q, &E);
  LocalHessian<2> H;
  c.term.evaluate(c.q, nullptr, &H);
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<2> gs;
    c.term.evaluate(s, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  const fd::ScalarFunction f = [&](const State& s) { return c.term.evaluate(s, nullptr, nullptr); };
  ASSERT_TRUE(fd::check_lie_hessian(grad, c.q, c.dofs, H));
  ASSERT_TRUE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, H));
  LocalHessian<2> no_bch = H;
  const Matrix3 half_hat_phi_E = 0.5 * so3::hat(phi) * E;
  no_bch.topRightCorner<3, 3>() -= half_hat_phi_E;
  no_bch.bottomLeftCorner<3, 3>() -= half_hat_phi_E.transpose();
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, no_bch));
  EXPECT_FALSE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, no_bch));
  LocalHessian<2> flat = H;  // H_φ = I: no curvature term
  const Matrix3 hat_phi = so3::hat(phi);
  const double t = phi.norm();
  const Matrix3 curvature = (1.0 / (t * t) - 0.5 / (t * std::tan(0.5 * t))) * hat_phi * hat_phi;
  flat.topLeftCorner<3, 3>() -= curvature;
  flat.bottomRightCorner<3, 3>() -= curvature;
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, flat));
}

}  // namespace
}  // namespace liedyn

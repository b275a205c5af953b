// Joint terms (lib/joint_terms.hpp): the translation JointPoint V = ½k‖p_b − (p_a − R_a s)‖²,
// the hinge's axis alignment V = ½k‖R_a(â + s) − R_b b̂‖² and the weld
// V = ½k‖log(R_a A S Bᵀ R_bᵀ)‖², with s, S the augmented-Lagrangian shifts.
//  * Value vs Lie gradient vs Lie Hessian by central finite differences in the tangent space
//    (tests/fd_check.hpp, left perturbations R ← exp(εe_j)R), and the least-squares forms
//    (½‖r‖² = V, Jᵀr = g, J by FD of r):
//      - the rotational terms unshifted, both ends free and with end b the world, at the
//        relative angles 0, 1e-9, 1e-4, 0.5, 2, π − 1e-6 between generic frames and axes
//        (random rotations, fixed seeds) and stiffnesses 1e-6, 1, 1e9;
//      - the same with a NON-zero shift (the header says the derivations hold unchanged): a
//        hinge shift of size 1e-3 and 0.3, a weld shift S at 1e-3 and 0.8 rad, the relative
//        angle taken by the shifted or by the joint's own geometry;
//      - JointPoint with end b a body, the world or a rod node (a point without rotation),
//        generic levers, body rotations at 0, 1e-9, 1e-4, π − 1e-6, π, 2π − 1e-6, the same
//        stiffnesses, shift zero and 0.3, generic and at rest;
//    and that the checks reject wrong derivatives.
//  * The half turn of the weld (the cut locus of log), the opposite axes of the hinge, and
//    physical facts derived by hand (rest, invariances, the spectrum of the weld's Hessian).
//  * The Constraint interface (term.hpp): violation() ignores the shift and is 0.0 exactly
//    when the joint holds; update_multiplier() adds kc to the force of the linear joint, carries
//    the residual (force, torque) over to the closed joint, keeps the weld's S a rotation and
//    adds the violation in frame b to it, and stores the shifts in end a's body coordinates
//    (world coordinates for a point without rotation).
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

namespace liedyn::joint_terms_tests {
namespace {

using fd::random_perpendicular;
using fd::random_unit;
using fd::rotation_at;
using fd::trace;
using fd::kPi;
using fd::kEps;

// The relative angles tested: the weld's angle of E, the hinge's angle between the axes.
const std::vector<double> kRelativeAngles = {0.0, 1e-9, 1e-4, 0.5, 2.0, kPi - 1e-6};
const std::vector<double> kStiffnesses = {1e-6, 1.0, 1e9};

Matrix3 random_rotation(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(0.1, kPi - 0.1);
  return rotation_at(angle(rng), rng);
}

template <class Term>
bool all_finite(const Term& term, const State& q) {
  LocalGradient<Term::kBlocks> g;
  LocalHessian<Term::kBlocks> H;
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
  constexpr int B = Term::kBlocks;
  if (value_hessian) return fd::check_term(c.term, c.q, c.dofs, opt);
  LocalGradient<B> g;
  LocalHessian<B> H;
  const double value = c.term.evaluate(c.q, &g, &H);
  if (value != c.term.evaluate(c.q, nullptr, nullptr)) {
    return ::testing::AssertionFailure() << "value depends on whether derivatives are requested";
  }
  const fd::ScalarFunction f = [&](const State& s) { return c.term.evaluate(s, nullptr, nullptr); };
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<B> gs;
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
// absolute at the scale √k of what r is computed from (r_scale; −1: √k itself).
template <class Term>
::testing::AssertionResult check_residual(const Case<Term>& c, double gradient_sigma,
                                          const fd::FdOptions& jacobian, bool zero_gradient,
                                          double r_scale = -1.0) {
  constexpr int B = Term::kBlocks;
  typename Term::Residual r, r_only;
  typename Term::ResidualJacobian J;
  c.term.residual(c.q, r, &J);
  c.term.residual(c.q, r_only, nullptr);
  if (r != r_only) return ::testing::AssertionFailure() << "r differs with and without J";
  LocalGradient<B> g;
  const double value = c.term.evaluate(c.q, &g, nullptr);
  const double half = 0.5 * r.squaredNorm();
  if (!(std::abs(half - value) <= 16 * kEps * (half + value))) {
    return ::testing::AssertionFailure() << "½‖r‖² = " << half << ", V = " << value;
  }
  // Only the compared (DOF) blocks: a world end's columns are written but are not DOFs.
  LocalGradient<B> Jtr = J.transpose() * r;
  for (int b = 0; b < B; ++b) {
    if (c.dofs[b].kind == fd::DofKind::kNone) {
      Jtr.template segment<3>(3 * b).setZero();
      g.template segment<3>(3 * b).setZero();
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
  const fd::VectorFunction F = fd::residual_of(c.term);
  return fd::check_vector_jacobian(F, c.q, c.dofs, J, jacobian,
                                   r_scale < 0.0 ? std::sqrt(c.term.stiffness) : r_scale);
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

// ========================================================================================
// Joint point  V = ½k‖p_b − (p_a − R_a s)‖² = ½k‖c + R_a s‖²,  c = p_b − p_a,  p = x + R p̄.

// Body rotations of the JointPoint cases: the extremes of the parameterisation.
const std::vector<double> kBodyAngles = {0.0, 1e-9, 1e-4, kPi - 1e-6, kPi, 2 * kPi - 1e-6};

enum class PointEndB { kBody, kWorld, kRodNode };

// End a a body (point 0, rotation 0, lever 0.5 along a random direction); end b a body
// (point 1, rotation 1, the same kind of lever), a world anchor (point = rotation = −1), or a
// rod node (point 1 without rotation, a translating offset). Blocks (x_a, θ_a, x_b, θ_b) at
// offsets (0, 6, 3, 9) of a state of two points and two rotations; blocks that are not DOFs
// have offset −1 and fd::no_dof(). The shift s: `shift_size` along a random direction.
Case<JointPoint> point_case(PointEndB end_b, double angle_a, double angle_b, double k,
                            double shift_size, std::mt19937& rng) {
  Case<JointPoint> c;
  c.term.stiffness = k;
  c.q.points = {fd::random_vector(rng, 1.0), fd::random_vector(rng, 1.0)};
  c.q.rotations = {rotation_at(angle_a, rng), rotation_at(angle_b, rng)};
  c.term.a = {0, 0, 0.5 * random_unit(rng)};
  c.term.offsets = {0, 6, 3, 9};
  c.dofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1), fd::rotation_dof(1)};
  switch (end_b) {
    case PointEndB::kBody:
      c.term.b = {1, 1, 0.5 * random_unit(rng)};
      break;
    case PointEndB::kWorld:
      c.term.b = {-1, -1, fd::random_vector(rng, 1.0)};
      c.term.offsets[2] = c.term.offsets[3] = -1;
      c.dofs[2] = c.dofs[3] = fd::no_dof();
      break;
    case PointEndB::kRodNode:
      c.term.b = {1, -1, 0.5 * random_unit(rng)};
      c.term.offsets[3] = -1;
      c.dofs[3] = fd::no_dof();
      break;
  }
  c.term.shift = shift_size * random_unit(rng);
  return c;
}

Matrix3 rotation_of(const State& q, int rotation) {
  return rotation < 0 ? Matrix3::Identity() : q.rotations[rotation];
}

// The world vector the shift adds to c: R_a s (s itself for a point without rotation).
Vector3 world_shift(const JointPoint& t, const State& q) {
  return rotation_of(q, t.a.rotation) * t.shift;
}

// c = p_b − p_a, from the definition p = x + R p̄ (not through AttachedPoint::position).
Vector3 point_violation_vector(const JointPoint& t, const State& q) {
  const auto p = [&](const AttachedPoint& e) {
    if (e.point < 0) return Vector3(e.local);
    return Vector3(q.points[e.point] + rotation_of(q, e.rotation) * e.local);
  };
  return p(t.b) - p(t.a);
}

// Moves end b (its point, or the anchor) so that the SHIFTED term is at rest:
// p_b = p_a − R_a s, d = c + R_a s = 0 up to round-off.
void put_point_at_rest(Case<JointPoint>& c) {
  const Vector3 target = c.term.a.position(c.q) - world_shift(c.term, c.q);
  if (c.term.b.point < 0) {
    c.term.b.local = target;
  } else {
    c.q.points[c.term.b.point] = target - c.term.b.lever(c.q);
  }
}

// Size of the positions r is computed from (its absolute round-off is eps times this).
double point_scale(const Case<JointPoint>& c) {
  double scale = 1.0;
  for (const Vector3& x : c.q.points) scale = std::max(scale, x.norm());
  return scale + c.term.a.local.norm() + c.term.b.local.norm() + c.term.shift.norm();
}

TEST(JointTermPoint, DerivativesMatchFiniteDifferences) {
  // Value V = ½k‖c + R_a s‖² (computed from the definition), Lie gradient and Lie Hessian by
  // central FD (gradient from the value; Hessian from the pulled-back gradient and from second
  // differences of the value), and the least-squares form r = √k(c + R_a s). Generic
  // configurations (c = O(1)), and the shifted term at rest (d = c + R_a s = 0 up to
  // round-off: g = 0, the Hessian k JdᵀJd only). Floors: set_joint_floors — V is k times O(1)
  // geometry whose round-off is absolute, a few eps·k per entry of g (see the top of the file);
  // "angle 0" there means g vanishes by construction (at rest).
  std::mt19937 rng(301);
  int checked = 0;
  for (const PointEndB end_b : {PointEndB::kBody, PointEndB::kWorld, PointEndB::kRodNode}) {
    for (const double k : kStiffnesses) {
      for (size_t i = 0; i < kBodyAngles.size(); ++i) {
        const double angle_a = kBodyAngles[i];
        const double angle_b = kBodyAngles[(i + 3) % kBodyAngles.size()];
        for (const double shift : {0.0, 0.3}) {
          for (const bool at_rest : {false, true}) {
            SCOPED_TRACE(trace("end b, stiffness, shift", static_cast<double>(end_b), k, shift));
            SCOPED_TRACE(trace("angles a, b, at rest", angle_a, angle_b, at_rest));
            Case<JointPoint> c = point_case(end_b, angle_a, angle_b, k, shift, rng);
            if (at_rest) put_point_at_rest(c);
            const double scale = point_scale(c);
            const Vector3 d = point_violation_vector(c.term, c.q) + world_shift(c.term, c.q);
            const double v = c.term.evaluate(c.q, nullptr, nullptr);
            if (at_rest) {
              EXPECT_LE(d.norm(), 16 * kEps * scale);
              EXPECT_LE(v, 0.5 * k * std::pow(16 * kEps * scale, 2));
            } else {
              EXPECT_GT(d.norm(), 0.1);
              EXPECT_NEAR(v, 0.5 * k * d.squaredNorm(), 32 * kEps * k * scale * (scale + d.norm()));
            }
            fd::TermCheckOptions opt;
            set_joint_floors(opt, at_rest ? 0.0 : 1.0, k);
            EXPECT_TRUE(check_derivatives(c, opt, true));
            EXPECT_TRUE(check_residual(c, 0.0, fd::FdOptions{}, at_rest, std::sqrt(k) * scale));
            EXPECT_TRUE(all_finite(c.term, c.q));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 3 * 6 * 2 * 2);
}

TEST(JointTermPoint, ChecksRejectWrongDerivatives) {
  // The checks above would see: the rotated-point curvature C(r_a, −f) (eq. 23) missing from
  // the θ_aθ_a block; a wrong sign of the x_a–θ_b coupling (both symmetric blocks, so that
  // the Hessian stays symmetric and only the FD can tell); and derivatives that forget the
  // shift (those of the unshifted term, evaluated at the same q).
  std::mt19937 rng(302);
  const Case<JointPoint> c = point_case(PointEndB::kBody, 1.0, 2.0, 1.0, 0.3, rng);
  LocalGradient<4> g;
  LocalHessian<4> H;
  c.term.evaluate(c.q, &g, &H);
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<4> gs;
    c.term.evaluate(s, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  const fd::ScalarFunction f = [&](const State& s) { return c.term.evaluate(s, nullptr, nullptr); };
  ASSERT_TRUE(fd::check_lie_gradient(f, c.q, c.dofs, g));
  ASSERT_TRUE(fd::check_lie_hessian(grad, c.q, c.dofs, H));
  ASSERT_TRUE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, H));

  const Vector3 force = c.term.stiffness * (point_violation_vector(c.term, c.q) +
                                            world_shift(c.term, c.q));  // f = ∂V/∂d
  const Vector3 lever_a = c.q.rotations[0] * (c.term.a.local - c.term.shift);
  LocalHessian<4> no_curvature = H;
  no_curvature.block<3, 3>(3, 3) -= rotated_point_curvature(lever_a, -force);
  ASSERT_GT((no_curvature - H).norm(), 0.1 * H.norm());
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, no_curvature));
  EXPECT_FALSE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, no_curvature));

  LocalHessian<4> flipped = H;
  flipped.block<3, 3>(0, 9) *= -1.0;
  flipped.block<3, 3>(9, 0) *= -1.0;
  ASSERT_GT(Matrix3(H.block<3, 3>(0, 9)).norm(), 0.1);
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, flipped));
  EXPECT_FALSE(fd::check_lie_hessian_from_value(f, c.q, c.dofs, flipped));

  JointPoint unshifted = c.term;
  unshifted.shift.setZero();
  LocalGradient<4> g0;
  LocalHessian<4> H0;
  unshifted.evaluate(c.q, &g0, &H0);
  EXPECT_FALSE(fd::check_lie_gradient(f, c.q, c.dofs, g0));
  EXPECT_FALSE(fd::check_lie_hessian(grad, c.q, c.dofs, H0));
  EXPECT_FALSE(fd::check_lie_gradient(f, c.q, c.dofs, Eigen::VectorXd(-g)));
}

// ========================================================================================
// The shifted rotational terms: the header says their derivations hold unchanged.

// Hinge with a shift s (size `shift_size`, random direction), so a = R_a(â + s) is not unit;
// b̂ is chosen so that b makes `angle` with the shifted axis a (of_shifted) or with the
// joint's own axis R_a â.
Case<JointAlignment> shifted_alignment_case(double angle, double k, bool world_b, double shift_size,
                                            bool of_shifted, std::mt19937& rng) {
  Case<JointAlignment> c = make_ends<JointAlignment>(k, world_b, rng);
  c.term.axis_a = random_unit(rng);
  c.term.shift = shift_size * random_unit(rng);
  const Vector3 axis = of_shifted ? Vector3(c.term.axis_a + c.term.shift) : c.term.axis_a;
  const Vector3 a = (c.q.rotations[0] * axis).normalized();
  const Vector3 b = so3::exp(angle * random_perpendicular(a, rng)) * a;
  c.term.axis_b = (rotation_b_of(c.q, c.term.rotation_b).transpose() * b).normalized();
  return c;
}

// The angle between the shifted axis a = R_a(â + s) and b.
double shifted_axis_angle(const JointAlignment& t, const State& q) {
  const Vector3 a = q.rotations[t.rotation_a] * (t.axis_a + t.shift);
  const Vector3 b = rotation_b_of(q, t.rotation_b) * t.axis_b;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Weld with a shift S = exp(shift_angle u), u random; B chosen so that the shifted relative
// rotation E = R_a A S Bᵀ R_bᵀ (of_shifted) or the joint's own R_a A Bᵀ R_bᵀ is
// exp(angle n), n random (returned through `axis` when non-null).
Case<JointWeld> shifted_weld_case(double angle, double k, bool world_b, double shift_angle,
                                  bool of_shifted, std::mt19937& rng, Vector3* axis = nullptr) {
  Case<JointWeld> c = make_ends<JointWeld>(k, world_b, rng);
  c.term.frame_a = random_rotation(rng);
  c.term.shift = so3::exp(shift_angle * random_unit(rng));
  const Vector3 n = random_unit(rng);
  if (axis != nullptr) *axis = n;
  const Matrix3 frame = of_shifted ? Matrix3(c.term.frame_a * c.term.shift) : c.term.frame_a;
  c.term.frame_b = rotation_b_of(c.q, c.term.rotation_b).transpose() * so3::exp(-angle * n) *
                   c.q.rotations[0] * frame;
  return c;
}

TEST(JointTermAlignment, ShiftedDerivativesMatchFiniteDifferences) {
  // a = R_a(â + s), ‖â + s‖ = ρ ≠ 1: V = ½k‖a − b‖² = ½k((ρ − 1)² + 4ρ sin²(θ/2)), θ the angle
  // between a and b. The derivatives involve only the bilinear a·b, so the unit-axis formulas
  // must hold: FD checks as in DerivativesMatchFiniteDifferences, at the relative angles of the
  // list taken between the SHIFTED axis and b (FD options of that angle), and between the
  // joint's own axis and b (the shifted angle then generic, computed); plus the opposite axes
  // (π, g = 0 up to round-off). Shifts of size 1e-3 and 0.3. Residual form: gradient_sigma kρ
  // (g = −k a × b, products of entries of size ρ and 1), r computed at the scale √kρ.
  std::mt19937 rng(106);
  std::vector<double> angles = kRelativeAngles;
  angles.push_back(kPi);
  int checked = 0;
  for (const bool of_shifted : {true, false}) {
    for (const bool world_b : {false, true}) {
      for (const double k : kStiffnesses) {
        for (const double shift : {1e-3, 0.3}) {
          for (const double angle : angles) {
            SCOPED_TRACE(trace("of shifted axis, world b, stiffness", of_shifted, world_b, k));
            SCOPED_TRACE(trace("shift, angle", shift, angle));
            const Case<JointAlignment> c =
                shifted_alignment_case(angle, k, world_b, shift, of_shifted, rng);
            const double theta = of_shifted ? angle : shifted_axis_angle(c.term, c.q);
            if (of_shifted) {
              EXPECT_NEAR(shifted_axis_angle(c.term, c.q), angle, 1e-7);
            }
            const double rho = (c.term.axis_a + c.term.shift).norm();
            const double expected =
                0.5 * k * ((rho - 1) * (rho - 1) + 4 * rho * std::pow(std::sin(0.5 * theta), 2));
            EXPECT_NEAR(c.term.evaluate(c.q, nullptr, nullptr), expected,
                        64 * kEps * k * (1 + rho) * (1 + rho) + 1e-12 * expected);
            fd::TermCheckOptions opt = alignment_options(theta, k);
            if (theta == kPi) opt.gradient.require_nonzero = fd::NonZero::kNone;  // g = 0
            // The value's round-off is absolute: the entries of a − b carry ~eps(1 + ρ), so V
            // carries ~k‖a − b‖eps(1 + ρ) and its central difference that over ε. With a shift
            // ‖a − b‖ ≥ |ρ − 1| however small θ, while ‖g‖ = kρ sin θ: where g is not 1e3 times
            // that floor (θ = 0 and 1e-9 here) the value cannot resolve it, and the FD of the
            // value only bounds g by the floor. g is still verified at every angle through
            // check_residual (J against FD of r, Jᵀr = g), whose round-off is relative to J.
            {
              const Vector3 a = c.q.rotations[0] * (c.term.axis_a + c.term.shift);
              const Vector3 b = rotation_b_of(c.q, c.term.rotation_b) * c.term.axis_b;
              const double value_floor =
                  fd::kNoiseUlps * kEps * k * (a - b).norm() * (1 + rho) / opt.gradient.step;
              opt.gradient.abs_floor = std::max(opt.gradient.abs_floor, value_floor);
              if (k * rho * std::sin(theta) < 1e3 * value_floor) {
                opt.gradient.require_nonzero = fd::NonZero::kNone;
              }
            }
            EXPECT_TRUE(check_derivatives(c, opt, true));
            EXPECT_TRUE(check_residual(c, k * rho, fd::FdOptions{}, theta == 0.0 || theta == kPi,
                                       std::sqrt(k) * (1 + rho)));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 2 * 2 * 3 * 2 * 7);
}

TEST(JointTermWeld, ShiftedDerivativesMatchFiniteDifferences) {
  // E = R_a A S Bᵀ R_bᵀ: A S is only another constant frame, so the derivation must hold as
  // it stands. S at a small (1e-3) and a moderate (0.8) angle; the relative angle of the list
  // taken by the shifted E (FD options of that angle, as in DerivativesMatchFiniteDifferences)
  // or by the joint's own R_a A Bᵀ R_bᵀ (the shifted angle then generic, computed: options of
  // that angle); residual form too, and at the shifted half turn (π) only its identities.
  std::mt19937 rng(208);
  std::vector<double> angles = kRelativeAngles;
  angles.push_back(kPi);
  int checked = 0;
  for (const bool of_shifted : {true, false}) {
    for (const bool world_b : {false, true}) {
      for (const double k : kStiffnesses) {
        for (const double shift_angle : {1e-3, 0.8}) {
          for (const double angle : angles) {
            SCOPED_TRACE(trace("of shifted E, world b, stiffness", of_shifted, world_b, k));
            SCOPED_TRACE(trace("shift angle, angle", shift_angle, angle));
            const Case<JointWeld> c =
                shifted_weld_case(angle, k, world_b, shift_angle, of_shifted, rng);
            const Matrix3& S = c.term.shift;
            EXPECT_LE((S.transpose() * S - Matrix3::Identity()).cwiseAbs().maxCoeff(), 8 * kEps);
            const double t = c.term.relative_rotation(c.q).norm();
            if (of_shifted) {
              EXPECT_NEAR(t, angle, 64 * kEps);
            }
            const double theta = of_shifted ? angle : t;
            EXPECT_NEAR(c.term.evaluate(c.q, nullptr, nullptr), 0.5 * k * t * t,
                        64 * kEps * k * (t + kEps));
            if (theta < kPi) {
              bool value_hessian = true;
              const fd::TermCheckOptions opt = weld_options(theta, k, &value_hessian);
              EXPECT_TRUE(check_derivatives(c, opt, value_hessian));
            }
            fd::FdOptions jacobian;
            if (theta > 3.0) jacobian.step = 2.5e-7;
            if (theta == kPi) {  // the half turn: no FD (r flips sign across it)
              jacobian.rtol = 1e300;
              jacobian.require_nonzero = fd::NonZero::kNone;
            }
            EXPECT_TRUE(check_residual(c, 0.0, jacobian, theta == 0.0));
            EXPECT_TRUE(all_finite(c.term, c.q));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 2 * 2 * 3 * 2 * 7);
}

// ========================================================================================
// Constraints (term.hpp): violation() and update_multiplier().

TEST(JointTermPoint, UpdateMultiplierOfTheLinearJointAddsKcToTheForce) {
  // Both ends points without rotation: c = (x_b + p̄_b) − (x_a + p̄_a), linear in q, and (R_a =
  // I) V = ½k‖c + s‖², so ∂V/∂x_b = k(c + s) = −∂V/∂x_a. update_multiplier sets s' = s + c
  // (world coordinates), so at the same q the force becomes k(c + s') = k(2c + s), and at a q'
  // where the joint holds (c' = 0) it is k s' = k(c + s): the force the penalty exerted at q,
  // now carried by the multiplier λ = k s'. Round-off: positions of size ≤ 2, so c and the
  // forces carry a few eps·k·(2 + ‖c‖ + ‖s‖).
  std::mt19937 rng(311);
  for (const double k : kStiffnesses) {
    for (const double s_size : {0.0, 0.3, 5.0}) {
      for (int trial = 0; trial < 4; ++trial) {
        SCOPED_TRACE(trace("stiffness, shift, trial", k, s_size, trial));
        JointPoint t;
        t.exact = true;
        t.stiffness = k;
        t.a = {0, -1, fd::random_vector(rng, 0.5)};
        t.b = {1, -1, fd::random_vector(rng, 0.5)};
        t.offsets = {0, -1, 3, -1};
        t.shift = s_size * random_unit(rng);
        State q;
        q.points = {fd::random_vector(rng, 1.0), fd::random_vector(rng, 1.0)};
        const Vector3 c = (q.points[1] + t.b.local) - (q.points[0] + t.a.local);
        const Vector3 s = t.shift;
        const double tol = 32 * kEps * k * (2 + c.norm() + s.norm());
        ASSERT_GT(k * c.norm(), 1e6 * tol);  // the update's effect is far above round-off

        LocalGradient<4> g;
        t.evaluate(q, &g, nullptr);
        EXPECT_LE((g.segment<3>(3 * 2) - k * (c + s)).norm(), tol);
        EXPECT_LE((g.segment<3>(0) + k * (c + s)).norm(), tol);
        const Vector3 force_before = g.segment<3>(3 * 2);

        t.update_multiplier(q);
        const Vector3 s_new = s + c;
        EXPECT_LE((t.shift - s_new).norm(), 8 * kEps * (2 + c.norm() + s.norm()));
        const double v = t.evaluate(q, &g, nullptr);
        EXPECT_LE((g.segment<3>(3 * 2) - k * (c + s_new)).norm(), tol);
        EXPECT_LE((g.segment<3>(0) + k * (c + s_new)).norm(), tol);
        EXPECT_NEAR(v, 0.5 * k * (c + s_new).squaredNorm(), tol * (c + s_new).norm());
        EXPECT_LE((g.segment<3>(3 * 2) - force_before - k * c).norm(), 2 * tol);

        State held = q;  // c' = 0
        held.points[1] = q.points[0] + t.a.local - t.b.local;
        EXPECT_LE(t.violation(held), 8 * kEps * 2);
        t.evaluate(held, &g, nullptr);
        EXPECT_LE((g.segment<3>(3 * 2) - force_before).norm(), tol);
      }
    }
  }
}

// The residual carried over to the closed joint: update_multiplier at q, then q' = q with the
// joint closed by moving an end WITHOUT turning end a. For each term r_new(q') = r_old(q):
//   point:     r = √k(c + R_a s), c' = 0: √k R_a s' = √k(R_a s + c);
//   alignment: r = √k(R_a(â + s) − b), b' = R_a â: √k R_a s' = √k(R_a s + c);
//   weld (F_a' = F_b, R_a turns here): E' = F_b S' F_bᵀ = F_a S F_bᵀ = E, φ' = φ exactly.
// That is the augmented-Lagrangian update: the multiplier takes over the force or torque the
// penalty exerted. Bound: round-off of r, a few eps·√k·(geometry size).
TEST(JointTermConstraint, UpdateMultiplierCarriesTheResidualOverToTheClosedJoint) {
  std::mt19937 rng(312);
  for (const double k : kStiffnesses) {
    for (int trial = 0; trial < 6; ++trial) {
      SCOPED_TRACE(trace("stiffness, trial", k, trial));
      const double sk = std::sqrt(k);
      {  // point: both bodies, or b the world (close the joint by moving x_a)
        const bool world_b = trial % 2 == 1;
        Case<JointPoint> c = point_case(world_b ? PointEndB::kWorld : PointEndB::kBody, 1.0 + trial,
                                        2.0, k, 0.3, rng);
        c.term.exact = true;
        JointPoint::Residual r_old, r_new;
        c.term.residual(c.q, r_old, nullptr);
        ASSERT_GT(r_old.norm(), 0.1 * sk);
        c.term.update_multiplier(c.q);
        State held = c.q;
        if (world_b) {
          held.points[0] = c.term.b.position(c.q) - c.term.a.lever(c.q);
        } else {
          held.points[1] = c.term.a.position(c.q) - c.term.b.lever(c.q);
        }
        EXPECT_LE(c.term.violation(held), 16 * kEps * point_scale(c));
        c.term.residual(held, r_new, nullptr);
        EXPECT_LE((r_new - r_old).norm(), 32 * kEps * sk * point_scale(c));
      }
      {  // alignment: turn b onto R_a â (both bodies)
        Case<JointAlignment> c =
            shifted_alignment_case(0.3 + 0.4 * trial, k, false, 0.3, false, rng);
        c.term.exact = true;
        const Vector3 a = c.q.rotations[0] * c.term.axis_a;
        const Vector3 b = c.q.rotations[1] * c.term.axis_b;
        JointAlignment::Residual r_old, r_new;
        c.term.residual(c.q, r_old, nullptr);
        c.term.update_multiplier(c.q);
        State held = c.q;
        const Vector3 axis = b.cross(a).normalized();
        held.rotations[1] =
            so3::exp(std::atan2(b.cross(a).norm(), b.dot(a)) * axis) * c.q.rotations[1];
        EXPECT_LE(c.term.violation(held), 16 * kEps);
        c.term.residual(held, r_new, nullptr);
        EXPECT_LE((r_new - r_old).norm(), 32 * kEps * sk);
      }
      {  // weld: turn a so that F_a = F_b (b the world or a body)
        const bool world_b = trial % 2 == 1;
        Case<JointWeld> c = shifted_weld_case(0.5 + 0.4 * trial, k, world_b, 0.3 + 0.3 * trial,
                                              true, rng);  // ‖φ‖ = 0.5 … 2.5
        c.term.exact = true;
        const Vector3 phi_old = c.term.relative_rotation(c.q);
        ASSERT_LT(phi_old.norm(), kPi - 0.1);  // away from the cut locus of log
        LocalGradient<2> g_old, g_new;
        const double v_old = c.term.evaluate(c.q, &g_old, nullptr);
        c.term.update_multiplier(c.q);
        State held = c.q;
        held.rotations[0] =
            rotation_b_of(c.q, c.term.rotation_b) * c.term.frame_b * c.term.frame_a.transpose();
        EXPECT_LE(c.term.violation(held), 16 * kEps);
        EXPECT_LE((c.term.relative_rotation(held) - phi_old).norm(), 64 * kEps);
        const double v_new = c.term.evaluate(held, &g_new, nullptr);
        EXPECT_NEAR(v_new, v_old, 64 * kEps * k);
        EXPECT_LE((g_new - g_old).norm(), 64 * kEps * k);
      }
    }
  }
}

TEST(JointTermConstraint, ViolationIgnoresTheShiftAndVanishesExactlyWhenTheJointHolds) {
  // violation(q) = ‖c(q)‖∞ of the joint's own geometry: the same for any shift (compared
  // exactly, with the shift zero, generic, large, and after update_multiplier, while V does
  // change), equal to ‖c‖∞ computed from the definition, and 0.0 EXACTLY when the joint holds
  // in floating point (c computed as x − x): world anchors placed at the other end's computed
  // position or axis, identical ends, frames made of signed permutations (exact products).
  // Where the joint holds only in exact arithmetic, round-off (a few eps); and it is positive
  // as soon as the joint opens by 1e-9.
  std::mt19937 rng(313);
  const auto expect_shift_independent = [](auto term, const State& q, const auto& shifts) {
    const double v0 = term.violation(q);
    const double V0 = term.evaluate(q, nullptr, nullptr);
    for (const auto& s : shifts) {
      term.shift = s;
      EXPECT_EQ(term.violation(q), v0);
      EXPECT_NE(term.evaluate(q, nullptr, nullptr), V0);  // the shift does enter V
    }
    term.update_multiplier(q);
    EXPECT_EQ(term.violation(q), v0);
    return v0;
  };
  for (int trial = 0; trial < 5; ++trial) {
    SCOPED_TRACE(trace("trial", trial));
    // Point.
    for (const PointEndB end_b : {PointEndB::kBody, PointEndB::kWorld, PointEndB::kRodNode}) {
      Case<JointPoint> c = point_case(end_b, 0.5 + trial, 2.0, 1.0, 0.0, rng);
      const std::vector<Vector3> shifts = {0.3 * random_unit(rng), 1e3 * random_unit(rng)};
      const double v = expect_shift_independent(c.term, c.q, shifts);
      EXPECT_NEAR(v, point_violation_vector(c.term, c.q).lpNorm<Eigen::Infinity>(),
                  16 * kEps * point_scale(c));
      EXPECT_GT(v, 0.01);
      // Held: b at a's computed point. World anchor: exactly 0; b a body or node: round-off.
      Case<JointPoint> held = c;
      held.term.shift = shifts[0];
      if (end_b == PointEndB::kWorld) {
        held.term.b.local = held.term.a.position(held.q);
        EXPECT_EQ(held.term.violation(held.q), 0.0);
      } else {
        held.q.points[1] = held.term.a.position(held.q) - held.term.b.lever(held.q);
        EXPECT_LE(held.term.violation(held.q), 8 * kEps * point_scale(held));
      }
      EXPECT_GT(held.term.evaluate(held.q, nullptr, nullptr), 0.0);  // the shifted term pulls
      held.q.points[0].x() += 1e-9;
      EXPECT_NEAR(held.term.violation(held.q), 1e-9, 16 * kEps * point_scale(held));
    }
    {  // two rod nodes with the same position and offset: c = 0.0 exactly
      JointPoint t;
      t.a = {0, -1, fd::random_vector(rng, 0.5)};
      t.b = {1, -1, t.a.local};
      t.shift = 0.3 * random_unit(rng);
      State q;
      q.points = {fd::random_vector(rng, 1.0)};
      q.points.push_back(q.points[0]);
      EXPECT_EQ(t.violation(q), 0.0);
    }
    // Alignment.
    for (const bool world_b : {false, true}) {
      Case<JointAlignment> c = alignment_case(0.4 + 0.5 * trial, 1.0, world_b, rng);
      const std::vector<Vector3> shifts = {0.3 * random_unit(rng), 10.0 * random_unit(rng)};
      const double v = expect_shift_independent(c.term, c.q, shifts);
      const Vector3 cv =
          c.q.rotations[0] * c.term.axis_a - rotation_b_of(c.q, c.term.rotation_b) * c.term.axis_b;
      EXPECT_NEAR(v, cv.lpNorm<Eigen::Infinity>(), 8 * kEps);
      EXPECT_GT(v, 0.01);
      // Held exactly: world b̂ = the computed R_a â; or R_b = R_a and b̂ = â.
      Case<JointAlignment> held = c;
      held.term.shift = shifts[0];
      if (world_b) {
        held.term.axis_b = held.q.rotations[0] * held.term.axis_a;
      } else {
        held.q.rotations[1] = held.q.rotations[0];
        held.term.axis_b = held.term.axis_a;
      }
      EXPECT_EQ(held.term.violation(held.q), 0.0);
      EXPECT_GT(held.term.evaluate(held.q, nullptr, nullptr), 0.0);
      held.q.rotations[0] = so3::exp(1e-9 * random_unit(rng)) * held.q.rotations[0];
      EXPECT_GT(held.term.violation(held.q), 1e-11);
    }
    // Weld.
    for (const bool world_b : {false, true}) {
      Vector3 n;
      const double angle = 0.3 + 0.6 * trial;
      Case<JointWeld> c = shifted_weld_case(angle, 1.0, world_b, 0.0, false, rng, &n);
      const std::vector<Matrix3> shifts = {so3::exp(0.3 * random_unit(rng)),
                                           so3::exp(2.5 * random_unit(rng))};
      const double v = expect_shift_independent(c.term, c.q, shifts);
      EXPECT_NEAR(v, angle * n.lpNorm<Eigen::Infinity>(), 64 * kEps);  // c = log E = angle n
      // Held in exact arithmetic (B = R_bᵀ R_a A): round-off.
      Case<JointWeld> held = c;
      held.term.shift = shifts[0];
      held.term.frame_b = rotation_b_of(held.q, held.term.rotation_b).transpose() *
                          held.q.rotations[0] * held.term.frame_a;
      EXPECT_LE(held.term.violation(held.q), 16 * kEps);
      EXPECT_GT(held.term.evaluate(held.q, nullptr, nullptr), 0.01);
    }
  }
  {  // Weld held exactly: signed permutations (exact products), shift a generic rotation.
    Matrix3 P1, P2, P3;
    P1 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    P2 << 1, 0, 0, 0, 0, 1, 0, -1, 0;
    P3 << 0, 0, 1, 0, 1, 0, -1, 0, 0;
    for (const bool world_b : {false, true}) {
      JointWeld t;
      t.rotation_a = 0;
      t.rotation_b = world_b ? -1 : 1;
      State q;
      q.rotations = {P1};
      if (!world_b) q.rotations.push_back(P3);
      t.frame_a = P2;
      t.frame_b = rotation_b_of(q, t.rotation_b).transpose() * P1 * P2;
      t.shift = so3::exp(Vector3(0.2, -0.5, 0.7));
      t.stiffness = 1.0;
      EXPECT_EQ(t.violation(q), 0.0) << world_b;
      EXPECT_NEAR(t.evaluate(q, nullptr, nullptr), 0.5 * Vector3(0.2, -0.5, 0.7).squaredNorm(),
                  64 * kEps);
      q.rotations[0] = so3::exp(Vector3(1e-9, 0.0, 0.0)) * q.rotations[0];
      EXPECT_NEAR(t.violation(q), 1e-9, 1e-15) << world_b;
    }
  }
}

TEST(JointTermWeld, UpdateMultiplierKeepsTheShiftARotationAndAddsTheViolation) {
  // (1) S ← orthonormalize(F_bᵀF_a S) stays in SO(3): ‖SᵀS − I‖ ≤ 1e-12, det S = 1 ± 1e-12, over
  // 200 updates at a fixed q (S then turns by W = F_bᵀF_a each time, S_n = Wⁿ S_0 = exp(n w) S_0
  // with w = log W: checked to 1e-11, the drift of 200 products at a few eps each).
  // (2) With F_a = F_b exp(w), w small: c = log(F_a F_bᵀ) = log(F_b exp(w) F_bᵀ) = F_b w, which is
  // w in frame b's coordinates (F_bᵀc = w), and log(S_new S_oldᵀ) = log(F_bᵀF_a) = w: the update
  // adds the violation expressed in frame b. The header claims it to first order (difference
  // O(|w|²), checked); it holds in fact exactly, up to round-off (checked too: 64 eps).
  std::mt19937 rng(209);
  std::vector<double> angles = kRelativeAngles;
  angles.push_back(kPi);
  for (const bool world_b : {false, true}) {
    for (const double angle : angles) {
      for (const double shift_angle : {0.0, 0.8, 3.0}) {
        SCOPED_TRACE(trace("world b, angle, shift angle", world_b, angle, shift_angle));
        Case<JointWeld> c = shifted_weld_case(angle, 1.0, world_b, shift_angle, false, rng);
        c.term.exact = true;
        const Matrix3 S0 = c.term.shift;
        const Matrix3 W = (rotation_b_of(c.q, c.term.rotation_b) * c.term.frame_b).transpose() *
                          c.q.rotations[0] * c.term.frame_a;
        const Vector3 w = so3::log(W);
        for (int n = 1; n <= 200; ++n) {
          c.term.update_multiplier(c.q);
          const Matrix3& S = c.term.shift;
          ASSERT_LE((S.transpose() * S - Matrix3::Identity()).cwiseAbs().maxCoeff(), 1e-12) << n;
          ASSERT_NEAR(S.determinant(), 1.0, 1e-12) << n;
          if (n == 1) {
            EXPECT_LE((S - W * S0).cwiseAbs().maxCoeff(), 16 * kEps);
          }
        }
        EXPECT_LE((c.term.shift - so3::exp(200.0 * w) * S0).cwiseAbs().maxCoeff(), 1e-11);
      }
    }
  }
  for (const bool world_b : {false, true}) {
    for (const double size : {1e-2, 1e-4, 1e-6}) {
      for (int trial = 0; trial < 3; ++trial) {
        SCOPED_TRACE(trace("world b, |w|, trial", world_b, size, trial));
        Case<JointWeld> c = make_ends<JointWeld>(1.0, world_b, rng);
        c.term.exact = true;
        c.term.frame_a = random_rotation(rng);
        c.term.shift = so3::exp(0.8 * random_unit(rng));
        const Vector3 w = size * random_unit(rng);
        // F_b = F_a exp(−w): B = R_bᵀ R_a A exp(−w).
        c.term.frame_b = rotation_b_of(c.q, c.term.rotation_b).transpose() * c.q.rotations[0] *
                         c.term.frame_a * so3::exp(-w);
        const Matrix3 F_a = c.q.rotations[0] * c.term.frame_a;
        const Matrix3 F_b = rotation_b_of(c.q, c.term.rotation_b) * c.term.frame_b;
        const Vector3 violation = so3::log(F_a * F_b.transpose());  // c, world
        EXPECT_LE((violation - F_b * w).norm(), 64 * kEps);
        EXPECT_NEAR(c.term.violation(c.q), (F_b * w).lpNorm<Eigen::Infinity>(), 64 * kEps);
        const Matrix3 S_old = c.term.shift;
        c.term.update_multiplier(c.q);
        const Vector3 added = so3::log(c.term.shift * S_old.transpose());
        const double difference = (added - F_b.transpose() * violation).norm();
        EXPECT_LE(difference, size * size);  // the header's first-order claim
        EXPECT_LE(difference, 64 * kEps);    // in fact exact
        EXPECT_LE((added - w).norm(), 64 * kEps);
      }
    }
  }
}

TEST(JointTermConstraint, ShiftsAreInEndABodyCoordinates) {
  // Rotating the whole configuration by a common Q (x_i ← Q x_i, R_i ← Q R_i, both ends free)
  // turns c to Q c and R_a to Q R_a, so the body-coordinate increments R_aᵀ c (point,
  // alignment) and F_bᵀF_a (weld) — hence the shift after update_multiplier — are unchanged;
  // a world-coordinate shift would turn by Q (checked to differ by ≫ round-off). For a point
  // WITHOUT rotation at end a the shift is in world coordinates: two rod nodes (no offsets,
  // so the configuration turns rigidly) get the increment Q c instead of c.
  std::mt19937 rng(314);
  for (const double psi : {0.7, 2.5, kPi - 1e-3}) {
    for (int trial = 0; trial < 3; ++trial) {
      SCOPED_TRACE(trace("psi, trial", psi, trial));
      const Matrix3 Q = so3::exp(psi * random_unit(rng));
      const auto rotated = [&](const State& q) {
        State r = q;
        for (Vector3& x : r.points) x = Q * x;
        for (Matrix3& R : r.rotations) R = Q * R;
        return r;
      };
      {  // point between two bodies
        Case<JointPoint> c = point_case(PointEndB::kBody, 1.0 + trial, 2.0, 1.0, 0.3, rng);
        const State qQ = rotated(c.q);
        const Vector3 cv = point_violation_vector(c.term, c.q);
        EXPECT_LE((point_violation_vector(c.term, qQ) - Q * cv).norm(), 32 * kEps * point_scale(c));
        ASSERT_GT((Q * cv - cv).norm(), 0.01);
        JointPoint t = c.term, tQ = c.term;
        t.update_multiplier(c.q);
        tQ.update_multiplier(qQ);
        EXPECT_LE((tQ.shift - t.shift).norm(), 64 * kEps * point_scale(c));
        EXPECT_GT((t.shift - c.term.shift).norm(), 0.01);
      }
      {  // two rod nodes: world coordinates, the increment turns with Q
        JointPoint t;
        t.a = {0, -1, Vector3::Zero()};
        t.b = {1, -1, Vector3::Zero()};
        t.shift = 0.3 * random_unit(rng);
        State q;
        q.points = {fd::random_vector(rng, 1.0), fd::random_vector(rng, 1.0)};
        const State qQ = rotated(q);
        JointPoint tQ = t;
        const Vector3 s0 = t.shift;
        t.update_multiplier(q);
        tQ.update_multiplier(qQ);
        EXPECT_LE((tQ.shift - s0 - Q * (t.shift - s0)).norm(), 64 * kEps);
        EXPECT_GT((tQ.shift - t.shift).norm(), 0.01);
      }
      {  // alignment between two bodies
        Case<JointAlignment> c = shifted_alignment_case(0.3 + trial, 1.0, false, 0.3, false, rng);
        const State qQ = rotated(c.q);
        JointAlignment t = c.term, tQ = c.term;
        t.update_multiplier(c.q);
        tQ.update_multiplier(qQ);
        EXPECT_LE((tQ.shift - t.shift).norm(), 32 * kEps);
        const Vector3 cv = c.q.rotations[0] * c.term.axis_a - c.q.rotations[1] * c.term.axis_b;
        ASSERT_GT((Q * cv - cv).norm(), 0.01);
      }
      {  // weld between two bodies
        Case<JointWeld> c = shifted_weld_case(0.5 + trial, 1.0, false, 0.8, false, rng);
        const State qQ = rotated(c.q);
        JointWeld t = c.term, tQ = c.term;
        t.update_multiplier(c.q);
        tQ.update_multiplier(qQ);
        EXPECT_LE((tQ.shift - t.shift).cwiseAbs().maxCoeff(), 32 * kEps);
        EXPECT_GT((t.shift - c.term.shift).norm(), 0.1);
      }
    }
  }
}

}  // namespace
}  // namespace liedyn::joint_terms_tests

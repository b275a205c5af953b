// Least-squares (residual) forms of the energy terms, for the Ceres back-end (contract:
// lib/term.hpp; forms in lib/inertia.hpp, lib/spring.hpp, lib/rod_terms.hpp). For every term
// that has one, at ordinary points and at the extremes (rotation angles 0, 1e-9, 1e-4, …,
// π − 1e-6, π, near 2π; rods straight, kinked to 170°, twisted to π, edges down to 1e-6 of
// their rest length; h from 1e-6 to 1, masses and stiffnesses over 18 decades):
//   (1) ValueIsHalfSquaredResidualPlusConstant: ½‖r‖² − Ψ is the documented constant at
//       several states of the same term;
//   (2) JacobianMatchesFiniteDifferences: J against central differences of r in the tangent
//       space (rotations r(exp(εe_k)R), points r(x + εe_k)), fd::check_vector_jacobian;
//   (3) JacobianTransposeResidualIsLieGradient: Jᵀr against the gradient of evaluate().
// ResidualChecks.* shows that each check rejects the mistakes it is there for.
//
// Tolerances. (1) and (3) compare two evaluations of the same quantity in floating point,
// so they allow a small multiple of eps times σ, an upper bound of the absolute values the
// two computations add up (σ is given per term, with the reason); both also demand that the
// compared quantity vary (1) or be non-zero (3) far above that tolerance, or the check would
// prove nothing. (2) uses fd_check.hpp's defaults (rtol 1e-6, floor 1e-9 of the largest
// entry, computed round-off floor), with the size of the quantities r is computed from passed
// as `r_scale` where r is a small difference of large ones.
//
// Length scales: as in test_rod_terms.cpp, rod point coordinates are differenced in units of
// a power of two s ≈ ‖e‖ (state y = x/s, point columns of J times s; exact), so that an edge
// 1e-6·l long gets an FD step of 1e-6·‖e‖.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fd_check.hpp"
#include "lib/incremental_potential.hpp"
#include "lib/inertia.hpp"
#include "lib/loads.hpp"
#include "lib/model.hpp"
#include "lib/rod_terms.hpp"
#include "lib/so3.hpp"
#include "lib/spring.hpp"

namespace liedyn::residuals_tests {
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
using fd::body_inertia;

// ----------------------------------------------------------------------------------------
// One test case of a term's residual form, and the three checks.

template <class Term>
struct Case {
  Term term;
  State q;
  fd::Dofs dofs;
  std::vector<State> states;  // for (1): q and other states of the same term
  // (1): ½‖r‖² − Ψ = constant, to within value_ulps·eps·σ(state); σ defaults to ½‖r‖² + |Ψ|
  // (both are sums of non-negative terms computed from the same intermediates: only the
  // last few roundings differ, ≤ ~10 eps of their size; 16 leaves a margin).
  double constant = 0.0;
  std::function<double(const State&)> value_sigma;
  double value_ulps = 16.0;
  // (2)
  double point_scale = 1.0;  // s (a power of two)
  double r_scale = 0.0;      // size of what r is computed from (fd::check_vector_jacobian)
  fd::FdOptions jacobian;
  // (3): |Jᵀr − g| ≤ 64 eps (‖J‖‖r‖ + ‖g‖ + gradient_sigma). ‖J‖‖r‖ bounds the round-off of
  // the product Jᵀr (≤ 9 terms each), ‖g‖ that of a gradient computed without cancellation;
  // gradient_sigma is added where evaluate() forms g as a small difference of larger terms.
  double gradient_sigma = 0.0;
  bool zero_gradient = false;  // g = 0 here by construction: no non-zero requirement
};

template <class Term>
Eigen::VectorXd residual_vector(const Term& term, const State& q) {
  typename Term::Residual r;
  term.residual(q, r, nullptr);
  return r;
}

template <class Term>
::testing::AssertionResult check_constant(const Case<Term>& c) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, largest_tol = 0.0;
  for (size_t i = 0; i < c.states.size(); ++i) {
    const State& s = c.states[i];
    const double half = 0.5 * residual_vector(c.term, s).squaredNorm();
    const double psi = c.term.evaluate(s, nullptr, nullptr);
    const double sigma = c.value_sigma ? c.value_sigma(s) : half + std::abs(psi);
    const double tol = c.value_ulps * kEps * sigma;
    if (!(std::abs(half - psi - c.constant) <= tol)) {
      std::ostringstream os;
      os.precision(17);
      os << "state " << i << ": ½‖r‖² = " << half << ", Ψ = " << psi
         << ", ½‖r‖² − Ψ = " << half - psi << ", expected " << c.constant << " ± " << tol;
      return ::testing::AssertionFailure() << os.str();
    }
    lo = std::min(lo, psi);
    hi = std::max(hi, psi);
    largest_tol = std::max(largest_tol, tol);
  }
  // A wrong scale of r (½‖r‖² = λΨ) would shift the "constant" by (λ − 1)Ψ: the states must
  // spread Ψ well beyond the tolerance for the check to see it.
  if (!(hi - lo > 1e3 * largest_tol)) {
    return ::testing::AssertionFailure()
           << "the states spread Ψ by only " << hi - lo << " (tolerance " << largest_tol
           << "): the check would prove nothing";
  }
  return ::testing::AssertionSuccess();
}

template <class Term>
::testing::AssertionResult check_jacobian(const Case<Term>& c) {
  typename Term::Residual r, r_only;
  typename Term::ResidualJacobian J;
  c.term.residual(c.q, r, &J);
  c.term.residual(c.q, r_only, nullptr);
  if (r != r_only) {  // same formula whether J is asked for or not: exactly equal
    return ::testing::AssertionFailure()
           << "r differs with and without J: " << r.transpose() << " vs " << r_only.transpose();
  }
  const double s = c.point_scale;
  Eigen::MatrixXd J_y = J;  // ∂r/∂y = s ∂r/∂x for point blocks
  for (size_t b = 0; b < c.dofs.size(); ++b) {
    if (c.dofs[b].kind == fd::DofKind::kPoint) J_y.middleCols<3>(3 * static_cast<int>(b)) *= s;
  }
  State y = c.q;
  for (Vector3& p : y.points) p /= s;
  const fd::VectorFunction F = [&](const State& ys) {
    State x = ys;
    for (Vector3& p : x.points) p *= s;
    return residual_vector(c.term, x);
  };
  return fd::check_vector_jacobian(F, y, c.dofs, J_y, c.jacobian, c.r_scale);
}

template <class Term>
::testing::AssertionResult check_gradient(const Case<Term>& c) {
  typename Term::Residual r;
  typename Term::ResidualJacobian J;
  c.term.residual(c.q, r, &J);
  LocalGradient<Term::kBlocks> g;
  c.term.evaluate(c.q, &g, nullptr);
  const LocalGradient<Term::kBlocks> Jtr = J.transpose() * r;
  const double sigma = J.norm() * r.norm() + g.norm() + c.gradient_sigma;
  const double tol = 64 * kEps * sigma;
  const double err = (Jtr - g).cwiseAbs().maxCoeff();
  std::ostringstream os;
  os.precision(17);
  os << "Jᵀr = " << Jtr.transpose() << "\ng   = " << g.transpose() << "\nmax |Jᵀr − g| = " << err
     << ", tolerance " << tol;
  if (!c.zero_gradient && !(g.cwiseAbs().maxCoeff() > 1e3 * tol)) {
    return ::testing::AssertionFailure() << "gradient negligible, the check would prove nothing\n"
                                         << os.str();
  }
  if (!(err <= tol)) return ::testing::AssertionFailure() << os.str();
  return ::testing::AssertionSuccess() << os.str();
}

// States for (1): q and `count` random tangent steps from it (points by up to `point_step`,
// rotations by up to 2 rad), over the blocks that are DOFs.
std::vector<State> states_around(const State& q, const fd::Dofs& dofs, double point_step,
                                 std::mt19937& rng, int count = 3) {
  std::vector<State> states{q};
  for (int k = 0; k < count; ++k) {
    Eigen::VectorXd delta(3 * static_cast<Eigen::Index>(dofs.size()));
    for (size_t b = 0; b < dofs.size(); ++b) {
      const double size = dofs[b].kind == fd::DofKind::kPoint ? point_step : 2.0 / std::sqrt(3.0);
      delta.segment<3>(3 * static_cast<Eigen::Index>(b)) = random_vector(rng, size);
    }
    states.push_back(fd::perturb(q, dofs, delta));
  }
  return states;
}

// ----------------------------------------------------------------------------------------
// Translational inertia with a load folded in: the term the Ceres back-end builds per point,
// next to what the Newton path sums (inertia + gravity + a constant node force).

struct LoadedInertia {
  static constexpr int kBlocks = 1;
  static constexpr int kResiduals = TranslationalInertia::kResiduals;
  using Residual = TranslationalInertia::Residual;
  using ResidualJacobian = TranslationalInertia::ResidualJacobian;
  TranslationalInertia inertia;
  Gravity gravity;
  ConstantForce force;  // at the point itself (no lever): V = −F·x

  Vector3 load() const { return gravity.scale * gravity.weight + force.scale * force.force; }
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const {
    LocalGradient<1> gi, gg;
    LocalGradient<2> gf;
    const bool grad = g != nullptr;
    const double value = inertia.evaluate(q, grad ? &gi : nullptr, nullptr) +
                         gravity.evaluate(q, grad ? &gg : nullptr, nullptr) +
                         force.evaluate(q, grad ? &gf : nullptr, nullptr);
    if (grad) *g = gi + gg + gf.head<3>();
    if (H != nullptr) inertia.evaluate(q, nullptr, H);  // the loads are linear
    return value;
  }
  void residual(const State& q, Residual& r, ResidualJacobian* J) const {
    inertia.residual(q, r, J, load());
  }
};

enum class Load { kNone, kGravity, kGravityAndForce };

std::vector<Case<LoadedInertia>> inertia_cases() {
  std::mt19937 rng(1001);
  std::vector<Case<LoadedInertia>> cases;
  for (const double h : {1e-6, 1e-2, 1.0}) {
    for (const double mass : {1e-9, 1.0, 1e6}) {
      for (const Load load : {Load::kNone, Load::kGravity, Load::kGravityAndForce}) {
        for (const bool at_equilibrium : {false, true}) {
          Case<LoadedInertia> c;
          LoadedInertia& t = c.term;
          t.inertia.point = 0;
          t.inertia.mass_over_h2 = mass / (h * h);
          State previous;
          previous.points = {random_vector(rng, 1.0)};
          Step step;
          step.points = {random_vector(rng, 0.5)};
          t.inertia.begin_step(previous, step);
          t.gravity.point = 0;
          t.gravity.weight =
              load == Load::kNone ? Vector3::Zero() : Vector3(mass * Vector3(0, 0, -9.81));
          t.force.at.point = 0;  // rotation −1, local 0: p = x
          t.force.force =
              load == Load::kGravityAndForce ? random_vector(rng, 2.0) : Vector3::Zero();
          const double a = t.inertia.mass_over_h2, sa = std::sqrt(a);
          const Vector3 x_tilde = t.inertia.x_tilde, f = t.load();
          c.q.points = {at_equilibrium ? Vector3(x_tilde + f / a) : random_vector(rng, 1.0)};
          c.dofs = {fd::point_dof(0)};
          // (1) a/2‖x − x̃‖² − f·x = ½‖r‖² − f·x̃ − ‖f‖²/(2a) (inertia.hpp), so
          // ½‖r‖² − Ψ = f·x̃ + ‖f‖²/(2a).
          c.constant = f.dot(x_tilde) + f.squaredNorm() / (2.0 * a);
          c.states = {c.q};
          for (int k = 0; k < 3; ++k) c.states.push_back(State{{random_vector(rng, 1.0)}, {}});
          // r = √a(x − x̃) − f/√a and Ψ each carry round-off eps × products of
          // √a(‖x‖ + ‖x̃‖) and ‖f‖/√a (x − x̃ itself carries eps(‖x‖ + ‖x̃‖)), so
          // σ = (√a(‖x‖ + ‖x̃‖) + ‖f‖/√a)² bounds every term of both sides and of the constant.
          c.value_sigma = [=](const State& s) {
            const double u = sa * (s.points[0].norm() + x_tilde.norm()) + f.norm() / sa;
            return u * u;
          };
          // (2) r is affine in x: central differences are exact for any ε, so ε = 1 (in
          // metres) leaves only round-off, eps·max|r|/ε, however large f/√a makes r.
          c.jacobian.step = 1.0;
          c.r_scale = sa * (c.q.points[0].norm() + 1.0 + x_tilde.norm()) + f.norm() / sa;
          // (3) g = a(x − x̃) − f is a difference of a(x − x̃) and f (zero at equilibrium).
          c.gradient_sigma = a * (c.q.points[0] - x_tilde).norm() + f.norm();
          c.zero_gradient = at_equilibrium;
          cases.push_back(c);
        }
      }
    }
  }
  return cases;
}

TEST(TranslationalInertiaResidual, ValueIsHalfSquaredResidualPlusConstant) {
  for (const auto& c : inertia_cases()) {
    SCOPED_TRACE(trace("m/h², load", c.term.inertia.mass_over_h2, c.term.load().norm()));
    EXPECT_TRUE(check_constant(c));
  }
}

TEST(TranslationalInertiaResidual, JacobianMatchesFiniteDifferences) {
  for (const auto& c : inertia_cases()) {
    SCOPED_TRACE(trace("m/h², load", c.term.inertia.mass_over_h2, c.term.load().norm()));
    EXPECT_TRUE(check_jacobian(c));
  }
}

TEST(TranslationalInertiaResidual, JacobianTransposeResidualIsLieGradient) {
  for (const auto& c : inertia_cases()) {
    SCOPED_TRACE(trace("m/h², load", c.term.inertia.mass_over_h2, c.term.load().norm()));
    EXPECT_TRUE(check_gradient(c));
  }
}

TEST(TranslationalInertiaResidual, MasslessPointNeedsNoLoad) {
  TranslationalInertia t;
  t.point = 0;
  t.mass_over_h2 = 0.0;
  const State q{{Vector3(1.0, 2.0, 3.0)}, {}};
  TranslationalInertia::Residual r;
  TranslationalInertia::ResidualJacobian J;
  t.residual(q, r, &J);
  EXPECT_TRUE(r.isZero(0.0));
  EXPECT_TRUE(J.isZero(0.0));
  EXPECT_THROW(t.residual(q, r, &J, Vector3(0.0, 0.0, -1.0)), std::invalid_argument);
}

// ----------------------------------------------------------------------------------------
// Rotational inertia  ‖(R − R̃) J^½‖²_F/(2h²).

enum class Shape { kBody, kThinRod };

// Angles of R for (1), besides the case's own.
constexpr double kOtherAngles[] = {0.7, 2.5, kPi - 1e-6};

template <class F>
void for_each_rotational_case(F&& f) {
  std::mt19937 rng(1002);
  for (const double h : {1e-6, 1.0}) {
    for (const double scale : {1e-9, 1e6}) {
      for (const Shape shape : {Shape::kBody, Shape::kThinRod}) {
        // Thin rod: J = ∫ρ x̄x̄ᵀ = diag(0, 0, m l²/12), singular (rank 1).
        const Matrix3 Q = rotation_at(0.8, rng);
        const Matrix3 J =
            shape == Shape::kBody
                ? rotational_mass(body_inertia(scale, rng))
                : Matrix3(scale * Q * Vector3(0.0, 0.0, 1.0).asDiagonal() * Q.transpose());
        for (const double a_prev : kAngles) {
          for (const double a_step : kAngles) {
            for (const double a : kAngles) {
              Case<RotationalInertia> c;
              RotationalInertia& t = c.term;
              t.rotation = 0;
              t.J_over_h2 = J / (h * h);
              t.sqrt_J_over_h = psd_sqrt(t.J_over_h2);
              State previous;
              previous.rotations = {rotation_at(a_prev, rng)};
              Step step;
              step.rotations = {rotation_at(a_step, rng)};
              t.begin_step(previous, step);
              c.q.rotations = {rotation_at(a, rng)};
              c.dofs = {fd::rotation_dof(0)};
              c.states = {c.q};
              for (const double other : kOtherAngles) {
                c.states.push_back(State{{}, {rotation_at(other, rng)}});
              }
              const Matrix3 Jh = t.J_over_h2, R_tilde = t.R_tilde, S = t.sqrt_J_over_h;
              // (1) Ψ = ½ Σₖₗ (J/h²)ₖₗ dₗ·dₖ and ½‖D S‖²_F (D = R − R̃, the same in both)
              // carry eps × Σ|J||d||d| ≤ eps ‖J/h²‖_F ‖D‖²_F and eps ‖S‖²_F ‖D‖²_F; S² differs
              // from J/h² by the eigen-decomposition's backward error, a few eps ‖J/h²‖.
              // J's off-diagonal entries make Ψ a sum of mixed signs: 64 ulps.
              c.value_sigma = [=](const State& s) {
                return (s.rotations[0] - R_tilde).squaredNorm() * (Jh.norm() + S.squaredNorm());
              };
              c.value_ulps = 64.0;
              // (2) r = (R − R̃)S: entries of RS and R̃S up to ‖S‖_F(1 + ‖R̃‖_F), however small
              // their difference.
              c.r_scale = S.norm() * (1.0 + R_tilde.norm());
              // (3) g = 2 vee(M), M = R J R̃ᵀ/h²: entries up to ‖J/h²‖_F ‖R̃‖_F, g their
              // antisymmetric part (0 at R = R̃).
              c.gradient_sigma = Jh.norm() * (1.0 + R_tilde.norm());
              c.zero_gradient = (c.q.rotations[0] - R_tilde).norm() < 1e-6;
              f(c, h, scale, shape, a_prev, a_step, a);
            }
          }
        }
      }
    }
  }
}

#define ROTATIONAL_TRACE()                                                                   \
  SCOPED_TRACE(trace("h, scale, thin rod", h, scale, shape == Shape::kThinRod ? 1.0 : 0.0) + \
               "; " + trace("angles R_{k-1}, dR_{k-1}, R", a_prev, a_step, a))

TEST(RotationalInertiaResidual, ValueIsHalfSquaredResidualPlusConstant) {
  int checked = 0;
  for_each_rotational_case([&](const Case<RotationalInertia>& c, double h, double scale,
                               Shape shape, double a_prev, double a_step, double a) {
    ROTATIONAL_TRACE();
    EXPECT_TRUE(check_constant(c));
    ++checked;
  });
  EXPECT_EQ(checked, 2 * 2 * 2 * 9 * 9 * 9);
}

TEST(RotationalInertiaResidual, JacobianMatchesFiniteDifferences) {
  for_each_rotational_case([&](const Case<RotationalInertia>& c, double h, double scale,
                               Shape shape, double a_prev, double a_step, double a) {
    ROTATIONAL_TRACE();
    EXPECT_TRUE(check_jacobian(c));
  });
}

TEST(RotationalInertiaResidual, JacobianTransposeResidualIsLieGradient) {
  for_each_rotational_case([&](const Case<RotationalInertia>& c, double h, double scale,
                               Shape shape, double a_prev, double a_step, double a) {
    ROTATIONAL_TRACE();
    EXPECT_TRUE(check_gradient(c));
  });
}

#undef ROTATIONAL_TRACE

TEST(RotationalInertiaResidual, ResidualLayoutIsColumnMajor) {
  // r(3k + i) = ((R − R̃) J^½/h)(i, k), as documented for the Ceres back-end.
  std::mt19937 rng(1003);
  RotationalInertia t;
  t.rotation = 0;
  t.J_over_h2 = rotational_mass(body_inertia(1.0, rng)) / 1e-4;
  t.sqrt_J_over_h = psd_sqrt(t.J_over_h2);
  t.R_tilde = rotation_at(0.4, rng);
  const State q{{}, {rotation_at(1.2, rng)}};
  RotationalInertia::Residual r;
  t.residual(q, r, nullptr);
  const Matrix3 expected = (q.rotations[0] - t.R_tilde) * t.sqrt_J_over_h;
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < 3; ++i) EXPECT_EQ(r(3 * k + i), expected(i, k)) << i << " " << k;
  }
}

// psd_sqrt: the symmetric square root the rotational residual is built on.
TEST(PsdSqrtResidual, SquaresBackForDefiniteSingularAndZeroMatrices) {
  std::mt19937 rng(1004);
  for (const Vector3& lambda :
       {Vector3(1.0, 1.6, 2.2), Vector3(0.0, 0.5, 0.5), Vector3(0.0, 0.0, 1.0),
        Vector3(1e-30, 1.0, 1e3), Vector3(2.0, 2.0, 2.0), Vector3(0.0, 0.0, 0.0)}) {
    for (const double scale : {1e-9, 1.0, 1e12}) {
      const Matrix3 Q = rotation_at(1.1, rng);
      const Matrix3 A = scale * Q * lambda.asDiagonal() * Q.transpose();
      const Matrix3 S = psd_sqrt(A);
      EXPECT_EQ(S, S.transpose());
      // Backward-stable eigen-decomposition: S² = A to a few eps ‖A‖.
      EXPECT_LE((S * S - A).norm(), 16 * kEps * A.norm()) << lambda.transpose() << " " << scale;
      const Vector3 mu = Eigen::SelfAdjointEigenSolver<Matrix3>(S).eigenvalues();
      EXPECT_GE(mu.minCoeff(), -16 * kEps * std::sqrt(A.norm())) << lambda.transpose();
    }
  }
}

TEST(PsdSqrtResidual, ClampsRoundOffAndRejectsIndefiniteMatrices) {
  std::mt19937 rng(1005);
  const Matrix3 Q = rotation_at(0.9, rng);
  // −1e-13 of the largest eigenvalue: within Model::validate's triangle-inequality tolerance
  // (λ_min(J) ≥ −1e-12 tr J) — clamped to 0, so S² = A + 1e-13 v vᵀ.
  const Matrix3 A = Q * Vector3(-1e-13, 1.0, 2.0).asDiagonal() * Q.transpose();
  const Matrix3 S = psd_sqrt(A);
  EXPECT_LE((S * S - A).norm(), 1e-13 + 16 * kEps * A.norm());
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Matrix3>(S).eigenvalues().minCoeff(),
            -16 * kEps * S.norm());  // round-off of V Λ^½ Vᵀ and of its eigenvalues
  EXPECT_THROW(psd_sqrt(Matrix3(Q * Vector3(-1e-6, 1.0, 2.0).asDiagonal() * Q.transpose())),
               std::invalid_argument);
  Matrix3 bad = Matrix3::Identity();
  bad(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(psd_sqrt(bad), std::invalid_argument);
}

TEST(PsdSqrtResidual, BuildComponentsSetsTheSquareRootBesideJOverH2) {
  Model model;
  model.time_step = 1e-3;
  std::mt19937 rng(1006);
  for (int i = 0; i < 2; ++i) {
    RigidBody b;
    b.name = "body" + std::to_string(i);
    b.mass = 2.0;
    b.inertia = body_inertia(0.1, rng);
    b.position = Vector3(2.0 * i, 0.0, 0.0);
    model.bodies.push_back(b);
  }
  RodSpec rod;
  rod.name = "rod";
  for (int i = 0; i <= 4; ++i) rod.nodes.push_back(Vector3(0.25 * i, 1.0, 0.0));
  rod.mass = 0.1;
  rod.radius = 1e-4;  // thin: J = diag(¼mr², ¼mr², ml²/12 − …) nearly singular
  rod.stretch_stiffness = 1e3;
  rod.shear_stiffness = 1e3;
  rod.bending_stiffness = Vector3(1.0, 1.0, 0.5);
  model.rods.push_back(rod);
  ASSERT_NO_THROW(model.validate());
  int checked = 0;
  for (const Component& c : build_components(model)) {
    for (const RotationalInertia& t : c.potential.terms<RotationalInertia>()) {
      EXPECT_EQ(t.sqrt_J_over_h, t.sqrt_J_over_h.transpose());
      EXPECT_LE((t.sqrt_J_over_h * t.sqrt_J_over_h - t.J_over_h2).norm(),
                16 * kEps * t.J_over_h2.norm());
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2 + 4);
}

// ----------------------------------------------------------------------------------------
// Spring  ½k(‖p_b − p_a‖ − L)².

enum class Ends { kBothBodies, kAnchorA, kAnchorB };
enum class Length { kStretched, kCompressed, kZeroRest, kNearlyCollapsed };

struct SpringCaseInfo {
  Ends ends;
  Length length;
  double k;
  double angle_a, angle_b;
};

template <class F>
void for_each_spring_case(F&& f) {
  std::mt19937 rng(1010);
  for (const Ends ends : {Ends::kBothBodies, Ends::kAnchorA, Ends::kAnchorB}) {
    for (const Length length :
         {Length::kStretched, Length::kCompressed, Length::kZeroRest, Length::kNearlyCollapsed}) {
      for (const double k : {1e-3, 1.0, 1e9}) {
        for (size_t i = 0; i < kAngles.size(); ++i) {
          const double angle_a = kAngles[i], angle_b = kAngles[(i + 4) % kAngles.size()];
          Case<Spring> c;
          Spring& t = c.term;
          c.q.points = {random_vector(rng, 1.0), random_vector(rng, 1.0)};
          c.q.rotations = {rotation_at(angle_a, rng), rotation_at(angle_b, rng)};
          t.a = {0, 0, 0.5 * random_unit(rng)};
          t.b = {1, 1, 0.5 * random_unit(rng)};
          c.dofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1), fd::rotation_dof(1)};
          if (ends == Ends::kAnchorA) {
            t.a = {-1, -1, random_vector(rng, 1.0)};
            c.dofs[0] = c.dofs[1] = fd::no_dof();
          }
          if (ends == Ends::kAnchorB) {
            t.b = {-1, -1, random_vector(rng, 1.0)};
            c.dofs[2] = c.dofs[3] = fd::no_dof();
          }
          t.stiffness = k;
          double l = (t.b.position(c.q) - t.a.position(c.q)).norm();
          if (length == Length::kNearlyCollapsed) {
            // p_b − p_a of length 1e-3, rest length 1: l/L = 1e-3, ∂r/∂d ~ √k L/l.
            l = 1e-3;
            const Vector3 d = l * random_unit(rng);
            if (ends == Ends::kAnchorB) {
              c.q.points[0] = t.b.position(c.q) - d - t.a.lever(c.q);
            } else {
              c.q.points[1] = t.a.position(c.q) + d - t.b.lever(c.q);
            }
          }
          t.rest_length = length == Length::kStretched    ? 0.6 * l
                          : length == Length::kCompressed ? 1.5 * l
                          : length == Length::kZeroRest   ? 0.0
                                                          : 1.0;
          c.states = states_around(c.q, c.dofs, 0.3, rng);
          // (2) r = √k (l − L) n: d carries eps(‖p_a‖ + ‖p_b‖), which ∂r/∂d (eigenvalues √k
          // along n, √k (l − L)/l across) passes on to r; l − L also carries eps·L.
          const double p_size = t.a.position(c.q).norm() + t.b.position(c.q).norm();
          const double gain = std::max(1.0, std::abs(l - t.rest_length) / l);
          c.r_scale = std::sqrt(k) * (gain * p_size + t.rest_length);
          if (length == Length::kNearlyCollapsed) {
            // Truncation (ε/l)² relative (r bends on the scale l = 1e-3): ε = 1e-8 gives 1e-10,
            // round-off 16 eps·r_scale/ε ~ 1e-3 √k against entries ~ √k L/l = 1e3 √k.
            c.jacobian.step = 1e-8;
          }
          f(c, SpringCaseInfo{ends, length, k, angle_a, angle_b});
        }
      }
    }
  }
}

#define SPRING_TRACE(info)                                                \
  SCOPED_TRACE(trace("ends, length, k", static_cast<double>((info).ends), \
                     static_cast<double>((info).length), (info).k) +      \
               "; " + trace("angles", (info).angle_a, (info).angle_b))

TEST(SpringResidual, ValueIsHalfSquaredResidualPlusConstant) {
  int checked = 0;
  for_each_spring_case([&](const Case<Spring>& c, const SpringCaseInfo& info) {
    SPRING_TRACE(info);
    EXPECT_TRUE(check_constant(c));
    ++checked;
  });
  EXPECT_EQ(checked, 3 * 4 * 3 * 9);
}

TEST(SpringResidual, JacobianMatchesFiniteDifferences) {
  for_each_spring_case([&](const Case<Spring>& c, const SpringCaseInfo& info) {
    SPRING_TRACE(info);
    EXPECT_TRUE(check_jacobian(c));
  });
}

TEST(SpringResidual, JacobianTransposeResidualIsLieGradient) {
  for_each_spring_case([&](const Case<Spring>& c, const SpringCaseInfo& info) {
    SPRING_TRACE(info);
    EXPECT_TRUE(check_gradient(c));
  });
}

#undef SPRING_TRACE

TEST(SpringResidual, CoincidentEndsWithPositiveRestLength) {
  // d = 0, L > 0: V = ½kL², evaluate() returns g = 0 (length_spring); the residual keeps the
  // value, r = −√k L e_x, with J = 0 so that Jᵀr = 0 = g (spring.hpp).
  // End b is a world anchor placed exactly at p_a, so that d = 0 exactly.
  std::mt19937 rng(1011);
  for (const double L : {1e-3, 1.0}) {
    Spring t;
    t.a = {0, 0, Vector3(0.3, -0.1, 0.2)};
    t.stiffness = 50.0;
    t.rest_length = L;
    State q;
    q.rotations = {rotation_at(1.0, rng)};
    q.points = {Vector3(0.5, 0.5, 0.5)};
    t.b = {-1, -1, t.a.position(q)};
    ASSERT_EQ(t.b.position(q) - t.a.position(q), Vector3::Zero());
    Spring::Residual r;
    Spring::ResidualJacobian J;
    t.residual(q, r, &J);
    LocalGradient<4> g;
    const double value = t.evaluate(q, &g, nullptr);
    EXPECT_EQ(value, 0.5 * 50.0 * L * L);
    EXPECT_NEAR(0.5 * r.squaredNorm(), value, 4 * kEps * value);
    EXPECT_TRUE(J.isZero(0.0));
    EXPECT_TRUE(g.isZero(0.0));
  }
}

// ----------------------------------------------------------------------------------------
// Rod stretch  ½ (k_s/l)(‖e‖ − l)².

struct RodCaseInfo {
  double l, k, ratio, angle = 0.0, kink = 0.0;
};

template <class F>
void for_each_stretch_case(F&& f) {
  std::mt19937 rng(1020);
  for (const double l : {1e-4, 1e-2, 1.0, 10.0}) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      for (const double ratio : {1e-6, 0.3, 0.9, 1.0, 1.5, 3.0}) {  // ‖e‖/l; 1 is rest
        Case<RodStretch> c;
        c.term.node0 = 0;
        c.term.node1 = 1;
        c.term.rest_length = l;
        c.term.stiffness = k;
        const double L = ratio * l;
        const Vector3 x0 = random_vector(rng, L);  // coordinates of the edge's own size
        c.q.points = {x0, x0 + L * random_unit(rng)};
        c.dofs = {fd::point_dof(0), fd::point_dof(1)};
        c.states = states_around(c.q, c.dofs, 0.3 * L, rng);
        const double s = power_of_two_near(L);
        c.point_scale = s;
        // (2) r = √(k/l)(‖e‖ − l): ‖e‖ carries eps(‖x0‖ + ‖x1‖), ‖e‖ − l also eps·l.
        c.r_scale = std::sqrt(k / l) * (c.q.points[0].norm() + c.q.points[1].norm() + l);
        // At ‖e‖ = 1e-6 l that round-off, eps·l√(k/l), is 1e6 times eps·‖e‖√(k/l) = eps·|J_y|:
        // a larger step ε = 1e-5 (in units of s ≈ ‖e‖) keeps it at ~1e-4 |J_y|, while the
        // truncation, ε²/6·|∂³r| with |∂³r| ≲ 3|J_y| on the unit scale, stays ~1e-10 |J_y|.
        if (ratio < 1e-3) c.jacobian.step = 1e-5;
        // (3) g = (k/l)(‖e‖ − l) n from the same ‖e‖ − l as r: no extra term. At rest the
        // stretch is a few ulps of l: no non-zero requirement there.
        c.zero_gradient = ratio == 1.0;
        f(c, RodCaseInfo{l, k, ratio});
      }
    }
  }
}

#define ROD_TRACE(info)                                                        \
  SCOPED_TRACE(trace("l, k, |e|/l", (info).l, (info).k, (info).ratio) + "; " + \
               trace("angle, kink", (info).angle, (info).kink))

TEST(RodStretchResidual, ValueIsHalfSquaredResidualPlusConstant) {
  for_each_stretch_case([&](const Case<RodStretch>& c, const RodCaseInfo& info) {
    ROD_TRACE(info);
    EXPECT_TRUE(check_constant(c));
  });
}

TEST(RodStretchResidual, JacobianMatchesFiniteDifferences) {
  for_each_stretch_case([&](const Case<RodStretch>& c, const RodCaseInfo& info) {
    ROD_TRACE(info);
    EXPECT_TRUE(check_jacobian(c));
  });
}

TEST(RodStretchResidual, JacobianTransposeResidualIsLieGradient) {
  for_each_stretch_case([&](const Case<RodStretch>& c, const RodCaseInfo& info) {
    ROD_TRACE(info);
    EXPECT_TRUE(check_gradient(c));
  });
}

TEST(RodStretchResidual, CoincidentNodes) {
  // e = 0: Ψ = ½ k l, g = 0 (length_spring); r = −√(k/l)·l keeps the value, J = 0.
  RodStretch t;
  t.node0 = 0;
  t.node1 = 1;
  t.rest_length = 0.5;
  t.stiffness = 8.0;
  const State q{{Vector3(1.0, 2.0, 3.0), Vector3(1.0, 2.0, 3.0)}, {}};
  RodStretch::Residual r;
  RodStretch::ResidualJacobian J;
  t.residual(q, r, &J);
  LocalGradient<2> g;
  const double value = t.evaluate(q, &g, nullptr);
  EXPECT_EQ(value, 0.5 * 8.0 * 0.5);
  EXPECT_NEAR(0.5 * r.squaredNorm(), value, 4 * kEps * value);
  EXPECT_TRUE(J.isZero(0.0));
  EXPECT_TRUE(g.isZero(0.0));
}

// ----------------------------------------------------------------------------------------
// Rod shear  ¼ k_x l ‖d − R e_z‖².

template <class F>
void for_each_shear_case(F&& f) {
  std::mt19937 rng(1030);
  for (const double l : {1e-4, 1.0, 10.0}) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      for (const double ratio : {1e-6, 1.0, 2.5}) {  // ‖e‖/l
        for (const double angle : kAngles) {
          for (const double kink : {0.0, 1e-4, 0.7, 1.6, 2.6, 170 * kDeg}) {
            Case<RodShear> c;
            RodShear& t = c.term;
            t.node0 = 0;
            t.node1 = 1;
            t.edge = 0;
            t.rest_length = l;
            t.stiffness = k;
            const double L = ratio * l;
            const Matrix3 R = rotation_at(angle, rng);
            const Vector3 tz = R.col(2);
            const Vector3 d = so3::exp(kink * random_perpendicular(tz, rng)) * tz;
            const Vector3 x0 = random_vector(rng, L);
            c.q.points = {x0, x0 + L * d};
            c.q.rotations = {R};
            c.dofs = {fd::point_dof(0), fd::point_dof(1), fd::rotation_dof(0)};
            c.states = states_around(c.q, c.dofs, 0.3 * L, rng);
            const double Le = (c.q.points[1] - c.q.points[0]).norm();
            c.point_scale = power_of_two_near(Le);
            const double cst = 0.5 * k * l;
            // (2) r = √c (d − t): d = e/L carries eps(‖x0‖ + ‖x1‖)/L, t eps.
            const double arms = (c.q.points[0].norm() + c.q.points[1].norm()) / Le;
            c.r_scale = std::sqrt(cst) * (2.0 + arms);
            // (3) g_e = −c (t − a d)/L and g_θ = −c t × d are differences of unit vectors,
            // with absolute round-off ~eps c (1 + arms)/L and eps c however small a kink makes
            // them; Jᵀr recovers them as c P(d − t)/L, with P d ≈ eps.
            c.gradient_sigma = cst * (1.0 + arms) * (1.0 + 1.0 / Le);
            c.zero_gradient = kink == 0.0;
            f(c, RodCaseInfo{l, k, ratio, angle, kink});
          }
        }
      }
    }
  }
}

TEST(RodShearResidual, ValueIsHalfSquaredResidualPlusConstant) {
  for_each_shear_case([&](const Case<RodShear>& c, const RodCaseInfo& info) {
    ROD_TRACE(info);
    EXPECT_TRUE(check_constant(c));
  });
}

TEST(RodShearResidual, JacobianMatchesFiniteDifferences) {
  for_each_shear_case([&](const Case<RodShear>& c, const RodCaseInfo& info) {
    ROD_TRACE(info);
    EXPECT_TRUE(check_jacobian(c));
  });
}

TEST(RodShearResidual, JacobianTransposeResidualIsLieGradient) {
  for_each_shear_case([&](const Case<RodShear>& c, const RodCaseInfo& info) {
    ROD_TRACE(info);
    EXPECT_TRUE(check_gradient(c));
  });
}

#undef ROD_TRACE

TEST(RodShearResidual, CoincidentNodes) {
  // e = 0: evaluate() takes d = 0 in c(1 − dᵀt), Ψ = c, g = 0; r = −√(2c) t, J = 0.
  RodShear t;
  t.node0 = 0;
  t.node1 = 1;
  t.edge = 0;
  t.rest_length = 1.0;
  t.stiffness = 2.0;
  std::mt19937 rng(1031);
  const State q{{Vector3(1.0, 2.0, 3.0), Vector3(1.0, 2.0, 3.0)}, {rotation_at(2.0, rng)}};
  RodShear::Residual r;
  RodShear::ResidualJacobian J;
  t.residual(q, r, &J);
  LocalGradient<3> g;
  const double value = t.evaluate(q, &g, nullptr);
  EXPECT_EQ(value, 1.0);
  EXPECT_NEAR(0.5 * r.squaredNorm(), value, 4 * kEps * value);
  EXPECT_TRUE(J.isZero(0.0));
  EXPECT_TRUE(g.isZero(0.0));
}

// ----------------------------------------------------------------------------------------
// Rod bend / twist  ½ l ΔωᵀKΔω.

enum class Axis { kTwist, kBend, kRandom };

struct BendCaseInfo {
  double l, K, angle;
  Axis axis;
  double q_angle;
  bool curved_rest;
};

template <class F>
void for_each_bend_case(F&& f) {
  std::mt19937 rng(1040);
  // Relative rotation angles: straight (0, 1e-9, 1e-4), generic, kinked to 170°, twisted to
  // π − 1e-6 and π, and near 2π (a small rotation the other way).
  const std::vector<double> q_angles = {
      0.0, 1e-9, 1e-4, 1.0, 2.5, 170 * kDeg, kPi - 1e-6, kPi, 2.0 * kPi - 1e-6};
  for (const double l : {1e-4, 1e-2, 1.0, 10.0}) {
    for (const double K : {1e-3, 1.0, 1e9}) {
      for (const double angle : kAngles) {
        for (const Axis axis : {Axis::kTwist, Axis::kBend, Axis::kRandom}) {
          for (const double q_angle : q_angles) {
            for (const bool curved_rest : {true, false}) {
              const Vector3 n = axis == Axis::kTwist  ? Vector3::UnitZ()
                                : axis == Axis::kBend ? random_perpendicular(Vector3::UnitZ(), rng)
                                                      : random_unit(rng);
              Case<RodBendTwist> c;
              RodBendTwist& t = c.term;
              t.edge0 = 0;
              t.edge1 = 1;
              t.rest_length = l;
              t.stiffness = K * Vector3(1.0, 1.7, 0.6);  // bend, bend, twist: all distinct
              // Rest curvature of a rest shape bent and twisted by 0.4 rad over one edge.
              t.rest_darboux = curved_rest
                                   ? darboux_vector(Matrix3::Identity(), rotation_at(0.4, rng), l)
                                   : Vector3::Zero();
              const Matrix3 Ra = rotation_at(angle, rng);
              c.q.rotations = {Ra, Ra * so3::exp(q_angle * n)};
              c.dofs = {fd::rotation_dof(0), fd::rotation_dof(1)};
              c.states = states_around(c.q, c.dofs, 0.0, rng);
              // (2) ω = vee(R_aᵀR_b)/l: differences of O(1) dot products, absolute
              // round-off ~eps/l; Δω = ω − ω̄ also eps‖ω̄‖.
              c.r_scale = std::sqrt(l * t.stiffness.maxCoeff()) * (1.0 / l + t.rest_darboux.norm());
              // (3) g = Gᵀ R_a K Δω and Jᵀr = Gᵀ R_a K^½ (√l K^½ Δω)/√l share Δω: no extra.
              // Δω = 0 exactly for a straight untwisted rest at Q = I or a half turn.
              c.zero_gradient = !curved_rest && (q_angle == 0.0 || q_angle == kPi);
              f(c, BendCaseInfo{l, K, angle, axis, q_angle, curved_rest});
            }
          }
        }
      }
    }
  }
}

#define BEND_TRACE(info)                                                                \
  SCOPED_TRACE(trace("l, K, angle of R_a", (info).l, (info).K, (info).angle) + "; " +   \
               trace("axis, angle of Q, curved rest", static_cast<double>((info).axis), \
                     (info).q_angle, (info).curved_rest ? 1.0 : 0.0))

TEST(RodBendTwistResidual, ValueIsHalfSquaredResidualPlusConstant) {
  int checked = 0;
  for_each_bend_case([&](const Case<RodBendTwist>& c, const BendCaseInfo& info) {
    BEND_TRACE(info);
    EXPECT_TRUE(check_constant(c));
    ++checked;
  });
  EXPECT_EQ(checked, 4 * 3 * 9 * 3 * 9 * 2);
}

TEST(RodBendTwistResidual, JacobianMatchesFiniteDifferences) {
  for_each_bend_case([&](const Case<RodBendTwist>& c, const BendCaseInfo& info) {
    BEND_TRACE(info);
    EXPECT_TRUE(check_jacobian(c));
  });
}

TEST(RodBendTwistResidual, JacobianTransposeResidualIsLieGradient) {
  for_each_bend_case([&](const Case<RodBendTwist>& c, const BendCaseInfo& info) {
    BEND_TRACE(info);
    EXPECT_TRUE(check_gradient(c));
  });
}

#undef BEND_TRACE

// ----------------------------------------------------------------------------------------
// The checks reject the mistakes they are there for. A term whose residual form is broken on
// purpose, in the ways a derivation goes wrong:
//   kScale       r(1 + 1e-7): ½‖r‖² no longer Ψ + const                 → (1), (3)
//   kShift       r + a constant vector: ½‖r‖² − Ψ varies with q          → (1), (3)
//   kSignLast    the last block of J negated (a sign slip)              → (2), (3)
//   kRightPert   rotation blocks of J for R⁺ = R exp(θ): J_b R_b         → (2), (3)
//   kTransposed  rotation blocks of J transposed                        → (2), (3)

enum class Break { kScale, kShift, kSignLast, kRightPert, kTransposed };

template <class Term>
struct Broken {
  static constexpr int kBlocks = Term::kBlocks;
  static constexpr int kResiduals = Term::kResiduals;
  using Residual = typename Term::Residual;
  using ResidualJacobian = typename Term::ResidualJacobian;
  Term term;
  fd::Dofs dofs;
  Break how = Break::kScale;

  double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
    return term.evaluate(q, g, H);
  }
  void residual(const State& q, Residual& r, ResidualJacobian* J) const {
    term.residual(q, r, J);
    if (how == Break::kScale) r *= 1.0 + 1e-7;
    if (how == Break::kShift) r += Residual::Constant(0.1 * r.norm() + 1e-3);
    if (J == nullptr) return;
    if (how == Break::kSignLast) J->template rightCols<3>() *= -1.0;
    for (int b = 0; b < kBlocks; ++b) {
      if (dofs[static_cast<size_t>(b)].kind != fd::DofKind::kRotation) continue;
      const Matrix3& R = q.rotations[dofs[static_cast<size_t>(b)].index];
      auto block = J->template middleCols<3>(3 * b);
      if (how == Break::kRightPert) block = (block * R).eval();
      if constexpr (kResiduals % 3 == 0) {
        if (how == Break::kTransposed) {
          for (int i = 0; i < kResiduals / 3; ++i) {
            const Matrix3 t = block.template middleRows<3>(3 * i).transpose();
            block.template middleRows<3>(3 * i) = t;
          }
        }
      }
    }
  }
};

template <class Term>
Case<Broken<Term>> broken(const Case<Term>& c, Break how) {
  Case<Broken<Term>> b;
  b.term.term = c.term;
  b.term.dofs = c.dofs;
  b.term.how = how;
  b.q = c.q;
  b.dofs = c.dofs;
  b.states = c.states;
  b.constant = c.constant;
  b.value_sigma = c.value_sigma;
  b.value_ulps = c.value_ulps;
  b.point_scale = c.point_scale;
  b.r_scale = c.r_scale;
  b.jacobian = c.jacobian;
  b.gradient_sigma = c.gradient_sigma;
  b.zero_gradient = c.zero_gradient;
  return b;
}

template <class Term>
void expect_checks_reject_breaks(const Case<Term>& c, bool has_rotation, const char* what) {
  SCOPED_TRACE(what);
  ASSERT_TRUE(check_constant(c));
  ASSERT_TRUE(check_jacobian(c));
  ASSERT_TRUE(check_gradient(c));
  EXPECT_FALSE(check_constant(broken(c, Break::kScale)));
  EXPECT_FALSE(check_gradient(broken(c, Break::kScale)));
  EXPECT_FALSE(check_constant(broken(c, Break::kShift)));
  EXPECT_FALSE(check_gradient(broken(c, Break::kShift)));
  EXPECT_FALSE(check_jacobian(broken(c, Break::kSignLast)));
  EXPECT_FALSE(check_gradient(broken(c, Break::kSignLast)));
  if (has_rotation) {
    EXPECT_FALSE(check_jacobian(broken(c, Break::kRightPert)));
    EXPECT_FALSE(check_gradient(broken(c, Break::kRightPert)));
    if (Term::kResiduals % 3 == 0) {
      EXPECT_FALSE(check_jacobian(broken(c, Break::kTransposed)));
      EXPECT_FALSE(check_gradient(broken(c, Break::kTransposed)));
    }
  }
}

TEST(ResidualChecks, RejectBrokenResidualForms) {
  // One ordinary case per term (generic angles, a kink, a curved rest shape).
  bool done = false;
  for (const auto& c : inertia_cases()) {
    if (done || c.zero_gradient || c.term.load().isZero(0.0)) continue;
    expect_checks_reject_breaks(c, false, "translational inertia");
    done = true;
  }
  EXPECT_TRUE(done);
  done = false;
  for_each_rotational_case([&](const Case<RotationalInertia>& c, double, double, Shape shape,
                               double a_prev, double a_step, double a) {
    if (done || shape != Shape::kBody || a_prev != 1.0 || a_step != 2.5 || a != 1.0) return;
    expect_checks_reject_breaks(c, true, "rotational inertia");
    done = true;
  });
  EXPECT_TRUE(done);
  done = false;
  for_each_spring_case([&](const Case<Spring>& c, const SpringCaseInfo& info) {
    if (done || info.ends != Ends::kBothBodies || info.length != Length::kStretched ||
        info.angle_a != 1.0) {
      return;
    }
    expect_checks_reject_breaks(c, true, "spring");
    done = true;
  });
  EXPECT_TRUE(done);
  done = false;
  for_each_stretch_case([&](const Case<RodStretch>& c, const RodCaseInfo& info) {
    if (done || info.ratio != 1.5) return;
    expect_checks_reject_breaks(c, false, "rod stretch");
    done = true;
  });
  EXPECT_TRUE(done);
  done = false;
  for_each_shear_case([&](const Case<RodShear>& c, const RodCaseInfo& info) {
    if (done || info.kink != 0.7 || info.angle != 1.0) return;
    expect_checks_reject_breaks(c, true, "rod shear");
    done = true;
  });
  EXPECT_TRUE(done);
  done = false;
  for_each_bend_case([&](const Case<RodBendTwist>& c, const BendCaseInfo& info) {
    if (done || info.q_angle != 1.0 || info.angle != 1.0 || !info.curved_rest) return;
    expect_checks_reject_breaks(c, true, "rod bend-twist");
    done = true;
  });
  EXPECT_TRUE(done);
}

}  // namespace
}  // namespace liedyn::residuals_tests

// Rotation vectors (manifolds/rotation_vector.hpp, paper §3.3): the chain rule that turns Lie
// derivatives into derivatives in r, the correction term C(r, g), the Jacobian of eq. (5) and
// wrap. Every derivative is checked by central finite differences, in r (a plain vector
// space: exp(r) is analytic, so no cut at π gets in the way), at the extremes of the
// parameterisation: ‖r‖ = 0, 1e-9, 1e-4, 1, the series switch at 2 (and 4 for σ(t/2)),
// π − 1e-6, π, 2π − 1e-3, along several axes.
//
// Tolerances of the r-space checks are absolute, in units of the natural size S of what is
// differenced (stated per check), not relative to each entry: a central difference with step
// ε errs by ≈ ε²/6·|f'''| (truncation) + a few eps·|f|/ε (round-off), set by S. Near 2π the
// compared entries themselves shrink (σ_min(J_l) = |sinc(t/2)| ≈ 1.6e-4 at 2π − 1e-3), so an
// entry-relative test would fail by conditioning, not by error.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/SVD>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "fd_check.hpp"
#include "rotation_test_functions.hpp"
#include "lib/so3.hpp"
#include "manifolds/rotation_vector.hpp"

namespace liedyn::rotation_vector_tests {
namespace {

using rotvec::Matrix3;
using rotvec::Vector3;
using Matrix93 = Eigen::Matrix<double, 9, 3>;
using fd::kPi;
using fd::kEps;
using fd::where;

// 2 and 4 are the series switches of rotation_vector.cpp (t, and t/2 in exp_jacobian).
const std::vector<double> kAngles = {
    0.0, 1e-9, 1e-4, 1.0, 2.0, kPi - 1e-6, kPi, 4.0, 2.0 * kPi - 1e-3};

std::vector<Vector3> test_axes() {
  std::vector<Vector3> axes = {Vector3::UnitX(), Vector3::UnitY(), Vector3::UnitZ(),
                               Vector3(1.0, 1.0, 1.0).normalized()};
  std::mt19937 rng(11);
  for (int i = 0; i < 3; ++i) axes.push_back(fd::random_unit(rng));
  return axes;
}

// Entrywise |a − d| ≤ tol, and a must stand well above tol unless it may vanish (comparing
// zeros proves nothing).
::testing::AssertionResult matches(const Eigen::MatrixXd& a, const Eigen::MatrixXd& d, double tol,
                                   bool require_nonzero = true) {
  const double largest = a.cwiseAbs().maxCoeff();
  if (require_nonzero && !(largest > 100.0 * tol)) {
    return ::testing::AssertionFailure()
           << "analytic object is negligible (max " << largest << ", tolerance " << tol << ")";
  }
  Eigen::Index i = 0, j = 0;
  const double error = (a - d).cwiseAbs().maxCoeff(&i, &j);
  if (error <= tol) return ::testing::AssertionSuccess();
  const Eigen::IOFormat fmt(8, 0, " ", "\n", "  [", "]");
  return ::testing::AssertionFailure() << "entry (" << i << ", " << j << "): " << a(i, j) << " vs "
                                       << d(i, j) << ", |error| " << error << " > " << tol << "\n"
                                       << a.format(fmt) << "\nvs\n"
                                       << d.format(fmt);
}

// Column k = (f(r + εe_k) − f(r − εe_k)) / 2ε.
Eigen::MatrixXd central_difference(const std::function<Eigen::VectorXd(const Vector3&)>& f,
                                   const Vector3& r, double step) {
  Eigen::MatrixXd d(f(r).size(), 3);
  for (int k = 0; k < 3; ++k) {
    const Vector3 e = step * Vector3::Unit(k);
    d.col(k) = (f(r + e) - f(r - e)) / (2.0 * step);
  }
  return d;
}

// (F(r+εe_i+εe_j) − F(r+εe_i−εe_j) − F(r−εe_i+εe_j) + F(r−εe_i−εe_j)) / 4ε².
Matrix3 second_difference(const std::function<double(const Vector3&)>& F, const Vector3& r,
                          double step) {
  Matrix3 d;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j <= i; ++j) {
      const Vector3 ei = step * Vector3::Unit(i);
      const Vector3 ej = step * Vector3::Unit(j);
      d(i, j) =
          (F(r + ei + ej) - F(r + ei - ej) - F(r - ei + ej) + F(r - ei - ej)) / (4.0 * step * step);
      d(j, i) = d(i, j);
    }
  }
  return d;
}

Eigen::VectorXd vec(const Matrix3& M) { return M.reshaped(); }

// ---------------------------------------------------------------------------------------
// Smooth test functions (tests/rotation_test_functions.hpp).
using test_functions::squared_bilinear;
using test_functions::sym;
using test_functions::TestFunction;
using test_functions::trace_and_point;

std::vector<TestFunction> test_functions() {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const Matrix3 A = Matrix3::NullaryExpr([&] { return uniform(rng); });
  return {trace_and_point(A, fd::random_vector(rng, 1.0), fd::random_vector(rng, 1.0)),
          squared_bilinear(fd::random_vector(rng, 1.0), fd::random_vector(rng, 1.0))};
}

// Largest |Ψ|, |g|, |H| at R: the size S of the derivatives of r ↦ Ψ(exp(r)) (|J_l| ≤ 1,
// and the higher derivatives of exp(r) are O(1)).
double size_at(const TestFunction& psi, const Matrix3& R) {
  return std::max({std::abs(psi.value(R)), psi.gradient(R).cwiseAbs().maxCoeff(),
                   psi.hessian(R).cwiseAbs().maxCoeff()});
}

TEST(RotationVector, TestFunctionLieDerivativesMatchFiniteDifferences) {
  const fd::Dofs dofs = {fd::rotation_dof(0)};
  for (const TestFunction& psi : test_functions()) {
    for (const Vector3& axis : test_axes()) {
      for (const double t : kAngles) {
        SCOPED_TRACE(psi.name + ", " + where(t, axis));
        State q;
        q.rotations = {so3::exp(t * axis)};
        const fd::ScalarFunction f = [&](const State& s) { return psi.value(s.rotations[0]); };
        const fd::GradientFunction grad = [&](const State& s) {
          return Eigen::VectorXd(psi.gradient(s.rotations[0]));
        };
        const Eigen::VectorXd g = psi.gradient(q.rotations[0]);
        const Eigen::MatrixXd H = psi.hessian(q.rotations[0]);
        EXPECT_TRUE(fd::check_lie_gradient(f, q, dofs, g));
        EXPECT_TRUE(fd::check_lie_hessian(grad, q, dofs, H));
        EXPECT_TRUE(fd::check_lie_hessian_from_value(f, q, dofs, H));
      }
    }
  }
}

// The point of the module: ∂Ψ/∂r = J_l(r)ᵀ g and ∂²Ψ/∂r² = J_l(r)ᵀ H J_l(r) + C(r, g), for
// r ↦ Ψ(exp(r)), at every angle including 2π − 1e-3 where J_l is nearly singular.
TEST(RotationVector, ChainRuleGivesTheDerivativesInR) {
  for (const TestFunction& psi : test_functions()) {
    const auto F = [&](const Vector3& r) { return psi.value(so3::exp(r)); };
    // ∇F(r) = J_l(r)ᵀ g(exp(r)), the analytic gradient in r.
    const auto gradient_in_r = [&](const Vector3& r) {
      Matrix3 J;
      const Matrix3 R = so3::exp(r, &J);
      return Eigen::VectorXd(J.transpose() * psi.gradient(R));
    };
    for (const Vector3& axis : test_axes()) {
      for (const double t : kAngles) {
        SCOPED_TRACE(psi.name + ", " + where(t, axis));
        const Vector3 r = t * axis;
        Matrix3 J;
        const Matrix3 R = so3::exp(r, &J);
        const Vector3 g = psi.gradient(R);
        const Vector3 gradient = J.transpose() * g;
        const Matrix3 hessian =
            J.transpose() * psi.hessian(R) * J + rotvec::hessian_correction(r, g);
        const double S = size_at(psi, R);

        // ε = 1e-6: round-off ≈ 10 eps·S/ε ≈ 2e-9·S, truncation ε²/6·|F'''| ≈ 2e-13·S.
        const std::function<Eigen::VectorXd(const Vector3&)> value = [&](const Vector3& x) {
          return Eigen::VectorXd::Constant(1, F(x));
        };
        EXPECT_TRUE(matches(gradient.transpose(), central_difference(value, r, 1e-6), 1e-8 * S));
        // The same step and error budget for differences of the analytic gradient.
        EXPECT_TRUE(matches(hessian, central_difference(gradient_in_r, r, 1e-6), 1e-8 * S));
        // ε = 1e-4 second differences: round-off ≈ 40 eps·S/ε² ≈ 1e-7·S (four values),
        // truncation ε²/12·|F''''| ≈ 1e-9·S.
        EXPECT_TRUE(matches(hessian, second_difference(F, r, 1e-4), 1e-6 * S));
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// C(r, g) on its own.

std::vector<Vector3> test_gradients() {
  std::mt19937 rng(3);
  return {Vector3::UnitX(), Vector3(0.3, -1.2, 0.7), fd::random_vector(rng, 2.0),
          fd::random_vector(rng, 2.0)};
}

// The definition, C_ij = ½ gᵀ (∂J_l/∂r_i e_j + ∂J_l/∂r_j e_i), with ∂J_l/∂r_i by central
// differences of so3::left_jacobian.
TEST(RotationVector, HessianCorrectionIsTheSymmetrisedDerivativeOfLeftJacobian) {
  for (const Vector3& g : test_gradients()) {
    for (const Vector3& axis : test_axes()) {
      for (const double t : kAngles) {
        // Below 1e-4, C ≈ t|g|/6 is under the FD resolution: see ...VanishesLinearlyAtZero.
        if (t < 1e-4) continue;
        SCOPED_TRACE(where(t, axis));
        const Vector3 r = t * axis;
        Matrix3 K;  // K_ij = gᵀ (∂J_l/∂r_i) e_j
        for (int i = 0; i < 3; ++i) {
          const Vector3 e = 1e-6 * Vector3::Unit(i);
          const Matrix3 dJ = (so3::left_jacobian(r + e) - so3::left_jacobian(r - e)) / (2.0 * 1e-6);
          K.row(i) = g.transpose() * dJ;
        }
        // ε = 1e-6 on entries of J_l ≤ 1: round-off ≈ 4 eps/ε ≈ 1e-9, truncation ε²·|J_l'''|
        // ≈ 1e-12; times |g|.
        EXPECT_TRUE(matches(rotvec::hessian_correction(r, g), sym(K), 2e-9 * g.norm()));
      }
    }
  }
}

TEST(RotationVector, HessianCorrectionIsSymmetricAndLinearInG) {
  const std::vector<Vector3> gradients = test_gradients();
  for (const Vector3& axis : test_axes()) {
    for (const double t : kAngles) {
      SCOPED_TRACE(where(t, axis));
      const Vector3 r = t * axis;
      EXPECT_TRUE(rotvec::hessian_correction(r, Vector3::Zero()).isZero(0.0));
      for (const Vector3& g : gradients) {
        const Matrix3 C = rotvec::hessian_correction(r, g);
        // ½(r vᵀ + v rᵀ): entries (i, j) and (j, i) add the same two products.
        EXPECT_LE((C - C.transpose()).cwiseAbs().maxCoeff(), 2.0 * kEps * C.norm());
        // Linear in g up to round-off of O(|g| (1 + t)²) sums.
        const Matrix3 sum = rotvec::hessian_correction(r, g + gradients[1]);
        const Matrix3 parts = C + rotvec::hessian_correction(r, gradients[1]);
        EXPECT_LE((sum - parts).cwiseAbs().maxCoeff(), 1e-14 * (g.norm() + 1.0) * (1.0 + t * t));
      }
    }
  }
}

// At r = 0, ∂J_l/∂r_i e_j = ½ hat(e_i) e_j = ½ e_i × e_j is antisymmetric in (i, j), so C(0, g) =
// 0. From the series J_l(r) = I + ½W + ⅙W² − (t²/24) W + O(t⁴), W = hat(r) (a = ½ − t²/24, b = ⅙ −
// t²/120), the next orders are
//   C(r, g) = ⅙ ((g·r) I − sym(r gᵀ)) − (1/12) sym(r (g × r)ᵀ) + O(t³ |g|):
// the ⅙W² term gives gᵀ(e_i × (r × e_j)) = (g·r) δ_ij − r_i g_j, the (t²/24)W term
// ∂(t²)/∂r_i gᵀ W e_j = 2 r_i (g × r)_j (hat(e_i) and W hat(e_i) parts are antisymmetric).
TEST(RotationVector, HessianCorrectionVanishesLinearlyAtZero) {
  for (const Vector3& g : test_gradients()) {
    EXPECT_TRUE(rotvec::hessian_correction(Vector3::Zero(), g).isZero(0.0));
    for (const Vector3& axis : test_axes()) {
      for (const double t : {1e-12, 1e-9, 1e-6, 1e-4, 1e-2}) {
        SCOPED_TRACE(where(t, axis));
        const Vector3 r = t * axis;
        const Matrix3 expected = (g.dot(r) * Matrix3::Identity() - sym(r * g.transpose())) / 6.0 -
                                 sym(r * g.cross(r).transpose()) / 12.0;
        // The O(t³) remainder has coefficients ≤ 1/20 (from b's t²/120 and β ≈ −1/60 in
        // rotation_vector.cpp's C = sym(r vᵀ) + b (g·r) I); plus a few ulps of C ≈ t|g|/6.
        EXPECT_TRUE(matches(rotvec::hessian_correction(r, g), expected,
                            (0.05 * t * t * t + 4.0 * kEps * t) * g.norm()));
      }
    }
  }
}

// Series and closed forms agree across the switch at t = 2 (and at t/2 = 2 for the half-angle
// terms of exp_jacobian): a wrong series coefficient would show here at its full size.
TEST(RotationVector, SeriesAndClosedFormsAgreeAtTheSwitch) {
  const Vector3 g(0.3, -1.2, 0.7);
  for (const Vector3& axis : test_axes()) {
    for (const double t : {2.0, 4.0}) {
      SCOPED_TRACE(where(t, axis));
      // 8 ulps either side, so that ‖r‖ is on the right side whatever the rounding of the norm.
      const Vector3 below = t * (1.0 - 8.0 * kEps) * axis;
      const Vector3 above = t * (1.0 + 8.0 * kEps) * axis;
      ASSERT_LT(below.norm(), t);
      ASSERT_GE(above.norm(), t);
      // The jump in r (16 ulps of t) moves each result by ≤ 16 ulps of t · |derivative| = O(1)
      // (entries O(1)–O(t²|g|)); the branches themselves differ by ≤ 16 ulps of their values.
      const Matrix3 C_below = rotvec::hessian_correction(below, g);
      EXPECT_TRUE(
          matches(C_below, rotvec::hessian_correction(above, g), 64.0 * kEps * t * t * g.norm()));
      EXPECT_TRUE(
          matches(rotvec::exp_jacobian(below), rotvec::exp_jacobian(above), 64.0 * kEps * t * t));
    }
  }
}

// ---------------------------------------------------------------------------------------
// Jacobian of the exponential, eq. (5).

TEST(RotationVector, ExpJacobianColumnsAreHatOfLeftJacobianTimesExp) {
  for (const Vector3& axis : test_axes()) {
    for (const double t : kAngles) {
      SCOPED_TRACE(where(t, axis));
      const Vector3 r = t * axis;
      Matrix3 J;
      const Matrix3 R = so3::exp(r, &J);
      Matrix93 expected;
      for (int k = 0; k < 3; ++k) expected.col(k) = vec(so3::hat(J.col(k)) * R);
      // Both sides are short sums of O(1) products: a few ulps (measured ≤ 1e-15).
      EXPECT_TRUE(matches(rotvec::exp_jacobian(r), expected, 1e-14));
    }
  }
}

TEST(RotationVector, ExpJacobianMatchesFiniteDifferences) {
  const std::function<Eigen::VectorXd(const Vector3&)> vec_exp = [](const Vector3& r) {
    return vec(so3::exp(r));
  };
  for (const Vector3& axis : test_axes()) {
    for (const double t : kAngles) {
      SCOPED_TRACE(where(t, axis));
      const Vector3 r = t * axis;
      // ε = 1e-6 on entries ≤ 1: round-off ≈ 4 eps/ε ≈ 1e-9, truncation ε²/6·|R'''| ≈ 1e-13.
      EXPECT_TRUE(matches(rotvec::exp_jacobian(r), central_difference(vec_exp, r, 1e-6), 2e-9));
    }
  }
}

// Paper Fig. 3. Column k is vec(hat(J_l e_k) R) and ⟨hat(u)R, hat(w)R⟩_F = tr(hat(u)ᵀhat(w)) = 2
// u·w (‖hat(e_k)‖_F = √2), so the singular values are √2 times those of J_l(r): 1 along the axis
// (J_l r = r), and on the plane normal to it J_l acts as |sinc(t/2)| times a rotation
// ((1 − b t²)² + (a t)² = (sin² t + (1 − cos t)²)/t² = sinc²(t/2)). Hence
//   σ1 = √2,  σ2 = σ3 = √2 |sinc(t/2)| → 0 as t → 2π.
TEST(RotationVector, ExpJacobianSingularValuesFollowFigure3) {
  const double sqrt2 = std::sqrt(2.0);
  for (const Vector3& axis : test_axes()) {
    double previous = sqrt2;
    for (int i = 0; i <= 64; ++i) {
      const double t = i < 64 ? 2.0 * kPi * i / 64.0 : 2.0 * kPi - 1e-6;
      SCOPED_TRACE(where(t, axis));
      const Eigen::Vector3d s =
          Eigen::JacobiSVD<Matrix93>(rotvec::exp_jacobian(t * axis)).singularValues();
      const double half = 0.5 * t;
      const double perpendicular = sqrt2 * (half == 0.0 ? 1.0 : std::abs(std::sin(half) / half));
      // One-sided Jacobi SVD: absolute error a few ulps of σ1.
      EXPECT_NEAR(s(0), sqrt2, 1e-14);
      EXPECT_NEAR(s(1), perpendicular, 1e-14);
      EXPECT_NEAR(s(2), perpendicular, 1e-14);
      EXPECT_LE(s(1), previous + 1e-14);  // decreasing towards 2π
      previous = s(1);
    }
    EXPECT_LT(previous, 1e-6);  // at 2π − 1e-6: √2 · 1e-6/(2π)
  }
}

// ---------------------------------------------------------------------------------------

TEST(RotationVector, WrapKeepsTheRotationWithAngleAtMostPi) {
  for (const Vector3& axis : test_axes()) {
    for (const double t : {0.0, 1.0, kPi, kPi + 1e-3, 1.5 * kPi, 2.0 * kPi - 1e-3, 5.0 * kPi}) {
      SCOPED_TRACE(where(t, axis));
      const Vector3 r = t * axis;
      const Vector3 w = rotvec::wrap(r);
      if (r.norm() <= kPi) {
        EXPECT_EQ(w, r);
      }
      EXPECT_LE(w.norm(), kPi * (1.0 + 4.0 * kEps));
      // The same rotation: exp of either has O(1) entries, the angles differ by a multiple of
      // 2π that carries the rounding of 2π and of t (a few ulps of 5π).
      EXPECT_LE((so3::exp(w) - so3::exp(r)).cwiseAbs().maxCoeff(), 1e-12);
      // Along the same axis, either sense.
      if (t > 0.0) {
        EXPECT_NEAR(std::abs(w.dot(axis)), w.norm(), 1e-15 * t);
      }
    }
  }
}

}  // namespace
}  // namespace liedyn::rotation_vector_tests

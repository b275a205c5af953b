// liedyn::SO3Manifold (manifolds/so3_manifold.hpp): unit quaternions (x, y, z, w) with the
// world-frame tangent of lib/so3.hpp, Plus(q, δ) = exp(δ) ⊗ q, Minus(p, q) = log(p ⊗ q⁻¹).
//   * Ceres's own manifold invariants (ceres/manifold_test_utils.h) at random points and at the
//     angle extremes;
//   * our own: Plus against so3::exp, Minus inverting Plus (to full relative precision where
//     the storage allows it), the antipodal sign, rotations by π, the Jacobians against central
//     differences, exp and log against extended precision, rejected input;
//   * ceres::GradientChecker on liedyn terms (rotational inertia, rod bend–twist) whose cost
//     returns J_Lie · lie_to_ambient(q);
//   * the Ceres step back-end with solver.ceres.lie_blocks = "manifold" against the chart
//     (check_ceres_gradients runs over both kinds of blocks in tests/test_backends.cpp).
//
// Round-off bounds below count roundings of O(1) numbers (unit quaternions, rotation
// entries): eps = 2.2e-16 per operation, a few operations per stage.

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <ceres/manifold_test_utils.h>
#include <ceres/product_manifold.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "fd_check.hpp"
#include "lib/incremental_potential.hpp"
#include "lib/inertia.hpp"
#include "lib/model.hpp"
#include "lib/rod_terms.hpp"
#include "lib/so3.hpp"
#include "manifolds/quaternion.hpp"
#include "manifolds/so3_manifold.hpp"
#include "problems/scene.hpp"
#include "solvers/ceres_step.hpp"
#include "solvers/simulator.hpp"
#include "trajectory_compare.hpp"
#include "solvers/step_solver.hpp"

namespace liedyn::so3_manifold_tests {
namespace {

using Vector4 = Eigen::Vector4d;
using RowMajor43 = Eigen::Matrix<double, 4, 3, Eigen::RowMajor>;
using RowMajor34 = Eigen::Matrix<double, 3, 4, Eigen::RowMajor>;

using fd::kPi;
using fd::kEps;

const std::filesystem::path kScenes = std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes";

Vector4 random_quaternion(std::mt19937& rng) {  // uniform on S³: both signs of w
  std::normal_distribution<double> normal;
  Vector4 q;
  for (int i = 0; i < 4; ++i) q(i) = normal(rng);
  return q.normalized();
}

// The quaternion of exp(angle·axis) R(x), in x's hemisphere (x·y ≥ 0), built through rotation
// matrices (so3::exp, Shepperd), independently of Plus.
Vector4 rotated(const Vector4& x, double angle, const Vector3& axis) {
  Vector4 y = SO3Manifold::quaternion(so3::exp(angle * axis) * SO3Manifold::rotation(x.data()));
  if (y.dot(x) < 0.0) y = -y;
  return y;
}

// Round-off that grows with the angle: sin and cos are taken at (multiples of) t = ‖δ‖, itself
// computed to a relative eps, so they move by ≲ eps·t.
double angle_roundoff(double t) { return 4 * kEps * t; }

template <int Rows, int Cols, int Options>
void fill_random(Eigen::Matrix<double, Rows, Cols, Options>& A, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    for (Eigen::Index j = 0; j < A.cols(); ++j) A(i, j) = u(rng);
  }
}

Vector4 plus(const Vector4& x, const Vector3& delta) {
  Vector4 y;
  EXPECT_TRUE(SO3Manifold{}.Plus(x.data(), delta.data(), y.data()));
  return y;
}

Vector3 minus(const Vector4& y, const Vector4& x) {
  Vector3 d;
  EXPECT_TRUE(SO3Manifold{}.Minus(y.data(), x.data(), d.data()));
  return d;
}

// Quaternions whose products with exp(δ) are exact (one non-zero component ±1: the identity,
// its antipode and the half turns about the axes), so that Plus and Minus lose nothing of a
// tiny δ: the only points where Minus(Plus(x, δ), x) = δ can hold to relative precision for
// ‖δ‖ ≪ 1 (elsewhere Plus stores O(1) numbers and δ comes back to absolute round-off).
std::vector<Vector4> exact_quaternions() {
  return {Vector4(0, 0, 0, 1), Vector4(0, 0, 0, -1), Vector4(1, 0, 0, 0), Vector4(0, 1, 0, 0),
          Vector4(0, 0, 1, 0), Vector4(0, -1, 0, 0)};
}

// ---------------------------------------------------------------------------------------
// 1. Ceres's manifold invariants (ceres/manifold_test_utils.h), which assert, at tolerance t:
//    Plus(x, 0) = x; Minus(x, x) = 0; Minus(Plus(x, δ), x) = δ and for δ = 0 (relative to
//    ‖δ‖); Plus(x, Minus(y, x)) = y and for y = x (AMBIENT vectors, relative to ‖y‖ = 1);
//    PlusJacobian and MinusJacobian against Ridders differences of Plus(x, ·) at 0 and of
//    Minus(·, x) at x (4 ambient directions); MinusJacobian · PlusJacobian = I;
//    RightMultiplyByPlusJacobian = A · PlusJacobian for 0–3 rows.
// Tolerance 1e-9, as Ceres's own manifold tests: the Ridders differences are good to ~1e-12,
// Plus/Minus round trips to ~1e-15 absolute.
// Points left out, because the invariants do not hold there:
//   * ‖δ‖ ≥ π: Minus returns the shorter way, δ − 2π δ/‖δ‖ (at π either sign) —
//     PlusBeyondPiIsTheExactExponential tests that instead;
//   * y at exactly π from x: x·y = 0 and Plus(x, Minus(y, x)) is ±y by round-off; and y in
//     the other hemisphere: −y is the same rotation, and Minus/Plus return the representative
//     in x's hemisphere. y is chosen in x's hemisphere, < π away (rotated above);
//   * ‖δ‖ < 1e-4 at x other than exact_quaternions(): δ is recovered to absolute round-off
//     ~eps (MinusInvertsPlusBelowPi), which the relative comparison at 1e-9 cannot resolve.

constexpr double kInvariantTolerance = 1e-9;

// Angles for ‖δ‖ and for the rotation between x and y.
const std::vector<double> kBelowPi = {0.0, 1e-9, 1e-4, 1.0, 2.5, kPi - 1e-6, kPi - 1e-12};

void expect_invariants(const Vector4& x, const Vector3& delta, const Vector4& y) {
  using namespace ceres;  // the macro names ceres::Vector and the matchers unqualified
  const SO3Manifold manifold;
  const ceres::Vector xv = x, dv = delta, yv = y;
  EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(manifold, xv, dv, yv, kInvariantTolerance);
}

TEST(SO3Manifold, CeresInvariantsHoldAtRandomPoints) {
  std::mt19937 rng(101);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector4 x = random_quaternion(rng);
    const Vector3 delta = std::uniform_real_distribution<double>(1e-4, kPi - 1e-6)(rng) *
                          fd::random_unit(rng);
    Vector4 y = random_quaternion(rng);
    if (y.dot(x) < 0.0) y = -y;  // x's hemisphere (see above)
    SCOPED_TRACE(trial);
    expect_invariants(x, delta, y);
  }
}

// A pose block of 7 doubles (position, then quaternion) for users who want one: Ceres's
// ProductManifold of R³ and SO3Manifold, whose tangent is (translation, left rotation vector),
// the pair liedyn's bodies use as two blocks (docs/manifolds.md). The invariants hold for the
// product as for its factor.
TEST(SO3Manifold, PoseBlocksAsAProductWithR3KeepTheInvariants) {
  using namespace ceres;  // the macro names ceres::Vector and the matchers unqualified
  const ProductManifold<EuclideanManifold<3>, SO3Manifold> pose{EuclideanManifold<3>{}, SO3Manifold{}};
  EXPECT_EQ(pose.AmbientSize(), 7);
  EXPECT_EQ(pose.TangentSize(), 6);
  std::mt19937 rng(107);
  for (int trial = 0; trial < 50; ++trial) {
    SCOPED_TRACE(trial);
    const Vector4 qx = random_quaternion(rng);
    Vector4 qy = random_quaternion(rng);
    if (qy.dot(qx) < 0.0) qy = -qy;  // qx's hemisphere, as above
    ceres::Vector x(7), y(7), delta(6);
    x << 3.0 * fd::random_unit(rng), qx;
    y << -2.0 * fd::random_unit(rng), qy;
    delta << fd::random_unit(rng),
        std::uniform_real_distribution<double>(1e-4, kPi - 1e-6)(rng) * fd::random_unit(rng);
    EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(pose, x, delta, y, kInvariantTolerance);
  }
}

TEST(SO3Manifold, CeresInvariantsHoldAtTheAngleExtremes) {
  std::mt19937 rng(103);
  std::vector<std::pair<Vector4, bool>> points;  // x, and whether products with it are exact
  for (const Vector4& x : exact_quaternions()) points.emplace_back(x, true);
  Vector4 half_turn;  // a half turn about a random axis: w = 0 exactly
  half_turn << fd::random_unit(rng), 0.0;
  points.emplace_back(half_turn, false);
  for (const double angle : fd::kAngles) {
    points.emplace_back(SO3Manifold::quaternion(fd::rotation_at(angle, rng)), false);
  }
  for (int i = 0; i < 4; ++i) points.emplace_back(random_quaternion(rng), false);
  int checked = 0;
  for (const auto& [x, exact] : points) {
    for (const double d : kBelowPi) {
      if (!exact && d > 0.0 && d < 1e-4) continue;  // absolute round-off only (see above)
      for (const double a : kBelowPi) {
        SCOPED_TRACE(fd::trace("x, |delta|, angle(x, y)", x.w(), d, a));
        const Vector3 delta = d * fd::random_unit(rng);
        const Vector4 y = rotated(x, a, fd::random_unit(rng));
        expect_invariants(x, delta, y);
        ++checked;
      }
    }
  }
  // 6 exact points × 7 × 7, the 14 others × 6 (1e-9 left out) × 7.
  EXPECT_EQ(checked, 6 * 7 * 7 + 14 * 6 * 7);
}

// Plus is the exact exponential for every δ, also beyond π and at 2π (where exp(δ) = −1 as a
// quaternion: Plus(x, δ) = −x, the same rotation); Minus then returns the shorter way.
TEST(SO3Manifold, PlusBeyondPiIsTheExactExponential) {
  std::mt19937 rng(107);
  for (int trial = 0; trial < 20; ++trial) {
    const Vector4 x = random_quaternion(rng);
    for (const double t : {kPi, kPi + 1e-6, 4.0, 2 * kPi - 1e-3, 2 * kPi - 1e-6, 2 * kPi,
                           2 * kPi + 1e-6, 3 * kPi, 10.0, 100.0}) {
      SCOPED_TRACE(fd::trace("trial, |delta|", trial, t));
      const Vector3 n = fd::random_unit(rng);
      const Vector3 delta = t * n;
      const Vector4 y = plus(x, delta);
      // Against exp(δ) ⊗ x in extended precision (80-bit long double): a few roundings of
      // O(1) numbers in the product and the normalisation, and angle_roundoff.
      const long double T = std::sqrt(static_cast<long double>(delta.x()) * delta.x() +
                                      static_cast<long double>(delta.y()) * delta.y() +
                                      static_cast<long double>(delta.z()) * delta.z());
      const long double s = std::sin(T / 2) / T, c = std::cos(T / 2);
      const long double e[4] = {s * delta.x(), s * delta.y(), s * delta.z(), c};
      const long double ref[4] = {e[3] * x(0) + x(3) * e[0] + e[1] * x(2) - e[2] * x(1),
                                  e[3] * x(1) + x(3) * e[1] + e[2] * x(0) - e[0] * x(2),
                                  e[3] * x(2) + x(3) * e[2] + e[0] * x(1) - e[1] * x(0),
                                  e[3] * x(3) - e[0] * x(0) - e[1] * x(1) - e[2] * x(2)};
      for (int i = 0; i < 4; ++i) {
        EXPECT_LE(std::abs(static_cast<long double>(y(i)) - ref[i]), 16 * kEps + angle_roundoff(t))
            << i;
      }
      EXPECT_LE((SO3Manifold::rotation(y.data()) - so3::exp(delta) * SO3Manifold::rotation(x.data()))
                    .cwiseAbs()
                    .maxCoeff(),
                32 * kEps + angle_roundoff(t));
      // The shorter way: δ − 2πk n with ‖·‖ ≤ π (k the nearest whole number of turns).
      if (std::abs(std::remainder(t, 2 * kPi)) < kPi - 1e-9) {
        const Vector3 shorter = std::remainder(t, 2 * kPi) * n;
        EXPECT_LE((minus(y, x) - shorter).norm(), 64 * kEps * (1.0 + t)) << minus(y, x).transpose();
      }
    }
    // At 2π (its double): −x, up to sin(t/2) at t/2 ≈ π.
    const Vector3 full = 2 * kPi * fd::random_unit(rng);
    EXPECT_LE((plus(x, full) + x).norm(), 16 * kEps + angle_roundoff(2 * kPi));
  }
}

// ---------------------------------------------------------------------------------------
// 2. Our own checks.

// R(Plus(q, δ)) = exp(δ) R(q). Each side: the quaternion product, normalisation and R(q)
// (≤ ~4 roundings per entry, each quaternion error counting 4× in R) against Rodrigues and a
// 3-term matrix product; ≤ ~25 eps in the worst case, plus angle_roundoff.
TEST(SO3Manifold, PlusIsTheLeftExponential) {
  std::mt19937 rng(109);
  for (int trial = 0; trial < 50; ++trial) {
    const Vector4 q = random_quaternion(rng);
    for (const double t : {0.0, 1e-12, 1e-9, 1e-4, 1e-3, 1.0, 2.5, kPi - 1e-6, kPi,
                           2 * kPi - 1e-6, 7.0}) {
      SCOPED_TRACE(fd::trace("trial, |delta|", trial, t));
      const Vector3 delta = t * fd::random_unit(rng);
      const Vector4 p = plus(q, delta);
      EXPECT_NEAR(p.norm(), 1.0, 2 * kEps);
      EXPECT_LE((SO3Manifold::rotation(p.data()) - so3::exp(delta) * SO3Manifold::rotation(q.data()))
                    .cwiseAbs()
                    .maxCoeff(),
                32 * kEps + angle_roundoff(t));
    }
  }
}

// Minus(Plus(q, δ), q) = δ for ‖δ‖ < π.
//   * At exact_quaternions() no product rounds beyond a relative eps, and the series
//     branches of exp and log (t < 1e-3, ‖v‖ < 1e-4 w) keep full relative precision:
//     ‖Minus − δ‖ ≤ 8 eps ‖δ‖, down to ‖δ‖ = 1e-300 (where ‖δ‖² underflows).
//   * At any q, Plus stores O(1) numbers, so δ comes back to absolute round-off: two products
//     and a normalisation (≤ ~10 eps per component of p ⊗ q⁻¹), scaled by log's derivative
//     (≤ π/2 · 2 near π): ≤ 64 eps.
TEST(SO3Manifold, MinusInvertsPlusBelowPi) {
  std::mt19937 rng(113);
  const std::vector<double> norms = {1e-300, 1e-30, 1e-12, 1e-9, 1e-6, 1e-4, 0.99e-3, 1.01e-3,
                                     0.1, 1.0, 2.5, kPi - 1e-6, kPi - 1e-12};
  for (const Vector4& q : exact_quaternions()) {
    for (const double t : norms) {
      SCOPED_TRACE(fd::trace("q.w, q.x, |delta|", q.w(), q.x(), t));
      const Vector3 delta = t * fd::random_unit(rng);
      EXPECT_LE((minus(plus(q, delta), q) - delta).norm(), 8 * kEps * t)
          << minus(plus(q, delta), q).transpose() << " vs " << delta.transpose();
    }
  }
  for (int trial = 0; trial < 100; ++trial) {
    const Vector4 q = random_quaternion(rng);
    for (const double t : norms) {
      SCOPED_TRACE(fd::trace("trial, |delta|", trial, t));
      const Vector3 delta = t * fd::random_unit(rng);
      EXPECT_LE((minus(plus(q, delta), q) - delta).norm(), 64 * kEps);
    }
  }
}

// q and −q are one rotation: Minus between them is 0, and Minus does not depend on the sign
// of either argument below π (where the result is unique).
TEST(SO3Manifold, MinusOfAntipodalQuaternionsIsZero) {
  std::mt19937 rng(127);
  for (int trial = 0; trial < 100; ++trial) {
    const Vector4 q = random_quaternion(rng);
    EXPECT_LE(minus(-q, q).norm(), 4 * kEps);
    EXPECT_LE(minus(q, -q).norm(), 4 * kEps);
    const Vector4 p = rotated(q, 2.0, fd::random_unit(rng));
    const Vector3 d = minus(p, q);
    EXPECT_NEAR(d.norm(), 2.0, 64 * kEps);
    EXPECT_LE((minus(-p, q) - d).norm(), 4 * kEps);
    EXPECT_LE((minus(p, -q) - d).norm(), 4 * kEps);
    EXPECT_LE((minus(-p, -q) - d).norm(), 4 * kEps);
  }
}

// A rotation by exactly π: w = 0 in p ⊗ q⁻¹ (exactly at q = I; to round-off at other q),
// the angle 2 atan2(‖v‖, |w|) = π, and Plus(q, Minus(p, q)) = ±p.
TEST(SO3Manifold, MinusAtExactlyPiHasNormPi) {
  std::mt19937 rng(131);
  const Vector4 identity(0, 0, 0, 1);
  for (int trial = 0; trial < 100; ++trial) {
    Vector4 p;
    p << fd::random_unit(rng), 0.0;
    EXPECT_NEAR(minus(p, identity).norm(), kPi, 4 * kEps * kPi);
    const Vector4 q = random_quaternion(rng);
    const Vector4 pq = quat::product(p, q);  // π away from q
    const Vector3 d = minus(pq, q);
    EXPECT_NEAR(d.norm(), kPi, 64 * kEps);
    const Vector4 back = plus(q, d);
    EXPECT_LE(std::min((back - pq).norm(), (back + pq).norm()), 64 * kEps);
  }
}

// PlusJacobian = ∂Plus(x, δ)/∂δ at 0 and MinusJacobian = ∂Minus(y, x)/∂y at y = x, against
// central differences (ε = 1e-5): truncation ε²/6·|f'''| with |f'''| ≲ 10 for these products
// of unit quaternions, their normalisation and log near 0, round-off ~eps/ε: ≤ 3e-10 against
// entries of size ½ (Q) and 2 (4Qᵀ). MinusJacobian is checked along the 4 ambient directions:
// y = x ± εe_j leaves the unit sphere, and Minus, which normalises y, sees only its tangent
// part; the radial direction x itself gives 0.
TEST(SO3Manifold, JacobiansMatchCentralDifferences) {
  const SO3Manifold m;
  std::mt19937 rng(137);
  std::vector<Vector4> points = exact_quaternions();
  for (const double angle : fd::kAngles) {
    points.push_back(SO3Manifold::quaternion(fd::rotation_at(angle, rng)));
  }
  for (int i = 0; i < 20; ++i) points.push_back(random_quaternion(rng));
  const double eps = 1e-5;
  for (const Vector4& x : points) {
    SCOPED_TRACE(fd::trace("x", x.x(), x.y(), x.w()));
    RowMajor43 P;
    RowMajor34 M;
    ASSERT_TRUE(m.PlusJacobian(x.data(), P.data()));
    ASSERT_TRUE(m.MinusJacobian(x.data(), M.data()));
    EXPECT_LE((P - quat::rate_matrix(x)).cwiseAbs().maxCoeff(), 0.0);  // Q(x), as documented
    for (int k = 0; k < 3; ++k) {
      const Vector4 fd_k = (plus(x, eps * Vector3::Unit(k)) - plus(x, -eps * Vector3::Unit(k))) / (2 * eps);
      EXPECT_LE((fd_k - P.col(k)).cwiseAbs().maxCoeff(), 1e-8) << "PlusJacobian column " << k;
    }
    for (int j = 0; j < 4; ++j) {
      const Vector3 fd_j = (minus(x + eps * Vector4::Unit(j), x) - minus(x - eps * Vector4::Unit(j), x)) / (2 * eps);
      EXPECT_LE((fd_j - M.col(j)).cwiseAbs().maxCoeff(), 1e-8) << "MinusJacobian column " << j;
    }
    const Vector3 radial = (minus((1 + eps) * x, x) - minus((1 - eps) * x, x)) / (2 * eps);
    EXPECT_LE(radial.cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LE((M * x).cwiseAbs().maxCoeff(), 8 * kEps);
    EXPECT_LE((M - SO3Manifold::lie_to_ambient(x.data())).cwiseAbs().maxCoeff(), 0.0);
  }
}

// MinusJacobian · PlusJacobian = 4 Q(x)ᵀ Q(x) = ‖x‖² I: four-term sums of products, ≤ 8 eps.
TEST(SO3Manifold, MinusJacobianIsALeftInverseOfPlusJacobian) {
  const SO3Manifold m;
  std::mt19937 rng(139);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector4 x = random_quaternion(rng);
    RowMajor43 P;
    RowMajor34 M;
    ASSERT_TRUE(m.PlusJacobian(x.data(), P.data()));
    ASSERT_TRUE(m.MinusJacobian(x.data(), M.data()));
    EXPECT_LE((M * P - Matrix3::Identity()).cwiseAbs().maxCoeff(), 8 * kEps);
  }
}

// RightMultiplyByPlusJacobian(x, A) = A · PlusJacobian(x) (row-major, as Ceres stores them),
// and for the ambient Jacobian J · lie_to_ambient(x) a cost returns, it gives back J.
TEST(SO3Manifold, RightMultiplyByPlusJacobianIsAPlusJacobian) {
  const SO3Manifold m;
  std::mt19937 rng(149);
  using Rows4 = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
  using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  for (int trial = 0; trial < 50; ++trial) {
    const Vector4 x = random_quaternion(rng);
    RowMajor43 P;
    ASSERT_TRUE(m.PlusJacobian(x.data(), P.data()));
    for (const int rows : {1, 3, 7}) {
      SCOPED_TRACE(rows);
      Rows4 A(rows, 4);
      fill_random(A, rng);
      Rows3 out(rows, 3);
      ASSERT_TRUE(m.RightMultiplyByPlusJacobian(x.data(), rows, A.data(), out.data()));
      EXPECT_LE((out - A * P).cwiseAbs().maxCoeff(), 8 * kEps);
      Rows3 J(rows, 3);
      fill_random(J, rng);
      const Rows4 J_amb = J * SO3Manifold::lie_to_ambient(x.data());
      ASSERT_TRUE(m.RightMultiplyByPlusJacobian(x.data(), rows, J_amb.data(), out.data()));
      EXPECT_LE((out - J).cwiseAbs().maxCoeff(), 16 * kEps);
    }
  }
}

// exp and log against 80-bit extended precision: the Taylor branches (exp: t < 1e-3; log:
// ‖v‖ < 1e-4 w) and the closed forms on both sides of their switches, to a relative 4 eps per
// component (a handful of roundings; the truncated series are good to < 1e-24 there).
TEST(SO3Manifold, ExpAndLogKeepFullRelativePrecision) {
  std::mt19937 rng(151);
  for (const double t : {1e-300, 1e-100, 1e-12, 1e-9, 1e-6, 1e-4, 0.999e-3, 1e-3, 1.001e-3,
                         0.01, 0.5, 1.0}) {
    for (int trial = 0; trial < 10; ++trial) {
      SCOPED_TRACE(fd::trace("t, trial", t, trial));
      const Vector3 delta = t * fd::random_unit(rng);
      const Vector4 e = SO3Manifold::exp(delta);
      const long double T = std::sqrt(static_cast<long double>(delta.x()) * delta.x() +
                                      static_cast<long double>(delta.y()) * delta.y() +
                                      static_cast<long double>(delta.z()) * delta.z());
      const long double s = std::sin(T / 2) / T;
      for (int i = 0; i < 3; ++i) {
        const long double ref = s * delta(i);
        EXPECT_LE(std::abs(e(i) - ref), 4 * kEps * std::abs(ref)) << i;
      }
      EXPECT_LE(std::abs(e(3) - std::cos(T / 2)), 2 * kEps);
      // log of a unit quaternion with ‖v‖ = sin(t/2) and w = cos(t/2), in double; the
      // reference is exact for these stored numbers.
      const Vector4 q = e;
      const Vector3 theta = SO3Manifold::log(q);
      const long double n = std::sqrt(static_cast<long double>(q.x()) * q.x() +
                                      static_cast<long double>(q.y()) * q.y() +
                                      static_cast<long double>(q.z()) * q.z());
      const long double f = n == 0 ? 2.0L / q.w() : 2 * std::atan2(n, static_cast<long double>(q.w())) / n;
      for (int i = 0; i < 3; ++i) {
        const long double ref = f * q(i);
        EXPECT_LE(std::abs(theta(i) - ref), 4 * kEps * std::abs(ref)) << i;
      }
    }
  }
  // log's switch at ‖v‖ = 1e-4 w, away from exp's.
  for (const double r : {0.999e-4, 1e-4, 1.001e-4}) {
    Vector4 q;
    q << r * fd::random_unit(rng), 1.0;
    const Vector3 theta = SO3Manifold::log(q);
    const long double n = std::sqrt(static_cast<long double>(q.x()) * q.x() +
                                    static_cast<long double>(q.y()) * q.y() +
                                    static_cast<long double>(q.z()) * q.z());
    const long double f = 2 * std::atan2(n, 1.0L) / n;
    for (int i = 0; i < 3; ++i) {
      EXPECT_LE(std::abs(theta(i) - f * q(i)), 4 * kEps * std::abs(f * q(i))) << r;
    }
  }
}

// log(exp(δ)) = δ below π, the shorter way beyond; log(−q) = log(q) (bit for bit where
// w ≠ 0; ±, both of norm π, at w = 0); exp(log(q)) = q or −q, whichever has w ≥ 0;
// ‖log(q)‖ ≤ π; the conversions quaternion(R) (w ≥ 0) and rotation(q) (normalising).
TEST(SO3Manifold, ExpLogRoundTripAndSign) {
  std::mt19937 rng(157);
  for (int trial = 0; trial < 50; ++trial) {
    for (const double t : {1e-9, 1e-4, 1.0, 2.5, kPi - 1e-6, kPi - 1e-12}) {
      const Vector3 delta = t * fd::random_unit(rng);
      EXPECT_LE((SO3Manifold::log(SO3Manifold::exp(delta)) - delta).norm(), 8 * kEps * t) << t;
      EXPECT_LE((SO3Manifold::rotation(SO3Manifold::exp(delta).data()) - so3::exp(delta))
                    .cwiseAbs()
                    .maxCoeff(),
                16 * kEps);
    }
    const Vector3 n = fd::random_unit(rng);
    const Vector3 beyond = SO3Manifold::log(SO3Manifold::exp((kPi + 0.5) * n));
    EXPECT_LE((beyond + (kPi - 0.5) * n).norm(), 16 * kEps);

    const Vector4 q = random_quaternion(rng);
    const Vector3 theta = SO3Manifold::log(q);
    EXPECT_LE(theta.norm(), kPi);
    EXPECT_EQ(SO3Manifold::log(-q), theta);
    const Vector4 back = SO3Manifold::exp(theta);
    EXPECT_GE(back.w(), 0.0);
    EXPECT_LE((back - (q.w() >= 0.0 ? q : Vector4(-q))).norm(), 8 * kEps);

    Vector4 half;  // w = 0
    half << fd::random_unit(rng), 0.0;
    const Vector3 a = SO3Manifold::log(half), b = SO3Manifold::log(-half);
    EXPECT_NEAR(a.norm(), kPi, 4 * kEps * kPi);
    EXPECT_LE(std::min((a - b).norm(), (a + b).norm()), 4 * kEps * kPi);

    const Matrix3 R = fd::rotation_at(std::uniform_real_distribution<double>(0.0, kPi)(rng), rng);
    const Vector4 qr = SO3Manifold::quaternion(R);
    EXPECT_GE(qr.w(), 0.0);
    EXPECT_NEAR(qr.norm(), 1.0, 2 * kEps);
    EXPECT_LE((SO3Manifold::rotation(qr.data()) - R).cwiseAbs().maxCoeff(), 16 * kEps);
    const Vector4 scaled = 3.0 * qr;
    EXPECT_LE((SO3Manifold::rotation(scaled.data()) - R).cwiseAbs().maxCoeff(), 16 * kEps);
  }
}

TEST(SO3Manifold, MinusRejectsZeroAndNonFiniteInput) {
  const SO3Manifold m;
  const Vector4 good = Vector4(1, 2, 3, 4).normalized();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<Vector4> bad = {Vector4::Zero(), Vector4(nan, 0, 0, 1), Vector4(0, 0, 0, nan),
                                    Vector4(inf, 0, 0, 1), Vector4(0, -inf, 0, 0)};
  Vector3 out;
  EXPECT_TRUE(m.Minus(good.data(), good.data(), out.data()));
  for (const Vector4& b : bad) {
    SCOPED_TRACE(::testing::Message() << b.transpose());
    EXPECT_FALSE(m.Minus(b.data(), good.data(), out.data()));
    EXPECT_FALSE(m.Minus(good.data(), b.data(), out.data()));
    EXPECT_FALSE(m.Minus(b.data(), b.data(), out.data()));
  }
}

// ---------------------------------------------------------------------------------------
// 3. ceres::GradientChecker on liedyn terms through SO3Manifold.
//
// The cost wraps a term's residual(q, r, J) (Lie Jacobian) over one quaternion block per
// rotation and returns J_amb = J_Lie · lie_to_ambient(q) (manifolds/so3_manifold.hpp).
// GradientChecker differentiates the cost in AMBIENT coordinates with Ridders' method and
// compares J_amb · PlusJacobian with numeric · PlusJacobian entry by entry, relatively. The
// cost normalises q (SO3Manifold::rotation), so it is smooth (analytic within |Δq| < 1 of a
// unit q, where q/‖q‖ is singular). Ridders' default initial step, 32·max(1e-2, 1e-2|x_i|)
// ≥ 0.32, is a third of that radius: on the bend–twist term its tableau looked unstable
// early and GradientChecker returned estimates off by up to 6e-4 of a block (4e-3 entry by
// entry) in 16 of the 384 probes below (Ceres 2.1; the analytic Jacobian and plain central
// differences of step 1e-6 agree to 1e-10 there).
// The bend–twist check therefore starts Ridders at 32·1e-4 (ridders_relative_initial_step_size
// = 1e-4, what ceres/manifold_test_utils.h uses for Plus and Minus); the inertia, linear in
// R, passes with the defaults. (Rod point coordinates, where the default step is as long as
// an edge — solvers/ceres_step.hpp — are left to check_ceres_gradients below.)
// Residuals are mixed by a random orthogonal matrix (½‖r‖² unchanged): GradientChecker's
// entry-by-entry relative test would otherwise compare the round-off of structural zeros
// (the diagonal of −hat(c_k) in the inertia's Jacobian) with each other.
// Precision 1e-6: Ridders' extrapolation is good to ~1e-13 absolute here (entry-relative
// errors ≤ 4e-12 on the inertia, ≤ 2e-8 on bend–twist except at R_a = I twisted to π − 1e-6,
// where two columns of each block are ~5e-7 of the block — a bend barely changes vee(Q) at a
// half twist — and read 2e-7); the mistakes this check is for — a wrong sign, factor, or
// perturbation side (the right-perturbation control below) — give relative errors of order 1.

constexpr double kCheckerPrecision = 1e-6;

enum class Perturbation { kLeft, kRight };  // kRight: J_Lie R, the body-frame slip

template <int Residuals, int Blocks>
struct QuaternionBlocks;
template <int Residuals>
struct QuaternionBlocks<Residuals, 1> {
  using type = ceres::SizedCostFunction<Residuals, 4>;
};
template <int Residuals>
struct QuaternionBlocks<Residuals, 2> {
  using type = ceres::SizedCostFunction<Residuals, 4, 4>;
};

// Term's rotation indices must be 0 … kBlocks − 1, one per block; it has no point blocks.
template <class Term>
class LieTermCost final : public QuaternionBlocks<Term::kResiduals, Term::kBlocks>::type {
 public:
  static constexpr int kResiduals = Term::kResiduals;
  static constexpr int kBlocks = Term::kBlocks;
  using Mix = Eigen::Matrix<double, kResiduals, kResiduals>;

  LieTermCost(const Term& term, const Mix& mix, Perturbation perturbation = Perturbation::kLeft)
      : term_(term), mix_(mix), perturbation_(perturbation) {}

  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    State q;
    for (int k = 0; k < kBlocks; ++k) q.rotations.push_back(SO3Manifold::rotation(p[k]));
    typename Term::Residual r;
    typename Term::ResidualJacobian J;
    term_.residual(q, r, jacobians != nullptr ? &J : nullptr);
    Eigen::Map<Eigen::Matrix<double, kResiduals, 1>>{residuals} = mix_ * r;
    if (jacobians == nullptr) return true;
    for (int k = 0; k < kBlocks; ++k) {
      if (jacobians[k] == nullptr) continue;
      Eigen::Matrix<double, kResiduals, 3> J_lie = mix_ * J.template middleCols<3>(3 * k);
      if (perturbation_ == Perturbation::kRight) J_lie = J_lie * q.rotations[k];
      Eigen::Map<Eigen::Matrix<double, kResiduals, 4, Eigen::RowMajor>>{jacobians[k]} =
          J_lie * SO3Manifold::lie_to_ambient(p[k]);
    }
    return true;
  }

 private:
  Term term_;
  Mix mix_;
  Perturbation perturbation_;
};

template <int N>
Eigen::Matrix<double, N, N> random_orthogonal(std::mt19937& rng) {
  Eigen::Matrix<double, N, N> A;
  fill_random(A, rng);
  return Eigen::HouseholderQR<Eigen::Matrix<double, N, N>>(A).householderQ();
}

// Probes `cost` at the rotations R (each block stored with sign `sign`); returns whether it
// passed, with Ceres's log on failure.
template <class Cost>
::testing::AssertionResult probe(const Cost& cost, const std::vector<Matrix3>& R, double sign,
                                 const ceres::NumericDiffOptions& options = {}) {
  const SO3Manifold m;
  const std::vector<const ceres::Manifold*> manifolds(R.size(), &m);
  std::vector<Vector4> x;
  for (const Matrix3& r : R) x.push_back(sign * SO3Manifold::quaternion(r));
  std::vector<const double*> blocks;
  for (const Vector4& v : x) blocks.push_back(v.data());
  ceres::GradientChecker checker(&cost, &manifolds, options);
  ceres::GradientChecker::ProbeResults results;
  const bool passed = checker.Probe(blocks.data(), kCheckerPrecision, &results);
  // For the record: the error relative to each block's largest entry.
  double block_error = 0.0;
  for (std::size_t k = 0; k < results.local_jacobians.size(); ++k) {
    const ceres::Matrix& a = results.local_jacobians[k];
    const ceres::Matrix& n = results.local_numeric_jacobians[k];
    block_error = std::max(block_error, (a - n).cwiseAbs().maxCoeff() /
                                            std::max(a.cwiseAbs().maxCoeff(), n.cwiseAbs().maxCoeff()));
  }
  auto out = passed ? ::testing::AssertionSuccess() : ::testing::AssertionFailure();
  out << "max relative error (entry by entry) " << results.maximum_relative_error
      << ", relative to the block " << block_error;
  if (!passed) out << "\n" << results.error_log;
  return out;
}

TEST(SO3ManifoldCeres, GradientCheckerPassesOnRotationalInertia) {
  std::mt19937 rng(163);
  for (const double h : {1e-3, 0.01, 0.1}) {
    for (const double angle : fd::kAngles) {
      SCOPED_TRACE(fd::trace("h, angle", h, angle));
      RotationalInertia term;
      term.rotation = 0;
      term.J_over_h2 = rotational_mass(Vector3(0.02, 0.03, 0.04).asDiagonal()) / (h * h);
      term.sqrt_J_over_h = psd_sqrt(term.J_over_h2);
      // R̃ = (2I − ΔRᵀ) R_{k−1} of a previous step at ω = (1, −2, 0.5): not a rotation.
      const Matrix3 R_previous = fd::rotation_at(1.3, rng);
      term.R_tilde = (2.0 * Matrix3::Identity() - so3::exp(h * Vector3(1.0, -2.0, 0.5)).transpose()) *
                     R_previous;
      const Matrix3 R = fd::rotation_at(angle, rng);
      const LieTermCost<RotationalInertia> cost(term, random_orthogonal<9>(rng));
      for (const double sign : {1.0, -1.0}) EXPECT_TRUE(probe(cost, {R}, sign)) << sign;
      // The control: a right-perturbation Jacobian J_Lie R fails, except where R ≈ I (there
      // the two perturbations coincide).
      if (so3::log(R).norm() > 0.5) {
        const LieTermCost<RotationalInertia> wrong(term, random_orthogonal<9>(rng), Perturbation::kRight);
        EXPECT_FALSE(probe(wrong, {R}, 1.0));
      }
    }
  }
}

// Two SO3Manifold blocks: rod bend–twist ½ l ΔωᵀKΔω, ω = vee(R_aᵀR_b)/l, r = √l K^½ Δω,
// J = [−W, W] (lib/rod_terms.hpp). Relative rotations Q = R_aᵀR_b straight (0), nearly
// straight (1e-4), ordinary, and twisted or bent to π − 1e-6 (where G = ½(tr Q I − Q) is
// nearly rank one); straight and curved rest shapes.
TEST(SO3ManifoldCeres, GradientCheckerPassesOnRodBendTwist) {
  ceres::NumericDiffOptions options;
  options.ridders_relative_initial_step_size = 1e-4;  // see above
  std::mt19937 rng(167);
  int checked = 0;
  for (const double l : {0.01, 0.05, 1.0}) {
    for (const double angle_a : {0.0, 1.0, 2.5, kPi - 1e-6}) {
      for (const double relative : {0.0, 1e-4, 1.0, kPi - 1e-6}) {
        for (const bool twist : {true, false}) {
          for (const bool curved_rest : {true, false}) {
            SCOPED_TRACE(fd::trace("l, angle of R_a, relative angle", l, angle_a, relative) +
                         (twist ? " twist" : " random axis") + (curved_rest ? " curved" : " straight"));
            RodBendTwist term;
            term.edge0 = 0;
            term.edge1 = 1;
            term.rest_length = l;
            term.stiffness = Vector3(1.0, 1.7, 0.6);  // bend, bend, twist: all distinct
            term.rest_darboux = curved_rest
                                    ? darboux_vector(Matrix3::Identity(), fd::rotation_at(0.4, rng), l)
                                    : Vector3::Zero();
            const Vector3 n = twist ? Vector3::UnitZ() : fd::random_unit(rng);
            const Matrix3 Ra = fd::rotation_at(angle_a, rng);
            const Matrix3 Rb = Ra * so3::exp(relative * n);
            const LieTermCost<RodBendTwist> cost(term, random_orthogonal<3>(rng));
            // Straight rest at Q = I: r = 0, still a full-rank Jacobian to compare.
            for (const double sign : {1.0, -1.0}) {
              EXPECT_TRUE(probe(cost, {Ra, Rb}, sign, options)) << sign;
            }
            if (angle_a == 1.0) {  // R_a 1 rad from I: the control must fail
              const LieTermCost<RodBendTwist> wrong(term, random_orthogonal<3>(rng), Perturbation::kRight);
              EXPECT_FALSE(probe(wrong, {Ra, Rb}, 1.0, options));
            }
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 4 * 4 * 2 * 2);
}

// ---------------------------------------------------------------------------------------
// 4. The Ceres step back-end with solver.ceres.lie_blocks = "manifold".

SolverOptions ceres_options(SolverOptions options, const char* lie_blocks) {
  options.backend = Backend::kCeres;
  options.rotation = RotationParameterization::kLie;
  options.ceres.lie_blocks = lie_blocks;
  return options;
}

// The option reaches Ceres: at its first evaluation Ceres reports ‖x − Plus(x, −g)‖₂ with g
// the tangent gradient (the Lie gradient, under either blocks). For a chart block that is
// ‖g_θ‖; for an SO3Manifold block ‖q − exp(−g_θ) ⊗ q‖ = 2 sin(‖g_θ‖/4). A free tumbling body
// (no gravity, no linear velocity) at its first step, where ‖g_θ‖ = ‖I ω‖/h ≈ 10 and the two
// differ tenfold; both to the round-off of g (1e-10 relative is generous).
TEST(SO3ManifoldCeres, TheStepBackEndHandsCeresTheManifold) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3::Zero();
  RigidBody b;
  b.inertia = Vector3(0.02, 0.03, 0.04).asDiagonal();
  b.orientation = so3::exp(Vector3(0.3, -1.2, 0.7));
  b.angular_velocity = Vector3(3.0, -2.0, 1.5);
  model.bodies.push_back(b);
  for (const char* lie_blocks : {"chart", "manifold"}) {
    SCOPED_TRACE(lie_blocks);
    std::vector<Component> components = build_components(model);
    ASSERT_EQ(components.size(), 1u);
    const std::unique_ptr<StepSolver> solver =
        make_step_solver(std::move(components[0]), ceres_options(SolverOptions{}, lie_blocks));
    State q = model.initial_state();
    Component& c = solver->component();
    c.potential.begin_step(q, model.initial_step());
    Eigen::VectorXd g = Eigen::VectorXd::Zero(c.dofs);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(c.dofs, c.dofs);
    c.potential.assemble(q, g, H);
    const double g_x = g.segment<3>(c.points[0].offset).norm();
    const double g_theta = g.segment<3>(c.rotations[0].offset).norm();
    ASSERT_GT(g_theta, 5.0);
    const double chart = std::hypot(g_x, g_theta);
    const double manifold = std::hypot(g_x, 2.0 * std::sin(g_theta / 4.0));
    const double expected = std::string(lie_blocks) == "manifold" ? manifold : chart;
    const StepReport r = solver->solve(q);
    EXPECT_TRUE(r.converged()) << to_string(r.status) << " " << r.message;
    EXPECT_NEAR(r.first_gradient_norm, expected, 1e-10 * expected)
        << "chart would give " << chart << ", manifold " << manifold;
  }
}

using test::deviation;
using test::Trajectory;

Trajectory run(const Scene& scene, const char* lie_blocks, int frames) {
  return test::run_frames(scene.model, ceres_options(scene.solver, lie_blocks), frames, lie_blocks);
}

// The scene's first `frames` frames with both kinds of blocks, at tolerance 1e-9: within 1e-6
// m and rad of each other, frame by frame.
void expect_manifold_agrees_with_chart(const char* file, int frames) {
  Scene scene = load_scene(kScenes / file);
  scene.solver.tolerance = 1e-9;
  const Trajectory chart = run(scene, "chart", frames);
  const Trajectory manifold = run(scene, "manifold", frames);
  ASSERT_EQ(static_cast<int>(manifold.states.size()), frames);
  const auto [dx, dR] = deviation(chart, manifold);
  EXPECT_LE(dx, 1e-6);
  EXPECT_LE(dR, 1e-6);
  EXPECT_GT(manifold.iterations, 0);
}

// Both blocks end every step only when the shared convergence test holds (‖δ‖∞ ≤ tolerance,
// step_solver.hpp), so each step lands within ~tolerance of the same minimiser and the two
// trajectories differ by ≲ 2·tolerance per step, carried forward by the step map.
//
// The butterfly bolt (spin about the intermediate axis, I = 1, 2, 2.8, ω = 2): its
// instability grows deviations by e^{λt}, λ = ω √((I₂−I₁)(I₃−I₂)/(I₁I₃)) ≈ 1.07/s, a factor
// ≈ 3 over 100 frames (1 s): at tolerance 1e-9, ≤ 100 · 2e-9 · 3 = 6e-7 < 1e-6.
TEST(SO3ManifoldCeres, ManifoldAndChartAgreeOnATumblingBody) {
  expect_manifold_agrees_with_chart("butterfly_bolt.json", 100);
}

// The dynamic cantilever (20 edges, clamped at one end, tip load; 117 DOFs: sparse): 20 frames,
// ≤ 20 · 2e-9 = 4e-8 for a stable, damped (backward Euler) rod; 1e-6 leaves a factor 25.
TEST(SO3ManifoldCeres, ManifoldAndChartAgreeOnACantilever) {
  expect_manifold_agrees_with_chart("cantilever.json", 20);
}

}  // namespace
}  // namespace liedyn::so3_manifold_tests

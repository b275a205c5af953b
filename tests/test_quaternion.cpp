// Unit quaternions (manifolds/quaternion.hpp; docs/design.md §10.3, eqs. A.13–A.25, order
// (x, y, z, s)):
// the algebra against Eigen, the rotation matrix and its derivatives, the round trip through
// rotation matrices at the hard angles, the rate matrix as a world-frame velocity, and the
// header's central claim — the gradient and Hessian of δ ↦ Ψ(R(retract(q, δ))) at δ = 0 are
// the Lie gradient and Lie Hessian of Ψ (conventions: lib/so3.hpp).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
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
#include "manifolds/quaternion.hpp"

namespace liedyn::quaternion_tests {
namespace {

using quat::Matrix3;
using quat::Matrix4;
using quat::Vector3;
using quat::Vector4;
using fd::kPi;
using fd::kEps;

// Rotation angles of the test points: identity, tiny, ordinary, near π and π (where s → 0).
const std::vector<double> kAngles = {0.0, 1e-9, 1e-4, 1.0, kPi - 1e-6, kPi};

// The quaternion of a rotation by `angle` about the unit `axis` (eq. A.18).
Vector4 from_angle_axis(double angle, const Vector3& axis) {
  Vector4 q;
  q << std::sin(0.5 * angle) * axis, std::cos(0.5 * angle);
  return q;
}

Vector4 random_quaternion(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Vector4(normal(rng), normal(rng), normal(rng), normal(rng));
}

Vector4 random_unit_quaternion(std::mt19937& rng) { return random_quaternion(rng).normalized(); }

// The pure quaternion (v, 0).
Vector4 pure(const Vector3& v) { return Vector4(v.x(), v.y(), v.z(), 0.0); }

// Eigen's constructor takes (w, x, y, z); its coeffs() are stored (x, y, z, w), our order.
Eigen::Quaterniond to_eigen(const Vector4& q) { return {q(3), q(0), q(1), q(2)}; }

// The sign of q with s ≥ 0 (from_rotation's choice), and the distance between two
// quaternions up to sign, for rotations by π where s = 0 leaves the sign open.
Vector4 canonical(const Vector4& q) { return q(3) < 0.0 ? Vector4(-q) : q; }
double distance_up_to_sign(const Vector4& a, const Vector4& b) {
  return std::min((a - b).cwiseAbs().maxCoeff(), (a + b).cwiseAbs().maxCoeff());
}

std::string where(const Vector4& q) {
  std::ostringstream s;
  s.precision(17);
  s << "q = (" << q.transpose() << ")";
  return s.str();
}

// Test quaternions: every angle of kAngles about a random axis, both signs.
std::vector<Vector4> test_quaternions() {
  std::mt19937 rng(5);
  std::vector<Vector4> qs;
  for (const double angle : kAngles) {
    const Vector4 q = from_angle_axis(angle, fd::random_unit(rng));
    qs.push_back(q);
    qs.push_back(-q);
  }
  return qs;
}

// ---------------------------------------------------------------------------------------
// Algebra (eqs. A.13–A.16, A.19, A.21).

// Entries of products of O(1) quaternions are sums of four products: a few ulps each, so
// identities between two such evaluations hold to 16 eps ≈ 3.6e-15 of the factors' size.
constexpr double kProductTol = 16.0 * kEps;

TEST(QuaternionProduct, IsAssociative) {
  std::mt19937 rng(1);
  for (int i = 0; i < 100; ++i) {
    const Vector4 a = random_quaternion(rng), b = random_quaternion(rng),
                  c = random_quaternion(rng);
    const Vector4 ab_c = quat::product(quat::product(a, b), c);
    const Vector4 a_bc = quat::product(a, quat::product(b, c));
    // Two nested products: twice the error of one, relative to ‖a‖‖b‖‖c‖.
    EXPECT_LE((ab_c - a_bc).cwiseAbs().maxCoeff(),
              2.0 * kProductTol * a.norm() * b.norm() * c.norm());
  }
}

TEST(QuaternionProduct, MatchesEigen) {
  std::mt19937 rng(2);
  for (int i = 0; i < 100; ++i) {
    const Vector4 a = random_quaternion(rng), b = random_quaternion(rng);
    const Vector4 expected = (to_eigen(a) * to_eigen(b)).coeffs();
    EXPECT_LE((quat::product(a, b) - expected).cwiseAbs().maxCoeff(),
              kProductTol * a.norm() * b.norm());
  }
  // Not commutative: the cross product flips (eq. A.14), so the comparison above can tell
  // a b from b a.
  const Vector4 i(1.0, 0.0, 0.0, 0.0), j(0.0, 1.0, 0.0, 0.0), k(0.0, 0.0, 1.0, 0.0);
  EXPECT_EQ(quat::product(i, j), k);
  EXPECT_EQ(quat::product(j, i), Vector4(-k));
}

TEST(QuaternionProduct, LeftAndRightMatricesGiveTheProduct) {
  std::mt19937 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Vector4 a = random_quaternion(rng), b = random_quaternion(rng);
    const Vector4 ab = quat::product(a, b);
    const double tol = kProductTol * a.norm() * b.norm();
    EXPECT_LE((quat::left_matrix(a) * b - ab).cwiseAbs().maxCoeff(), tol);   // eq. A.15
    EXPECT_LE((quat::right_matrix(b) * a - ab).cwiseAbs().maxCoeff(), tol);  // eq. A.16
  }
}

TEST(QuaternionProduct, InverseUndoesTheProduct) {
  std::mt19937 rng(4);
  for (int i = 0; i < 100; ++i) {
    const Vector4 q = random_unit_quaternion(rng);
    const Vector4 one(0.0, 0.0, 0.0, 1.0);
    EXPECT_LE((quat::product(q, quat::inverse(q)) - one).cwiseAbs().maxCoeff(), kProductTol);
    EXPECT_LE((quat::product(quat::inverse(q), q) - one).cwiseAbs().maxCoeff(), kProductTol);
  }
}

TEST(QuaternionRotation, RotatesLikeTheSandwichProductAndMatchesEigen) {
  std::mt19937 rng(5);
  for (int i = 0; i < 100; ++i) {
    const Vector4 q = random_unit_quaternion(rng);
    const Vector3 v = fd::random_vector(rng, 1.0);
    const Matrix3 R = quat::rotation(q);
    // v_rot = q v q⁻¹ (eq. A.19) = R v (eq. A.20): two products against one matrix-vector.
    const Vector4 sandwich = quat::product(quat::product(q, pure(v)), quat::inverse(q));
    EXPECT_LE((R * v - sandwich.head<3>()).norm(), 2.0 * kProductTol * v.norm());
    EXPECT_LE(std::abs(sandwich(3)), 2.0 * kProductTol * v.norm());
    // Same (Hamilton) convention as Eigen.
    EXPECT_LE((R - to_eigen(q).toRotationMatrix()).cwiseAbs().maxCoeff(), kProductTol);
  }
}

TEST(QuaternionRotation, OfProductIsProductOfRotations) {
  std::mt19937 rng(6);
  for (int i = 0; i < 100; ++i) {
    const Vector4 a = random_unit_quaternion(rng), b = random_unit_quaternion(rng);
    // R(a) R(b) sums three products of entries ≤ 1 that each carry a few ulps.
    EXPECT_LE((quat::rotation(quat::product(a, b)) - quat::rotation(a) * quat::rotation(b))
                  .cwiseAbs()
                  .maxCoeff(),
              2.0 * kProductTol);
  }
}

TEST(QuaternionRotation, IsOrthonormalWithUnitDeterminantAndEvenInQ) {
  std::mt19937 rng(7);
  std::vector<Vector4> qs = test_quaternions();
  for (int i = 0; i < 100; ++i) qs.push_back(random_unit_quaternion(rng));
  for (const Vector4& q : qs) {
    SCOPED_TRACE(where(q));
    const Matrix3 R = quat::rotation(q);
    // RᵀR − I and det R − 1 are the round-off of q's unit norm and of A.21: a few ulps.
    EXPECT_LE((R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff(), kProductTol);
    EXPECT_NEAR(R.determinant(), 1.0, kProductTol);
    // A.21 is a quadratic form: (−a)(−b) = ab exactly, so R(−q) = R(q) bit for bit.
    EXPECT_EQ(quat::rotation(-q), R);
    // R(q⁻¹) = Rᵀ: A.21 with u → −u swaps the signed terms of each off-diagonal pair. Bitwise
    // equal as written; the tolerance allows for compilers that contract a b + c d into FMAs.
    EXPECT_LE((quat::rotation(quat::inverse(q)) - R.transpose()).cwiseAbs().maxCoeff(), 4.0 * kEps);
  }
}

// ---------------------------------------------------------------------------------------
// from_rotation (Shepperd's method).

TEST(QuaternionFromRotation, InvertsRotationWithNonNegativeScalar) {
  std::mt19937 rng(8);
  const double r = 1.0 / std::sqrt(2.0);
  std::vector<Vector4> qs = {
      Vector4(0.0, 0.0, 0.0, 1.0),               // identity
      from_angle_axis(kPi, Vector3::UnitX()),    // π about each axis: s = 0 and
      from_angle_axis(kPi, Vector3::UnitY()),    // the rotation has no sign;
      from_angle_axis(kPi, Vector3::UnitZ()),    // two components vanish
      from_angle_axis(kPi, Vector3(r, r, 0.0)),  // π, two equal components
      from_angle_axis(1e-9, Vector3(1.0, 2.0, 3.0).normalized()),
      from_angle_axis(kPi - 1e-6, Vector3(1.0, 2.0, 3.0).normalized()),
      from_angle_axis(kPi - 1e-6, Vector3::UnitZ())};
  for (const Vector4& q : test_quaternions()) qs.push_back(q);
  for (int i = 0; i < 200; ++i) qs.push_back(random_unit_quaternion(rng));
  for (const Vector4& q : qs) {
    SCOPED_TRACE(where(q));
    const Vector4 p = quat::from_rotation(quat::rotation(q));
    EXPECT_GE(p(3), 0.0);
    EXPECT_NEAR(p.norm(), 1.0, 2.0 * kEps);
    // The chosen branch takes the root of a sum ≥ 1 of entries with a few ulps each and
    // divides by 4|q_k| ≥ 2: every component is accurate to a few ulps, at any angle.
    const double error = std::abs(q(3)) > 1e-12 ? (p - canonical(q)).cwiseAbs().maxCoeff()
                                                : distance_up_to_sign(p, q);
    EXPECT_LE(error, 8.0 * kEps);
  }
}

TEST(QuaternionFromRotation, RotationOfItReproducesTheMatrix) {
  std::mt19937 rng(9);
  std::vector<Matrix3> Rs;
  for (const double angle : {0.0, 1e-12, 1e-9, 1e-4, 0.5, 1.0, 2.0, 3.0, kPi - 1e-6, kPi}) {
    for (int i = 0; i < 10; ++i) Rs.push_back(so3::exp(angle * fd::random_unit(rng)));
  }
  for (const Vector3& axis : {Vector3(Vector3::UnitX()), Vector3(Vector3::UnitY()),
                              Vector3(Vector3::UnitZ()), Vector3(1.0, 1.0, 0.0).normalized()}) {
    Rs.push_back(so3::exp(kPi * axis));
  }
  for (const Matrix3& R : Rs) {
    // R from so3::exp is orthonormal to a few ulps; A.21 adds a few more.
    EXPECT_LE((quat::rotation(quat::from_rotation(R)) - R).cwiseAbs().maxCoeff(), 1e-14) << R;
  }
}

// ---------------------------------------------------------------------------------------
// Derivatives (eqs. A.23, A.25).

TEST(QuaternionRotationDerivatives, MatchCentralDifferences) {
  std::mt19937 rng(10);
  const Vector4 q = random_unit_quaternion(rng);
  const Vector4 nudge = 1e-3 * random_quaternion(rng);
  // A.21 is defined (as a quadratic) on all of R⁴, so differences may leave the unit sphere.
  // Points: ±q and ±q nudged (same rotation up to sign), a non-unit q, identity, π about x.
  const std::vector<Vector4> points = {q,
                                       -q,
                                       q + nudge,
                                       -q + nudge,
                                       2.5 * random_quaternion(rng),
                                       Vector4(0.0, 0.0, 0.0, 1.0),
                                       Vector4(1.0, 0.0, 0.0, 0.0)};
  // Central differences of a quadratic are exact (no third derivative), so a large step is
  // free of truncation; what remains is the round-off of A.21, ~8 eps ‖q‖² / 2h ≈ 1e-13.
  const double h = 1e-2;
  for (const Vector4& p : points) {
    SCOPED_TRACE(where(p));
    Matrix3 dR[4];
    quat::rotation_derivatives(p, dR);
    for (int i = 0; i < 4; ++i) {
      const Vector4 e = Vector4::Unit(i);
      const Matrix3 fd = (quat::rotation(p + h * e) - quat::rotation(p - h * e)) / (2.0 * h);
      ASSERT_GT(dR[i].cwiseAbs().maxCoeff(), 1.0);  // 2|q_k| ≥ 1 for one k: not vacuous
      EXPECT_LE((dR[i] - fd).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, p.squaredNorm()))
          << "∂R/∂q_" << i;
    }
  }
}

TEST(QuaternionRateMatrix, IsHalfTheLeftProductWithOmega) {
  std::mt19937 rng(11);
  for (int i = 0; i < 100; ++i) {
    const Vector4 q = random_unit_quaternion(rng);
    const Vector3 w = fd::random_vector(rng, 2.0);
    // q̇ = ½ (ω, 0) q (eq. A.24).
    const Vector4 expected = 0.5 * quat::product(pure(w), q);
    EXPECT_LE((quat::rate_matrix(q) * w - expected).cwiseAbs().maxCoeff(), kProductTol * w.norm());
    // Q is half the first three columns of B(q) (eq. A.16): the same numbers, exactly.
    const Eigen::Matrix<double, 4, 3> half_B = 0.5 * quat::right_matrix(q).leftCols<3>();
    EXPECT_EQ(quat::rate_matrix(q), half_B);
  }
}

TEST(QuaternionRateMatrix, IsTheDerivativeOfAWorldFrameRotation) {
  // q(t) = quaternion of exp(tω) R(q) (left, world-frame perturbation), sign-matched to q so
  // that the curve is smooth through the s = 0 of the π rotations. Central differences with
  // h = 1e-5: truncation h²/6 |q'''| ≤ 2e-11 |ω|³, round-off of from_rotation ~4 eps / 2h ≈
  // 4e-11. Tolerance 1e-9.
  std::mt19937 rng(12);
  const double h = 1e-5;
  for (const Vector4& q : test_quaternions()) {
    SCOPED_TRACE(where(q));
    const Vector3 w = fd::random_vector(rng, 1.0);
    const Matrix3 R = quat::rotation(q);
    const auto at = [&](double t) {
      const Vector4 p = quat::from_rotation(so3::exp(t * w) * R);
      return p.dot(q) < 0.0 ? Vector4(-p) : p;
    };
    const Vector4 fd = (at(h) - at(-h)) / (2.0 * h);
    const Vector4 qdot = quat::rate_matrix(q) * w;
    EXPECT_LE((qdot - fd).cwiseAbs().maxCoeff(), 1e-9);
    // A body-frame ω would give ½ q (ω, 0) instead; it differs by (u × ω, 0), so away from
    // the identity the comparison above tells the two frames apart.
    const Vector4 body = 0.5 * quat::product(q, pure(w));
    if (q.head<3>().norm() > 0.5) {
      EXPECT_GT((body - fd).norm(), 1e-3);
    }
  }
}

// ---------------------------------------------------------------------------------------
// retract: the update, and the claim that it gives the Lie gradient and Hessian.

TEST(QuaternionRetract, TurnsByTwiceTheArctangentAboutTheWorldAxis) {
  std::mt19937 rng(13);
  for (const Vector4& q : test_quaternions()) {
    const Matrix3 R = quat::rotation(q);
    for (const double size : {1e-8, 1e-6, 1e-4, 1e-2, 0.1, 1.0, 2.0, 3.0}) {
      const Vector3 delta = size * fd::random_unit(rng);
      SCOPED_TRACE(where(q) + ", |δ| = " + std::to_string(size));
      const Vector3 theta = so3::log(quat::rotation(quat::retract(q, delta)) * R.transpose());
      const Vector3 expected = 2.0 * std::atan(0.5 * size) / size * delta;
      // Both rotations carry a few ulps absolute in their entries; log of the near-identity
      // or moderate (≤ 2 atan 1.5 ≈ 1.97 rad) product passes that on with a factor ≤ π/2.
      EXPECT_LE((theta - expected).norm(), 1e-14);
    }
  }
}

// Ψ(R) = tr(A R) + ½‖R p − y‖² (tests/rotation_test_functions.hpp): non-trivial Lie
// gradient and Hessian everywhere.
using test_functions::TestFunction;

TestFunction make_test_function() {
  std::mt19937 rng(14);
  // Evaluated in this order (A first), as before the function moved to the shared header.
  const Matrix3 A = Matrix3::Random();
  const Vector3 p = fd::random_vector(rng, 1.0);
  const Vector3 y = fd::random_vector(rng, 1.0);
  return test_functions::trace_and_point(A, p, y);
}

TEST(QuaternionRetract, TestFunctionLieDerivativesMatchFiniteDifferences) {
  // First the hand-derived g and H, through Ψ(exp(θ)R) (tests/fd_check.hpp, its defaults).
  const TestFunction psi = make_test_function();
  const fd::Dofs dofs = {fd::rotation_dof(0)};
  const fd::ScalarFunction f = [&](const State& s) { return psi.value(s.rotations[0]); };
  const fd::GradientFunction grad = [&](const State& s) {
    return Eigen::VectorXd(psi.gradient(s.rotations[0]));
  };
  for (const Vector4& q : test_quaternions()) {
    SCOPED_TRACE(where(q));
    const State state{{}, {quat::rotation(q)}};
    const Matrix3& R = state.rotations[0];
    EXPECT_TRUE(fd::check_lie_gradient(f, state, dofs, Eigen::VectorXd(psi.gradient(R))));
    EXPECT_TRUE(fd::check_lie_hessian(grad, state, dofs, Eigen::MatrixXd(psi.hessian(R))));
    EXPECT_TRUE(fd::check_lie_hessian_from_value(f, state, dofs, Eigen::MatrixXd(psi.hessian(R))));
  }
}

TEST(QuaternionRetract, GradientAndHessianThroughRetractAreTheLieOnes) {
  // φ(δ) = Ψ(R(retract(q, δ))) = Ψ(exp(θ(δ)) R(q)) with θ(δ) = δ − ‖δ‖²δ/12 + …: its first
  // two derivatives at 0 are those of Ψ(exp(δ) R(q)), i.e. g and H, exactly.
  //   gradient: step 1e-5; truncation h²/6 |φ'''| ≈ 2e-11, round-off eps |Ψ| / h ≈ 2e-11 (×
  //             a few ulps of A.21 and retract): tolerance 1e-8 of the scale max(|Ψ|, |g|).
  //   Hessian:  second differences, step 1e-4; round-off eps |Ψ| / h² ≈ 2e-8 (× a few),
  //             truncation h²/12 |φ''''| ≈ 1e-9: tolerance 1e-6 of the scale.
  const TestFunction psi = make_test_function();
  for (const Vector4& q : test_quaternions()) {
    SCOPED_TRACE(where(q));
    const auto phi = [&](const Vector3& delta) {
      return psi.value(quat::rotation(quat::retract(q, delta)));
    };
    const Matrix3 R = quat::rotation(q);
    const Vector3 g = psi.gradient(R);
    const Matrix3 H = psi.hessian(R);
    const double scale =
        std::max({std::abs(psi.value(R)), g.cwiseAbs().maxCoeff(), H.cwiseAbs().maxCoeff()});
    ASSERT_GT(g.norm(), 1e-2 * scale);  // a vanishing gradient would prove nothing
    ASSERT_GT(H.norm(), 1e-2 * scale);

    const double hg = 1e-5;
    Vector3 fd_g;
    for (int i = 0; i < 3; ++i) {
      const Vector3 e = hg * Vector3::Unit(i);
      fd_g(i) = (phi(e) - phi(-e)) / (2.0 * hg);
    }
    EXPECT_LE((fd_g - g).cwiseAbs().maxCoeff(), 1e-8 * scale) << fd_g.transpose();

    const double hh = 1e-4;
    Matrix3 fd_H;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const Vector3 ei = hh * Vector3::Unit(i), ej = hh * Vector3::Unit(j);
        fd_H(i, j) = (phi(ei + ej) - phi(ei - ej) - phi(-ei + ej) + phi(-ei - ej)) / (4 * hh * hh);
      }
    }
    EXPECT_LE((fd_H - H).cwiseAbs().maxCoeff(), 1e-6 * scale) << fd_H;
  }
}

TEST(QuaternionRetract, ZeroStepIsIdentityAndNormNeverDrifts) {
  std::mt19937 rng(15);
  std::uniform_real_distribution<double> exponent(-8.0, 0.5);
  Vector4 q = random_unit_quaternion(rng);
  // Dividing by a norm that rounds to 1 within an ulp moves each entry by at most ~1 ulp.
  EXPECT_LE((quat::retract(q, Vector3::Zero()) - q).cwiseAbs().maxCoeff(), 2.0 * kEps);
  // Each step renormalises, so the norm error is that of one normalisation (a few ulps),
  // never a sum over steps.
  double worst = 0.0;
  for (int i = 0; i < 10000; ++i) {
    q = quat::retract(q, std::pow(10.0, exponent(rng)) * fd::random_unit(rng));
    worst = std::max(worst, std::abs(q.norm() - 1.0));
  }
  EXPECT_LE(worst, 1e-15);
  EXPECT_LE((quat::retract(q, Vector3::Zero()) - q).cwiseAbs().maxCoeff(), 2.0 * kEps);
}

}  // namespace
}  // namespace liedyn::quaternion_tests

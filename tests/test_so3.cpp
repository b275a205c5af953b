// SO(3) core (lib/so3.hpp): hat/vee, exp, log, left Jacobian and its inverse, quaternions,
// orthonormalisation, distance. Jacobians are checked by finite differences in the tangent
// space (tests/fd_check.hpp) over the whole range of angles, including the branch points of
// the implementation (Taylor switches at 1e-4 and 0.1, the symmetric-part log past π/2), the
// cut of log at π and the singularity of J_l⁻¹ at 2π.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <vector>

#include "fd_check.hpp"
#include "lib/so3.hpp"

namespace liedyn::so3_tests {
namespace {

using so3::Matrix3;
using so3::Vector3;
using fd::kPi;
using fd::kEps;
using fd::where;

// Angles up to π: log's domain.
// 9.9e-5/1.01e-4 and 0.099/0.101 straddle the Taylor-branch switches of so3.cpp, where a
// wrong series coefficient would show up in J_l J_l⁻¹ = I (series terms are ~t⁴ there).
const std::vector<double> kAngles = {0.0,   1e-12, 1e-9,  1e-6, 9.9e-5,    1e-4,       1.01e-4,
                                     0.099, 0.1,   0.101, 1.0,  kPi / 2.0, kPi - 1e-6, kPi};
// Past π, towards the singularity of J_l at 2π (exp only).
const std::vector<double> kLongAngles = {4.0, 2.0 * kPi - 1e-3, 2.0 * kPi - 1e-6};

std::vector<Vector3> test_axes() {
  std::vector<Vector3> axes = {Vector3::UnitX(), Vector3::UnitY(), Vector3::UnitZ(),
                               Vector3(1.0, 1.0, 1.0).normalized()};
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 3; ++i)
    axes.push_back(Vector3(normal(rng), normal(rng), normal(rng)).normalized());
  return axes;
}

Matrix3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized().toRotationMatrix();
}

// Rotation vector with the same exp as `theta` (a log result) closest to `reference`:
// moves across the cut at π (and back from the short vector near 2π) so that finite
// differences of log see a smooth map.
Vector3 unwrap(const Vector3& theta, const Vector3& reference) {
  const double t = theta.norm();
  if (t == 0.0) return theta;
  Vector3 best = theta;
  for (const double m : {-1.0, 1.0}) {
    const Vector3 candidate = theta + m * 2.0 * kPi * theta / t;
    if ((candidate - reference).norm() < (best - reference).norm()) best = candidate;
  }
  return best;
}

TEST(So3, HatIsCrossProductAndVeeInvertsIt) {
  std::mt19937 rng(1);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 20; ++i) {
    const Vector3 u(normal(rng), normal(rng), normal(rng));
    const Vector3 v(normal(rng), normal(rng), normal(rng));
    // Each entry of u × v is a difference of two products: exact up to one rounding each.
    EXPECT_LE((so3::hat(u) * v - u.cross(v)).norm(), 4.0 * kEps * u.norm() * v.norm());
    EXPECT_TRUE((so3::hat(u) + so3::hat(u).transpose()).isZero(0.0));
    EXPECT_EQ(so3::vee(so3::hat(u)), u);  // ½(u − (−u)) is exact in binary
    // vee of a general matrix takes its antisymmetric part.
    const Matrix3 M = Matrix3::Random();
    EXPECT_LE((so3::vee(M) - so3::vee(0.5 * (M - M.transpose()))).norm(), 4.0 * kEps);
  }
}

TEST(So3, ExpMatchesAngleAxisAndIsARotation) {
  std::vector<double> angles = kAngles;
  angles.insert(angles.end(), kLongAngles.begin(), kLongAngles.end());
  for (const Vector3& axis : test_axes()) {
    for (const double t : angles) {
      SCOPED_TRACE(where(t, axis));
      const Matrix3 R = so3::exp(t * axis);
      const Matrix3 expected = Eigen::AngleAxisd(t, axis).toRotationMatrix();
      // Entries are O(1) sums of a few products of O(1) terms: a few ulps.
      EXPECT_LE((R - expected).cwiseAbs().maxCoeff(), 8e-15);
      EXPECT_LE((R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff(), 8 * kEps);
      EXPECT_NEAR(R.determinant(), 1.0, 8 * kEps);
    }
  }
}

TEST(So3, ExpTaylorBranchKeepsFullRelativePrecisionForTinyAngles) {
  // exp(θ) − I = hat(θ) + O(θ²): the off-diagonal part must be θ to full relative precision.
  for (const double t : {1e-300, 1e-150, 1e-12, 1e-9, 1e-6, 9.999e-5, 1.0001e-4}) {
    const Vector3 theta = t * Vector3(1.0, -2.0, 3.0).normalized();
    const Matrix3 R = so3::exp(theta);
    EXPECT_LE((so3::vee(R) - std::sin(t) / t * theta).norm(), 4.0 * kEps * t) << t;
  }
}

TEST(So3, LogInvertsExpBelowPi) {
  for (const Vector3& axis : test_axes()) {
    for (const double t : kAngles) {
      if (t == kPi) continue;  // sign ambiguous: LogAtPiReturnsEitherSign
      SCOPED_TRACE(where(t, axis));
      const Vector3 theta = t * axis;
      // exp and log each make O(eps) absolute errors on O(1) entries; log's sensitivity is
      // ‖J_l⁻¹‖ ≤ π/2 up to π, and below 1 the error is relative (the antisymmetric part
      // carries θ exactly to first order). Hence a relative bound of a few hundred ulps.
      EXPECT_LE((so3::log(so3::exp(theta)) - theta).norm(), 1e-14 * t);
    }
  }
}

TEST(So3, LogIsAccurateJustBelowPi) {
  // At π − 1e-6 sin t ≈ 1e-6 carries only ~10 digits of the axis; the symmetric part must be
  // used. Required: ≤ 1e-12 absolute (≈ 10 ulps of π times ‖J_l⁻¹‖).
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 50; ++i) {
    const Vector3 axis = Vector3(normal(rng), normal(rng), normal(rng)).normalized();
    for (const double gap : {1e-6, 1e-8, 1e-10, 1e-12}) {
      const Vector3 theta = (kPi - gap) * axis;
      EXPECT_LE((so3::log(so3::exp(theta)) - theta).norm(), 1e-12) << where(kPi - gap, axis);
    }
  }
}

TEST(So3, LogAtPiReturnsEitherSign) {
  for (const Vector3& axis : test_axes()) {
    const Vector3 theta = kPi * axis;
    const Vector3 l = so3::log(so3::exp(theta));
    EXPECT_LE(std::min((l - theta).norm(), (l + theta).norm()), 1e-14) << where(kPi, axis);
    EXPECT_LE((so3::exp(l) - so3::exp(theta)).cwiseAbs().maxCoeff(), 1e-14);
  }
}

TEST(So3, LogPastPiReturnsTheShortRotationVector) {
  for (const Vector3& axis : test_axes()) {
    for (const double t : kLongAngles) {
      SCOPED_TRACE(where(t, axis));
      const Vector3 theta = t * axis;
      const Vector3 expected = theta - 2.0 * kPi * axis;  // same rotation, ‖·‖ = 2π − t ≤ π
      // Absolute: exp evaluated at t ≈ 2π has O(eps·2π) absolute error in its entries.
      EXPECT_LE((so3::log(so3::exp(theta)) - expected).norm(), 1e-14);
    }
  }
}

TEST(So3, ExpInvertsLogOnRandomRotations) {
  std::mt19937 rng(11);
  for (int i = 0; i < 200; ++i) {
    const Matrix3 R = random_rotation(rng);
    const Vector3 theta = so3::log(R);
    EXPECT_LE(theta.norm(), kPi + 1e-15);
    EXPECT_LE((so3::exp(theta) - R).cwiseAbs().maxCoeff(), 1e-14);
  }
}

TEST(So3, LeftJacobianTimesInverseIsIdentity) {
  std::vector<double> angles = kAngles;
  angles.insert(angles.end(), kLongAngles.begin(), kLongAngles.end());
  for (const Vector3& axis : test_axes()) {
    for (const double t : angles) {
      SCOPED_TRACE(where(t, axis));
      const Vector3 theta = t * axis;
      Matrix3 J_exp;
      so3::exp(theta, &J_exp);
      const Matrix3 J = so3::left_jacobian(theta);
      EXPECT_LE((J - J_exp).cwiseAbs().maxCoeff(), 4 * kEps);
      // The smallest singular value of J_l is 2 sin(t/2)/t (perpendicular to the axis), so
      // J_l J_l⁻¹ − I is round-off times cond(J_l) = t / (2 sin(t/2)) ≥ 1.
      const double cond = t < 1e-8 ? 1.0 : t / (2.0 * std::sin(0.5 * t));
      const Matrix3 Jinv = so3::left_jacobian_inverse(theta);
      EXPECT_LE((J * Jinv - Matrix3::Identity()).cwiseAbs().maxCoeff(), 1e-14 * cond);
      EXPECT_LE((Jinv * J - Matrix3::Identity()).cwiseAbs().maxCoeff(), 1e-14 * cond);
      // J_l θ = θ and J_l⁻¹ θ = θ: the axis is fixed. hat(θ)²θ = 0 only up to eps·t³, which
      // the W² coefficient of J_l⁻¹ (size ~ cond/t²) amplifies.
      EXPECT_LE((J * theta - theta).norm(), 1e-15 * (1.0 + t));
      EXPECT_LE((Jinv * theta - theta).norm(), 1e-15 * (1.0 + t) * cond);
    }
  }
}

// Finite-difference tolerances for the SO(3) Jacobians, ε = 1e-6:
//  exp:  FD of log(exp(θ ± εe) exp(θ)ᵀ), a near-identity log: round-off ~eps/ε ≈ 2e-10,
//        truncation ~ε²·O(1) = 1e-12. 1e-8 leaves a 50× margin and still catches any wrong
//        coefficient of J_l (those are O(t²) or larger for t ≥ 1e-4).
//  log:  FD of log(exp(±εe) R) at O(1) angles: round-off ~π·eps/ε ≈ 1e-9; 1e-7 (100×).
fd::FdOptions exp_fd_options() {
  fd::FdOptions o;
  o.rtol = o.floor = 1e-8;
  o.require_nonzero = fd::NonZero::kEveryBlock;
  return o;
}

TEST(So3, ExpJacobianIsLeftJacobianByFiniteDifferences) {
  // exp(θ + ε) ≈ exp(J_l(θ) ε) exp(θ): input θ is a point, output exp(θ) a rotation.
  std::vector<double> angles = kAngles;
  angles.insert(angles.end(), kLongAngles.begin(), kLongAngles.end());
  const fd::Dofs in = {fd::point_dof(0)};
  const fd::Dofs out = {fd::rotation_dof(0)};
  const fd::StateFunction F = [](const State& s) {
    State y;
    y.rotations = {so3::exp(s.points[0])};
    return y;
  };
  for (const Vector3& axis : test_axes()) {
    for (const double t : angles) {
      SCOPED_TRACE(where(t, axis));
      State q;
      q.points = {t * axis};
      Matrix3 J;
      so3::exp(q.points[0], &J);
      EXPECT_TRUE(fd::check_jacobian(F, q, in, out, J, exp_fd_options()));
      EXPECT_TRUE(
          fd::check_jacobian(F, q, in, out, so3::left_jacobian(q.points[0]), exp_fd_options()));
    }
  }
}

TEST(So3, LogJacobianIsInverseLeftJacobianByFiniteDifferences) {
  // log(exp(ε) R) ≈ θ + J_l⁻¹(θ) ε: input R is a rotation, output log R a point. At and just
  // below π the perturbed log may jump to the other side of the cut; unwrap() follows the
  // continuous branch through θ, on which J_l⁻¹(θ) is the derivative (J_l⁻¹ is analytic
  // for t < 2π), so π itself is checked too.
  fd::FdOptions opt;
  opt.rtol = opt.floor = 1e-7;
  const fd::Dofs in = {fd::rotation_dof(0)};
  const fd::Dofs out = {fd::point_dof(0)};
  for (const Vector3& axis : test_axes()) {
    for (const double t : kAngles) {
      SCOPED_TRACE(where(t, axis));
      State q;
      q.rotations = {so3::exp(t * axis)};
      Matrix3 J;
      const Vector3 theta = so3::log(q.rotations[0], &J);
      const fd::StateFunction F = [&theta](const State& s) {
        State y;
        y.points = {unwrap(so3::log(s.rotations[0]), theta)};
        return y;
      };
      EXPECT_TRUE(fd::check_jacobian(F, q, in, out, J, opt));
      EXPECT_LE((J - so3::left_jacobian_inverse(theta)).cwiseAbs().maxCoeff(), 0.0);
    }
  }
}

TEST(So3, InverseLeftJacobianNearTwoPiByFiniteDifferences) {
  // Past π the unwrapped log is still smooth, up to the singularity at 2π. At distance δ from
  // it the map's k-th derivative grows like δ^(1−k), so the FD step is ε = 1e-3·δ (relative
  // truncation ~ (ε/δ)² = 1e-6) and the tolerance 1e-5.
  const fd::Dofs in = {fd::rotation_dof(0)};
  const fd::Dofs out = {fd::point_dof(0)};
  for (const Vector3& axis : test_axes()) {
    for (const double t : {4.0, 2.0 * kPi - 1e-3}) {
      SCOPED_TRACE(where(t, axis));
      const Vector3 theta = t * axis;
      State q;
      q.rotations = {so3::exp(theta)};
      const fd::StateFunction F = [&theta](const State& s) {
        State y;
        y.points = {unwrap(so3::log(s.rotations[0]), theta)};
        return y;
      };
      fd::FdOptions opt;
      opt.step = 1e-3 * std::min(1.0, 2.0 * kPi - t);
      opt.rtol = opt.floor = 1e-5;
      EXPECT_TRUE(fd::check_jacobian(F, q, in, out, so3::left_jacobian_inverse(theta), opt));
    }
  }
}

TEST(So3, QuaternionRoundTripsAndCanonicalSign) {
  std::vector<double> angles = kAngles;
  angles.insert(angles.end(), kLongAngles.begin(), kLongAngles.end());
  for (const Vector3& axis : test_axes()) {
    for (const double t : angles) {
      SCOPED_TRACE(where(t, axis));
      const Matrix3 R = so3::exp(t * axis);
      const Eigen::Quaterniond q = so3::to_quaternion(R);
      EXPECT_GE(q.w(), 0.0);
      EXPECT_NEAR(q.norm(), 1.0, 4 * kEps);
      // Expected (cos t/2, sin t/2 n) up to the sign (ambiguous only at t = π, where w ≈ 0).
      const Eigen::Vector4d expected(std::cos(0.5 * t), std::sin(0.5 * t) * axis.x(),
                                     std::sin(0.5 * t) * axis.y(), std::sin(0.5 * t) * axis.z());
      const Eigen::Vector4d got(q.w(), q.x(), q.y(), q.z());
      EXPECT_LE(std::min((got - expected).norm(), (got + expected).norm()), 8e-15);
      EXPECT_LE((so3::from_quaternion(q) - R).cwiseAbs().maxCoeff(), 8e-15);
      // A non-unit quaternion is normalised first.
      Eigen::Quaterniond scaled = q;
      scaled.coeffs() *= 3.7;
      EXPECT_LE((so3::from_quaternion(scaled) - R).cwiseAbs().maxCoeff(), 8e-15);
    }
  }
}

TEST(So3, OrthonormalizeSquaresTheError) {
  std::mt19937 rng(5);
  for (int i = 0; i < 50; ++i) {
    const Matrix3 R = random_rotation(rng);
    // An exact rotation is a fixed point up to round-off.
    EXPECT_LE((so3::orthonormalize(R) - R).cwiseAbs().maxCoeff(), 4 * kEps);
    for (const double size : {1e-4, 1e-6, 1e-8}) {
      const Matrix3 A = R + size * Matrix3::Random();
      const double before = (A.transpose() * A - Matrix3::Identity()).norm();
      const Matrix3 B = so3::orthonormalize(A);
      const double after = (B.transpose() * B - Matrix3::Identity()).norm();
      // With AᵀA = I + E, BᵀB = I − ¾E² + O(E³) (one Newton step of the polar decomposition).
      EXPECT_LE(after, before * before + 8 * kEps) << size;
      // And B approaches the polar factor U Vᵀ of A to second order.
      const Eigen::JacobiSVD<Matrix3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Matrix3 polar = svd.matrixU() * svd.matrixV().transpose();
      EXPECT_LE((B - polar).norm(), before * before + 8 * kEps) << size;
    }
  }
}

TEST(So3, OrthonormalizeStopsDriftOverLongRuns) {
  // The Newton loop updates R ← exp(δ) R every iteration; with re-orthonormalisation the
  // error must stay at round-off level instead of random-walking.
  Matrix3 R = Matrix3::Identity();
  const Vector3 step(0.3, -0.2, 0.7);
  for (int i = 0; i < 20000; ++i) R = so3::orthonormalize(so3::exp(step) * R);
  EXPECT_LE((R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff(), 8 * kEps);
  EXPECT_NEAR(R.determinant(), 1.0, 8 * kEps);
}

TEST(So3, DistanceIsTheGeodesicAngle) {
  std::mt19937 rng(9);
  for (const Vector3& axis : test_axes()) {
    for (const double t : kAngles) {
      if (t == kPi) continue;
      const Matrix3 B = random_rotation(rng);
      const Matrix3 A = so3::exp(t * axis) * B;
      // ABᵀ = exp(θ) up to O(eps) round-off, so ‖log‖ = t up to a few ulps of π.
      EXPECT_NEAR(so3::distance(A, B), t, 1e-14) << where(t, axis);
      EXPECT_NEAR(so3::distance(B, A), t, 1e-14);
      const Matrix3 C = random_rotation(rng);
      EXPECT_NEAR(so3::distance(C * A, C * B), t, 1e-14);  // conjugation keeps the angle
      EXPECT_NEAR(so3::distance(A * C, B * C), t, 1e-14);
    }
  }
  const Matrix3 A = random_rotation(rng);
  EXPECT_LE(so3::distance(A, A), 1e-15);
  EXPECT_NEAR(so3::distance(so3::exp(kPi * Vector3::UnitZ()), Matrix3::Identity()), kPi, 1e-15);
}

}  // namespace
}  // namespace liedyn::so3_tests

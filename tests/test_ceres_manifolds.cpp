// The unit-quaternion manifold for Ceres (manifolds/ceres_manifolds.hpp): Plus/Minus
// consistency, their Jacobians against central finite differences, and — the property the
// back-end relies on — that a cost returning J_Lie · MinusJacobian passes Ceres's own
// GradientChecker, while the padded [J_Lie 0] of docs/design.md §9.3 does not. At the extreme
// angles of tests/fd_check.hpp.

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>
#include <vector>

#include "fd_check.hpp"
#include "lib/so3.hpp"
#include "manifolds/ceres_manifolds.hpp"
#include "manifolds/quaternion.hpp"

namespace liedyn {
namespace {

using Vector4 = Eigen::Vector4d;
template <int Rows, int Cols>
using RowMajor = Eigen::Matrix<double, Rows, Cols, Eigen::RowMajor>;

std::vector<double> ambient(const Matrix3& R) {
  const Vector4 q = quat::from_rotation(R);
  return std::vector<double>(q.data(), q.data() + 4);
}

Matrix3 rotation_of(const double* x) { return quat::rotation(Eigen::Map<const Vector4>(x)); }

// Plus moves along the left perturbation exp(δ) R, to first order exactly (the retraction
// turns by 2 atan(‖δ‖/2) instead of ‖δ‖: same direction, O(‖δ‖³) apart).
TEST(QuaternionManifold, PlusIsTheLeftPerturbationAndMinusInvertsIt) {
  const UnitQuaternionRetraction m;
  std::mt19937 rng(7);
  for (const double angle : fd::kAngles) {
    SCOPED_TRACE(angle);
    const Matrix3 R = fd::rotation_at(angle, rng);
    const std::vector<double> x = ambient(R);
    for (const double size : {1e-8, 1e-3, 0.3, 2.0}) {
      const Vector3 delta = size * fd::random_unit(rng);
      std::vector<double> y(m.AmbientSize());
      ASSERT_TRUE(m.Plus(x.data(), delta.data(), y.data()));
      const Matrix3 expected = so3::exp(2.0 * std::atan(0.5 * size) / size * delta) * R;
      EXPECT_LE(so3::distance(rotation_of(y.data()), expected), 1e-14);
      Vector3 back;
      ASSERT_TRUE(m.Minus(y.data(), x.data(), back.data()));
      EXPECT_LE((back - delta).norm(), 1e-13 * (1.0 + size)) << back.transpose();
    }
  }
}

TEST(QuaternionManifold, JacobiansMatchFiniteDifferencesAndInvertEachOther) {
  const UnitQuaternionRetraction m;
  const int n = m.AmbientSize();
  std::mt19937 rng(11);
  for (const double angle : fd::kAngles) {
    SCOPED_TRACE(angle);
    const std::vector<double> x = ambient(fd::rotation_at(angle, rng));
    Eigen::MatrixXd P(n, 3), M(3, n);
    {
      std::vector<double> p(n * 3), mm(3 * n);
      ASSERT_TRUE(m.PlusJacobian(x.data(), p.data()));
      ASSERT_TRUE(m.MinusJacobian(x.data(), mm.data()));
      P = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(p.data(), n, 3);
      M = Eigen::Map<Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>>(mm.data(), 3, n);
    }
    EXPECT_LE((M * P - Matrix3::Identity()).cwiseAbs().maxCoeff(), 1e-14);
    // PlusJacobian: central differences of Plus(x, ±εe_k); truncation O(ε²), round-off
    // O(eps/ε): 1e-8 leaves a wide margin at ε = 1e-5.
    const double eps = 1e-5;
    for (int k = 0; k < 3; ++k) {
      std::vector<double> plus(n), minus(n);
      const Vector3 d = eps * Vector3::Unit(k);
      const Vector3 md = -d;
      m.Plus(x.data(), d.data(), plus.data());
      m.Plus(x.data(), md.data(), minus.data());
      for (int i = 0; i < n; ++i) {
        EXPECT_NEAR(P(i, k), (plus[i] - minus[i]) / (2 * eps), 1e-8) << "entry " << i << ", " << k;
      }
    }
    // MinusJacobian: central differences of Minus(y, x) for y = Plus(x, ±εe_k) give I through P,
    // already covered by M·P = I; along the manifold that is all Ceres uses.
  }
}

// r(R) = A R p − y, with Lie Jacobian ∂r/∂θ = −A hat(R p) (A generic, so that no entry is
// structurally zero: the checker divides entry by entry and would flag the round-off of a zero
// entry). As a Ceres cost over a rotation block it returns J_Lie · M (the back-end's recipe),
// or the padded [J_Lie 0] when `pad` is set.
class RotatedPointCost final : public ceres::CostFunction {
 public:
  explicit RotatedPointCost(bool pad) : pad_(pad) {
    set_num_residuals(3);
    mutable_parameter_block_sizes()->push_back(4);
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const Matrix3 R = rotation_of(x[0]);
    const Vector3 p(0.3, -0.2, 0.5), y(0.1, 0.4, -0.3);
    Matrix3 A;
    A << 1.0, 0.3, -0.2, 0.1, 0.8, 0.4, -0.5, 0.2, 1.1;
    Eigen::Map<Vector3> r(residuals);
    r = A * R * p - y;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      const Matrix3 J_lie = -A * so3::hat(R * p);
      Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> J(jacobians[0]);
      if (pad_) {
        J.setZero();
        J.leftCols<3>() = J_lie;
      } else {
        J = J_lie * UnitQuaternionRetraction::lie_to_ambient(x[0]);
      }
    }
    return true;
  }

 private:
  bool pad_;
};

TEST(QuaternionManifold, LieJacobianTimesMinusJacobianPassesCeresGradientChecker) {
  const UnitQuaternionRetraction m;
  const std::vector<const ceres::Manifold*> manifolds{&m};
  std::mt19937 rng(5);
  for (const double angle : fd::kAngles) {
    SCOPED_TRACE(angle);
    const std::vector<double> x = ambient(fd::rotation_at(angle, rng));
    const double* blocks[] = {x.data()};
    for (const bool pad : {false, true}) {
      RotatedPointCost cost(pad);
      ceres::GradientChecker checker(&cost, &manifolds, ceres::NumericDiffOptions{});
      ceres::GradientChecker::ProbeResults results;
      const bool passed = checker.Probe(blocks, 1e-7, &results);
      if (pad) {
        EXPECT_FALSE(passed) << "the padded Jacobian must fail the check";
      } else {
        EXPECT_TRUE(passed) << results.error_log;
      }
    }
  }
}

}  // namespace
}  // namespace liedyn

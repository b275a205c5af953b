// The banded Cholesky kernel (solvers/banded_cholesky.hpp) against Eigen's dense LLT: same
// solutions for random band matrices of several bandwidths, shifts, and the edge cases
// (bandwidth 0, bandwidth n − 1, n = 1); indefinite matrices are refused without harm to A.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <random>

#include "solvers/banded_cholesky.hpp"

namespace liedyn {
namespace {

// A random symmetric band matrix with half-bandwidth b, diagonally dominant by `margin`
// (margin > 0: positive definite; margin < 0 with a negative diagonal entry: indefinite).
Eigen::MatrixXd random_band(int n, int b, double margin, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) {
    for (int i = j + 1; i <= std::min(n - 1, j + b); ++i) A(i, j) = A(j, i) = u(rng);
  }
  for (int i = 0; i < n; ++i) A(i, i) = A.row(i).cwiseAbs().sum() + margin;
  return A;
}

void load(const Eigen::MatrixXd& A, int b, BandedCholesky& band) {
  band.resize(static_cast<int>(A.rows()), b);
  for (int j = 0; j < A.cols(); ++j) {
    for (int i = j; i <= std::min<int>(static_cast<int>(A.rows()) - 1, j + b); ++i) {
      band.values()[band.index(i, j)] = A(i, j);
    }
  }
}

TEST(BandedCholesky, SolvesLikeDenseCholeskyForEveryBandwidth) {
  std::mt19937 rng(7);
  for (const int n : {1, 2, 9, 40}) {
    for (const int b : {0, 1, 3, 8, 11}) {
      if (b > n - 1 && b != 0) continue;
      for (const double mu : {0.0, 0.5}) {
        SCOPED_TRACE(testing::Message() << "n=" << n << " b=" << b << " mu=" << mu);
        const Eigen::MatrixXd A = random_band(n, b, 0.1, rng);
        BandedCholesky band;
        load(A, b, band);
        ASSERT_TRUE(band.factorize(mu));
        const Eigen::VectorXd rhs = Eigen::VectorXd::Random(n);
        Eigen::VectorXd x = rhs;
        band.solve(x.data());
        const Eigen::MatrixXd shifted = A + mu * Eigen::MatrixXd::Identity(n, n);
        const Eigen::VectorXd expected = shifted.llt().solve(rhs);
        // Diagonally dominant by ≥ 0.1 relative to O(b) entries: condition number ≲ 10³,
        // so the two solutions agree to ~1e-13 relative.
        EXPECT_LT((x - expected).norm(), 1e-12 * (1.0 + expected.norm()));
        EXPECT_LT((shifted * x - rhs).norm(), 1e-12 * (1.0 + rhs.norm()));
      }
    }
  }
}

TEST(BandedCholesky, RefusesAnIndefiniteMatrixAndKeepsIt) {
  std::mt19937 rng(3);
  Eigen::MatrixXd A = random_band(12, 4, 0.1, rng);
  A(7, 7) = -1.0;  // a negative diagonal entry: not positive definite
  BandedCholesky band;
  load(A, 4, band);
  const std::vector<double> before(band.values(), band.values() + band.value_count());
  EXPECT_FALSE(band.factorize(0.0));
  EXPECT_EQ(std::vector<double>(band.values(), band.values() + band.value_count()), before);
  // A large enough shift makes it definite (Gershgorin: μ > 1 + Σ|off-diagonal| of row 7).
  EXPECT_TRUE(band.factorize(1.0 + A.row(7).cwiseAbs().sum()));
}

TEST(BandedCholesky, RefusesNaN) {
  BandedCholesky band;
  band.resize(3, 1);
  band.values()[band.index(0, 0)] = 1.0;
  band.values()[band.index(1, 1)] = std::numeric_limits<double>::quiet_NaN();
  band.values()[band.index(2, 2)] = 1.0;
  EXPECT_FALSE(band.factorize(0.0));
}

}  // namespace
}  // namespace liedyn

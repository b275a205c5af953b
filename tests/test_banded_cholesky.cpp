// The banded Cholesky kernel (solvers/banded_cholesky.hpp) against Eigen's dense LLT: same
// solutions for random band matrices of several bandwidths, shifts, and the edge cases
// (bandwidth 0, bandwidth n − 1, n = 1); indefinite matrices are refused without harm to A.
// Its LU without pivoting of A + μI + W (W skew) against Eigen's dense LU, both solves.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
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

// A random skew-symmetric band matrix with half-bandwidth b, entries up to `size`.
Eigen::MatrixXd random_skew_band(int n, int b, double size, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-size, size);
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) {
    for (int i = j + 1; i <= std::min(n - 1, j + b); ++i) {
      W(i, j) = u(rng);
      W(j, i) = -W(i, j);
    }
  }
  return W;
}

void load_skew(const Eigen::MatrixXd& W, int b, BandedCholesky& band) {
  for (int j = 0; j < W.cols(); ++j) {
    for (int i = j + 1; i <= std::min<int>(static_cast<int>(W.rows()) - 1, j + b); ++i) {
      band.skew_values()[band.index(i, j)] = W(i, j);
    }
  }
}

// A + μI + W with A + μI positive definite, W skew (as large as A's off-diagonal entries, or
// 10× larger), every size from 1 to 50 and several bandwidths: both solves agree with a dense
// LU with partial pivoting. Shifts: none, and one that regularises an indefinite A (a negative
// diagonal entry beyond its row's off-diagonal sum, made definite by μ). A matrix with
// positive definite symmetric part S has ‖M⁻¹‖₂ ≤ 1/λ_min(S) (xᵀMx = xᵀSx), here ≤ 1/0.1 by
// Gershgorin, so both solutions are accurate; with ‖W‖ ≤ 10·2b the growth bound of
// banded_cholesky.hpp allows a few hundred ulps of ‖x‖, hence 1e-11.
TEST(BandedLu, SolvesLikeDenseLuForEverySizeAndBandwidth) {
  std::mt19937 rng(11);
  double worst = 0.0;
  for (int n = 1; n <= 50; ++n) {
    for (const int b : {0, 1, 2, 3, 8, 11, n - 1}) {
      if (b > n - 1 || (b == n - 1 && n - 1 <= 11)) continue;  // n − 1: once
      for (const double skew : {1.0, 10.0}) {
        for (const bool regularised : {false, true}) {
          SCOPED_TRACE(testing::Message() << "n=" << n << " b=" << b << " skew=" << skew
                                          << " regularised=" << regularised);
          Eigen::MatrixXd A = random_band(n, b, 0.1, rng);
          double mu = 0.0;
          if (regularised) {
            const int i = n / 2;
            const double off = A.row(i).cwiseAbs().sum() - std::abs(A(i, i));
            A(i, i) = -1.0 - off;  // row i: indefinite (A_ii < −Σ|off-diagonal|)
            mu = 2.0 + 2.0 * off;  // A_ii + μ ≥ 1 + Σ|off-diagonal|: dominant again
          }
          const Eigen::MatrixXd W = random_skew_band(n, b, skew, rng);
          BandedCholesky band;
          load(A, b, band);
          load_skew(W, b, band);
          ASSERT_TRUE(band.factorize_skew(mu));
          const Eigen::MatrixXd M = A + mu * Eigen::MatrixXd::Identity(n, n) + W;
          const Eigen::PartialPivLU<Eigen::MatrixXd> lu(M);
          const Eigen::VectorXd rhs = Eigen::VectorXd::Random(n);
          Eigen::VectorXd x = rhs, y = rhs;
          band.solve(x.data());
          band.solve_transposed(y.data());
          const Eigen::VectorXd expected_x = lu.solve(rhs);
          const Eigen::VectorXd expected_y = lu.transpose().solve(rhs);
          const double error = std::max((x - expected_x).norm() / expected_x.norm(),
                                        (y - expected_y).norm() / expected_y.norm());
          worst = std::max(worst, error);
          EXPECT_LT(error, 1e-11);
          EXPECT_LT((M * x - rhs).norm(), 1e-12 * M.norm() * x.norm());
          EXPECT_LT((M.transpose() * y - rhs).norm(), 1e-12 * M.norm() * y.norm());
        }
      }
    }
  }
  std::printf("largest relative difference from the dense LU: %.2e\n", worst);
}

// The symmetric factorisation after a skew one solves the symmetric matrix again (the solves
// follow the last factorisation), and W = 0 gives the Cholesky solution.
TEST(BandedLu, WithoutTheSkewPartIsTheCholeskySolve) {
  std::mt19937 rng(5);
  const int n = 30, b = 8;
  const Eigen::MatrixXd A = random_band(n, b, 0.1, rng);
  BandedCholesky band;
  load(A, b, band);
  const Eigen::VectorXd rhs = Eigen::VectorXd::Random(n);
  ASSERT_TRUE(band.factorize(0.0));
  Eigen::VectorXd cholesky = rhs;
  band.solve(cholesky.data());
  ASSERT_TRUE(band.factorize_skew(0.0));  // W = 0 after resize()
  Eigen::VectorXd x = rhs, y = rhs;
  band.solve(x.data());
  band.solve_transposed(y.data());
  EXPECT_LT((x - cholesky).norm(), 1e-13 * cholesky.norm());
  EXPECT_LT((y - cholesky).norm(), 1e-13 * cholesky.norm());
  load_skew(random_skew_band(n, b, 1.0, rng), b, band);
  ASSERT_TRUE(band.factorize_skew(0.0));
  ASSERT_TRUE(band.factorize(0.0));
  x = rhs;
  band.solve(x.data());
  EXPECT_EQ(x, cholesky);
}

// A non-positive pivot is refused, A and W kept; a large enough shift then factorises. And
// the converse the header warns of: the skew part can lift the pivot of an indefinite
// symmetric part, [[1, 2], [−2, −1]] = diag(1, −1) + W has pivots 1 and 3.
TEST(BandedLu, RefusesANonPositivePivotButNotEveryIndefiniteSymmetricPart) {
  std::mt19937 rng(3);
  Eigen::MatrixXd A = random_band(12, 4, 0.1, rng);
  A(7, 7) = -1.0 - 10.0 * A.row(7).cwiseAbs().sum();  // beyond what W (entries ≤ 1) can lift
  BandedCholesky band;
  load(A, 4, band);
  load_skew(random_skew_band(12, 4, 1.0, rng), 4, band);
  const std::vector<double> a(band.values(), band.values() + band.value_count());
  const std::vector<double> w(band.skew_values(), band.skew_values() + band.value_count());
  EXPECT_FALSE(band.factorize_skew(0.0));
  EXPECT_EQ(std::vector<double>(band.values(), band.values() + band.value_count()), a);
  EXPECT_EQ(std::vector<double>(band.skew_values(), band.skew_values() + band.value_count()), w);
  EXPECT_TRUE(band.factorize_skew(2.0 - A(7, 7) + A.row(7).cwiseAbs().sum()));

  BandedCholesky lifted;
  lifted.resize(2, 1);
  lifted.values()[lifted.index(0, 0)] = 1.0;
  lifted.values()[lifted.index(1, 1)] = -1.0;
  lifted.skew_values()[lifted.index(1, 0)] = -2.0;  // W_10 = −2, W_01 = 2
  EXPECT_FALSE(lifted.factorize(0.0));
  ASSERT_TRUE(lifted.factorize_skew(0.0));
  Eigen::Vector2d x(1.0, 0.0);
  lifted.solve(x.data());
  const Eigen::Vector2d expected = (Eigen::Matrix2d() << 1.0, 2.0, -2.0, -1.0).finished().lu().solve(
      Eigen::Vector2d(1.0, 0.0));
  EXPECT_LT((x - expected).norm(), 1e-15);
}

TEST(BandedLu, RefusesNaN) {
  BandedCholesky band;
  band.resize(3, 1);
  band.values()[band.index(0, 0)] = 1.0;
  band.values()[band.index(1, 1)] = 1.0;
  band.values()[band.index(2, 2)] = 1.0;
  band.skew_values()[band.index(1, 0)] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(band.factorize_skew(0.0));
}

}  // namespace
}  // namespace liedyn

#pragma once
// Cholesky factorisation of a symmetric band matrix, A + μI = L D Lᵀ (L unit lower), and LU
// factorisation without pivoting of its nonsymmetric sum with a skew-symmetric band matrix,
// A + μI + W = L D U (L unit lower, U unit upper).
//
// A has half-bandwidth b when A_ij = 0 for |i − j| > b; its Cholesky factor has the same
// band, so nothing fills in outside it and no ordering or symbolic analysis is needed. A rod
// whose nodes and edges are numbered along it (node, edge, node, …) has b = 8, whatever its
// length: factorising costs about n b(b + 3)/2 multiply–adds (≈ 42k for the 963 free DOFs of
// the helix scene) and the two triangular solves 2 n b, all on contiguous memory. Without
// pivoting the LU's factors keep the band too, at twice the multiply–adds, n b(b + 3).
//
// Storage (LAPACK's lower band layout): A_ij, j ≤ i ≤ j + b, at values()[j (b + 1) + i − j],
// i.e. column j holds its diagonal then the b entries below it. W is given by its strict lower
// band in the same layout (skew_values(); W_ji = −W_ij). The factors are kept apart, so that
// A survives a failed factorisation and can be refactorised with another shift μ.
// A + μI is positive definite iff every pivot D_j is positive; factorize() checks that.
// Nothing is allocated after resize().
//
// Why the LU needs no pivoting (the trapezoidal integrator's Newton matrix H + K, H the
// symmetric Hessian and K skew, solvers/newton.hpp): let S = A + μI be positive definite.
// Eliminating a pivot of a matrix S + W leaves a Schur complement whose symmetric part is the
// Schur complement of S plus a positive semi-definite term (for the first pivot, s the
// symmetric and w the skew part of its column below it: S₂₂ − s sᵀ/d + w wᵀ/d), so every
// pivot of S + W is at least the corresponding Cholesky pivot of S: elimination without
// pivoting exists and meets no pivot smaller than Cholesky's. Its growth is bounded as well:
// ‖|L| |DU|‖ ≤ n (‖S‖ + ‖Wᵀ S⁻¹ W‖) (Golub and Van Loan, Matrix Computations, on
// unsymmetric positive definite systems), i.e. of the order of ‖S‖ while ‖S⁻¹W‖ is not large
// — as for Newton's H + K, where K = ½ hat(c) is small against H. A shift μ only adds to S:
// it makes the pivots larger and the bound smaller. The converse does not hold: positive
// pivots do not prove that S is positive definite (the skew part adds w wᵀ/d to the symmetric
// part, which can lift a negative pivot: [[1, 2], [−2, −1]]), so factorize_skew()'s refusal of a
// non-positive pivot detects some indefinite S, not all (Newton tests the rest along its step).

#include <vector>

namespace liedyn {

class BandedCholesky {
 public:
  // Sets the size and half-bandwidth and zeroes A and W.
  void resize(int n, int bandwidth);

  int size() const { return n_; }
  int bandwidth() const { return b_; }

  // A's lower band (layout above). Entries beyond the last row (i ≥ n) are never read.
  double* values() { return a_.data(); }
  const double* values() const { return a_.data(); }
  std::size_t value_count() const { return a_.size(); }
  // W's strict lower band, in the same layout (the diagonal entries are never read).
  double* skew_values() { return w_.data(); }
  // Index in values() and skew_values() of the entry (i, j), for j ≤ i ≤ j + b.
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * (b_ + 1) + static_cast<std::size_t>(i - j);
  }

  void set_zero();

  // Factorises A + μI (L D Lᵀ). False when a pivot is not positive (A + μI is not positive
  // definite to working precision); the factor is then unusable, A is unchanged.
  bool factorize(double mu);
  // Factorises A + μI + W (L D U, no pivoting). False when a pivot is not positive (then
  // A + μI is not positive definite; see above for the converse); A and W are unchanged.
  bool factorize_skew(double mu);

  // x ← M⁻¹ x and x ← M⁻ᵀ x, M the matrix of the last successful factorize() (A + μI) or
  // factorize_skew() (A + μI + W).
  void solve(double* x) const;
  void solve_transposed(double* x) const;

 private:
  // The kernels for a half-bandwidth known at compile time (kB > 0) or not (kB = 0): L D Lᵀ,
  // L D U, and the solves with factors whose entries are kStep apart (banded_cholesky.cpp).
  template <int kB>
  bool factorize_band(double mu);
  template <int kB>
  bool factorize_skew_band(double mu);
  template <int kB, int kStep>
  void solve_band(double* x, const double* lower, const double* upper) const;
  template <int kStep>
  void solve_any(double* x, const double* lower, const double* upper) const;

  int n_ = 0;
  int b_ = 0;
  std::vector<double> a_;              // A's lower band
  std::vector<double> w_;              // W's strict lower band
  std::vector<double> l_;              // L D Lᵀ: D_j, then L's strict lower band, per column
  std::vector<double> lu_;             // L D U: (D_j, D_j), then (L_{j+r,j}, U_{j,j+r}) pairs
  std::vector<double> inverse_pivot_;  // 1 / D_j, so that the solves multiply
  std::vector<double> scratch_;        // 2b entries, for bandwidths not compiled in
  bool skew_ = false;                  // the last factorisation was factorize_skew()'s
};

}  // namespace liedyn

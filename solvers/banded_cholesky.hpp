#pragma once
// Cholesky factorisation of a symmetric band matrix, A + μI = L D Lᵀ (L unit lower).
//
// A has half-bandwidth b when A_ij = 0 for |i − j| > b; its Cholesky factor has the same
// band, so nothing fills in outside it and no ordering or symbolic analysis is needed. A rod
// whose nodes and edges are numbered along it (node, edge, node, …) has b = 8, whatever its
// length: factorising costs about n b(b + 3)/2 multiply–adds (≈ 42k for the 963 free DOFs of
// the helix scene) and the two triangular solves 2 n b, all on contiguous memory.
//
// Storage (LAPACK's lower band layout): A_ij, j ≤ i ≤ j + b, at values()[j (b + 1) + i − j],
// i.e. column j holds its diagonal then the b entries below it. The factor is kept apart, so
// that A survives a failed factorisation and can be refactorised with another shift μ.
// A + μI is positive definite iff every pivot D_j is positive; factorize() checks that.
// Nothing is allocated after resize().

#include <vector>

namespace liedyn {

class BandedCholesky {
 public:
  // Sets the size and half-bandwidth and zeroes A.
  void resize(int n, int bandwidth);

  int size() const { return n_; }
  int bandwidth() const { return b_; }

  // A's lower band (layout above). Entries beyond the last row (i ≥ n) are never read.
  double* values() { return a_.data(); }
  const double* values() const { return a_.data(); }
  std::size_t value_count() const { return a_.size(); }
  // Index in values() of A_ij, for j ≤ i ≤ j + b.
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * (b_ + 1) + static_cast<std::size_t>(i - j);
  }

  void set_zero();

  // Factorises A + μI. False when a pivot is not positive (A + μI is not positive definite
  // to working precision); the factor is then unusable, A is unchanged.
  bool factorize(double mu);

  // x ← (L Lᵀ)⁻¹ x, with the factor of the last successful factorize().
  void solve(double* x) const;

 private:
  // The kernels for a half-bandwidth known at compile time (kB > 0) or not (kB = 0).
  template <int kB>
  bool factorize_band(double mu);
  template <int kB>
  void solve_band(double* x) const;

  int n_ = 0;
  int b_ = 0;
  std::vector<double> a_;              // A's lower band
  std::vector<double> l_;              // D_j, then L's strict lower band, per column
  std::vector<double> inverse_pivot_;  // 1 / D_j, so that the solves multiply
  std::vector<double> scratch_;        // b entries, for bandwidths not compiled in
};

}  // namespace liedyn

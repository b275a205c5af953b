#include "banded_cholesky.hpp"
#include "unroll.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace liedyn {

void BandedCholesky::resize(int n, int bandwidth) {
  n_ = n;
  b_ = bandwidth;
  const std::size_t count = static_cast<std::size_t>(n) * (bandwidth + 1);
  a_.assign(count, 0.0);
  w_.assign(count, 0.0);
  l_.assign(count, 0.0);
  u_.assign(count, 0.0);
  inverse_pivot_.assign(n, 0.0);
  scratch_.assign(2 * static_cast<std::size_t>(bandwidth), 0.0);
}

void BandedCholesky::set_zero() { std::fill(a_.begin(), a_.end(), 0.0); }

// The kernels, for a half-bandwidth known at compile time (kB > 0: the loops over a full
// band unroll completely) or at run time (kB = 0, b given).
//
// LDLᵀ rather than LLᵀ, left-looking (dot-product form). A band factorisation is a chain:
// column j needs L_{j,j−1}, which needs column j − 1's pivot. LLᵀ puts a square root and a
// division on that chain, LDLᵀ only a division; and each entry is accumulated in registers
// and stored once. Measured on the 963-DOF rod (b = 8, perf samples of
// BM_Rod_FactorizeSolve_Banded): factorisation 51 µs as right-looking LLᵀ with a runtime
// bandwidth, 22 µs in this form.
//
// The LU (kSkew) is the same elimination with the two triangles apart: column j of L and row
// j of U, each from its own dot products, A_{j,j+r} = A_{j+r,j} (symmetric) and
// W_{j,j+r} = −W_{j+r,j}. Without W, U = Lᵀ and the row is the column: kSkew = false skips it.
//
// Layout: column j of l holds D_j, then L_{j+1,j} … L_{j+b,j} (unit diagonal implied); row j
// of u holds U_{j,j+1} … U_{j,j+b} at u[j (b + 1) + 1 …] (its first slot unused).
template <int kB, bool kSkew>
bool BandedCholesky::factorize_band(double mu) {
  const int n = n_, b = kB > 0 ? kB : b_;
  const double* a = a_.data();
  const double* w_band = w_.data();
  double* l = l_.data();
  double* u = kSkew ? u_.data() : l_.data();
  double* inverse_pivot = inverse_pivot_.data();
  const std::ptrdiff_t stride = b + 1;
  // Column j: `first` = columns to its left inside the band, `below` = rows below the
  // diagonal. Inlined into the loops below with constants where the band is full.
  auto column = [&](int j, int first, int below) {
    // For the columns k = j − first + t to the left (k < j): w_t = D_k U_{k,j} for L's column
    // and v_t = L_{j,k} D_k for U's row (the same numbers without W); in registers when b is a
    // compile-time constant.
    double local[kB > 0 ? 2 * kB : 1];
    double* w = kB > 0 ? local : scratch_.data();
    double* v = w + b;
    LIEDYN_UNROLL
    for (int t = 0; t < first; ++t) {
      const std::ptrdiff_t k = j - first + t;
      w[t] = u[k * stride + first - t] * l[k * stride];
      if constexpr (kSkew) v[t] = l[k * stride + first - t] * l[k * stride];
    }
    const double* a_j = a + j * stride;
    const double* w_j = w_band + j * stride;
    double* l_j = l + j * stride;
    double* u_j = u + j * stride;
    // c_r = A_{j+r,j} (+ W_{j+r,j}) − Σ_k L_{j+r,k} D_k U_{k,j}, over the columns k where
    // L_{j+r,k} is in the band (j + r − k ≤ b). The newest column (k = j − 1) comes last: it
    // is the one on the dependency chain.
    LIEDYN_UNROLL
    for (int r = 0; r <= below; ++r) {
      double c = a_j[r];
      if constexpr (kSkew) {
        if (r > 0) c += w_j[r];
      }
      LIEDYN_UNROLL
      for (int t = std::max(0, first - b + r); t < first; ++t) {
        c -= l[(j - first + t) * stride + first - t + r] * w[t];
      }
      if (r == 0) {
        const double pivot = c + mu;
        if (!(pivot > 0.0)) return false;  // not positive definite (or NaN)
        l_j[0] = pivot;
        inverse_pivot[j] = 1.0 / pivot;
      } else {
        l_j[r] = c * inverse_pivot[j];
      }
    }
    if constexpr (kSkew) {
      // d_r = A_{j,j+r} − W_{j+r,j} − Σ_k L_{j,k} D_k U_{k,j+r}.
      LIEDYN_UNROLL
      for (int r = 1; r <= below; ++r) {
        double d = a_j[r] - w_j[r];
        LIEDYN_UNROLL
        for (int t = std::max(0, first - b + r); t < first; ++t) {
          d -= u[(j - first + t) * stride + first - t + r] * v[t];
        }
        u_j[r] = d * inverse_pivot[j];
      }
    }
    return true;
  };
  if (kB == 0 || n <= 2 * b) {
    for (int j = 0; j < n; ++j) {
      if (!column(j, std::min(j, b), std::min(b, n - 1 - j))) return false;
    }
    return true;
  }
  int j = 0;
  for (; j < b; ++j) {
    if (!column(j, j, b)) return false;
  }
  for (; j < n - b; ++j) {
    if (!column(j, kB, kB)) return false;  // full band: compile-time trip counts
  }
  for (; j < n; ++j) {
    if (!column(j, b, n - 1 - j)) return false;
  }
  return true;
}

// Solves F D G x = x in place, F unit lower with F_{j,k} at lower[k (b + 1) + j − k] and G
// unit upper with G_{j,j+r} at upper[j (b + 1) + r]: M = L D U is (F, G) = (L, U), its
// transpose Uᵀ D Lᵀ is (F, G) = (Uᵀ, Lᵀ), read from the same arrays the other way round.
template <int kB>
void BandedCholesky::solve_band(double* x, const double* lower, const double* upper) const {
  const int n = n_, b = kB > 0 ? kB : b_;
  const double* inverse_pivot = inverse_pivot_.data();
  const std::ptrdiff_t stride = b + 1;
  // F z = x (unit lower), by rows: z_j = x_j − Σ_k F_jk z_k over the `left` columns
  // k = j − left … j − 1, the newest unknown last (it ends the dependency chain).
  auto forward = [&](int j, int left) {
    double s = x[j];
    LIEDYN_UNROLL
    for (int t = 0; t < left; ++t) {
      const int k = j - left + t;
      s -= lower[k * stride + left - t] * x[k];
    }
    x[j] = s;
  };
  // G w = D⁻¹ z (unit upper), by rows: w_j = z_j / D_j − Σ_r G_{j,j+r} w_{j+r}.
  auto backward = [&](int j, int below) {
    const double* g_j = upper + j * stride;
    double s = x[j] * inverse_pivot[j];
    LIEDYN_UNROLL
    for (int r = below; r >= 1; --r) s -= g_j[r] * x[j + r];
    x[j] = s;
  };
  const bool unrolled = kB > 0 && n > 2 * b;
  int j = 0;
  for (; j < b; ++j) forward(j, j);
  for (; j < n; ++j) unrolled ? forward(j, kB) : forward(j, b);
  j = n - 1;
  for (; j >= n - b && j >= 0; --j) backward(j, n - 1 - j);
  for (; j >= 0; --j) unrolled ? backward(j, kB) : backward(j, b);
}

// Rods have b = 8, chains of rigid bodies b = 11: compiled in; other bandwidths run the
// same code with runtime trip counts.
template <bool kSkew>
bool BandedCholesky::factorize_any(double mu) {
  skew_ = kSkew;
  switch (b_) {
    case 8:
      return factorize_band<8, kSkew>(mu);
    case 11:
      return factorize_band<11, kSkew>(mu);
    default:
      return factorize_band<0, kSkew>(mu);
  }
}

bool BandedCholesky::factorize(double mu) { return factorize_any<false>(mu); }
bool BandedCholesky::factorize_skew(double mu) { return factorize_any<true>(mu); }

void BandedCholesky::solve_any(double* x, const double* lower, const double* upper) const {
  switch (b_) {
    case 8:
      return solve_band<8>(x, lower, upper);
    case 11:
      return solve_band<11>(x, lower, upper);
    default:
      return solve_band<0>(x, lower, upper);
  }
}

void BandedCholesky::solve(double* x) const {
  solve_any(x, l_.data(), skew_ ? u_.data() : l_.data());
}

void BandedCholesky::solve_transposed(double* x) const {
  solve_any(x, skew_ ? u_.data() : l_.data(), l_.data());
}

}  // namespace liedyn

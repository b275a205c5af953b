#include "banded_cholesky.hpp"
#include "unroll.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <type_traits>

namespace liedyn {

void BandedCholesky::resize(int n, int bandwidth) {
  n_ = n;
  b_ = bandwidth;
  const std::size_t count = static_cast<std::size_t>(n) * (bandwidth + 1);
  a_.assign(count, 0.0);
  w_.assign(count, 0.0);
  l_.assign(count, 0.0);
  lu_.assign(2 * count, 0.0);
  inverse_pivot_.assign(n, 0.0);
  scratch_.assign(2 * static_cast<std::size_t>(bandwidth), 0.0);
}

void BandedCholesky::set_zero() { std::fill(a_.begin(), a_.end(), 0.0); }

namespace {

// Calls column(j, first, below) for j = 0 … n − 1 in order until it returns false (then
// false): `first` = columns to the left of j inside the band, `below` = rows below the
// diagonal. With a half-bandwidth known at compile time (kB > 0) the columns where the band
// is full get the constants kB, kB: their loops unroll completely.
template <int kB, class Column>
bool for_each_band_column(int n, int b, Column&& column) {
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
    if (!column(j, kB, kB)) return false;
  }
  for (; j < n; ++j) {
    if (!column(j, b, n - 1 - j)) return false;
  }
  return true;
}

// Calls f(std::integral_constant<int, kB>{}) with kB = b where b is a bandwidth compiled in
// (rods have b = 8, chains of rigid bodies b = 11), else kB = 0: the same code with runtime
// trip counts.
template <class F>
decltype(auto) with_compiled_bandwidth(int b, F&& f) {
  switch (b) {
    case 8:
      return f(std::integral_constant<int, 8>{});
    case 11:
      return f(std::integral_constant<int, 11>{});
    default:
      return f(std::integral_constant<int, 0>{});
  }
}

}  // namespace

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
// Layout: column j of l holds D_j, then L_{j+1,j} … L_{j+b,j} (unit diagonal implied).
template <int kB>
bool BandedCholesky::factorize_band(double mu) {
  const int b = kB > 0 ? kB : b_;
  const double* a = a_.data();
  double* l = l_.data();
  double* inverse_pivot = inverse_pivot_.data();
  const std::ptrdiff_t stride = b + 1;
  return for_each_band_column<kB>(n_, b, [&](int j, int first, int below) {
    // w_t = L_{j,k} D_k for the columns k = j − first + t to the left (k < j); in registers
    // when b is a compile-time constant.
    double local[kB > 0 ? kB : 1];
    double* w = kB > 0 ? local : scratch_.data();
    LIEDYN_UNROLL
    for (int t = 0; t < first; ++t) {
      const double* l_k = l + (j - first + t) * stride;
      w[t] = l_k[first - t] * l_k[0];
    }
    const double* a_j = a + j * stride;
    double* l_j = l + j * stride;
    // u_r = A_{j+r,j} − Σ_k L_{j+r,k} L_{j,k} D_k, over the columns k where L_{j+r,k} is in
    // the band (j + r − k ≤ b). The newest column (k = j − 1) comes last: it is the one on
    // the dependency chain.
    LIEDYN_UNROLL
    for (int r = 0; r <= below; ++r) {
      double u = a_j[r];
      LIEDYN_UNROLL
      for (int t = std::max(0, first - b + r); t < first; ++t) {
        u -= l[(j - first + t) * stride + first - t + r] * w[t];
      }
      if (r == 0) {
        const double pivot = u + mu;
        if (!(pivot > 0.0)) return false;  // not positive definite (or NaN)
        l_j[0] = pivot;
        inverse_pivot[j] = 1.0 / pivot;
      } else {
        l_j[r] = u * inverse_pivot[j];
      }
    }
    return true;
  });
}

// The LU, A + μI + W = L D U: the same elimination with the two triangles apart. Column j of
// L and row j of U come from the same dot products over the same columns k < j,
//   c_r = A_{j+r,j} + W_{j+r,j} − Σ_k L_{j+r,k} (D_k U_{k,j}),   L_{j+r,j} = c_r / D_j,
//   d_r = A_{j,j+r} − W_{j+r,j} − Σ_k U_{k,j+r} (D_k L_{j,k}),   U_{j,j+r} = d_r / D_j
// (A_{j,j+r} = A_{j+r,j}, W_{j,j+r} = −W_{j+r,j}; c_0 = d_0 the pivot), so L_{j+r,k} and
// U_{k,k+r} are stored side by side (lu: per column k, the pair (D_k, D_k), then
// (L_{k+r,k}, U_{k,k+r}) for r = 1 … b) and every step works on the pair (c_r, d_r): one
// two-wide multiply and subtraction for two entries, about the LDLᵀ's instruction count for
// twice its arithmetic.
template <int kB>
bool BandedCholesky::factorize_skew_band(double mu) {
  using Pair = Eigen::Array2d;
  const int b = kB > 0 ? kB : b_;
  const double* a = a_.data();
  const double* w_band = w_.data();
  double* lu = lu_.data();
  double* inverse_pivot = inverse_pivot_.data();
  const std::ptrdiff_t stride = 2 * (b + 1);
  const auto pair = [](const double* p) { return Eigen::Map<const Pair>(p); };
  return for_each_band_column<kB>(n_, b, [&](int j, int first, int below) {
    // wv_t = D_k (U_{k,j}, L_{j,k}) for the columns k = j − first + t to the left, at
    // wv[2t]; in registers when b is a compile-time constant.
    double local[kB > 0 ? 2 * kB : 1];
    double* wv = kB > 0 ? local : scratch_.data();
    LIEDYN_UNROLL
    for (int t = 0; t < first; ++t) {
      const double* lu_k = lu + (j - first + t) * stride;
      Eigen::Map<Pair>(wv + 2 * t) = lu_k[0] * pair(lu_k + 2 * (first - t)).reverse();
    }
    const double* a_j = a + j * stride / 2;
    const double* w_j = w_band + j * stride / 2;
    double* lu_j = lu + j * stride;
    // The newest column (k = j − 1) comes last: it is the one on the dependency chain.
    LIEDYN_UNROLL
    for (int r = 0; r <= below; ++r) {
      Pair cd = r == 0 ? Pair(a_j[0], a_j[0]) : Pair(a_j[r] + w_j[r], a_j[r] - w_j[r]);
      LIEDYN_UNROLL
      for (int t = std::max(0, first - b + r); t < first; ++t) {
        cd -= pair(lu + (j - first + t) * stride + 2 * (first - t + r)) * pair(wv + 2 * t);
      }
      if (r == 0) {
        const double pivot = cd[0] + mu;
        if (!(pivot > 0.0)) return false;  // S + μI not positive definite (or NaN)
        lu_j[0] = lu_j[1] = pivot;
        inverse_pivot[j] = 1.0 / pivot;
      } else {
        Eigen::Map<Pair>(lu_j + 2 * r) = cd * inverse_pivot[j];
      }
    }
    return true;
  });
}

// Solves F D G x = x in place, F unit lower with F_{j,k} at lower[kStep (k (b + 1) + j − k)]
// and G unit upper with G_{j,j+r} at upper[kStep (j (b + 1) + r)]: L D Lᵀ is (F, G) = (L, Lᵀ)
// from l (kStep 1); L D U is (L, U) from the pairs of lu (kStep 2), its transpose
// Uᵀ D Lᵀ is (Uᵀ, Lᵀ), the same arrays the other way round.
template <int kB, int kStep>
void BandedCholesky::solve_band(double* x, const double* lower, const double* upper) const {
  const int n = n_, b = kB > 0 ? kB : b_;
  const double* inverse_pivot = inverse_pivot_.data();
  const std::ptrdiff_t stride = kStep * (b + 1);
  // F z = x (unit lower), by rows: z_j = x_j − Σ_k F_jk z_k over the `left` columns
  // k = j − left … j − 1, the newest unknown last (it ends the dependency chain).
  auto forward = [&](int j, int left) {
    double s = x[j];
    LIEDYN_UNROLL
    for (int t = 0; t < left; ++t) {
      const int k = j - left + t;
      s -= lower[k * stride + kStep * (left - t)] * x[k];
    }
    x[j] = s;
  };
  // G w = D⁻¹ z (unit upper), by rows: w_j = z_j / D_j − Σ_r G_{j,j+r} w_{j+r}.
  auto backward = [&](int j, int below) {
    const double* g_j = upper + j * stride;
    double s = x[j] * inverse_pivot[j];
    LIEDYN_UNROLL
    for (int r = below; r >= 1; --r) s -= g_j[kStep * r] * x[j + r];
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

bool BandedCholesky::factorize(double mu) {
  skew_ = false;
  return with_compiled_bandwidth(b_, [&](auto kB) { return factorize_band<kB()>(mu); });
}

bool BandedCholesky::factorize_skew(double mu) {
  skew_ = true;
  return with_compiled_bandwidth(b_, [&](auto kB) { return factorize_skew_band<kB()>(mu); });
}

template <int kStep>
void BandedCholesky::solve_any(double* x, const double* lower, const double* upper) const {
  with_compiled_bandwidth(b_, [&](auto kB) { solve_band<kB(), kStep>(x, lower, upper); });
}

void BandedCholesky::solve(double* x) const {
  if (skew_) return solve_any<2>(x, lu_.data(), lu_.data() + 1);
  solve_any<1>(x, l_.data(), l_.data());
}

void BandedCholesky::solve_transposed(double* x) const {
  if (skew_) return solve_any<2>(x, lu_.data() + 1, lu_.data());
  solve_any<1>(x, l_.data(), l_.data());
}

}  // namespace liedyn

#include "linear_system.hpp"
#include "unroll.hpp"

#include <Eigen/Eigenvalues>
#include <omp.h>
#include <suitesparse/cholmod.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>  // memset
#include <limits>
#include <stdexcept>
#include <vector>

namespace liedyn {

namespace {


// Cholesky factorisation A + μI = L Lᵀ of a small fixed-size matrix. F receives L's strict
// lower triangle and, on its diagonal, the reciprocals 1/L_jj (so that the solve needs no
// division); F's strict upper triangle is never touched or read. Same algorithm and
// acceptance test as Eigen's unblocked LLT (column by column; a pivot that is not positive
// fails), but with compile-time, unrolled loops: for 6×6, factorisation + solve is ~2.5×
// faster than Eigen::LLT<Matrix<double, 6, 6>>, whose kernels work on runtime-sized blocks.
template <int N>
bool cholesky_fixed(const Eigen::Matrix<double, N, N>& A, double mu,
                    Eigen::Matrix<double, N, N>& F) {
  LIEDYN_UNROLL
  for (int j = 0; j < N; ++j) {
    double d = A(j, j) + mu;
    LIEDYN_UNROLL
    for (int k = 0; k < j; ++k) d -= F(j, k) * F(j, k);
    if (!(d > 0.0)) return false;
    const double inv = 1.0 / std::sqrt(d);
    F(j, j) = inv;
    LIEDYN_UNROLL
    for (int i = j + 1; i < N; ++i) {
      double s = A(i, j);
      LIEDYN_UNROLL
      for (int k = 0; k < j; ++k) s -= F(i, k) * F(j, k);
      F(i, j) = s * inv;
    }
  }
  return true;
}

// Solves L Lᵀ x = b with the factor F of cholesky_fixed.
template <int N>
void cholesky_fixed_solve(const Eigen::Matrix<double, N, N>& F,
                          const Eigen::Matrix<double, N, 1>& b, Eigen::Matrix<double, N, 1>& x) {
  LIEDYN_UNROLL
  for (int i = 0; i < N; ++i) {  // L y = b
    double s = b(i);
    LIEDYN_UNROLL
    for (int k = 0; k < i; ++k) s -= F(i, k) * x(k);
    x(i) = s * F(i, i);
  }
  LIEDYN_UNROLL
  for (int i = N - 1; i >= 0; --i) {  // Lᵀ x = y
    double s = x(i);
    LIEDYN_UNROLL
    for (int k = i + 1; k < N; ++k) s -= F(k, i) * x(k);
    x(i) = s * F(i, i);
  }
}


// LU factorisation without pivoting of A = H + μI + K, H symmetric and K skew (why none is
// needed: banded_cholesky.hpp), for a fixed size N (unrolled) or a dynamic one. Doolittle
// order, row j of U then column j of L, each entry a dot product over the columns before it.
// F receives L's strict lower triangle (unit diagonal implied), U's strict upper triangle and,
// on its diagonal, the reciprocals of the pivots U_jj. False at a pivot that is not positive.
template <int N, class Matrix>
bool lu_skew(const Matrix& H, double mu, const Matrix& K, Matrix& F) {
  const int n = N == Eigen::Dynamic ? static_cast<int>(H.rows()) : N;
  LIEDYN_UNROLL
  for (int j = 0; j < n; ++j) {
    double pivot = H(j, j) + mu;
    LIEDYN_UNROLL
    for (int k = 0; k < j; ++k) pivot -= F(j, k) * F(k, j);
    if (!(pivot > 0.0)) return false;
    const double inverse = 1.0 / pivot;
    F(j, j) = inverse;
    LIEDYN_UNROLL
    for (int i = j + 1; i < n; ++i) {
      double u = H(j, i) + K(j, i);  // U_ji
      double l = H(i, j) + K(i, j);  // L_ij U_jj
      LIEDYN_UNROLL
      for (int k = 0; k < j; ++k) {
        u -= F(j, k) * F(k, i);
        l -= F(i, k) * F(k, j);
      }
      F(j, i) = u;
      F(i, j) = l * inverse;
    }
  }
  return true;
}

// Solves L U x = b (transposed: Uᵀ Lᵀ x = b) with the factors F of lu_skew.
template <int N, bool kTransposed, class Matrix, class Vector>
void lu_skew_solve(const Matrix& F, const Vector& b, Vector& x) {
  const int n = N == Eigen::Dynamic ? static_cast<int>(F.rows()) : N;
  x = b;
  // Entry (i, k) off the diagonal of the factors solved with: L and U, or Uᵀ and Lᵀ.
  const auto entry = [&](int i, int k) { return kTransposed ? F(k, i) : F(i, k); };
  LIEDYN_UNROLL
  for (int i = 0; i < n; ++i) {  // L y = b, or Uᵀ y = b
    double s = x(i);
    LIEDYN_UNROLL
    for (int k = 0; k < i; ++k) s -= entry(i, k) * x(k);
    x(i) = kTransposed ? s * F(i, i) : s;
  }
  LIEDYN_UNROLL
  for (int i = n - 1; i >= 0; --i) {  // U x = y, or Lᵀ x = y
    double s = x(i);
    LIEDYN_UNROLL
    for (int k = i + 1; k < n; ++k) s -= entry(i, k) * x(k);
    x(i) = kTransposed ? s : s * F(i, i);
  }
}

// A sink that records the block positions of one assembly: the pattern.
struct BlockRecorder {
  std::vector<std::pair<int, int>> blocks;
  void clear() { blocks.clear(); }
  template <class Block>
  void add(int row, int column, const Block&) {
    blocks.emplace_back(row, column);
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------
// DenseSystem

template <int N>
DenseSystem<N>::DenseSystem(const Component& component)
    : g_(component.dofs),
      H_(component.dofs, component.dofs),
      K_(component.dofs, component.dofs),
      factor_(component.dofs, component.dofs),
      llt_(component.dofs) {}

template <int N>
bool DenseSystem<N>::hessian_finite() const {
  return std::isfinite(H_.sum());  // a NaN or Inf entry makes the sum non-finite
}

template <int N>
double DenseSystem<N>::hessian_scale() const {
  return H_.diagonal().cwiseAbs().maxCoeff();
}

template <int N>
void DenseSystem<N>::set_history_skew(const IncrementalPotential* potential) {
  skew_ = potential != nullptr;
  if (!skew_) return;
  K_.setZero();
  potential->for_each_history_skew(
      [&](int o, const Matrix3& K) { K_.template block<3, 3>(o, o) = K; });
}

template <int N>
bool DenseSystem<N>::factorize(double mu) {
  if (skew_) return lu_skew<N>(H_, mu, K_, factor_);
  if constexpr (N != Eigen::Dynamic) {
    return cholesky_fixed<N>(H_, mu, factor_);
  } else {
    factor_ = H_;
    factor_.diagonal().array() += mu;
    llt_.compute(factor_);
    return llt_.info() == Eigen::Success;
  }
}

template <int N>
void DenseSystem<N>::solve(Vector& delta) {
  solve_linear(g_, delta);
  delta = -delta;
}

template <int N>
void DenseSystem<N>::solve_linear(const Vector& b, Vector& x) {
  if (skew_) {
    lu_skew_solve<N, false>(factor_, b, x);
  } else if constexpr (N != Eigen::Dynamic) {
    cholesky_fixed_solve<N>(factor_, b, x);
  } else {
    x = llt_.solve(b);
  }
}

template <int N>
void DenseSystem<N>::solve_linear_transposed(const Vector& b, Vector& x) {
  if (skew_) {
    lu_skew_solve<N, true>(factor_, b, x);
  } else {
    solve_linear(b, x);
  }
}

template class DenseSystem<6>;
template class DenseSystem<Eigen::Dynamic>;

// ---------------------------------------------------------------------------------------
// SparseSystem

struct SparseSystem::Cholmod {
  cholmod_common common{};
  // H with its 3×3 blocks reordered by a fill-reducing permutation π of the blocks, upper
  // triangle (stype = +1), CSC. CHOLMOD factorises exactly this layout in place (natural
  // ordering, simplicial): any other layout makes cholmod_factorize copy (allocate) a
  // permuted transpose at every call.
  cholmod_sparse* A = nullptr;
  cholmod_factor* L = nullptr;   // symbolic analysis once, numeric factorisation per call
  cholmod_dense* B = nullptr;    // right-hand side P g, overwritten by the solution
  std::vector<int> block_position;  // π: block b of the tangent vector → block π(b) of A
  // For the k-th sink.add() call of an assembly: the index in A->x of the first of the
  // block's three rows in each of its three columns, or −1 for a block below the diagonal
  // of A (its transpose is added by the symmetric call and is the one stored).
  std::vector<std::array<int, 3>> block_columns;
  std::size_t cursor = 0;
  int dofs = 0;

  explicit Cholmod(int n) : dofs(n) {
    cholmod_start(&common);
    common.print = 0;  // failures are reported through Newton's status, not printed
    // LLᵀ computed directly (simplicial LDLᵀ would succeed on indefinite matrices, and
    // Newton must know when H is not positive definite to regularise it).
    common.final_ll = 1;
    common.supernodal = CHOLMOD_SIMPLICIAL;
    common.final_asis = 1;  // keep the factor as computed: no repacking after each call
  }
  ~Cholmod() {
    cholmod_free_sparse(&A, &common);
    cholmod_free_factor(&L, &common);
    cholmod_free_dense(&B, &common);
    cholmod_finish(&common);
  }
  Cholmod(const Cholmod&) = delete;
  Cholmod& operator=(const Cholmod&) = delete;

  // A fill-reducing order of the blocks: CHOLMOD's default ordering (AMD, or METIS where it
  // does better) of the block graph.
  std::vector<int> block_order(const std::vector<std::pair<int, int>>& blocks, int nb) {
    std::vector<std::vector<int>> rows_of(nb);
    for (const auto& [r, c] : blocks) {
      if (r <= c) rows_of[c / 3].push_back(r / 3);  // upper triangle of the block graph
    }
    std::size_t nnz = 0;
    for (auto& rows : rows_of) {
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      nnz += rows.size();
    }
    cholmod_sparse* G = cholmod_allocate_sparse(nb, nb, nnz, 1, 1, /*stype=*/1, CHOLMOD_PATTERN,
                                                &common);
    if (G == nullptr) throw std::runtime_error("CHOLMOD could not allocate the block graph");
    auto* p = static_cast<int*>(G->p);
    auto* i = static_cast<int*>(G->i);
    int k = 0;
    for (int c = 0; c < nb; ++c) {
      p[c] = k;
      for (int r : rows_of[c]) i[k++] = r;
    }
    p[nb] = k;
    cholmod_factor* symbolic = cholmod_analyze(G, &common);
    std::vector<int> position(nb);
    if (symbolic == nullptr) {
      cholmod_free_sparse(&G, &common);
      throw std::runtime_error("CHOLMOD could not order the Hessian");
    }
    const auto* perm = static_cast<const int*>(symbolic->Perm);  // perm[new] = old
    for (int b = 0; b < nb; ++b) position[perm[b]] = b;
    cholmod_free_factor(&symbolic, &common);
    cholmod_free_sparse(&G, &common);
    return position;
  }

  // Builds A's pattern, the scatter indices and the symbolic factorisation (which leaves
  // the factorisation's flop count in common.fl).
  void build(const std::vector<std::pair<int, int>>& blocks) {
    const int n = dofs;
    const int nb = n / 3;
    block_position = block_order(blocks, nb);
    // Stored block rows (in A's block numbering) of each block column of A: upper triangle.
    std::vector<std::vector<int>> rows_of(nb);
    for (const auto& [r, c] : blocks) {
      const int pr = block_position[r / 3], pc = block_position[c / 3];
      if (pr <= pc) rows_of[pc].push_back(pr);
    }
    std::size_t nnz = 0;
    for (auto& rows : rows_of) {
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      nnz += 9 * rows.size();
    }
    A = cholmod_allocate_sparse(n, n, nnz, /*sorted=*/1, /*packed=*/1, /*stype=*/1, CHOLMOD_REAL,
                                &common);
    if (A == nullptr) throw std::runtime_error("CHOLMOD could not allocate the Hessian");
    auto* p = static_cast<int*>(A->p);
    auto* i = static_cast<int*>(A->i);
    int k = 0;
    for (int bc = 0; bc < nb; ++bc) {
      for (int c = 0; c < 3; ++c) {
        p[3 * bc + c] = k;
        for (int br : rows_of[bc]) {
          for (int rr = 0; rr < 3; ++rr) i[k++] = 3 * br + rr;
        }
      }
    }
    p[n] = k;
    block_columns.clear();
    block_columns.reserve(blocks.size());
    for (const auto& [r, c] : blocks) {
      const int pr = block_position[r / 3], pc = block_position[c / 3];
      std::array<int, 3> starts{-1, -1, -1};
      if (pr <= pc) {
        const auto& rows = rows_of[pc];
        const int slot =
            static_cast<int>(std::lower_bound(rows.begin(), rows.end(), pr) - rows.begin());
        for (int cc = 0; cc < 3; ++cc) starts[cc] = p[3 * pc + cc] + 3 * slot;
      }
      block_columns.push_back(starts);
    }
    common.nmethods = 1;  // A is already ordered: analyse it as it is
    common.method[0].ordering = CHOLMOD_NATURAL;
    common.postorder = 0;
    L = cholmod_analyze(A, &common);
    B = cholmod_allocate_dense(n, 1, n, CHOLMOD_REAL, &common);
    if (L == nullptr || B == nullptr) throw std::runtime_error("CHOLMOD analysis failed");
    if (L->ordering != CHOLMOD_NATURAL || L->is_super) {
      throw std::logic_error("CHOLMOD factor is not simplicial with natural ordering");
    }
  }

  // The sink of every assembly after the first: adds each block at its precomputed place.
  struct Scatter {
    Cholmod& self;
    void clear() {
      std::memset(self.A->x, 0, sizeof(double) * static_cast<int*>(self.A->p)[self.dofs]);
      self.cursor = 0;
    }
    template <class Block>
    void add(int, int, const Block& block) {
      const std::array<int, 3>& starts = self.block_columns[self.cursor++];
      if (starts[0] < 0) return;  // below A's diagonal: the symmetric block is stored
      auto* x = static_cast<double*>(self.A->x);
      for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) x[starts[c] + r] += block(r, c);
      }
    }
  };
};

namespace {

// Adds the lower-triangle part of a 3×3 block at (row, column), row ≥ column, into a band
// stored in BandedCholesky's layout (stride = half-bandwidth + 1).
template <class Block>
inline void add_to_band(double* a, int stride, int row, int column, const Block& block) {
  // Two loops with constant bounds rather than one starting at (row == column ? c : 0): the
  // compiler unrolls both, and for a diagonal block of an unrolled term loop it knows which
  // one runs.
  if (row == column) {
    for (int c = 0; c < 3; ++c) {
      double* entries = a + (column + c) * (stride - 1);  // entries[i] = A_ij, j = column + c
      for (int r = c; r < 3; ++r) entries[row + r] += block(r, c);
    }
  } else {
    for (int c = 0; c < 3; ++c) {
      double* entries = a + (column + c) * (stride - 1);
      for (int r = 0; r < 3; ++r) entries[row + r] += block(r, c);
    }
  }
}

}  // namespace

// The sink of every serial banded assembly: adds the lower-triangle part of each block to
// the band (the block's transpose arrives through the symmetric add() call).
struct SparseSystem::BandScatter {
  BandedCholesky& band;
  void clear() { band.set_zero(); }
  template <class Block>
  void add(int row, int column, const Block& block) {
    if (row < column) return;
    add_to_band(band.values(), band.bandwidth() + 1, row, column, block);
  }
};

// Parallel banded assembly: part k of the terms (IncrementalPotential::Part) runs on thread
// k. A column block of the band written by one part only is written in place; one written by
// several parts is written into each part's private copy of the band, and the copies are
// summed into the band after the join. A rod numbered along its length shares only the few
// column blocks where its parts meet. Part 0 adds its gradient into g, the others into
// private vectors, also summed after the join.
//
// Each part zeroes what it writes, on its own thread: zeroed by the main thread, the other
// part's columns would have to move between the cores' caches before every write (measured
// on the 957-DOF helix: the second part then took twice as long as the first).
struct SparseSystem::ParallelAssembly {
  int parts = 1;
  std::vector<char> shared;         // per DOF, set at a block's first column: written by > 1 part
  std::vector<int> shared_columns;  // the first columns of the shared column blocks
  std::vector<std::vector<std::pair<int, int>>> own_ranges;  // per part: band entries [b, e)
                                                             // written in place
  std::vector<std::vector<double>> band;  // per part: a private band (shared columns only used)
  std::vector<Eigen::VectorXd> g;         // per part; part 0 uses the system's g (g[0] empty)
  std::vector<double> value, magnitude;   // per part: Σ Ψ_t and the round-off sum

  // The sink of part k.
  struct Scatter {
    double* band;
    double* own;
    const char* shared;
    int stride;
    void clear() {}
    template <class Block>
    void add(int row, int column, const Block& block) {
      if (row < column) return;
      add_to_band(shared[column] ? own : band, stride, row, column, block);
    }
  };
};

SparseSystem::SparseSystem(const Component& component, Factorization factorization,
                           int assembly_threads)
    : g_(component.dofs),
      factorization_(factorization),
      cholmod_(std::make_unique<Cholmod>(component.dofs)),
      assembly_threads_(assembly_threads) {
  if (assembly_threads < 0) {
    throw std::invalid_argument("SparseSystem: assembly_threads must be >= 0");
  }
}
SparseSystem::SparseSystem(SparseSystem&&) noexcept = default;
SparseSystem& SparseSystem::operator=(SparseSystem&&) noexcept = default;
SparseSystem::~SparseSystem() = default;

void SparseSystem::build(const std::vector<std::pair<int, int>>& blocks) {
  const int n = static_cast<int>(g_.size());
  int bandwidth = 0;
  for (const auto& [r, c] : blocks) bandwidth = std::max(bandwidth, r - c + 2);
  bandwidth = std::min(bandwidth, n - 1);
  if (factorization_ != Factorization::kBanded) cholmod_->build(blocks);
  if (factorization_ == Factorization::kUndecided) {
    double band_flops = 0.0;  // counted as CHOLMOD counts: Σ_j (non-zeros in column j of L)²
    for (int j = 0; j < n; ++j) {
      const double column = std::min(bandwidth, n - 1 - j) + 1.0;
      band_flops += column * column;
    }
    factorization_ = band_flops <= kBandedFlopAdvantage * cholmod_->common.fl
                         ? Factorization::kBanded
                         : Factorization::kCholmod;
  }
  if (factorization_ == Factorization::kBanded) {
    cholmod_.reset();
    band_.resize(n, bandwidth);
  }
  built_ = true;
}

double SparseSystem::assemble(const IncrementalPotential& potential, const State& q,
                              double* roundoff, const RotationVectorChart* chart) {
  if (!built_) {  // first use: the pattern
    BlockRecorder recorder;
    assemble_charted(potential, q, g_, recorder, nullptr, chart);
    build(recorder.blocks);
    if (factorization_ == Factorization::kBanded) split_assembly(potential, q);
  }
  if (parallel_ != nullptr) return assemble_in_parts(potential, q, roundoff, chart);
  if (factorization_ == Factorization::kBanded) {
    BandScatter scatter{band_};
    return assemble_charted(potential, q, g_, scatter, roundoff, chart);
  }
  Cholmod::Scatter scatter{*cholmod_};
  return assemble_charted(potential, q, g_, scatter, roundoff, chart);
}

void SparseSystem::split_assembly(const IncrementalPotential& potential, const State& q) {
  const int n = static_cast<int>(g_.size());
  int parts = assembly_threads_;
  if (parts == 0) {
    parts = n >= kParallelAssemblyMinDofs && omp_get_max_threads() >= 2 ? 2 : 1;
  }
  if (parts == 1) return;
  auto p = std::make_unique<ParallelAssembly>();
  p->parts = parts;
  p->shared.assign(n, 0);
  std::vector<int> writer(n, -1);  // the part that writes a column block, if only one
  BlockRecorder recorder;
  for (int k = 0; k < parts; ++k) {
    recorder.clear();
    potential.add_terms(q, g_, recorder, IncrementalPotential::Part{k, parts}, 1.0, nullptr);
    for (const auto& [row, column] : recorder.blocks) {
      if (row < column) continue;  // not stored
      if (writer[column] < 0) writer[column] = k;
      if (writer[column] != k && !p->shared[column]) {
        p->shared[column] = 1;
        p->shared_columns.push_back(column);
      }
    }
  }
  // Runs of consecutive column blocks that one part writes in place. Columns nobody writes
  // stay at the zero resize() gave them (the factorisation does not overwrite the band).
  const int stride = band_.bandwidth() + 1;
  p->own_ranges.assign(parts, {});
  for (int column = 0; column < n; column += 3) {
    const int k = writer[column];
    if (k < 0 || p->shared[column]) continue;
    auto& ranges = p->own_ranges[k];
    if (!ranges.empty() && ranges.back().second == column * stride) {
      ranges.back().second += 3 * stride;
    } else {
      ranges.emplace_back(column * stride, (column + 3) * stride);
    }
  }
  p->band.assign(parts, std::vector<double>(band_.value_count(), 0.0));
  p->g.assign(parts, Eigen::VectorXd::Zero(n));
  p->g[0].resize(0);
  p->value.assign(parts, 0.0);
  p->magnitude.assign(parts, 0.0);
  parallel_ = std::move(p);
}

double SparseSystem::assemble_in_parts(const IncrementalPotential& potential, const State& q,
                                       double* roundoff, const RotationVectorChart* chart) {
  ParallelAssembly& p = *parallel_;
  const int stride = band_.bandwidth() + 1;
  const double position_scale =
      roundoff != nullptr ? IncrementalPotential::roundoff_position_scale(q) : 1.0;
  double* a = band_.values();
#pragma omp parallel num_threads(p.parts)
  {
    // Fewer threads than parts (OpenMP may give fewer): each thread takes several parts.
    for (int k = omp_get_thread_num(); k < p.parts; k += omp_get_num_threads()) {
      Eigen::VectorXd& g = k == 0 ? g_ : p.g[k];
      g.setZero();
      for (const auto& [begin, end] : p.own_ranges[k]) std::fill(a + begin, a + end, 0.0);
      double* own = p.band[k].data();
      for (int column : p.shared_columns) {
        std::fill(own + column * stride, own + (column + 3) * stride, 0.0);
      }
      ParallelAssembly::Scatter sink{a, own, p.shared.data(), stride};
      const IncrementalPotential::Part part{k, p.parts};
      double* magnitude = roundoff != nullptr ? &p.magnitude[k] : nullptr;
      p.magnitude[k] = 0.0;
      p.value[k] = through_chart(sink, chart, [&](auto& s) {
        return potential.add_terms(q, g, s, part, position_scale, magnitude);
      });
    }
  }
  double value = p.value[0];
  double magnitude = p.magnitude[0];
  for (int k = 1; k < p.parts; ++k) {
    value += p.value[k];
    magnitude += p.magnitude[k];
    g_ += p.g[k];
  }
  for (int column : p.shared_columns) {
    std::fill(a + column * stride, a + (column + 3) * stride, 0.0);
    for (int k = 0; k < p.parts; ++k) {
      const double* own = p.band[k].data();
      for (int e = column * stride; e < (column + 3) * stride; ++e) a[e] += own[e];
    }
  }
  if (chart != nullptr) {
    BandScatter scatter{band_};
    chart->finish(g_, scatter);
  }
  if (roundoff != nullptr) *roundoff = std::numeric_limits<double>::epsilon() * magnitude;
  return value;
}

int SparseSystem::assembly_parts() const { return parallel_ != nullptr ? parallel_->parts : 1; }

bool SparseSystem::hessian_finite() const {
  const double* x = nullptr;
  long count = stored_nonzeros();
  if (factorization_ == Factorization::kBanded) {
    x = band_.values();
  } else {
    x = static_cast<const double*>(cholmod_->A->x);
  }
  // One sum (Eigen's, vectorised with independent partial sums): a NaN or Inf entry makes
  // it non-finite.
  return std::isfinite(Eigen::Map<const Eigen::VectorXd>(x, count).sum());
}

double SparseSystem::hessian_scale() const {
  double scale = 0.0;
  if (factorization_ == Factorization::kBanded) {
    for (int j = 0; j < band_.size(); ++j) {
      scale = std::max(scale, std::abs(band_.values()[band_.index(j, j)]));
    }
    return scale;
  }
  const Cholmod& c = *cholmod_;
  const auto* p = static_cast<const int*>(c.A->p);
  const auto* i = static_cast<const int*>(c.A->i);
  const auto* x = static_cast<const double*>(c.A->x);
  for (int col = 0; col < c.dofs; ++col) {
    for (int k = p[col]; k < p[col + 1]; ++k) {
      if (i[k] == col) scale = std::max(scale, std::abs(x[k]));
    }
  }
  return scale;
}

void SparseSystem::dense_hessian(Eigen::MatrixXd& H) const {
  const int n = static_cast<int>(g_.size());
  H.setZero(n, n);
  if (factorization_ == Factorization::kBanded) {
    for (int j = 0; j < n; ++j) {
      for (int i = j; i <= std::min(n - 1, j + band_.bandwidth()); ++i) {
        H(i, j) = H(j, i) = band_.values()[band_.index(i, j)];
      }
    }
    return;
  }
  // A holds the upper triangle of P H Pᵀ: map its rows and columns back through P.
  const Cholmod& c = *cholmod_;
  std::vector<int> original(n);
  for (int block = 0; block < n / 3; ++block) {
    for (int r = 0; r < 3; ++r) original[3 * c.block_position[block] + r] = 3 * block + r;
  }
  const auto* p = static_cast<const int*>(c.A->p);
  const auto* i = static_cast<const int*>(c.A->i);
  const auto* x = static_cast<const double*>(c.A->x);
  for (int col = 0; col < n; ++col) {
    for (int k = p[col]; k < p[col + 1]; ++k) {
      H(original[i[k]], original[col]) = H(original[col], original[i[k]]) = x[k];
    }
  }
}

double condition_number(const Eigen::MatrixXd& H) {
  const Eigen::VectorXd magnitudes =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H, Eigen::EigenvaluesOnly)
          .eigenvalues()
          .cwiseAbs();
  return magnitudes.maxCoeff() / magnitudes.minCoeff();
}

void SparseSystem::set_history_skew(const IncrementalPotential* potential) {
  if (!can_factorize_skew()) throw std::logic_error("SparseSystem: K needs the banded path");
  skew_ = potential != nullptr;
  if (!skew_) return;
  // K's blocks sit on the diagonal: their strict lower triangles, written in place (each
  // block is one rotation's, every entry of the band outside them stays 0 from resize()).
  double* w = band_.skew_values();
  potential->for_each_history_skew([&](int o, const Matrix3& K) {
    for (int c = 0; c < 3; ++c) {
      for (int r = c + 1; r < 3; ++r) w[band_.index(o + r, o + c)] = K(r, c);
    }
  });
}

bool SparseSystem::factorize(double mu) {
  if (factorization_ == Factorization::kBanded) {
    return skew_ ? band_.factorize_skew(mu) : band_.factorize(mu);
  }
  Cholmod& c = *cholmod_;
  double beta[2] = {mu, 0.0};  // factorise A + βI
  const int ok = cholmod_factorize_p(c.A, beta, nullptr, 0, c.L, &c.common);
  // LLᵀ stops at the first non-positive pivot and reports it through L->minor.
  return ok && c.common.status == CHOLMOD_OK && c.L->is_ll && c.L->minor == c.L->n;
}

void SparseSystem::solve(Vector& delta) {
  solve_linear(g_, delta);
  delta = -delta;
}

void SparseSystem::solve_linear_transposed(const Vector& b, Vector& solution) {
  if (factorization_ != Factorization::kBanded) return solve_linear(b, solution);  // symmetric
  solution = b;
  band_.solve_transposed(solution.data());
}

void SparseSystem::solve_linear(const Vector& b, Vector& solution) {
  if (factorization_ == Factorization::kBanded) {
    solution = b;
    band_.solve(solution.data());
    return;
  }
  // Triangular solves with the simplicial LLᵀ factor of P (H + μI) Pᵀ (natural ordering:
  // the permutation P of the blocks is ours). Written out because cholmod_solve2 reallocates
  // its workspace at every call in this version.
  Cholmod& c = *cholmod_;
  solution.resize(c.dofs);  // the adjoint's first solve hands an empty vector
  const auto* p = static_cast<const int*>(c.L->p);
  const auto* i = static_cast<const int*>(c.L->i);
  const auto* nz = static_cast<const int*>(c.L->nz);
  const auto* x = static_cast<const double*>(c.L->x);
  auto* y = static_cast<double*>(c.B->x);
  for (int block = 0; block < c.dofs / 3; ++block) {  // y = P b
    for (int r = 0; r < 3; ++r) y[3 * c.block_position[block] + r] = b[3 * block + r];
  }
  for (int j = 0; j < c.dofs; ++j) {  // L z = y; column j holds L_jj first, then rows > j
    y[j] /= x[p[j]];
    for (int k = p[j] + 1; k < p[j] + nz[j]; ++k) y[i[k]] -= x[k] * y[j];
  }
  for (int j = c.dofs - 1; j >= 0; --j) {  // Lᵀ w = z
    for (int k = p[j] + 1; k < p[j] + nz[j]; ++k) y[j] -= x[k] * y[i[k]];
    y[j] /= x[p[j]];
  }
  for (int block = 0; block < c.dofs / 3; ++block) {  // solution = Pᵀ w
    for (int r = 0; r < 3; ++r) solution[3 * block + r] = y[3 * c.block_position[block] + r];
  }
}

long SparseSystem::stored_nonzeros() const {
  switch (factorization()) {
    case Factorization::kUndecided:
      return 0;
    case Factorization::kBanded:
      return static_cast<long>(band_.value_count());
    case Factorization::kCholmod:
      break;
  }
  return static_cast<const int*>(cholmod_->A->p)[cholmod_->dofs];
}

}  // namespace liedyn

#pragma once
// The linear algebra of a Newton iteration: assemble the Lie gradient g and Hessian H of a
// component's incremental potential, factorise H + μI (Cholesky), solve δ = −(H + μI)⁻¹ g.
//
// Two implementations behind one interface, both allocation-free after their first use:
//   * DenseSystem<N>  — dense Hessian. N = 6 (one rigid body) uses a fixed-size, unrolled
//     Cholesky; N = Eigen::Dynamic uses Eigen::LLT. For a few coupled bodies.
//   * SparseSystem    — for rods and many coupled bodies. The first assembly records the
//     block pattern and picks one of two factorisations by their flop counts:
//       - banded (banded_cholesky.hpp), in the component's own DOF order, when that order
//         already has a narrow band (rods: half-bandwidth 8);
//       - CHOLMOD (SuiteSparse), simplicial LLᵀ otherwise: a fill-reducing order of the
//         blocks (CHOLMOD's AMD on the block graph), the upper triangle of the reordered
//         matrix in CSC form with the scatter index of every term block, and the symbolic
//         analysis, all once; each iteration refills the values, refactorises numerically in
//         place and does the two triangular solves itself.
//
// Interface used by Newton<System>:
//   using Vector;                                   // tangent vector type
//   double assemble(potential, q, double* roundoff, chart);  // Ψ(q); fills g and H, in the
//                                                   // rotation-vector chart if non-null
//   const Vector& gradient() const;
//   bool hessian_finite() const;
//   double hessian_scale() const;                   // max |H_ii|
//   bool can_factorize_skew() const;                // can M include K (below)?
//   static constexpr bool kReusesFactorizations;    // does a factorisation cost enough more
//                                                   // than a gradient pass that later steps
//                                                   // should reuse it (hessian_reuse)?
//   void set_history_skew(const IncrementalPotential* potential);  // M = H + μI + K from
//                                                   // now on, or H + μI (nullptr)
//   bool factorize(double mu);                      // M = H + μI: positive definite?
//   void solve(Vector& delta) ;                     // δ = −M⁻¹ g, last factorisation
//   void solve_linear(const Vector& b, Vector& x);  // x = M⁻¹ b
//   void solve_linear_transposed(const Vector& b, Vector& x);  // x = M⁻ᵀ b (the adjoint's)
//   void dense_hessian(Eigen::MatrixXd& H) const;   // H, dense and symmetric (for analysis)
//
// The trapezoidal integrator's Newton matrix is H + K, K = ½ hat(c) skew on each rotation
// block (IncrementalPotential::history_skew, solvers/newton.hpp). set_history_skew takes the
// potential's K into every later factorisation, which then factorises H + μI + K by LU without
// pivoting (banded_cholesky.hpp says why none is needed and what its pivots prove), one
// factorisation for all the solves of an iteration, with M⁻ᵀ from the same factors. Dense
// and banded systems can; CHOLMOD's path cannot and stays symmetric: CHOLMOD factorises
// symmetric matrices only, and a nonsymmetric one would need a sparse LU (both triangles of
// the reordered matrix, another SuiteSparse library: KLU or UMFPACK, their own analysis and
// solves), not written. There Newton and the adjoint keep their fixed-point iterations on
// H's factorisation.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <memory>

#include "../lib/incremental_potential.hpp"
#include "../manifolds/rotation_chart.hpp"
#include "banded_cholesky.hpp"

namespace liedyn {

// |λ|max/|λ|min of a symmetric matrix (dense eigendecomposition; infinite if singular).
double condition_number(const Eigen::MatrixXd& H);

template <int N>
class DenseSystem {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;

  explicit DenseSystem(const Component& component);

  double assemble(const IncrementalPotential& potential, const State& q, double* roundoff,
                  const RotationVectorChart* chart = nullptr) {
    DenseHessianSink<Matrix> sink{H_};
    return assemble_charted(potential, q, g_, sink, roundoff, chart);
  }
  const Vector& gradient() const { return g_; }
  bool hessian_finite() const;
  double hessian_scale() const;
  bool can_factorize_skew() const { return true; }
  // A dense factorisation of a few bodies costs about a gradient pass: reusing it saves less
  // than the chord steps' slower convergence costs (newton.hpp, "Reusing a factorisation").
  static constexpr bool kReusesFactorizations = false;
  void set_history_skew(const IncrementalPotential* potential);
  bool factorize(double mu);
  void solve(Vector& delta);
  void solve_linear(const Vector& b, Vector& x);
  void solve_linear_transposed(const Vector& b, Vector& x);
  void dense_hessian(Eigen::MatrixXd& H) const { H = H_; }

 private:
  Vector g_;
  Matrix H_;
  Matrix K_;       // the history's skew part, with set_history_skew
  bool skew_ = false;
  // Fixed size: the Cholesky factor of H + μI; dynamic: H + μI for llt_. With K: the LU
  // factors of H + μI + K (lu_skew in linear_system.cpp).
  Matrix factor_;
  Eigen::LLT<Matrix> llt_;
};

class SparseSystem {
 public:
  using Vector = Eigen::VectorXd;
  enum class Factorization { kUndecided, kBanded, kCholmod };

  // The banded factorisation is chosen when its flop count (Σ_j nnz(L_{:,j})²) is at most
  // this multiple of CHOLMOD's for its fill-reducing order: its unrolled loops do many more
  // flops per second than CHOLMOD's indexed ones. On the 963-DOF helix the band needs 1.25×
  // CHOLMOD's flops (77.6k against 62.0k) and factorisation + solve takes 35 µs against
  // 191 µs (BM_Rod_FactorizeSolve_*, CPU-time medians, Release, 2 GHz Xeon VM): ~7× per
  // flop, so 4 is a conservative crossover. (A spring chain: 1.5×, banded; a star: 20×,
  // CHOLMOD.)
  static constexpr double kBandedFlopAdvantage = 4.0;

  // Banded assembly on several threads (OpenMP) pays from about this many DOFs on: below,
  // the fork and join cost more than half an assembly saves. See assembly_threads.
  static constexpr int kParallelAssemblyMinDofs = 300;

  // `factorization` = kUndecided: chosen at the first assembly as described above; kBanded
  // or kCholmod: imposed (to compare the two, in tests and benchmarks).
  // `assembly_threads` (≥ 0): the banded system is assembled in that many parts, each a slice
  // of every term vector, on as many OpenMP threads; 0 chooses: 2 when the component has at
  // least kParallelAssemblyMinDofs DOFs and OpenMP may use 2 threads (omp_get_max_threads,
  // i.e. OMP_NUM_THREADS or the number of processors), else 1. The CHOLMOD path assembles
  // on one thread: its scatter follows the order of the blocks.
  explicit SparseSystem(const Component& component,
                        Factorization factorization = Factorization::kUndecided,
                        int assembly_threads = 1);
  SparseSystem(SparseSystem&&) noexcept;
  SparseSystem& operator=(SparseSystem&&) noexcept;
  ~SparseSystem();

  double assemble(const IncrementalPotential& potential, const State& q, double* roundoff,
                  const RotationVectorChart* chart = nullptr);
  const Vector& gradient() const { return g_; }
  bool hessian_finite() const;
  double hessian_scale() const;
  // Banded (known after the first assembly, which chooses the factorisation).
  bool can_factorize_skew() const { return factorization() == Factorization::kBanded; }
  // Rods and large couplings: assembly and factorisation are most of a step.
  static constexpr bool kReusesFactorizations = true;
  void set_history_skew(const IncrementalPotential* potential);
  bool factorize(double mu);
  void solve(Vector& delta);
  void solve_linear(const Vector& b, Vector& x);
  void solve_linear_transposed(const Vector& b, Vector& x);
  void dense_hessian(Eigen::MatrixXd& H) const;

  // Known after the first assembly (kUndecided before).
  Factorization factorization() const { return built_ ? factorization_ : Factorization::kUndecided; }
  // Non-zeros stored: the lower band (banded) or the upper triangle of the block-reordered
  // matrix (CHOLMOD); 0 before the first assembly.
  long stored_nonzeros() const;
  // Parts the assembly is split into (1: serial); known after the first assembly.
  int assembly_parts() const;

 private:
  struct Cholmod;  // CHOLMOD objects, kept out of this header
  struct BandScatter;
  struct ParallelAssembly;  // per-part buffers of the parallel banded assembly
  // After build(), banded only: sets up parallel_ if the assembly is to be split.
  void split_assembly(const IncrementalPotential& potential, const State& q);
  double assemble_in_parts(const IncrementalPotential& potential, const State& q,
                           double* roundoff, const RotationVectorChart* chart);
  // The pattern, from the blocks of one assembly; chooses the factorisation if not imposed.
  void build(const std::vector<std::pair<int, int>>& blocks);

  Vector g_;
  Factorization factorization_ = Factorization::kUndecided;  // chosen or imposed
  bool built_ = false;  // pattern known (after the first assembly)
  bool skew_ = false;   // banded, with set_history_skew: factorises H + μI + K
  BandedCholesky band_;
  std::unique_ptr<Cholmod> cholmod_;  // null when the banded factorisation is used
  int assembly_threads_ = 1;          // as requested (0: automatic)
  std::unique_ptr<ParallelAssembly> parallel_;  // null when assembling serially
};

extern template class DenseSystem<6>;
extern template class DenseSystem<Eigen::Dynamic>;

}  // namespace liedyn

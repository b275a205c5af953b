#pragma once
// The linear algebra of a Newton iteration: assemble the Lie gradient g and Hessian H of a
// component's incremental potential, factorise H + μI (Cholesky), solve δ = −(H + μI)⁻¹ g.
//
// Two implementations behind one interface, both allocation-free after their first use:
//   * DenseSystem<N>  — dense Hessian. N = 6 (one rigid body) uses a fixed-size, unrolled
//     Cholesky; N = Eigen::Dynamic uses Eigen::LLT. For a few coupled bodies.
//   * SparseSystem    — CHOLMOD (SuiteSparse), simplicial LLᵀ. At the first assembly: the
//     block pattern, a fill-reducing order of the blocks (CHOLMOD's AMD on the block graph),
//     the upper triangle of the reordered matrix in CSC form with the scatter index of every
//     term block, and the symbolic analysis. Each iteration then refills the values,
//     refactorises numerically in place and does the two triangular solves itself. For many
//     coupled bodies (and, later, rods).
//
// Interface used by Newton<System>:
//   using Vector;                                   // tangent vector type
//   double assemble(potential, q, double* roundoff);  // Ψ(q); fills g and H
//   const Vector& gradient() const;
//   bool hessian_finite() const;
//   double hessian_scale() const;                   // max |H_ii|
//   bool factorize(double mu);                      // H + μI positive definite?
//   void solve(Vector& delta) ;                     // δ = −(H + μI)⁻¹ g, last factorisation

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <memory>

#include "../lib/incremental_potential.hpp"

namespace liedyn {

template <int N>
class DenseSystem {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;

  explicit DenseSystem(const Component& component);

  double assemble(const IncrementalPotential& potential, const State& q, double* roundoff) {
    return potential.assemble(q, g_, H_, roundoff);
  }
  const Vector& gradient() const { return g_; }
  bool hessian_finite() const;
  double hessian_scale() const;
  bool factorize(double mu);
  void solve(Vector& delta);

 private:
  Vector g_;
  Matrix H_;
  Matrix factor_;  // fixed size: the Cholesky factor of H + μI; dynamic: H + μI for llt_
  Eigen::LLT<Matrix> llt_;
};

class SparseSystem {
 public:
  using Vector = Eigen::VectorXd;

  explicit SparseSystem(const Component& component);
  SparseSystem(SparseSystem&&) noexcept;
  SparseSystem& operator=(SparseSystem&&) noexcept;
  ~SparseSystem();

  double assemble(const IncrementalPotential& potential, const State& q, double* roundoff);
  const Vector& gradient() const { return g_; }
  bool hessian_finite() const;
  double hessian_scale() const;
  bool factorize(double mu);
  void solve(Vector& delta);

  // Non-zeros stored (upper triangle of the block-reordered matrix) once the pattern is
  // known; 0 before the first assembly.
  long stored_nonzeros() const;

 private:
  struct Cholmod;  // CHOLMOD objects, kept out of this header
  Vector g_;
  std::unique_ptr<Cholmod> cholmod_;
};

extern template class DenseSystem<6>;
extern template class DenseSystem<Eigen::Dynamic>;

}  // namespace liedyn

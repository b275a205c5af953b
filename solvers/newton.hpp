#pragma once
// Newton's method with backtracking line search on one component's incremental potential
// (paper §4.3, eq. 11):
//   H δ = −g   (Lie Hessian and Lie gradient),   x ← x + α δx,   R ← exp(α δθ) R.
// Rotations are re-orthonormalised after every update (DESIGN.md §4).
//
// Convergence: the Newton step at the current iterate satisfies ‖δ‖∞ ≤ tolerance, i.e. the
// quadratic model puts the minimiser within `tolerance` metres and radians. Unlike a
// gradient threshold this does not depend on the scale of masses, stiffnesses or h.
// The final gradient norm is reported beside it.
//
// Indefinite Hessians (compressed springs, large rotations against R̃): when the Cholesky
// factorisation fails, H + μI is factorised with μ = 10⁻⁸·max|H_ii| growing tenfold until
// it succeeds; such iterations are counted in StepReport::regularized_iterations and a
// regularised step never counts as converged.
//
// Memory: all buffers are sized in the constructor (the sparse pattern at the first
// assembly); later solves allocate nothing (tests/allocation_test.cpp).
// Linear algebra (solvers/linear_system.hpp): DenseSystem<6> for a single rigid body,
// DenseSystem<Dynamic> for a few bodies coupled by springs, SparseSystem (CHOLMOD) beyond
// Simulator::kDenseLimit coupled DOFs.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "../lib/incremental_potential.hpp"
#include "linear_system.hpp"

namespace liedyn {

struct NewtonOptions {
  // Convergence threshold on ‖δ‖∞, in metres and radians; > 0.
  double tolerance = 1e-9;
  // Newton updates allowed per time step; ≥ 1. With 1, every step does exactly one update
  // and is flagged unless that update already meets the tolerance.
  int max_iterations = 50;
  // Armijo sufficient-decrease constant c in Ψ(q ⊕ αδ) ≤ Ψ(q) + c α gᵀδ; in (0, 0.5).
  double armijo = 1e-4;
  // Smallest line-search step α before the step is declared failed; in (0, 1).
  double min_step_length = 1e-10;
  // Measure wall time of assembly and of factorisation + solve (StepReport). Off by
  // default: the clock reads cost ~10 % of a single rigid body's Newton iteration.
  bool measure_time = false;

  // Throws ModelError naming "solver.<field>".
  void validate() const;
};

enum class StepStatus {
  kConverged,         // tolerance met; state updated
  kMaxIterations,     // max_iterations updates without meeting the tolerance; state updated
  kLineSearchFailed,  // no decrease along the Newton direction; state NOT updated
  kNonFinite,         // NaN/Inf in Ψ, g, H or δ; state NOT updated
};

const char* to_string(StepStatus status);

struct StepReport {
  StepStatus status = StepStatus::kConverged;
  int iterations = 0;              // accepted Newton updates
  int regularized_iterations = 0;  // of which used H + μI
  int factorizations = 0;          // Cholesky factorisations, including retries
  double gradient_norm = 0.0;      // ‖g‖₂ at the final iterate
  double step_norm = 0.0;          // ‖δ‖∞ of the last Newton step computed
  int assemblies = 0;              // gradient + Hessian assemblies (iterations + final check)
  double assembly_seconds = 0.0;   // with NewtonOptions::measure_time: time in assemblies,
  double solve_seconds = 0.0;      // and in factorisations + triangular solves

  bool state_updated() const {
    return status == StepStatus::kConverged || status == StepStatus::kMaxIterations;
  }
  bool converged() const { return status == StepStatus::kConverged; }
  // Merges the report of another component of the same time step.
  void merge(const StepReport& other);
};

// Newton's method on one component, over a linear system type (solvers/linear_system.hpp).
template <class System>
class Newton {
 public:
  using Vector = typename System::Vector;

  Newton(Component component, const NewtonOptions& options);

  Component& component() { return component_; }
  const Component& component() const { return component_; }
  const System& system() const { return system_; }

  // Minimises the component's potential, starting from (and writing into) q.
  // On failure, q is restored to its value on entry.
  StepReport solve(State& q);

 private:
  // Factorises H, regularising if needed; false if even the regularised matrix fails.
  bool factorize(StepReport& report, bool& regularized);
  void save(const State& q);
  void restore(State& q) const;
  void retract(State& q, double alpha) const;

  Component component_;
  NewtonOptions options_;
  System system_;
  Vector delta_;
  std::vector<Vector3> saved_points_, entry_points_;
  std::vector<Matrix3> saved_rotations_, entry_rotations_;
};

// One rigid body (fixed size), a few coupled bodies (dense), many coupled bodies (CHOLMOD).
template <int N>
using DenseNewton = Newton<DenseSystem<N>>;
using SparseNewton = Newton<SparseSystem>;

extern template class Newton<DenseSystem<6>>;
extern template class Newton<DenseSystem<Eigen::Dynamic>>;
extern template class Newton<SparseSystem>;

}  // namespace liedyn

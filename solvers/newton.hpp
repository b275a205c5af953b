#pragma once
// Newton's method with backtracking line search on one component's incremental potential
// (paper §4.3, eq. 11):
//   H δ = −g   (Lie Hessian and Lie gradient),   x ← x + α δx,   R ← exp(α δθ) R.
// Rotations are re-orthonormalised after every update (DESIGN.md §4).
//
// Rotation parameterisations (NewtonOptions::rotation; paper §3.3, DESIGN.md §7), same
// potential, same tolerances, same line search:
//   * Lie (default): as above.
//   * Rotation vectors: each rotation is R = exp(r) with r = log(R) at the start of the
//     solve (so ‖r‖ ≤ π there: the re-wrapping between steps); the unknowns are the r's,
//     with derivatives J_l(r)ᵀ g and J_l(r)ᵀ H J_l(r) + C(r, g) (manifolds/rotation_chart.hpp),
//     and r ← r + α δr. Within a solve ‖r‖ may pass π.
//   * Quaternions: each rotation is R(q) (eq. A.21) of a unit quaternion q, from R at the
//     start of the solve; a step moves q along the unit sphere's tangent and renormalises,
//     q ← (q + α Q(q) δ)/‖·‖ (manifolds/quaternion.hpp). The derivatives with respect to δ at
//     δ = 0 are exactly the Lie ones; the update turns by 2 atan(α‖δ‖/2) instead of α‖δ‖.
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
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "../lib/incremental_potential.hpp"
#include "../manifolds/quaternion.hpp"
#include "../manifolds/rotation_chart.hpp"
#include "linear_system.hpp"

namespace liedyn {

enum class RotationParameterization { kLie, kRotationVector, kQuaternion };

// "lie", "rotvec", "quat" (the scene file's names), and back (nullopt for another name).
const char* to_string(RotationParameterization rotation);
std::optional<RotationParameterization> parse_rotation(std::string_view name);

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
  // Condition number of the first Hessian of every solve (StepReport): a dense symmetric
  // eigendecomposition, O(n³) — for analysis (liedyn compare), not for production runs.
  bool measure_condition = false;
  // Threads for assembling a banded (rod) system: n ≥ 1 uses n; 0 chooses (2 from
  // SparseSystem::kParallelAssemblyMinDofs DOFs on, when OpenMP may use 2). Dense systems and
  // CHOLMOD-factorised ones always assemble on one thread. One by default: on the 957-DOF
  // helix (2-vCPU VM) two threads saved only 10–20 % of an assembly, while OpenMP's waiting
  // thread keeps the second core busy for the whole run (README, Performance).
  int assembly_threads = 1;
  static constexpr int kMaxAssemblyThreads = 256;

  // How rotations are parameterised (see the top of this file).
  RotationParameterization rotation = RotationParameterization::kLie;

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
  // Paper Fig. 4's diagnostics, in the parameterisation's own coordinates: ‖g‖₂ at the first
  // and second assembly (NaN if there was none) and, with NewtonOptions::measure_condition,
  // the 2-norm condition number |λ|max/|λ|min of the first Hessian (NaN otherwise). Merged
  // over components: the largest.
  double first_gradient_norm = std::numeric_limits<double>::quiet_NaN();
  double second_gradient_norm = std::numeric_limits<double>::quiet_NaN();
  double first_hessian_condition = std::numeric_limits<double>::quiet_NaN();

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
  // Turns NewtonOptions::measure_condition on or off for the next solves.
  void set_measure_condition(bool on) { options_.measure_condition = on; }

  // Minimises the component's potential, starting from (and writing into) q.
  // On failure, q is restored to its value on entry.
  StepReport solve(State& q);

 private:
  // Factorises H, regularising if needed; false if even the regularised matrix fails.
  bool factorize(StepReport& report, bool& regularized);
  void save(const State& q);
  // |λ|max/|λ|min of the assembled Hessian (an infinite value if singular).
  double hessian_condition() const;
  void restore(State& q);
  void retract(State& q, double alpha);

  // Sets the rotation-vector or quaternion parameters from the rotations of q (and the
  // rotations from them, so that both agree exactly).
  void enter_parameterization(State& q);

  Component component_;
  NewtonOptions options_;
  System system_;
  Vector delta_;
  std::vector<Vector3> saved_points_, entry_points_;
  std::vector<Matrix3> saved_rotations_, entry_rotations_;
  // Rotation vectors: the chart (current and saved r's and J_l(r)'s).
  RotationVectorChart chart_;
  // Quaternions: current and saved, per rotation of the component.
  std::vector<quat::Vector4> quaternions_, saved_quaternions_;
};

// One rigid body (fixed size), a few coupled bodies (dense), many coupled bodies (CHOLMOD).
template <int N>
using DenseNewton = Newton<DenseSystem<N>>;
using SparseNewton = Newton<SparseSystem>;

extern template class Newton<DenseSystem<6>>;
extern template class Newton<DenseSystem<Eigen::Dynamic>>;
extern template class Newton<SparseSystem>;

}  // namespace liedyn

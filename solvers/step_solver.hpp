#pragma once
// One time step of one component: minimise its incremental potential
// Ψ(q; q_{k−1}, Δq_{k−1}) (paper §4.2) over positions and rotations. Three back-ends behind
// one interface, chosen by SolverOptions::backend (scene: "solver": {"backend": ...}):
//   * newton — our Newton solver on the exact Lie Hessian (solvers/newton.hpp);
//   * ceres  — Ψ as a nonlinear least-squares problem ½Σ‖r_t‖² over SO(3) manifolds
//              (solvers/ceres_step.hpp): Gauss–Newton/Levenberg–Marquardt, no residual
//              curvature;
//   * ipopt  — Ψ as an unconstrained NLP over tangent increments R = exp(θ) R₀ with the
//              exact gradient J_l(θ)ᵀ g and Hessian (solvers/ipopt_step.hpp), re-centred
//              between solves.
//
// One convergence test for all three, so that "converged" means the same thing whichever
// back-end ran: the Newton step of the exact Lie Hessian at the final state,
//   δ = −H⁻¹ g,   ‖δ‖∞ ≤ tolerance   with H positive definite (no regularisation),
// i.e. the quadratic model puts the minimiser within `tolerance` metres and radians. Newton
// evaluates it on its own iterates; Ceres and Ipopt stop on their own step sizes and are
// then checked with StepSolver::check, after each Ceres round or Ipopt solve (its cost is
// included in their time).

#include <chrono>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "../lib/incremental_potential.hpp"

namespace liedyn {

enum class Backend { kNewton, kCeres, kIpopt };
enum class RotationParameterization { kLie, kRotationVector, kQuaternion };
// How Newton judges an accepted update (newton.hpp, "Convergence"): "estimated" — the Newton
// step at the new iterate from the last factorisation, where the quadratic model predicted the
// update; "assembled" — always from a new assembly and factorisation there.
enum class ConvergenceCheck { kEstimated, kAssembled };

// The scene file's names ("newton", "ceres", "ipopt"; "lie", "rotvec", "quat") and back
// (nullopt for another name).
const char* to_string(Backend backend);
std::optional<Backend> parse_backend(std::string_view name);
const char* to_string(RotationParameterization rotation);
std::optional<RotationParameterization> parse_rotation(std::string_view name);
const char* to_string(ConvergenceCheck check);  // "estimated", "assembled"
std::optional<ConvergenceCheck> parse_convergence_check(std::string_view name);

// Components with more DOFs than this use sparse linear algebra (Newton: SparseSystem; Ceres:
// SPARSE_NORMAL_CHOLESKY); up to it, dense. Measured (BM_ChainIteration, one Newton iteration
// of a spring chain, Release, 2 GHz Xeon VM): dense/sparse 7.4/8.3 µs at 24 DOFs, 7.8/10.7 µs
// at 30, 14.4/12.7 µs at 36, 34/10 µs at 48, 625/54 µs at 192.
inline constexpr int kDenseLimit = 30;

struct CeresOptions {
  // "auto" (dense_qr up to kDenseLimit DOFs, sparse_normal_cholesky with SuiteSparse above),
  // "dense_qr", "dense_normal_cholesky", "sparse_normal_cholesky".
  std::string linear_solver = "auto";
  // "levenberg_marquardt" or "dogleg".
  std::string trust_region_strategy = "levenberg_marquardt";
  // How a rotation block is handed to Ceres under "rotation": "lie" (solvers/ceres_step.hpp):
  // "manifold" — 4 doubles, a unit quaternion on liedyn::SO3Manifold
  // (manifolds/so3_manifold.hpp); "chart" — 3 doubles θ, R = exp(θ) R₀ re-centred at every
  // solve. Ignored by rotvec and quat, which have their own storage. The manifold is the
  // default: measured against the chart, fewer stalls in about the same or less time on rods and
  // through contact (docs/design.md §9.3).
  std::string lie_blocks = "manifold";
  // Ceres's per-iteration progress on stdout.
  bool verbose = false;
};

struct IpoptOptions {
  // "exact" (the Lie Hessian through the chart) or "limited-memory" (Ipopt's L-BFGS).
  std::string hessian_approximation = "exact";
  // Ipopt's console output, 0 (silent) … 12. Its linear solver is MUMPS (the only one in
  // Debian's Ipopt).
  int print_level = 0;
  // Ipopt's derivative checker before every solve: "none", "first-order", "second-order"
  // (its findings go to the console or output_file; for tests and debugging).
  std::string derivative_test = "none";
  // If not empty, Ipopt also writes its log there at print level max(print_level, 5).
  std::string output_file;
  // Re-centrings R₀ ← R allowed per step (a new Ipopt solve each) before the step is
  // declared unconverged; ≥ 0.
  int max_recentrings = 3;
};

struct SolverOptions {
  Backend backend = Backend::kNewton;
  // Convergence threshold on ‖δ‖∞ (the Newton step above), in metres and radians; > 0.
  double tolerance = 1e-9;
  // Iterations allowed per time step (Newton updates, Ceres or Ipopt iterations); ≥ 1.
  // Newton with 1: every step does exactly one update and is flagged unless that update
  // already meets the tolerance.
  int max_iterations = 50;
  // Newton's Armijo sufficient-decrease constant c in Ψ(q ⊕ αδ) ≤ Ψ(q) + c α gᵀδ; in (0, 0.5).
  double armijo = 1e-4;
  // Newton's smallest line-search step α before the step is declared failed; in (0, 1).
  double min_step_length = 1e-10;
  // How Newton judges an update (ConvergenceCheck above; newton.hpp). Estimated by default: a
  // step that converges in one iteration then costs one assembly and one factorisation.
  ConvergenceCheck convergence_check = ConvergenceCheck::kEstimated;
  // How many time steps one factorisation of the Hessian may serve (Newton; newton.hpp,
  // "Reusing a factorisation"); ≥ 1. 1 (the default) factorises at every solve. N > 1 starts
  // a solve with the factorisation of a step at most N − 1 steps earlier in the run, and ends
  // it there when that chord step is within the tolerance; the other back-ends ignore it, as
  // they ignore convergence_check. Must be 1 with ConvergenceCheck::kAssembled (validate()).
  int hessian_reuse = 1;
  // Measure wall time of assembly and of factorisation + solve (StepReport; Newton). Off by
  // default: the clock reads cost ~10 % of a single rigid body's Newton iteration.
  bool measure_time = false;
  // Condition number of the first Hessian of every solve (StepReport; Newton): a dense
  // symmetric eigendecomposition, O(n³) — for analysis (liedyn compare), not for production.
  bool measure_condition = false;
  // Threads for assembling a banded (rod) system (Newton): n ≥ 1 uses n; 0 chooses (2 from
  // SparseSystem::kParallelAssemblyMinDofs DOFs on, when OpenMP may use 2). Dense systems and
  // CHOLMOD-factorised ones always assemble on one thread. One by default: on the 957-DOF
  // helix (2-vCPU VM) two threads saved only 10–20 % of an assembly, while OpenMP's waiting
  // thread keeps the second core busy for the whole run (README, Performance).
  int assembly_threads = 1;
  static constexpr int kMaxAssemblyThreads = 256;
  // Threads for the independent components ("islands") of a step (Simulator::step): n ≥ 1
  // uses up to n, one island per thread at a time; 0 chooses (as many as OpenMP may use).
  // Islands of one step share nothing but the read-only model, so their solves run
  // concurrently with the same results as in sequence. Ipopt's islands always run in
  // sequence: its MUMPS (Debian's sequential build) is not known to be re-entrant. One by
  // default; when it pays: README, Performance.
  int island_threads = 1;

  // How rotations are parameterised (newton.hpp; Ceres: ceres_step.hpp). Ipopt supports lie
  // and rotvec.
  RotationParameterization rotation = RotationParameterization::kLie;

  CeresOptions ceres;
  IpoptOptions ipopt;

  // Throws ModelError naming "solver.<field>".
  void validate() const;
};

// StepReport::merge keeps the worst (last listed) status of a step's components.
enum class StepStatus {
  kConverged,         // tolerance met; state updated
  kMaxIterations,     // iterations used up without meeting the tolerance; state updated
  kStalled,           // stopped short of the tolerance with iterations left, because the
                      // iterates stopped improving (Newton: see newton.hpp; Ceres: a round
                      // accepted no step; Ipopt: its search direction became too small);
                      // state updated
  kLineSearchFailed,  // Newton: no decrease along the Newton direction; state NOT updated
  kNonFinite,         // NaN/Inf in Ψ, g, H or δ, or in the new state, its Ψ, ‖g‖ or the
                      // kinetic energy of the step (StepSolver::solve); state NOT updated
  kSolverFailed,      // Ceres or Ipopt reported an error (StepReport::message); NOT updated
};

const char* to_string(StepStatus status);

struct StepReport {
  StepStatus status = StepStatus::kConverged;
  int iterations = 0;              // accepted Newton updates / Ceres or Ipopt iterations
  int regularized_iterations = 0;  // Newton: of which used H + μI
  int factorizations = 0;          // Cholesky factorisations, including retries (Newton, check)
  double gradient_norm = 0.0;      // ‖g‖₂ at the final iterate (Lie gradient for Ceres/Ipopt)
  double step_norm = 0.0;          // ‖δ‖∞ of the last Newton step computed
  int assemblies = 0;              // gradient + Hessian assemblies (iterations + final check)
  double assembly_seconds = 0.0;   // with SolverOptions::measure_time: time in assemblies,
  double solve_seconds = 0.0;      // and in factorisations + triangular solves. Ceres: its
                                   // residual + Jacobian evaluation time, and its linear-solver
                                   // time; Ipopt: our evaluations, and the rest of its wall
                                   // time; both plus their checks'. Not comparable across
                                   // back-ends (liedyn compare shows them for Newton only).
  // Paper Fig. 4's diagnostics, in the parameterisation's own coordinates: ‖g‖₂ at the first
  // and second assembly (NaN if there was none) and, with SolverOptions::measure_condition,
  // the 2-norm condition number |λ|max/|λ|min of the first Hessian (NaN otherwise). Merged
  // over components: the largest.
  double first_gradient_norm = std::numeric_limits<double>::quiet_NaN();
  double second_gradient_norm = std::numeric_limits<double>::quiet_NaN();
  double first_hessian_condition = std::numeric_limits<double>::quiet_NaN();
  // Ψ at the final state (from the last assembly there; NaN if the step failed before one).
  // Merged over components: the sum.
  double psi = std::numeric_limits<double>::quiet_NaN();
  // Exact joints (StepSolver::solve): the largest violation ‖c‖∞ (m or rad) at the final
  // state, 0 without exact joints, and the multiplier updates (the back-end's solves after
  // the first). Merged over components: the largest.
  double constraint_violation = 0.0;
  int multiplier_updates = 0;
  // The trapezoidal integrator (StepSolver::solve): the solves after the first that moved the
  // torque fields' references, and how far (rad) the last move was. Merged: the largest.
  int history_updates = 0;
  double history_moved = 0.0;
  // Newton with SolverOptions::hessian_reuse > 1 (newton.hpp): the solves that ended with a
  // chord step on a reused factorisation (summed over a step's solves and components), and
  // the largest measured relative error of such a step, ‖δ̃ − δ‖∞/‖δ‖∞, where a new
  // factorisation met the old one (0 where none was measured). Merged: the sum, the largest.
  int reused_factorizations = 0;
  double reuse_error = 0.0;
  // Why the step did not converge, when there is more to say than the status: the
  // back-end's own termination (Ceres, Ipopt), what stalled, what was not finite (else
  // empty).
  std::string message;

  bool state_updated() const {
    return status == StepStatus::kConverged || status == StepStatus::kMaxIterations ||
           status == StepStatus::kStalled;
  }
  bool converged() const { return status == StepStatus::kConverged; }
  // Merges the report of another component of the same time step.
  void merge(const StepReport& other);
  // Adds a later solve of the same step (a multiplier or history update, a contact round):
  // counts summed, status and final values from `next`, the first-iteration diagnostics of
  // the earliest solve that has them. A default report is its identity.
  void accumulate(StepReport next);
};

// The positions and rotations of a component's DOF blocks, copied out of a State and back: a
// failed solve restores its entry state, Newton's line search its last iterate. Sized at
// construction; save and restore never allocate.
class ComponentSnapshot {
 public:
  ComponentSnapshot() = default;
  explicit ComponentSnapshot(const Component& c)
      : points_(c.points.size()), rotations_(c.rotations.size()) {}
  void save(const Component& c, const State& q) {
    for (std::size_t i = 0; i < c.points.size(); ++i) points_[i] = q.points[c.points[i].index];
    for (std::size_t i = 0; i < c.rotations.size(); ++i) {
      rotations_[i] = q.rotations[c.rotations[i].index];
    }
  }
  void restore(const Component& c, State& q) const {
    for (std::size_t i = 0; i < c.points.size(); ++i) q.points[c.points[i].index] = points_[i];
    for (std::size_t i = 0; i < c.rotations.size(); ++i) {
      q.rotations[c.rotations[i].index] = rotations_[i];
    }
  }
  // The saved value of the component's i-th point block and rotation block.
  const Vector3& point(std::size_t i) const { return points_[i]; }
  const Matrix3& rotation(std::size_t i) const { return rotations_[i]; }

 private:
  std::vector<Vector3> points_;
  std::vector<Matrix3> rotations_;
};

// x with three significant digits ("%.3g"), for back-end messages.
std::string short_number(double x);

// Wall time since `start`, in seconds (the back-ends' and the adjoint's timings).
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

class StepSolver {
 public:
  virtual ~StepSolver() = default;

  // The component whose potential is minimised (the simulator calls begin_step and
  // set_load_scale on it before each solve).
  virtual Component& component() = 0;
  virtual const Component& component() const = 0;

  // Minimises the component's potential, starting from (and writing into) q. On failure
  // (state_updated() false), q is restored to its value on entry.
  //
  // Exact joints (compliance 0; term.hpp, Constraint) are enforced by an augmented
  // Lagrangian loop around the back-end's minimisation, the same for the three back-ends:
  // after each solve, while the largest violation ‖c‖∞ exceeds the tolerance (metres and
  // radians, as for the Newton step), every multiplier is updated, s ← s + c, and the
  // back-end solves again from where it stopped — at most kMaxMultiplierUpdates times per
  // step. Where a violation has not fallen below a tenth of the previous one, the penalties
  // are raised tenfold (at most kMaxPenaltyGrowth over the initial ones). The multipliers are
  // kept from step to step: the joint's force changes little per step, so most steps need
  // one update or none. A step that is left with a violation above the tolerance (or whose
  // last solve did not converge) is not converged: status kMaxIterations, with a message.
  //
  // The trapezoidal integrator's rotation history (lib/history.hpp) is a torque field exact at
  // a reference rotation: after each solve (and its exact-joint loop) every reference moves to
  // where the solve ended, and while one moved more than the tolerance (radians) the back-end
  // solves again from there, at most kMaxHistoryUpdates times; a step left with a larger move
  // is not converged (kMaxIterations, with a message). Each solve contracts the move by about
  // ½ ω h (the step's rotation angle over two).
  //
  // Every back-end's result passes one test here, so that no back-end can report a
  // non-finite outcome as a step: a step the back-end reports as done (state_updated()) is
  // turned into kNonFinite, with q restored and StepReport::message naming the value, when
  // any coordinate of the component's new positions or rotations, Ψ there
  // (StepReport::psi), ‖g‖ (gradient_norm: an overflow of ‖g‖₂ counts, the gradient is then
  // beyond what the reports can hold) or step_norm is not finite, or when the kinetic
  // energy of the move from the state this solver last returned to the new one is not
  // (translational ½ (m/h²)‖Δx‖² and rotational ½ θᵀ (I/h²) θ of the inertia terms,
  // θ = log(R Rₚᵀ) in the body frame; the simulator's q_{k−1}, so this is the kinetic
  // energy the simulator reports; not tested at the first solve, which has no such state).
  // Ψ being finite covers the potential energy: its terms are among Ψ's.
  StepReport solve(State& q);

  // The convergence test above at q, without moving q: status kConverged or kMaxIterations
  // (kNonFinite if Ψ, g or H is not finite), gradient_norm, step_norm and psi set.
  virtual StepReport check(State& q) = 0;

  // SolverOptions::measure_condition for the next solves (Newton only; others ignore it).
  virtual void set_measure_condition(bool) {}

  static constexpr int kMaxMultiplierUpdates = 30;
  static constexpr int kMaxHistoryUpdates = 30;
  static constexpr double kMaxPenaltyGrowth = 1e6;

 protected:
  explicit StepSolver(const SolverOptions& options) : tolerance_(options.tolerance) {}

  // The back-end's minimisation behind solve() (same contract, before the test).
  virtual StepReport minimize(State& q) = 0;

 private:
  // The name of the first non-finite value of the test in solve(), or nullptr.
  const char* non_finite_value(const StepReport& report, const State& q) const;
  // The augmented Lagrangian loop above, after the first minimisation gave `report`.
  void enforce_exact_constraints(State& q, StepReport& report);

  double tolerance_;
  bool has_exact_constraints_ = false;
  double penalty_growth_ = 1.0;  // the penalties' factor over their initial values

  // Sized at the first solve (solve allocates nothing after it).
  bool sized_ = false;
  ComponentSnapshot entry_;     // q on entry, restored when the test rejects a step
  ComponentSnapshot returned_;  // the component's blocks as the last successful solve left them
  bool has_returned_ = false;
  std::vector<int> inertia_point_;     // per translational inertia term: its point's block
  std::vector<int> inertia_rotation_;  // per rotational inertia term: its rotation's block
  // Σ π² tr(J/h²) over those rotations, the bound of their kinetic energy (non_finite_value).
  double rotation_energy_bound_ = 0.0;
};

// The step solver for `component` that `options` choose (options validated by the caller):
// Newton on a DenseSystem<6>, DenseSystem<Dynamic> or SparseSystem by size, or Ceres or Ipopt.
std::unique_ptr<StepSolver> make_step_solver(Component component, const SolverOptions& options);

}  // namespace liedyn

#pragma once
// The outer optimisers of trajectory optimisation (docs/design.md §11): three L-BFGS back-ends
// behind one function, with the same objective, gradient and stopping rule, so that they can
// be compared on the same problem.
//
// Problem. Minimise a loss f(x) over parameters x ∈ Rⁿ (initial velocities, per-frame forces,
// rest shape, …). One call of the objective returns f(x) and its exact gradient ∇f(x) — for
// a trajectory, one forward simulation and one adjoint pass (docs/design.md §8), typically
// 1–100 ms: evaluations are what counts. The back-ends' own work is O(m n) per iteration for
// memory m, except Ipopt's fixed bookkeeping of about 1 ms per iteration and more (a KKT
// factorisation, timing, option look-ups), which dominates for cheap objectives.
//
// Normalised loss. The caller gives a scale s = loss_scale > 0 (f(x₀), or a physical scale
// such as the squared size of the target), and ℓ(x) = f(x)/s is what the back-ends see and
// minimise (same minimiser, gradient ∇ℓ = ∇f/s). This makes every absolute tolerance inside
// a back-end relative to s — in particular NLopt's L-BFGS stops, by a test we cannot change,
// once ‖∇ℓ‖∞ ≤ 1e-8 (PLIS's TOLG), which on the raw loss of a problem in metres and seconds
// (f ~ 1e-6) would end the run at once. Everything reported (Evaluation,
// OptimizationResult) gives the raw loss f, and the normalised loss ℓ beside it.
//
// L-BFGS. Each back-end keeps the m = lbfgs_memory latest pairs s_k = x_{k+1} − x_k,
// y_k = ∇ℓ(x_{k+1}) − ∇ℓ(x_k), applies the inverse-Hessian approximation H_k built from them
// on H⁰ = γ I, γ = sᵀy / yᵀy of the latest pair (Nocedal & Wright, Numerical Optimization,
// eq. 7.20 — set explicitly for Ceres and Ipopt, whose defaults differ and cost 2–5× the
// evaluations, see optimizer.cpp), to −∇ℓ, and searches along that direction:
//   nlopt-lbfgs — NLopt 2.7 NLOPT_LD_LBFGS: Lukšan's PLIS (limited-memory variable metric by
//                 Strang's recurrences) with its own line search. The default.
//   ceres-lbfgs — Ceres 2.1 GradientProblemSolver: line_search_direction_type LBFGS,
//                 line_search_type WOLFE (strong Wolfe conditions), Euclidean (no manifold),
//                 use_approximate_eigenvalue_bfgs_scaling.
//   ipopt-lbfgs — Ipopt 3.11 on the NLP min ℓ(x) with m = 0 constraints and no bounds
//                 (±2e19, beyond nlp_lower/upper_bound_inf): no barrier terms remain, and
//                 Ipopt is a line-search quasi-Newton method with hessian_approximation
//                 limited-memory (limited_memory_initialization scalar2, B⁰ = I/γ), a KKT
//                 solve by MUMPS per iteration and filter (Armijo) backtracking.
//
// Iterations. What one iteration is depends on the back-end, and both counts are reported:
//   ceres  — an accepted line-search step (IterationCallback / Summary::iterations);
//   ipopt  — Ipopt's iter_count (intermediate_callback), its restoration phase included;
//   nlopt  — NLopt has no iteration hook: there an iteration is an evaluation, and
//            `max_iterations` caps evaluations. Lukšan's L-BFGS usually accepts the first
//            trial step, so that is nearly one iteration per evaluation.
// `max_iterations` becomes Ceres's max_num_iterations, Ipopt's max_iter and NLopt's maxeval
// (enforced by the wrapper too: NLopt checks its cap only between line searches).
//
// Stopping rule, the same for all: stop once the best normalised loss ever evaluated is
// ≤ target_normalized_loss (NLopt: stopval = target, on ℓ; Ceres: an IterationCallback
// returning SOLVER_TERMINATE_SUCCESSFULLY; Ipopt: intermediate_callback returning false), or
// after max_iterations. Ceres and Ipopt test between iterations, NLopt between line searches.
// The back-ends' own tests are switched off as far as they can be, except genuine
// convergence, a stationary point: ‖∇ℓ‖∞ ≤ kStationaryGradient = 1e-8 — NLopt's fixed
// tolerance, given to Ceres as gradient_tolerance and to Ipopt as tol (acceptable_iter 0:
// no "acceptable" termination). What is left of their other tests detects only a stall:
// Ceres's function_tolerance and parameter_tolerance are 0 (an iteration that changed
// nothing), NLopt's relative tolerances are at PLIS's floors (f change ≤ 1e-14, x change
// ≤ 1e-16, twice in a row). Ipopt has no stall test: where round-off hides every decrease it
// keeps iterating (to max_iterations, or until ‖∇ℓ‖∞ ≤ 1e-8 after all).
// Best point. The wrapper keeps the point with the lowest loss over all evaluations
// (line-search trial points included) and returns it, whatever the back-end returns. A
// point asked for twice in a row is served from a one-point cache and not evaluated again:
// Ipopt asks for f (eval_f) and then ∇f (eval_grad_f) at every accepted point, which without
// the cache would double its evaluations (Ceres 2.1 and NLopt never ask twice).
//
// Failures. If f throws a std::exception, or returns a loss or gradient that is not finite,
// the back-end is stopped at once (later requests are refused without calling f: NLopt is
// force-stopped, Ceres and Ipopt are told that the evaluation failed, and stop at their next
// check), and minimize returns status "failed" with the exception's what() (or a message
// naming the evaluation and the non-finite value) and the best point of the evaluations
// before. An exception thrown by on_evaluation is handled the same way (its evaluation
// counts, and its point may be the best). Exceptions not derived from std::exception are
// rethrown by minimize once the back-end has returned. Bad input (options, loss_scale, x0)
// throws std::invalid_argument.
//
// Statuses (OptimizationResult::status), in this order of precedence:
//   "failed"           — f or on_evaluation threw, returned a non-finite value, or a back-end
//                        error (invalid options, out of memory, an Ipopt error status);
//   "target_reached"   — best normalised loss ≤ target (reached_target is set whenever that
//                        holds, even with "failed");
//   "max_iterations"   — NLopt maxeval, Ceres NO_CONVERGENCE, Ipopt Maximum_Iterations_Exceeded;
//   "converged"        — a stationary point by the back-end's own test (above): NLopt SUCCESS,
//                        Ceres CONVERGENCE with ‖∇ℓ‖∞ ≤ 1e-8, Ipopt Solve_Succeeded (or
//                        Solved_To_Acceptable_Level, switched off);
//   "roundoff_limited" — no further progress, not at a stationary point: the line search found
//                        no acceptable step or the iterate stopped changing — round-off near
//                        a minimum, or a gradient inconsistent with the loss. NLopt
//                        ROUNDOFF_LIMITED, FAILURE (from PLIS: its line search failed even
//                        after a steepest-descent restart), FTOL/XTOL_REACHED at its floors;
//                        Ceres FAILURE (line search) or CONVERGENCE by a zero change; Ipopt
//                        Search_Direction_Becomes_Too_Small or Restoration_Failed (for an
//                        unconstrained NLP its restoration phase runs only when the line
//                        search fails).
// OptimizationResult::message keeps the back-end's raw status and message.
//
// Allocation. The wrapper evaluates into preallocated vectors (x, gradient, best x): no
// allocation per evaluation beyond what the objective and the back-ends do themselves
// (Ceres builds a few vectors per line search; Ipopt allocates within its iterations).

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace liedyn {

enum class Optimizer {
  kNloptLbfgs,  // "nlopt-lbfgs" (default)
  kCeresLbfgs,  // "ceres-lbfgs"
  kIpoptLbfgs,  // "ipopt-lbfgs"
};
const char* to_string(Optimizer optimizer);
std::optional<Optimizer> parse_optimizer(std::string_view name);  // nullopt: unknown name

// ‖∇ℓ‖∞ at which every back-end may report "converged" (see the header comment).
inline constexpr double kStationaryGradient = 1e-8;

struct OptimizerOptions {
  Optimizer optimizer = Optimizer::kNloptLbfgs;
  // ≥ 1. Iterations of the back-end (evaluations for NLopt, see above).
  int max_iterations = 100;
  // ≥ 0, finite. Stop once f/loss_scale ≤ this; 0: never (run to max_iterations or the
  // back-end's own convergence).
  double target_normalized_loss = 1e-3;
  // ≥ 1. L-BFGS history m: NLopt vector_storage, Ceres max_lbfgs_rank, Ipopt
  // limited_memory_max_history.
  int lbfgs_memory = 10;
  // x0 is where an earlier run of the same problem got to (`liedyn optimize --resume`: the
  // checkpoint's best point), not a first guess. Only Ipopt uses it: its interior-point
  // start is then tuned to continue rather than begin (monotone barrier from a small μ, x0
  // kept where it is; optimizer.cpp gives the reason and the measurements). NLopt and Ceres
  // start at x0 as given either way. false: today's start (Ipopt's adaptive barrier).
  bool warm_start = false;

  // Throws ModelError (a std::invalid_argument) whose what() names the field as
  // "optimization.<field>", its value and the rule.
  void validate() const;
};

// Box bounds lower_i ≤ x_i ≤ upper_i (±∞: none on that side); empty vectors: none at all.
//   nlopt-lbfgs — PLIS is a bound-constrained method (NLopt set_lower/upper_bounds): steps
//                 stay in the box, and "converged" is a stationary point of the box problem.
//   ipopt-lbfgs — the bounds enter the NLP: log-barrier terms keep iterates strictly inside
//                 (a start on or near a bound is pushed in by bound_push, 1e-2
//                 by default, 1e-9 with warm_start), "converged" is the KKT
//                 point at tol.
//   ceres-lbfgs — GradientProblemSolver is unconstrained: minimize rejects finite bounds.
// x0 must lie within them.
struct Bounds {
  Eigen::VectorXd lower, upper;
  bool empty() const { return lower.size() == 0 && upper.size() == 0; }
};
// Why a bounded problem is refused for Ceres (minimize, and `liedyn optimize` before it).
inline constexpr const char* kCeresHasNoBounds =
    "ceres-lbfgs cannot respect bounds (Ceres's GradientProblemSolver is unconstrained): use "
    "nlopt-lbfgs or ipopt-lbfgs";

// Returns f(x) and writes ∇f(x) into `gradient` (already sized like x; do not resize it).
// May throw std::exception (e.g. a forward simulation step that did not converge).
using ObjectiveFunction =
    std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd& gradient)>;

// Thrown by an objective for a point it cannot evaluate, typically a line-search trial step
// so long that the simulation is not defined there (a forward time step that does not
// converge, an initial angular velocity beyond π per step). Ceres and Ipopt are told that
// the evaluation failed and shorten their step (Ceres's line search contracts, Ipopt "cuts
// back alpha"); NLopt has no such mechanism, so there it is a failure like any other
// exception. Infeasible points do not count as the best point; their number and the last
// message are appended to OptimizationResult::message.
class InfeasiblePoint : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One successful evaluation of f, as reported to an EvaluationCallback.
struct Evaluation {
  int evaluation = 0;            // 1, 2, …: calls of f so far, including this one
  int iteration = 0;             // back-end iterations completed before this evaluation
  double loss = 0.0;             // f(x)
  double normalized_loss = 0.0;  // f(x) / loss_scale
  double gradient_norm = 0.0;    // ‖∇f(x)‖₂ (raw, not normalised)
  double seconds = 0.0;          // wall time since minimize() started
};
// Called after every successful evaluation (history files, checkpoints), with the point and
// the raw gradient ∇f(x). Failed evaluations (a throw, a non-finite value, an InfeasiblePoint
// that Ceres or Ipopt step back from) are not reported; they count, so after an infeasible
// point Evaluation::evaluation skips a number.
using EvaluationCallback = std::function<void(const Evaluation&, const Eigen::VectorXd& x,
                                              const Eigen::VectorXd& gradient)>;

struct OptimizationResult {
  Eigen::VectorXd best_x;             // lowest loss ever evaluated (x0 if no evaluation succeeded)
  double best_loss = 0.0;             // f(best_x); +∞ if no evaluation succeeded
  double best_normalized_loss = 0.0;  // best_loss / loss_scale
  int iterations = 0;                 // back-end iterations (NLopt: = evaluations)
  int evaluations = 0;                // calls of f, failed ones included
  bool reached_target = false;        // target > 0 and best_normalized_loss ≤ target
  // "target_reached", "max_iterations", "roundoff_limited", "converged", "failed" (see above).
  std::string status;
  std::string message;   // the back-end's raw status and message / the error
  double seconds = 0.0;  // wall time of minimize()
};

// Minimises f from x0 (finite, non-empty) with the back-end options.optimizer, within
// `bounds`, reporting each evaluation to on_evaluation; normalised loss = loss / loss_scale
// (finite, > 0). Throws std::invalid_argument for bad options, loss_scale, x0 or bounds
// (sizes other than x0's, NaN, lower ≥ upper, x0 outside, or any finite bound for Ceres);
// never throws for a failure of f that is a std::exception (status "failed").
OptimizationResult minimize(const ObjectiveFunction& f, const Eigen::VectorXd& x0,
                            double loss_scale, const OptimizerOptions& options,
                            const EvaluationCallback& on_evaluation = {},
                            const Bounds& bounds = {});

}  // namespace liedyn

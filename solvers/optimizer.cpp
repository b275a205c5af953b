#include "optimizer.hpp"
#include "ipopt_lock.hpp"
#include "ipopt_status.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <coin/IpIpoptApplication.hpp>
#include <coin/IpTNLP.hpp>
#include <exception>
#include <limits>
#include <nlopt.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "../lib/model.hpp"
#include "ceres_step.hpp"
#include "step_solver.hpp"  // short_number

namespace liedyn {

const char* to_string(Optimizer optimizer) {
  switch (optimizer) {
    case Optimizer::kNloptLbfgs: return "nlopt-lbfgs";
    case Optimizer::kCeresLbfgs: return "ceres-lbfgs";
    case Optimizer::kIpoptLbfgs: return "ipopt-lbfgs";
  }
  return "unknown";
}

std::optional<Optimizer> parse_optimizer(std::string_view name) {
  for (const auto o : {Optimizer::kNloptLbfgs, Optimizer::kCeresLbfgs, Optimizer::kIpoptLbfgs}) {
    if (name == to_string(o)) return o;
  }
  return std::nullopt;
}

void OptimizerOptions::validate() const {
  if (optimizer != Optimizer::kNloptLbfgs && optimizer != Optimizer::kCeresLbfgs &&
      optimizer != Optimizer::kIpoptLbfgs) {
    throw ModelError("optimization.optimizer",
                     "unknown optimizer " + std::to_string(static_cast<int>(optimizer)) +
                         " (expected nlopt-lbfgs, ceres-lbfgs or ipopt-lbfgs)");
  }
  if (max_iterations < 1) {
    throw ModelError("optimization.max_iterations",
                     "must be at least 1 (got " + std::to_string(max_iterations) + ")");
  }
  if (!(target_normalized_loss >= 0.0) || !std::isfinite(target_normalized_loss)) {
    throw ModelError("optimization.target_normalized_loss",
                     "must be a finite number >= 0 (got " + short_number(target_normalized_loss) +
                         "; 0: no target)");
  }
  if (lbfgs_memory < 1) {
    throw ModelError("optimization.lbfgs_memory",
                     "must be at least 1 (got " + std::to_string(lbfgs_memory) + ")");
  }
}

namespace {

using Clock = std::chrono::steady_clock;

// ---------------------------------------------------------------------------------------
// What the three back-ends share: one evaluation of ℓ = f / loss_scale and ∇ℓ at a point,
// the best point, the counters, the callback, and the conversion of a failure of f into a
// stop (see the header). Not thread-safe (the back-ends evaluate serially).
class Evaluator {
 public:
  Evaluator(const ObjectiveFunction& f, const Eigen::VectorXd& x0, double loss_scale,
            double target, const EvaluationCallback& on_evaluation, Clock::time_point start)
      : f_(f),
        on_evaluation_(on_evaluation),
        loss_scale_(loss_scale),
        target_(target),
        start_(start),
        x_(x0),
        gradient_(x0.size()),
        best_x_(x0) {}

  // NLopt: an iteration is an evaluation, and at most `cap` evaluations are made.
  void count_evaluations_as_iterations(int cap) {
    evaluations_are_iterations_ = true;
    cap_ = cap;
  }
  void set_iterations(int iterations) { iterations_ = std::max(iterations_, iterations); }
  // Ceres and Ipopt: an InfeasiblePoint is a failed evaluation the back-end recovers from.
  void recover_from_infeasible_points() { recover_infeasible_ = true; }
  int infeasible_points() const { return infeasible_points_; }
  const std::string& last_infeasible() const { return last_infeasible_; }

  // ℓ(x) into `normalized_loss` and, if `normalized_gradient` is not null, ∇ℓ(x) into it
  // (n doubles). Returns false, without calling f, once stopped (a failure, or NLopt's cap).
  bool evaluate(const double* x, double& normalized_loss, double* normalized_gradient) {
    const Eigen::Index n = x_.size();
    if (stopped_) return false;
    if (!cached_ || !std::equal(x, x + n, x_.data())) {
      cached_ = false;
      if (!call(x)) return false;
      cached_ = true;
    }
    normalized_loss = loss_ / loss_scale_;
    if (normalized_gradient != nullptr) {
      Eigen::Map<Eigen::VectorXd>(normalized_gradient, n) = gradient_ / loss_scale_;
    }
    return true;
  }

  bool stopped() const { return stopped_; }
  bool failed() const { return failed_; }
  bool cap_reached() const { return cap_reached_; }
  bool target_reached() const { return target_ > 0.0 && best_loss_ / loss_scale_ <= target_; }
  const std::string& error() const { return error_; }
  const std::exception_ptr& foreign_exception() const { return foreign_exception_; }
  int evaluations() const { return evaluations_; }
  int iterations() const { return evaluations_are_iterations_ ? evaluations_ : iterations_; }
  const Eigen::VectorXd& best_x() const { return best_x_; }
  double best_loss() const { return best_loss_; }

 private:
  // One call of f at x (copied into x_), then the bookkeeping. False: f failed.
  bool call(const double* x) {
    const Eigen::Index n = x_.size();
    std::copy(x, x + n, x_.data());
    Evaluation e;
    e.iteration = evaluations_are_iterations_ ? evaluations_ : iterations_;
    e.evaluation = ++evaluations_;
    try {
      loss_ = f_(x_, gradient_);
    } catch (const InfeasiblePoint& error) {
      if (!recover_infeasible_) return fail(error.what());
      ++infeasible_points_;
      last_infeasible_ = error.what();
      return false;  // not stopped: the back-end shortens its step
    } catch (const std::exception& error) {
      return fail(error.what());
    } catch (...) {
      foreign_exception_ = std::current_exception();
      return fail("the objective threw an exception not derived from std::exception");
    }
    const auto at = [&e] { return " at evaluation " + std::to_string(e.evaluation); };
    if (gradient_.size() != n) {
      return fail("the objective resized its gradient to " + std::to_string(gradient_.size()) +
                  " entries (expected " + std::to_string(n) + ")" + at());
    }
    if (!std::isfinite(loss_)) {
      return fail("the objective returned a loss of " + short_number(loss_) + at());
    }
    if (!gradient_.allFinite()) {
      Eigen::Index i = 0;
      while (std::isfinite(gradient_[i])) ++i;
      return fail("the objective returned a gradient entry [" + std::to_string(i) +
                  "] = " + short_number(gradient_[i]) + at());
    }
    if (loss_ < best_loss_) {
      best_loss_ = loss_;
      best_x_ = x_;  // same size: a copy, no allocation
    }
    if (cap_ > 0 && evaluations_ >= cap_) {
      cap_reached_ = true;
      stopped_ = true;  // refuse later requests; this value still goes to the back-end
    }
    if (on_evaluation_) {
      e.loss = loss_;
      e.normalized_loss = loss_ / loss_scale_;
      e.gradient_norm = gradient_.norm();
      e.seconds = std::chrono::duration<double>(Clock::now() - start_).count();
      try {
        on_evaluation_(e, x_, gradient_);
      } catch (const std::exception& error) {
        return fail(std::string("on_evaluation: ") + error.what());
      } catch (...) {
        foreign_exception_ = std::current_exception();
        return fail("on_evaluation threw an exception not derived from std::exception");
      }
    }
    return true;
  }

  bool fail(std::string message) {
    failed_ = true;
    stopped_ = true;
    error_ = std::move(message);
    return false;
  }

  const ObjectiveFunction& f_;
  const EvaluationCallback& on_evaluation_;
  const double loss_scale_;
  const double target_;
  const Clock::time_point start_;
  Eigen::VectorXd x_;         // the point of the last call of f
  Eigen::VectorXd gradient_;  // ∇f there (raw)
  double loss_ = 0.0;         // f there
  bool cached_ = false;       // x_, loss_, gradient_ hold a successful evaluation
  Eigen::VectorXd best_x_;
  double best_loss_ = std::numeric_limits<double>::infinity();
  int evaluations_ = 0;
  int iterations_ = 0;
  bool evaluations_are_iterations_ = false;
  int cap_ = 0;  // > 0: at most this many evaluations
  bool cap_reached_ = false;
  bool stopped_ = false;
  bool failed_ = false;
  std::string error_;
  std::exception_ptr foreign_exception_;
  bool recover_infeasible_ = false;
  int infeasible_points_ = 0;
  std::string last_infeasible_;
};

// How a back-end ended, in our terms (before the precedence of minimize: failed, target).
struct Outcome {
  std::string status;
  std::string message;
  int iterations = 0;
};

// ---------------------------------------------------------------------------------------
// NLopt: NLOPT_LD_LBFGS on ℓ.

struct NloptData {
  Evaluator* evaluator;
  nlopt::opt* opt;
};

double nlopt_objective(unsigned n, const double* x, double* gradient, void* data) {
  NloptData& d = *static_cast<NloptData*>(data);
  double value = 0.0;
  if (!d.evaluator->evaluate(x, value, gradient)) {
    // A failure, or a request after the cap: NLopt's line search may still ask for a few
    // points before it checks the forced stop; they cost nothing.
    d.opt->force_stop();
    if (gradient != nullptr) std::fill(gradient, gradient + n, 0.0);
    return HUGE_VAL;
  }
  if (d.evaluator->stopped()) d.opt->force_stop();  // this evaluation reached the cap
  return value;
}

const char* nlopt_result_name(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS: return "SUCCESS (gradient tolerance)";
    case nlopt::STOPVAL_REACHED: return "STOPVAL_REACHED";
    case nlopt::FTOL_REACHED: return "FTOL_REACHED";
    case nlopt::XTOL_REACHED: return "XTOL_REACHED";
    case nlopt::MAXEVAL_REACHED: return "MAXEVAL_REACHED";
    case nlopt::MAXTIME_REACHED: return "MAXTIME_REACHED";
    default: return "unexpected result";
  }
}

Outcome run_nlopt(Evaluator& evaluator, const Eigen::VectorXd& x0,
                  const OptimizerOptions& options, const Bounds& bounds) {
  Outcome out;
  try {
    const auto n = static_cast<unsigned>(x0.size());
    nlopt::opt opt(nlopt::LD_LBFGS, n);
    NloptData data{&evaluator, &opt};
    evaluator.count_evaluations_as_iterations(options.max_iterations);
    opt.set_min_objective(nlopt_objective, &data);
    opt.set_vector_storage(static_cast<unsigned>(options.lbfgs_memory));
    opt.set_maxeval(options.max_iterations);
    if (options.target_normalized_loss > 0.0) opt.set_stopval(options.target_normalized_loss);
    // 0: PLIS's own floors, relative f change ≤ 1e-14 and x change ≤ 1e-16 (header).
    opt.set_ftol_rel(0.0);
    opt.set_xtol_rel(0.0);
    if (!bounds.empty()) {
      opt.set_lower_bounds(std::vector<double>(bounds.lower.data(), bounds.lower.data() + n));
      opt.set_upper_bounds(std::vector<double>(bounds.upper.data(), bounds.upper.data() + n));
    }
    std::vector<double> x(x0.data(), x0.data() + n);
    double value = 0.0;
    try {
      const nlopt::result r = opt.optimize(x, value);
      out.message = std::string("nlopt: ") + nlopt_result_name(r);
      switch (r) {
        case nlopt::MAXEVAL_REACHED: out.status = "max_iterations"; break;
        case nlopt::STOPVAL_REACHED: out.status = "target_reached"; break;
        case nlopt::SUCCESS: out.status = "converged"; break;  // ‖∇ℓ‖∞ ≤ 1e-8
        case nlopt::FTOL_REACHED:                              // at PLIS's floors: no change
        case nlopt::XTOL_REACHED: out.status = "roundoff_limited"; break;
        default: out.status = "failed"; break;
      }
    } catch (const nlopt::roundoff_limited&) {
      out.status = "roundoff_limited";
      out.message = "nlopt: ROUNDOFF_LIMITED";
    } catch (const nlopt::forced_stop&) {
      // Forced by the wrapper: a failure of f (minimize reports it) or the evaluation cap.
      out.status = evaluator.cap_reached() ? "max_iterations" : "failed";
      out.message = evaluator.cap_reached()
                        ? "nlopt: FORCED_STOP at the evaluation cap (max_iterations)"
                        : "nlopt: FORCED_STOP";
    } catch (const std::runtime_error& error) {
      // NLOPT_FAILURE: from PLIS, only "the method failed" (ITERM < 0: no descent even after
      // a steepest-descent restart, its line search found no acceptable step).
      out.status = "roundoff_limited";
      out.message = std::string("nlopt: FAILURE (") + error.what() +
                    "): the line search found no acceptable step";
    }
  } catch (const std::exception& error) {  // invalid arguments, out of memory
    out.status = "failed";
    out.message = std::string("nlopt: ") + error.what();
  }
  // After the cap, NLopt's line search is refused every point: it may then end in FAILURE
  // (its restart finds no descent) before it notices the forced stop.
  if (evaluator.cap_reached() && !evaluator.failed() && out.status != "converged" &&
      out.status != "target_reached" && out.status != "max_iterations") {
    out.message += " (after the evaluation cap, max_iterations)";
    out.status = "max_iterations";
  }
  out.iterations = evaluator.iterations();
  return out;
}

// ---------------------------------------------------------------------------------------
// Ceres: GradientProblemSolver, LBFGS direction, Wolfe line search, on ℓ.

class CeresObjective final : public ceres::FirstOrderFunction {
 public:
  CeresObjective(Evaluator& evaluator, int n) : evaluator_(evaluator), n_(n) {}
  bool Evaluate(const double* parameters, double* cost, double* gradient) const override {
    return evaluator_.evaluate(parameters, *cost, gradient);
  }
  int NumParameters() const override { return n_; }

 private:
  Evaluator& evaluator_;
  int n_;
};

// Runs between iterations (also after the initial evaluation, iteration 0).
class CeresStopRule final : public ceres::IterationCallback {
 public:
  explicit CeresStopRule(Evaluator& evaluator) : evaluator_(evaluator) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    evaluator_.set_iterations(summary.iteration);
    if (evaluator_.failed()) return ceres::SOLVER_ABORT;
    return evaluator_.target_reached() ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                       : ceres::SOLVER_CONTINUE;
  }

 private:
  Evaluator& evaluator_;
};

Outcome run_ceres(Evaluator& evaluator, const Eigen::VectorXd& x0,
                  const OptimizerOptions& options) {
  Outcome out;
  try {
    initialize_ceres_logging();
    ceres::GradientProblemSolver::Options solver;
    solver.line_search_direction_type = ceres::LBFGS;
    solver.line_search_type = ceres::WOLFE;
    solver.max_lbfgs_rank = options.lbfgs_memory;
    // H⁰ = (sᵀy / yᵀy) I, as NLopt and Ipopt (scalar2). Ceres's default, H⁰ = I, took 3–4×
    // the iterations on the quadratics of tests/test_optimizer.cpp (condition 1e4, to 1e-8:
    // 1000 against 330) and 1.7× on chained Rosenbrock 10-D.
    solver.use_approximate_eigenvalue_bfgs_scaling = true;
    solver.max_num_iterations = options.max_iterations;
    solver.max_solver_time_in_seconds = 1e12;
    // Only a stationary point or an iteration that changes nothing stops Ceres (header).
    solver.gradient_tolerance = kStationaryGradient;
    solver.function_tolerance = 0.0;
    solver.parameter_tolerance = 0.0;
    solver.logging_type = ceres::SILENT;
    solver.minimizer_progress_to_stdout = false;
    CeresStopRule stop_rule(evaluator);
    solver.callbacks.push_back(&stop_rule);
    std::string error;
    if (!solver.IsValid(&error)) {
      out.status = "failed";
      out.message = "ceres: invalid options: " + error;
      return out;
    }
    ceres::GradientProblem problem(new CeresObjective(evaluator, static_cast<int>(x0.size())));
    Eigen::VectorXd x = x0;
    ceres::GradientProblemSolver::Summary summary;
    ceres::Solve(solver, problem, x.data(), &summary);
    if (!summary.iterations.empty()) evaluator.set_iterations(summary.iterations.back().iteration);
    out.message = std::string("ceres: ") +
                  ceres::TerminationTypeToString(summary.termination_type) + ": " +
                  summary.message;
    switch (summary.termination_type) {
      case ceres::CONVERGENCE:
        // Gradient tolerance, or (function and parameter tolerances being 0) an iteration
        // that changed nothing: a stall.
        out.status = !summary.iterations.empty() &&
                             summary.iterations.back().gradient_max_norm <= kStationaryGradient
                         ? "converged"
                         : "roundoff_limited";
        break;
      case ceres::NO_CONVERGENCE: out.status = "max_iterations"; break;
      case ceres::USER_SUCCESS: out.status = "target_reached"; break;
      // A line search without an acceptable step (when f itself did not fail: minimize
      // checks that first).
      case ceres::FAILURE: out.status = "roundoff_limited"; break;
      case ceres::USER_FAILURE: out.status = "failed"; break;
    }
  } catch (const std::exception& error) {
    out.status = "failed";
    out.message = std::string("ceres: ") + error.what();
  }
  out.iterations = evaluator.iterations();
  return out;
}

// ---------------------------------------------------------------------------------------
// Ipopt: min ℓ(x), m = 0, box bounds (or none), limited-memory Hessian.

class LbfgsNlp final : public Ipopt::TNLP {
 public:
  LbfgsNlp(Evaluator& evaluator, const Eigen::VectorXd& x0, const Bounds& bounds)
      : evaluator_(evaluator), x0_(x0), bounds_(bounds) {}

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g,
                    Ipopt::Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = static_cast<Ipopt::Index>(x0_.size());
    m = 0;
    nnz_jac_g = 0;
    nnz_h_lag = 0;  // hessian_approximation limited-memory: eval_h is never called
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index,
                       Ipopt::Number*, Ipopt::Number*) override {
    // Beyond ±nlp_lower/upper_bound_inf (±1e19): no bound.
    std::fill(x_l, x_l + n, -2e19);
    std::fill(x_u, x_u + n, 2e19);
    if (!bounds_.empty()) {
      for (Ipopt::Index i = 0; i < n; ++i) {
        if (std::isfinite(bounds_.lower(i))) x_l[i] = bounds_.lower(i);
        if (std::isfinite(bounds_.upper(i))) x_u[i] = bounds_.upper(i);
      }
    }
    return true;
  }

  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index, bool, Ipopt::Number*) override {
    if (init_x) std::copy(x0_.data(), x0_.data() + n, x);
    return true;
  }

  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& obj_value) override {
    return evaluator_.evaluate(x, obj_value, nullptr);
  }

  bool eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* grad_f) override {
    double value = 0.0;
    return evaluator_.evaluate(x, value, grad_f);
  }

  bool eval_g(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Index, Ipopt::Number*) override {
    return true;  // m = 0
  }

  bool eval_jac_g(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Index, Ipopt::Index,
                  Ipopt::Index*, Ipopt::Index*, Ipopt::Number*) override {
    return true;  // m = 0
  }

  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index, const Ipopt::Number*,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    // Nothing: the wrapper keeps the best point of all evaluations.
  }

  // After each iteration (iter 0: after the initial evaluation), restoration phase included.
  bool intermediate_callback(Ipopt::AlgorithmMode, Ipopt::Index iter, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Index,
                             const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    evaluator_.set_iterations(static_cast<int>(iter));
    return !evaluator_.failed() && !evaluator_.target_reached();
  }

 private:
  Evaluator& evaluator_;
  const Eigen::VectorXd& x0_;
  const Bounds& bounds_;
};

Outcome run_ipopt(Evaluator& evaluator, const Eigen::VectorXd& x0,
                  const OptimizerOptions& options, const Bounds& bounds) {
  Outcome out;
  // The whole life of the application, evaluations included (ipopt_lock.hpp).
  const std::lock_guard<std::recursive_mutex> lock(ipopt_mutex());
  try {
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = new Ipopt::IpoptApplication();
    Ipopt::OptionsList& o = *app->Options();
    bool ok = true;
    // Output options are read by Initialize, so they are set before it (solvers/ipopt_step).
    ok &= o.SetIntegerValue("print_level", 0);
    ok &= o.SetStringValue("sb", "yes");  // no banner
    ok &= o.SetStringValue("linear_solver", "mumps");
    ok &= o.SetStringValue("hessian_approximation", "limited-memory");
    ok &= o.SetIntegerValue("limited_memory_max_history", options.lbfgs_memory);
    // B⁰ = (yᵀy / sᵀy) I, the usual L-BFGS scaling, as in NLopt and Ceres. Ipopt's default,
    // scalar1 (sᵀy / sᵀs), gives longer first trial steps that its backtracking then cuts:
    // 2–5× the evaluations (chained Rosenbrock 10-D to 1e-6: 263 against 89; a 100-D
    // quadratic of condition 1e4 to 1e-8: 1391 against 354).
    ok &= o.SetStringValue("limited_memory_initialization", "scalar2");
    ok &= o.SetStringValue("nlp_scaling_method", "none");
    // Genuine convergence only: ‖∇ℓ‖∞ ≤ kStationaryGradient; "acceptable" termination off.
    ok &= o.SetNumericValue("tol", kStationaryGradient);
    ok &= o.SetIntegerValue("acceptable_iter", 0);
    // Ipopt relaxes bounds by 1e-8 relative by default; a bound here is physical (a cable
    // cannot push), so it is kept exactly.
    ok &= o.SetNumericValue("bound_relax_factor", 0.0);
    ok &= o.SetIntegerValue("max_iter", options.max_iterations);
    if (options.warm_start) {
      // x0 is an earlier run's best point (--resume), interior and often close to bounds.
      // With limited-memory Hessians Ipopt's default barrier is "adaptive": its oracle sets μ
      // from the complementarity at the start, where every bound multiplier is 1
      // (bound_mult_init_val), so at such a point (cable tensions up to ~170) μ starts near
      // 0.1 (lg μ = −1.1 at iteration 2): the barrier pulls the iterate off the bounds, the
      // loss rises (0.106 → 0.186), and from there the quasi-Newton steps head where the
      // forward simulation fails. mu_init is ignored by the adaptive oracle, as are bound_push
      // and bound_frac: neither helps alone. A monotone barrier from a small μ continues
      // instead of beginning. μ is in units of the normalised loss, and n μ bounds what the
      // barrier adds to it at the barrier problem's solution: 1e-6 keeps that below a
      // target of 1e-3 for n = 800, and was the best of 1e-9 … 1e-3 measured (below). The
      // start is also kept where it is (bound_push, bound_frac 1e-9 instead of 1e-2: x0's
      // loss is the checkpoint's best loss, not that of a point moved 1e-2 into the box).
      // Measured on problems/scenes/optimization/cable_tip_curve.json (800 tensions ≥ 0;
      // uninterrupted: 16 evaluations, the target at evaluation 16), resumed after k
      // iterations (k + 1 evaluations), evaluations of the resumed run to the target
      // against 2 × the uninterrupted run's remaining 15 − k:
      //   k          1   2   4   6   8     10  12  14
      //   default    17  17  11  11  6377  14  15  39   (k = 8: 200 iterations, 6048
      //                                                 infeasible trial points, no target)
      //   this       21  20  12  12  10    8   6   3
      //   2 × rest   28  26  22  18  14    10  6   2
      // (at k = 14 one evaluation was left: a restart without L-BFGS pairs needs more).
      // warm_start_init_point is not used: it needs the earlier run's bound multipliers,
      // which a checkpoint does not keep (without them: 36 evaluations at k = 4).
      ok &= o.SetStringValue("mu_strategy", "monotone");
      ok &= o.SetNumericValue("mu_init", 1e-6);
      ok &= o.SetNumericValue("bound_push", 1e-9);
      ok &= o.SetNumericValue("bound_frac", 1e-9);
    }
    if (!ok) {
      out.status = "failed";
      out.message = "ipopt: an option was rejected";
      return out;
    }
    // Initialize("") reads no options file (plain Initialize() reads ./ipopt.opt).
    if (app->Initialize("") != Ipopt::Solve_Succeeded) {
      out.status = "failed";
      out.message = "ipopt: could not be initialised";
      return out;
    }
    Ipopt::SmartPtr<Ipopt::TNLP> nlp = new LbfgsNlp(evaluator, x0, bounds);
    const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
    out.message = std::string("ipopt: ") + ipopt_status_name(status);
    switch (status) {
      case Ipopt::Solve_Succeeded:
      case Ipopt::Solved_To_Acceptable_Level: out.status = "converged"; break;
      case Ipopt::Maximum_Iterations_Exceeded: out.status = "max_iterations"; break;
      case Ipopt::User_Requested_Stop: out.status = "target_reached"; break;
      case Ipopt::Search_Direction_Becomes_Too_Small:
      case Ipopt::Restoration_Failed: out.status = "roundoff_limited"; break;
      default: out.status = "failed"; break;
    }
  } catch (const std::exception& error) {
    out.status = "failed";
    out.message = std::string("ipopt: ") + error.what();
  }
  out.iterations = evaluator.iterations();
  return out;
}

// Throws std::invalid_argument unless `bounds` fit x0 and the back-end (see the header).
void check_bounds(const Bounds& bounds, const Eigen::VectorXd& x0, Optimizer optimizer) {
  if (bounds.empty()) return;
  if (bounds.lower.size() != x0.size() || bounds.upper.size() != x0.size()) {
    throw std::invalid_argument("minimize: bounds of sizes " + std::to_string(bounds.lower.size()) +
                                " and " + std::to_string(bounds.upper.size()) + " for " +
                                std::to_string(x0.size()) + " parameters");
  }
  for (Eigen::Index i = 0; i < x0.size(); ++i) {
    const double l = bounds.lower(i), u = bounds.upper(i);
    const std::string entry = "minimize: parameter " + std::to_string(i) + ": ";
    if (std::isnan(l) || std::isnan(u) || !(l < u)) {
      throw std::invalid_argument(entry + "the lower bound " + short_number(l) +
                                  " is not below the upper bound " + short_number(u));
    }
    if (!(l <= x0(i) && x0(i) <= u)) {
      throw std::invalid_argument(entry + "x0 = " + short_number(x0(i)) + " is outside [" +
                                  short_number(l) + ", " + short_number(u) + "]");
    }
  }
  const bool finite = (bounds.lower.array().isFinite() || bounds.upper.array().isFinite()).any();
  if (finite && optimizer == Optimizer::kCeresLbfgs) {
    throw std::invalid_argument(std::string("minimize: ") + kCeresHasNoBounds);
  }
}

}  // namespace

OptimizationResult minimize(const ObjectiveFunction& f, const Eigen::VectorXd& x0,
                            double loss_scale, const OptimizerOptions& options,
                            const EvaluationCallback& on_evaluation, const Bounds& bounds) {
  const Clock::time_point start = Clock::now();
  options.validate();
  if (!(loss_scale > 0.0) || !std::isfinite(loss_scale)) {
    throw std::invalid_argument("minimize: loss_scale must be a finite number > 0 (got " +
                                short_number(loss_scale) + ")");
  }
  if (x0.size() == 0) throw std::invalid_argument("minimize: x0 is empty (no parameters)");
  if (!x0.allFinite()) throw std::invalid_argument("minimize: x0 has a non-finite entry");
  if (!f) throw std::invalid_argument("minimize: no objective function");
  check_bounds(bounds, x0, options.optimizer);

  Evaluator evaluator(f, x0, loss_scale, options.target_normalized_loss, on_evaluation, start);
  if (options.optimizer != Optimizer::kNloptLbfgs) evaluator.recover_from_infeasible_points();
  Outcome outcome;
  switch (options.optimizer) {
    case Optimizer::kNloptLbfgs: outcome = run_nlopt(evaluator, x0, options, bounds); break;
    case Optimizer::kCeresLbfgs: outcome = run_ceres(evaluator, x0, options); break;
    case Optimizer::kIpoptLbfgs: outcome = run_ipopt(evaluator, x0, options, bounds); break;
  }
  if (evaluator.foreign_exception()) std::rethrow_exception(evaluator.foreign_exception());

  OptimizationResult result;
  result.best_x = evaluator.best_x();
  result.best_loss = evaluator.best_loss();
  result.best_normalized_loss = result.best_loss / loss_scale;
  result.iterations = outcome.iterations;
  result.evaluations = evaluator.evaluations();
  result.reached_target = evaluator.target_reached();
  if (evaluator.failed()) {
    result.status = "failed";
    result.message = evaluator.error();
  } else if (result.reached_target) {
    result.status = "target_reached";
    result.message = std::move(outcome.message);
  } else if (!std::isfinite(result.best_loss)) {  // Ceres, Ipopt: x0 was an InfeasiblePoint
    result.status = "failed";
    result.message = "x0 could not be evaluated; " + outcome.message;
  } else {
    result.status = outcome.status == "target_reached" ? "failed" : std::move(outcome.status);
    result.message = std::move(outcome.message);
  }
  if (evaluator.infeasible_points() > 0) {
    result.message += "; " + std::to_string(evaluator.infeasible_points()) +
                      " trial points could not be evaluated (last: " + evaluator.last_infeasible() +
                      ")";
  }
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace liedyn

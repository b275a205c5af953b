#pragma once
// Ipopt over rotations: your problem on SO(3)^r × R^n, written with Lie derivatives, solved by
// Ipopt without writing a chart.
//
//   minimise  f(R_1, …, R_r, v)   subject to  c_L ≤ c(R_1, …, R_r, v) ≤ c_U,  v_L ≤ v ≤ v_U.
//
// You implement LieNlp: values, Lie gradients and Lie Jacobians in the tangent layout below,
// and optionally the Lie Hessian of the Lagrangian. solve_with_ipopt hands Ipopt an NLP in
// chart variables and turns your derivatives into theirs:
//
// Charts. Rotation i is R_i = exp(θ_i) R0_i around a reference R0_i (the starting rotation),
// θ_i ∈ R³ Ipopt's variables. Since exp(θ + ε) = exp(J_l(θ) ε) exp(θ) + O(ε²) (lib/so3.hpp), a
// change ε of θ_i is the left (world-frame) perturbation J_l(θ_i) ε of R_i, so with your Lie
// gradient g, Lie Jacobian A and Lie Hessian H of the Lagrangian L = σ f + λᵀc:
//   ∂f/∂θ_i = J_l(θ_i)ᵀ g_i,    ∂c/∂θ_i = A_i J_l(θ_i),
//   ∂²L/∂θ_i∂θ_j = J_l(θ_i)ᵀ H_ij J_l(θ_j)  + δ_ij C(θ_i, ∇L_i),
// C(θ, g) the chain rule's second-order term (manifolds/rotation_vector.hpp), ∇L_i = σ g_i +
// A_iᵀλ; vector entries pass unchanged. These are the exact derivatives of the functions Ipopt
// evaluates, as its line search and derivative checker need (the Lie derivatives alone are
// that only at θ = 0).
//
// Re-centring. A chart is good near its reference (J_l(θ) is singular at ‖θ‖ = 2π and its
// conditioning degrades well before). When a solve ends with some ‖θ_i‖ above
// `recentre_angle`, the references move to the solution (R0_i ← R_i, θ_i = 0) and Ipopt solves
// again from there (warm-started multipliers), up to `max_recentrings` times. A solution is
// the same point on the manifold in any chart: the KKT conditions in θ are the Lie ones times
// the invertible J_l(θ) (‖θ‖ < 2π), so a solve that converged with re-centrings used up is
// still reported converged, its message saying how far the last chart moved.
//
// Tangent layout (gradients, Jacobian columns, Hessian rows and columns): rotation i at 3i
// (its world-frame rotation vector, as everywhere in liedyn), then v at 3r.
//
// Dense or sparse derivatives. By default the Jacobian (m × (3r + n)) and the Hessian
// ((3r + n)²) are dense matrices and Ipopt gets dense patterns. A problem whose derivatives are
// sparse (a trajectory, a graph) returns true from sparse() and fills Eigen sparse matrices
// instead, which Ipopt then gets as sparse patterns: the nonzeros of the first evaluation, at
// the starting point (explicit zeros count), widened to whole 3×3 blocks of rotations (the
// chart's J_l(θ) mixes a rotation's three columns). A later evaluation with an entry outside
// that pattern is an evaluation error (Ipopt shortens its step, or stops).
//
// Thread safety: a call owns its problem for its duration; separate problems may be solved on
// separate threads.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <map>
#include <string>
#include <vector>

namespace liedyn {

// A point of SO(3)^r × R^n.
struct LiePoint {
  std::vector<Eigen::Matrix3d> rotations;
  Eigen::VectorXd vector;
  int tangent_size() const { return 3 * static_cast<int>(rotations.size()) + static_cast<int>(vector.size()); }
};

// Your problem. Every evaluation may return false when it cannot be evaluated at x (Ipopt
// then shortens its step); derivatives are written into the arrays given, which are sized. An
// output resized to another shape is an evaluation error too, named in the summary's message.
class LieNlp {
 public:
  virtual ~LieNlp() = default;

  // m, the number of constraint rows (default: none).
  virtual int constraints() const { return 0; }
  // c_L, c_U (size m; equal entries make an equality). Default: all equalities c = 0.
  virtual void constraint_bounds(Eigen::VectorXd& lower, Eigen::VectorXd& upper) const {
    lower.setZero();
    upper.setZero();
  }
  // v_L, v_U (size n; ±infinity for none, the default).
  virtual void vector_bounds(Eigen::VectorXd& lower, Eigen::VectorXd& upper) const;

  // f(x), and its Lie gradient (tangent layout) when `gradient` is non-null.
  virtual bool objective(const LiePoint& x, double& f, Eigen::VectorXd* gradient) = 0;
  // c(x) (size m), and its Lie Jacobian (m × tangent size) when `jacobian` is non-null (only
  // asked for when sparse() is false).
  virtual bool constraint_values(const LiePoint& x, Eigen::VectorXd& c, Eigen::MatrixXd* jacobian);
  // The Lie Hessian of L = σ f + λᵀc (tangent size squared): ∂²L(exp(θ) R, v)/∂(θ, v)² at
  // θ = 0, symmetric (lib/so3.hpp). Return false if you do not provide it: Ipopt's
  // limited-memory quasi-Newton approximation is used instead (LieIpoptOptions::hessian).
  virtual bool lagrangian_hessian(const LiePoint& x, double sigma, const Eigen::VectorXd& lambda,
                                  Eigen::MatrixXd& hessian);

  // The sparse alternative: when sparse() is true, the two methods below are called instead of
  // the dense derivatives above (both matrices are given sized and empty; the Hessian is the
  // whole symmetric matrix, both triangles). Their defaults return false.
  virtual bool sparse() const { return false; }
  virtual bool constraint_jacobian(const LiePoint& x, Eigen::SparseMatrix<double>& jacobian);
  virtual bool lagrangian_hessian(const LiePoint& x, double sigma, const Eigen::VectorXd& lambda,
                                  Eigen::SparseMatrix<double>& hessian);
};

struct LieIpoptOptions {
  double tolerance = 1e-9;    // Ipopt's tol (scaled KKT error); > 0
  int max_iterations = 500;   // Ipopt iterations over all solves; ≥ 1
  int max_recentrings = 5;    // extra solves after re-centring; ≥ 0
  double recentre_angle = 1.0;  // rad, in (0, π]
  // "auto" (exact if lagrangian_hessian provides it), "exact" (it must), "limited-memory".
  std::string hessian = "auto";
  int print_level = 0;        // Ipopt's console output, 0 … 12
  // Ipopt's derivative checker at the start of each solve, on the chart derivatives:
  // "none", "first-order", "second-order" (findings on the console).
  std::string derivative_test = "none";
  // If not empty, Ipopt also writes its log there, at print level max(print_level, 5).
  std::string output_file;
  // Further Ipopt options by name (Ipopt's option list; e.g. {"mu_strategy", "adaptive"},
  // {"acceptable_tol", 1e-6}). solve_with_ipopt throws std::invalid_argument naming an option
  // that Ipopt refuses (unknown, of another type, out of range) or that a field above owns
  // (tol, max_iter, hessian_approximation, print_level, derivative_test, output_file) or the
  // re-centring sets (warm_start_init_point).
  std::map<std::string, std::string> ipopt_strings;
  std::map<std::string, int> ipopt_integers;
  std::map<std::string, double> ipopt_numbers;

  // Throws std::invalid_argument naming the field and the rule.
  void validate() const;
};

enum class LieIpoptTermination {
  kConverged,      // Ipopt's Solve_Succeeded in the last chart
  kAcceptable,     // Ipopt's Solved_To_Acceptable_Level
  kNoConvergence,  // Ipopt's iteration (or time) limit
  kFailure,        // any other Ipopt status (infeasible, restoration failed, evaluation errors)
};

struct LieIpoptSummary {
  LieIpoptTermination termination = LieIpoptTermination::kFailure;
  std::string message;   // Ipopt's last status, and what happened
  int iterations = 0;    // Ipopt iterations over all solves
  int solves = 0;        // 1 + re-centrings
  double objective = 0.0;
  double constraint_violation = 0.0;  // max over rows of the bound violation at the solution
  // Ipopt's unscaled dual infeasibility ‖∇L‖∞ at the end of the last solve (chart
  // coordinates, bound multipliers included; the Lie one times J_l(θ)ᵀ).
  double dual_infeasibility = 0.0;
  Eigen::VectorXd multipliers;        // λ of the constraint rows
  bool converged() const { return termination == LieIpoptTermination::kConverged; }
};

// Solves from x (x.vector's size sets n; rotations must be rotations to round-off) and leaves
// the final point in x (also when not converged). Throws std::invalid_argument for invalid
// options, an x that is not a point of the manifold, hessian = "exact" without
// lagrangian_hessian, or an output_file that cannot be opened.
LieIpoptSummary solve_with_ipopt(LieNlp& problem, LiePoint& x, const LieIpoptOptions& options = {});

}  // namespace liedyn

#include "lie_ipopt.hpp"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "../lib/so3.hpp"
#include "../solvers/ipopt_status.hpp"
#include "rotation_chart.hpp"

namespace liedyn {

void LieNlp::vector_bounds(Eigen::VectorXd& lower, Eigen::VectorXd& upper) const {
  lower.setConstant(-std::numeric_limits<double>::infinity());
  upper.setConstant(std::numeric_limits<double>::infinity());
}

bool LieNlp::constraint_values(const LiePoint&, Eigen::VectorXd&, Eigen::MatrixXd*) { return true; }

bool LieNlp::lagrangian_hessian(const LiePoint&, double, const Eigen::VectorXd&, Eigen::MatrixXd&) {
  return false;
}

bool LieNlp::constraint_jacobian(const LiePoint&, Eigen::SparseMatrix<double>&) { return false; }

bool LieNlp::lagrangian_hessian(const LiePoint&, double, const Eigen::VectorXd&,
                                Eigen::SparseMatrix<double>&) {
  return false;
}

void LieIpoptOptions::validate() const {
  const auto fail = [](const std::string& field, const std::string& rule) {
    throw std::invalid_argument("LieIpoptOptions::" + field + ": " + rule);
  };
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) fail("tolerance", "must be finite and > 0");
  if (max_iterations < 1) fail("max_iterations", "must be ≥ 1");
  if (max_recentrings < 0) fail("max_recentrings", "must be ≥ 0");
  if (!(recentre_angle > 0.0 && recentre_angle <= std::numbers::pi)) fail("recentre_angle", "must be in (0, π]");
  if (hessian != "auto" && hessian != "exact" && hessian != "limited-memory") {
    fail("hessian", "unknown \"" + hessian + "\" (expected auto, exact or limited-memory)");
  }
  if (print_level < 0 || print_level > 12) fail("print_level", "must be in [0, 12]");
  if (derivative_test != "none" && derivative_test != "first-order" &&
      derivative_test != "second-order") {
    fail("derivative_test",
         "unknown \"" + derivative_test + "\" (expected none, first-order or second-order)");
  }
}

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Sparse = Eigen::SparseMatrix<double>;
using Index = Ipopt::Index;
using Number = Ipopt::Number;

// Ipopt's infinity (nlp_lower_bound_inf / nlp_upper_bound_inf default to ∓1e19).
constexpr double kIpoptInfinity = 2e19;
double to_ipopt(double bound) {
  return std::clamp(bound, -kIpoptInfinity, kIpoptInfinity);
}

// A fixed sparsity pattern handed to Ipopt: its entries (row, column) in order, and where each
// one's value goes.
class Pattern {
 public:
  void add(int row, int column) { entries_.emplace_back(row, column); }
  // Sorts, drops repeats and indexes the entries.
  void finish() {
    std::sort(entries_.begin(), entries_.end());
    entries_.erase(std::unique(entries_.begin(), entries_.end()), entries_.end());
    slot_.clear();
    for (std::size_t k = 0; k < entries_.size(); ++k) slot_[key(entries_[k])] = static_cast<int>(k);
  }
  Index size() const { return static_cast<Index>(entries_.size()); }
  void structure(Index* rows, Index* columns) const {
    for (std::size_t k = 0; k < entries_.size(); ++k) {
      rows[k] = entries_[k].first;
      columns[k] = entries_[k].second;
    }
  }
  // Where (row, column)'s value goes, or −1 if it is not in the pattern.
  int slot(int row, int column) const {
    const auto it = slot_.find(key({row, column}));
    return it == slot_.end() ? -1 : it->second;
  }

 private:
  static std::int64_t key(const std::pair<int, int>& e) {
    return (static_cast<std::int64_t>(e.first) << 32) | static_cast<std::uint32_t>(e.second);
  }
  std::vector<std::pair<int, int>> entries_;
  std::unordered_map<std::int64_t, int> slot_;
};

// The NLP in chart variables z = (θ_1, …, θ_r, v) (lie_ipopt.hpp), around references R0: the
// rotation-vector chart of the step back-ends (rotation_chart.hpp) over this layout.
class ChartNlp final : public Ipopt::TNLP {
 public:
  ChartNlp(LieNlp& problem, const LiePoint& start)
      : problem_(problem),
        rotations_(static_cast<int>(start.rotations.size())),
        n_(start.tangent_size()),
        m_(problem.constraints()),
        chart_(rotation_offsets(rotations_), n_),
        point_(start),
        z_(VectorXd::Zero(n_)),
        z_lower_(VectorXd::Zero(0)),
        z_upper_(VectorXd::Zero(0)),
        lambda_(VectorXd::Zero(m_)),
        gradient_(n_),
        jacobian_(m_, n_),
        constraints_(m_) {
    z_.tail(n_ - 3 * rotations_) = start.vector;
    for (int i = 0; i < rotations_; ++i) chart_.set_reference(i, start.rotations[i]);
  }

  // The patterns (lie_ipopt.hpp), and whether the exact Hessian is used: `hessian` is
  // LieIpoptOptions::hessian; the problem's Hessian is asked for once here (σ = 1, λ = 1, so
  // that no term weighted by a multiplier is left out of a sparse pattern) unless it is
  // "limited-memory". Dense problems get whole matrices; sparse ones the nonzeros of their
  // derivatives at the start, widened to whole rotation blocks, and every rotation's diagonal
  // block of the Hessian (C(θ, ∇L)). False if the Jacobian cannot be evaluated there.
  bool record_patterns(const std::string& hessian_option) {
    Sparse hessian(n_, n_);
    exact_hessian_ = hessian_option != "limited-memory" && lie_hessian(1.0, VectorXd::Ones(m_), hessian);
    if (hessian_option == "exact" && !exact_hessian_) {
      throw std::invalid_argument(
          "LieIpoptOptions::hessian: \"exact\" but the problem's lagrangian_hessian returns false");
    }
    if (!problem_.sparse()) {
      for (int r = 0; r < m_; ++r) {
        for (int c = 0; c < n_; ++c) jacobian_pattern_.add(r, c);
      }
      for (int r = 0; exact_hessian_ && r < n_; ++r) {
        for (int c = 0; c <= r; ++c) hessian_pattern_.add(r, c);
      }
    } else {
      if (!lie_jacobian()) return false;
      for (int k = 0; k < jacobian_.outerSize(); ++k) {
        for (Sparse::InnerIterator it(jacobian_, k); it; ++it) {
          const auto [first, width] = block(static_cast<int>(it.col()));
          for (int c = first; c < first + width; ++c) jacobian_pattern_.add(static_cast<int>(it.row()), c);
        }
      }
      if (exact_hessian_) {
        for (int k = 0; k < hessian.outerSize(); ++k) {
          for (Sparse::InnerIterator it(hessian, k); it; ++it) {
            add_block_pair(static_cast<int>(it.row()), static_cast<int>(it.col()));
          }
        }
        for (int i = 0; i < rotations_; ++i) add_block_pair(3 * i, 3 * i);
      }
    }
    jacobian_pattern_.finish();
    hessian_pattern_.finish();
    return true;
  }

  // Chart around the current point: R0 ← R, θ = 0 (multipliers kept for a warm start).
  void recentre() {
    for (int i = 0; i < rotations_; ++i) {
      chart_.set_reference(i, point_.rotations[i]);
      z_.segment<3>(3 * i).setZero();
    }
    have_gradient_ = have_jacobian_ = false;
  }
  double largest_chart_angle() const {
    double largest = 0.0;
    for (int i = 0; i < rotations_; ++i) largest = std::max(largest, chart_.r(i).norm());
    return largest;
  }
  const LiePoint& point() const { return point_; }
  const VectorXd& multipliers() const { return lambda_; }
  double objective() const { return objective_; }
  const VectorXd& constraint_values() const { return constraints_; }
  bool warm() const { return warm_; }
  bool exact_hessian() const { return exact_hessian_; }
  const std::string& error() const { return error_; }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override {
    n = n_;
    m = m_;
    nnz_jac_g = jacobian_pattern_.size();
    nnz_h_lag = hessian_pattern_.size();
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index, Number* x_l, Number* x_u, Index, Number* g_l, Number* g_u) override {
    const int v = n_ - 3 * rotations_;
    VectorXd lower(v), upper(v);
    problem_.vector_bounds(lower, upper);
    for (int i = 0; i < 3 * rotations_; ++i) {  // charts: unbounded
      x_l[i] = -kIpoptInfinity;
      x_u[i] = kIpoptInfinity;
    }
    for (int j = 0; j < v; ++j) {
      x_l[3 * rotations_ + j] = to_ipopt(lower(j));
      x_u[3 * rotations_ + j] = to_ipopt(upper(j));
    }
    VectorXd c_lower(m_), c_upper(m_);
    problem_.constraint_bounds(c_lower, c_upper);
    for (int r = 0; r < m_; ++r) {
      g_l[r] = to_ipopt(c_lower(r));
      g_u[r] = to_ipopt(c_upper(r));
    }
    return true;
  }

  bool get_starting_point(Index, bool init_x, Number* x, bool init_z, Number* z_L, Number* z_U,
                          Index, bool init_lambda, Number* lambda) override {
    if (init_x) Eigen::Map<VectorXd>(x, n_) = z_;
    if (init_z) {  // a warm start: the last solve's bound multipliers
      if (z_lower_.size() != n_) return false;
      Eigen::Map<VectorXd>(z_L, n_) = z_lower_;
      Eigen::Map<VectorXd>(z_U, n_) = z_upper_;
    }
    if (init_lambda) Eigen::Map<VectorXd>(lambda, m_) = lambda_;
    return true;
  }

  bool eval_f(Index, const Number* x, bool new_x, Number& f) override {
    if (new_x) set(x);
    double value = 0.0;
    if (!problem_.objective(point_, value, nullptr) || !std::isfinite(value)) return false;
    f = value;
    return true;
  }

  bool eval_grad_f(Index, const Number* x, bool new_x, Number* grad_f) override {
    if (new_x) set(x);
    if (!lie_gradient()) return false;
    Eigen::Map<VectorXd> g(grad_f, n_);
    g = gradient_;
    chart_.to_chart_gradient(g);  // ∂f/∂θ_i = J_l(θ_i)ᵀ g_i
    return true;
  }

  bool eval_g(Index, const Number* x, bool new_x, Index, Number* g) override {
    if (new_x) set(x);
    VectorXd c(m_);
    if (!problem_.constraint_values(point_, c, nullptr) || !sized(c, m_, 1, "constraint_values: c") ||
        !c.allFinite()) {
      return false;
    }
    Eigen::Map<VectorXd>(g, m_) = c;
    return true;
  }

  bool eval_jac_g(Index, const Number* x, bool new_x, Index, Index, Index* iRow, Index* jCol,
                  Number* values) override {
    if (values == nullptr) {
      jacobian_pattern_.structure(iRow, jCol);
      return true;
    }
    if (new_x) set(x);
    if (!lie_jacobian()) return false;
    const Sparse J = jacobian_ * chart_matrix();  // ∂c/∂θ_i = A_i J_l(θ_i)
    return scatter(J, jacobian_pattern_, false, values);
  }

  bool eval_h(Index, const Number* x, bool new_x, Number obj_factor, Index, const Number* lambda,
              bool, Index, Index* iRow, Index* jCol, Number* values) override {
    if (values == nullptr) {  // the lower triangle
      hessian_pattern_.structure(iRow, jCol);
      return true;
    }
    if (new_x) set(x);
    const Eigen::Map<const VectorXd> l(lambda, m_);
    Sparse H(n_, n_);
    if (!lie_hessian(obj_factor, l, H)) return false;
    if (!lie_gradient() || !lie_jacobian()) return false;
    const VectorXd lagrangian_gradient = obj_factor * gradient_ + jacobian_.transpose() * l;
    // Tᵀ H T with T = diag(J_l(θ_1), …, J_l(θ_r), I), then C(θ_i, ∇L_i) on each rotation's
    // diagonal block.
    const Sparse T = chart_matrix();
    const Sparse symmetric = 0.5 * (H + Sparse(H.transpose()));
    const Sparse charted = Sparse(T.transpose()) * symmetric * T;
    if (!scatter(charted, hessian_pattern_, true, values)) return false;
    CorrectionSink sink{*this, values};
    chart_.add_corrections(lagrangian_gradient, sink);
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn, Index, const Number* x, const Number* z_L,
                         const Number* z_U, Index, const Number*, const Number* lambda,
                         Number obj_value, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    set(x);
    z_lower_ = Eigen::Map<const VectorXd>(z_L, n_);
    z_upper_ = Eigen::Map<const VectorXd>(z_U, n_);
    lambda_ = Eigen::Map<const VectorXd>(lambda, m_);
    objective_ = obj_value;
    warm_ = true;
    // Keep the rotations rotations: exp(θ) R0 drifts from SO(3) by round-off per re-centring.
    for (Eigen::Matrix3d& R : point_.rotations) R = so3::orthonormalize(R);
    constraints_.resize(m_);
    if (m_ > 0 && !problem_.constraint_values(point_, constraints_, nullptr)) {
      constraints_.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }

 private:
  // The entries of variable `index`'s block: a rotation's three, or a vector entry alone.
  std::pair<int, int> block(int index) const {
    return index < 3 * rotations_ ? std::pair{index - index % 3, 3} : std::pair{index, 1};
  }
  // Every lower-triangle entry of the block pair holding (row, column).
  void add_block_pair(int row, int column) {
    const auto [r0, rows] = block(row);
    const auto [c0, columns] = block(column);
    for (int r = r0; r < r0 + rows; ++r) {
      for (int c = c0; c < c0 + columns; ++c) {
        if (r >= c) hessian_pattern_.add(r, c);
      }
    }
  }
  // T = diag(J_l(θ_1), …, J_l(θ_r), I): a change of the chart variables as a Lie perturbation.
  Sparse chart_matrix() const {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(9 * rotations_ + n_);
    for (int i = 0; i < rotations_; ++i) {
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) t.emplace_back(3 * i + a, 3 * i + b, chart_.jacobian(i)(a, b));
      }
    }
    for (int j = 3 * rotations_; j < n_; ++j) t.emplace_back(j, j, 1.0);
    Sparse T(n_, n_);
    T.setFromTriplets(t.begin(), t.end());
    return T;
  }
  // Writes A's entries (its lower triangle only if `lower`) into `values` at their slots of
  // `pattern`, the others 0; false if A has a nonzero outside the pattern or is not finite.
  static bool scatter(const Sparse& A, const Pattern& pattern, bool lower, Number* values) {
    std::fill(values, values + pattern.size(), 0.0);
    for (int k = 0; k < A.outerSize(); ++k) {
      for (Sparse::InnerIterator it(A, k); it; ++it) {
        if (lower && it.row() < it.col()) continue;
        const int slot = pattern.slot(static_cast<int>(it.row()), static_cast<int>(it.col()));
        if (!std::isfinite(it.value()) || (slot < 0 && it.value() != 0.0)) return false;
        if (slot >= 0) values[slot] += it.value();
      }
    }
    return true;
  }
  // Receives the chart's C(θ, g) blocks (RotationVectorChart::add_corrections) into the
  // Hessian's values (every rotation's diagonal block is in the pattern).
  struct CorrectionSink {
    const ChartNlp& nlp;
    Number* values;
    void add(int row, int column, const Eigen::Matrix3d& block) {
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b <= a; ++b) values[nlp.hessian_pattern_.slot(row + a, column + b)] += block(a, b);
      }
    }
  };
  static std::vector<int> rotation_offsets(int rotations) {
    std::vector<int> offsets;
    for (int i = 0; i < rotations; ++i) offsets.push_back(3 * i);
    return offsets;
  }
  // Writes the chart point z into point_ (R_i = exp(θ_i) R0_i, with J_l(θ_i)).
  void set(const Number* x) {
    z_ = Eigen::Map<const VectorXd>(x, n_);
    for (int i = 0; i < rotations_; ++i) point_.rotations[i] = chart_.set(i, z_.segment<3>(3 * i));
    point_.vector = z_.tail(n_ - 3 * rotations_);
    have_gradient_ = have_jacobian_ = false;
  }
  bool lie_gradient() {
    if (have_gradient_) return true;
    double value = 0.0;
    gradient_.setZero(n_);  // sized again: the problem may have resized it last time
    have_gradient_ = problem_.objective(point_, value, &gradient_) &&
                     sized(gradient_, n_, 1, "objective: the gradient") && gradient_.allFinite();
    return have_gradient_;
  }
  // The constraints' Lie Jacobian at point_, as a sparse matrix whichever way it is given.
  bool lie_jacobian() {
    if (have_jacobian_) return true;
    jacobian_.resize(m_, n_);
    jacobian_.setZero();
    if (m_ == 0) {
      have_jacobian_ = true;
    } else if (problem_.sparse()) {
      have_jacobian_ = problem_.constraint_jacobian(point_, jacobian_) &&
                       sized(jacobian_, m_, n_, "constraint_jacobian: the Jacobian");
      jacobian_.makeCompressed();
      have_jacobian_ = have_jacobian_ && finite(jacobian_);
    } else {
      VectorXd c(m_);
      MatrixXd dense = MatrixXd::Zero(m_, n_);
      have_jacobian_ = problem_.constraint_values(point_, c, &dense) &&
                       sized(dense, m_, n_, "constraint_values: the Jacobian") && dense.allFinite();
      jacobian_ = dense.sparseView(0.0, 0.0);
    }
    return have_jacobian_;
  }
  // The Lie Hessian of σf + λᵀc at point_, likewise.
  bool lie_hessian(double sigma, const VectorXd& lambda, Sparse& H) {
    H.resize(n_, n_);
    H.setZero();
    if (problem_.sparse()) {
      const bool given = problem_.lagrangian_hessian(point_, sigma, lambda, H) &&
                         sized(H, n_, n_, "lagrangian_hessian: the Hessian");
      H.makeCompressed();
      return given && finite(H);
    }
    MatrixXd dense = MatrixXd::Zero(n_, n_);
    if (!problem_.lagrangian_hessian(point_, sigma, lambda, dense) ||
        !sized(dense, n_, n_, "lagrangian_hessian: the Hessian") || !dense.allFinite()) {
      return false;
    }
    H = dense.sparseView(0.0, 0.0);
    return true;
  }
  // False, and the first such error kept for the summary, if the problem resized `a` away from
  // rows × columns (tangent layout: lie_ipopt.hpp).
  template <class Matrix>
  bool sized(const Matrix& a, Eigen::Index rows, Eigen::Index columns, const char* what) {
    if (a.rows() == rows && a.cols() == columns) return true;
    if (error_.empty()) {
      error_ = std::string(what) + " is " + std::to_string(a.rows()) + " × " + std::to_string(a.cols()) +
               ", expected " + std::to_string(rows) + " × " + std::to_string(columns) +
               " (3 entries per rotation, then the vector; one row per constraint)";
    }
    return false;
  }
  static bool finite(const Sparse& A) {
    return std::all_of(A.valuePtr(), A.valuePtr() + A.nonZeros(), [](double v) { return std::isfinite(v); });
  }

  LieNlp& problem_;
  int rotations_, n_, m_;
  bool exact_hessian_ = false;
  RotationVectorChart chart_;  // R_i = exp(θ_i) R0_i, and J_l(θ_i)
  LiePoint point_;             // at z_
  VectorXd z_, z_lower_, z_upper_, lambda_;
  VectorXd gradient_;  // Lie gradient of f at point_ (when have_gradient_)
  Sparse jacobian_;    // Lie Jacobian of c at point_ (when have_jacobian_)
  Pattern jacobian_pattern_, hessian_pattern_;
  VectorXd constraints_;
  bool have_gradient_ = false, have_jacobian_ = false, warm_ = false;
  std::string error_;  // the first malformed answer of the problem (sized)
  double objective_ = 0.0;
};

// The largest violation of c_L ≤ c ≤ c_U.
double bound_violation(const VectorXd& c, const VectorXd& lower, const VectorXd& upper) {
  double worst = 0.0;
  for (Eigen::Index r = 0; r < c.size(); ++r) {
    if (!std::isfinite(c(r))) return std::numeric_limits<double>::infinity();
    worst = std::max({worst, lower(r) - c(r), c(r) - upper(r)});
  }
  return worst;
}

}  // namespace

LieIpoptSummary solve_with_ipopt(LieNlp& problem, LiePoint& x, const LieIpoptOptions& options) {
  options.validate();
  const int m = problem.constraints();
  if (m < 0) throw std::invalid_argument("solve_with_ipopt: constraints() returned a negative count");
  for (std::size_t i = 0; i < x.rotations.size(); ++i) {
    const Eigen::Matrix3d& R = x.rotations[i];
    if (!R.allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
        R.determinant() < 0.0) {
      throw std::invalid_argument("solve_with_ipopt: x.rotations[" + std::to_string(i) +
                                  "] is not a rotation (RᵀR = I, det R = 1 to 1e-6)");
    }
  }
  if (!x.vector.allFinite()) throw std::invalid_argument("solve_with_ipopt: x.vector is not finite");

  auto* nlp = new ChartNlp(problem, x);
  const Ipopt::SmartPtr<Ipopt::TNLP> tnlp = nlp;  // owns it (Ipopt's reference count)
  if (!nlp->record_patterns(options.hessian)) {
    LieIpoptSummary failed;
    failed.message = "the problem's derivatives cannot be evaluated at the starting point";
    if (!nlp->error().empty()) failed.message += ": " + nlp->error();
    return failed;
  }
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = new Ipopt::IpoptApplication();
  Ipopt::OptionsList& o = *app->Options();
  o.SetIntegerValue("print_level", options.print_level);
  if (options.print_level == 0) o.SetStringValue("sb", "yes");
  if (!options.output_file.empty()) {
    o.SetStringValue("output_file", options.output_file);
    o.SetIntegerValue("file_print_level", std::max(options.print_level, 5));
  }
  o.SetStringValue("linear_solver", "mumps");
  o.SetStringValue("hessian_approximation", nlp->exact_hessian() ? "exact" : "limited-memory");
  o.SetStringValue("derivative_test", options.derivative_test);
  // The checker moves the starting point by up to this much per variable: within the chart.
  o.SetNumericValue("point_perturbation_radius", 0.1);
  o.SetNumericValue("tol", options.tolerance);
  // Further options: not those the fields above own or the solve loop sets.
  const auto check = [](const std::string& name, bool accepted) {
    static const std::map<std::string, std::string> owned = {
        {"tol", "tolerance"},           {"max_iter", "max_iterations"},
        {"hessian_approximation", "hessian"}, {"print_level", "print_level"},
        {"derivative_test", "derivative_test"}, {"output_file", "output_file"},
        {"warm_start_init_point", "(set by the re-centring)"}};
    if (const auto it = owned.find(name); it != owned.end()) {
      throw std::invalid_argument("LieIpoptOptions: the Ipopt option \"" + name +
                                  "\" is set through LieIpoptOptions::" + it->second);
    }
    if (!accepted) {
      throw std::invalid_argument("LieIpoptOptions: Ipopt refuses the option \"" + name +
                                  "\" (unknown, of another type, or its value out of range)");
    }
  };
  for (const auto& [name, value] : options.ipopt_strings) check(name, o.SetStringValue(name, value));
  for (const auto& [name, value] : options.ipopt_integers) check(name, o.SetIntegerValue(name, value));
  for (const auto& [name, value] : options.ipopt_numbers) check(name, o.SetNumericValue(name, value));
  // Initialize("") reads no options file; in Ipopt 3.11 it fails only when the output file
  // cannot be opened.
  if (app->Initialize("") != Ipopt::Solve_Succeeded) {
    throw std::invalid_argument("LieIpoptOptions::output_file: cannot open \"" +
                                options.output_file + "\" for writing");
  }

  LieIpoptSummary summary;
  Ipopt::ApplicationReturnStatus status = Ipopt::Internal_Error;
  for (;;) {
    o.SetIntegerValue("max_iter", std::max(0, options.max_iterations - summary.iterations));
    if (nlp->warm()) o.SetStringValue("warm_start_init_point", "yes");
    status = summary.solves == 0 ? app->OptimizeTNLP(tnlp) : app->ReOptimizeTNLP(tnlp);
    ++summary.solves;
    if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); IsValid(stats)) {
      summary.iterations += stats->IterationCount();
      double constraint_violation, complementarity, kkt_error;
      stats->Infeasibilities(summary.dual_infeasibility, constraint_violation, complementarity,
                             kkt_error);
    }
    const bool solved = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
    const double angle = nlp->largest_chart_angle();
    if (!solved || angle <= options.recentre_angle || summary.solves > options.max_recentrings ||
        summary.iterations >= options.max_iterations) {
      summary.message = std::string("Ipopt: ") + ipopt_status_name(status) + " after " +
                        std::to_string(summary.solves) + " solve(s)";
      if (!nlp->error().empty()) summary.message += "; the problem's " + nlp->error();
      if (solved && angle > options.recentre_angle) {
        summary.message += "; the last chart moved a rotation by " + std::to_string(angle) +
                           " rad (> recentre_angle) with no re-centring left";
      }
      break;
    }
    nlp->recentre();
  }

  x = nlp->point();
  summary.objective = nlp->objective();
  summary.multipliers = nlp->multipliers();
  Eigen::VectorXd lower(m), upper(m);
  problem.constraint_bounds(lower, upper);
  summary.constraint_violation = bound_violation(nlp->constraint_values(), lower, upper);
  switch (status) {
    case Ipopt::Solve_Succeeded: summary.termination = LieIpoptTermination::kConverged; break;
    case Ipopt::Solved_To_Acceptable_Level: summary.termination = LieIpoptTermination::kAcceptable; break;
    case Ipopt::Maximum_Iterations_Exceeded:
    case Ipopt::Maximum_CpuTime_Exceeded: summary.termination = LieIpoptTermination::kNoConvergence; break;
    default: summary.termination = LieIpoptTermination::kFailure; break;
  }
  return summary;
}

}  // namespace liedyn

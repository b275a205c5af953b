// The public Ipopt adapter (manifolds/lie_ipopt.hpp): Ipopt's derivative checker on the chart
// derivatives it builds from Lie ones, solutions against closed forms, the Lie KKT
// conditions at the solution, re-centring from far starts (angles up to π − 1e-6), bounds,
// exact against limited-memory Hessians, and the errors.

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include "lib/so3.hpp"
#include "lib/state.hpp"
#include "manifolds/lie_ipopt.hpp"

namespace liedyn {
namespace {

using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

// f(R) = −tr(R Mᵀ) = ½‖R − M‖²_F + const: the chordal mean of rotations summing to M.
// With B = R Mᵀ and exp(δ) ≈ I + hat(δ) + ½ hat(δ)², tr(hat(δ) B) = −2 δ·vee(B) and
// tr(hat(δ)² B) = δᵀBδ − ‖δ‖² tr B give
//   Lie gradient 2 vee(B),   Lie Hessian tr(B) I − ½(B + Bᵀ).
// Its minimiser is the polar factor of M.
struct Chordal {
  Matrix3d M;
  double value(const Matrix3d& R) const { return -(R * M.transpose()).trace(); }
  Vector3d gradient(const Matrix3d& R) const { return 2.0 * so3::vee(R * M.transpose()); }
  Matrix3d hessian(const Matrix3d& R) const {
    const Matrix3d B = R * M.transpose();
    return B.trace() * Matrix3d::Identity() - 0.5 * (B + B.transpose());
  }
  Matrix3d minimiser() const {
    const Eigen::JacobiSVD<Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Matrix3d D = Matrix3d::Identity();
    D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant();
    return svd.matrixU() * D * svd.matrixV().transpose();
  }
};

// A point a = R ā of a rotation paired with a vector v: t = a·v.
//   ∂t/∂δ = a × v,  ∂t/∂v = a,
//   ∂²t/∂δ² = ½(a vᵀ + v aᵀ) − (a·v) I   (lib/state.hpp, rotated_point_curvature),
//   ∂²t/∂δ∂v = hat(a)   (∂(a × v)/∂v).
struct Pairing {
  static void add_hessian(const Vector3d& a, const Vector3d& v, double weight, int rotation,
                          int vector, MatrixXd& H) {
    H.block<3, 3>(rotation, rotation) += weight * rotated_point_curvature(a, v);
    H.block<3, 3>(rotation, vector) += weight * so3::hat(a);
    H.block<3, 3>(vector, rotation) += weight * so3::hat(a).transpose();
  }
};

// Two rotations and a 3-vector:
//   f = −tr(R₁M₁ᵀ) − tr(R₂M₂ᵀ) + ½‖v − b‖² + κ v·(R₁e₁),
//   c = v·(R₂e₃) − 1 = 0   (optional).
// Tangent layout: R₁ at 0, R₂ at 3, v at 6.
class TwoRotations final : public LieNlp {
 public:
  Chordal f1{}, f2{};
  Vector3d b = Vector3d(0.3, -0.2, 1.4);
  double kappa = 0.4;
  bool constrained = true;
  bool hessian = true;
  Vector3d upper = Vector3d::Constant(std::numeric_limits<double>::infinity());

  int constraints() const override { return constrained ? 1 : 0; }
  void vector_bounds(VectorXd& lower, VectorXd& up) const override {
    lower.setConstant(-std::numeric_limits<double>::infinity());
    up = upper;
  }
  bool objective(const LiePoint& x, double& f, VectorXd* g) override {
    const Matrix3d &R1 = x.rotations[0], &R2 = x.rotations[1];
    const Vector3d v = x.vector, a = R1.col(0);
    f = f1.value(R1) + f2.value(R2) + 0.5 * (v - b).squaredNorm() + kappa * v.dot(a);
    if (g != nullptr) {
      g->segment<3>(0) = f1.gradient(R1) + kappa * a.cross(v);
      g->segment<3>(3) = f2.gradient(R2);
      g->segment<3>(6) = v - b + kappa * a;
    }
    return true;
  }
  bool constraint_values(const LiePoint& x, VectorXd& c, MatrixXd* J) override {
    if (!constrained) return true;
    const Vector3d a = x.rotations[1].col(2), v = x.vector;
    c(0) = a.dot(v) - 1.0;
    if (J != nullptr) {
      J->setZero();
      J->block<1, 3>(0, 3) = a.cross(v).transpose();
      J->block<1, 3>(0, 6) = a.transpose();
    }
    return true;
  }
  bool lagrangian_hessian(const LiePoint& x, double sigma, const VectorXd& lambda,
                          MatrixXd& H) override {
    if (!hessian) return false;
    const Vector3d v = x.vector;
    H.setZero();
    H.block<3, 3>(0, 0) = sigma * f1.hessian(x.rotations[0]);
    H.block<3, 3>(3, 3) = sigma * f2.hessian(x.rotations[1]);
    H.block<3, 3>(6, 6) = sigma * Matrix3d::Identity();
    Pairing::add_hessian(x.rotations[0].col(0), v, sigma * kappa, 0, 6, H);
    if (constrained) Pairing::add_hessian(x.rotations[1].col(2), v, lambda(0), 3, 6, H);
    return true;
  }
};

Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector3d axis(n(rng), n(rng), n(rng));
  std::uniform_real_distribution<double> angle(0.0, std::numbers::pi);
  return so3::exp(angle(rng) * axis.normalized());
}

Matrix3d random_matrix(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Matrix3d M;
  for (int i = 0; i < 9; ++i) M(i) = n(rng);
  return M;
}

TwoRotations make_problem(unsigned seed) {
  std::mt19937 rng(seed);
  TwoRotations p;
  p.f1.M = 2.0 * random_rotation(rng) + 0.3 * random_matrix(rng);
  p.f2.M = 2.0 * random_rotation(rng) + 0.3 * random_matrix(rng);
  return p;
}

LiePoint start_point(unsigned seed) {
  std::mt19937 rng(seed + 1000);
  LiePoint x;
  x.rotations = {random_rotation(rng), random_rotation(rng)};
  x.vector = Vector3d(0.5, 0.5, 0.5);
  return x;
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::filesystem::path log_path(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("liedyn_lie_ipopt_" + name + "_" + std::to_string(::getpid()) + ".txt");
}

// The text of an Ipopt log file, which is then removed.
std::string take_log(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  in.close();
  std::filesystem::remove(path);
  return text.str();
}

// ‖σ∇f + Aᵀλ‖∞ in Lie coordinates: zero at a KKT point without active bounds.
double lie_kkt_residual(TwoRotations& p, const LiePoint& x, const VectorXd& lambda) {
  double f;
  VectorXd g(x.tangent_size());
  p.objective(x, f, &g);
  if (p.constraints() > 0) {
    VectorXd c(1);
    MatrixXd J(1, x.tangent_size());
    p.constraint_values(x, c, &J);
    g += J.transpose() * lambda;
  }
  return g.lpNorm<Eigen::Infinity>();
}

// Solves from x with Ipopt's second-order derivative checker on, which must find no error
// in any solve. Every solve starts at θ = 0 and the checker moves it by up to 0.1 per
// variable, so J_l(θ) ≠ I and C(θ, g) ≠ 0 are exercised; far starts re-centre and check again.
void expect_checker_finds_no_errors(LieNlp& problem, LiePoint x) {
  LieIpoptOptions options;
  options.derivative_test = "second-order";
  options.output_file = log_path("checker").string();
  const LieIpoptSummary summary = solve_with_ipopt(problem, x, options);
  EXPECT_TRUE(summary.converged()) << summary.message;
  const std::string log = take_log(options.output_file);
  EXPECT_EQ(count(log, "Starting derivative checker for second derivatives."), summary.solves);
  EXPECT_EQ(count(log, "No errors detected by derivative checker."), summary.solves)
      << log.substr(0, 6000);
  EXPECT_EQ(count(log, "Derivative checker detected"), 0);
}

TEST(LieIpopt, DerivativeCheckerFindsNoErrorsInTheChartDerivatives) {
  for (const bool constrained : {false, true}) {
    SCOPED_TRACE(constrained ? "constrained" : "unconstrained");
    TwoRotations p = make_problem(1);
    p.constrained = constrained;
    expect_checker_finds_no_errors(p, start_point(1));
  }
}

TEST(LieIpopt, ReachesThePolarFactorFromEveryStartingAngle) {
  // Unconstrained, κ = 0: each rotation's minimiser is the polar factor of its M.
  for (const double angle : {0.0, 1e-9, 1e-4, 1.0, 2.5, std::numbers::pi - 1e-6}) {
    for (const char* hessian : {"exact", "limited-memory"}) {
      SCOPED_TRACE("start " + std::to_string(angle) + " rad away, " + hessian);
      TwoRotations p = make_problem(2);
      p.constrained = false;
      p.kappa = 0.0;
      const Matrix3d R1 = p.f1.minimiser(), R2 = p.f2.minimiser();
      LiePoint x;
      const Vector3d axis1 = Vector3d(1.0, 2.0, -0.5).normalized();
      const Vector3d axis2 = Vector3d(-0.3, 0.4, 1.0).normalized();
      x.rotations = {so3::exp(angle * axis1) * R1, so3::exp(angle * axis2) * R2};
      x.vector = Vector3d::Zero();
      LieIpoptOptions options;
      options.hessian = hessian;
      const LieIpoptSummary summary = solve_with_ipopt(p, x, options);
      ASSERT_TRUE(summary.converged()) << summary.message;
      EXPECT_LT(so3::distance(x.rotations[0], R1), 1e-6);
      EXPECT_LT(so3::distance(x.rotations[1], R2), 1e-6);
      EXPECT_LT((x.vector - p.b).lpNorm<Eigen::Infinity>(), 1e-7);
      EXPECT_LT((x.rotations[0].transpose() * x.rotations[0] - Matrix3d::Identity()).norm(), 1e-14);
      // A chart that moved a rotation by more than recentre_angle (1 rad) is followed by a
      // re-centred solve.
      if (angle > options.recentre_angle + 0.1) {
        EXPECT_GE(summary.solves, 2);
      }
      if (angle < 1e-3) {
        EXPECT_EQ(summary.solves, 1);
      }
    }
  }
}

TEST(LieIpopt, ConstrainedSolutionMeetsTheLieKktConditions) {
  for (const unsigned seed : {3u, 4u, 5u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    LiePoint solutions[2];
    int k = 0;
    for (const char* hessian : {"exact", "limited-memory"}) {
      TwoRotations p = make_problem(seed);
      LiePoint x = start_point(seed);
      LieIpoptOptions options;
      options.hessian = hessian;
      const LieIpoptSummary summary = solve_with_ipopt(p, x, options);
      ASSERT_TRUE(summary.converged()) << hessian << ": " << summary.message;
      EXPECT_LT(summary.constraint_violation, 1e-9);
      EXPECT_LT(summary.dual_infeasibility, 1e-7);
      EXPECT_LT(std::abs(x.rotations[1].col(2).dot(x.vector) - 1.0), 1e-9);
      ASSERT_EQ(summary.multipliers.size(), 1);
      // Ipopt's tolerance is on its scaled KKT error; the Lie residual is the same residual
      // times J_l(θ)⁻ᵀ, θ small at the end.
      EXPECT_LT(lie_kkt_residual(p, x, summary.multipliers), 1e-7) << hessian;
      double f;
      p.objective(x, f, nullptr);
      EXPECT_NEAR(summary.objective, f, 1e-12 * (1.0 + std::abs(f)));
      solutions[k++] = x;
    }
    // Exact and limited-memory Hessians find the same local minimiser from the same start.
    EXPECT_LT(so3::distance(solutions[0].rotations[0], solutions[1].rotations[0]), 1e-5);
    EXPECT_LT(so3::distance(solutions[0].rotations[1], solutions[1].rotations[1]), 1e-5);
    EXPECT_LT((solutions[0].vector - solutions[1].vector).norm(), 1e-5);
  }
}

TEST(LieIpopt, ExactHessianTakesFewerIterationsThanLimitedMemory) {
  // A wrong chart Hessian (missing J_l or C) would cost Newton its fast local convergence;
  // the checker test above is the direct check, this one the consequence.
  int iterations[2];
  int k = 0;
  for (const char* hessian : {"exact", "limited-memory"}) {
    TwoRotations p = make_problem(6);
    LiePoint x = start_point(6);
    LieIpoptOptions options;
    options.hessian = hessian;
    const LieIpoptSummary summary = solve_with_ipopt(p, x, options);
    ASSERT_TRUE(summary.converged()) << summary.message;
    iterations[k++] = summary.iterations;
  }
  EXPECT_LT(iterations[0], iterations[1]);
}

TEST(LieIpopt, VectorBoundsHold) {
  TwoRotations p = make_problem(7);
  p.constrained = false;
  p.kappa = 0.0;
  p.upper = Vector3d(0.1, 10.0, 10.0);  // b = (0.3, …): the first bound is active
  LiePoint x = start_point(7);
  x.vector.setZero();
  const LieIpoptSummary summary = solve_with_ipopt(p, x);
  ASSERT_TRUE(summary.converged()) << summary.message;
  EXPECT_NEAR(x.vector(0), 0.1, 1e-8);
  EXPECT_NEAR(x.vector(1), p.b(1), 1e-7);
  EXPECT_NEAR(x.vector(2), p.b(2), 1e-7);
}

// The same problem through the sparse interface, with the structural nonzeros (zeros
// included) of every block that can be nonzero: the Jacobian's row touches R₂ and v; the
// Hessian has the diagonal blocks, R₁–v (κ) and R₂–v (λ).
class SparseTwoRotations final : public LieNlp {
 public:
  explicit SparseTwoRotations(TwoRotations dense) : dense_(std::move(dense)) {}
  TwoRotations& dense() { return dense_; }
  // Leave the R₁–v blocks out of the first Hessian (the pattern), not of later ones.
  bool drop_first_coupling = false;

  bool sparse() const override { return true; }
  int constraints() const override { return dense_.constraints(); }
  void vector_bounds(VectorXd& lower, VectorXd& upper) const override { dense_.vector_bounds(lower, upper); }
  bool objective(const LiePoint& x, double& f, VectorXd* g) override { return dense_.objective(x, f, g); }
  bool constraint_values(const LiePoint& x, VectorXd& c, MatrixXd* J) override {
    EXPECT_EQ(J, nullptr);  // sparse(): the dense Jacobian is never asked for
    return dense_.constraint_values(x, c, nullptr);
  }
  bool constraint_jacobian(const LiePoint& x, Eigen::SparseMatrix<double>& J) override {
    VectorXd c(1);
    MatrixXd D(1, x.tangent_size());
    dense_.constraint_values(x, c, &D);
    J = blocks(D, {{0, 3}, {0, 6}}, 1);
    return true;
  }
  bool lagrangian_hessian(const LiePoint& x, double sigma, const VectorXd& lambda,
                          Eigen::SparseMatrix<double>& H) override {
    MatrixXd D(x.tangent_size(), x.tangent_size());
    dense_.lagrangian_hessian(x, sigma, lambda, D);
    std::vector<std::pair<int, int>> at = {{0, 0}, {3, 3}, {6, 6}, {3, 6}, {6, 3}};
    if (!(drop_first_coupling && calls_++ == 0)) at.insert(at.end(), {{0, 6}, {6, 0}});
    H = blocks(D, at, 3);
    return true;
  }

 private:
  // The 3-column blocks of D at the given (row, column) starts, `rows` rows each, zeros kept.
  static Eigen::SparseMatrix<double> blocks(const MatrixXd& D, const std::vector<std::pair<int, int>>& at,
                                           int rows) {
    std::vector<Eigen::Triplet<double>> t;
    for (const auto& [r0, c0] : at) {
      for (int r = r0; r < r0 + rows; ++r) {
        for (int c = c0; c < c0 + 3; ++c) t.emplace_back(r, c, D(r, c));
      }
    }
    Eigen::SparseMatrix<double> S(D.rows(), D.cols());
    S.setFromTriplets(t.begin(), t.end());
    return S;
  }
  TwoRotations dense_;
  int calls_ = 0;
};

TEST(LieIpopt, SparseDerivativesGiveTheDenseSolve) {
  for (const bool constrained : {false, true}) {
    SCOPED_TRACE(constrained ? "constrained" : "unconstrained");
    TwoRotations dense = make_problem(10);
    dense.constrained = constrained;
    SparseTwoRotations sparse(dense);
    // The chart derivatives through the sparse patterns, by Ipopt's checker.
    expect_checker_finds_no_errors(sparse, start_point(10));
    LiePoint x_dense = start_point(10), x_sparse = start_point(10);
    const LieIpoptSummary s = solve_with_ipopt(sparse, x_sparse);
    const LieIpoptSummary d = solve_with_ipopt(dense, x_dense);
    ASSERT_TRUE(s.converged()) << s.message;
    ASSERT_TRUE(d.converged()) << d.message;
    // The same NLP, with its Jacobian and Hessian given as fewer entries: Ipopt takes the same
    // path, up to the round-off of summing the products in another order.
    EXPECT_EQ(s.iterations, d.iterations);
    EXPECT_LT(so3::distance(x_sparse.rotations[0], x_dense.rotations[0]), 1e-10);
    EXPECT_LT(so3::distance(x_sparse.rotations[1], x_dense.rotations[1]), 1e-10);
    EXPECT_LT((x_sparse.vector - x_dense.vector).norm(), 1e-10);
  }
}

TEST(LieIpopt, AnEntryOutsideTheFirstPatternIsAnEvaluationError) {
  SparseTwoRotations sparse(make_problem(11));
  sparse.drop_first_coupling = true;
  LiePoint x = start_point(11);
  const LieIpoptSummary summary = solve_with_ipopt(sparse, x);
  EXPECT_EQ(summary.termination, LieIpoptTermination::kFailure) << summary.message;
  // Ipopt 3.11 treats a failed eval_h as an invalid number in the step computation.
  EXPECT_NE(summary.message.find("Invalid_Number_Detected"), std::string::npos) << summary.message;
}

TEST(LieIpopt, RejectsBadOptionsAndPoints) {
  const auto expect_invalid = [](const LieIpoptOptions& o, const std::string& field) {
    try {
      o.validate();
      ADD_FAILURE() << "accepted a bad " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  EXPECT_NO_THROW(LieIpoptOptions{}.validate());
  const std::pair<const char*, void (*)(LieIpoptOptions&)> bad[] = {
      {"tolerance", [](LieIpoptOptions& o) { o.tolerance = 0.0; }},
      {"tolerance", [](LieIpoptOptions& o) { o.tolerance = std::numeric_limits<double>::quiet_NaN(); }},
      {"max_iterations", [](LieIpoptOptions& o) { o.max_iterations = 0; }},
      {"max_recentrings", [](LieIpoptOptions& o) { o.max_recentrings = -1; }},
      {"recentre_angle", [](LieIpoptOptions& o) { o.recentre_angle = 4.0; }},
      {"hessian", [](LieIpoptOptions& o) { o.hessian = "bfgs"; }},
      {"print_level", [](LieIpoptOptions& o) { o.print_level = 13; }},
      {"derivative_test", [](LieIpoptOptions& o) { o.derivative_test = "third-order"; }}};
  for (const auto& [field, spoil] : bad) {
    LieIpoptOptions o;
    spoil(o);
    expect_invalid(o, field);
  }

  TwoRotations p = make_problem(8);
  LiePoint x = start_point(8);
  x.rotations[1] *= 1.01;  // not orthonormal
  EXPECT_THROW(solve_with_ipopt(p, x), std::invalid_argument);
  x = start_point(8);
  x.rotations[0] = -x.rotations[0];  // det = −1
  EXPECT_THROW(solve_with_ipopt(p, x), std::invalid_argument);

  x = start_point(8);
  p.hessian = false;
  LieIpoptOptions exact;
  exact.hessian = "exact";
  EXPECT_THROW(solve_with_ipopt(p, x, exact), std::invalid_argument);
  // "auto" falls back to the quasi-Newton approximation.
  EXPECT_TRUE(solve_with_ipopt(p, x).converged());

  LieIpoptOptions file;
  file.output_file = "/nonexistent-directory/ipopt.txt";
  x = start_point(8);
  EXPECT_THROW(solve_with_ipopt(p, x, file), std::invalid_argument);
}

// A problem that resizes what it is given gets an evaluation error naming what, not a
// read past the end.
class WrongSizes final : public LieNlp {
 public:
  TwoRotations inner = make_problem(12);
  bool short_gradient = false;
  bool wide_jacobian = false;
  int constraints() const override { return inner.constraints(); }
  bool objective(const LiePoint& x, double& f, VectorXd* g) override {
    inner.objective(x, f, g);
    if (g != nullptr && short_gradient) g->conservativeResize(g->size() - 1);
    return true;
  }
  bool constraint_values(const LiePoint& x, VectorXd& c, MatrixXd* J) override {
    inner.constraint_values(x, c, J);
    if (J != nullptr && wide_jacobian) J->conservativeResize(J->rows(), J->cols() + 3);
    return true;
  }
};

TEST(LieIpopt, ProblemsThatResizeTheirOutputsAreReported) {
  {
    WrongSizes p;
    p.short_gradient = true;
    LiePoint x = start_point(12);
    const LieIpoptSummary s = solve_with_ipopt(p, x);
    EXPECT_FALSE(s.converged());
    EXPECT_NE(s.message.find("objective: the gradient is 8 × 1, expected 9 × 1"), std::string::npos)
        << s.message;
  }
  {
    WrongSizes p;
    p.wide_jacobian = true;
    LiePoint x = start_point(12);
    const LieIpoptSummary s = solve_with_ipopt(p, x);
    EXPECT_FALSE(s.converged());
    EXPECT_NE(s.message.find("constraint_values: the Jacobian is 1 × 12, expected 1 × 9"),
              std::string::npos)
        << s.message;
  }
}

TEST(LieIpopt, PassesFurtherIpoptOptionsAndRefusesUnknownOnes) {
  TwoRotations p = make_problem(13);
  LiePoint x = start_point(13);
  LieIpoptOptions options;
  options.ipopt_strings["mu_strategy"] = "adaptive";
  options.ipopt_integers["max_soc"] = 2;
  options.ipopt_numbers["bound_push"] = 1e-3;
  EXPECT_TRUE(solve_with_ipopt(p, x, options).converged());
  // They reach Ipopt: it lists them among the options set (print_user_options, itself one).
  LieIpoptOptions checked;
  checked.output_file = log_path("options").string();
  checked.ipopt_strings["check_derivatives_for_naninf"] = "yes";
  checked.ipopt_strings["print_user_options"] = "yes";
  checked.ipopt_numbers["derivative_test_tol"] = 1e-3;
  x = start_point(13);
  EXPECT_TRUE(solve_with_ipopt(p, x, checked).converged());
  // Ipopt's list of user-set options: name, value, and whether it was used.
  const std::string log = take_log(checked.output_file);
  EXPECT_NE(log.find("check_derivatives_for_naninf = yes"), std::string::npos) << log.substr(0, 3000);
  EXPECT_NE(log.find("derivative_test_tol = 0.001"), std::string::npos) << log.substr(0, 3000);
  LieIpoptOptions owned;
  owned.ipopt_integers["max_iter"] = 1;  // LieIpoptOptions::max_iterations
  x = start_point(13);
  EXPECT_THROW(solve_with_ipopt(p, x, owned), std::invalid_argument);
  LieIpoptOptions unknown;
  unknown.ipopt_strings["no_such_option"] = "yes";
  x = start_point(13);
  try {
    solve_with_ipopt(p, x, unknown);
    ADD_FAILURE() << "accepted an unknown option";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_option"), std::string::npos) << e.what();
  }
  LieIpoptOptions wrong_type;
  wrong_type.ipopt_strings["bound_push"] = "small";  // a number
  x = start_point(13);
  EXPECT_THROW(solve_with_ipopt(p, x, wrong_type), std::invalid_argument);
}

TEST(LieIpopt, ReportsAnIterationLimit) {
  TwoRotations p = make_problem(9);
  LiePoint x = start_point(9);
  LieIpoptOptions options;
  options.max_iterations = 2;
  const LieIpoptSummary summary = solve_with_ipopt(p, x, options);
  EXPECT_EQ(summary.termination, LieIpoptTermination::kNoConvergence) << summary.message;
  EXPECT_FALSE(summary.converged());
  EXPECT_LE(summary.iterations, 2);
  EXPECT_NE(summary.message.find("Maximum_Iterations_Exceeded"), std::string::npos) << summary.message;
}

}  // namespace
}  // namespace liedyn

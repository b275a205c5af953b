// rotation_averaging: estimate N rotations from noisy relative rotations, with Ceres and with
// Ipopt, through liedyn's SO3Manifold and LieNlp.
//
// Data. Ground truth R_0 … R_{N−1}: N = 30 uniformly random rotations (fixed seed). The
// measurement graph is a ring (i, i+1 mod N) plus 60 random extra edges; edge (i, j) measures
//   R̃_ij = exp(ε_ij) R_j R_iᵀ,   ε_ij ~ N(0, σ² I₃),  σ = 0.05 rad.
// R_0 is known exactly (the anchor). Relative measurements fix the rotations only up to one
// global rotation (the gauge); holding R_0 fixed removes it.
//
// Problem (geodesic least squares):
//   minimise  f(R_1, …, R_{N−1}) = Σ_edges ½ ‖e_ij‖²,   e_ij = log(R̃_ij R_i R_jᵀ),
// which is 0 at noise-free data. Solved
//   (a) by Ceres: one residual block e_ij per edge, parameter blocks the unit quaternions of
//       R_i and R_j under liedyn::SO3Manifold, R_0's block held constant;
//   (b) by Ipopt: a liedyn::LieNlp over R_1 … R_{N−1} (R_0 is data) with the Lie gradient and
//       the exact Lie Hessian of f,
// both from the same initial guess (the measurements chained around the ring from R_0).
//
// Lie Jacobians of one edge (lib/so3.hpp: left perturbations R ← exp(δ) R, and
// log(exp(δ) E) = log E + J_l⁻¹(e) δ + O(δ²), J_l⁻¹(e) returned by so3::log). With
// E = R̃ R_i R_jᵀ = exp(e):
//   R_i ← exp(δ) R_i:  E ← R̃ exp(δ) R_i R_jᵀ = exp(R̃ δ) E       ⇒  ∂e/∂δ_i = J_l⁻¹(e) R̃,
//   R_j ← exp(δ) R_j:  E ← E exp(−δ) = exp(−E δ) E               ⇒  ∂e/∂δ_j = −J_l⁻¹(e) E,
// using A exp(δ) Aᵀ = exp(A δ) for a rotation A. The Lie gradient of ½‖e‖² is (∂e/∂δ)ᵀ e.
//
// Lie Hessian of one edge. Let Φ(w) = ½ ‖log(exp(w) E)‖². Its gradient at w is J_l(w)ᵀ u(w),
// u(w) = log(exp(w) E) (chain rule through exp(w + η) = exp(J_l(w) η) exp(w), and
// J_l(u)ᵀ u = u), so with J_l(w)ᵀ = I − ½ hat(w) + O(w²):
//   Φ'(0) = e,   Φ''(0) = J_l⁻¹(e) + ½ hat(e) =: H_e   (symmetric: I + c(‖e‖) hat(e)²).
// The edge is Φ(w(δ_i, δ_j)) with exp(w) = exp(R̃ δ_i) exp(−E δ_j), and by BCH
//   w = R̃ δ_i − E δ_j − ½ (R̃ δ_i) × (E δ_j) + O(δ³).
// The Hessian of a composition Φ∘w with w(0) = 0 is Lᵀ Φ''(0) L + Φ'(0)·w'', L = [R̃, −E]; the
// bracket term contributes e·(−½ (R̃δ_i) × (Eδ_j)) = ½ δ_iᵀ R̃ᵀ hat(e) E δ_j. So
//   H_ii = R̃ᵀ H_e R̃,   H_jj = Eᵀ H_e E,   H_ij = −R̃ᵀ H_e E + ½ R̃ᵀ hat(e) E = H_jiᵀ.
// The example checks all of these against finite differences before solving (lie_check.hpp)
// and exits with status 1 if any disagrees by more than 1e-6 relative.
//
// Exit status 0 only if: the derivative checks pass; Ceres converged (IsSolutionUsable and
// termination CONVERGENCE); Ipopt converged; the two costs agree to 1e-6 relative and the two
// solutions to 1e-5 rad; and the mean error against the ground truth, after the best global
// alignment, is below σ (see the comment above `Errors` for why, and for the error in R_0's
// gauge, which is printed but not tested).

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <liedyn/lib/so3.hpp>
#include <liedyn/manifolds/lie_ipopt.hpp>
#include <liedyn/manifolds/so3_manifold.hpp>
#include <numbers>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "lie_check.hpp"

namespace {

using liedyn::SO3Manifold;
using liedyn::so3::hat;
using Matrix3 = Eigen::Matrix3d;
using Vector3 = Eigen::Vector3d;
using Vector4 = Eigen::Vector4d;

constexpr int kRotations = 30;   // N
constexpr int kExtraEdges = 60;  // beside the ring's N
constexpr double kSigma = 0.05;  // rad, per component of ε_ij
constexpr unsigned kSeed = 2024;

// Acceptance thresholds (see the top).
constexpr double kDerivativeTolerance = 1e-6;  // relative, analytic vs central differences
constexpr double kCostAgreement = 1e-6;        // relative
constexpr double kSolutionAgreement = 1e-5;    // rad

struct Edge {
  int i, j;
  Matrix3 measured;  // R̃_ij ≈ R_j R_iᵀ
};

// ---------------------------------------------------------------------------------------------
// One edge: e = log(R̃ R_i R_jᵀ), its Lie Jacobians and (on request) its Lie Hessian.

struct EdgeResidual {
  Vector3 e;
  Matrix3 J_i, J_j;        // ∂e/∂δ_i, ∂e/∂δ_j
  Matrix3 E, J_l_inverse;  // kept for the Hessian
};

EdgeResidual edge_residual(const Matrix3& measured, const Matrix3& R_i, const Matrix3& R_j) {
  EdgeResidual r;
  r.E = measured * R_i * R_j.transpose();
  r.e = liedyn::so3::log(r.E, &r.J_l_inverse);
  r.J_i = r.J_l_inverse * measured;
  r.J_j = -r.J_l_inverse * r.E;
  return r;
}

// The 6×6 Lie Hessian of ½‖e‖² over (δ_i, δ_j), derived at the top.
Eigen::Matrix<double, 6, 6> edge_hessian(const Matrix3& measured, const EdgeResidual& r) {
  const Matrix3 H_e = r.J_l_inverse + 0.5 * hat(r.e);
  Eigen::Matrix<double, 6, 6> H;
  H.topLeftCorner<3, 3>() = measured.transpose() * H_e * measured;
  H.bottomRightCorner<3, 3>() = r.E.transpose() * H_e * r.E;
  H.topRightCorner<3, 3>() =
      -measured.transpose() * H_e * r.E + 0.5 * measured.transpose() * hat(r.e) * r.E;
  H.bottomLeftCorner<3, 3>() = H.topRightCorner<3, 3>().transpose();
  return H;
}

// ---------------------------------------------------------------------------------------------
// (a) Ceres: a cost function with Lie Jacobians. Ceres wants ∂e/∂q (3×4, row-major) for each
// quaternion block; SO3Manifold::lie_to_ambient(q) turns the Lie Jacobian into it, and Ceres's
// product with the manifold's PlusJacobian gives back the Lie Jacobian exactly.

class EdgeCost final : public ceres::SizedCostFunction<3, 4, 4> {
 public:
  explicit EdgeCost(const Matrix3& measured) : measured_(measured) {}

  bool Evaluate(double const* const* q, double* residuals, double** jacobians) const override {
    const EdgeResidual r =
        edge_residual(measured_, SO3Manifold::rotation(q[0]), SO3Manifold::rotation(q[1]));
    Eigen::Map<Vector3>{residuals} = r.e;
    using Jacobian = Eigen::Matrix<double, 3, 4, Eigen::RowMajor>;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Jacobian>{jacobians[0]} = r.J_i * SO3Manifold::lie_to_ambient(q[0]);
    }
    if (jacobians && jacobians[1]) {
      Eigen::Map<Jacobian>{jacobians[1]} = r.J_j * SO3Manifold::lie_to_ambient(q[1]);
    }
    return true;
  }

 private:
  Matrix3 measured_;
};

// ---------------------------------------------------------------------------------------------
// (b) Ipopt: the variables are R_1 … R_{N−1} (LiePoint::rotations[i − 1], tangent columns
// 3(i − 1) … 3(i − 1) + 2); R_0 is data.

class AveragingNlp final : public liedyn::LieNlp {
 public:
  AveragingNlp(const std::vector<Edge>& edges, const Matrix3& anchor)
      : edges_(edges), anchor_(anchor) {}

  bool objective(const liedyn::LiePoint& x, double& f, Eigen::VectorXd* gradient) override {
    f = 0.0;
    if (gradient) gradient->setZero(x.tangent_size());
    for (const Edge& edge : edges_) {
      const EdgeResidual r = edge_residual(edge.measured, rotation(x, edge.i), rotation(x, edge.j));
      f += 0.5 * r.e.squaredNorm();
      if (!gradient) continue;
      if (edge.i > 0) gradient->segment<3>(column(edge.i)) += r.J_i.transpose() * r.e;
      if (edge.j > 0) gradient->segment<3>(column(edge.j)) += r.J_j.transpose() * r.e;
    }
    return std::isfinite(f);
  }

  // No constraints: the Hessian of the Lagrangian is σ times that of f.
  bool lagrangian_hessian(const liedyn::LiePoint& x, double sigma,
                          const Eigen::VectorXd& /*lambda*/, Eigen::MatrixXd& hessian) override {
    hessian.setZero(x.tangent_size(), x.tangent_size());
    for (const Edge& edge : edges_) {
      const EdgeResidual r = edge_residual(edge.measured, rotation(x, edge.i), rotation(x, edge.j));
      const Eigen::Matrix<double, 6, 6> H = sigma * edge_hessian(edge.measured, r);
      const int a[2] = {edge.i, edge.j};
      for (int s = 0; s < 2; ++s) {
        for (int t = 0; t < 2; ++t) {
          if (a[s] == 0 || a[t] == 0) continue;  // the anchor is not a variable
          hessian.block<3, 3>(column(a[s]), column(a[t])) += H.block<3, 3>(3 * s, 3 * t);
        }
      }
    }
    return true;
  }

  const Matrix3& rotation(const liedyn::LiePoint& x, int i) const {
    return i == 0 ? anchor_ : x.rotations[i - 1];
  }
  static int column(int i) { return 3 * (i - 1); }

 private:
  std::vector<Edge> edges_;
  Matrix3 anchor_;
};

// ---------------------------------------------------------------------------------------------
// Data.

Matrix3 random_rotation(std::mt19937& rng) {
  // A normalised 4-vector of independent standard normals is uniform on the unit sphere S³,
  // so its rotation is uniform (Haar) on SO(3).
  std::normal_distribution<double> normal;
  Vector4 q(normal(rng), normal(rng), normal(rng), normal(rng));
  return SO3Manifold::rotation(q.data());
}

Vector3 random_normal_vector(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> normal(0.0, sigma);
  return Vector3(normal(rng), normal(rng), normal(rng));
}

std::vector<Edge> make_edges(const std::vector<Matrix3>& truth, std::mt19937& rng) {
  const int n = static_cast<int>(truth.size());
  std::set<std::pair<int, int>> used;  // unordered pairs, (min, max)
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < n; ++i) {
    pairs.emplace_back(i, (i + 1) % n);
    used.emplace(std::min(i, (i + 1) % n), std::max(i, (i + 1) % n));
  }
  std::uniform_int_distribution<int> node(0, n - 1);
  while (static_cast<int>(pairs.size()) < n + kExtraEdges) {
    const int i = node(rng), j = node(rng);
    if (i == j || !used.emplace(std::min(i, j), std::max(i, j)).second) continue;
    pairs.emplace_back(i, j);
  }
  std::vector<Edge> edges;
  for (const auto& [i, j] : pairs) {
    const Matrix3 noise = liedyn::so3::exp(random_normal_vector(rng, kSigma));
    edges.push_back({i, j, noise * truth[j] * truth[i].transpose()});
  }
  return edges;
}

// Errors against the ground truth, in two gauges.
//
// Relative measurements cannot see a common rotation of the body frames: R_j G (R_i G)ᵀ =
// R_j R_iᵀ for every rotation G. Holding R_0 at its true value picks one G. The estimate's error
// in that gauge is then also the error of R_0's own connection to the graph, common to every
// rotation. The other error reported is after the best global alignment, R̂_i ← R̂_i G with
// G = argmin Σ ‖R̂_i G − R_i*‖²_F = the rotation nearest Σ R̂_iᵀ R_i* (Procrustes): that is what
// the measurements determine, independent of which rotation was chosen as the anchor.
//
// Linearised prediction. With R_i = R_i* exp(β_i) (body-frame errors β_i; the geodesic error
// is ‖β_i‖), an edge's residual is
//   e_ij = log(exp(ε_ij) R_j* exp(β_i − β_j) R_j*ᵀ) ≈ ε_ij + R_j* (β_i − β_j),
// and ‖e_ij‖ = ‖R_j*ᵀ ε_ij + β_i − β_j‖ with R_j*ᵀ ε_ij ~ N(0, σ² I₃) again. So to first order
// the estimate solves, per axis, unit-weight least squares on the graph: its covariance is
// σ² L_0⁻¹ in R_0's gauge (L_0 the graph Laplacian without the anchor's row and column) and
// σ² L⁺ after the alignment (which removes the mean of the β_i; L⁺ the pseudo-inverse). A
// 3-D Gaussian with per-axis variance s² has mean norm 2√(2/π) s, so the predicted mean
// errors are 2√(2/π) σ · mean_i √(L_0⁻¹)_ii and 2√(2/π) σ · mean_i √(L⁺)_ii.
//
// Why the aligned mean error is below σ: a single measurement's error ‖ε_ij‖ has mean
// 2√(2/π) σ ≈ 1.6 σ, while each rotation's estimate averages over its edges (6 per node on
// average) and the rest of the graph; (L⁺)_ii is roughly 1/d_i, so the prediction is ≈ 1.6 σ
// √(1/6) ≈ 0.65 σ — more where nodes have few edges; this graph's value (0.74 σ) is printed. In
// R_0's gauge every error also carries R_0's connection, (L_0⁻¹)_ii ≈ 1/d_0 + 1/d_i: with this seed
// no random edge reaches node 0 (d_0 = 2, its ring edges only), so that prediction is ≈ 1.5 σ — an
// effect of the anchor, not of the averaging, and not tested.
struct Errors {
  double mean = 0.0, max = 0.0;
};

Errors errors(const std::vector<Matrix3>& estimate, const std::vector<Matrix3>& truth) {
  Errors result;
  for (std::size_t i = 1; i < truth.size(); ++i) {  // R_0's error is 0 in its own gauge
    const double error = liedyn::so3::distance(estimate[i], truth[i]);
    result.mean += error / static_cast<double>(truth.size() - 1);
    result.max = std::max(result.max, error);
  }
  return result;
}

Errors aligned_errors(const std::vector<Matrix3>& estimate, const std::vector<Matrix3>& truth) {
  Matrix3 M = Matrix3::Zero();
  for (std::size_t i = 0; i < truth.size(); ++i) M += estimate[i].transpose() * truth[i];
  const Eigen::JacobiSVD<Matrix3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3 S = Matrix3::Identity();
  S(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() > 0.0 ? 1.0 : -1.0;
  const Matrix3 G = svd.matrixU() * S * svd.matrixV().transpose();
  Errors result;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double error = liedyn::so3::distance(estimate[i] * G, truth[i]);
    result.mean += error / static_cast<double>(truth.size());
    result.max = std::max(result.max, error);
  }
  return result;
}

struct Prediction {
  double anchor_gauge, aligned;  // predicted mean errors, rad
};

Prediction predicted_mean_errors(const std::vector<Edge>& edges, int n) {
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  for (const Edge& edge : edges) {
    L(edge.i, edge.i) += 1.0;
    L(edge.j, edge.j) += 1.0;
    L(edge.i, edge.j) -= 1.0;
    L(edge.j, edge.i) -= 1.0;
  }
  const double mean_norm_factor = 2.0 * std::sqrt(2.0 / std::numbers::pi);
  // R_0's gauge: node 0 removed.
  const Eigen::MatrixXd L_0 = L.bottomRightCorner(n - 1, n - 1);
  const Eigen::VectorXd anchored =
      L_0.ldlt().solve(Eigen::MatrixXd::Identity(n - 1, n - 1)).diagonal();
  // Aligned: the pseudo-inverse, from the eigenvectors of the nonzero eigenvalues (the graph is
  // connected, so only the first, the constant vector's, is 0).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(L);
  const Eigen::MatrixXd V = eigen.eigenvectors().rightCols(n - 1);
  const Eigen::VectorXd inverse_values = eigen.eigenvalues().tail(n - 1).cwiseInverse();
  const Eigen::VectorXd aligned = (V * inverse_values.asDiagonal() * V.transpose()).diagonal();
  return {mean_norm_factor * kSigma * anchored.cwiseSqrt().mean(),
          mean_norm_factor * kSigma * aligned.cwiseSqrt().mean()};
}

// ---------------------------------------------------------------------------------------------
// Checks of every derivative above against central differences, at `x`.

bool check_derivatives(AveragingNlp& nlp, const std::vector<Edge>& edges,
                       const liedyn::LiePoint& x) {
  auto f = [&](const liedyn::LiePoint& y) {
    double value = 0.0;
    nlp.objective(y, value, nullptr);
    return value;
  };
  auto g = [&](const liedyn::LiePoint& y) {
    double value = 0.0;
    Eigen::VectorXd gradient;
    nlp.objective(y, value, &gradient);
    return gradient;
  };
  Eigen::MatrixXd H;
  nlp.lagrangian_hessian(x, 1.0, Eigen::VectorXd(), H);
  const double gradient_error = lie_check::relative_error(g(x), lie_check::gradient(f, x, 1e-5));
  const double hessian_error = lie_check::relative_error(H, lie_check::hessian(g, x, 1e-5));

  // Every edge's Ceres cost function, along SO3Manifold::Plus.
  SO3Manifold manifold;
  double ceres_error = 0.0;
  for (const Edge& edge : edges) {
    Vector4 q_i = SO3Manifold::quaternion(nlp.rotation(x, edge.i));
    Vector4 q_j = SO3Manifold::quaternion(nlp.rotation(x, edge.j));
    const EdgeCost cost(edge.measured);
    ceres_error =
        std::max(ceres_error, lie_check::cost_function_error(cost, {q_i.data(), q_j.data()},
                                                             {&manifold, &manifold}, 1e-5));
  }
  std::printf(
      "derivative checks (max |analytic - central difference| / max |entry|):\n"
      "  Lie gradient %.1e, Lie Hessian %.1e, Ceres Jacobians along Plus %.1e  (tolerance %.0e)\n",
      gradient_error, hessian_error, ceres_error, kDerivativeTolerance);
  return gradient_error <= kDerivativeTolerance && hessian_error <= kDerivativeTolerance &&
         ceres_error <= kDerivativeTolerance;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int run() {
  std::mt19937 rng(kSeed);
  std::vector<Matrix3> truth;
  for (int i = 0; i < kRotations; ++i) truth.push_back(random_rotation(rng));
  const std::vector<Edge> edges = make_edges(truth, rng);
  const Matrix3& anchor = truth[0];
  std::printf(
      "rotation_averaging: %d rotations, %zu edges (ring + %d random), sigma = %.3f rad, "
      "R_0 fixed\n",
      kRotations, edges.size(), kExtraEdges, kSigma);

  // Initial guess: chain the ring's measurements from the anchor, R_{i+1} = R̃_{i,i+1} R_i.
  // The ring edges come first in `edges`, edge i being (i, i+1).
  liedyn::LiePoint initial;
  Matrix3 R = anchor;
  for (int i = 0; i + 1 < kRotations; ++i) {
    R = liedyn::so3::orthonormalize(edges[i].measured * R);
    initial.rotations.push_back(R);
  }

  AveragingNlp nlp(edges, anchor);

  // Check the derivatives away from any solution, where the residuals are not small and every
  // term of the Hessian matters: the ground truth, each rotation turned by 0.5 rad about a
  // random axis (residuals up to ~1 rad).
  liedyn::LiePoint rough;
  for (int i = 1; i < kRotations; ++i) {
    const Vector3 axis = random_normal_vector(rng, 1.0).normalized();
    rough.rotations.push_back(liedyn::so3::exp(0.5 * axis) * truth[i]);
  }
  if (!check_derivatives(nlp, edges, rough)) {
    std::fprintf(stderr, "rotation_averaging: a derivative disagrees with finite differences\n");
    return 1;
  }

  double initial_cost = 0.0;
  nlp.objective(initial, initial_cost, nullptr);
  std::printf("initial guess (ring chained from R_0): cost %.9g\n", initial_cost);

  // (a) Ceres.
  std::vector<Vector4> q(kRotations);
  q[0] = SO3Manifold::quaternion(anchor);
  for (int i = 1; i < kRotations; ++i) q[i] = SO3Manifold::quaternion(initial.rotations[i - 1]);
  SO3Manifold manifold;  // one instance serves every block; the problem must not delete it
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (Vector4& block : q) problem.AddParameterBlock(block.data(), 4, &manifold);
  problem.SetParameterBlockConstant(q[0].data());  // the gauge
  for (const Edge& edge : edges) {
    problem.AddResidualBlock(new EdgeCost(edge.measured), nullptr, q[edge.i].data(),
                             q[edge.j].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  // Tight tolerances: the comparison with Ipopt below wants both at the minimiser, not near it.
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  options.max_num_iterations = 100;
  ceres::Solver::Summary ceres_summary;
  auto start = std::chrono::steady_clock::now();
  ceres::Solve(options, &problem, &ceres_summary);
  const double ceres_seconds = seconds_since(start);
  liedyn::LiePoint ceres_solution;
  for (int i = 1; i < kRotations; ++i)
    ceres_solution.rotations.push_back(SO3Manifold::rotation(q[i].data()));
  const bool ceres_converged =
      ceres_summary.IsSolutionUsable() && ceres_summary.termination_type == ceres::CONVERGENCE;

  // (b) Ipopt, exact Lie Hessian.
  liedyn::LiePoint ipopt_solution = initial;
  liedyn::LieIpoptOptions ipopt_options;
  ipopt_options.hessian = "exact";
  start = std::chrono::steady_clock::now();
  const liedyn::LieIpoptSummary ipopt_summary =
      liedyn::solve_with_ipopt(nlp, ipopt_solution, ipopt_options);
  const double ipopt_seconds = seconds_since(start);

  // Both costs by the same function, at both solutions.
  double ceres_cost = 0.0, ipopt_cost = 0.0;
  nlp.objective(ceres_solution, ceres_cost, nullptr);
  nlp.objective(ipopt_solution, ipopt_cost, nullptr);
  double solver_distance = 0.0;
  for (int i = 1; i < kRotations; ++i) {
    solver_distance = std::max(
        solver_distance,
        liedyn::so3::distance(ceres_solution.rotations[i - 1], ipopt_solution.rotations[i - 1]));
  }
  std::vector<Matrix3> estimate{anchor};
  estimate.insert(estimate.end(), ipopt_solution.rotations.begin(), ipopt_solution.rotations.end());
  const Errors anchored = errors(estimate, truth);
  const Errors aligned = aligned_errors(estimate, truth);
  const Prediction prediction = predicted_mean_errors(edges, kRotations);
  const double cost_difference =
      std::abs(ceres_cost - ipopt_cost) / std::max(ceres_cost, ipopt_cost);
  // At the minimiser, 2 f/σ² is about chi-squared with 3 (edges − (N − 1)) degrees of freedom.
  const double expected_cost =
      0.5 * kSigma * kSigma * 3.0 * static_cast<double>(edges.size() - (kRotations - 1));

  std::printf("Ceres : %s, %d iterations, cost %.12g, %.1f ms  [%s]\n",
              ceres::TerminationTypeToString(ceres_summary.termination_type),
              ceres_summary.num_successful_steps + ceres_summary.num_unsuccessful_steps, ceres_cost,
              1e3 * ceres_seconds, ceres_summary.message.c_str());
  std::printf("Ipopt : %s, %d iterations, cost %.12g, %.1f ms  [%s]\n",
              ipopt_summary.converged() ? "converged" : "NOT converged", ipopt_summary.iterations,
              ipopt_cost, 1e3 * ipopt_seconds, ipopt_summary.message.c_str());
  std::printf("expected cost at the minimum ~ %.3f (sigma^2/2 x %d degrees of freedom)\n",
              expected_cost, 3 * static_cast<int>(edges.size() - (kRotations - 1)));
  std::printf(
      "Ceres vs Ipopt: cost relative difference %.1e (tolerance %.0e), "
      "max geodesic distance %.1e rad (tolerance %.0e)\n",
      cost_difference, kCostAgreement, solver_distance, kSolutionAgreement);
  std::printf(
      "error against ground truth, sigma = %.4f rad:\n"
      "  in R_0's gauge (R_1 ... R_%d): mean %.4f rad, max %.4f rad "
      "(linearised prediction of the mean %.4f)\n"
      "  after the best global alignment: mean %.4f rad, max %.4f rad "
      "(linearised prediction of the mean %.4f)\n",
      kSigma, kRotations - 1, anchored.mean, anchored.max, prediction.anchor_gauge, aligned.mean,
      aligned.max, prediction.aligned);

  bool ok = true;
  auto require = [&ok](bool condition, const char* what) {
    if (!condition) {
      std::fprintf(stderr, "rotation_averaging: FAILED: %s\n", what);
      ok = false;
    }
  };
  require(ceres_converged, "Ceres did not converge");
  require(ipopt_summary.converged(), "Ipopt did not converge");
  require(cost_difference <= kCostAgreement, "the Ceres and Ipopt costs differ");
  require(solver_distance <= kSolutionAgreement, "the Ceres and Ipopt solutions differ");
  require(aligned.mean < kSigma,
          "the aligned mean error against the ground truth is not below sigma");
  if (ok) std::printf("rotation_averaging: passed\n");
  return ok ? 0 : 1;
}

}  // namespace

int main() {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rotation_averaging: %s\n", e.what());
    return 1;
  }
}

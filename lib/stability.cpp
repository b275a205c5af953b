#include "stability.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace liedyn {

namespace {

// Enough for the extreme eigenvalue of any component to a fraction of a percent (a 100-edge
// rod's top modes lie within 1e-4 of each other); a component with fewer DOFs is exact.
constexpr int kLanczosSteps = 100;

// K: the Lie Hessian of the component's terms of the state at q, unweighted, symmetrised.
Eigen::SparseMatrix<double> state_stiffness(const Component& c, const State& q) {
  std::vector<Eigen::Triplet<double>> entries;
  c.potential.for_each_term_vector([&](const auto& terms) {
    using T = typename std::decay_t<decltype(terms)>::value_type;
    LocalHessian<T::kBlocks> H;
    for (const T& t : terms) {
      if (!IncrementalPotential::state_term(t)) continue;
      t.evaluate(q, nullptr, &H);
      for (int i = 0; i < T::kBlocks; ++i) {
        for (int j = 0; j < T::kBlocks; ++j) {
          if (t.offsets[i] < 0 || t.offsets[j] < 0) continue;
          for (int r = 0; r < 3; ++r) {
            for (int s = 0; s < 3; ++s) {
              const double h = 0.5 * (H(3 * i + r, 3 * j + s) + H(3 * j + s, 3 * i + r));
              entries.emplace_back(t.offsets[i] + r, t.offsets[j] + s, h);
            }
          }
        }
      }
    }
  });
  Eigen::SparseMatrix<double> K(c.dofs, c.dofs);
  K.setFromTriplets(entries.begin(), entries.end());
  return K;
}

// L⁻¹ of each 3×3 block of M/h² = L Lᵀ (block b at offset 3b).
std::vector<Matrix3> inverse_mass_factors(const Component& c, const State& q) {
  std::vector<Matrix3> M(c.dofs / 3, Matrix3::Zero());
  std::vector<bool> has(c.dofs / 3, false);
  for (const TranslationalInertia& t : c.potential.terms<TranslationalInertia>()) {
    if (t.offsets[0] < 0) continue;
    M[t.offsets[0] / 3] = t.mass_over_h2 * Matrix3::Identity();
    has[t.offsets[0] / 3] = true;
  }
  for (const RotationalInertia& t : c.potential.terms<RotationalInertia>()) {
    if (t.offsets[0] < 0) continue;
    const Matrix3& R = q.rotations[t.rotation];
    M[t.offsets[0] / 3] = R * (t.J_over_h2.trace() * Matrix3::Identity() - t.J_over_h2) * R.transpose();
    has[t.offsets[0] / 3] = true;
  }
  std::vector<Matrix3> factors(M.size());
  for (std::size_t b = 0; b < M.size(); ++b) {
    // Model::validate makes every mass and inertia positive (definite): a block without one is
    // a caller's error, not a model's.
    const Eigen::LLT<Matrix3> llt(M[b]);
    if (!has[b] || llt.info() != Eigen::Success) {
      throw std::logic_error("largest_mode_step_squared: a DOF block without a positive definite inertia");
    }
    factors[b] = llt.matrixL().solve(Matrix3::Identity());
  }
  return factors;
}

bool conditionally_stable(const Model& model) {
  const double beta = newmark_beta(model.integrator);
  return !model.static_equilibrium && beta > 0.0 && beta < 0.25;
}

}  // namespace

double largest_mode_step_squared(const Component& c, const State& q) {
  const int n = c.dofs;
  if (n == 0) return 0.0;
  const Eigen::SparseMatrix<double> K = state_stiffness(c, q);
  const std::vector<Matrix3> L_inverse = inverse_mass_factors(c, q);
  Eigen::VectorXd scratch(n);
  // y = L⁻¹ K L⁻ᵀ x
  const auto apply = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    for (int b = 0; b < n / 3; ++b) scratch.segment<3>(3 * b) = L_inverse[b].transpose() * x.segment<3>(3 * b);
    y = K * scratch;
    for (int b = 0; b < n / 3; ++b) y.segment<3>(3 * b) = (L_inverse[b] * y.segment<3>(3 * b)).eval();
  };
  const int m = std::min(n, kLanczosSteps);
  Eigen::MatrixXd Q(n, m);
  Eigen::VectorXd alpha = Eigen::VectorXd::Zero(m), beta = Eigen::VectorXd::Zero(m);
  // A fixed start (the same estimate on every run), with a part on every mode.
  std::mt19937 random(20261206u);
  Eigen::VectorXd v(n), w(n);
  for (int i = 0; i < n; ++i) v[i] = static_cast<double>(random()) / 4294967296.0 - 0.5;
  v.normalize();
  int steps = 0;
  for (int k = 0; k < m; ++k) {
    Q.col(k) = v;
    ++steps;
    apply(v, w);
    alpha[k] = v.dot(w);
    // Full reorthogonalisation, twice (Gram–Schmidt): the Ritz values stay those of an
    // orthonormal basis, without the spurious copies plain Lanczos makes in finite precision.
    for (int pass = 0; pass < 2; ++pass) w -= Q.leftCols(k + 1) * (Q.leftCols(k + 1).transpose() * w);
    if (k + 1 == m) break;
    beta[k] = w.norm();
    if (!(beta[k] > 1e-12 * std::max(1.0, std::abs(alpha[k])))) break;  // an invariant subspace
    v = w / beta[k];
  }
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(steps, steps);
  for (int k = 0; k < steps; ++k) {
    T(k, k) = alpha[k];
    if (k + 1 < steps) T(k, k + 1) = T(k + 1, k) = beta[k];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(T, Eigen::EigenvaluesOnly);
  const double largest = eigen.eigenvalues().maxCoeff();
  // A stiffness that is not finite at q has no stable step (and std::max would drop a NaN).
  if (std::isnan(largest)) return std::numeric_limits<double>::infinity();
  return std::max(0.0, largest);
}

void check_stable_step(const Model& model, const std::vector<Component>& components, const State& q,
                       int frame) {
  if (!conditionally_stable(model)) return;
  const double beta = newmark_beta(model.integrator);
  const double bound = 4.0 / (1.0 - 4.0 * beta);  // on (ωh)²
  double largest = 0.0;
  for (const Component& c : components) largest = std::max(largest, largest_mode_step_squared(c, q));
  if (largest < bound) return;
  const double h = model.time_step;
  const double omega = std::sqrt(largest) / h;
  std::ostringstream os;
  os.precision(3);
  os << "is too large for the " << to_string(model.integrator) << " integrator, stable only for ωh < "
     << std::sqrt(bound) << " on every mode: the stiffest mode at frame " << frame << " (ω ≈ " << omega
     << " rad/s) needs time_step < " << std::sqrt(bound) / omega
     << " s, with a margin where stiffness grows as the model deforms (trapezoidal and bdf2 are stable "
        "at any time_step)";
  throw ModelError("time_step", os.str());
}

void check_stable_start(const Model& model) {
  if (!conditionally_stable(model)) return;
  check_stable_step(model, build_components(model), model.initial_state(), 0);
}

}  // namespace liedyn

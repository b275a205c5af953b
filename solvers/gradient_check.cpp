#include "gradient_check.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace liedyn {

bool GradientCheckResult::passed() const {
  return std::isfinite(max_relative_error) && max_relative_error <= tolerance;
}

GradientCheckResult check_gradient(const DifferentiableSimulation& simulation,
                                   const Eigen::VectorXd& gamma, const GradientCheckOptions& options) {
  if (!(options.step > 0.0) || !(options.floor >= 0.0) || options.sample < 0 ||
      !(options.tolerance >= 0.0)) {
    throw std::invalid_argument("check_gradient: step > 0, floor ≥ 0, sample ≥ 0 and tolerance ≥ 0");
  }
  GradientCheckResult result;
  result.tolerance = options.tolerance;
  Eigen::VectorXd adjoint;
  const auto start = std::chrono::steady_clock::now();
  const DifferentiableSimulation::Result pass = simulation.evaluate(gamma, &adjoint);
  result.adjoint_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.forward_seconds = pass.forward_seconds;
  result.backward_seconds = pass.backward_seconds;
  result.loss = pass.loss;

  std::vector<int> indices(gamma.size());
  std::iota(indices.begin(), indices.end(), 0);
  if (options.sample > 0 && options.sample < static_cast<int>(indices.size())) {
    std::mt19937 rng(options.seed);
    std::shuffle(indices.begin(), indices.end(), rng);
    indices.resize(options.sample);
    std::sort(indices.begin(), indices.end());
  }
  const double scale = options.floor * (adjoint.size() > 0 ? adjoint.cwiseAbs().maxCoeff() : 0.0);
  Eigen::VectorXd probe = gamma;
  for (int j : indices) {
    const double eps = options.step * std::max(1.0, std::abs(gamma(j)));
    probe(j) = gamma(j) + eps;
    const double plus = simulation.evaluate(probe, nullptr).loss;
    probe(j) = gamma(j) - eps;
    const double minus = simulation.evaluate(probe, nullptr).loss;
    probe(j) = gamma(j);
    GradientCheckEntry e;
    e.index = j;
    e.adjoint = adjoint(j);
    e.finite_difference = (plus - minus) / (2.0 * eps);
    const double denominator =
        std::max({std::abs(e.adjoint), std::abs(e.finite_difference), scale});
    const double difference = std::abs(e.adjoint - e.finite_difference);
    e.relative_error = denominator > 0.0 ? difference / denominator
                                         : (difference == 0.0 ? 0.0 : INFINITY);
    if (!std::isfinite(e.adjoint) || !std::isfinite(e.finite_difference)) e.relative_error = INFINITY;
    if (result.worst < 0 || !(e.relative_error <= result.max_relative_error)) {
      result.max_relative_error = e.relative_error;
      result.worst = j;
    }
    result.entries.push_back(e);
  }
  return result;
}

}  // namespace liedyn

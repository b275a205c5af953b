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

std::vector<int> sample_indices(int n, int sample, unsigned seed) {
  std::vector<int> indices(n);
  std::iota(indices.begin(), indices.end(), 0);
  if (sample > 0 && sample < n) {
    std::mt19937 rng(seed);
    std::shuffle(indices.begin(), indices.end(), rng);
    indices.resize(sample);
    std::sort(indices.begin(), indices.end());
  }
  return indices;
}

std::vector<double> central_differences(const DifferentiableSimulation& simulation,
                                        const Eigen::VectorXd& gamma,
                                        const std::vector<int>& indices, double step) {
  std::vector<double> differences;
  Eigen::VectorXd probe = gamma;
  for (const int j : indices) {
    const double eps = step * std::max(1.0, std::abs(gamma(j)));
    probe(j) = gamma(j) + eps;
    const double plus = simulation.evaluate(probe, nullptr).loss;
    probe(j) = gamma(j) - eps;
    const double minus = simulation.evaluate(probe, nullptr).loss;
    probe(j) = gamma(j);
    differences.push_back((plus - minus) / (2.0 * eps));
  }
  return differences;
}

double relative_error(double adjoint, double finite_difference, double scale) {
  if (!std::isfinite(adjoint) || !std::isfinite(finite_difference)) return INFINITY;
  const double denominator = std::max({std::abs(adjoint), std::abs(finite_difference), scale});
  const double difference = std::abs(adjoint - finite_difference);
  return denominator > 0.0 ? difference / denominator : (difference == 0.0 ? 0.0 : INFINITY);
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

  const std::vector<int> indices =
      sample_indices(static_cast<int>(gamma.size()), options.sample, options.seed);
  const std::vector<double> differences =
      central_differences(simulation, gamma, indices, options.step);
  const double scale = options.floor * (adjoint.size() > 0 ? adjoint.cwiseAbs().maxCoeff() : 0.0);
  for (std::size_t i = 0; i < indices.size(); ++i) {
    GradientCheckEntry e;
    e.index = indices[i];
    e.adjoint = adjoint(e.index);
    e.finite_difference = differences[i];
    e.relative_error = relative_error(e.adjoint, e.finite_difference, scale);
    if (result.worst < 0 || !(e.relative_error <= result.max_relative_error)) {
      result.max_relative_error = e.relative_error;
      result.worst = e.index;
    }
    result.entries.push_back(e);
  }
  return result;
}

}  // namespace liedyn

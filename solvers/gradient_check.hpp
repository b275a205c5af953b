#pragma once
// The adjoint gradient (solvers/adjoint.hpp) against central finite differences of the loss,
// parameter by parameter — `liedyn gradcheck` and the tests.
//
//   d_j = (g(γ + ε_j e_j) − g(γ − ε_j e_j)) / 2ε_j,   ε_j = step · max(1, |γ_j|),
//   error_j = |a_j − d_j| / max(|a_j|, |d_j|, floor · max_i |a_i|).
// The floor (default 1e-3 of the largest adjoint entry) keeps entries that are tiny beside the
// others from being judged relative to themselves: a difference quotient cannot resolve them
// better than its noise, which scales with the loss, not with the entry. Every forward run of
// the differences must converge (SimulationFailed otherwise): use a tight solver tolerance.

#include <Eigen/Core>
#include <vector>

#include "adjoint.hpp"

namespace liedyn {

struct GradientCheckOptions {
  double step = 1e-6;       // relative FD step (see above), > 0
  double floor = 1e-3;      // relative error floor (see above), ≥ 0
  int sample = 0;           // check this many parameters drawn at random (0: all)
  unsigned seed = 1;        // of the sample
  double tolerance = 1e-5;  // passed when max error_j ≤ tolerance
};

struct GradientCheckEntry {
  int index = 0;
  double adjoint = 0.0;
  double finite_difference = 0.0;
  double relative_error = 0.0;
};

struct GradientCheckResult {
  double loss = 0.0;
  std::vector<GradientCheckEntry> entries;  // in parameter order
  double max_relative_error = 0.0;
  int worst = -1;                           // parameter index of the largest error
  double adjoint_seconds = 0.0;             // one forward + backward pass
  double forward_seconds = 0.0, backward_seconds = 0.0;  // of that pass
  bool passed() const;
  double tolerance = 0.0;
};

// The pieces check_gradient is made of, for callers that compare other gradients (liedyn
// sweep: a cheap run's adjoint against a fine run's differences).
// Indices 0 … n−1, or `sample` of them drawn at random with `seed` (0 or ≥ n: all), sorted.
std::vector<int> sample_indices(int n, int sample, unsigned seed);
// d_j of the formula above for each j in `indices`.
std::vector<double> central_differences(const DifferentiableSimulation& simulation,
                                        const Eigen::VectorXd& gamma,
                                        const std::vector<int>& indices, double step);
// error_j of the formula above, with `scale` = floor · max_i |a_i|; ∞ if a value is not finite.
double relative_error(double adjoint, double finite_difference, double scale);

GradientCheckResult check_gradient(const DifferentiableSimulation& simulation,
                                   const Eigen::VectorXd& gamma, const GradientCheckOptions& options);

}  // namespace liedyn

#include "newton.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "../lib/so3.hpp"

namespace liedyn {

void NewtonOptions::validate() const {
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) {
    throw ModelError("solver.tolerance", "must be a finite positive number");
  }
  if (max_iterations < 1) throw ModelError("solver.max_iterations", "must be at least 1");
  if (!(armijo > 0.0 && armijo < 0.5)) throw ModelError("solver.armijo", "must be in (0, 0.5)");
  if (!(min_step_length > 0.0 && min_step_length < 1.0)) {
    throw ModelError("solver.min_step_length", "must be in (0, 1)");
  }
}

const char* to_string(StepStatus status) {
  switch (status) {
    case StepStatus::kConverged: return "converged";
    case StepStatus::kMaxIterations: return "max_iterations";
    case StepStatus::kLineSearchFailed: return "line_search_failed";
    case StepStatus::kNonFinite: return "non_finite";
  }
  return "unknown";
}

void StepReport::merge(const StepReport& other) {
  // The worst status wins; iterations are the slowest component's (they are independent).
  if (static_cast<int>(other.status) > static_cast<int>(status)) status = other.status;
  iterations = std::max(iterations, other.iterations);
  regularized_iterations = std::max(regularized_iterations, other.regularized_iterations);
  factorizations += other.factorizations;
  gradient_norm = std::hypot(gradient_norm, other.gradient_norm);
  step_norm = std::max(step_norm, other.step_norm);
}

template <int N>
DenseNewton<N>::DenseNewton(Component component, const NewtonOptions& options)
    : component_(std::move(component)),
      options_(options),
      g_(component_.dofs),
      delta_(component_.dofs),
      H_(component_.dofs, component_.dofs),
      H_shifted_(component_.dofs, component_.dofs),
      llt_(component_.dofs),
      saved_points_(component_.points.size()),
      entry_points_(component_.points.size()),
      saved_rotations_(component_.rotations.size()),
      entry_rotations_(component_.rotations.size()) {}

template <int N>
void DenseNewton<N>::save(const State& q) {
  for (std::size_t i = 0; i < component_.points.size(); ++i) {
    saved_points_[i] = q.points[component_.points[i].index];
  }
  for (std::size_t i = 0; i < component_.rotations.size(); ++i) {
    saved_rotations_[i] = q.rotations[component_.rotations[i].index];
  }
}

template <int N>
void DenseNewton<N>::restore(State& q) const {
  for (std::size_t i = 0; i < component_.points.size(); ++i) {
    q.points[component_.points[i].index] = saved_points_[i];
  }
  for (std::size_t i = 0; i < component_.rotations.size(); ++i) {
    q.rotations[component_.rotations[i].index] = saved_rotations_[i];
  }
}

template <int N>
void DenseNewton<N>::retract(State& q, double alpha) const {
  for (const DofBlock& b : component_.points) {
    q.points[b.index] += alpha * delta_.template segment<3>(b.offset);
  }
  for (const DofBlock& b : component_.rotations) {
    Matrix3& R = q.rotations[b.index];
    R = so3::orthonormalize(so3::exp(alpha * delta_.template segment<3>(b.offset)) * R);
  }
}

namespace {

// Full unrolling of the fixed-size loops below (their bounds are compile-time constants,
// but GCC does not unroll the triangular nests by itself; unrolled, they run ~2× faster).
#if defined(__clang__)
#define LIEDYN_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define LIEDYN_UNROLL _Pragma("GCC unroll 16")
#else
#define LIEDYN_UNROLL
#endif

// Cholesky factorisation A + μI = L Lᵀ of a small fixed-size matrix. F receives L's strict
// lower triangle and, on its diagonal, the reciprocals 1/L_jj (so that the solve needs no
// division); F's strict upper triangle is never touched or read. Same algorithm and
// acceptance test as Eigen's unblocked LLT (column by column; a pivot that is not positive
// fails), but with compile-time, unrolled loops: for 6×6, factorisation + solve is ~2.5×
// faster than Eigen::LLT<Matrix<double, 6, 6>>, whose kernels work on runtime-sized blocks.
template <int N>
bool cholesky_fixed(const Eigen::Matrix<double, N, N>& A, double mu,
                    Eigen::Matrix<double, N, N>& F) {
  LIEDYN_UNROLL
  for (int j = 0; j < N; ++j) {
    double d = A(j, j) + mu;
    LIEDYN_UNROLL
    for (int k = 0; k < j; ++k) d -= F(j, k) * F(j, k);
    if (!(d > 0.0)) return false;
    const double inv = 1.0 / std::sqrt(d);
    F(j, j) = inv;
    LIEDYN_UNROLL
    for (int i = j + 1; i < N; ++i) {
      double s = A(i, j);
      LIEDYN_UNROLL
      for (int k = 0; k < j; ++k) s -= F(i, k) * F(j, k);
      F(i, j) = s * inv;
    }
  }
  return true;
}

// Solves L Lᵀ x = b with the factor F of cholesky_fixed.
template <int N>
void cholesky_fixed_solve(const Eigen::Matrix<double, N, N>& F,
                          const Eigen::Matrix<double, N, 1>& b, Eigen::Matrix<double, N, 1>& x) {
  LIEDYN_UNROLL
  for (int i = 0; i < N; ++i) {  // L y = b
    double s = b(i);
    LIEDYN_UNROLL
    for (int k = 0; k < i; ++k) s -= F(i, k) * x(k);
    x(i) = s * F(i, i);
  }
  LIEDYN_UNROLL
  for (int i = N - 1; i >= 0; --i) {  // Lᵀ x = y
    double s = x(i);
    LIEDYN_UNROLL
    for (int k = i + 1; k < N; ++k) s -= F(k, i) * x(k);
    x(i) = s * F(i, i);
  }
}

#undef LIEDYN_UNROLL

}  // namespace

template <int N>
bool DenseNewton<N>::try_factorize(double mu) {
  if constexpr (N != Eigen::Dynamic) {
    // Fixed size: H_shifted_ holds the factor of H + μI (see cholesky_fixed); llt_ is unused.
    return cholesky_fixed<N>(H_, mu, H_shifted_);
  } else {
    if (mu == 0.0) {
      llt_.compute(H_);
    } else {
      H_shifted_ = H_;
      H_shifted_.diagonal().array() += mu;
      llt_.compute(H_shifted_);
    }
    return llt_.info() == Eigen::Success;
  }
}

template <int N>
void DenseNewton<N>::solve_factorized() {
  if constexpr (N != Eigen::Dynamic) {
    cholesky_fixed_solve<N>(H_shifted_, g_, delta_);
  } else {
    delta_ = llt_.solve(g_);
  }
  delta_ = -delta_;
}

template <int N>
bool DenseNewton<N>::factorize(StepReport& report, bool& regularized) {
  regularized = false;
  ++report.factorizations;
  if (try_factorize(0.0)) return true;
  const double scale = std::max(H_.diagonal().cwiseAbs().maxCoeff(),
                                std::numeric_limits<double>::min());
  regularized = true;
  for (double mu = 1e-8 * scale; mu < 1e12 * scale; mu *= 10.0) {
    ++report.factorizations;
    if (try_factorize(mu)) return true;
  }
  return false;
}

template <int N>
StepReport DenseNewton<N>::solve(State& q) {
  StepReport report;
  // Keep the entry state so that a failed step leaves q untouched.
  for (std::size_t i = 0; i < component_.points.size(); ++i) {
    entry_points_[i] = q.points[component_.points[i].index];
  }
  for (std::size_t i = 0; i < component_.rotations.size(); ++i) {
    entry_rotations_[i] = q.rotations[component_.rotations[i].index];
  }
  auto fail = [&](StepStatus status) {
    report.status = status;
    for (std::size_t i = 0; i < component_.points.size(); ++i) {
      q.points[component_.points[i].index] = entry_points_[i];
    }
    for (std::size_t i = 0; i < component_.rotations.size(); ++i) {
      q.rotations[component_.rotations[i].index] = entry_rotations_[i];
    }
    return report;
  };

  for (;;) {
    double roundoff = 0.0;
    const double psi = component_.potential.assemble(q, g_, H_, &roundoff);
    report.gradient_norm = g_.norm();
    // A NaN or Inf entry makes the sum non-finite (so does an overflow to ±Inf, which is
    // as unusable); one sum is much cheaper than testing all entries.
    if (!std::isfinite(psi + g_.sum() + H_.sum())) {
      return fail(StepStatus::kNonFinite);
    }
    bool regularized = false;
    if (!factorize(report, regularized)) return fail(StepStatus::kNonFinite);
    solve_factorized();
    if (!std::isfinite(delta_.sum())) return fail(StepStatus::kNonFinite);
    report.step_norm = delta_.template lpNorm<Eigen::Infinity>();
    if (!regularized && report.step_norm <= options_.tolerance) {
      report.status = StepStatus::kConverged;
      return report;
    }
    if (report.iterations >= options_.max_iterations) {
      report.status = StepStatus::kMaxIterations;
      return report;
    }

    // Backtracking (Armijo) line search on Ψ. Near convergence the predicted decrease falls
    // below the round-off of Ψ itself (estimated by assemble from the terms' values and
    // gradients, which can be large while they cancel); a change within a small multiple of
    // that round-off is accepted, otherwise a tight tolerance stalls on noise.
    const double slope = g_.dot(delta_);  // < 0: H (or H + μI) is positive definite
    roundoff *= 16.0;
    save(q);
    double alpha = 1.0;
    for (;;) {
      retract(q, alpha);
      const double psi_trial = component_.potential.value(q);
      if (std::isfinite(psi_trial) &&
          psi_trial <= psi + options_.armijo * alpha * slope + roundoff) {
        break;
      }
      restore(q);
      alpha *= 0.5;
      if (alpha < options_.min_step_length) return fail(StepStatus::kLineSearchFailed);
    }
    ++report.iterations;
    if (regularized) ++report.regularized_iterations;
  }
}

template class DenseNewton<6>;
template class DenseNewton<Eigen::Dynamic>;

}  // namespace liedyn

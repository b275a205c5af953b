#include "newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "../lib/so3.hpp"

namespace liedyn {

namespace {

template <class System>
System make_system(const Component& component, const SolverOptions& options) {
  if constexpr (std::is_same_v<System, SparseSystem>) {
    return SparseSystem(component, SparseSystem::Factorization::kUndecided,
                        options.assembly_threads);
  } else {
    return System(component);
  }
}

}  // namespace

template <class System>
Newton<System>::Newton(Component component, const SolverOptions& options)
    : StepSolver(options),
      component_(std::move(component)),
      options_(options),
      system_(make_system<System>(component_, options)),
      delta_(component_.dofs),
      delta0_(component_.dofs),
      skew_(component_.dofs),
      correction_(component_.dofs),
      trial_gradient_(component_.dofs),
      chord_delta_(component_.dofs),
      reuse_window_(options.hessian_reuse),
      saved_(component_),
      entry_(component_) {
  const std::size_t n = component_.rotations.size();
  if (options_.rotation == RotationParameterization::kRotationVector) {
    chart_ = RotationVectorChart(component_);
  } else if (options_.rotation == RotationParameterization::kQuaternion) {
    quaternions_.resize(n);
    saved_quaternions_.resize(n);
  }
}

template <class System>
void Newton<System>::enter_parameterization(State& q) {
  if (options_.rotation == RotationParameterization::kLie) return;
  for (std::size_t i = 0; i < component_.rotations.size(); ++i) {
    Matrix3& R = q.rotations[component_.rotations[i].index];
    if (options_.rotation == RotationParameterization::kRotationVector) {
      R = chart_.set(i, so3::log(R));
    } else if (options_.rotation == RotationParameterization::kQuaternion) {
      quaternions_[i] = quat::from_rotation(R);
      R = quat::rotation(quaternions_[i]);
    }
  }
}

template <class System>
void Newton<System>::save(const State& q) {
  saved_.save(component_, q);
  if (options_.rotation == RotationParameterization::kRotationVector) chart_.save();
  for (std::size_t i = 0; i < saved_quaternions_.size(); ++i) {
    saved_quaternions_[i] = quaternions_[i];
  }
}

template <class System>
void Newton<System>::restore(State& q) {
  saved_.restore(component_, q);
  if (options_.rotation == RotationParameterization::kRotationVector) chart_.restore();
  for (std::size_t i = 0; i < saved_quaternions_.size(); ++i) {
    quaternions_[i] = saved_quaternions_[i];
  }
}

template <class System>
void Newton<System>::retract(State& q, double alpha) {
  for (const DofBlock& b : component_.points) {
    q.points[b.index] += alpha * delta_.template segment<3>(b.offset);
  }
  for (std::size_t i = 0; i < component_.rotations.size(); ++i) {
    const DofBlock& b = component_.rotations[i];
    const Vector3 step = alpha * delta_.template segment<3>(b.offset);
    Matrix3& R = q.rotations[b.index];
    switch (options_.rotation) {
      case RotationParameterization::kLie:
        R = so3::orthonormalize(so3::exp(step) * R);
        break;
      case RotationParameterization::kRotationVector:
        R = chart_.set(i, chart_.r(i) + step);
        break;
      case RotationParameterization::kQuaternion:
        quaternions_[i] = quat::retract(quaternions_[i], step);
        R = quat::rotation(quaternions_[i]);
        break;
    }
  }
}


template <class System>
void Newton<System>::correct_for_history_skew() {
  delta0_ = delta_;
  for (int m = 0; m < kSkewCorrections; ++m) {
    component_.potential.history_skew(delta_, skew_);
    system_.solve_linear(skew_, correction_);
    delta_ = delta0_ - correction_;
  }
  // Where ‖H⁻¹K‖ is not small (large fields against a soft rotation: bodies stacked in contact)
  // the series does not converge, and its δ need not descend on Ψ: keep H's own step then.
  const Vector& g = system_.gradient();
  if (!(correction_.norm() <= 0.5 * delta0_.norm() && g.dot(delta_) <= 0.5 * g.dot(delta0_))) {
    delta_ = delta0_;
  }
}

template <class System>
double Newton<System>::hessian_condition() const {
  Eigen::MatrixXd H;
  system_.dense_hessian(H);
  return condition_number(H);
}

template <class System>
bool Newton<System>::factorize_and_solve(StepReport& report, bool& regularized) {
  // With K the factorisation's success does not prove H + μI positive definite: δ must also
  // descend, gᵀδ = −δᵀ(H + μI)δ < 0 (newton.hpp), or be 0 (g = 0).
  const auto step_found = [&] {
    system_.solve(delta_);
    if (!skew_factorized_) return true;
    return system_.gradient().dot(delta_) < 0.0 || delta_.isZero(0.0);
  };
  regularized = false;
  ++report.factorizations;
  if (system_.factorize(0.0) && step_found()) return true;
  const double scale = std::max(system_.hessian_scale(), std::numeric_limits<double>::min());
  regularized = true;
  for (double mu = 1e-8 * scale; mu < 1e12 * scale; mu *= 10.0) {
    ++report.factorizations;
    if (system_.factorize(mu) && step_found()) return true;
  }
  return false;
}

namespace {

// The stall test (newton.hpp): updates in a row without progress, and the relative
// decrease of ‖g‖ or ‖δ‖∞ that counts as progress.
constexpr int kStallIterations = 10;
constexpr double kProgress = 0.01;
// The estimated convergence check (newton.hpp): how well the quadratic model must have
// predicted the update's decrease of Ψ, and by how much that decrease must exceed Ψ's
// round-off to be measured at all.
constexpr double kModelAgreement = 0.05;
constexpr double kMeasurableDecrease = 100.0;
// ... and how far above the tolerance the estimate may be predicted to land and still be tried.
constexpr double kHopefulEstimate = 10.0;

}  // namespace

template <class System>
StepReport Newton<System>::iterate(State& q, int max_iterations) {
  StepReport report;
  // Keep the entry state so that a failed step leaves q untouched.
  entry_.save(component_, q);
  auto fail = [&](StepStatus status) {
    report.status = status;
    entry_.restore(component_, q);
    return report;
  };

  enter_parameterization(q);
  const RotationVectorChart* chart =
      options_.rotation == RotationParameterization::kRotationVector ? &chart_ : nullptr;
  // The stall test: the lowest Ψ and ‖g‖ at the last progress, and the updates since.
  double lowest_psi = std::numeric_limits<double>::infinity();
  double lowest_gradient_norm = std::numeric_limits<double>::infinity();
  double lowest_step_norm = std::numeric_limits<double>::infinity();
  int updates_without_progress = 0;
  // The trapezoidal integrator's torque fields are exact at their reference (lib/history.hpp):
  // each iteration starts with them referenced to its iterate, so that the gradient it
  // assembles is the step's equations' exact residual, and ‖δ‖∞ ≤ tolerance means they hold.
  // Ψ then changes from one iteration to the next (not within the line search), which the
  // stall test below tolerates: ‖g‖ and ‖δ‖ count as progress too.
  const bool follow_history = component_.potential.has_rotation_history();
  const bool skew = follow_history && options_.rotation == RotationParameterization::kLie;
  // SolverOptions::hessian_reuse: a chord step on a recent factorisation first (newton.hpp).
  const bool reuse = max_iterations > 0 && factorization_reusable();
  if (reuse && chord_step(q, chart, report)) {
    chord_backoff_ = 0;
    return report;
  }
  if (reuse) {
    // Where chord steps keep failing (Newton needs several iterations: a pendulum swinging
    // through large angles) each attempt costs gradients for nothing: after the second
    // failure in a row skip 1 solve before the next attempt, then 2, 4, … at most the window.
    chord_skip_ = chord_backoff_;
    chord_backoff_ = std::min(std::max(1, 2 * chord_backoff_), options_.hessian_reuse);
  }
  // Where that factorisation served or was offered this solve, the first new one measures
  // the error of its steps (newton.hpp).
  bool measure_reuse = reusable_ && (reuse || chords_since_factorization_ > 0);
  bool whole_steps = true;  // every line search so far took the whole step
  for (;;) {
    if (follow_history) component_.potential.rereference_history(q);
    using Clock = std::chrono::steady_clock;
    const auto t0 = options_.measure_time ? Clock::now() : Clock::time_point{};
    double roundoff = 0.0;
    const double psi = system_.assemble(component_.potential, q, &roundoff, chart);
    ++report.assemblies;
    const auto t1 = options_.measure_time ? Clock::now() : Clock::time_point{};
    const Vector& g = system_.gradient();
    report.gradient_norm = g.norm();
    report.psi = psi;
    if (report.assemblies == 1) {
      report.first_gradient_norm = report.gradient_norm;
      if (options_.measure_condition) report.first_hessian_condition = hessian_condition();
    } else if (report.assemblies == 2) {
      report.second_gradient_norm = report.gradient_norm;
    }
    // A NaN or Inf entry makes the sum non-finite (so does an overflow to ±Inf, which is
    // as unusable); one sum is much cheaper than testing all entries.
    if (!std::isfinite(psi + g.sum()) || !system_.hessian_finite()) {
      return fail(StepStatus::kNonFinite);
    }
    // Before the systems' K is set for the new factorisation: the old one's step, −δ̃.
    if (measure_reuse) measure_reuse = solve_with_last_factorization(g, chord_delta_);
    // The trapezoidal integrator, Lie rotations (newton.hpp): (H + K) δ = −g, factorised where
    // the system can (H δ = −g once a step was damped), else by the fixed-point steps.
    const bool direct = skew && system_.can_factorize_skew();
    skew_factorized_ = direct && whole_steps;
    if (direct) system_.set_history_skew(skew_factorized_ ? &component_.potential : nullptr);
    bool regularized = false;
    const bool factorized = factorize_and_solve(report, regularized);
    reusable_ = factorized && !regularized;
    if (!factorized) return fail(StepStatus::kNonFinite);
    if (skew && !direct) correct_for_history_skew();
    if (measure_reuse) {
      measure_reuse = false;
      adapt_reuse_window(report);
    }
    if (reusable_) {
      factorization_frame_ = component_.potential.frame();
      factorization_start_ = component_.potential.start_frame();
      chords_since_factorization_ = 0;
      // A window closed by a large error opens again, at 2, after hessian_reuse factorisations.
      if (reuse_window_ == 1 && ++closed_factorizations_ >= options_.hessian_reuse) {
        reuse_window_ = 2;
        closed_factorizations_ = 0;
      }
    }
    if (options_.measure_time) {
      const auto t2 = Clock::now();
      report.assembly_seconds += std::chrono::duration<double>(t1 - t0).count();
      report.solve_seconds += std::chrono::duration<double>(t2 - t1).count();
    }
    if (!std::isfinite(delta_.sum())) return fail(StepStatus::kNonFinite);
    report.step_norm = delta_.template lpNorm<Eigen::Infinity>();
    if (!regularized && report.step_norm <= options_.tolerance) {
      // Converged; the step just solved for is taken too (newton.hpp: take_final_step).
      if (max_iterations > 0) retract(q, 1.0);
      report.status = StepStatus::kConverged;
      return report;
    }
    if (report.iterations >= max_iterations) {
      report.status = StepStatus::kMaxIterations;
      report.message = "newton: " + std::to_string(max_iterations) + " iterations (max_iterations) used up; Newton step " +
                       short_number(report.step_norm) + " > tolerance" +
                       (regularized ? ", the Hessian shifted (not positive definite: a free or unstable mode?)" : "");
      return report;
    }
    // Backtracking (Armijo) line search on Ψ, below. Near convergence the predicted decrease
    // falls below the round-off of Ψ itself (estimated by assemble from the terms' values and
    // gradients, which can be large while they cancel); a change within a small multiple of
    // that round-off is accepted, otherwise a tight tolerance stalls on noise. The same
    // multiple is what the stall test does not count as a decrease of Ψ.
    roundoff *= 16.0;
    if (psi < lowest_psi - roundoff ||
        report.gradient_norm < (1.0 - kProgress) * lowest_gradient_norm ||
        report.step_norm < (1.0 - kProgress) * lowest_step_norm) {
      updates_without_progress = 0;
      lowest_psi = std::min(lowest_psi, psi);
      lowest_gradient_norm = std::min(lowest_gradient_norm, report.gradient_norm);
      lowest_step_norm = std::min(lowest_step_norm, report.step_norm);
    } else if (++updates_without_progress >= kStallIterations) {
      report.status = StepStatus::kStalled;
      report.message = "newton: no decrease of Psi beyond its round-off (" +
                       short_number(roundoff) + "), of |g| or of the Newton step in " +
                       std::to_string(kStallIterations) + " iterations; Newton step " +
                       short_number(report.step_norm) + " > tolerance";
      return report;
    }

    const double slope = g.dot(delta_);  // < 0: H (or H + μI) positive definite (or along δ)
    // The estimated check needs the gradient at the full step, taken with its value in one
    // pass. Only for H's own Newton step (not regularised), and where its decrease of Ψ can be
    // measured: for Newton's step the model predicts Ψ(q ⊕ δ) − Ψ(q) = gᵀδ + ½ δᵀHδ = ½ gᵀδ
    // (with K too: gᵀδ = −δᵀHδ). And where it may succeed: Newton's steps shrink
    // quadratically, ‖δ̂‖∞ ≈ C ‖δ‖∞², with C as the last estimate found it (0 before any): no
    // estimate predicted above 10× the tolerance is attempted (it would cost a gradient and a
    // solve for nothing). Not with H alone where the equations' matrix is H + K (after a damped
    // step, newton.hpp): its δ̂ would lack the part H⁻¹Kδ̂.
    const double predicted = 0.5 * slope;
    const bool estimate = options_.convergence_check == ConvergenceCheck::kEstimated &&
                          !regularized && (skew_factorized_ || !direct) &&
                          -predicted > kMeasurableDecrease * roundoff &&
                          contraction_ * report.step_norm * report.step_norm <=
                              kHopefulEstimate * options_.tolerance;
    save(q);
    double alpha = 1.0;
    double psi_trial = psi;
    for (;;) {
      retract(q, alpha);
      psi_trial = estimate && alpha == 1.0
                      ? component_.potential.value_and_gradient(q, trial_gradient_)
                      : component_.potential.value(q);
      if (std::isfinite(psi_trial) &&
          psi_trial <= psi + options_.armijo * alpha * slope + roundoff) {
        break;
      }
      restore(q);
      alpha *= 0.5;
      if (alpha < options_.min_step_length) return fail(StepStatus::kLineSearchFailed);
    }
    ++report.iterations;
    whole_steps = whole_steps && alpha == 1.0;
    if (regularized) ++report.regularized_iterations;
    if (estimate && alpha == 1.0 && std::abs((psi_trial - psi) / predicted - 1.0) <= kModelAgreement &&
        converged_by_estimate(q, chart, psi_trial, report)) {
      delta_ = -correction_;  // the estimate's step δ̂, taken too (newton.hpp: take_final_step)
      retract(q, 1.0);
      return report;
    }
  }
}

template <class System>
bool Newton<System>::converged_by_estimate(const State& q, const RotationVectorChart* chart,
                                           double psi, StepReport& report) {
  using Clock = std::chrono::steady_clock;
  const auto start = options_.measure_time ? Clock::now() : Clock::time_point{};
  // Trapezoidal: the gradient the next iteration would assemble, its torque fields
  // re-referenced at q (which the step then keeps, converged or not).
  const bool follow_history = component_.potential.has_rotation_history();
  if (follow_history) component_.potential.rereference_history(q, trial_gradient_);
  if (chart != nullptr) chart->to_chart_gradient(trial_gradient_);
  if (!std::isfinite(trial_gradient_.sum())) return false;
  // −δ̂, with the last factorisation; where its series does not settle the estimate says nothing.
  if (!solve_with_last_factorization(trial_gradient_, correction_)) return false;
  if (options_.measure_time) {
    report.solve_seconds += std::chrono::duration<double>(Clock::now() - start).count();
  }
  const double step_norm = correction_.template lpNorm<Eigen::Infinity>();
  if (report.step_norm > 0.0) contraction_ = step_norm / (report.step_norm * report.step_norm);
  if (!(step_norm <= options_.tolerance)) return false;
  report.status = StepStatus::kConverged;
  report.step_norm = step_norm;
  report.gradient_norm = trial_gradient_.norm();
  report.psi = psi;
  if (report.assemblies == 1) report.second_gradient_norm = report.gradient_norm;
  return true;
}

template <class System>
bool Newton<System>::solve_with_last_factorization(const Vector& b, Vector& x) {
  system_.solve_linear(b, x);
  if (!(component_.potential.has_rotation_history() &&
        options_.rotation == RotationParameterization::kLie && !skew_factorized_)) {
    return true;
  }
  // As correct_for_history_skew: x ← x₀ − H⁻¹K x.
  delta0_ = x;
  for (int m = 0; m < kSkewCorrections; ++m) {
    component_.potential.history_skew(x, skew_);
    system_.solve_linear(skew_, delta_);
    x = delta0_ - delta_;
  }
  return delta_.norm() <= 0.5 * delta0_.norm();
}

template <class System>
bool Newton<System>::factorization_reusable() {
  if (!System::kReusesFactorizations || options_.hessian_reuse == 1 || !reusable_) return false;
  if (chord_skip_ > 0) {
    --chord_skip_;
    return false;
  }
  // Within the window of the factorisation's step, in the same run (a restart counts its
  // steps from the new start frame: Simulator::set_state).
  const IncrementalPotential& P = component_.potential;
  const int age = P.frame() - factorization_frame_;
  return P.start_frame() == factorization_start_ && age >= 0 && age < reuse_window_;
}

template <class System>
bool Newton<System>::chord_step(State& q, const RotationVectorChart* chart, StepReport& report) {
  IncrementalPotential& P = component_.potential;
  double last = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kMaxChordSteps; ++i) {
    if (P.has_rotation_history()) P.rereference_history(q);
    const double psi = P.value_and_gradient(q, trial_gradient_);
    if (chart != nullptr) chart->to_chart_gradient(trial_gradient_);
    if (!std::isfinite(psi + trial_gradient_.sum())) return false;
    if (!solve_with_last_factorization(trial_gradient_, correction_)) return false;
    const double step_norm = correction_.template lpNorm<Eigen::Infinity>();
    // Not contracting (or not finite): Newton's own iterations take over from here.
    if (!(step_norm <= kChordContraction * last)) return false;
    delta_ = -correction_;
    retract(q, 1.0);
    report.gradient_norm = trial_gradient_.norm();
    if (i == 0) report.first_gradient_norm = report.gradient_norm;
    if (i == 1) report.second_gradient_norm = report.gradient_norm;
    if (step_norm <= options_.tolerance) {
      ++chords_since_factorization_;
      report.status = StepStatus::kConverged;
      report.step_norm = step_norm;
      report.psi = psi;
      report.reused_factorizations = 1;
      return true;
    }
    ++report.iterations;
    last = step_norm;
  }
  return false;
}

template <class System>
void Newton<System>::adapt_reuse_window(StepReport& report) {
  // chord_delta_ = −δ̃ (the old factorisation's step at this iterate), delta_ = δ (the new one).
  const double newton = delta_.template lpNorm<Eigen::Infinity>();
  if (!(newton > 0.0)) return;
  const double error = (chord_delta_ + delta_).template lpNorm<Eigen::Infinity>() / newton;
  report.reuse_error = std::max(report.reuse_error, error);
  if (!(error <= kMaxReuseError)) {
    reuse_window_ = std::max(1, reuse_window_ / 2);
  } else if (error < 0.2 * kMaxReuseError) {
    reuse_window_ = std::min(options_.hessian_reuse, 2 * reuse_window_);
  }
}

std::unique_ptr<StepSolver> make_newton(Component component, const SolverOptions& options) {
  if (component.dofs == 6) return std::make_unique<DenseNewton<6>>(std::move(component), options);
  if (component.dofs <= kDenseLimit) {
    return std::make_unique<DenseNewton<Eigen::Dynamic>>(std::move(component), options);
  }
  return std::make_unique<SparseNewton>(std::move(component), options);
}

template class Newton<DenseSystem<6>>;
template class Newton<DenseSystem<Eigen::Dynamic>>;
template class Newton<SparseSystem>;

}  // namespace liedyn

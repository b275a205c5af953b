#include "ceres_step.hpp"

#include <Eigen/Eigenvalues>

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

#include "../lib/so3.hpp"
#include "../manifolds/ceres_manifolds.hpp"
#include "../manifolds/quaternion.hpp"
#include "../manifolds/so3_manifold.hpp"
#include "newton.hpp"

namespace liedyn {

namespace {

// Ceres's Jacobian blocks are row-major.
template <int Rows>
using RowMajorMap = Eigen::Map<Eigen::Matrix<double, Rows, Eigen::Dynamic, Eigen::RowMajor>>;

// How a Ceres parameter block stores one 3-DOF block of the component.
enum class Storage {
  kPoint,       // x, 3 doubles
  kChart,       // θ, 3 doubles, R = exp(θ) R_ref (Lie: R_ref = R at the start; rotvec: I)
  kQuaternion,  // q, 4 doubles, UnitQuaternionRetraction
  kSO3,         // q, 4 doubles, SO3Manifold (Lie under CeresOptions::lie_blocks = "manifold")
};

int storage_size(Storage s) {
  switch (s) {
    case Storage::kPoint: return 3;
    case Storage::kChart: return 3;
    case Storage::kQuaternion:
    case Storage::kSO3: return 4;
  }
  return 0;
}

// The parameter blocks of a component, one per 3-DOF block of its tangent vector.
struct Parameters {
  struct Block {
    Storage storage = Storage::kPoint;
    int index = -1;     // into State::points or State::rotations
    int rotation = -1;  // among the component's rotations (chart reference), −1 for a point
    int start = 0;      // into values
  };
  std::vector<Block> blocks;       // by tangent offset / 3
  std::vector<double> values;      // what Ceres optimises (user state)
  std::vector<Matrix3> reference;  // kChart: R_ref per component rotation

  double* data(const Block& b) { return values.data() + b.start; }

  // R of a rotation block from its parameters, and T (3 × size) with J_amb = J_Lie T.
  Matrix3 decode(const Block& b, const double* p, Eigen::Matrix<double, 3, 4>& T) const {
    switch (b.storage) {
      case Storage::kChart: {
        Matrix3 J;
        const Matrix3 R = so3::exp(Eigen::Map<const Vector3>(p), &J) * reference[b.rotation];
        T.leftCols<3>() = J;
        return R;
      }
      case Storage::kQuaternion:  // the retraction and SO3Manifold differ only in Plus
      case Storage::kSO3:
        T.leftCols<4>() = SO3Manifold::lie_to_ambient(p);
        // SO3Manifold's rotation normalises q first (what its users get), the retraction's not.
        return b.storage == Storage::kSO3 ? SO3Manifold::rotation(p)
                                          : quat::rotation(Eigen::Map<const Eigen::Vector4d>(p));
      case Storage::kPoint: break;
    }
    return Matrix3::Identity();
  }

  // q → parameters (the chart re-centres on q's rotations).
  void load(const State& q) {
    for (const Block& b : blocks) {
      double* p = data(b);
      Eigen::Map<Vector3> v(p);
      switch (b.storage) {
        case Storage::kPoint: v = q.points[b.index]; break;
        case Storage::kChart:
          if (reference_is_start) {
            reference[b.rotation] = q.rotations[b.index];
            v.setZero();
          } else {
            v = so3::log(q.rotations[b.index]);
          }
          break;
        case Storage::kQuaternion:
        case Storage::kSO3:
          Eigen::Map<Eigen::Vector4d>(p, 4) = quat::from_rotation(q.rotations[b.index]);
          break;
      }
    }
  }

  // parameters → q.
  void store(State& q) {
    Eigen::Matrix<double, 3, 4> T;
    for (const Block& b : blocks) {
      const double* p = data(b);
      if (b.storage == Storage::kPoint) {
        q.points[b.index] = Eigen::Map<const Vector3>(p);
      } else {
        q.rotations[b.index] = so3::orthonormalize(decode(b, p, T));
      }
    }
  }

  bool reference_is_start = true;  // kChart: Lie increments (true) or rotation vectors (false)
};

// A residual form: r(q) ∈ R^kResiduals of a term with kBlocks blocks, and its Lie Jacobian,
// times √w for the term's weight w in Ψ (IncrementalPotential::weight).
// Returns false where the form is not defined (Ceres then rejects the trial point).
template <class Term>
struct TermForm {
  static constexpr int kBlocks = Term::kBlocks;
  static constexpr int kResiduals = Term::kResiduals;
  using Residual = typename Term::Residual;
  using Jacobian = typename Term::ResidualJacobian;
  const Term* term;
  double root_weight = 1.0;  // √w
  const std::array<int, kBlocks>& offsets() const { return term->offsets; }
  bool operator()(const State& q, Residual& r, Jacobian* J) const {
    term->residual(q, r, J);
    if (root_weight != 1.0) {
      r *= root_weight;
      if (J != nullptr) *J *= root_weight;
    }
    return true;
  }
};

// An inertia term with what folds into its residual passed along (its residual's last
// argument): a translational inertia with the constant forces on its point (gravity, node
// forces), by completing the square (docs/design.md §9.3); a rotational inertia with the
// trapezoidal integrator's torque field on its rotation, R̃ + S in place of R̃
// (RotationHistory::inertia_shift).
template <class Inertia, class Folded>
struct FoldedInertiaForm {
  static constexpr int kBlocks = 1;
  static constexpr int kResiduals = Inertia::kResiduals;
  using Residual = typename Inertia::Residual;
  using Jacobian = typename Inertia::ResidualJacobian;
  const Inertia* term;
  const Folded* folded;  // the load, or S
  const std::array<int, 1>& offsets() const { return term->offsets; }
  bool operator()(const State& q, Residual& r, Jacobian* J) const {
    term->residual(q, r, J, *folded);
    return true;
  }
};

// A linear load V (gravity, a force or a torque that cannot be folded: static mode, a force
// with a lever arm, a torque), weighted (w V, IncrementalPotential::weight), as one residual
// r = √(2(w V + c)), J = w gᵀ/r, with the constant c
// set before each solve so that V + c = β > 0 at the start (CeresStepSolver::refresh). Exact
// in value and gradient; its Gauss–Newton curvature g gᵀ/(2(V + c)) is spurious but small
// for a large β, and where V + c ≤ 0 the trial point is rejected.
template <class Term>
struct OffsetRootForm {
  static constexpr int kBlocks = Term::kBlocks;
  static constexpr int kResiduals = 1;
  using Residual = Eigen::Matrix<double, 1, 1>;
  using Jacobian = Eigen::Matrix<double, 1, 3 * kBlocks>;
  const Term* term;
  const double* offset;  // c
  double weight = 1.0;   // w
  const std::array<int, kBlocks>& offsets() const { return term->offsets; }
  bool operator()(const State& q, Residual& r, Jacobian* J) const {
    LocalGradient<kBlocks> g;
    const double twice =
        2.0 * (weight * term->evaluate(q, J != nullptr ? &g : nullptr, nullptr) + *offset);
    if (!(twice > 0.0)) return false;
    r(0) = std::sqrt(twice);
    if (J != nullptr) {  // g/r unweighted: the same rounding as before weights existed
      *J = weight == 1.0 ? Jacobian(g.transpose() / r(0)) : Jacobian((weight / r(0)) * g.transpose());
    }
    return true;
  }
};

// The name of a residual block's term, for CeresGradientCheck.
class LabeledCost : public ceres::CostFunction {
 public:
  virtual const char* label() const = 0;
};

// A Ceres cost function over a form: writes the parameter blocks into a scratch state shared
// by the component's cost functions (hence Ceres runs them on one thread), evaluates the form
// there, and maps each rotation block's Lie Jacobian to its storage (J_amb = J_Lie T).
template <class Form>
class FormCost final : public LabeledCost {
 public:
  FormCost(Form form, const char* label, const Parameters& parameters, State& scratch)
      : label_(label), form_(form), parameters_(parameters), scratch_(scratch) {
    set_num_residuals(Form::kResiduals);
    for (int i = 0; i < Form::kBlocks; ++i) {
      const int offset = form_.offsets()[i];
      if (offset < 0) continue;
      const Parameters::Block& b = parameters.blocks[offset / 3];
      stencil_[dofs_++] = {i, &b};
      mutable_parameter_block_sizes()->push_back(storage_size(b.storage));
    }
  }

  int dof_blocks() const { return dofs_; }
  const char* label() const override { return label_; }
  // The parameter blocks, in the order of the cost's parameter_block_sizes.
  std::vector<double*> blocks(Parameters& parameters) const {
    std::vector<double*> out;
    for (int k = 0; k < dofs_; ++k) out.push_back(parameters.data(*stencil_[k].block));
    return out;
  }

  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    std::array<Eigen::Matrix<double, 3, 4>, Form::kBlocks> T;
    for (int k = 0; k < dofs_; ++k) {
      const Parameters::Block& b = *stencil_[k].block;
      if (b.storage == Storage::kPoint) {
        scratch_.points[b.index] = Eigen::Map<const Vector3>(p[k]);
      } else {
        scratch_.rotations[b.index] = parameters_.decode(b, p[k], T[k]);
      }
    }
    typename Form::Residual r;
    typename Form::Jacobian J;
    if (!form_(scratch_, r, jacobians != nullptr ? &J : nullptr)) return false;
    Eigen::Map<typename Form::Residual>{residuals} = r;
    if (jacobians == nullptr) return true;
    for (int k = 0; k < dofs_; ++k) {
      if (jacobians[k] == nullptr) continue;
      const Parameters::Block& b = *stencil_[k].block;
      const int size = storage_size(b.storage);
      RowMajorMap<Form::kResiduals> Jk(jacobians[k], Form::kResiduals, size);
      const auto J_lie = J.template middleCols<3>(3 * stencil_[k].term_block);
      if (b.storage == Storage::kPoint) {
        Jk = J_lie;
      } else {
        Jk = J_lie * T[k].leftCols(size);
      }
    }
    return true;
  }

 private:
  struct Entry {
    int term_block = 0;
    const Parameters::Block* block = nullptr;
  };
  const char* label_;
  Form form_;
  const Parameters& parameters_;
  State& scratch_;
  std::array<Entry, Form::kBlocks> stencil_{};
  int dofs_ = 0;
};

// Stops Ceres once a step it computed is at most `threshold` long (the 2-norm of the change of
// the parameters, ≥ the ∞-norm of the shared test's step; halved for quaternions, see
// solve), whether Ceres accepted it, rejected it, or found it invalid (step_norm 0: a linear
// solver failure, or a predicted decrease ≤ 0 from round-off): near the minimum the cost
// change of such a step is below the round-off of the cost itself, so Ceres's acceptance
// test is noise there. The shared test then decides; a round that accepted nothing ends the
// solve as stalled.
class StopOnSmallStep final : public ceres::IterationCallback {
 public:
  double threshold = 0.0;
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    return s.iteration > 0 && s.step_norm <= threshold
               ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
               : ceres::SOLVER_CONTINUE;
  }
};

class CeresStepSolver final : public StepSolver {
 public:
  CeresStepSolver(Component component, const SolverOptions& options)
      : StepSolver(options), options_(options) {
    SolverOptions lie = options;
    lie.rotation = RotationParameterization::kLie;
    lie.measure_condition = false;  // the check needs no eigendecomposition
    newton_ = make_newton(std::move(component), lie);
    initialize_ceres_logging();
  }

  Component& component() override { return newton_->component(); }
  const Component& component() const override { return newton_->component(); }
  StepReport check(State& q) override { return newton_->check(q); }

  CeresGradientCheck check_gradients(const State& q) {
    if (problem_ == nullptr) build(q);
    scratch_ = q;
    refresh(q);
    parameters_.load(q);
    CeresGradientCheck out;
    std::vector<ceres::ResidualBlockId> blocks;
    problem_->GetResidualBlocks(&blocks);
    for (const ceres::ResidualBlockId id : blocks) {
      const auto* cost =
          static_cast<const LabeledCost*>(problem_->GetCostFunctionForResidualBlock(id));
      std::vector<double*> x;
      problem_->GetParameterBlocksForResidualBlock(id, &x);
      const int m = cost->num_residuals();
      const std::vector<int32_t>& sizes = cost->parameter_block_sizes();
      std::vector<std::vector<double>> J(x.size());
      std::vector<double*> J_ptr(x.size());
      for (std::size_t k = 0; k < x.size(); ++k) {
        J[k].resize(m * sizes[k]);
        J_ptr[k] = J[k].data();
      }
      std::vector<double> r(m), r_plus(m), r_minus(m);
      ++out.residual_blocks;
      if (!cost->Evaluate(x.data(), r.data(), J_ptr.data())) {
        out.worst_error = std::numeric_limits<double>::infinity();
        out.worst_term = cost->label();
        continue;
      }
      for (std::size_t k = 0; k < x.size(); ++k) {
        // Analytic, in tangent space: J_amb · PlusJacobian (identity without a manifold).
        const ceres::Manifold* manifold = problem_->GetManifold(x[k]);
        const int n = sizes[k];
        const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
            J_amb(J[k].data(), m, n);
        Eigen::MatrixXd analytic = J_amb;
        if (manifold != nullptr) {
          Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> P(n, 3);
          manifold->PlusJacobian(x[k], P.data());
          analytic = J_amb * P;
        }
        // Numeric: central differences along each tangent direction, through Plus.
        Eigen::MatrixXd numeric(m, 3);
        const std::vector<double> x0(x[k], x[k] + n);
        for (int j = 0; j < 3; ++j) {
          for (const double sign : {1.0, -1.0}) {
            Vector3 delta = Vector3::Zero();
            delta(j) = sign * kStep;
            if (manifold != nullptr) {
              manifold->Plus(x0.data(), delta.data(), x[k]);
            } else {
              for (int i = 0; i < n; ++i) x[k][i] = x0[i] + delta(i);
            }
            if (!cost->Evaluate(x.data(), sign > 0 ? r_plus.data() : r_minus.data(), nullptr)) {
              out.worst_error = std::numeric_limits<double>::infinity();
              out.worst_term = cost->label();
            }
          }
          std::copy(x0.begin(), x0.end(), x[k]);
          for (int i = 0; i < m; ++i) numeric(i, j) = (r_plus[i] - r_minus[i]) / (2.0 * kStep);
        }
        const double scale = std::max({analytic.cwiseAbs().maxCoeff(),
                                       numeric.cwiseAbs().maxCoeff(),
                                       std::numeric_limits<double>::min()});
        const double error = (analytic - numeric).cwiseAbs().maxCoeff() / scale;
        if (error > out.worst_error) {
          out.worst_error = error;
          out.worst_term = cost->label();
        }
      }
    }
    return out;
  }
  static constexpr double kStep = 1e-6;  // m or rad: FD truncation ~1e-12 relative

 protected:
  StepReport minimize(State& q) override {
    if (problem_ == nullptr) build(q);
    const Component& c = component();
    entry_.save(c, q);
    scratch_ = q;  // the constant (clamped) blocks; same sizes: no allocation

    StepReport report;
    ceres::Solver::Options solver = solver_options_;
    // Ceres measures a step as the change of the stored parameters: for a quaternion block
    // ‖Q(q)δ‖ = ½‖δ‖, half the rotation.
    const double step_scale = storage_size(rotation_storage()) == 4 ? 0.5 : 1.0;
    stop_.threshold = step_scale * options_.tolerance;
    int iterations = 0;
    // Rounds until the test holds or the iterations are used up. Gauss–Newton converges only
    // linearly where residuals stay large at the minimum (inertia under load, a bent rod), so
    // a step of size `tolerance` does not guarantee the test: each round tightens the
    // threshold tenfold and restarts Ceres from where it stopped, with the chart re-centred
    // and the offset-root constants reset there.
    while (iterations < options_.max_iterations) {
      refresh(q);
      parameters_.load(q);
      solver.max_num_iterations = options_.max_iterations - iterations;
      ceres::Solver::Summary summary;
      ceres::Solve(solver, problem_.get(), &summary);
      if (options_.ceres.verbose) std::printf("ceres: %s\n", summary.message.c_str());
      // Ceres's iteration 0 only evaluates the starting point; it counts as a successful step.
      int accepted = 0;
      for (const ceres::IterationSummary& it : summary.iterations) {
        if (it.iteration > 0 && it.step_is_successful) {
          // Paper Fig. 4's diagnostics: Ceres's gradient norm ‖x − Plus(x, −g)‖ (for chart
          // blocks ‖g‖ in the chart's coordinates, like Newton's; for the 4-double blocks
          // (quat's retraction, lie's SO3Manifold) the change of q, 2 sin(‖g‖/4) for a rotation's
          // g under SO3Manifold, about ½‖g‖ when small) at the start and after the first accepted
          // step of the first round.
          if (accepted == 0 && std::isnan(report.second_gradient_norm) && iterations == 0) {
            report.second_gradient_norm = it.gradient_norm;
          }
          ++accepted;
        }
      }
      if (iterations == 0 && !summary.iterations.empty()) {
        report.first_gradient_norm = summary.iterations.front().gradient_norm;
      }
      iterations += std::max(0, static_cast<int>(summary.iterations.size()) - 1);
      report.assemblies += summary.num_jacobian_evaluations;
      if (options_.measure_time) {
        report.assembly_seconds +=
            summary.residual_evaluation_time_in_seconds + summary.jacobian_evaluation_time_in_seconds;
        report.solve_seconds += summary.linear_solver_time_in_seconds;
      }
      if (summary.termination_type == ceres::FAILURE ||
          summary.termination_type == ceres::USER_FAILURE) {
        restore(q);
        report.status = StepStatus::kSolverFailed;
        report.message = "ceres: " + summary.message;
        report.iterations = iterations;
        return report;
      }
      parameters_.store(q);
      const StepReport test = newton_->check(q);
      report.gradient_norm = test.gradient_norm;
      report.step_norm = test.step_norm;
      report.psi = test.psi;
      report.factorizations += test.factorizations;
      report.assemblies += test.assemblies;
      report.assembly_seconds += test.assembly_seconds;
      report.solve_seconds += test.solve_seconds;
      if (test.status == StepStatus::kNonFinite) {
        restore(q);
        report.status = StepStatus::kNonFinite;
        report.iterations = iterations;
        return report;
      }
      report.status = test.status;
      if (test.converged()) break;
      if (accepted == 0) {
        // No step was accepted: Ceres cannot tell a decrease from the round-off of its cost
        // (about 1e-16 Ψ; a step δ changes the cost by ~½δᵀHδ). More rounds would not help.
        report.status =
            iterations >= options_.max_iterations ? StepStatus::kMaxIterations : StepStatus::kStalled;
        report.message = "ceres: stalled, a round accepted no step (" + summary.message + ")";
        break;
      }
      stop_.threshold = std::max(0.1 * stop_.threshold, 1e-3 * step_scale * options_.tolerance);
    }
    report.iterations = iterations;
    if (!report.converged() && report.message.empty()) {
      report.message = "ceres: iterations used up";
    }
    if (!report.converged()) {
      report.message += "; Newton step " + short_number(report.step_norm) + " > tolerance";
    }
    return report;
  }

 private:
  void restore(State& q) const { entry_.restore(component(), q); }

  // Per solve: the folded loads and the offset-root constants (c = β − V(q)).
  void refresh(const State& q) {
    for (auto& f : refresh_) f(q);
  }

  Storage rotation_storage() const {
    if (options_.rotation == RotationParameterization::kQuaternion) return Storage::kQuaternion;
    if (options_.rotation == RotationParameterization::kLie && options_.ceres.lie_blocks == "manifold") {
      return Storage::kSO3;
    }
    return Storage::kChart;
  }

  template <class Form>
  void add(const Form& form, const char* label) {
    auto* cost = new FormCost<Form>(form, label, parameters_, scratch_);
    if (cost->dof_blocks() == 0) {  // every block clamped: a constant
      delete cost;
      return;
    }
    problem_->AddResidualBlock(cost, nullptr, cost->blocks(parameters_));
  }

  void build(const State& q) {
    const Component& c = component();
    const IncrementalPotential& P = c.potential;
    entry_ = ComponentSnapshot(c);
    scratch_ = q;

    // Parameter blocks.
    const Storage rotation = rotation_storage();
    parameters_.reference_is_start = options_.rotation == RotationParameterization::kLie;
    parameters_.blocks.assign(c.dofs / 3, {});
    parameters_.reference.assign(c.rotations.size(), Matrix3::Identity());
    int start = 0;
    for (const DofBlock& d : c.points) {
      parameters_.blocks[d.offset / 3] = {Storage::kPoint, d.index, -1, start};
      start += 3;
    }
    for (std::size_t i = 0; i < c.rotations.size(); ++i) {
      const DofBlock& d = c.rotations[i];
      parameters_.blocks[d.offset / 3] = {rotation, d.index, static_cast<int>(i), start};
      start += storage_size(rotation);
    }
    parameters_.values.assign(start, 0.0);
    parameters_.load(q);

    ceres::Problem::Options problem_options;
    problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_ = std::make_unique<ceres::Problem>(problem_options);
    for (const Parameters::Block& b : parameters_.blocks) {
      double* p = parameters_.data(b);
      switch (b.storage) {
        case Storage::kPoint:
        case Storage::kChart: problem_->AddParameterBlock(p, 3); break;
        case Storage::kQuaternion: problem_->AddParameterBlock(p, 4, &quaternion_); break;
        case Storage::kSO3: problem_->AddParameterBlock(p, 4, &so3_); break;
      }
    }

    // Loads on a point with translational inertia fold into its residual (dynamics); the
    // other terms without a residual form (linear loads) become offset-root residuals.
    const std::vector<TranslationalInertia>& inertia = P.terms<TranslationalInertia>();
    std::vector<int> inertia_of_point(q.points.size(), -1);
    for (std::size_t t = 0; t < inertia.size(); ++t) {
      inertia_of_point[inertia[t].point] = static_cast<int>(t);
    }
    loads_.assign(inertia.size(), Vector3::Zero());  // no reallocation below: forms keep &loads_[t]
    refresh_.push_back([this](const State&) {
      for (Vector3& l : loads_) l.setZero();
    });
    // The trapezoidal integrator's torque field on a rotation folds into the rotation's inertia
    // where J is invertible (a rod of zero radius or a flat body has a singular J: the field
    // is then an offset root, on which Ceres stalls sooner).
    const std::vector<RotationHistory>& history = P.terms<RotationHistory>();
    std::vector<bool> folded(history.size(), false);
    shifts_.assign(history.size(), Matrix3::Zero());  // no reallocation below: forms keep &shifts_[t]
    P.for_each_term_vector([&](const auto& terms) {
      using T = typename std::decay_t<decltype(terms)>::value_type;
      if constexpr (std::is_same_v<T, TranslationalInertia>) {
        for (std::size_t t = 0; t < terms.size(); ++t) {
          add(FoldedInertiaForm<T, Vector3>{&terms[t], &loads_[t]}, T::kName);
        }
      } else if constexpr (std::is_same_v<T, RotationalInertia>) {
        for (std::size_t t = 0; t < terms.size(); ++t) {
          const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(terms[t].J_over_h2);
          const Vector3 lambda = eigen.eigenvalues();  // ascending
          if (t < history.size() && lambda(0) > 1e-10 * lambda(2)) {
            folded[t] = true;
            const Matrix3 J_inverse = eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() *
                                      eigen.eigenvectors().transpose();
            refresh_.push_back([this, &h = history[t], J_inverse, t](const State&) {
              shifts_[t] = h.inertia_shift(J_inverse);
            });
            add(FoldedInertiaForm<T, Matrix3>{&terms[t], &shifts_[t]},
                "rotational_inertia (with history)");
          } else {
            add(TermForm<T>{&terms[t]}, T::kName);
          }
        }
      } else if constexpr (std::is_same_v<T, RotationHistory>) {
        for (std::size_t t = 0; t < terms.size(); ++t) {
          if (!folded[t]) add_offset_root(terms[t], 1.0);
        }
      } else if constexpr (HasResidual<T>) {
        for (const T& t : terms) add(TermForm<T>{&t, std::sqrt(P.weight(t))}, T::kName);
      } else {
        for (const T& t : terms) {
          if constexpr (PointLoad<T>) {
            int point = -1;
            Vector3 force;
            if (t.offsets[0] >= 0 && t.point_load(point, force) && inertia_of_point[point] >= 0) {
              const int k = inertia_of_point[point];
              refresh_.push_back([this, &t, k, w = P.weight(t)](const State&) {
                int p = -1;
                Vector3 f;
                t.point_load(p, f);
                loads_[k] += w * f;
              });
              continue;
            }
          }
          add_offset_root(t, P.weight(t));
        }
      }
    });

    ceres::Solver::Options& o = solver_options_;
    const bool dense = options_.ceres.linear_solver == "auto" ? c.dofs <= kDenseLimit
                                                             : options_.ceres.linear_solver != "sparse_normal_cholesky";
    if (options_.ceres.linear_solver == "dense_normal_cholesky") {
      o.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    } else {
      o.linear_solver_type = dense ? ceres::DENSE_QR : ceres::SPARSE_NORMAL_CHOLESKY;
    }
    o.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
    o.trust_region_strategy_type = options_.ceres.trust_region_strategy == "dogleg"
                                       ? ceres::DOGLEG
                                       : ceres::LEVENBERG_MARQUARDT;
    o.num_threads = 1;  // the cost functions share one scratch state
    o.minimizer_progress_to_stdout = options_.ceres.verbose;
    o.logging_type = options_.ceres.verbose ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
    // Ceres's own tests at round-off level only: the shared test decides (StopOnSmallStep,
    // then check()).
    o.use_nonmonotonic_steps = true;
    o.function_tolerance = 0.0;
    o.gradient_tolerance = 0.0;
    o.parameter_tolerance = 1e-15;
    o.callbacks.push_back(&stop_);
  }

  template <class Term>
  void add_offset_root(const Term& term, double weight) {
    static const std::string label = std::string(Term::kName) + " (offset root)";
    offset_roots_.push_back(0.0);
    double* c = &offset_roots_.back();
    add(OffsetRootForm<Term>{&term, c, weight}, label.c_str());
    refresh_.push_back([&term, c, weight](const State& q) {
      LocalGradient<Term::kBlocks> g;
      const double v = weight * term.evaluate(q, &g, nullptr);
      g *= weight;
      // β: ten times the change of V over a move of the size of the state. Larger would
      // leave Ceres's cost (which includes β) less room above its round-off; a trial point
      // beyond it is rejected, and the next round resets c there.
      const double beta =
          10.0 * g.template lpNorm<1>() * IncrementalPotential::roundoff_position_scale(q);
      *c = std::max(beta, std::numeric_limits<double>::min()) - v;
    });
  }

  SolverOptions options_;
  std::unique_ptr<StepSolver> newton_;  // owns the component; runs the convergence test
  Parameters parameters_;
  State scratch_;
  ComponentSnapshot entry_;  // the component's blocks on entry
  std::vector<Vector3> loads_;          // folded loads, per translational inertia term
  std::vector<Matrix3> shifts_;         // folded torque fields, per rotation history term
  std::deque<double> offset_roots_;     // c per offset-root residual (stable addresses)
  std::vector<std::function<void(const State&)>> refresh_;
  UnitQuaternionRetraction quaternion_;
  SO3Manifold so3_;
  StopOnSmallStep stop_;
  ceres::Solver::Options solver_options_;
  std::unique_ptr<ceres::Problem> problem_;
};

}  // namespace

void initialize_ceres_logging() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!google::IsGoogleLoggingInitialized()) google::InitGoogleLogging("liedyn");
  });
}

std::unique_ptr<StepSolver> make_ceres_step_solver(Component component,
                                                   const SolverOptions& options) {
  return std::make_unique<CeresStepSolver>(std::move(component), options);
}

CeresGradientCheck check_ceres_gradients(Component component, const SolverOptions& options,
                                         const State& q) {
  CeresStepSolver solver(std::move(component), options);
  return solver.check_gradients(q);
}

}  // namespace liedyn

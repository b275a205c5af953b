#include "ipopt_step.hpp"
#include "ipopt_lock.hpp"
#include "ipopt_status.hpp"

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <compare>
#include <coin/IpIpoptApplication.hpp>
#include <coin/IpTNLP.hpp>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "../lib/so3.hpp"
#include "../manifolds/quaternion_chart.hpp"
#include "../manifolds/rotation_chart.hpp"
#include "newton.hpp"

namespace liedyn {

namespace {

using Clock = std::chrono::steady_clock;

// ---------------------------------------------------------------------------------------
// The lower triangle of the NLP's Hessian in Ipopt's triplet form.
//
// IncrementalPotential::assemble_into (and the coordinates' finish after it) call
// add(row, column, block) in the same order for every assembly of a potential, with blocks of
// 3 or 4 rows and columns (a position's 3 coordinates, a quaternion's 4) at the coordinates'
// offsets. The first assembly records that order (and the blocks); finish_recording() then
// builds the pattern: one slot per distinct block of the lower block triangle (row > column:
// all its entries; row = column: its lower triangle), and for every call the start of its
// slot — or −1 for a block above the diagonal, the transpose of one below (every term's local
// Hessian is symmetric, and so is J_rowᵀ B J_column under transposition). Later assemblies
// scatter each call into its slot by call number: no search, no allocation.
class LowerTriangleSink {
 public:
  // With discard (Ipopt's limited-memory Hessian), every block is dropped.
  explicit LowerTriangleSink(bool discard) : discard_(discard) {}

  void clear() {
    next_call_ = 0;
    order_broken_ = false;  // judged per assembly
    std::fill(values_.begin(), values_.end(), 0.0);
  }

  template <class Block>
  void add(int row, int column, const Block& block) {
    if (discard_) return;
    const int rows = static_cast<int>(block.rows()), columns = static_cast<int>(block.cols());
    if (!recorded_) {
      calls_.push_back(Call{row, column, rows, columns});
      recorded_blocks_.emplace_back(block);
      return;
    }
    // The contract of assemble_into, checked at the cost of a few integer comparisons.
    if (next_call_ >= calls_.size() || calls_[next_call_].row != row ||
        calls_[next_call_].column != column || calls_[next_call_].rows != rows ||
        calls_[next_call_].columns != columns) {
      order_broken_ = true;
      return;
    }
    const int start = slot_of_call_[next_call_++];
    if (start < 0) return;
    double* v = values_.data() + start;
    for (int i = 0; i < rows; ++i) {
      const int last = row == column ? i + 1 : columns;
      for (int j = 0; j < last; ++j) *v++ += block(i, j);
    }
  }

  bool recorded() const { return recorded_ || discard_; }

  // After the first assembly: the pattern, and the values of that assembly.
  void finish_recording() {
    if (recorded()) return;
    std::vector<Call> lower;  // distinct blocks with row ≥ column
    for (const Call& c : calls_) {
      if (c.row >= c.column) lower.push_back(c);
    }
    std::sort(lower.begin(), lower.end());
    lower.erase(std::unique(lower.begin(), lower.end()), lower.end());
    std::vector<int> start_of_block(lower.size());
    for (std::size_t b = 0; b < lower.size(); ++b) {
      const Call& c = lower[b];
      start_of_block[b] = static_cast<int>(rows_.size());
      for (int i = 0; i < c.rows; ++i) {
        for (int j = 0; j < (c.row == c.column ? i + 1 : c.columns); ++j) {
          rows_.push_back(c.row + i);
          columns_.push_back(c.column + j);
        }
      }
    }
    slot_of_call_.resize(calls_.size());
    for (std::size_t k = 0; k < calls_.size(); ++k) {
      if (calls_[k].row < calls_[k].column) {
        slot_of_call_[k] = -1;
        continue;
      }
      const auto it = std::lower_bound(lower.begin(), lower.end(), calls_[k]);
      slot_of_call_[k] = start_of_block[it - lower.begin()];
    }
    values_.assign(rows_.size(), 0.0);
    recorded_ = true;
    // Scatter the recorded first assembly.
    for (std::size_t k = 0; k < calls_.size(); ++k) {
      add(calls_[k].row, calls_[k].column, recorded_blocks_[k]);
    }
    recorded_blocks_.clear();
    recorded_blocks_.shrink_to_fit();
  }

  // Entries of the lower triangle (0 before the pattern is recorded, and when discarding).
  int nonzeros() const { return static_cast<int>(values_.size()); }
  const std::vector<int>& rows() const { return rows_; }
  const std::vector<int>& columns() const { return columns_; }
  const std::vector<double>& values() const { return values_; }
  // True if the last assembly called add in another order than the recorded one, or made
  // fewer calls (a broken contract: the values are then wrong and must not be used).
  bool order_broken() const {
    return order_broken_ || (recorded_ && !discard_ && next_call_ != calls_.size());
  }

 private:
  struct Call {
    int row, column, rows, columns;
    auto operator<=>(const Call&) const = default;
  };
  using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 4>;
  bool discard_ = false;
  bool recorded_ = false;
  bool order_broken_ = false;
  std::vector<Call> calls_;              // every add, in call order
  std::vector<Block> recorded_blocks_;   // the first assembly's blocks (until recorded)
  std::vector<int> slot_of_call_;        // per call: start in values_, −1 if skipped
  std::vector<int> rows_, columns_;      // per entry (Ipopt's iRow, jCol; 0-based)
  std::vector<double> values_;
  std::size_t next_call_ = 0;
};

// ---------------------------------------------------------------------------------------
// The NLP's variables (ipopt_step.hpp), in the component's tangent order: a position's 3, and
// per rotation its 3 chart coordinates θ (lie, rotvec: RotationVectorChart, n = dofs) or its
// 4 quaternion numbers (quat: QuaternionCoordinates, n = dofs + rotations, with a row
// qᵀq − 1 = 0 per rotation after the joints' rows).
class Coordinates {
 public:
  Coordinates(const Component& component, RotationParameterization rotation)
      : rotation_(rotation), chart_(component) {
    if (rotation_ == RotationParameterization::kQuaternion) quaternions_ = QuaternionCoordinates(component);
  }

  bool quaternions() const { return rotation_ == RotationParameterization::kQuaternion; }
  int size(const Component& component) const {
    return quaternions() ? quaternions_.size() : component.dofs;
  }
  // The norm rows: one per rotation under quat, else none.
  int norm_rows() const { return quaternions() ? static_cast<int>(quaternions_.rotations()) : 0; }
  // First variable and number of variables of the tangent block at `offset`.
  int variable(int offset) const { return quaternions() ? quaternions_.variable(offset) : offset; }
  int width(int offset) const {
    return quaternions() && quaternions_.jacobian_at(offset) != nullptr ? 4 : 3;
  }

  // The starting point of a solve at q, and the chart around it (lie: R₀ = R, θ = 0; rotvec:
  // R₀ = I, θ = log R, and R ← exp(θ) so that both agree exactly; quat: q of R, s ≥ 0).
  void start(const Component& component, State& q, Eigen::VectorXd& x) {
    if (quaternions()) {
      quaternions_.get(component, q, x.data());
      quaternions_.set(component, x.data(), q);  // R(q) exactly
      return;
    }
    for (const DofBlock& b : component.points) x.segment<3>(b.offset) = q.points[b.index];
    for (std::size_t i = 0; i < component.rotations.size(); ++i) {
      const DofBlock& b = component.rotations[i];
      Matrix3& R = q.rotations[b.index];
      if (rotation_ == RotationParameterization::kRotationVector) {
        x.segment<3>(b.offset) = so3::log(R);
        R = chart_.set(i, x.segment<3>(b.offset));
      } else {
        chart_.set_reference(i, R);
        x.segment<3>(b.offset).setZero();
      }
    }
  }

  // Writes the point x into q.
  void set(const Component& component, const Ipopt::Number* x, State& q) {
    if (quaternions()) {
      quaternions_.set(component, x, q);
      return;
    }
    const Eigen::Map<const Eigen::VectorXd> xv(x, component.dofs);
    for (const DofBlock& b : component.points) q.points[b.index] = xv.segment<3>(b.offset);
    for (std::size_t i = 0; i < component.rotations.size(); ++i) {
      const DofBlock& b = component.rotations[i];
      q.rotations[b.index] = chart_.set(i, xv.segment<3>(b.offset));
    }
  }

  // Ψ at q (as last set), its gradient in the variables and their Hessian through `sink`; a
  // norm row's multiplier μ_i adds 2 μ_i I to its quaternion's diagonal block (when non-null).
  template <class Sink>
  double assemble(const IncrementalPotential& potential, const State& q, Eigen::VectorXd& lie,
                  Eigen::VectorXd& g, Sink& sink, const double* norm_multipliers) const {
    if (quaternions()) {
      return assemble_in_quaternions(potential, q, quaternions_, lie, g, sink, norm_multipliers);
    }
    return assemble_charted(potential, q, g, sink, nullptr, &chart_);
  }

  // A constraint's Lie Jacobian block (r × 3, at the tangent `offset`) in the variables:
  // times J_l(θ) (a change ε of θ is the left perturbation J_l(θ) ε) or E(q) (r × 4).
  Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 4> in_variables(int offset, const Matrix3& lie) const {
    if (quaternions()) {
      const Matrix34* E = quaternions_.jacobian_at(offset);
      if (E != nullptr) return lie * *E;
      return lie;
    }
    const Matrix3* J_l = chart_.jacobian_at(offset);
    if (J_l != nullptr) return lie * *J_l;
    return lie;
  }

  // qᵀq − 1 per rotation, and its gradient 2qᵀ (4 entries per row, at rotation_variable).
  void norms(Ipopt::Number* g) const {
    for (std::size_t i = 0; i < quaternions_.rotations(); ++i) {
      g[i] = quaternions_.quaternion(i).squaredNorm() - 1.0;
    }
  }
  void norm_gradients(Ipopt::Number* v) const {
    for (std::size_t i = 0; i < quaternions_.rotations(); ++i) {
      for (int j = 0; j < 4; ++j) *v++ = 2.0 * quaternions_.quaternion(i)(j);
    }
  }
  int rotation_variable(std::size_t i) const { return quaternions_.rotation_variable(i); }

  // Lie's rotations exp(θ) R₀ drift from SO(3) by round-off with every re-centring: they are
  // re-orthonormalised at the end of a solve (docs/design.md §2.3); rotvec's exp(θ) and
  // quat's R(q) are rotations to round-off of their own.
  bool reorthonormalize() const { return rotation_ == RotationParameterization::kLie; }

 private:
  RotationParameterization rotation_;
  RotationVectorChart chart_;
  QuaternionCoordinates quaternions_;
};

// ---------------------------------------------------------------------------------------
// The NLP of one step: Coordinates' variables, rows for the exact equalities, then (quat)
// the quaternions' norms (ipopt_step.hpp). Evaluations write the point into the state being
// solved.
class StepNlp final : public Ipopt::TNLP {
 public:
  StepNlp(Component& component, const SolverOptions& options)
      : component_(component),
        tolerance_(options.tolerance),
        measure_time_(options.measure_time),
        coordinates_(component, options.rotation),
        n_(coordinates_.size(component)),
        sink_(options.ipopt.hessian_approximation != "exact"),
        lagrangian_sink_(options.ipopt.hessian_approximation != "exact"),
        equalities_(component.potential.exact_equalities()),
        no_multipliers_(static_cast<std::size_t>(equalities_), Vector3::Zero()),
        multipliers_(no_multipliers_),
        penalties_(static_cast<std::size_t>(equalities_), 0.0),
        bases_(static_cast<std::size_t>(equalities_)),
        ranks_(static_cast<std::size_t>(equalities_), 0),
        norm_multipliers_(static_cast<std::size_t>(coordinates_.norm_rows()), 0.0),
        lie_(component.dofs),
        g_(n_),
        g_lagrangian_(n_),
        x0_(n_),
        x_state_(n_),
        x_assembled_(n_),
        x_final_(n_) {
    record_constraint_rows();
  }

  // Per step: clears the counters below.
  void begin_step() {
    assemblies_ = 0;
    evaluation_seconds_ = 0.0;
    first_gradient_norm_ = second_gradient_norm_ = std::numeric_limits<double>::quiet_NaN();
  }

  // Per Ipopt solve: the starting point at q and the chart around it (Coordinates::start).
  void start(State& q) {
    q_ = &q;
    // The objective: Ψ without the exact equalities (λ = 0, ρ = 0; header); their ρ are kept
    // for the shared test.
    int i = 0;
    component_.potential.for_each_exact_equality([&](const auto& t) { penalties_[i++] = t.stiffness; });
    set_lagrangian(no_multipliers_, false);
    coordinates_.start(component_, q, x0_);
    choose_constraint_rows(q);
    x_state_ = x0_;
    state_valid_ = true;
    assembled_valid_ = false;
    has_final_ = false;
    iterations_ = 0;
  }

  // At the end of a step without a final point from Ipopt: the exact equalities get their ρ
  // back (λ = 0), as every consumer outside a solve expects.
  void leave() {
    if (penalties_out_) set_lagrangian(no_multipliers_, true);
  }

  // Assembles at the starting point (the pattern too, the first time); false if Ψ, g or H
  // is not finite there.
  bool assemble_start() {
    assemble(x0_.data());
    return assembled_finite_;
  }

  // Writes Ipopt's final point into q (Coordinates::reorthonormalize) and its multipliers into the exact equalities, with their ρ back: the Lagrangian
  // λᵀc + ½ρ‖c‖² the shared test sees, and the forces the adjoint reads. False if Ipopt
  // returned none.
  bool write_final() {
    if (!has_final_) return false;
    set_lagrangian(multipliers_, true);
    set_point(x_final_.data());
    if (coordinates_.reorthonormalize()) {
      for (const DofBlock& b : component_.rotations) {
        q_->rotations[b.index] = so3::orthonormalize(q_->rotations[b.index]);
      }
      state_valid_ = false;  // q no longer holds exactly exp(θ) R₀
    }
    return true;
  }

  int iterations() const { return iterations_; }
  int assemblies() const { return assemblies_; }
  double evaluation_seconds() const { return evaluation_seconds_; }
  double first_gradient_norm() const { return first_gradient_norm_; }
  double second_gradient_norm() const { return second_gradient_norm_; }
  bool hessian_order_broken() const { return sink_.order_broken(); }

  // --- Ipopt::TNLP --------------------------------------------------------------------
  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g,
                    Ipopt::Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = n_;
    m = constraint_rows_ + coordinates_.norm_rows();
    nnz_jac_g = static_cast<Ipopt::Index>(jacobian_rows_.size());
    nnz_h_lag = sink_.nonzeros();
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m,
                       Ipopt::Number* g_l, Ipopt::Number* g_u) override {
    // Beyond ±nlp_lower/upper_bound_inf (±1e19): no bounds. The equalities: c = 0.
    std::fill(x_l, x_l + n, -1e20);
    std::fill(x_u, x_u + n, 1e20);
    std::fill(g_l, g_l + m, 0.0);
    std::fill(g_u, g_u + m, 0.0);
    return true;
  }

  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index m, bool init_lambda,
                          Ipopt::Number* lambda) override {
    if (init_x) std::copy(x0_.data(), x0_.data() + n, x);
    if (init_lambda) std::fill(lambda, lambda + m, 0.0);
    return true;
  }

  // Ψ: from the assembly if there is one at x, else one IncrementalPotential::value (a
  // line-search trial point). A non-finite Ψ is an evaluation error for Ipopt.
  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& obj_value) override {
    if (assembled_at(x)) {
      obj_value = value_;
      return std::isfinite(obj_value);
    }
    const auto t0 = measure_time_ ? Clock::now() : Clock::time_point{};
    set_point(x);
    obj_value = component_.potential.value(*q_);
    if (measure_time_) evaluation_seconds_ += seconds_since(t0);
    return std::isfinite(obj_value);
  }

  // ∇f: [g_x, J_l(θ)ᵀ g_θ] in a chart, [g_x, E(q)ᵀ g_θ] in quaternions.
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number* grad_f) override {
    assemble(x);
    std::copy(g_.data(), g_.data() + n, grad_f);
    return assembled_finite_;
  }

  // Pᵀc of every exact equality (its r rows, choose_constraint_rows), then (quat) qᵀq − 1.
  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index m, Ipopt::Number* g) override {
    set_point(x);
    Ipopt::Number* row = g;
    int i = 0;
    component_.potential.for_each_exact_equality([&](const auto& t) {
      const Vector3 c = t.constraint(*q_, nullptr);
      for (int k = 0; k < ranks_[i]; ++k) *row++ = bases_[i].col(k).dot(c);
      ++i;
    });
    coordinates_.norms(row);
    return std::all_of(g, g + m, [](double v) { return std::isfinite(v); });
  }

  // ∂(Pᵀc)/∂x: Pᵀ times the terms' Lie Jacobian blocks in the variables
  // (Coordinates::in_variables); r × 3 entries per block (r × 4 for a quaternion). Then
  // (quat) 2qᵀ per norm row.
  bool eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index nele_jac,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (nele_jac != static_cast<Ipopt::Index>(jacobian_rows_.size())) return false;
    if (values == nullptr) {
      std::copy(jacobian_rows_.begin(), jacobian_rows_.end(), iRow);
      std::copy(jacobian_columns_.begin(), jacobian_columns_.end(), jCol);
      return true;
    }
    set_point(x);
    Ipopt::Number* v = values;
    for_each_jacobian_block(*q_, [&](int i, int offset, const Matrix3& lie) {
      const auto block = (bases_[i].transpose() * coordinates_.in_variables(offset, lie)).eval();
      for (int k = 0; k < ranks_[i]; ++k) {
        for (int j = 0; j < block.cols(); ++j) *v++ = block(k, j);
      }
    });
    coordinates_.norm_gradients(v);
    v += 4 * coordinates_.norm_rows();
    return std::all_of(values, v, [](double e) { return std::isfinite(e); });
  }

  // Lower triangle of obj_factor · ∇²f + Σ λᵀ∇²c, with f's Hessian in the variables (charted:
  // [H_xx, H_xθ J_l; ·, J_lᵀ H_θθ J_l + C(θ, g)]; quaternions: quaternion_chart.hpp) and the
  // constraints' part as the difference of two assemblies, with the multipliers λ and with
  // none: the exact equalities' Lagrangian blocks ∇²(λᵀc), the coordinates' correction from
  // Jᵀλ and the norms' 2μ I, whatever obj_factor (0 in Ipopt's restoration).
  bool eval_h(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number obj_factor, Ipopt::Index,
              const Ipopt::Number* lambda, bool, Ipopt::Index nele_hess, Ipopt::Index* iRow,
              Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (nele_hess != sink_.nonzeros()) return false;
    if (values == nullptr) {
      std::copy(sink_.rows().begin(), sink_.rows().end(), iRow);
      std::copy(sink_.columns().begin(), sink_.columns().end(), jCol);
      return true;
    }
    assemble(x);
    if (!assembled_finite_ || sink_.order_broken()) return false;
    const std::vector<double>& h = sink_.values();
    for (std::size_t k = 0; k < h.size(); ++k) values[k] = obj_factor * h[k];
    if (equalities_ == 0 && coordinates_.norm_rows() == 0) return true;
    const auto t0 = measure_time_ ? Clock::now() : Clock::time_point{};
    world_multipliers(lambda);
    std::copy(lambda + constraint_rows_, lambda + constraint_rows_ + coordinates_.norm_rows(),
              norm_multipliers_.begin());
    set_lagrangian(multipliers_, false);
    set_point(x);  // assemble(x) may have found its values without moving the state there
    const double value = coordinates_.assemble(component_.potential, *q_, lie_, g_lagrangian_,
                                               lagrangian_sink_, norm_multipliers_.data());
    set_lagrangian(no_multipliers_, false);
    lagrangian_sink_.finish_recording();  // the first time only: the same calls as sink_'s
    if (measure_time_) evaluation_seconds_ += seconds_since(t0);
    const std::vector<double>& hl = lagrangian_sink_.values();
    if (lagrangian_sink_.order_broken() || hl.size() != h.size() ||
        !std::isfinite(value + g_lagrangian_.sum())) {
      return false;
    }
    for (std::size_t k = 0; k < h.size(); ++k) values[k] += hl[k] - h[k];
    return std::all_of(values, values + h.size(), [](double e) { return std::isfinite(e); });
  }

  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index,
                         const Ipopt::Number*, const Ipopt::Number* lambda, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    if (x == nullptr || (constraint_rows_ + coordinates_.norm_rows() > 0 && lambda == nullptr)) return;
    std::copy(x, x + n, x_final_.data());
    world_multipliers(lambda);
    has_final_ = true;
  }

  // Stops Ipopt once the primal direction of the iteration just made has ‖d‖∞ ≤ tolerance
  // (never at iteration 0, whose d is 0 by convention, nor in the restoration phase, whose d
  // belongs to another problem).
  bool intermediate_callback(Ipopt::AlgorithmMode mode, Ipopt::Index iter, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Number d_norm,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Index,
                             const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    iterations_ = iter;
    return !(mode == Ipopt::RegularMode && iter > 0 && d_norm <= tolerance_);
  }

 private:
  // f(i, offset, J_block) for every DOF block of every exact equality i's Lie Jacobian (its
  // columns at `offset`), in a fixed order.
  template <class Function>
  void for_each_jacobian_block(const State& q, Function&& f) const {
    int i = 0;
    component_.potential.for_each_exact_equality([&](const auto& t) {
      using T = std::decay_t<decltype(t)>;
      typename T::ConstraintJacobian J;
      t.constraint(q, &J);
      for (int b = 0; b < T::kBlocks; ++b) {
        if (t.offsets[b] >= 0) f(i, t.offsets[b], Matrix3(J.template block<3, 3>(0, 3 * b)));
      }
      ++i;
    });
  }

  // The rows Ipopt sees (header): per exact equality, r = kConstraintRank rows Pᵀc (term.hpp;
  // 2 for a hinge's alignment c = a − b and a slider's line c = n × d, whose 3 numbers hold 2
  // constraints: 3 rows would make a rank-deficient Jacobian that Ipopt takes for a square
  // system), then (quat) a norm row per rotation; and the Jacobian's pattern, in eval_jac_g's
  // order: r × (3 or 4) per DOF block, then 4 per norm row.
  void record_constraint_rows() {
    std::vector<int> first_row;
    component_.potential.for_each_exact_equality([&](const auto& t) {
      first_row.push_back(constraint_rows_);
      ranks_[first_row.size() - 1] = constraint_rank<std::decay_t<decltype(t)>>();
      constraint_rows_ += ranks_[first_row.size() - 1];
    });
    int i = 0;
    component_.potential.for_each_exact_equality([&](const auto& t) {
      for (const int offset : t.offsets) {
        if (offset < 0) continue;
        for (int k = 0; k < ranks_[i]; ++k) {
          for (int j = 0; j < coordinates_.width(offset); ++j) {
            jacobian_rows_.push_back(first_row[i] + k);
            jacobian_columns_.push_back(coordinates_.variable(offset) + j);
          }
        }
      }
      ++i;
    });
    for (int r = 0; r < coordinates_.norm_rows(); ++r) {
      for (int j = 0; j < 4; ++j) {
        jacobian_rows_.push_back(constraint_rows_ + r);
        jacobian_columns_.push_back(coordinates_.rotation_variable(static_cast<std::size_t>(r)) + j);
      }
    }
  }

  // P per exact equality at the start of a solve: the r leading eigenvectors of J Jᵀ (J its
  // Lie Jacobian over the DOF blocks), the directions c moves in; for r = 2 the one dropped
  // is along the axis (a + b for the alignment, n for the line), in which c is second order.
  // P is constant within a solve, so the rows' derivatives are Pᵀ times the terms', and
  // Pᵀc = 0 is c = 0 near the start.
  void choose_constraint_rows(const State& q) {
    if (equalities_ == 0) return;
    std::vector<Matrix3>& JJt = bases_;  // J Jᵀ first, then its eigenvectors in place
    std::fill(JJt.begin(), JJt.end(), Matrix3::Zero());
    for_each_jacobian_block(q, [&](int i, int, const Matrix3& J) { JJt[i] += J * J.transpose(); });
    for (int i = 0; i < equalities_; ++i) {
      const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(JJt[i]);  // ascending eigenvalues
      for (int k = 0; k < 3; ++k) bases_[i].col(k) = eigen.eigenvectors().col(2 - k);
    }
  }

  // Every exact equality as the Lagrangian λᵀc + ½ρ‖c‖² (term.hpp, Constraint) with λ from
  // `multipliers` and ρ its own (with_penalties) or 0.
  void set_lagrangian(const std::vector<Vector3>& multipliers, bool with_penalties) {
    int i = 0;
    component_.potential.for_each_exact_equality([&](auto& t) {
      t.adjoint = true;
      t.multiplier = multipliers[i];
      t.stiffness = with_penalties ? penalties_[i] : 0.0;
      ++i;
    });
    penalties_out_ = !with_penalties && equalities_ > 0;
  }

  // λ = P λ̃ (world) of every exact equality from Ipopt's λ̃ of its rows.
  void world_multipliers(const Ipopt::Number* lambda) {
    for (int i = 0; i < equalities_; ++i) {
      multipliers_[i].setZero();
      for (int k = 0; k < ranks_[i]; ++k) multipliers_[i] += *lambda++ * bases_[i].col(k);
    }
  }

  bool same_point(const Ipopt::Number* x, const Eigen::VectorXd& y) const {
    return std::equal(x, x + n_, y.data());
  }
  bool assembled_at(const Ipopt::Number* x) const {
    return assembled_valid_ && same_point(x, x_assembled_);
  }

  // Writes the point x into the state (and the coordinates' J_l(θ) or E(q)).
  void set_point(const Ipopt::Number* x) {
    if (state_valid_ && same_point(x, x_state_)) return;
    coordinates_.set(component_, x, *q_);
    x_state_ = Eigen::Map<const Eigen::VectorXd>(x, n_);
    state_valid_ = true;
  }

  // Ψ, the charted gradient and Hessian at x, unless they are there already.
  void assemble(const Ipopt::Number* x) {
    if (assembled_at(x)) return;
    const auto t0 = measure_time_ ? Clock::now() : Clock::time_point{};
    set_point(x);
    value_ = coordinates_.assemble(component_.potential, *q_, lie_, g_, sink_, nullptr);
    sink_.finish_recording();  // the first time only
    if (measure_time_) evaluation_seconds_ += seconds_since(t0);
    double h_sum = 0.0;
    for (const double h : sink_.values()) h_sum += h;
    // A NaN or Inf entry makes the sum non-finite (as does an overflow, as unusable).
    assembled_finite_ = std::isfinite(value_ + g_.sum() + h_sum);
    x_assembled_ = x_state_;
    assembled_valid_ = true;
    ++assemblies_;
    if (assemblies_ == 1) {
      first_gradient_norm_ = g_.norm();
    } else if (assemblies_ == 2) {
      second_gradient_norm_ = g_.norm();
    }
  }

  Component& component_;
  double tolerance_;
  bool measure_time_;
  Coordinates coordinates_;
  int n_;                              // variables
  LowerTriangleSink sink_;             // f's Hessian (the exact equalities at λ = 0)
  LowerTriangleSink lagrangian_sink_;  // the same assembly at Ipopt's λ (eval_h)
  int equalities_;                     // exact equality terms
  std::vector<Vector3> no_multipliers_;
  std::vector<Vector3> multipliers_;  // P λ̃ per equality (eval_h, then the final one)
  std::vector<double> penalties_;     // per equality: its ρ, while Ipopt sees ρ = 0
  bool penalties_out_ = false;        // the terms hold ρ = 0 (during a solve)
  std::vector<Matrix3> bases_;        // per equality: P in its leading ranks_ columns
  std::vector<int> ranks_;            // per equality: r, its rows in Ipopt's problem
  int constraint_rows_ = 0;           // Σ r
  std::vector<Ipopt::Index> jacobian_rows_, jacobian_columns_;
  std::vector<double> norm_multipliers_;  // quat: Ipopt's λ of the norm rows (eval_h)
  Eigen::VectorXd lie_;          // quat: the Lie gradient, in tangent order (work space)
  Eigen::VectorXd g_;            // gradient in the variables at x_assembled_
  Eigen::VectorXd g_lagrangian_;  // the Lagrangian assembly's (unused but for finiteness)
  Eigen::VectorXd x0_;           // starting point
  Eigen::VectorXd x_state_;      // the point *q_ holds (if state_valid_)
  Eigen::VectorXd x_assembled_;  // the point of value_, g_ and the sink (if assembled_valid_)
  Eigen::VectorXd x_final_;      // Ipopt's final point (if has_final_)
  State* q_ = nullptr;
  double value_ = 0.0;
  bool state_valid_ = false;
  bool assembled_valid_ = false;
  bool assembled_finite_ = false;
  bool has_final_ = false;
  int iterations_ = 0;
  int assemblies_ = 0;
  double evaluation_seconds_ = 0.0;
  double first_gradient_norm_ = std::numeric_limits<double>::quiet_NaN();
  double second_gradient_norm_ = std::numeric_limits<double>::quiet_NaN();
};

// Ipopt stopped at a usable point (our stop, its own, a limit): the shared test decides.
// Every other status is an error and the step fails.
bool usable(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded:
    case Ipopt::Solved_To_Acceptable_Level:
    case Ipopt::Search_Direction_Becomes_Too_Small:
    case Ipopt::User_Requested_Stop:
    case Ipopt::Feasible_Point_Found:
    case Ipopt::Maximum_Iterations_Exceeded:
    case Ipopt::Maximum_CpuTime_Exceeded: return true;
    default: return false;
  }
}

class IpoptStepSolver final : public StepSolver {
 public:
  ~IpoptStepSolver() override {
    const std::lock_guard<std::recursive_mutex> lock(ipopt_mutex());  // MUMPS's termination
    app_ = nullptr;
  }
  IpoptStepSolver(Component component, const SolverOptions& options)
      : StepSolver(options),
        options_(options),
        entry_(component) {
    // The shared convergence test: Newton on the Lie parameterisation, owning the component.
    SolverOptions lie = options;
    lie.backend = Backend::kNewton;
    lie.rotation = RotationParameterization::kLie;
    lie.measure_condition = false;
    newton_ = make_newton(std::move(component), lie);
    nlp_ = new StepNlp(newton_->component(), options);
    tnlp_ = nlp_;  // owns it (Ipopt's intrusive reference count)

    app_ = new Ipopt::IpoptApplication();
    const IpoptOptions& ipopt = options.ipopt;
    // Output options are read by Initialize, so they are set before it.
    set_integer("print_level", ipopt.print_level);
    if (ipopt.print_level == 0) set_string("sb", "yes");
    if (!ipopt.output_file.empty()) {
      set_string("output_file", ipopt.output_file);
      set_integer("file_print_level", std::max(ipopt.print_level, 5));
    }
    set_string("linear_solver", "mumps");
    set_string("hessian_approximation", ipopt.hessian_approximation);
    set_string("derivative_test", ipopt.derivative_test);
    // The checker tests at the starting point moved at random by up to this much per
    // variable. Ipopt's default, 10, takes rotation vectors past 2π, where the chart is
    // singular and forward differences say nothing; 0.1 stays where Ipopt works and still
    // makes θ ≠ 0 under lie (J_l(θ) ≠ I, C(θ, g) ≠ 0: the whole chart is exercised).
    set_numeric("point_perturbation_radius", 0.1);
    set_string("nlp_scaling_method", "none");
    // Ipopt's own optimality test off: our callback and the shared test decide (header).
    set_numeric("tol", 1e-300);
    set_integer("acceptable_iter", 0);
    set_integer("max_iter", options.max_iterations);
    // Initialize("") reads no options file; in Ipopt 3.11 it fails only when the output
    // file cannot be opened.
    if (app_->Initialize("") != Ipopt::Solve_Succeeded) {
      if (!ipopt.output_file.empty()) {
        throw ModelError("solver.ipopt.output_file",
                         "cannot open \"" + ipopt.output_file + "\" for writing");
      }
      throw std::runtime_error("Ipopt could not be initialised");
    }
  }

  Component& component() override { return newton_->component(); }
  const Component& component() const override { return newton_->component(); }

  StepReport check(State& q) override { return newton_->check(q); }

 protected:
  StepReport minimize(State& q) override {
    StepReport report;
    const Component& c = newton_->component();
    entry_.save(c, q);
    nlp_->begin_step();
    double ipopt_seconds = 0.0;  // Ipopt's wall time, less our evaluations within it
    double test_assembly_seconds = 0.0, test_solve_seconds = 0.0;
    int test_assemblies = 0;
    auto finish = [&](StepStatus status, std::string message) {
      report.status = status;
      report.message = std::move(message);
      report.assemblies = nlp_->assemblies() + test_assemblies;
      report.first_gradient_norm = nlp_->first_gradient_norm();
      report.second_gradient_norm = nlp_->second_gradient_norm();
      if (options_.measure_time) {
        report.assembly_seconds = nlp_->evaluation_seconds() + test_assembly_seconds;
        report.solve_seconds = ipopt_seconds + test_solve_seconds;
      }
      nlp_->leave();
      if (!report.state_updated()) entry_.restore(c, q);
      return report;
    };

    for (int solves = 1;; ++solves) {
      const std::string which = "Ipopt solve " + std::to_string(solves);
      nlp_->start(q);
      if (!nlp_->assemble_start()) {
        return finish(StepStatus::kNonFinite,
                      "Psi, its gradient or Hessian is not finite at the start of " + which);
      }
      set_integer("max_iter", options_.max_iterations - report.iterations);
      const double evaluation_before = nlp_->evaluation_seconds();
      const auto t0 = options_.measure_time ? Clock::now() : Clock::time_point{};
      Ipopt::ApplicationReturnStatus status;
      {
        const std::lock_guard<std::recursive_mutex> lock(ipopt_mutex());
        status = optimized_ ? app_->ReOptimizeTNLP(tnlp_) : app_->OptimizeTNLP(tnlp_);
      }
      optimized_ = true;
      if (options_.measure_time) {
        ipopt_seconds += seconds_since(t0) - (nlp_->evaluation_seconds() - evaluation_before);
      }
      report.iterations += nlp_->iterations();
      if (nlp_->hessian_order_broken()) {
        return finish(StepStatus::kSolverFailed,
                      std::string("Ipopt: ") + ipopt_status_name(status) +
                          "; the potential's Hessian blocks came in another order than at "
                          "the first assembly");
      }
      if (!usable(status) || !nlp_->write_final()) {
        return finish(StepStatus::kSolverFailed,
                      std::string("Ipopt: ") + ipopt_status_name(status) + " in " + which + " after " +
                          std::to_string(nlp_->iterations()) + " iterations");
      }

      const StepReport test = newton_->check(q);
      ++test_assemblies;
      test_assembly_seconds += test.assembly_seconds;
      test_solve_seconds += test.solve_seconds;
      report.factorizations += test.factorizations;
      report.gradient_norm = test.gradient_norm;
      report.step_norm = test.step_norm;
      report.psi = test.psi;
      if (test.status == StepStatus::kNonFinite) {
        return finish(StepStatus::kNonFinite,
                      std::string("Ipopt: ") + ipopt_status_name(status) + " in " + which +
                          ", but Psi, g or H is not finite at its final point");
      }
      if (test.converged()) return finish(StepStatus::kConverged, "");
      if (solves > options_.ipopt.max_recentrings || report.iterations >= options_.max_iterations) {
        // With iterations left, Ipopt stopped on its own (a search direction too small, its
        // tolerance met in a chart where ours is not) as often as it was re-centred: stalled.
        return finish(report.iterations >= options_.max_iterations ? StepStatus::kMaxIterations
                                                                   : StepStatus::kStalled,
                      std::string("Ipopt: ") + ipopt_status_name(status) + " in " + which + ", " +
                          std::to_string(report.iterations) +
                          " iterations in all; Newton step at the final state " +
                          short_number(test.step_norm) + " > tolerance");
      }
    }
  }

 private:
  void set_integer(const char* name, int value) {
    if (!app_->Options()->SetIntegerValue(name, value)) invalid(name);
  }
  void set_numeric(const char* name, double value) {
    if (!app_->Options()->SetNumericValue(name, value)) invalid(name);
  }
  void set_string(const char* name, const std::string& value) {
    if (!app_->Options()->SetStringValue(name, value)) invalid(name);
  }
  [[noreturn]] static void invalid(const char* name) {
    throw std::logic_error(std::string("Ipopt rejected the value of its option ") + name);
  }

  SolverOptions options_;
  bool optimized_ = false;
  std::unique_ptr<StepSolver> newton_;  // the shared test; owns the component
  StepNlp* nlp_ = nullptr;              // owned by tnlp_
  Ipopt::SmartPtr<Ipopt::TNLP> tnlp_;
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app_;
  ComponentSnapshot entry_;
};

}  // namespace

std::unique_ptr<StepSolver> make_ipopt_step_solver(Component component,
                                                   const SolverOptions& options) {
  return std::make_unique<IpoptStepSolver>(std::move(component), options);
}

}  // namespace liedyn

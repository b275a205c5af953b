#pragma once
// The rotation-vector chart of a component: every rotation is R = exp(r) R_ref, with a fixed
// reference R_ref per rotation (the identity unless set_reference says otherwise: the global
// rotation vectors of a Newton solve; Ipopt's tangent increments use R_ref = R at the start,
// solvers/ipopt_step.hpp, and so does the public Ipopt adapter, manifolds/lie_ipopt.hpp, over
// any tangent layout). Since exp(r + dr) = exp(J_l(r) dr) exp(r), R_ref changes nothing
// below. Assembly turns the Lie gradient and Hessian that the terms provide into the
// derivatives with respect to the r's (manifolds/rotation_vector.hpp):
//   g_r = J_l(r)ᵀ g,   H_rr' = J_l(r)ᵀ H_rr' J_l(r')  (+ C(r, g) on the diagonal),
//   H_xr = H_xr J_l(r)  for a position x.
// Each 3×3 block is transformed on its way to the linear system's sink (ChartSink), so the
// same scatter, pattern and factorisation serve every parameterisation; C is added once per
// rotation after the terms, from the rotation's total Lie gradient.

#include <vector>

#include "../lib/incremental_potential.hpp"
#include "rotation_vector.hpp"

namespace liedyn {

class RotationVectorChart {
 public:
  RotationVectorChart() = default;
  // Rotation i's 3 entries at offsets[i] (a multiple of 3) of a tangent vector of `size`.
  RotationVectorChart(std::vector<int> offsets, int size)
      : offsets_(std::move(offsets)),
        r_(offsets_.size(), Vector3::Zero()),
        J_(offsets_.size(), Matrix3::Identity()),
        reference_(offsets_.size(), Matrix3::Identity()),
        rotation_of_block_((size + 2) / 3, -1) {
    for (std::size_t i = 0; i < offsets_.size(); ++i) {
      rotation_of_block_[offsets_[i] / 3] = static_cast<int>(i);
    }
  }
  explicit RotationVectorChart(const Component& component)
      : RotationVectorChart(rotation_offsets(component), component.dofs) {}

  // Sets rotation i's vector and returns exp(r) R_ref.
  Matrix3 set(std::size_t i, const Vector3& r) {
    r_[i] = r;
    return so3::exp(r, &J_[i]) * reference_[i];
  }
  const Vector3& r(std::size_t i) const { return r_[i]; }
  const Matrix3& jacobian(std::size_t i) const { return J_[i]; }  // J_l(r_i)
  // Re-centres rotation i on R: R_ref = R, r = 0 (so J_l = I).
  void set_reference(std::size_t i, const Matrix3& R) {
    reference_[i] = R;
    r_[i].setZero();
    J_[i].setIdentity();
  }
  std::size_t size() const { return r_.size(); }

  // Keeps the current r's and J_l(r)'s / returns to them (Newton's line search backtracking:
  // the rotations themselves are restored by the caller, so nothing is recomputed here).
  void save() {
    saved_r_ = r_;  // same sizes: no allocation after the first save
    saved_J_ = J_;
  }
  void restore() {
    r_ = saved_r_;
    J_ = saved_J_;
  }

  // J_l(r) of the rotation whose DOFs start at `offset`, or null for a position.
  const Matrix3* jacobian_at(int offset) const {
    const int i = rotation_of_block_[offset / 3];
    return i < 0 ? nullptr : &J_[i];
  }

  // After the terms: adds C(r, g) to each rotation's diagonal block (through `sink`, the
  // system's own sink, so that a pattern recorded once sees these blocks too) and replaces g's
  // rotation entries by J_l(r)ᵀ g.
  template <class Vector, class Sink>
  void finish(Vector& g, Sink& sink) const {
    add_corrections(g, sink);
    to_chart_gradient(g);
  }
  // The two halves of finish: C(r, g) from a Lie gradient g (e.g. a Lagrangian's) into
  // `sink`, and g's rotation entries ← J_l(r)ᵀ g.
  template <class Vector, class Sink>
  void add_corrections(const Vector& g, Sink& sink) const {
    for (std::size_t i = 0; i < offsets_.size(); ++i) {
      const int o = offsets_[i];
      sink.add(o, o, rotvec::hessian_correction(r_[i], g.template segment<3>(o)));
    }
  }
  template <class Vector>
  void to_chart_gradient(Vector& g) const {
    for (std::size_t i = 0; i < offsets_.size(); ++i) {
      const int o = offsets_[i];
      g.template segment<3>(o) = (J_[i].transpose() * g.template segment<3>(o)).eval();
    }
  }

 private:
  static std::vector<int> rotation_offsets(const Component& component) {
    std::vector<int> offsets;
    for (const DofBlock& b : component.rotations) offsets.push_back(b.offset);
    return offsets;
  }

  std::vector<int> offsets_;            // per rotation, in the tangent vector
  std::vector<Vector3> r_;              // per rotation
  std::vector<Matrix3> J_;              // per rotation: J_l(r)
  std::vector<Matrix3> reference_;      // per rotation: R_ref
  std::vector<int> rotation_of_block_;  // per 3-DOF block: its rotation, or −1 (a position)
  std::vector<Vector3> saved_r_;        // save() / restore()
  std::vector<Matrix3> saved_J_;
};

// Passes each Hessian block to `sink` as Jᵀ_row block J_column (identity for positions).
template <class Sink>
struct ChartSink {
  Sink& sink;
  const RotationVectorChart& chart;
  void clear() { sink.clear(); }
  template <class Block>
  void add(int row, int column, const Block& block) {
    const Matrix3* J_row = chart.jacobian_at(row);
    const Matrix3* J_column = chart.jacobian_at(column);
    if (J_row == nullptr && J_column == nullptr) {
      sink.add(row, column, block);
      return;
    }
    Matrix3 b = block;
    if (J_row != nullptr) b = J_row->transpose() * b;
    if (J_column != nullptr) b = b * *J_column;
    sink.add(row, column, b);
  }
};

// Calls assemble(s) with s = `sink` itself, or `sink` behind the chart's ChartSink when
// `chart` is non-null; returns what it returns. (The caller still owes chart->finish.)
template <class Sink, class Assemble>
double through_chart(Sink& sink, const RotationVectorChart* chart, Assemble&& assemble) {
  if (chart == nullptr) return assemble(sink);
  ChartSink<Sink> charted{sink, *chart};
  return assemble(charted);
}

// IncrementalPotential::assemble_into, in the chart's coordinates when `chart` is non-null.
template <class Vector, class Sink>
double assemble_charted(const IncrementalPotential& potential, const State& q, Vector& g,
                        Sink& sink, double* roundoff, const RotationVectorChart* chart) {
  const double value = through_chart(
      sink, chart, [&](auto& s) { return potential.assemble_into(q, g, s, roundoff); });
  if (chart != nullptr) chart->finish(g, sink);
  return value;
}

}  // namespace liedyn

#pragma once
// A recorded forward simulation, for objectives and the adjoint pass (paper §5).
// Memory: the states only (one State per frame: 3 doubles per point, 9 per rotation, about
// 16 KB per frame for a 171-node rod, 160 MB for 10⁴ frames); the steps Δq_k, k ≥ 1, are
// recomputed from consecutive states exactly as the simulator computes them.

#include <vector>

#include "so3.hpp"
#include "state.hpp"

namespace liedyn {

// ΔR_k = R_k R_{k−1}ᵀ (eq. 6), re-orthonormalised: the one formula of the simulator's steps
// and the adjoint's recomputed ones, so that both agree bit for bit.
inline Matrix3 rotation_step(const Matrix3& R, const Matrix3& R_previous) {
  return so3::orthonormalize(R * R_previous.transpose());
}

struct Trajectory {
  double time_step = 0.0;
  bool static_equilibrium = false;  // load steps: every Δq is zero (Model::static_equilibrium)
  std::vector<State> states;        // q_0 … q_n
  Step initial_step;                // Δq_0
  // Exact joints: per frame k (index k, empty at 0), the multiplier λ of every exact
  // constraint term at the converged q_k, over the components of step k in build_components
  // order and within each in term order (IncrementalPotential::exact_forces). Empty without
  // any.
  std::vector<std::vector<Vector3>> multipliers;
  // Per frame k (index k, empty at 0): the couplings that held in step k (Model::coupling_key:
  // its joints, and its bodies in contact), the key of its islands for the backward pass.
  std::vector<std::vector<bool>> couplings;

  int frames() const { return static_cast<int>(states.size()) - 1; }

  // Δq_k: Δq_0 as recorded; for k ≥ 1, Δx_k = x_k − x_{k−1}, ΔR_k = R_k R_{k−1}ᵀ
  // (orthonormalised, as in Simulator::step); zero in static mode.
  Step step(int k) const {
    if (k == 0) return initial_step;
    const State& q = states[k];
    const State& p = states[k - 1];
    Step dq;
    dq.points.resize(q.points.size(), Vector3::Zero());
    dq.rotations.resize(q.rotations.size(), Matrix3::Identity());
    if (static_equilibrium) return dq;
    for (std::size_t i = 0; i < q.points.size(); ++i) dq.points[i] = q.points[i] - p.points[i];
    for (std::size_t i = 0; i < q.rotations.size(); ++i) {
      dq.rotations[i] = rotation_step(q.rotations[i], p.rotations[i]);
    }
    return dq;
  }
};

}  // namespace liedyn

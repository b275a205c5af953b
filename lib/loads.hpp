#pragma once
// External loads as potentials: gravity, constant forces at attached points, constant
// world torques. Values, Lie gradients and Lie Hessians per term (conventions: so3.hpp).
// Each load is multiplied by `scale` (1 in dynamics; the load factor λ = k/N of load step k
// in static mode), which enters value, gradient and Hessian linearly.

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// Gravity on a point mass: V = −m g·x;  ∇V = −m g,  ∇²V = 0.
struct Gravity {
  static constexpr int kBlocks = 1;
  static constexpr const char* kName = "gravity";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1};
  int point = -1;
  Vector3 weight = Vector3::Zero();  // m g
  double scale = 1.0;

  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;
  // PointLoad (term.hpp).
  bool point_load(int& on, Vector3& force) const {
    on = point;
    force = scale * weight;
    return true;
  }
};

// A constant world force F applied at p = x + R p̄ (blocks: x, θ). V = −F·p, so with
// f = ∂V/∂p = −F (eqs. 22, 23):
//   ∂V/∂x = −F,   DV/DR = r × f = −r × F (minus the torque),   D²V/DR² = ½(f rᵀ + r fᵀ) − (f·r) I.
struct ConstantForce {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "force";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1};
  AttachedPoint at;
  Vector3 force = Vector3::Zero();
  double scale = 1.0;
  ScheduledParameter<3> control;  // per-step force F and its slot in γ (term.hpp)

  // Step k's force from the schedule (kept constant without one).
  void begin_frame(int k) { force = control.at(k, force); }
  bool scheduled() const { return !control.schedule.empty(); }
  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;
  // PointLoad (term.hpp): only a force on a point without rotation (a rod node) has no lever.
  bool point_load(int& on, Vector3& load) const {
    on = at.point;
    load = scale * force;
    return at.rotation < 0 && at.point >= 0;
  }
  // For the adjoint: ∂(Lie gradient)/∂F = −scale [I; hat(r)] (the gradient is linear in F).
  Eigen::Matrix<double, 6, 3> force_jacobian(const State& q) const;
  // HasParameters (term.hpp): adds (∂C/∂γ)ᵀ z for step `frame`.
  void add_parameter_adjoint(const State& q, int frame, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const;
};

// A constant world torque τ on a rotation. A constant world torque has no potential on
// SO(3), so each step uses the incremental potential
//   V(R) = −τ · vee(P),   P = R R_{k−1}ᵀ,   vee(P) = sin φ n for P = exp(φ n),
// whose Lie gradient is exactly −τ at P = I and −τ + O(φ) over the step (first order, like
// backward Euler itself):
//   DV/DR = −½ (tr(P) I − P)ᵀ τ,
//   D²V/DR² = ¼ (P hat(τ) − hat(τ) Pᵀ) − ½ tr(hat(τ) P) I.
// Derived by substituting exp(θ) ≈ I + hat(θ) + ½hat(θ)² (paper §3.2); FD-checked in tests.
// torque_potential evaluates V, its gradient and Hessian for given P and τ (also the torque
// fields of the trapezoidal integrator, lib/history.hpp).
double torque_potential(const Matrix3& P, const Vector3& tau, LocalGradient<1>* g,
                        LocalHessian<1>* H);

struct ConstantTorque {
  static constexpr int kBlocks = 1;
  static constexpr const char* kName = "torque";
  std::array<int, kBlocks> offsets{-1};
  int rotation = -1;
  Vector3 torque = Vector3::Zero();
  double scale = 1.0;
  Matrix3 R_previous = Matrix3::Identity();
  ScheduledParameter<3> control;  // per-step torque τ and its slot in γ (term.hpp)

  void begin_step(const State& previous, const Step& previous_step);
  void begin_frame(int k) { torque = control.at(k, torque); }
  bool scheduled() const { return !control.schedule.empty(); }
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;

  // For the adjoint (C = the Lie gradient above, linear in τ; P = R R_{k−1}ᵀ):
  //   ∂C/∂τ = −½ scale (tr(P) I − Pᵀ),
  //   ∂C/∂φ for R_{k−1} → exp(φ) R_{k−1}:  P → P − P hat(φ) + O(φ²), and with
  //   tr(P hat(φ)) = −2 vee(P)·φ,   ∂C/∂φ = −(τ vee(P)ᵀ + ½ hat(Pᵀτ))   (τ scaled).
  Matrix3 torque_jacobian(const State& q) const;
  Matrix3 previous_jacobian(const State& q) const;
  // ReadsPreviousStep (term.hpp): adds (∂C/∂q_{k−1})ᵀ z and (∂C/∂Δq_{k−1})ᵀ z.
  void add_step_adjoint(const State& q, const State& previous, const Step& previous_step,
                        const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                        Eigen::VectorXd& da_previous) const;
  // HasParameters (term.hpp): adds (∂C/∂γ)ᵀ z for step `frame`.
  void add_parameter_adjoint(const State& q, int frame, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const;
};

// A push on a point while it is inside a region (the endoscope of paper §7.2, driven by
// forces on the nodes inside an entry region): V = −a F·x, with a = 1 if the point was
// within `radius` of `center` at the start of the step (lagged, like friction), else 0.
//   ∂V/∂x = −a F,   ∂²V/∂x² = 0.
// a is piecewise constant in q_{k−1}: the adjoint has no mixed block for it (its derivative
// vanishes wherever it exists; a point exactly on the region's boundary is measure zero).
struct RegionForce {
  static constexpr int kBlocks = 1;
  static constexpr const char* kName = "region_force";
  std::array<int, kBlocks> offsets{-1};
  int point = -1;
  Vector3 force = Vector3::Zero();
  Vector3 center = Vector3::Zero();
  double radius = 0.0;
  double scale = 1.0;
  bool active = false;  // a, set by begin_step

  void begin_step(const State& previous, const Step& previous_step);
  double evaluate(const State& q, LocalGradient<1>* g, LocalHessian<1>* H) const;
};

}  // namespace liedyn

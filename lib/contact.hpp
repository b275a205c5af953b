#pragma once
// Penalty contact of a sample point with a static collider (paper §7.1–7.3; SDFs: sdf.hpp).
//
// A sample is a point p = x + R p̄ attached to a rigid body (blocks x, θ) or a rod node
// p = x (block x only; the θ block is then not a DOF, offset −1). With the sample's radius
// ρ and the collider's signed distance φ, the penetration is d = ρ − φ(p) and
//   V = ½ k max(0, d)²                                 (quadratic penalty, as in the paper).
// With n = ∇φ(p), N = ∇²φ(p), and d > 0:
//   f = ∂V/∂p = −k d n,       K = ∂²V/∂p² = k (n nᵀ − d N).
// K is indefinite where the surface curves towards the sample (−k d N for a convex collider
// has negative eigenvalues of size k d/radius of curvature): exact, and regularised by the
// Newton solver like every indefinite Hessian (solvers/newton.hpp). At d ≤ 0 everything is
// zero: V is C¹ with a jump of K at d = 0, which Newton's line search handles.
//
// Through p = x + r, r = R p̄ (eqs. 22, 23), mapped to the blocks (x, θ) by
// attached_point_derivatives (point_pair.hpp).
//
// Least-squares form (contract: term.hpp), 1 residual:
//   r = √k max(0, d),   J = ∂r/∂(x, θ) = −√k [nᵀ, (r × n)ᵀ] where d > 0, else 0;
// ½ r² = V and Jᵀ r = the gradient above.
//
// The term reads q_k only: the adjoint needs no mixed block for it (its Hessian enters H_k).
// Colliders are static, so a sample's stencil is its own body's or node's blocks, which the
// inertia already puts in the pattern: contacts that come and go never change the sparsity.

#include <memory>
#include <string>
#include <vector>

#include "sdf.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// What a body's or rod's contact samples are made of (scene: "contact", docs/scene-format.md).
struct ContactMaterial {
  double stiffness = 0.0;          // k, N/m, > 0 to enable contact
  double radius = 0.0;             // ρ, m, ≥ 0: the sample's sphere (a rod node: the rod radius)
  double friction = 0.0;           // μ, ≥ 0 (0: frictionless)
  double friction_velocity = 1e-3; // ε_v, m/s, > 0: the smoothed Coulomb law's stick–slip
                                   // transition speed (friction.hpp); sticking creeps below it
  double damping = 0.0;            // c, N·s/m, ≥ 0: dashpot on the normal approach velocity
                                   // against colliders (contact_damping.hpp; 0: none)
  // What it touches, by name (bodies, colliders): everything by default, only those in
  // collides_with when it is given, never those in ignores (one of the two at most).
  std::vector<std::string> collides_with;
  std::vector<std::string> ignores;
  bool enabled() const { return stiffness > 0.0; }
  bool touches(const std::string& name) const;
};

// What a contact term and its friction term share: a sample, a sphere of radius ρ attached
// at `at`, pressed into `collider` with stiffness k.
struct ContactSample {
  std::array<int, 2> offsets{-1, -1};  // x, θ
  AttachedPoint at;
  std::shared_ptr<const Collider> collider;
  double stiffness = 0.0;  // k
  double radius = 0.0;     // ρ

  // ρ − φ(p): > 0 when the sample's sphere overlaps the collider.
  double penetration(const State& q) const;

  // For the lagged terms (friction, damping) whose force f on the sample's point depends on its
  // previous position p̂ = x̂ + R̂ p̄: the 6×6 block ∂C/∂(x̂, θ̂) of their local gradient
  // C = (f, r × f) from ∂f/∂p̂ (∂p̂/∂(x̂, θ̂) = [I, −hat(r̂)]), and its transpose times z added
  // to the adjoint of q_{k−1} at the sample's point and rotation.
  // What the lagged terms (friction, damping) freeze at the start of a step: the sample's
  // previous position p̂, its penetration ρ − φ(p̂) and the unit normal ∇φ(p̂)/‖∇φ(p̂)‖ (e_z
  // where ∇φ vanishes).
  struct Lagged {
    Vector3 position;
    double penetration;
    Vector3 normal;
  };
  Lagged lag(const State& previous) const;
  // ∂n/∂p̂ = P ∇²φ(p̂)/‖∇φ(p̂)‖ of the lagged unit normal n = ∇φ(p̂)/‖∇φ(p̂)‖ (P = I − n nᵀ;
  // 0 where ∇φ vanishes); `lagged` receives φ's value and derivatives at p̂.
  Matrix3 normal_jacobian(const Vector3& previous_position, const Vector3& normal,
                          SdfValue& lagged) const;
  Eigen::Matrix<double, 6, 6> previous_block(const State& q, const State& previous,
                                             const Matrix3& df_dprevious) const;
  void add_previous_adjoint(const State& q, const Eigen::Matrix<double, 6, 6>& block,
                            const LocalGradient<2>& z, Eigen::VectorXd& a_previous) const;
};

struct Contact : ContactSample {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "contact";
  static constexpr bool kEnergyOfState = true;

  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;

  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

}  // namespace liedyn

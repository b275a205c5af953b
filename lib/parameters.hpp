#pragma once
// The parameters γ of a trajectory optimisation (paper §5, §7.3–7.4): which numbers of a
// Model are free, their place in the vector γ, writing γ into a Model, and the part of the
// gradient that comes through the initial state and step,
//   dg/dγ ⊇ (∂q_0/∂γ)ᵀ a_0 + (∂Δq_0/∂γ)ᵀ Δa_0   (docs/design.md §8.4).
// Parameters that enter the incremental potential (forces, torques, tensions, rest shape,
// stiffnesses) are handed to the terms as slots (lib/term.hpp), and their gradient
// (∂C_k/∂γ)ᵀ z_k is summed by IncrementalPotential::add_parameter_adjoint.
//
// Kinds, and their size per block (h the time step, n the number of frames):
//   body_linear_velocity     3       v_0 of a body: Δx_0 = h v_0
//   body_angular_velocity    3       ω_0 (world): ΔR_0 = exp(h ω_0), ∂/∂ω_0 = h J_l(h ω_0)
//   body_position            3       x_0
//   body_orientation         3       ε with R_0 = exp(ε) R_scene (γ starts at 0): ∂/∂ε = J_l(ε)
//   rod_node_velocities      3·free  v_0 of each free node of a rod, in node order: Δx_0 = h v_0
//                                    (clamped nodes keep their prescribed state: not in γ;
//                                    describe names each entry by its node's own index)
//   force, torque            3·n     per-step world force (at a body point) / torque
//   node_force               3·n     per-step world force on a rod node (rods[r].node_forces[j])
//   cable_tension            n       per-step tension of a rod's cable (rods[r].cables[c])
//   joint_motor              n       per-step torque (hinge) or force (slider) of joints[i].motor
//   rest_darboux             3·(nodes−2)      static rest Darboux vectors of a rod
//   rest_darboux_per_frame   3·(nodes−2)·n    per-step rest Darboux vectors (frame-major)
//   spring_stiffness, stretch_stiffness, shear_stiffness   1
//   bending_stiffness        3       (K₁, K₂, K₃)
//
// Bounds. Each block may carry box bounds lower ≤ γ_i ≤ upper on all its entries (a cable
// pulls: tension ≥ 0; a stiffness stays positive); ±∞ means none. They are the optimiser's
// business (solvers/optimizer.hpp); the simulation itself is defined outside them.

#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model.hpp"

namespace liedyn {

enum class ParameterKind {
  kBodyLinearVelocity,
  kBodyAngularVelocity,
  kBodyPosition,
  kBodyOrientation,
  kRodNodeVelocities,
  kForce,
  kTorque,
  kNodeForce,
  kCableTension,
  kJointMotor,
  kRestDarboux,
  kRestDarbouxPerFrame,
  kSpringStiffness,
  kStretchStiffness,
  kShearStiffness,
  kBendingStiffness,
};

const char* to_string(ParameterKind kind);
std::optional<ParameterKind> parse_parameter_kind(std::string_view name);

struct ParameterBlock {
  ParameterKind kind;
  int index = 0;  // body, forces[]/torques[]/springs[]/joints[] entry, or rod
  int sub = -1;   // node_force / cable_tension: its index in rods[index].node_forces / cables
  int offset = 0;
  int size = 0;
  double lower = -std::numeric_limits<double>::infinity();  // bounds on every entry
  double upper = std::numeric_limits<double>::infinity();
};

class ParameterSet {
 public:
  // `frames`: the number of steps simulated (sizes the per-step kinds).
  explicit ParameterSet(int frames) : frames_(frames) {}

  // Most numbers γ may hold (80 MB a vector): per-step kinds grow with frames and rod nodes.
  static constexpr int kMaxSize = 10000000;

  // Appends a block; throws ModelError naming `field` (e.g. "optimization.parameters[2]")
  // when the block repeats one already added, γ would exceed kMaxSize or a rod's node
  // velocities are asked for when every node of the rod is clamped, and the key of an
  // index that does not exist in the model (`field`.index for forces, torques, springs and
  // joints — a joint must have a motor —, .node_force, .cable).
  void add(const Model& model, ParameterKind kind, int index, int sub, const std::string& field);

  // Bounds of the last block added; throws ModelError naming `field` unless lower < upper
  // and neither is NaN (±∞: unbounded on that side).
  void set_bounds(double lower, double upper, const std::string& field);

  int size() const { return size_; }
  // Whether any block has a finite bound, and the bounds entry by entry (size()).
  bool bounded() const;
  Eigen::VectorXd lower_bounds() const;
  Eigen::VectorXd upper_bounds() const;
  int frames() const { return frames_; }
  const std::vector<ParameterBlock>& blocks() const { return blocks_; }
  // e.g. "bodies[0].angular_velocity[2]", "forces[1].frame[17][0]" (for reports).
  std::string describe(const Model& model, int i) const;

  // γ as the model states it (per-step values: the constant repeated; orientation: 0).
  Eigen::VectorXd initial_values(const Model& model) const;
  // A copy of `base` with γ written in, and the slots of the potential's parameters set.
  Model apply(const Model& base, const Eigen::VectorXd& gamma) const;
  // dgamma += (∂q_0/∂γ)ᵀ a_0 + (∂Δq_0/∂γ)ᵀ Δa_0 (whole-state tangent layout).
  void add_initial_gradient(const Model& applied, const Eigen::VectorXd& gamma,
                            const Eigen::VectorXd& a0, const Eigen::VectorXd& da0,
                            Eigen::VectorXd& dgamma) const;

 private:
  long long block_size(const Model& model, ParameterKind kind, int index) const;
  int frames_;
  int size_ = 0;
  std::vector<ParameterBlock> blocks_;
};

}  // namespace liedyn

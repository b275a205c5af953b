#include "parameters.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "so3.hpp"
#include "trajectory.hpp"

namespace liedyn {

namespace {

struct KindName {
  ParameterKind kind;
  const char* name;
};
constexpr std::array<KindName, 16> kKindNames{{
    {ParameterKind::kBodyLinearVelocity, "body_linear_velocity"},
    {ParameterKind::kBodyAngularVelocity, "body_angular_velocity"},
    {ParameterKind::kBodyPosition, "body_position"},
    {ParameterKind::kBodyOrientation, "body_orientation"},
    {ParameterKind::kRodNodeVelocities, "rod_node_velocities"},
    {ParameterKind::kForce, "force"},
    {ParameterKind::kTorque, "torque"},
    {ParameterKind::kNodeForce, "node_force"},
    {ParameterKind::kCableTension, "cable_tension"},
    {ParameterKind::kJointMotor, "joint_motor"},
    {ParameterKind::kRestDarboux, "rest_darboux"},
    {ParameterKind::kRestDarbouxPerFrame, "rest_darboux_per_frame"},
    {ParameterKind::kSpringStiffness, "spring_stiffness"},
    {ParameterKind::kStretchStiffness, "stretch_stiffness"},
    {ParameterKind::kShearStiffness, "shear_stiffness"},
    {ParameterKind::kBendingStiffness, "bending_stiffness"},
}};

bool on_body(ParameterKind k) {
  return k == ParameterKind::kBodyLinearVelocity || k == ParameterKind::kBodyAngularVelocity ||
         k == ParameterKind::kBodyPosition || k == ParameterKind::kBodyOrientation;
}
bool on_rod(ParameterKind k) {
  return k == ParameterKind::kRodNodeVelocities || k == ParameterKind::kNodeForce ||
         k == ParameterKind::kCableTension ||
         k == ParameterKind::kRestDarboux || k == ParameterKind::kRestDarbouxPerFrame ||
         k == ParameterKind::kStretchStiffness || k == ParameterKind::kShearStiffness ||
         k == ParameterKind::kBendingStiffness;
}

// A per-step schedule of `frames` values read from γ at `slot` (stride 3), and its slot.
ScheduledParameter<3> schedule_from(const Eigen::VectorXd& gamma, int slot, int frames) {
  ScheduledParameter<3> s;
  s.slot = slot;
  s.stride = 3;
  s.schedule.resize(frames);
  for (int k = 0; k < frames; ++k) s.schedule[k] = gamma.segment<3>(slot + 3 * k);
  return s;
}

// The same for one number per step (stride 1).
ScheduledParameter<1> scalar_schedule_from(const Eigen::VectorXd& gamma, int slot, int frames) {
  ScheduledParameter<1> s;
  s.slot = slot;
  s.stride = 1;
  s.schedule.resize(frames);
  for (int k = 0; k < frames; ++k) s.schedule[k](0) = gamma(slot + k);
  return s;
}

// The nodes of a rod that are not clamped, in increasing order: the nodes of a
// rod_node_velocities block (a clamped node keeps its prescribed state, so it has no initial
// velocity to choose). Clamped indices out of range are left to Model::validate_rod.
std::vector<int> free_nodes(const RodSpec& rod) {
  std::vector<bool> clamped(rod.node_count(), false);
  for (int i : rod.fixed_nodes) {
    if (i >= 0 && i < rod.node_count()) clamped[i] = true;
  }
  std::vector<int> nodes;
  for (int i = 0; i < rod.node_count(); ++i) {
    if (!clamped[i]) nodes.push_back(i);
  }
  return nodes;
}

// "[i]" (appended piecewise: GCC 12 warns falsely (-Wrestrict) on "[" + std::to_string(i)).
std::string bracket(int i) {
  std::string s = "[";
  s += std::to_string(i);
  s += ']';
  return s;
}

}  // namespace

const char* to_string(ParameterKind kind) {
  for (const KindName& k : kKindNames) {
    if (k.kind == kind) return k.name;
  }
  return "?";
}

std::optional<ParameterKind> parse_parameter_kind(std::string_view name) {
  for (const KindName& k : kKindNames) {
    if (name == k.name) return k.kind;
  }
  return std::nullopt;
}

long long ParameterSet::block_size(const Model& model, ParameterKind kind, int index) const {
  const long long frames = frames_, nodes = on_rod(kind) ? model.rods[index].node_count() : 0;
  switch (kind) {
    case ParameterKind::kBodyLinearVelocity:
    case ParameterKind::kBodyAngularVelocity:
    case ParameterKind::kBodyPosition:
    case ParameterKind::kBodyOrientation:
    case ParameterKind::kBendingStiffness:
      return 3;
    case ParameterKind::kRodNodeVelocities:
      return 3 * static_cast<long long>(free_nodes(model.rods[index]).size());
    case ParameterKind::kForce:
    case ParameterKind::kTorque:
    case ParameterKind::kNodeForce:
      return 3 * frames;
    case ParameterKind::kCableTension:
    case ParameterKind::kJointMotor:
      return frames;
    case ParameterKind::kRestDarboux:
      return 3 * (nodes - 2);
    case ParameterKind::kRestDarbouxPerFrame:
      return 3 * (nodes - 2) * frames;
    case ParameterKind::kSpringStiffness:
    case ParameterKind::kStretchStiffness:
    case ParameterKind::kShearStiffness:
      return 1;
  }
  return 0;
}

void ParameterSet::add(const Model& model, ParameterKind kind, int index, int sub,
                       const std::string& field) {
  const auto out_of_range = [&](const char* what, std::size_t count) {
    // Forces, torques and springs are chosen by "index"; bodies and rods by name (resolved
    // by the caller), so an index of theirs is the caller's error, reported at the block.
    const bool by_index = kind == ParameterKind::kForce || kind == ParameterKind::kTorque ||
                          kind == ParameterKind::kSpringStiffness ||
                          kind == ParameterKind::kJointMotor;
    throw ModelError(by_index ? field + ".index" : field,
                     std::string("refers to ") + what + " " + std::to_string(index) +
                         ", but the model has " + std::to_string(count));
  };
  if (on_body(kind) && (index < 0 || index >= static_cast<int>(model.bodies.size()))) {
    out_of_range("body", model.bodies.size());
  }
  if (on_body(kind) && model.bodies[index].kinematic) {
    throw ModelError(field, "\"" + model.bodies[index].name +
                                "\" is kinematic: its motion is given, and its initial state is not a control");
  }
  if (on_rod(kind) && (index < 0 || index >= static_cast<int>(model.rods.size()))) {
    out_of_range("rod", model.rods.size());
  }
  if (kind == ParameterKind::kForce && (index < 0 || index >= static_cast<int>(model.forces.size()))) {
    out_of_range("force", model.forces.size());
  }
  if (kind == ParameterKind::kTorque &&
      (index < 0 || index >= static_cast<int>(model.torques.size()))) {
    out_of_range("torque", model.torques.size());
  }
  if (kind == ParameterKind::kSpringStiffness &&
      (index < 0 || index >= static_cast<int>(model.springs.size()))) {
    out_of_range("spring", model.springs.size());
  }
  if (kind == ParameterKind::kBendingStiffness) {
    for (std::size_t i = 0; i < model.joints.size(); ++i) {
      const JointSpec& j = model.joints[i];
      if (j.type == JointSpec::Type::kSplice && (j.a.object == index || j.b.object == index)) {
        throw ModelError(field, "rod " + std::to_string(index) + " is spliced (joints[" + std::to_string(i) +
                                    "]): the junction's bending, the two rods' mean, is not an optimisation parameter, "
                                    "so the rod's bending stiffness cannot be one either");
      }
    }
  }
  if (kind == ParameterKind::kJointMotor) {
    if (index < 0 || index >= static_cast<int>(model.joints.size())) {
      out_of_range("joint", model.joints.size());
    }
    if (!model.joints[index].has_motor) {
      throw ModelError(field + ".index", "joint " + std::to_string(index) +
                                             " has no motor (give a hinge \"motor\": {\"torque\": …}, a slider \"motor\": {\"force\": …})");
    }
  }
  if (kind == ParameterKind::kNodeForce &&
      (sub < 0 || sub >= static_cast<int>(model.rods[index].node_forces.size()))) {
    throw ModelError(field + ".node_force", "refers to node force " + std::to_string(sub) + " of rod " +
                                std::to_string(index) + ", which has " +
                                std::to_string(model.rods[index].node_forces.size()));
  }
  if (kind == ParameterKind::kCableTension &&
      (sub < 0 || sub >= static_cast<int>(model.rods[index].cables.size()))) {
    throw ModelError(field + ".cable", "refers to cable " + std::to_string(sub) + " of rod " +
                                std::to_string(index) + ", which has " +
                                std::to_string(model.rods[index].cables.size()));
  }
  if ((kind == ParameterKind::kRestDarboux || kind == ParameterKind::kRestDarbouxPerFrame) &&
      model.rods[index].node_count() < 3) {
    throw ModelError(field, "rod " + std::to_string(index) + " has no interior node");
  }
  if (kind == ParameterKind::kRodNodeVelocities && free_nodes(model.rods[index]).empty()) {
    throw ModelError(field, "rod " + std::to_string(index) +
                                " has no free node: every node is clamped (fixed_nodes)");
  }
  if ((kind == ParameterKind::kBodyLinearVelocity || kind == ParameterKind::kBodyAngularVelocity ||
       kind == ParameterKind::kRodNodeVelocities) &&
      model.static_equilibrium) {
    throw ModelError(field, "initial velocities have no effect in static mode");
  }
  const bool per_frame_darboux = kind == ParameterKind::kRestDarbouxPerFrame;
  for (const ParameterBlock& b : blocks_) {
    const bool both_darboux =
        (b.kind == ParameterKind::kRestDarboux || b.kind == ParameterKind::kRestDarbouxPerFrame) &&
        (kind == ParameterKind::kRestDarboux || per_frame_darboux);
    if ((b.kind == kind || both_darboux) && b.index == index && b.sub == sub) {
      throw ModelError(field, std::string("repeats the parameter ") + to_string(kind) + " " +
                                  std::to_string(index));
    }
  }
  // In long long: 3 · (nodes − 2) · frames overflows int long before it is refused here.
  const long long size = block_size(model, kind, index);
  if (size > kMaxSize - size_) {
    throw ModelError(field, "would make γ " + std::to_string(size_ + size) +
                                " numbers long; at most " + std::to_string(kMaxSize) +
                                " are allowed (fewer frames or nodes)");
  }
  ParameterBlock block{kind, index, sub, size_, static_cast<int>(size)};
  blocks_.push_back(block);
  size_ += block.size;
}

std::string ParameterSet::describe(const Model& model, int i) const {
  for (const ParameterBlock& b : blocks_) {
    if (i < b.offset || i >= b.offset + b.size) continue;
    const int j = i - b.offset;
    const std::string axis = bracket(j % 3);
    const std::string rod = "rods" + bracket(b.index);
    const std::string body = "bodies" + bracket(b.index);
    const std::string step = ".frame" + bracket(j / 3 + 1) + axis;
    switch (b.kind) {
      case ParameterKind::kBodyLinearVelocity: return body + ".linear_velocity" + axis;
      case ParameterKind::kBodyAngularVelocity: return body + ".angular_velocity" + axis;
      case ParameterKind::kBodyPosition: return body + ".position" + axis;
      case ParameterKind::kBodyOrientation: return body + ".orientation_increment" + axis;
      case ParameterKind::kRodNodeVelocities:  // named by the node's own index
        return rod + ".node_velocities" + bracket(free_nodes(model.rods[b.index])[j / 3]) + axis;
      case ParameterKind::kForce: return "forces" + bracket(b.index) + step;
      case ParameterKind::kTorque: return "torques" + bracket(b.index) + step;
      case ParameterKind::kNodeForce:
        return rod + ".node_forces" + bracket(b.sub) + step;
      case ParameterKind::kCableTension:
        return rod + ".cables" + bracket(b.sub) + ".tension.frame" + bracket(j + 1);
      case ParameterKind::kJointMotor:
        return "joints" + bracket(b.index) +
               (model.joints[b.index].type == JointSpec::Type::kSlider ? ".motor.force" : ".motor.torque") +
               ".frame" + bracket(j + 1);
      case ParameterKind::kRestDarboux:
        return rod + ".rest_darboux" + bracket(j / 3) + axis;
      case ParameterKind::kRestDarbouxPerFrame: {
        const int interior = model.rods[b.index].node_count() - 2;
        return rod + ".rest_darboux.frame" + bracket(j / (3 * interior) + 1) +
               bracket((j / 3) % interior) + axis;
      }
      case ParameterKind::kSpringStiffness:
        return "springs" + bracket(b.index) + ".stiffness";
      case ParameterKind::kStretchStiffness: return rod + ".stretch_stiffness";
      case ParameterKind::kShearStiffness: return rod + ".shear_stiffness";
      case ParameterKind::kBendingStiffness: return rod + ".bending_stiffness" + axis;
    }
  }
  return "?";
}

void ParameterSet::set_bounds(double lower, double upper, const std::string& field) {
  if (blocks_.empty()) throw ModelError(field, "bounds without a parameter block");
  if (std::isnan(lower) || std::isnan(upper) || !(lower < upper)) {
    std::ostringstream os;
    os << std::setprecision(17) << "the lower bound (" << lower
       << ") must be below the upper bound (" << upper << ")";
    throw ModelError(field, os.str());
  }
  blocks_.back().lower = lower;
  blocks_.back().upper = upper;
}

bool ParameterSet::bounded() const {
  return std::any_of(blocks_.begin(), blocks_.end(), [](const ParameterBlock& b) {
    return std::isfinite(b.lower) || std::isfinite(b.upper);
  });
}

Eigen::VectorXd ParameterSet::lower_bounds() const {
  Eigen::VectorXd lower(size_);
  for (const ParameterBlock& b : blocks_) lower.segment(b.offset, b.size).setConstant(b.lower);
  return lower;
}

Eigen::VectorXd ParameterSet::upper_bounds() const {
  Eigen::VectorXd upper(size_);
  for (const ParameterBlock& b : blocks_) upper.segment(b.offset, b.size).setConstant(b.upper);
  return upper;
}

Eigen::VectorXd ParameterSet::initial_values(const Model& model) const {
  Eigen::VectorXd gamma = Eigen::VectorXd::Zero(size_);
  for (const ParameterBlock& b : blocks_) {
    auto block = gamma.segment(b.offset, b.size);
    const auto repeat = [&](const Vector3& v, int times) {
      for (int k = 0; k < times; ++k) block.segment<3>(3 * k) = v;
    };
    switch (b.kind) {
      case ParameterKind::kBodyLinearVelocity: block = model.bodies[b.index].linear_velocity; break;
      case ParameterKind::kBodyAngularVelocity: block = model.bodies[b.index].angular_velocity; break;
      case ParameterKind::kBodyPosition: block = model.bodies[b.index].position; break;
      case ParameterKind::kBodyOrientation: break;  // ε = 0
      case ParameterKind::kRodNodeVelocities: {
        const RodSpec& rod = model.rods[b.index];
        const std::vector<int> nodes = free_nodes(rod);
        for (std::size_t k = 0; k < nodes.size(); ++k) {
          block.segment<3>(3 * k) =
              rod.node_velocities.empty() ? Vector3::Zero() : rod.node_velocities[nodes[k]];
        }
        break;
      }
      case ParameterKind::kForce: repeat(model.forces[b.index].force, frames_); break;
      case ParameterKind::kTorque: repeat(model.torques[b.index].torque, frames_); break;
      case ParameterKind::kNodeForce:
        repeat(model.rods[b.index].node_forces[b.sub].force, frames_);
        break;
      case ParameterKind::kCableTension:
        block.setConstant(model.rods[b.index].cables[b.sub].tension);
        break;
      case ParameterKind::kJointMotor: block.setConstant(model.joints[b.index].motor_effort); break;
      case ParameterKind::kRestDarboux:
      case ParameterKind::kRestDarbouxPerFrame: {
        const std::vector<Vector3> rest = model.discretize_rod(b.index).rest_darboux;
        const int interior = static_cast<int>(rest.size());
        const int copies = b.kind == ParameterKind::kRestDarboux ? 1 : frames_;
        for (int k = 0; k < copies; ++k) {
          for (int i = 0; i < interior; ++i) block.segment<3>(3 * (k * interior + i)) = rest[i];
        }
        break;
      }
      case ParameterKind::kSpringStiffness: block(0) = model.springs[b.index].stiffness; break;
      case ParameterKind::kStretchStiffness: block(0) = model.rods[b.index].stretch_stiffness; break;
      case ParameterKind::kShearStiffness: block(0) = model.rods[b.index].shear_stiffness; break;
      case ParameterKind::kBendingStiffness: block = model.rods[b.index].bending_stiffness; break;
    }
  }
  return gamma;
}

Model ParameterSet::apply(const Model& base, const Eigen::VectorXd& gamma) const {
  Model m = base;
  for (const ParameterBlock& b : blocks_) {
    const auto block = gamma.segment(b.offset, b.size);
    switch (b.kind) {
      case ParameterKind::kBodyLinearVelocity: m.bodies[b.index].linear_velocity = block; break;
      case ParameterKind::kBodyAngularVelocity: m.bodies[b.index].angular_velocity = block; break;
      case ParameterKind::kBodyPosition: m.bodies[b.index].position = block; break;
      case ParameterKind::kBodyOrientation:
        m.bodies[b.index].orientation =
            so3::orthonormalize(so3::exp(block) * base.bodies[b.index].orientation);
        break;
      case ParameterKind::kRodNodeVelocities: {  // the clamped nodes stay at rest
        RodSpec& rod = m.rods[b.index];
        const std::vector<int> nodes = free_nodes(rod);
        rod.node_velocities.resize(rod.node_count(), Vector3::Zero());
        for (std::size_t k = 0; k < nodes.size(); ++k) {
          rod.node_velocities[nodes[k]] = block.segment<3>(3 * k);
        }
        break;
      }
      case ParameterKind::kForce:
        m.forces[b.index].control = schedule_from(gamma, b.offset, frames_);
        break;
      case ParameterKind::kTorque:
        m.torques[b.index].control = schedule_from(gamma, b.offset, frames_);
        break;
      case ParameterKind::kNodeForce:
        m.rods[b.index].node_forces[b.sub].control = schedule_from(gamma, b.offset, frames_);
        break;
      case ParameterKind::kCableTension:
        m.rods[b.index].cables[b.sub].control = scalar_schedule_from(gamma, b.offset, frames_);
        break;
      case ParameterKind::kJointMotor:
        m.joints[b.index].motor = scalar_schedule_from(gamma, b.offset, frames_);
        break;
      case ParameterKind::kRestDarboux:
      case ParameterKind::kRestDarbouxPerFrame: {
        RodSpec& rod = m.rods[b.index];
        const int interior = rod.node_count() - 2;
        const bool per_frame = b.kind == ParameterKind::kRestDarbouxPerFrame;
        rod.rest_darboux.resize(interior);
        rod.rest_darboux_controls.assign(interior, ScheduledParameter<3>{});
        for (int i = 0; i < interior; ++i) {
          rod.rest_darboux[i] = block.segment<3>(3 * i);  // per frame: frame 1's (and ω̄ before)
          ScheduledParameter<3>& c = rod.rest_darboux_controls[i];
          c.slot = b.offset + 3 * i;
          if (!per_frame) continue;
          c.stride = 3 * interior;
          c.schedule.resize(frames_);
          for (int k = 0; k < frames_; ++k) c.schedule[k] = block.segment<3>(3 * (k * interior + i));
        }
        break;
      }
      case ParameterKind::kSpringStiffness:
        m.springs[b.index].stiffness = block(0);
        m.springs[b.index].stiffness_slot = b.offset;
        break;
      case ParameterKind::kStretchStiffness:
        m.rods[b.index].stretch_stiffness = block(0);
        m.rods[b.index].stretch_stiffness_slot = b.offset;
        break;
      case ParameterKind::kShearStiffness:
        m.rods[b.index].shear_stiffness = block(0);
        m.rods[b.index].shear_stiffness_slot = b.offset;
        break;
      case ParameterKind::kBendingStiffness:
        m.rods[b.index].bending_stiffness = block;
        m.rods[b.index].bending_stiffness_slot = b.offset;
        break;
    }
  }
  return m;
}

void ParameterSet::add_initial_gradient(const Model& applied, const Eigen::VectorXd& gamma,
                                        const Eigen::VectorXd& a0, const Eigen::VectorXd& da0,
                                        Eigen::VectorXd& dgamma) const {
  const double h = applied.time_step;
  const int point_count = applied.point_count();  // rotations follow the points
  for (const ParameterBlock& b : blocks_) {
    auto block = dgamma.segment(b.offset, b.size);
    const int body_point = tangent_point(b.index);
    const int body_rotation = 3 * (point_count + b.index);
    switch (b.kind) {
      case ParameterKind::kBodyLinearVelocity:  // Δx_0 = h v_0
        block += h * da0.segment<3>(body_point);
        break;
      case ParameterKind::kBodyAngularVelocity:  // ΔR_0 = exp(h ω_0)
        block += h * so3::left_jacobian(h * gamma.segment<3>(b.offset)).transpose() *
                 da0.segment<3>(body_rotation);
        break;
      case ParameterKind::kBodyPosition: block += a0.segment<3>(body_point); break;
      case ParameterKind::kBodyOrientation:  // R_0 = exp(ε) R_scene
        block += so3::left_jacobian(gamma.segment<3>(b.offset)).transpose() *
                 a0.segment<3>(body_rotation);
        break;
      case ParameterKind::kRodNodeVelocities: {  // Δx_0 = h v_0 per free node
        const int first = applied.rod_point(b.index, 0);
        const std::vector<int> nodes = free_nodes(applied.rods[b.index]);
        for (std::size_t k = 0; k < nodes.size(); ++k) {
          block.segment<3>(3 * k) += h * da0.segment<3>(tangent_point(first + nodes[k]));
        }
        break;
      }
      default:  // enters the potential, not q_0 or Δq_0
        break;
    }
  }
}

}  // namespace liedyn

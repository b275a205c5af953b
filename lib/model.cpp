#include "model.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <numbers>
#include <sstream>
#include <tuple>

#include "inertia.hpp"
#include "so3.hpp"

namespace liedyn {
namespace {

std::string index_field(const std::string& array, std::size_t i, const std::string& member) {
  return array + "[" + std::to_string(i) + "]" + (member.empty() ? "" : "." + member);
}

// The inertia terms of a dynamic step hold m/h² and J/h² (lib/inertia.hpp): finite values can
// still overflow there (a rod edge of 1e200 m, a time step of 1e-200 s), and a non-finite
// inertia term fails only later, when the simulator is built.
void require_finite_over_h2(double mass, const Matrix3& inertia, double inv_h2,
                            const std::string& field) {
  if (!std::isfinite(mass * inv_h2) || !(rotational_mass(inertia) * inv_h2).allFinite()) {
    throw ModelError(field, "is too large for the time step: its mass or rotational inertia "
                            "divided by time_step² overflows");
  }
}

void require_body(int body, std::size_t count, const std::string& field, bool allow_world) {
  if (body == -1 && allow_world) return;
  if (body < 0 || static_cast<std::size_t>(body) >= count) {
    throw ModelError(field, "refers to body " + std::to_string(body) + ", but there are " +
                                std::to_string(count) + " bodies");
  }
}

// A joint end's indices and point; `end_name` is "a" or "b".
void validate_joint_end(const Model& m, const JointEnd& end, const std::string& end_name,
                        const std::function<std::string(const std::string&)>& field) {
  switch (end.kind) {
    case JointEnd::Kind::kWorld: break;
    case JointEnd::Kind::kBody: require_body(end.object, m.bodies.size(), field(end_name + ".body"), false); break;
    case JointEnd::Kind::kRodNode:
    case JointEnd::Kind::kRodEdge: {
      if (end.object < 0 || end.object >= static_cast<int>(m.rods.size())) {
        throw ModelError(field(end_name + ".rod"), "refers to rod " + std::to_string(end.object) +
                                                      ", but there are " + std::to_string(m.rods.size()));
      }
      const bool node = end.kind == JointEnd::Kind::kRodNode;
      const int count = node ? m.rods[end.object].node_count() : m.rods[end.object].edge_count();
      if (end.element < 0 || end.element >= count) {
        throw ModelError(field(end_name + (node ? ".node" : ".edge")),
                         "refers to " + std::string(node ? "node " : "edge ") + std::to_string(end.element) +
                             ", but the rod has " + std::to_string(count));
      }
      break;
    }
  }
  require_finite(end.point, field(end_name + ".point"));
}

// Loads on a kinematic body would push nothing: it follows its motion.
void require_moving_body(const Model& m, int body, const std::string& field) {
  if (m.bodies[body].kinematic) {
    throw ModelError(field, "\"" + m.bodies[body].name + "\" is kinematic: it follows its motion, and a load on it would do nothing");
  }
}

// Whether a joint end has a DOF: a body, or a rod node or edge that is not clamped.
bool joint_end_moves(const Model& m, const JointEnd& end) {
  const auto free = [](const std::vector<int>& fixed, int i) {
    return std::find(fixed.begin(), fixed.end(), i) == fixed.end();
  };
  switch (end.kind) {
    case JointEnd::Kind::kWorld: return false;
    case JointEnd::Kind::kBody: return !m.bodies[end.object].kinematic;
    case JointEnd::Kind::kRodNode: return free(m.rods[end.object].fixed_nodes, end.element);
    case JointEnd::Kind::kRodEdge:
      return free(m.rods[end.object].fixed_nodes, end.element) ||
             free(m.rods[end.object].fixed_edges, end.element);
  }
  return false;
}

void validate_inertia(const Matrix3& I, const std::string& field) {
  require_finite(I, field);
  if (!I.isApprox(I.transpose(), 1e-12)) throw ModelError(field, "must be symmetric");
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Matrix3>(I).eigenvalues();
  if (moments.minCoeff() <= 0.0) {
    std::ostringstream os;
    os << "must be positive definite (principal moments " << moments.transpose() << ")";
    throw ModelError(field, os.str());
  }
  // Triangle inequality: the largest moment may not exceed the sum of the other two,
  // otherwise J = ½ tr(I) 1 − I is not PSD and no mass distribution has this inertia.
  if (moments(2) > moments(0) + moments(1) + kInertiaTolerance * moments.sum()) {
    std::ostringstream os;
    os << "violates the triangle inequality: principal moments " << moments.transpose()
       << " have " << moments(2) << " > " << moments(0) << " + " << moments(1);
    throw ModelError(field, os.str());
  }
}

void require_rotation(const Matrix3& R, const std::string& field) {
  require_finite(R, field);
  if ((R.transpose() * R - Matrix3::Identity()).norm() > 1e-9 || R.determinant() <= 0.0) {
    throw ModelError(field, "must be a rotation matrix");
  }
}

// A body's contact samples: finite, and only with contact enabled. Its shape: a valid
// collider, and one a body may have unless the body is kinematic (validate_body_shape: a
// kinematic body's shape is only touched, so a moving plane, tube or bowl is one).
void validate_body_contact(const RigidBody& b, const std::string& path) {
  Model::validate_contact(b.contact, path + ".contact");
  if (b.shape != nullptr) {
    b.shape->validate(path + ".contact.shape");
    if (!b.kinematic) validate_body_shape(*b.shape, path + ".contact.shape");
  }
  for (std::size_t k = 0; k < b.contact_points.size(); ++k) {
    require_finite(b.contact_points[k], path + ".contact.points[" + std::to_string(k) + "]");
  }
  if (!b.contact_points.empty() && !b.contact.enabled()) {
    throw ModelError(path + ".contact.stiffness", "must be positive: the body has contact points");
  }
}

}  // namespace

ModelError::ModelError(std::string field, std::string reason)
    : std::invalid_argument(field + ": " + reason),
      field_(std::move(field)),
      reason_(std::move(reason)) {}

void require_finite(const Eigen::MatrixXd& m, const std::string& field) {
  if (!m.allFinite()) throw ModelError(field, "must be finite (found NaN or Inf)");
}

const char* to_string(Integrator integrator) {
  switch (integrator) {
    case Integrator::kBackwardEuler: return "backward_euler";
    case Integrator::kTrapezoidal: return "trapezoidal";
    case Integrator::kFoxGoodwin: return "fox_goodwin";
    case Integrator::kBdf2: return "bdf2";
  }
  return "unknown";
}

std::optional<Integrator> parse_integrator(std::string_view name) {
  for (const auto i : {Integrator::kBackwardEuler, Integrator::kTrapezoidal, Integrator::kFoxGoodwin,
                       Integrator::kBdf2}) {
    if (name == to_string(i)) return i;
  }
  return std::nullopt;
}

double newmark_beta(Integrator integrator) {
  switch (integrator) {
    case Integrator::kTrapezoidal: return 0.25;
    case Integrator::kFoxGoodwin: return 1.0 / 12.0;
    default: return 0.0;
  }
}

void Model::validate() const {
  if (!std::isfinite(time_step) || time_step <= 0.0) {
    throw ModelError("time_step", "must be a finite positive number of seconds");
  }
  const double inv_h2 = 1.0 / (time_step * time_step);
  if (!static_equilibrium && !std::isfinite(inv_h2)) {
    throw ModelError("time_step", "is too small: 1 / time_step² overflows");
  }
  require_finite(gravity, "gravity");
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const RigidBody& b = bodies[i];
    if (b.kinematic) {
      // Only its pose, motion and contact matter (lib/kinematic.hpp).
      require_finite(b.position, index_field("bodies", i, "position"));
      require_rotation(b.orientation, index_field("bodies", i, "orientation"));
      if (!b.linear_velocity.isZero(0.0) || !b.angular_velocity.isZero(0.0)) {
        throw ModelError(index_field("bodies", i, "linear_velocity"),
                         "a kinematic body moves as its motion says: give velocities there");
      }
      b.kinematic->validate(b.orientation, time_step, static_equilibrium, index_field("bodies", i, "kinematic"));
      validate_body_contact(b, index_field("bodies", i, ""));
      continue;
    }
    if (!std::isfinite(b.mass) || b.mass <= 0.0) {
      throw ModelError(index_field("bodies", i, "mass"), "must be a finite positive number");
    }
    validate_inertia(b.inertia, index_field("bodies", i, "inertia"));
    if (!static_equilibrium) {
      require_finite_over_h2(b.mass, b.inertia, inv_h2, index_field("bodies", i, ""));
    }
    require_finite(b.position, index_field("bodies", i, "position"));
    require_rotation(b.orientation, index_field("bodies", i, "orientation"));
    require_finite(b.linear_velocity, index_field("bodies", i, "linear_velocity"));
    require_finite(b.angular_velocity, index_field("bodies", i, "angular_velocity"));
    // ΔR_0 = exp(h ω_0) and the reported ω = log(ΔR)/h only represent |ω| h < π: a faster
    // spin would silently alias to a slower one (or the opposite sense).
    if (b.angular_velocity.norm() * time_step >= std::numbers::pi) {
      std::ostringstream os;
      os << "|angular_velocity| · time_step = " << b.angular_velocity.norm() * time_step
         << " rad per step must be below π (reduce time_step)";
      throw ModelError(index_field("bodies", i, "angular_velocity"), os.str());
    }
    // A finite velocity can still carry an energy beyond double range (|v| ≳ 1e154): every
    // reported kinetic energy would be inf, and the steps would run on overflowed numbers.
    if (!std::isfinite(0.5 * b.mass * b.linear_velocity.squaredNorm())) {
      throw ModelError(index_field("bodies", i, "linear_velocity"),
                       "the kinetic energy ½ m |v|² overflows a double");
    }
    if (!std::isfinite(0.5 * b.angular_velocity.dot(b.inertia * b.angular_velocity))) {
      throw ModelError(index_field("bodies", i, "angular_velocity"),
                       "the kinetic energy ½ ωᵀ I ω overflows a double");
    }
    validate_body_contact(b, index_field("bodies", i, ""));
  }
  for (std::size_t c = 0; c < colliders.size(); ++c) {
    colliders[c].validate(index_field("colliders", c, ""));
  }
  for (std::size_t i = 0; i < springs.size(); ++i) {
    const SpringSpec& s = springs[i];
    require_body(s.a.body, bodies.size(), index_field("springs", i, "body_a"), true);
    require_body(s.b.body, bodies.size(), index_field("springs", i, "body_b"), true);
    if (s.a.body == s.b.body) {
      throw ModelError(index_field("springs", i, "body_b"),
                       s.a.body == -1 ? "connects two world anchors"
                                      : "connects a body to itself (the spring would do nothing)");
    }
    const auto moves = [&](int body) { return body >= 0 && !bodies[body].kinematic; };
    if (!moves(s.a.body) && !moves(s.b.body)) {
      throw ModelError(index_field("springs", i, "body_b"),
                       "neither end can move (the world or kinematic bodies): the spring would do nothing");
    }
    require_finite(s.a.point, index_field("springs", i, "point_a"));
    require_finite(s.b.point, index_field("springs", i, "point_b"));
    if (!std::isfinite(s.stiffness) || s.stiffness < 0.0) {
      throw ModelError(index_field("springs", i, "stiffness"), "must be finite and ≥ 0");
    }
    if (!std::isfinite(s.rest_length) || s.rest_length < 0.0) {
      throw ModelError(index_field("springs", i, "rest_length"), "must be finite and ≥ 0");
    }
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const JointSpec& j = joints[i];
    const auto field = [&](const std::string& member) { return index_field("joints", i, member); };
    if (j.a.kind == JointEnd::Kind::kWorld) {
      throw ModelError(field("a"), "end a cannot be the world (put the world at end b)");
    }
    validate_joint_end(*this, j.a, "a", field);
    validate_joint_end(*this, j.b, "b", field);
    if (j.a == j.b || (j.a.kind == JointEnd::Kind::kBody && j.b.kind == JointEnd::Kind::kBody &&
                       j.a.object == j.b.object)) {
      if (j.a.kind == JointEnd::Kind::kBody) {
        throw ModelError(field("b.body"), "joins a body to itself (the joint would do nothing)");
      }
      throw ModelError(field("b"), "joins an end to itself (the joint would do nothing)");
    }
    if (!joint_end_moves(*this, j.a) && !joint_end_moves(*this, j.b)) {
      throw ModelError(field("b"), "neither end can move (the world, kinematic bodies, or clamped rod nodes and edges): "
                                   "the joint would hold nothing");
    }
    if (j.type == JointSpec::Type::kSplice) {
      for (const auto& [end, member, last] : {std::tuple{&j.a, "a", true}, std::tuple{&j.b, "b", false}}) {
        const std::string which = last ? "the last node of a rod" : "the first node of a rod";
        if (end->kind != JointEnd::Kind::kRodNode) {
          throw ModelError(field(member), std::string("a splice joins the last node of one rod (a) to the first node of another (b): ") +
                                               member + " must be " + which);
        }
        const int n = rods[end->object].node_count();
        if (end->element != (last ? n - 1 : 0)) {
          throw ModelError(field(std::string(member) + ".node"),
                           "must be " + which + " (" + std::to_string(last ? n - 1 : 0) + " for rod \"" +
                               rods[end->object].name + "\"): the rods run on through the junction");
        }
      }
    } else if (j.type != JointSpec::Type::kBall) {
      for (const auto& [end, member] : {std::pair{&j.a, "a"}, std::pair{&j.b, "b"}}) {
        if (end->kind == JointEnd::Kind::kRodNode) {
          throw ModelError(field(std::string(member) + ".node"),
                           "a rod node has a position only: only a ball joint can hold it (a rod "
                           "edge has a frame)");
        }
      }
    }
    if (j.first_frame < 1 || j.last_frame < j.first_frame) {
      throw ModelError(field("active_frames"), "must be steps [first, last] with 1 <= first <= last (got [" +
                                                   std::to_string(j.first_frame) + ", " +
                                                   std::to_string(j.last_frame) + "])");
    }
    if (j.type == JointSpec::Type::kSplice && (j.first_frame != 1 || j.last_frame != std::numeric_limits<int>::max())) {
      throw ModelError(field("active_frames"), "a splice makes two rods one for the whole run");
    }
    // 0: exact; else 1/compliance is the stiffness of the terms: it must be finite too.
    for (const auto& [value, member] : {std::pair{j.compliance, "compliance"},
                                        std::pair{j.compliance_rotation, "compliance_rotation"}}) {
      if (!(value == 0.0 || (std::isfinite(value) && value > 0.0 && std::isfinite(1.0 / value)))) {
        throw ModelError(field(member),
                         "must be 0 (an exact joint) or a finite number > 0 whose inverse is "
                         "finite (an elastic joint)");
      }
    }
    if (j.has_motor) {
      const bool hinge = j.type == JointSpec::Type::kHinge;
      if (!hinge && j.type != JointSpec::Type::kSlider) {
        throw ModelError(field("motor"), "only a hinge (a torque about its axis) or a slider (a force along it) has a motor");
      }
      const std::string member = hinge ? "motor.torque" : "motor.force";
      if (!std::isfinite(j.motor_effort)) throw ModelError(field(member), "must be finite");
      for (const auto& effort : j.motor.schedule) {
        if (!std::isfinite(effort(0))) throw ModelError(field(member), "must be finite in every frame");
      }
    }
    if (j.has_limits) {
      if (j.type != JointSpec::Type::kHinge && j.type != JointSpec::Type::kSlider) {
        throw ModelError(field("limits"), "only a hinge (an angle, rad) or a slider (a distance, m) has limits");
      }
      if (!std::isfinite(j.lower_limit) || !std::isfinite(j.upper_limit)) {
        throw ModelError(field("limits"), "must be finite");
      }
      if (!(j.lower_limit < j.upper_limit)) {
        throw ModelError(field("limits"), "the lower limit must be below the upper (a weld fixes the angle, a hinge fixes the position)");
      }
      if (!(j.lower_limit <= 0.0 && 0.0 <= j.upper_limit)) {
        throw ModelError(field("limits"), "must hold the start (angle and position 0): [lo, hi] with lo ≤ 0 ≤ hi");
      }
    }
    if (j.type == JointSpec::Type::kSlider && !(std::abs(j.axis_a.norm() - 1.0) <= 1e-12)) {
      throw ModelError(field("a.axis"), "must be a unit vector");
    }
    if (j.type == JointSpec::Type::kHinge) {
      for (const auto& [axis, member] : {std::pair{j.axis_a, "a.axis"}, std::pair{j.axis_b, "b.axis"}}) {
        if (!(std::abs(axis.norm() - 1.0) <= 1e-12)) throw ModelError(field(member), "must be a unit vector");
      }
    }
    if (j.type == JointSpec::Type::kWeld || j.type == JointSpec::Type::kSlider) {
      for (const auto& [frame, member] : {std::pair{j.frame_a, "a"}, std::pair{j.frame_b, "b"}}) {
        if (!((frame.transpose() * frame - Matrix3::Identity()).norm() <= 1e-9 && frame.determinant() > 0.0)) {
          throw ModelError(field(member), "the weld frame must be a rotation");
        }
      }
    }
  }
  for (std::size_t i = 0; i < forces.size(); ++i) {
    require_body(forces[i].at.body, bodies.size(), index_field("forces", i, "body"), false);
    require_moving_body(*this, forces[i].at.body, index_field("forces", i, "body"));
    require_finite(forces[i].at.point, index_field("forces", i, "point"));
    require_finite(forces[i].force, index_field("forces", i, "force"));
  }
  for (std::size_t i = 0; i < torques.size(); ++i) {
    require_body(torques[i].body, bodies.size(), index_field("torques", i, "body"), false);
    require_moving_body(*this, torques[i].body, index_field("torques", i, "body"));
    require_finite(torques[i].torque, index_field("torques", i, "torque"));
  }
  for (std::size_t r = 0; r < rods.size(); ++r) {
    validate_rod(rods[r], index_field("rods", r, ""));
    if (static_equilibrium) continue;
    const RodDiscretization d = discretize(rods[r]);  // masses and inertias only
    for (std::size_t j = 0; j < d.edge_inertia.size(); ++j) {
      require_finite_over_h2(d.node_mass[j] + d.node_mass[j + 1], d.edge_inertia[j], inv_h2,
                             index_field("rods", r, ""));
    }
  }
  if (!static_equilibrium) validate_motion_speeds();
  if (!static_equilibrium && integrator == Integrator::kFoxGoodwin) validate_conditional_stability();
  validate_contact_names();
  if (static_equilibrium) validate_anchoring();
}

void Model::validate_conditional_stability() const {
  // The Simulator checks ωh < √6 on the modes of the terms a set of islands starts with
  // (lib/stability.hpp); these stiffnesses appear within a run, where no check can see them.
  const std::string why =
      " under the fox_goodwin integrator, which is stable only for ωh < √6 on every mode: its "
      "stiffness appears within a step, where no check at the start can see it (trapezoidal and "
      "bdf2 are stable at any h)";
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].contact.enabled()) throw ModelError(index_field("bodies", i, "contact"), "cannot have contact" + why);
  }
  for (std::size_t r = 0; r < rods.size(); ++r) {
    if (rods[r].contact.enabled()) throw ModelError(index_field("rods", r, "contact"), "cannot have contact" + why);
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const JointSpec& j = joints[i];
    // A hinge's limit is as elastic as its rotation, a slider's as its position.
    const double compliance = j.type == JointSpec::Type::kHinge ? j.compliance_rotation : j.compliance;
    if (j.has_limits && compliance > 0.0) {
      throw ModelError(index_field("joints", i, "limits"), "cannot be elastic (a compliant joint's)" + why);
    }
  }
}

void Model::validate_motion_speeds() const {
  // As for body spins: a prescribed rotation of π or more per time step would alias in the
  // reported angular velocities (log(ΔR)/h).
  for (std::size_t r = 0; r < rods.size(); ++r) {
    for (std::size_t m = 0; m < rods[r].prescribed_motions.size(); ++m) {
      const std::vector<Keyframe>& keys = rods[r].prescribed_motions[m].keyframes;
      for (std::size_t k = 0; k < keys.size(); ++k) {
        const Keyframe before = k == 0 ? Keyframe{} : keys[k - 1];
        const double per_step = (keys[k].rotation - before.rotation).norm() * time_step /
                                (keys[k].time - before.time);
        if (per_step >= std::numbers::pi) {
          std::ostringstream os;
          os << "rotates the clamped items by " << per_step
             << " rad per time step, which must be below π (reduce time_step or slow the "
                "motion)";
          throw ModelError(index_field("rods", r, "") + "." +
                               index_field("prescribed_motions", m, "") + "." +
                               index_field("keyframes", k, "rotation"),
                           os.str());
        }
      }
    }
  }
}

std::vector<std::pair<int, int>> Model::body_pairs() const {
  std::vector<std::pair<int, int>> out;
  const auto faces = [&](const RigidBody& sampled, const RigidBody& solid) {
    return sampled.contact.enabled() && !sampled.contact_points.empty() && solid.shape != nullptr;
  };
  for (int a = 0; a < static_cast<int>(bodies.size()); ++a) {
    for (int b = a + 1; b < static_cast<int>(bodies.size()); ++b) {
      const RigidBody& A = bodies[a];
      const RigidBody& B = bodies[b];
      if (A.kinematic && B.kinematic) continue;  // neither moves the other
      if (!A.contact.touches(B.name) || !B.contact.touches(A.name)) continue;  // both must agree
      if (faces(A, B) || faces(B, A)) out.emplace_back(a, b);
    }
  }
  return out;
}

std::vector<EdgePair> Model::edge_pairs() const {
  std::vector<EdgePair> out;
  const auto clamped = [&](int r, int node) {
    const std::vector<int>& fixed = rods[r].fixed_nodes;
    return std::find(fixed.begin(), fixed.end(), node) != fixed.end();
  };
  const auto add = [&](int r, int i, int s, int j) {
    if (clamped(r, i) && clamped(r, i + 1) && clamped(s, j) && clamped(s, j + 1)) return;
    out.push_back({r, i, s, j});
  };
  for (int r = 0; r < static_cast<int>(rods.size()); ++r) {
    const RodSpec& a = rods[r];
    if (!a.contact.enabled()) continue;
    for (int i = 0; a.self_contact && i < a.edge_count(); ++i) {
      for (int j = i + a.self_contact_skip + 1; j < a.edge_count(); ++j) add(r, i, r, j);
    }
    for (int s = r + 1; s < static_cast<int>(rods.size()); ++s) {
      const RodSpec& b = rods[s];
      if (!b.contact.enabled() || !a.contact.touches(b.name) || !b.contact.touches(a.name)) continue;
      for (int i = 0; i < a.edge_count(); ++i) {
        for (int j = 0; j < b.edge_count(); ++j) add(r, i, s, j);
      }
    }
  }
  return out;
}

std::vector<std::pair<int, int>> Model::rod_body_pairs() const {
  std::vector<std::pair<int, int>> out;
  for (int r = 0; r < static_cast<int>(rods.size()); ++r) {
    const RodSpec& rod = rods[r];
    if (!rod.contact.enabled() || static_cast<int>(rod.fixed_nodes.size()) == rod.node_count()) continue;
    for (int b = 0; b < static_cast<int>(bodies.size()); ++b) {
      const RigidBody& body = bodies[b];
      if (body.shape != nullptr && rod.contact.touches(body.name) && body.contact.touches(rod.name)) out.emplace_back(r, b);
    }
  }
  return out;
}

void Model::coupling_key(int frame, const std::vector<bool>& touching, std::vector<bool>& key) const {
  key.resize(joints.size() + touching.size());  // allocates the first time only
  for (std::size_t j = 0; j < joints.size(); ++j) key[j] = joints[j].active_at(frame);
  std::copy(touching.begin(), touching.end(), key.begin() + static_cast<std::ptrdiff_t>(joints.size()));
}

std::vector<std::pair<int, int>> Model::couplings(const std::vector<bool>* key) const {
  std::vector<std::pair<int, int>> out;
  for (const SpringSpec& s : springs) out.emplace_back(s.a.body, s.b.body);
  for (std::size_t j = 0; j < joints.size(); ++j) {
    if (key == nullptr || (*key)[j]) out.emplace_back(object_of(joints[j].a), object_of(joints[j].b));
  }
  if (key != nullptr && key->size() > joints.size()) {
    const std::vector<std::pair<int, int>> pairs = body_pairs();
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      if ((*key)[joints.size() + p]) out.push_back(pairs[p]);
    }
    const std::vector<EdgePair> edges = edge_pairs();
    const std::size_t first = joints.size() + pairs.size();
    const int n = static_cast<int>(bodies.size());
    for (std::size_t p = 0; p < edges.size() && first + p < key->size(); ++p) {
      if ((*key)[first + p] && edges[p].rod_a != edges[p].rod_b) out.emplace_back(n + edges[p].rod_a, n + edges[p].rod_b);
    }
    const std::vector<std::pair<int, int>> rod_bodies = rod_body_pairs();
    const std::size_t after = first + edges.size();
    for (std::size_t p = 0; p < rod_bodies.size() && after + p < key->size(); ++p) {
      if ((*key)[after + p]) out.emplace_back(n + rod_bodies[p].first, rod_bodies[p].second);
    }
  }
  // A kinematic body ties what touches or is joined to it to nothing: it is moved, as the
  // world is fixed.
  for (auto& [a, b] : out) {
    for (int* o : {&a, &b}) {
      if (*o >= 0 && *o < static_cast<int>(bodies.size()) && bodies[*o].kinematic) *o = -1;
    }
  }
  return out;
}

int Model::object_of(const JointEnd& end) const {
  switch (end.kind) {
    case JointEnd::Kind::kWorld: return -1;
    case JointEnd::Kind::kBody: return end.object;
    default: return static_cast<int>(bodies.size()) + end.object;
  }
}

AttachedPoint Model::attached_point(const JointEnd& end) const {
  switch (end.kind) {
    case JointEnd::Kind::kWorld: return {-1, -1, end.point};
    case JointEnd::Kind::kBody: return {end.object, end.object, end.point};
    case JointEnd::Kind::kRodNode: return {rod_point(end.object, end.element), -1, Vector3::Zero()};
    case JointEnd::Kind::kRodEdge:
      return {rod_point(end.object, end.element), rod_rotation(end.object, end.element), end.point};
  }
  return {};
}

Vector3 Model::initial_origin(const JointEnd& end) const {
  switch (end.kind) {
    case JointEnd::Kind::kWorld: return Vector3::Zero();
    case JointEnd::Kind::kBody: return bodies[end.object].position;
    default: return rods[end.object].nodes[end.element];  // a node, or an edge's first node
  }
}

Matrix3 Model::initial_rotation(const JointEnd& end) const {
  switch (end.kind) {
    case JointEnd::Kind::kBody: return bodies[end.object].orientation;
    case JointEnd::Kind::kRodEdge: return parallel_transport_frames(rods[end.object].nodes)[end.element];
    default: return Matrix3::Identity();
  }
}

void Model::validate_anchoring() const {
  if (load_steps < 1) throw ModelError("frames", "static mode needs at least one load step");
  // Objects (bodies, then rods) joined by springs and joints form groups; a group is anchored
  // by a coupling to the world or by a clamped rod node in it.
  const int n = static_cast<int>(bodies.size());
  std::vector<int> parent(n + rods.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  const std::vector<std::pair<int, int>> pairs = couplings();
  for (const auto& [a, b] : pairs) {
    if (a >= 0 && b >= 0) parent[root(a)] = root(b);
  }
  std::vector<bool> anchored(parent.size(), false);
  for (const auto& [a, b] : pairs) {
    if (a < 0 || b < 0) anchored[root(std::max(a, b))] = true;
  }
  for (std::size_t r = 0; r < rods.size(); ++r) {
    if (!rods[r].fixed_nodes.empty()) anchored[root(n + static_cast<int>(r))] = true;
  }
  for (int i = 0; i < n; ++i) {
    if (bodies[i].kinematic) anchored[i] = true;  // coupled to nothing (couplings): its own root
  }
  for (int i = 0; i < static_cast<int>(parent.size()); ++i) {
    if (anchored[root(i)]) continue;
    if (i < n) {
      throw ModelError(index_field("bodies", i, ""),
                       "static mode needs every body connected by springs or joints to a world "
                       "anchor or a clamped rod node");
    }
    throw ModelError(index_field("rods", i - n, "fixed_nodes"),
                     "static mode needs at least one clamped node, or a joint to the world or to "
                     "an anchored object (a free rod has no equilibrium under load)");
  }
}

void Model::validate_contact_names() const {
  const auto check = [&](const ContactMaterial& contact, const std::string& owner, const std::string& path) {
    if (!contact.collides_with.empty() && !contact.ignores.empty()) {
      throw ModelError(path + ".ignores", "give \"collides_with\" or \"ignores\", not both");
    }
    for (const auto& [list, member] : {std::pair{&contact.collides_with, "collides_with"},
                                       std::pair{&contact.ignores, "ignores"}}) {
      for (std::size_t k = 0; k < list->size(); ++k) {
        const std::string& name = (*list)[k];
        const std::string field = path + "." + member + "[" + std::to_string(k) + "]";
        if (name == owner) throw ModelError(field, "names its own object");
        const bool body = std::any_of(bodies.begin(), bodies.end(), [&](const RigidBody& b) { return b.name == name; });
        const bool rod = std::any_of(rods.begin(), rods.end(), [&](const RodSpec& r) { return r.name == name; });
        const bool collider =
            std::any_of(colliders.begin(), colliders.end(), [&](const Collider& c) { return c.name == name; });
        if (!body && !rod && !collider) {
          throw ModelError(field, "no body, rod or collider is named \"" + name + "\"");
        }
      }
    }
  };
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    check(bodies[i].contact, bodies[i].name, index_field("bodies", i, "contact"));
  }
  for (std::size_t r = 0; r < rods.size(); ++r) {
    check(rods[r].contact, rods[r].name, index_field("rods", r, "contact"));
  }
}

void Model::validate_contact(const ContactMaterial& contact, const std::string& path) {
  const auto check = [&](double value, const std::string& member, bool positive) {
    if (!std::isfinite(value) || value < 0.0 || (positive && value == 0.0)) {
      throw ModelError(path + "." + member,
                       positive ? "must be a finite positive number" : "must be finite and ≥ 0");
    }
  };
  check(contact.stiffness, "stiffness", false);
  check(contact.radius, "radius", false);
  check(contact.friction, "friction", false);
  check(contact.friction_velocity, "friction_velocity", true);
  check(contact.damping, "damping", false);
}

void Model::validate_rod(const RodSpec& rod, const std::string& path) {
  const auto field = [&](const std::string& member) { return path + "." + member; };
  if (rod.nodes.size() < 2) throw ModelError(field("nodes"), "must list at least 2 nodes");
  const auto check_polyline = [&](const std::vector<Vector3>& nodes, const std::string& member) {
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      require_finite(nodes[i], field(member) + "[" + std::to_string(i) + "]");
      if (i > 0 && !((nodes[i] - nodes[i - 1]).norm() > 0.0)) {
        throw ModelError(field(member) + "[" + std::to_string(i) + "]",
                         "coincides with the previous node (zero-length edge)");
      }
      if (i > 0 && !std::isfinite((nodes[i] - nodes[i - 1]).norm())) {
        throw ModelError(field(member) + "[" + std::to_string(i) + "]",
                         "is too far from the previous node (the edge length overflows)");
      }
    }
  };
  check_polyline(rod.nodes, "nodes");
  if (!rod.rest_nodes.empty()) {
    if (rod.rest_nodes.size() != rod.nodes.size()) {
      throw ModelError(field("rest_nodes"),
                       "has " + std::to_string(rod.rest_nodes.size()) +
                           " nodes, but the initial shape has " + std::to_string(rod.nodes.size()));
    }
    check_polyline(rod.rest_nodes, "rest_nodes");
  }
  const auto positive = [&](double value, const std::string& member) {
    if (!std::isfinite(value) || value <= 0.0) {
      throw ModelError(field(member), "must be a finite positive number");
    }
  };
  const auto non_negative = [&](double value, const std::string& member) {
    if (!std::isfinite(value) || value < 0.0) throw ModelError(field(member), "must be finite and ≥ 0");
  };
  positive(rod.mass, "mass");
  positive(rod.radius, "radius");
  non_negative(rod.stretch_stiffness, "stretch_stiffness");
  non_negative(rod.shear_stiffness, "shear_stiffness");
  validate_contact(rod.contact, field("contact"));
  if (rod.self_contact_skip < 1) throw ModelError(field("contact.self_contact_skip"), "must be at least 1 (neighbouring edges share a node)");
  non_negative(rod.stretch_damping, "stretch_damping");
  non_negative(rod.shear_damping, "shear_damping");
  for (int k = 0; k < 3; ++k) {
    non_negative(rod.bending_stiffness[k], "bending_stiffness[" + std::to_string(k) + "]");
    non_negative(rod.bending_damping[k], "bending_damping[" + std::to_string(k) + "]");
  }
  const auto check_indices = [&](const std::vector<int>& indices, int count,
                                 const std::string& member, const char* what) {
    std::vector<bool> seen(count, false);
    for (std::size_t k = 0; k < indices.size(); ++k) {
      const int i = indices[k];
      const std::string f = field(member) + "[" + std::to_string(k) + "]";
      if (i < 0 || i >= count) {
        throw ModelError(f, "refers to " + std::string(what) + " " + std::to_string(i) +
                                ", but the rod has " + std::to_string(count));
      }
      if (seen[i]) throw ModelError(f, "repeats " + std::string(what) + " " + std::to_string(i));
      seen[i] = true;
    }
  };
  check_indices(rod.fixed_nodes, rod.node_count(), "fixed_nodes", "node");
  check_indices(rod.fixed_edges, rod.edge_count(), "fixed_edges", "edge");
  for (std::size_t k = 0; k < rod.region_pushes.size(); ++k) {
    const std::string f = field("region_pushes") + "[" + std::to_string(k) + "]";
    require_finite(rod.region_pushes[k].force, f + ".force");
    require_finite(rod.region_pushes[k].center, f + ".center");
    const double radius = rod.region_pushes[k].radius;
    if (!std::isfinite(radius) || radius <= 0.0) {
      throw ModelError(f + ".radius", "must be a finite positive number");
    }
  }
  for (std::size_t k = 0; k < rod.node_forces.size(); ++k) {
    const std::string f = field("node_forces") + "[" + std::to_string(k) + "]";
    if (rod.node_forces[k].node < 0 || rod.node_forces[k].node >= rod.node_count()) {
      throw ModelError(f + ".node", "refers to node " + std::to_string(rod.node_forces[k].node) +
                                        ", but the rod has " + std::to_string(rod.node_count()));
    }
    require_finite(rod.node_forces[k].force, f + ".force");
  }
  const auto check_count = [&](std::size_t size, std::size_t expected, const std::string& member,
                               const char* per) {
    if (size != 0 && size != expected) {
      throw ModelError(field(member), "has " + std::to_string(size) + " entries, but the rod has " +
                                          std::to_string(expected) + " " + per);
    }
  };
  check_count(rod.node_velocities.size(), rod.nodes.size(), "node_velocities", "nodes");
  for (std::size_t i = 0; i < rod.node_velocities.size(); ++i) {
    require_finite(rod.node_velocities[i], field("node_velocities") + "[" + std::to_string(i) + "]");
    // As for bodies: no node may carry a kinetic energy beyond double range (its lumped mass
    // is at most the rod's).
    if (!std::isfinite(0.5 * rod.mass * rod.node_velocities[i].squaredNorm())) {
      throw ModelError(field("node_velocities") + "[" + std::to_string(i) + "]",
                       "the kinetic energy ½ m |v|² overflows a double");
    }
  }
  // A clamped node keeps its prescribed position (it is not a DOF; only a prescribed motion
  // moves it), so an initial velocity of it would contradict the clamp.
  if (!rod.node_velocities.empty()) {
    std::vector<bool> clamped(rod.node_count(), false);
    for (int i : rod.fixed_nodes) clamped[i] = true;  // indices checked above
    for (int i = 0; i < rod.node_count(); ++i) {
      if (clamped[i] && !rod.node_velocities[i].isZero(0.0)) {
        throw ModelError(field("node_velocities") + "[" + std::to_string(i) + "]",
                         "must be zero: node " + std::to_string(i) +
                             " is clamped (in fixed_nodes), and a clamped node keeps its "
                             "prescribed position (only a prescribed motion moves it)");
      }
    }
  }
  const std::size_t interior = rod.nodes.size() - 2;
  check_count(rod.rest_darboux.size(), interior, "rest_darboux", "interior nodes");
  for (std::size_t i = 0; i < rod.rest_darboux.size(); ++i) {
    require_finite(rod.rest_darboux[i], field("rest_darboux") + "[" + std::to_string(i) + "]");
  }
  check_count(rod.rest_darboux_controls.size(), interior, "rest_darboux_controls",
              "interior nodes");
  for (std::size_t c = 0; c < rod.cables.size(); ++c) {
    const CableSpec& cable = rod.cables[c];
    const std::string f = field("cables") + "[" + std::to_string(c) + "]";
    if (cable.route.size() < 2) throw ModelError(f + ".route", "must have at least 2 points");
    for (std::size_t k = 0; k < cable.route.size(); ++k) {
      const std::string point = f + ".route[" + std::to_string(k) + "]";
      if (cable.route[k].edge < 0 || cable.route[k].edge >= rod.edge_count()) {
        throw ModelError(point + ".edge", "refers to edge " + std::to_string(cable.route[k].edge) +
                                              ", but the rod has " + std::to_string(rod.edge_count()));
      }
      require_finite(cable.route[k].local, point + ".local");
    }
    if (!std::isfinite(cable.tension) || cable.tension < 0.0) {
      throw ModelError(f + ".tension", "must be finite and ≥ 0");
    }
  }
  validate_motions(rod, path);
}

void Model::validate_motions(const RodSpec& rod, const std::string& path) {
  // Each moved node or edge must be clamped (a DOF cannot also be prescribed) and moved by
  // one motion only.
  std::vector<bool> clamped_node(rod.node_count(), false), clamped_edge(rod.edge_count(), false);
  for (int i : rod.fixed_nodes) clamped_node[i] = true;
  for (int j : rod.fixed_edges) clamped_edge[j] = true;
  std::vector<bool> moved_node(rod.node_count(), false), moved_edge(rod.edge_count(), false);
  for (std::size_t m = 0; m < rod.prescribed_motions.size(); ++m) {
    const PrescribedMotion& motion = rod.prescribed_motions[m];
    const std::string f = path + "." + index_field("prescribed_motions", m, "");
    const auto check = [&](const std::vector<int>& items, const std::vector<bool>& clamped,
                           std::vector<bool>& moved, const std::string& member,
                           const std::string& what) {
      for (std::size_t k = 0; k < items.size(); ++k) {
        const int i = items[k];
        const std::string item = f + "." + index_field(member, k, "");
        if (i < 0 || i >= static_cast<int>(clamped.size())) {
          throw ModelError(item, "refers to " + what + " " + std::to_string(i) +
                                     ", but the rod has " + std::to_string(clamped.size()));
        }
        if (!clamped[i]) {
          throw ModelError(item, what + " " + std::to_string(i) + " is not in fixed_" + what +
                                     "s: only clamped " + what + "s can be moved");
        }
        if (moved[i]) {
          throw ModelError(item, what + " " + std::to_string(i) + " is moved twice (by this " +
                                     "or an earlier motion)");
        }
        moved[i] = true;
      }
    };
    check(motion.nodes, clamped_node, moved_node, "nodes", "node");
    check(motion.edges, clamped_edge, moved_edge, "edges", "edge");
    if (motion.nodes.empty() && motion.edges.empty()) {
      throw ModelError(f + ".nodes", "a motion must move at least one node or edge");
    }
    require_finite(motion.center, f + ".center");
    if (motion.keyframes.empty()) throw ModelError(f + ".keyframes", "must list at least one keyframe");
    double previous = 0.0;
    for (std::size_t k = 0; k < motion.keyframes.size(); ++k) {
      const Keyframe& key = motion.keyframes[k];
      const std::string kf = f + "." + index_field("keyframes", k, "");
      if (!std::isfinite(key.time) || key.time <= previous) {
        throw ModelError(kf + ".time",
                         k == 0 ? "must be a finite time after 0 (the motion starts from the "
                                  "initial pose at t = 0)"
                                : "must be finite and later than the previous keyframe's");
      }
      previous = key.time;
      require_finite(key.translation, kf + ".translation");
      require_finite(key.rotation, kf + ".rotation");
    }
  }
}

int Model::rod_point(int rod, int node) const {
  int index = static_cast<int>(bodies.size());
  for (int r = 0; r < rod; ++r) index += rods[r].node_count();
  return index + node;
}

int Model::rod_rotation(int rod, int edge) const {
  int index = static_cast<int>(bodies.size());
  for (int r = 0; r < rod; ++r) index += rods[r].edge_count();
  return index + edge;
}

RodDiscretization Model::discretize_rod(int rod) const {
  RodEnds ends;
  const int last_edge = rods[rod].edge_count() - 1;
  for (const JointSpec& j : joints) {
    if (j.type == JointSpec::Type::kSplice) {  // a's last node to b's first
      if (j.a.object == rod) ends.last_spliced = true;
      if (j.b.object == rod) ends.first_spliced = true;
    }
    // A weld to the world that holds for the whole run is a clamp (end b is the only one that
    // can be the world); one that lets go or catches later leaves a free end part of the run.
    const bool whole_run = j.first_frame == 1 && j.last_frame == std::numeric_limits<int>::max();
    if (j.type != JointSpec::Type::kWeld || j.b.kind != JointEnd::Kind::kWorld || !whole_run) continue;
    if (j.a.kind != JointEnd::Kind::kRodEdge || j.a.object != rod) continue;
    if (j.a.element == 0) ends.first_welded = true;
    if (j.a.element == last_edge) ends.last_welded = true;
  }
  return discretize(rods[rod], ends);
}

State Model::initial_state() const {
  State q;
  for (const RigidBody& b : bodies) {
    q.points.push_back(b.position);
    q.rotations.push_back(so3::orthonormalize(b.orientation));
  }
  for (const RodSpec& rod : rods) {
    q.points.insert(q.points.end(), rod.nodes.begin(), rod.nodes.end());
    const std::vector<Matrix3> frames = discretize(rod).frames;
    q.rotations.insert(q.rotations.end(), frames.begin(), frames.end());
  }
  return q;
}

Step Model::initial_step() const {
  Step dq;
  for (const RigidBody& b : bodies) {
    if (b.kinematic) {  // the motion over the first step
      Vector3 x;
      Matrix3 R;
      b.kinematic->pose(time_step, b.position, b.orientation, x, R);
      dq.points.push_back(x - b.position);
      dq.rotations.push_back(so3::orthonormalize(R * b.orientation.transpose()));
      continue;
    }
    dq.points.push_back(time_step * b.linear_velocity);
    dq.rotations.push_back(so3::exp(time_step * b.angular_velocity));
  }
  // Rod edges start at rest, and nodes too unless given velocities; clamped nodes always
  // (validate refuses a velocity on one): a Δx_0 of theirs would be carried into every step.
  for (const RodSpec& rod : rods) {
    const std::size_t first = dq.points.size();
    dq.points.insert(dq.points.end(), rod.node_count(), Vector3::Zero());
    if (!rod.node_velocities.empty()) {
      const int given = std::min(rod.node_count(), static_cast<int>(rod.node_velocities.size()));
      for (int i = 0; i < given; ++i) dq.points[first + i] = time_step * rod.node_velocities[i];
      for (int i : rod.fixed_nodes) {
        if (i >= 0 && i < rod.node_count()) dq.points[first + i].setZero();
      }
    }
    dq.rotations.insert(dq.rotations.end(), rod.edge_count(), Matrix3::Identity());
  }
  return dq;
}

}  // namespace liedyn

#pragma once
// A rigid-body model as a user describes it, in code or through a scene file
// (problems/scene.hpp). Units SI. Body i owns point i (centre of mass) and rotation i.

#include <stdexcept>
#include <string>
#include <vector>

#include "state.hpp"

namespace liedyn {

// Invalid input to the model; `field` is a dotted path such as "bodies[1].inertia".
class ModelError : public std::invalid_argument {
 public:
  ModelError(std::string field, const std::string& reason);
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

struct RigidBody {
  std::string name;
  double mass = 1.0;                              // kg, > 0
  Matrix3 inertia = Matrix3::Identity();          // body-frame tensor about the centre of mass
  Vector3 position = Vector3::Zero();             // centre of mass, world
  Matrix3 orientation = Matrix3::Identity();      // body → world
  Vector3 linear_velocity = Vector3::Zero();      // world
  Vector3 angular_velocity = Vector3::Zero();     // world
};

// End of a spring or point of application of a force: a body point given in body
// coordinates, or (body = −1) a fixed world point.
struct BodyPoint {
  int body = -1;
  Vector3 point = Vector3::Zero();
};

struct SpringSpec {
  BodyPoint a, b;
  double stiffness = 0.0;     // N/m, ≥ 0
  double rest_length = 0.0;   // m, ≥ 0
};

struct ForceSpec {
  BodyPoint at;               // body ≥ 0 required
  Vector3 force = Vector3::Zero();  // world, N
};

struct TorqueSpec {
  int body = -1;
  Vector3 torque = Vector3::Zero();  // world, N·m
};

struct Model {
  double time_step = 0.01;  // h, s, > 0
  Vector3 gravity = Vector3::Zero();
  std::vector<RigidBody> bodies;
  std::vector<SpringSpec> springs;
  std::vector<ForceSpec> forces;
  std::vector<TorqueSpec> torques;

  // Throws ModelError naming the first offending field. Checks finiteness, positivity,
  // symmetric positive-definite inertia obeying the triangle inequality, orthonormal
  // orientations, and valid body indices.
  void validate() const;

  // State q_0 and step Δq_0 = (h v_0, exp(h ω_0)) (DESIGN.md §3).
  State initial_state() const;
  Step initial_step() const;
};

// Tolerance on the triangle inequality I₁ ≤ I₂ + I₃ (relative to tr I_b): a body whose
// principal moments violate it by more is rejected, a thin rod (I₁ → 0) is accepted.
inline constexpr double kInertiaTolerance = 1e-12;

}  // namespace liedyn

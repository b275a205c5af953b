#pragma once
// Kinematic bodies: bodies whose pose is a given function of time instead of a DOF (a motor-
// driven spool, a moving piston, a collider that sweeps through a scene). Before each step the
// simulator puts them where their motion says they are at its end; they then push what they
// touch (their shape and samples enter the contact terms of the bodies and rods they touch,
// with no DOF on their side) and are not pushed back: no inertia, no load, no DOF. Their
// shape is only touched, so it may be any collider, an unbounded plane or inside-out shape or
// a tube included (a moving floor, a moving lumen; sdf.hpp, validate_body_shape).
//
// Two kinds of motion, from the body's pose (x_0, R_0) at t = 0:
//   velocities  x(t) = x_0 + v t,  R(t) = exp(ω t) R_0    (v, ω world frame, constant);
//   keyframes   poses (t_k, x_k, R_k) at increasing times t_1 < t_2 < …, with (0, x_0, R_0)
//               before the first: between two of them, with s = (t − t_a)/(t_b − t_a),
//                 x(t) = x_a + s (x_b − x_a),   R(t) = R_a exp(s log(R_aᵀ R_b)),
//               a constant linear and angular velocity along each span (the rotation the
//               shorter way round, so consecutive orientations must differ by less than π);
//               held after the last.
// In static mode a keyframed motion is followed over the load steps like a rod's prescribed
// motion (load step k at λ_k of the last keyframe's time); velocities have no end and need
// dynamic mode.

#include <string>
#include <vector>

#include "state.hpp"

namespace liedyn {

struct KinematicPose {
  double time = 0.0;                          // s, > 0, increasing along the list
  Vector3 position = Vector3::Zero();         // world
  Matrix3 orientation = Matrix3::Identity();  // body → world
};

struct KinematicMotion {
  Vector3 linear_velocity = Vector3::Zero();   // v, m/s, world (when no keyframes)
  Vector3 angular_velocity = Vector3::Zero();  // ω, rad/s, world (when no keyframes)
  std::vector<KinematicPose> keyframes;        // none: the velocities

  // The last keyframe's time; 0 for velocities.
  double duration() const { return keyframes.empty() ? 0.0 : keyframes.back().time; }

  // The pose at `time` of a body that starts at (x0, R0); time ≤ 0 gives (x0, R0).
  void pose(double time, const Vector3& x0, const Matrix3& R0, Vector3& x, Matrix3& R) const;

  // Throws ModelError naming path + ".linear_velocity", ".angular_velocity" or
  // ".keyframes[k].time|position|orientation": finite numbers; keyframe times > 0 and
  // increasing; orientations rotations; consecutive orientations (from R0) less than π apart;
  // a rotation of less than π per time step h (as for a body's spin: a faster one would alias
  // in the reported angular velocity log(ΔR)/h); velocities only in dynamic mode.
  void validate(const Matrix3& R0, double time_step, bool static_mode, const std::string& path) const;
};

}  // namespace liedyn

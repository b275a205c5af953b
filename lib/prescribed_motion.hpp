#pragma once
// Prescribed rigid motion of clamped rod nodes and edges: pulling, pushing and twisting the
// ends of a rod (paper Fig. 5). The clamped positions and rotations are not DOFs; before
// each step the simulator moves them to where the motion says they are at the end of it.
//
// A motion is a keyframed rigid transform about a pivot c, starting at the identity at
// t = 0:  x(t) = c + d(t) + exp(r(t)) (x(0) − c),   R(t) = exp(r(t)) R(0),
// with the translation d and the rotation vector r interpolated linearly between keyframes
// (so a rotation about a fixed axis runs at constant angular velocity, and |r| may exceed π:
// a keyframe can twist an end by several turns) and held after the last keyframe.
// In static mode ("mode": "static") the keyframe path is followed over the load steps:
// load step k sees the motion at time λ_k · (last keyframe time), λ_k = min(k/load_steps, 1).

#include <vector>

#include "state.hpp"

namespace liedyn {

struct Keyframe {
  double time = 0.0;                       // s, > 0, increasing along the list
  Vector3 translation = Vector3::Zero();   // d, m
  Vector3 rotation = Vector3::Zero();      // r, rad (rotation vector about the pivot)
};

struct RigidTransform {
  Vector3 translation = Vector3::Zero();
  Matrix3 rotation = Matrix3::Identity();
};

struct PrescribedMotion {
  std::vector<int> nodes;  // rod nodes moved (each must be clamped: in fixed_nodes)
  std::vector<int> edges;  // rod edges moved (each must be clamped: in fixed_edges)
  Vector3 center = Vector3::Zero();  // pivot c, world, at t = 0
  std::vector<Keyframe> keyframes;   // at least one

  double duration() const { return keyframes.empty() ? 0.0 : keyframes.back().time; }

  // (d(t), exp(r(t))). t ≤ 0 gives the identity.
  RigidTransform at(double time) const;

  // Where the motion puts a point that was at x0 at t = 0.
  Vector3 move_point(const RigidTransform& T, const Vector3& x0) const {
    return center + T.translation + T.rotation * (x0 - center);
  }
};

}  // namespace liedyn

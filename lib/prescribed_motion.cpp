#include "prescribed_motion.hpp"

#include "so3.hpp"

namespace liedyn {

RigidTransform PrescribedMotion::at(double time) const {
  RigidTransform T;
  if (keyframes.empty() || !(time > 0.0)) return T;
  // Segment [t_a, t_b] containing `time`; the motion starts from the identity at t = 0.
  double t_a = 0.0;
  Vector3 d_a = Vector3::Zero(), r_a = Vector3::Zero();
  for (const Keyframe& k : keyframes) {
    if (time <= k.time) {
      const double s = (time - t_a) / (k.time - t_a);
      T.translation = d_a + s * (k.translation - d_a);
      T.rotation = so3::exp(r_a + s * (k.rotation - r_a));
      return T;
    }
    t_a = k.time;
    d_a = k.translation;
    r_a = k.rotation;
  }
  T.translation = d_a;  // after the last keyframe: hold
  T.rotation = so3::exp(r_a);
  return T;
}

}  // namespace liedyn

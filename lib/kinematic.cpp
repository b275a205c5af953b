#include "kinematic.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

#include "model.hpp"
#include "so3.hpp"

namespace liedyn {

void KinematicMotion::pose(double time, const Vector3& x0, const Matrix3& R0, Vector3& x, Matrix3& R) const {
  x = x0;
  R = R0;
  if (!(time > 0.0)) return;
  if (keyframes.empty()) {
    x = x0 + time * linear_velocity;
    R = so3::orthonormalize(so3::exp(time * angular_velocity) * R0);
    return;
  }
  // The span [t_a, t_b] holding `time`; the body's initial pose opens the first.
  double t_a = 0.0;
  const Vector3* x_a = &x0;
  const Matrix3* R_a = &R0;
  for (const KinematicPose& k : keyframes) {
    if (time <= k.time) {
      const double s = (time - t_a) / (k.time - t_a);
      x = *x_a + s * (k.position - *x_a);
      R = so3::orthonormalize(*R_a * so3::exp(s * so3::log(R_a->transpose() * k.orientation)));
      return;
    }
    t_a = k.time;
    x_a = &k.position;
    R_a = &k.orientation;
  }
  x = *x_a;  // after the last keyframe: hold
  R = *R_a;
}

void KinematicMotion::validate(const Matrix3& R0, double time_step, bool static_mode,
                               const std::string& path) const {
  const auto finite = [&](const auto& m, const std::string& field) {
    if (!m.allFinite()) throw ModelError(path + "." + field, "must be finite (found NaN or Inf)");
  };
  const auto too_fast = [&](double per_step, const std::string& field) {
    if (per_step < std::numbers::pi) return;
    std::ostringstream os;
    os << "turns the body by " << per_step
       << " rad per time step, which must be below π (reduce time_step or slow the motion)";
    throw ModelError(path + "." + field, os.str());
  };
  if (keyframes.empty()) {
    finite(linear_velocity, "linear_velocity");
    finite(angular_velocity, "angular_velocity");
    if (static_mode) {
      throw ModelError(path + ".linear_velocity",
                       "a motion by velocities has no end to follow over static load steps: give "
                       "\"keyframes\", or use dynamic mode");
    }
    too_fast(angular_velocity.norm() * time_step, "angular_velocity");
    return;
  }
  if (!linear_velocity.isZero(0.0) || !angular_velocity.isZero(0.0)) {
    throw ModelError(path + ".linear_velocity", "give velocities or keyframes, not both");
  }
  double t_a = 0.0;
  const Matrix3* R_a = &R0;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    const KinematicPose& key = keyframes[k];
    const std::string at = "keyframes[" + std::to_string(k) + "].";
    if (!std::isfinite(key.time) || !(key.time > t_a)) {
      throw ModelError(path + "." + at + "time",
                       k == 0 ? "must be a finite time > 0 (the body's own pose is the motion at t = 0)"
                              : "must be finite and later than the keyframe before");
    }
    finite(key.position, at + "position");
    finite(key.orientation, at + "orientation");
    if ((key.orientation.transpose() * key.orientation - Matrix3::Identity()).norm() > 1e-9 ||
        key.orientation.determinant() <= 0.0) {
      throw ModelError(path + "." + at + "orientation", "must be a rotation");
    }
    // log is unique below π only: at π the way round (and so the motion) would be a guess.
    const double angle = so3::log(R_a->transpose() * key.orientation).norm();
    if (angle > std::numbers::pi - 1e-6) {
      std::ostringstream os;
      os << "turns " << angle << " rad from the pose before: consecutive orientations must differ by "
         << "less than π (add a keyframe between them)";
      throw ModelError(path + "." + at + "orientation", os.str());
    }
    if (!static_mode) too_fast(angle * time_step / (key.time - t_a), at + "orientation");
    t_a = key.time;
    R_a = &key.orientation;
  }
}

}  // namespace liedyn

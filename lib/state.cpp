#include "state.hpp"

namespace liedyn {

const Matrix3& rotation_or_identity(const State& q, int rotation) {
  static const Matrix3 kIdentity = Matrix3::Identity();
  return rotation < 0 ? kIdentity : q.rotations[rotation];
}

Vector3 AttachedPoint::position(const State& q) const {
  if (point < 0) return local;
  return q.points[point] + lever(q);
}

Vector3 AttachedPoint::lever(const State& q) const {
  if (rotation >= 0) return q.rotations[rotation] * local;
  return point >= 0 ? local : Vector3::Zero();
}

Matrix3 rotated_point_curvature(const Vector3& r, const Vector3& f) {
  return 0.5 * (f * r.transpose() + r * f.transpose()) - f.dot(r) * Matrix3::Identity();
}

}  // namespace liedyn

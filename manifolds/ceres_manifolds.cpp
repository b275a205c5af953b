#include "ceres_manifolds.hpp"

#include <Eigen/Core>

#include "quaternion.hpp"
#include "so3_manifold.hpp"

namespace liedyn {

namespace {
using Vector3 = Eigen::Vector3d;
using Vector4 = Eigen::Vector4d;
}  // namespace

// The retraction and SO3Manifold's exponential agree to first order at δ = 0 (both move q
// along Q(q) δ), so their Jacobians are SO3Manifold's.
UnitQuaternionRetraction::LieToAmbient UnitQuaternionRetraction::lie_to_ambient(
    const double* q) {
  return SO3Manifold::lie_to_ambient(q);
}

bool UnitQuaternionRetraction::Plus(const double* x, const double* delta,
                                    double* x_plus_delta) const {
  Eigen::Map<Vector4>{x_plus_delta} =
      quat::retract(Eigen::Map<const Vector4>(x), Eigen::Map<const Vector3>(delta));
  return true;
}

bool UnitQuaternionRetraction::PlusJacobian(const double* x, double* jacobian) const {
  return SO3Manifold().PlusJacobian(x, jacobian);
}

bool UnitQuaternionRetraction::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Eigen::Map<const Vector4> q(x);
  Vector4 p = Eigen::Map<const Vector4>(y);
  double c = q.dot(p);
  if (c < 0.0) {  // −p is the same rotation, in q's hemisphere
    p = -p;
    c = -c;
  }
  if (!(c > 0.0)) return false;  // a half turn away: no δ reaches it
  Eigen::Map<Vector3>{y_minus_x} = 4.0 * quat::rate_matrix(q).transpose() * p / c;
  return true;
}

bool UnitQuaternionRetraction::MinusJacobian(const double* x, double* jacobian) const {
  return SO3Manifold().MinusJacobian(x, jacobian);
}

}  // namespace liedyn

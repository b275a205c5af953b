#include "ceres_manifolds.hpp"

#include <Eigen/Core>

#include "quaternion.hpp"

namespace liedyn {

namespace {
using Vector3 = Eigen::Vector3d;
using Vector4 = Eigen::Vector4d;
template <int Rows, int Cols>
using RowMajor = Eigen::Matrix<double, Rows, Cols, Eigen::RowMajor>;
}  // namespace

UnitQuaternionRetraction::LieToAmbient UnitQuaternionRetraction::lie_to_ambient(
    const double* q) {
  return 4.0 * quat::rate_matrix(Eigen::Map<const Vector4>(q)).transpose();
}

bool UnitQuaternionRetraction::Plus(const double* x, const double* delta,
                                    double* x_plus_delta) const {
  Eigen::Map<Vector4>{x_plus_delta} =
      quat::retract(Eigen::Map<const Vector4>(x), Eigen::Map<const Vector3>(delta));
  return true;
}

bool UnitQuaternionRetraction::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<RowMajor<4, 3>>{jacobian} = quat::rate_matrix(Eigen::Map<const Vector4>(x));
  return true;
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
  Eigen::Map<RowMajor<3, 4>>{jacobian} = lie_to_ambient(x);
  return true;
}

}  // namespace liedyn

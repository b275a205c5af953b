#include "so3_manifold.hpp"

#include <cmath>

#include "quaternion.hpp"

namespace liedyn {

namespace {
template <int Rows, int Cols>
using RowMajor = Eigen::Matrix<double, Rows, Cols, Eigen::RowMajor>;
}  // namespace

SO3Manifold::Vector4 SO3Manifold::exp(const Vector3& delta) {
  const double t2 = delta.squaredNorm();
  const double t = std::sqrt(t2);
  // sin(t/2)/t and cos(t/2); the series below has relative error < t⁶/10⁵ for t < 1e-3.
  const double s = t < 1e-3 ? 0.5 - t2 / 48.0 + t2 * t2 / 3840.0 : std::sin(0.5 * t) / t;
  Vector4 q;
  q << s * delta, std::cos(0.5 * t);
  return q;
}

SO3Manifold::Vector3 SO3Manifold::log(const Vector4& q) {
  // q and −q are one rotation: take w ≥ 0, so that the angle 2 atan2(‖v‖, w) is in [0, π].
  const Vector3 v = q(3) < 0.0 ? Vector3(-q.head<3>()) : Vector3(q.head<3>());
  const double w = std::abs(q(3));
  const double n = v.norm();
  // θ = (2 atan2(n, w)/n) v; near n = 0, 2 atan2(n, w)/n = (2/w)(1 − n²/(3w²) + …).
  if (n < 1e-4 * w) {
    const double r2 = n * n / (w * w);
    return (2.0 / w) * (1.0 - r2 / 3.0 + r2 * r2 / 5.0) * v;
  }
  return (2.0 * std::atan2(n, w) / n) * v;
}

SO3Manifold::Vector4 SO3Manifold::quaternion(const Matrix3& R) { return quat::from_rotation(R); }

SO3Manifold::Matrix3 SO3Manifold::rotation(const double* q) {
  return quat::rotation(Eigen::Map<const Vector4>(q).normalized());
}

SO3Manifold::LieToAmbient SO3Manifold::lie_to_ambient(const double* q) {
  return 4.0 * quat::rate_matrix(Eigen::Map<const Vector4>(q)).transpose();
}

bool SO3Manifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Vector4 p = quat::product(exp(Eigen::Map<const Vector3>(delta)), Eigen::Map<const Vector4>(x));
  Eigen::Map<Vector4>{x_plus_delta} = p.normalized();
  return true;
}

bool SO3Manifold::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<RowMajor<4, 3>>{jacobian} = quat::rate_matrix(Eigen::Map<const Vector4>(x));
  return true;
}

bool SO3Manifold::RightMultiplyByPlusJacobian(const double* x, int num_rows,
                                              const double* ambient_matrix,
                                              double* tangent_matrix) const {
  const PlusJacobianMatrix Q = quat::rate_matrix(Eigen::Map<const Vector4>(x));
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>> A(ambient_matrix,
                                                                                  num_rows, 4);
  // noalias: Ceres calls this per residual block and iteration; without it Eigen would
  // evaluate the product into a heap temporary first.
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(tangent_matrix, num_rows, 3)
      .noalias() = A * Q;
  return true;
}

bool SO3Manifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Eigen::Map<const Vector4> p(y), q(x);
  if (!p.allFinite() || !q.allFinite() || p.squaredNorm() == 0.0 || q.squaredNorm() == 0.0) {
    return false;
  }
  const Vector4 d = quat::product(p.normalized(), quat::inverse(q.normalized()));
  Eigen::Map<Vector3>{y_minus_x} = log(d);
  return true;
}

bool SO3Manifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<RowMajor<3, 4>>{jacobian} = lie_to_ambient(x);
  return true;
}

}  // namespace liedyn

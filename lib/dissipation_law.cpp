#include "dissipation_law.hpp"

#include <cmath>

namespace liedyn {

double SlipFriction::evaluate(const Vector3& d, double lambda, const Vector3& n, double, Vector3* f,
                              Matrix3* K) const {
  const Matrix3 P = Matrix3::Identity() - n * n.transpose();
  const SmoothedSlip slip(P * d, epsilon);
  const double scale = coefficient * lambda;  // μλ
  if (f != nullptr) *f = scale * slip.phi1 * slip.u;
  if (K != nullptr) *K = scale * slip.curvature(P);
  return scale * slip.f0;
}

double NormalDashpot::evaluate(const Vector3& d, double, const Vector3& n, double k, Vector3* f,
                               Matrix3* K) const {
  const double r = rate(k);
  const double s = n.dot(d);
  if (f != nullptr) *f = r * s * n;
  if (K != nullptr) *K = r * n * n.transpose();
  return 0.5 * r * s * s;
}

double NormalDashpot::residual(const Vector3& d, const Vector3& n, double k, Eigen::RowVector3d& row) const {
  const double root = std::sqrt(rate(k));
  row = root * n.transpose();
  return root * n.dot(d);
}

}  // namespace liedyn

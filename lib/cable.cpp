#include "cable.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "point_pair.hpp"

namespace liedyn {

double CableSegment::evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
  const Vector3 d = b.position(q) - a.position(q);
  const double l = d.norm();
  const double value = tension * l;  // V = T l: the same expression on every path
  if (g == nullptr && H == nullptr) return value;
  if (!(l > 0.0)) {
    // Degenerate segment (or NaN, which the value carries): see cable.hpp.
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return value;
  }
  const double inv_l = 1.0 / l;
  const Vector3 n = inv_l * d;
  const Vector3 f = tension * n;  // ∂V/∂d = T n
  // ∂²V/∂d² = T (I − n nᵀ)/l, the projector onto the plane normal to the segment.
  const double t_over_l = tension * inv_l;
  const Matrix3 K = t_over_l * Matrix3::Identity() - t_over_l * (n * n.transpose());
  point_pair_derivatives(a.lever(q), b.lever(q), f, K, g, H);  // eqs. (22), (23)
  return value;
}

LocalGradient<4> CableSegment::tension_gradient(const State& q) const {
  CableSegment unit = *this;  // V is linear in T: ∂(gradient)/∂T is the gradient at T = 1
  unit.tension = 1.0;
  LocalGradient<4> g;
  unit.evaluate(q, &g, nullptr);
  return g;
}

void CableSegment::validate() const {
  if (!(std::isfinite(tension) && tension >= 0.0)) {
    std::ostringstream msg;
    msg.precision(17);
    msg << "CableSegment::tension = " << tension << ": must be finite and >= 0 (a cable pulls)";
    throw std::invalid_argument(msg.str());
  }
}

void CableSegment::add_parameter_adjoint(const State& q, int frame, const LocalGradient<4>& z,
                                         Eigen::VectorXd& dgamma) const {
  const int slot = control.slot_at(frame);
  if (slot >= 0) dgamma(slot) += tension_gradient(q).dot(z);
}

}  // namespace liedyn

#include "rod_terms.hpp"

#include "so3.hpp"
#include "spring.hpp"

namespace liedyn {

Vector3 darboux_vector(const Matrix3& Ra, const Matrix3& Rb, double rest_length) {
  return so3::vee(Ra.transpose() * Rb) / rest_length;
}

double RodStretch::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  const Vector3 e = q.points[node1] - q.points[node0];
  // ½ k_s l (1 − L/l)² = ½ (k_s/l)(L − l)²: a length spring of stiffness k_s/l, whose form
  // has no cancellation.
  const double k_over_l = stiffness / rest_length;
  if (g == nullptr && H == nullptr) {
    const double stretch = e.norm() - rest_length;
    return 0.5 * k_over_l * stretch * stretch;
  }
  const auto [value, f, K] = length_spring(e, k_over_l, rest_length);  // ∂Ψ/∂e, ∂²Ψ/∂e²
  if (g != nullptr) {
    g->segment<3>(0) = -f;
    g->segment<3>(3) = f;
  }
  if (H != nullptr) {
    H->block<3, 3>(0, 0) = K;
    H->block<3, 3>(0, 3) = -K;
    H->block<3, 3>(3, 0) = -K;
    H->block<3, 3>(3, 3) = K;
  }
  return value;
}

double RodShear::evaluate(const State& q, LocalGradient<3>* g, LocalHessian<3>* H) const {
  const Vector3 e = q.points[node1] - q.points[node0];
  const double L = e.norm();
  const Vector3 t = q.rotations[edge].col(2);  // R e_z
  const double c = 0.5 * stiffness * rest_length;
  if (!(L > 0.0)) {
    // Coincident nodes: d is undefined. Take d = 0 (Ψ = c, the mean over directions) and no
    // force or curvature; a rod never gets here unless it is crushed to a point.
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return c;
  }
  const Vector3 d = e / L;
  // ½ c ‖d − t‖² = c (1 − dᵀt) for unit d, t, without the cancellation of 1 − dᵀt near rest.
  const double value = 0.5 * c * (d - t).squaredNorm();
  if (g == nullptr && H == nullptr) return value;

  const double a = d.dot(t);
  const Vector3 Pt = t - a * d;  // P t,  P = I − d dᵀ
  if (g != nullptr) {
    const Vector3 g_e = -c / L * Pt;  // ∂Ψ/∂e = −c P t / L
    g->segment<3>(0) = -g_e;
    g->segment<3>(3) = g_e;
    g->segment<3>(6) = -c * t.cross(d);  // DΨ/DR = −c t × d
  }
  if (H != nullptr) {
    const Matrix3 dt = d * t.transpose();
    const Matrix3 dtS = dt + dt.transpose();  // d tᵀ + t dᵀ (exactly symmetric)
    const Matrix3 P = Matrix3::Identity() - d * d.transpose();
    // ∂²Ψ/∂e² = c [d tᵀ + t dᵀ + a (I − 3 d dᵀ)] / L²
    const Matrix3 H_ee = c / (L * L) * (dtS + a * (Matrix3::Identity() - 3.0 * d * d.transpose()));
    // ∂²Ψ/∂θ∂e = −c hat(t) P / L
    const Matrix3 H_te = -c / L * so3::hat(t) * P;
    // D²Ψ/DR² = −c [½ (d tᵀ + t dᵀ) − a I]
    const Matrix3 H_tt = -c * (0.5 * dtS - a * Matrix3::Identity());
    H->block<3, 3>(0, 0) = H_ee;
    H->block<3, 3>(0, 3) = -H_ee;
    H->block<3, 3>(3, 0) = -H_ee;
    H->block<3, 3>(3, 3) = H_ee;
    H->block<3, 3>(6, 0) = -H_te;
    H->block<3, 3>(6, 3) = H_te;
    H->block<3, 3>(0, 6) = -H_te.transpose();
    H->block<3, 3>(3, 6) = H_te.transpose();
    H->block<3, 3>(6, 6) = H_tt;
  }
  return value;
}

double RodBendTwist::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  const Matrix3& Ra = q.rotations[edge0];
  const Matrix3& Rb = q.rotations[edge1];
  const Vector3 omega = darboux_vector(Ra, Rb, rest_length);
  const Vector3 dw = omega - rest_darboux;
  const Vector3 Kdw = stiffness.cwiseProduct(dw);
  const double value = 0.5 * rest_length * dw.dot(Kdw);
  if (g == nullptr && H == nullptr) return value;

  const Matrix3 C = Rb * Ra.transpose();                          // world-frame relative rotation
  const Matrix3 G = 0.5 * (C.trace() * Matrix3::Identity() - C);  // vee(hat(u) C) = G u
  const Vector3 m = Ra * Kdw;                                     // world-frame moment R_a K Δω
  const Vector3 Gtm = G.transpose() * m;
  if (g != nullptr) {
    g->segment<3>(0) = -Gtm;
    g->segment<3>(3) = Gtm;
  }
  if (H != nullptr) {
    const Matrix3 RaG = Ra.transpose() * G;  // l ∂ω/∂β
    Matrix3 S = RaG.transpose() * stiffness.asDiagonal() * RaG / rest_length;
    S = 0.5 * (S + S.transpose()).eval();  // Gᵀ R_a K R_aᵀ G / l, symmetric up to round-off
    const Matrix3 N = -C * so3::hat(m);
    const double mc = m.dot(so3::vee(C));
    const Matrix3 diag = S + 0.25 * (N + N.transpose()) - mc * Matrix3::Identity();
    const Matrix3 mixed = -S - 0.5 * N + mc * Matrix3::Identity();
    H->block<3, 3>(0, 0) = diag;
    H->block<3, 3>(3, 3) = diag;
    H->block<3, 3>(0, 3) = mixed;
    H->block<3, 3>(3, 0) = mixed.transpose();
  }
  return value;
}

}  // namespace liedyn

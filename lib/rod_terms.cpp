#include "rod_terms.hpp"

#include <cmath>

#include "so3.hpp"
#include "spring.hpp"

namespace liedyn {

namespace {

// vee(R_aᵀ R_b)/l, shared by darboux_vector and RodBendTwist (see the former).
inline Vector3 darboux(const Matrix3& Ra, const Matrix3& Rb, double rest_length) {
  // vee(Q) = ½ (Q₃₂ − Q₂₃, Q₁₃ − Q₃₁, Q₂₁ − Q₁₂),  Q_ij = a_i · b_j  (a_i, b_j the columns
  // of R_a, R_b): six dot products rather than the whole of R_aᵀ R_b. Q_ij − Q_ji is then
  // exactly 0 when R_a = R_b, and RodBendTwist computes ω here too, so Δω = 0 exactly at
  // the rest shape.
  const auto Q = [&](int i, int j) { return Ra.col(i).dot(Rb.col(j)); };
  return (0.5 / rest_length) * Vector3(Q(2, 1) - Q(1, 2), Q(0, 2) - Q(2, 0), Q(1, 0) - Q(0, 1));
}

}  // namespace

Vector3 darboux_vector(const Matrix3& Ra, const Matrix3& Rb, double rest_length) {
  return darboux(Ra, Rb, rest_length);
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
  edge_derivatives(f, K, g, H);
  return value;
}

double RodShear::evaluate(const State& q, LocalGradient<3>* g, LocalHessian<3>* H) const {
  const Vector3 e = q.points[node1] - q.points[node0];
  const double L = e.norm();
  const Vector3 t = q.rotations[edge] * material_axis;  // R a
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
  const Vector3 txd = t.cross(d);
  if (g != nullptr) {
    const Vector3 g_e = -c / L * Pt;  // ∂Ψ/∂e = −c P t / L
    g->segment<3>(0) = -g_e;
    g->segment<3>(3) = g_e;
    g->segment<3>(6) = -c * txd;  // DΨ/DR = −c t × d
  }
  if (H != nullptr) {
    const Matrix3 dt = d * t.transpose();
    const Matrix3 dtS = dt + dt.transpose();  // d tᵀ + t dᵀ (exactly symmetric)
    // ∂²Ψ/∂e² = c [d tᵀ + t dᵀ + a (I − 3 d dᵀ)] / L²
    const Matrix3 H_ee = c / (L * L) * (dtS + a * (Matrix3::Identity() - 3.0 * d * d.transpose()));
    // ∂²Ψ/∂θ∂e = −c hat(t) P / L = −c [hat(t) − (t × d) dᵀ] / L
    const Matrix3 H_te = -c / L * (so3::hat(t) - txd * d.transpose());
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
  Matrix3 offset_storage;
  const Matrix3& Rb = rotation1(q, offset_storage);
  const Vector3 dw = darboux(Ra, Rb, rest_length) - rest_darboux;  // Δω = ω − ω̄
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
    // S = Gᵀ R_a K R_aᵀ G / l = W (K/l) Wᵀ,  W = Gᵀ R_a = (l ∂ω/∂β)ᵀ: each entry on and
    // below the diagonal once, mirrored above (exactly symmetric, and cheaper than a
    // product followed by ½ (S + Sᵀ)).
    const Matrix3 W = G.transpose() * Ra;
    const Matrix3 WK = W * ((1.0 / rest_length) * stiffness).asDiagonal();
    Matrix3 S;
    for (int j = 0; j < 3; ++j) {
      for (int i = j; i < 3; ++i) S(i, j) = S(j, i) = WK.row(i).dot(W.row(j));
    }
    // N = −C hat(m): row k of C hat(m) is (row k of C) × m, so row k of N is m × (row k of C).
    Matrix3 N;
    for (int k = 0; k < 3; ++k) N.row(k) = m.cross(C.row(k).transpose()).transpose();
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

void RodBendTwist::parameter_jacobians(const State& q, Eigen::Matrix<double, 6, 3>* d_rest_darboux,
                                       Eigen::Matrix<double, 6, 3>* d_stiffness) const {
  const Matrix3& Ra = q.rotations[edge0];
  Matrix3 offset_storage;
  const Matrix3& Rb = rotation1(q, offset_storage);
  const Matrix3 C = Rb * Ra.transpose();
  const Matrix3 W = 0.5 * (C.trace() * Matrix3::Identity() - C).transpose() * Ra;  // Gᵀ R_a
  if (d_rest_darboux != nullptr) {
    const Matrix3 WK = W * stiffness.asDiagonal();
    *d_rest_darboux << WK, -WK;
  }
  if (d_stiffness != nullptr) {
    const Vector3 dw = darboux(Ra, Rb, rest_length) - rest_darboux;
    const Matrix3 Wdw = W * dw.asDiagonal();
    *d_stiffness << -Wdw, Wdw;
  }
}

// ---------------------------------------------------------------------------------------
// Residual forms (derivations in rod_terms.hpp). Each r is built from the same intermediates
// as evaluate()'s value, so ½‖r‖² equals it to round-off.

void RodStretch::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const Vector3 e = q.points[node1] - q.points[node0];
  const double L = e.norm();
  const double s = std::sqrt(stiffness / rest_length);  // √(k_s/l)
  r(0) = s * (L - rest_length);                         // √(k_s/l) (‖e‖ − l)
  if (J == nullptr) return;
  if (!(L > 0.0)) {
    J->setZero();  // no direction: J = 0, as evaluate()'s gradient is 0 (rod_terms.hpp)
    return;
  }
  const Vector3 sn = (s / L) * e;  // √(k_s/l) n
  J->leftCols<3>() = -sn.transpose();
  J->rightCols<3>() = sn.transpose();
}

void RodShear::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const Vector3 e = q.points[node1] - q.points[node0];
  const double L = e.norm();
  const Vector3 t = q.rotations[edge] * material_axis;  // R a
  const double c = 0.5 * stiffness * rest_length;
  if (!(L > 0.0)) {
    // Coincident nodes: ½‖r‖² = c, evaluate()'s value there; J = 0, its zero gradient.
    r = -std::sqrt(2.0 * c) * t;
    if (J != nullptr) J->setZero();
    return;
  }
  const double sqrt_c = std::sqrt(c);
  const Vector3 d = e / L;
  r = sqrt_c * (d - t);  // √c (d − t)
  if (J != nullptr) {
    // ∂r/∂e = √c P/L, P = I − d dᵀ;  ∂r/∂θ = √c hat(t)
    const Matrix3 A = (sqrt_c / L) * (Matrix3::Identity() - d * d.transpose());
    J->block<3, 3>(0, 0) = -A;
    J->block<3, 3>(0, 3) = A;
    J->block<3, 3>(0, 6) = sqrt_c * so3::hat(t);
  }
}

void RodBendTwist::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const Matrix3& Ra = q.rotations[edge0];
  Matrix3 offset_storage;
  const Matrix3& Rb = rotation1(q, offset_storage);
  const Vector3 dw = darboux(Ra, Rb, rest_length) - rest_darboux;  // Δω = ω − ω̄
  r = (rest_length * stiffness).cwiseSqrt().cwiseProduct(dw);      // √l K^½ Δω
  if (J != nullptr) {
    const Matrix3 C = Rb * Ra.transpose();
    const Matrix3 G = 0.5 * (C.trace() * Matrix3::Identity() - C);  // vee(hat(u) C) = G u
    // W = √l K^½ ∂ω/∂β = √l K^½ R_aᵀ G / l = diag(√(K/l)) R_aᵀ G;  ∂ω/∂α = −∂ω/∂β
    const Matrix3 W = (stiffness / rest_length).cwiseSqrt().asDiagonal() * (Ra.transpose() * G);
    J->leftCols<3>() = -W;
    J->rightCols<3>() = W;
  }
}

void RodBendTwist::add_parameter_adjoint(const State& q, int frame, const LocalGradient<2>& z,
                                         Eigen::VectorXd& dgamma) const {
  const int slot = rest_control.slot_at(frame);
  if (slot < 0 && stiffness_slot < 0) return;
  Eigen::Matrix<double, 6, 3> d_rest, d_stiffness;
  parameter_jacobians(q, slot >= 0 ? &d_rest : nullptr, stiffness_slot >= 0 ? &d_stiffness : nullptr);
  if (slot >= 0) dgamma.segment<3>(slot) += d_rest.transpose() * z;
  if (stiffness_slot >= 0) dgamma.segment<3>(stiffness_slot) += d_stiffness.transpose() * z;
}

}  // namespace liedyn

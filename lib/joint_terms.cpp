#include "joint_terms.hpp"

#include <cmath>

#include "point_pair.hpp"
#include "so3.hpp"

namespace liedyn {

namespace {

// c(t) of H_φ = I + c hat(φ)² (header), with its series below t = 1e-3, where the closed form
// loses digits to cancellation (1/t² against cot(t/2)/(2t)).
double weld_curvature_coefficient(double t) {
  if (t < 1e-3) return 1.0 / 12.0 + t * t / 720.0;
  return 1.0 / (t * t) - 1.0 / (2.0 * t * std::tan(0.5 * t));
}

// c'(t)/t for the derivative of J_l⁻¹ (the weld's Lagrangian, header), with its series below
// t = 0.25, where the closed form −2/t⁴ + csc²(t/2)/(4t²) + cot(t/2)/(2t³) loses digits to
// cancellation (720 eps/t⁴ relative); the series' first omitted term is below 1e-10 there.
double weld_curvature_slope(double t) {
  const double t2 = t * t;
  if (t < 0.25) return 1.0 / 360.0 + t2 / 7560.0 + t2 * t2 / 201600.0 + t2 * t2 * t2 / 5987520.0;
  const double s = std::sin(0.5 * t);
  return -2.0 / (t2 * t2) + 1.0 / (4.0 * t2 * s * s) + 1.0 / (2.0 * t2 * t * std::tan(0.5 * t));
}

// R_aᵀ v: a world vector in the body coordinates of end a (v itself without a rotation).
Vector3 in_body_a(const State& q, int rotation_a, const Vector3& v) {
  return rotation_a < 0 ? v : Vector3(q.rotations[rotation_a].transpose() * v);
}

// The adjoint's Lagrangian of an exact part (header): λᵀc + ½ρ‖c‖², its gradient Jᵀ(λ + ρc)
// and the Gauss–Newton part ρ JᵀJ of its Hessian; the term adds ∇²(λᵀc). The penalty's own
// curvature ρ ∇²(cᵀc)/2 is left out: it vanishes with c, which is at the tolerance there, and
// ρ c would otherwise weigh in beside λ (ρ ≈ 10⁴ m/h², so ρ·1e-9 is not small).
template <class Term>
double lagrangian(const Term& t, const State& q, LocalGradient<Term::kBlocks>* g,
                  LocalHessian<Term::kBlocks>* H) {
  typename Term::ConstraintJacobian J;
  const Vector3 c = t.constraint(q, &J);
  if (g != nullptr) *g = J.transpose() * (t.multiplier + t.stiffness * c);
  if (H != nullptr) *H = t.stiffness * J.transpose() * J;
  return t.multiplier.dot(c) + 0.5 * t.stiffness * c.squaredNorm();
}

// A motor's value and derivatives: the sum of its ends' loads (a ConstantTorque or
// ConstantForce each, over its own blocks: the two do not couple), end a's blocks first, then
// end b's (zero for the world, load_b null).
template <class Load, int B>
double sum_of_end_loads(const Load& load_a, const Load* load_b, const State& q, LocalGradient<B>* g,
                        LocalHessian<B>* H) {
  constexpr int E = Load::kBlocks;
  static_assert(B == 2 * E);
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  LocalGradient<E> g_end;
  LocalHessian<E> H_end;
  double value = 0.0;
  for (int end = 0; end < 2; ++end) {
    const Load* load = end == 0 ? &load_a : load_b;
    if (load == nullptr) break;
    value += load->evaluate(q, g != nullptr ? &g_end : nullptr, H != nullptr ? &H_end : nullptr);
    if (g != nullptr) g->template segment<3 * E>(3 * E * end) = g_end;
    if (H != nullptr) H->template block<3 * E, 3 * E>(3 * E * end, 3 * E * end) = H_end;
  }
  return value;
}

}  // namespace

AttachedPoint JointPoint::shifted_a() const {
  AttachedPoint shifted = a;
  shifted.local -= shift;
  return shifted;
}

double JointPoint::evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
  if (adjoint) {  // + ∇²(λᵀc): the rotated points' curvature (point_pair.hpp)
    const double value = lagrangian(*this, q, g, H);
    if (H != nullptr) {
      H->block<3, 3>(3, 3) += rotated_point_curvature(a.lever(q), -multiplier);
      H->block<3, 3>(9, 9) += rotated_point_curvature(b.lever(q), multiplier);
    }
    return value;
  }
  const AttachedPoint a_s = shifted_a();
  const Vector3 d = b.position(q) - a_s.position(q);
  if (g != nullptr || H != nullptr) {
    // V = ½ k ‖d‖²: ∂V/∂d = k d, ∂²V/∂d² = k I (point_pair.hpp maps them to the blocks).
    point_pair_derivatives(a_s.lever(q), b.lever(q), stiffness * d,
                           stiffness * Matrix3::Identity(), g, H);
  }
  return 0.5 * stiffness * d.squaredNorm();
}

Vector3 JointPoint::force(const State& q) const {
  return stiffness * (b.position(q) - shifted_a().position(q));
}

Vector3 JointPoint::constraint(const State& q, ConstraintJacobian* J) const {
  if (J != nullptr) {
    *J << -Matrix3::Identity(), so3::hat(a.lever(q)), Matrix3::Identity(), -so3::hat(b.lever(q));
  }
  return b.position(q) - a.position(q);
}

void JointPoint::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const AttachedPoint a_s = shifted_a();
  const double s = std::sqrt(stiffness);
  r = s * (b.position(q) - a_s.position(q));
  if (J != nullptr) {
    *J << -s * Matrix3::Identity(), s * so3::hat(a_s.lever(q)), s * Matrix3::Identity(),
        -s * so3::hat(b.lever(q));
  }
}

double JointPoint::violation(const State& q) const {
  return constraint(q, nullptr).lpNorm<Eigen::Infinity>();
}

void JointPoint::update_multiplier(const State& q) {
  shift += in_body_a(q, a.rotation, constraint(q, nullptr));
}

Vector3 JointLine::line(const State& q, const Vector3& w, ConstraintJacobian* J, const Vector3* mu,
                        LocalHessian<4>* H) const {
  const Matrix3& R_a = q.rotations[a.rotation];
  const Vector3 n = R_a * axis_a;
  const Vector3 d = b.position(q) - a.position(q);
  const Vector3 r_a = a.lever(q), r_b = b.lever(q);
  const Matrix3 hat_n = so3::hat(n);
  if (J != nullptr) {
    *J << -hat_n, hat_n * so3::hat(r_a) + n * d.transpose() - n.dot(d) * Matrix3::Identity() - so3::hat(w),
        hat_n, -hat_n * so3::hat(r_b);
  }
  if (H != nullptr && mu != nullptr) {
    const Vector3 mu_x_n = mu->cross(n);
    H->block<3, 3>(3, 3) += rotated_point_curvature(n, d.cross(*mu)) +
                            rotated_point_curvature(r_a, -mu_x_n) + rotated_point_curvature(w, *mu);
    H->block<3, 3>(9, 9) += rotated_point_curvature(r_b, mu_x_n);
    // The bilinear −δdᵀ hat(μ) hat(n) θ_a: Dᵀ A into the θ_a column, its transpose the row.
    const Matrix3 A = -so3::hat(*mu) * hat_n;
    Eigen::Matrix<double, 3, 12> D;
    D << -Matrix3::Identity(), so3::hat(r_a), Matrix3::Identity(), -so3::hat(r_b);
    const Eigen::Matrix<double, 12, 3> DtA = D.transpose() * A;
    H->block<12, 3>(0, 3) += DtA;
    H->block<3, 12>(3, 0) += DtA.transpose();
  }
  return n.cross(d) + w;
}

double JointLine::evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
  if (adjoint) {
    const double value = lagrangian(*this, q, g, H);
    if (H != nullptr) line(q, Vector3::Zero(), nullptr, &multiplier, H);
    return value;
  }
  const Vector3 w = q.rotations[a.rotation] * shift;
  ConstraintJacobian J;
  const bool derivatives = g != nullptr || H != nullptr;
  const Vector3 c = line(q, w, derivatives ? &J : nullptr, nullptr, nullptr);
  if (g != nullptr) *g = stiffness * J.transpose() * c;
  if (H != nullptr) {
    *H = stiffness * J.transpose() * J;
    const Vector3 mu = stiffness * c;
    line(q, w, nullptr, &mu, H);
  }
  return 0.5 * stiffness * c.squaredNorm();
}

void JointLine::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const double s = std::sqrt(stiffness);
  r = s * line(q, q.rotations[a.rotation] * shift, J, nullptr, nullptr);
  if (J != nullptr) *J *= s;
}

double JointLine::violation(const State& q) const {
  return constraint(q, nullptr).lpNorm<Eigen::Infinity>();
}

void JointLine::update_multiplier(const State& q) {
  shift += in_body_a(q, a.rotation, constraint(q, nullptr));
}

Vector3 JointLine::force(const State& q) const {
  return stiffness * line(q, q.rotations[a.rotation] * shift, nullptr, nullptr, nullptr);
}

Vector3 JointLine::constraint(const State& q, ConstraintJacobian* J) const {
  return line(q, Vector3::Zero(), J, nullptr, nullptr);
}

double JointAlignment::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  if (adjoint) {  // + ∇²(λᵀ(a − b)): λ·(½ θ × (θ × a)) is the rotated-point curvature
    const double value = lagrangian(*this, q, g, H);
    if (H != nullptr) {
      H->block<3, 3>(0, 0) += rotated_point_curvature(rotation_or_identity(q, rotation_a) * axis_a, multiplier);
      H->block<3, 3>(3, 3) += rotated_point_curvature(rotation_or_identity(q, rotation_b) * axis_b, -multiplier);
    }
    return value;
  }
  const Vector3 a = rotation_or_identity(q, rotation_a) * (axis_a + shift);
  const Vector3 b = rotation_or_identity(q, rotation_b) * axis_b;
  const double ab = a.dot(b);
  if (g != nullptr) {
    const Vector3 axb = a.cross(b);
    g->segment<3>(0) = -stiffness * axb;
    g->segment<3>(3) = stiffness * axb;
  }
  if (H != nullptr) {
    const Matrix3 diagonal = -stiffness * (0.5 * (a * b.transpose() + b * a.transpose()) -
                                           ab * Matrix3::Identity());
    const Matrix3 mixed = stiffness * so3::hat(a) * so3::hat(b);
    H->block<3, 3>(0, 0) = diagonal;
    H->block<3, 3>(3, 3) = diagonal;
    H->block<3, 3>(0, 3) = mixed;
    H->block<3, 3>(3, 0) = mixed.transpose();
  }
  // ½ k ‖a − b‖² rather than k (1 − a·b): no cancellation for nearly aligned axes.
  return 0.5 * stiffness * (a - b).squaredNorm();
}

Vector3 JointAlignment::force(const State& q) const {
  return stiffness * (rotation_or_identity(q, rotation_a) * (axis_a + shift) -
                      rotation_or_identity(q, rotation_b) * axis_b);
}

Vector3 JointAlignment::constraint(const State& q, ConstraintJacobian* J) const {
  const Vector3 a = rotation_or_identity(q, rotation_a) * axis_a;
  const Vector3 b = rotation_or_identity(q, rotation_b) * axis_b;
  if (J != nullptr) *J << -so3::hat(a), so3::hat(b);
  return a - b;
}

void JointAlignment::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const Vector3 a = rotation_or_identity(q, rotation_a) * (axis_a + shift);
  const Vector3 b = rotation_or_identity(q, rotation_b) * axis_b;
  const double s = std::sqrt(stiffness);
  r = s * (a - b);
  if (J != nullptr) {
    J->block<3, 3>(0, 0) = -s * so3::hat(a);
    J->block<3, 3>(0, 3) = s * so3::hat(b);
  }
}

double JointAlignment::violation(const State& q) const {
  return constraint(q, nullptr).lpNorm<Eigen::Infinity>();
}

void JointAlignment::update_multiplier(const State& q) {
  shift += in_body_a(q, rotation_a, constraint(q, nullptr));
}

Vector3 JointWeld::relative_rotation(const State& q, Matrix3* E) const {
  const Matrix3 relative = rotation_or_identity(q, rotation_a) * frame_a * shift *
                           (rotation_or_identity(q, rotation_b) * frame_b).transpose();
  if (E != nullptr) *E = relative;
  return so3::log(relative);
}

double JointWeld::violation(const State& q) const {
  return constraint(q, nullptr).lpNorm<Eigen::Infinity>();
}

void JointWeld::update_multiplier(const State& q) {
  const Matrix3 F_a = rotation_or_identity(q, rotation_a) * frame_a;
  const Matrix3 F_b = rotation_or_identity(q, rotation_b) * frame_b;
  shift = so3::orthonormalize(F_b.transpose() * F_a * shift);
}

double JointWeld::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  if (adjoint) {  // + ∇²(λᵀφ) (header)
    const double value = lagrangian(*this, q, g, H);
    if (H != nullptr) {
      const Matrix3 E = rotation_or_identity(q, rotation_a) * frame_a *
                        (rotation_or_identity(q, rotation_b) * frame_b).transpose();
      const Vector3 phi = so3::log(E);
      const Matrix3 J_inverse = so3::left_jacobian_inverse(phi);
      const double t = phi.norm();
      const double c = weld_curvature_coefficient(t), slope = weld_curvature_slope(t);
      const Matrix3 P = so3::hat(phi);
      // M = sym(M̃), row i of M̃ = λᵀ D(J_l⁻¹)(φ)[J_l⁻¹ e_i].
      Matrix3 M;
      for (int i = 0; i < 3; ++i) {
        const Vector3 w = J_inverse.col(i);
        const Matrix3 W = so3::hat(w);
        const Matrix3 D = -0.5 * W + slope * phi.dot(w) * P * P + c * (W * P + P * W);
        M.row(i) = multiplier.transpose() * D;
      }
      M = (0.5 * (M + M.transpose())).eval();
      const Matrix3 mixed = -M * E + 0.5 * so3::hat(J_inverse.transpose() * multiplier) * E;
      H->block<3, 3>(0, 0) += M;
      H->block<3, 3>(3, 3) += E.transpose() * M * E;
      H->block<3, 3>(0, 3) += mixed;
      H->block<3, 3>(3, 0) += mixed.transpose();
    }
    return value;
  }
  Matrix3 E;
  const Vector3 phi = relative_rotation(q, &E);
  if (g != nullptr) {
    g->segment<3>(0) = stiffness * phi;
    g->segment<3>(3) = -stiffness * phi;
  }
  if (H != nullptr) {
    const Matrix3 hat_phi = so3::hat(phi);
    const Matrix3 H_phi =
        Matrix3::Identity() + weld_curvature_coefficient(phi.norm()) * hat_phi * hat_phi;
    const Matrix3 mixed = stiffness * (-H_phi * E + 0.5 * hat_phi * E);
    H->block<3, 3>(0, 0) = stiffness * H_phi;
    H->block<3, 3>(3, 3) = stiffness * H_phi;
    H->block<3, 3>(0, 3) = mixed;
    H->block<3, 3>(3, 0) = mixed.transpose();
  }
  return 0.5 * stiffness * phi.squaredNorm();
}

Vector3 JointWeld::force(const State& q) const { return stiffness * relative_rotation(q); }

Vector3 JointWeld::constraint(const State& q, ConstraintJacobian* J) const {
  const Matrix3 F_a = rotation_or_identity(q, rotation_a) * frame_a;
  const Matrix3 F_b = rotation_or_identity(q, rotation_b) * frame_b;
  const Matrix3 E = F_a * F_b.transpose();
  const Vector3 phi = so3::log(E);
  if (J != nullptr) {
    const Matrix3 J_inverse = so3::left_jacobian_inverse(phi);
    *J << J_inverse, -J_inverse * E;
  }
  return phi;
}

void JointWeld::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  Matrix3 E;
  const Vector3 phi = relative_rotation(q, &E);
  const double s = std::sqrt(stiffness);
  r = s * phi;
  if (J != nullptr) {
    const Matrix3 J_inverse = so3::left_jacobian_inverse(phi);
    J->block<3, 3>(0, 0) = s * J_inverse;
    J->block<3, 3>(0, 3) = -s * J_inverse * E;
  }
}

void JointMotor::begin_step(const State& previous, const Step&) {
  R_previous_a = previous.rotations[rotation_a];
  if (rotation_b >= 0) R_previous_b = previous.rotations[rotation_b];
}

ConstantTorque JointMotor::end_torque(int end) const {
  ConstantTorque t;
  t.rotation = end == 0 ? rotation_a : rotation_b;
  t.R_previous = end == 0 ? R_previous_a : R_previous_b;
  t.torque = (end == 0 ? torque : -torque) * axis();
  t.scale = scale;
  return t;
}

double JointMotor::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  const ConstantTorque on_b = rotation_b >= 0 ? end_torque(1) : ConstantTorque{};
  return sum_of_end_loads<ConstantTorque, kBlocks>(end_torque(0), rotation_b >= 0 ? &on_b : nullptr, q, g, H);
}

void JointMotor::add_step_adjoint(const State& q, const State&, const Step&,
                                  const LocalGradient<2>& z, Eigen::VectorXd& a_previous,
                                  Eigen::VectorXd&) const {
  const ConstantTorque on_a = end_torque(0);
  // τ hat(ê): M = torque_jacobian carries the load scale itself.
  const Matrix3 tau_hat_axis = torque * so3::hat(axis());
  // R_{a,k−1} through P_a, and through ê in both ends' torques (header).
  const Matrix3 dC_a = on_a.previous_jacobian(q) - on_a.torque_jacobian(q) * tau_hat_axis;
  Vector3 into_a = dC_a.transpose() * z.head<3>();
  if (rotation_b >= 0) {
    const ConstantTorque on_b = end_torque(1);
    const Matrix3 dC_b_da = on_b.torque_jacobian(q) * tau_hat_axis;
    into_a += dC_b_da.transpose() * z.tail<3>();
    a_previous.segment<3>(tangent_rotation(q, rotation_b)) +=
        on_b.previous_jacobian(q).transpose() * z.tail<3>();
  }
  a_previous.segment<3>(tangent_rotation(q, rotation_a)) += into_a;
}

void JointMotor::add_parameter_adjoint(const State& q, int frame, const LocalGradient<2>& z,
                                       Eigen::VectorXd& dgamma) const {
  const int slot = control.slot_at(frame);
  if (slot < 0) return;
  const Vector3 e = axis();
  double d = (end_torque(0).torque_jacobian(q) * e).dot(z.head<3>());
  if (rotation_b >= 0) d -= (end_torque(1).torque_jacobian(q) * e).dot(z.tail<3>());
  dgamma(slot) += d;
}

void JointForceMotor::begin_step(const State& previous, const Step&) {
  R_previous_a = previous.rotations[a.rotation];
}

ConstantForce JointForceMotor::end_force(int end) const {
  ConstantForce f;
  f.at = end == 0 ? a : b;
  f.force = (end == 0 ? force : -force) * axis();
  f.scale = scale;
  return f;
}

double JointForceMotor::evaluate(const State& q, LocalGradient<4>* g, LocalHessian<4>* H) const {
  const ConstantForce on_b = end_force(1);
  return sum_of_end_loads<ConstantForce, kBlocks>(end_force(0), &on_b, q, g, H);
}

void JointForceMotor::add_step_adjoint(const State& q, const State&, const Step&,
                                       const LocalGradient<4>& z, Eigen::VectorXd& a_previous,
                                       Eigen::VectorXd&) const {
  // f hat(ê) through each end's M = force_jacobian (which carries the load scale), header.
  const Matrix3 f_hat_axis = force * so3::hat(axis());
  const Eigen::Matrix<double, 6, 3> dC_a = -end_force(0).force_jacobian(q) * f_hat_axis;
  const Eigen::Matrix<double, 6, 3> dC_b = end_force(1).force_jacobian(q) * f_hat_axis;
  a_previous.segment<3>(tangent_rotation(q, a.rotation)) +=
      dC_a.transpose() * z.head<6>() + dC_b.transpose() * z.tail<6>();
}

void JointForceMotor::add_parameter_adjoint(const State& q, int frame, const LocalGradient<4>& z,
                                            Eigen::VectorXd& dgamma) const {
  const int slot = control.slot_at(frame);
  if (slot < 0) return;
  const Vector3 e = axis();
  dgamma(slot) += (end_force(0).force_jacobian(q) * e).dot(z.head<6>()) -
                  (end_force(1).force_jacobian(q) * e).dot(z.tail<6>());
}

}  // namespace liedyn

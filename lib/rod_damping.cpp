#include "rod_damping.hpp"

#include <cmath>

#include "so3.hpp"
#include "spring.hpp"

namespace liedyn {

void RodStretchDamping::begin_step(const State& previous, const Step&) {
  previous_length = (previous.points[node1] - previous.points[node0]).norm();
}

double RodStretchDamping::evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const {
  const auto [value, f, K] = length_spring(q.points[node1] - q.points[node0], rate(), previous_length);
  edge_derivatives(f, K, g, H);
  return value;
}

void RodStretchDamping::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  const Vector3 e = q.points[node1] - q.points[node0];
  const double L = e.norm();
  const double root = std::sqrt(rate());
  r(0) = root * (L - previous_length);
  if (J == nullptr) return;
  if (L > 0.0) {
    const Vector3 n = e / L;
    J->leftCols<3>() = -root * n.transpose();
    J->rightCols<3>() = root * n.transpose();
  } else {
    J->setZero();  // as length_spring's gradient at e = 0
  }
}

Eigen::Matrix<double, 6, 6> RodStretchDamping::previous_jacobian(const State& q,
                                                                 const State& previous) const {
  Eigen::Matrix<double, 6, 6> out = Eigen::Matrix<double, 6, 6>::Zero();
  const Vector3 e = q.points[node1] - q.points[node0];
  const Vector3 e_previous = previous.points[node1] - previous.points[node0];
  const double L = e.norm(), L_previous = e_previous.norm();
  if (!(L > 0.0) || !(L_previous > 0.0)) return out;
  const Matrix3 df = -rate() * (e / L) * (e_previous / L_previous).transpose();  // ∂f/∂x̂_{i+1}
  out.block<3, 3>(0, 0) = df;   // C_i = −f: −(∂f/∂x̂_i) = −(−df)
  out.block<3, 3>(0, 3) = -df;
  out.block<3, 3>(3, 0) = -df;
  out.block<3, 3>(3, 3) = df;
  return out;
}

void RodStretchDamping::add_step_adjoint(const State& q, const State& previous, const Step&,
                                         const LocalGradient<2>& z, Eigen::VectorXd& a_previous,
                                         Eigen::VectorXd&) const {
  const Eigen::Matrix<double, 6, 1> w = previous_jacobian(q, previous).transpose() * z;
  // Clamped nodes (offset −1) are not DOFs: nothing flows back into them.
  if (offsets[0] >= 0) a_previous.segment<3>(tangent_point(node0)) += w.head<3>();
  if (offsets[1] >= 0) a_previous.segment<3>(tangent_point(node1)) += w.tail<3>();
}

void RodBendTwistDamping::set(int edge0, int edge1, double bending_length) {
  form.edge0 = edge0;
  form.edge1 = edge1;
  form.rest_length = bending_length;
  form.stiffness = damping / time_step;
}

void RodBendTwistDamping::begin_step(const State& previous, const Step&) {
  Matrix3 storage;
  form.rest_darboux = darboux_vector(previous.rotations[form.edge0], form.rotation1(previous, storage),
                                     form.rest_length);
}

Eigen::Matrix<double, 6, 6> RodBendTwistDamping::previous_jacobian(const State& q,
                                                                   const State& previous) const {
  Eigen::Matrix<double, 6, 3> d_rest;
  form.parameter_jacobians(q, &d_rest, nullptr);  // ∂C/∂ω̂
  const Matrix3& Ra = previous.rotations[form.edge0];
  Matrix3 storage;
  const Matrix3 C = form.rotation1(previous, storage) * Ra.transpose();
  const Matrix3 dw = Ra.transpose() * (0.5 * (C.trace() * Matrix3::Identity() - C)) / form.rest_length;
  Eigen::Matrix<double, 6, 6> out;
  out.leftCols<3>() = -d_rest * dw;  // ∂ω̂/∂θ̂_a = −R̂_aᵀ Ĝ/w
  out.rightCols<3>() = d_rest * dw;  // ∂ω̂/∂θ̂_b = R̂_aᵀ Ĝ/w
  return out;
}

void RodBendTwistDamping::add_step_adjoint(const State& q, const State& previous, const Step&,
                                           const LocalGradient<2>& z, Eigen::VectorXd& a_previous,
                                           Eigen::VectorXd&) const {
  const Eigen::Matrix<double, 6, 1> w = previous_jacobian(q, previous).transpose() * z;
  // Clamped edges (offset −1) are not DOFs: nothing flows back into them.
  if (offsets[0] >= 0) a_previous.segment<3>(tangent_rotation(q, form.edge0)) += w.head<3>();
  if (offsets[1] >= 0) a_previous.segment<3>(tangent_rotation(q, form.edge1)) += w.tail<3>();
}

void RodShearDamping::set(int node0, int node1, int edge, double rest_length) {
  form.node0 = node0;
  form.node1 = node1;
  form.edge = edge;
  form.rest_length = rest_length;
  form.stiffness = damping / time_step;
}

void RodShearDamping::begin_step(const State& previous, const Step&) {
  const Vector3 e = previous.points[form.node1] - previous.points[form.node0];
  const double L = e.norm();
  // A crushed edge has no direction: no shear to lag, the elastic term's axis instead.
  form.material_axis = L > 0.0 ? Vector3(previous.rotations[form.edge].transpose() * (e / L))
                               : Vector3::UnitZ();
}

Eigen::Matrix<double, 9, 9> RodShearDamping::previous_jacobian(const State& q,
                                                               const State& previous) const {
  Eigen::Matrix<double, 9, 9> out = Eigen::Matrix<double, 9, 9>::Zero();
  const Vector3 e = q.points[form.node1] - q.points[form.node0];
  const Vector3 e_previous = previous.points[form.node1] - previous.points[form.node0];
  const double L = e.norm(), L_previous = e_previous.norm();
  if (!(L > 0.0) || !(L_previous > 0.0)) return out;  // the form's gradient is 0 / â is fixed
  const double c = 0.5 * form.stiffness * form.rest_length;
  const Matrix3& R = q.rotations[form.edge];
  const Vector3 d = e / L;
  const Matrix3 P = Matrix3::Identity() - d * d.transpose();
  Eigen::Matrix<double, 9, 3> d_axis;  // ∂C/∂â
  d_axis.topRows<3>() = (c / L) * P * R;
  d_axis.middleRows<3>(3) = -d_axis.topRows<3>();
  d_axis.bottomRows<3>() = c * so3::hat(d) * R;
  const Matrix3 Rt_previous = previous.rotations[form.edge].transpose();
  const Vector3 d_previous = e_previous / L_previous;
  const Matrix3 da_dx = Rt_previous * (Matrix3::Identity() - d_previous * d_previous.transpose()) / L_previous;
  out.middleCols<3>(0) = -d_axis * da_dx;
  out.middleCols<3>(3) = d_axis * da_dx;
  out.middleCols<3>(6) = d_axis * (Rt_previous * so3::hat(d_previous));
  return out;
}

void RodShearDamping::add_step_adjoint(const State& q, const State& previous, const Step&,
                                       const LocalGradient<3>& z, Eigen::VectorXd& a_previous,
                                       Eigen::VectorXd&) const {
  const Eigen::Matrix<double, 9, 1> w = previous_jacobian(q, previous).transpose() * z;
  // Clamped nodes and edges (offset −1) are not DOFs: nothing flows back into them.
  if (offsets[0] >= 0) a_previous.segment<3>(tangent_point(form.node0)) += w.head<3>();
  if (offsets[1] >= 0) a_previous.segment<3>(tangent_point(form.node1)) += w.segment<3>(3);
  if (offsets[2] >= 0) a_previous.segment<3>(tangent_rotation(q, form.edge)) += w.tail<3>();
}

}  // namespace liedyn

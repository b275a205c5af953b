#include "inertia.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "so3.hpp"

namespace liedyn {

Matrix3 rotational_mass(const Matrix3& body_inertia) {
  return 0.5 * body_inertia.trace() * Matrix3::Identity() - body_inertia;
}

Matrix3 psd_sqrt(const Matrix3& A) {
  if (!A.allFinite()) throw std::invalid_argument("psd_sqrt: the matrix has non-finite entries");
  // Iterative (not the closed-form computeDirect) solver: accurate eigenvectors also for
  // (nearly) repeated eigenvalues; this runs once per term, at set-up.
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(0.5 * (A + A.transpose()));
  const Vector3 lambda = eig.eigenvalues();  // ascending
  const double largest = lambda.cwiseAbs().maxCoeff();
  if (lambda(0) < -1e-9 * largest) {
    std::ostringstream os;
    os << "psd_sqrt: the matrix is not positive semi-definite: eigenvalues " << lambda.transpose()
       << " (rule: λ_min ≥ −1e-9 λ_max; for J = ½ tr(I_b) 1 − I_b "
       << "this is the triangle inequality of the inertia I_b)";
    throw std::invalid_argument(os.str());
  }
  // Round-off negatives (see inertia.hpp) → 0.
  const Vector3 root = lambda.cwiseMax(0.0).cwiseSqrt();
  const Matrix3& V = eig.eigenvectors();
  const Matrix3 S = V * root.asDiagonal() * V.transpose();
  return 0.5 * (S + S.transpose());  // exactly symmetric
}

void TranslationalInertia::begin_step(const State& previous, const Step& previous_step) {
  x_tilde = previous.points[point] + previous_step.points[point];
}

double TranslationalInertia::evaluate(const State& q, LocalGradient<1>* g,
                                      LocalHessian<1>* H) const {
  const Vector3 e = q.points[point] - x_tilde;
  if (g != nullptr) *g = mass_over_h2 * e;                          // m/h² (x − x̃)
  if (H != nullptr) *H = mass_over_h2 * LocalHessian<1>::Identity();  // m/h² I
  return 0.5 * mass_over_h2 * e.squaredNorm();
}

void TranslationalInertia::residual(const State& q, Residual& r, ResidualJacobian* J,
                                    const Vector3& load) const {
  if (!(mass_over_h2 > 0.0)) {
    if (!load.isZero(0.0)) {
      std::ostringstream os;
      os << "TranslationalInertia::residual: mass_over_h2 = " << mass_over_h2 << " with a load "
         << load.transpose()
         << " (rule: a load needs mass_over_h2 > 0 to be folded into the square)";
      throw std::invalid_argument(os.str());
    }
    r.setZero();  // a/2 ‖x − x̃‖² = 0
    if (J != nullptr) J->setZero();
    return;
  }
  const double s = std::sqrt(mass_over_h2);                 // √(m/h²)
  r = s * (q.points[point] - x_tilde) - load / s;           // √a (x − x̃ − load/a)
  if (J != nullptr) *J = s * ResidualJacobian::Identity();  // ∂r/∂x = √a I
}

void RotationalInertia::begin_step(const State& previous, const Step& previous_step) {
  const Matrix3& R_prev = previous.rotations[rotation];
  if (variational) {
    R_tilde = R_prev;
    return;
  }
  R_tilde = (2.0 * Matrix3::Identity() - previous_step.rotations[rotation].transpose()) * R_prev;
}

double RotationalInertia::evaluate(const State& q, LocalGradient<1>* g,
                                   LocalHessian<1>* H) const {
  const Matrix3& R = q.rotations[rotation];
  const Matrix3 RJ = R * J_over_h2;  // R J/h²
  if (g != nullptr || H != nullptr) {
    const Matrix3 M = RJ * R_tilde.transpose();  // M = R J R̃ᵀ/h² = S + A
    if (g != nullptr) *g = 2.0 * so3::vee(M);    // (12): vee takes A
    if (H != nullptr) {
      const Matrix3 S = 0.5 * (M + M.transpose());
      *H = S.trace() * Matrix3::Identity() - S;  // (13)
    }
  }
  // ½ tr(D J Dᵀ)/h² = ½ Σₖₗ (J/h²)ₖₗ dₖ·dₗ,  dₖ the columns of D = R − R̃. Column by column
  // rather than as (D J) ⊙ D: a 3×3 temporary D, stored in 2-wide pieces across its columns
  // and read back column-wise by the product, stalled store forwarding (−38 % for this term).
  const Vector3 d[3] = {R.col(0) - R_tilde.col(0), R.col(1) - R_tilde.col(1),
                        R.col(2) - R_tilde.col(2)};
  double value = 0.0;
  for (int k = 0; k < 3; ++k) {
    for (int l = 0; l < 3; ++l) value += J_over_h2(l, k) * d[l].dot(d[k]);
  }
  return 0.5 * value;
}

void RotationalInertia::residual(const State& q, Residual& r, ResidualJacobian* J,
                                 const Matrix3& shift) const {
  const Matrix3& R = q.rotations[rotation];
  // r = vec((R − R̃ − S) J^½/h), column k in rows 3k…3k+2.
  Eigen::Map<Matrix3>(r.data()) = (R - R_tilde - shift) * sqrt_J_over_h;
  if (J != nullptr) {
    const Matrix3 C = R * sqrt_J_over_h;  // columns c_k
    for (int k = 0; k < 3; ++k) {
      // ∂/∂θ (exp(θ) c_k) = ∂/∂θ (θ × c_k) = −hat(c_k)
      J->block<3, 3>(3 * k, 0) = -so3::hat(C.col(k));
    }
  }
}

void RotationalInertia::step_jacobians(const State& q, const Matrix3& R_previous,
                                       const Matrix3& dR_previous, Matrix3& dC_dR_previous,
                                       Matrix3& dC_ddR_previous) const {
  const Matrix3 B = q.rotations[rotation] * J_over_h2 * R_previous.transpose();
  const Matrix3 X =
      variational ? Matrix3::Identity() : Matrix3(2.0 * Matrix3::Identity() - dR_previous);
  for (int j = 0; j < 3; ++j) {
    const Matrix3 B_hat = B * so3::hat(Vector3::Unit(j));
    dC_dR_previous.col(j) = -2.0 * so3::vee(B_hat * X);
    dC_ddR_previous.col(j) = variational ? Vector3::Zero() : Vector3(-2.0 * so3::vee(B_hat * dR_previous));
  }
}

Matrix3 RotationalInertia::R_tilde_adjoint(const State& q, const Vector3& z) const {
  return -so3::hat(z) * q.rotations[rotation] * J_over_h2;
}

void TranslationalInertia::add_step_adjoint(const State&, const State&, const Step&,
                                            const LocalGradient<1>& z, Eigen::VectorXd& a_previous,
                                            Eigen::VectorXd& da_previous) const {
  const Vector3 w = step_jacobian() * z;  // the Jacobian is symmetric: w = Jᵀ z
  a_previous.segment<3>(tangent_point(point)) += w;
  da_previous.segment<3>(tangent_point(point)) += w;
}

void RotationalInertia::add_step_adjoint(const State& q, const State& previous,
                                         const Step& previous_step, const LocalGradient<1>& z,
                                         Eigen::VectorXd& a_previous,
                                         Eigen::VectorXd& da_previous) const {
  Matrix3 d_previous, d_step;
  step_jacobians(q, previous.rotations[rotation], previous_step.rotations[rotation], d_previous,
                 d_step);
  a_previous.segment<3>(tangent_rotation(q, rotation)) += d_previous.transpose() * z;
  da_previous.segment<3>(tangent_rotation(q, rotation)) += d_step.transpose() * z;
}

}  // namespace liedyn

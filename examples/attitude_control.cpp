// attitude_control: turn a rigid body by 120° about a tilted axis, from rest to rest, with the
// least torque — a direct transcription over SO(3), solved with Ceres and with Ipopt through
// liedyn's SO3Manifold and LieNlp.
//
// Body: inertia I = diag(1, 2, 3) kg m² (body frame). Starts at rest at R_0 = I (identity
// rotation) and must be at rest at R_target = exp(θ_T), θ_T = (2π/3) (1, 2, 2)/3, after
// T = 2 s: N = 40 steps of h = 0.05 s.
//
// Unknowns: R_1 … R_N ∈ SO(3), body angular velocities ω_1 … ω_N and body torques
// τ_0 … τ_{N−1} (R³ each); R_0 = I and ω_0 = 0 are data. Discrete dynamics (Lie-group explicit
// Euler, body-frame increments):
//   R_{k+1} = R_k exp(h ω_k),    ω_{k+1} = ω_k + h I⁻¹ (τ_k − ω_k × I ω_k).
// As residuals, k = 0 … N−1, and at the end:
//   r_k = log(R_k exp(h ω_k) R_{k+1}ᵀ)                (world frame; 0 iff the rotation step holds)
//   s_k = ω_{k+1} − ω_k − h I⁻¹ (τ_k − ω_k × I ω_k)
//   t   = log(R_targetᵀ R_N),   and ω_N.
//
// Three solves:
//   Ceres, soft:  minimise F = ½ w Σ_k (‖r_k‖² + ‖s_k‖²) + ½ Σ_k h ‖τ_k‖² + ½ w (‖t‖² + ‖ω_N‖²),
//                 w = 10⁴ — a least-squares problem, SO3Manifold blocks for the R_k;
//   Ipopt, soft:  the same F as a LieNlp objective (Lie gradient, exact Lie Hessian);
//   Ipopt, hard:  minimise E = ½ Σ_k h ‖τ_k‖² subject to r_k = 0, s_k = 0, t = 0, ω_N = 0 —
//                 the adapter's constraint path (Lie Jacobian, exact Lie Hessian of the
//                 Lagrangian), which is what Ipopt is for.
// The soft problems are one problem solved twice: their objectives and solutions must agree
// tightly. The hard problem is a different one; the comparison with it is loose and exact at
// once: every point satisfying the hard constraints has F = E, so the soft minimum is at most
// the hard one, F_soft ≤ E_hard. (To first order in 1/w, the soft minimiser has residuals c ≈
// λ/w and F_soft ≈ E_hard − ‖λ‖²/(2w), λ the hard problem's multipliers; printed, not tested.)
//
// Lie derivatives (lib/so3.hpp: left perturbations R ← exp(δ) R; so3::exp returns
// J_l(θ) with exp(θ + ε) = exp(J_l(θ) ε) exp(θ); so3::log returns J_l⁻¹(r) with
// log(exp(δ) exp(r)) = r + J_l⁻¹(r) δ + O(δ²); A exp(x) Aᵀ = exp(A x) for a rotation A).
// With D = R_k exp(h ω_k) R_{k+1}ᵀ = exp(r_k):
//   R_k ← exp(δ) R_k:          D ← exp(δ) D                        ⇒ ∂r/∂δ_k     = J_l⁻¹(r),
//   ω_k ← ω_k + η:             D ← exp(R_k J_l(hω_k) h η) D        ⇒ ∂r/∂ω_k     = J_l⁻¹(r) M,
//                              M = h R_k J_l(h ω_k)   (R exp(x) = exp(R x) R: the body-frame
//                              increment is the world-frame one R_k x),
//   R_{k+1} ← exp(δ) R_{k+1}:  D ← D exp(−δ) = exp(−D δ) D        ⇒ ∂r/∂δ_{k+1} = −J_l⁻¹(r) D;
//   ∂t/∂δ_N = J_l⁻¹(t) R_targetᵀ   (R_targetᵀ exp(δ) R_N = exp(R_targetᵀ δ) R_targetᵀ R_N);
//   ∂s/∂ω_k = −I₃ + h I⁻¹ (hat(ω_k) I − hat(I ω_k)),  ∂s/∂τ_k = −h I⁻¹,  ∂s/∂ω_{k+1} = I₃.
//
// Lie Hessians of λᵀr for a multiplier λ ∈ R³ (both solvers' exact Hessians are sums of
// these: F's is Σ w (JᵀJ + Hess(λ = residual)), the Lagrangian's Σ Hess(λ_row block)):
//   * of ξ ↦ λᵀ log(exp(ξ) exp(r)) at ξ = 0: differentiating exp(r + ε(ξ)) = exp(ξ) exp(r)
//     twice gives  K(λ) = −J_l⁻ᵀ C(r, J_l⁻ᵀ λ) J_l⁻¹, with C(r, g) the Hessian of
//     ε ↦ gᵀθ(ε), exp(r + ε) = exp(θ(ε)) exp(r) (liedyn::rotvec::hessian_correction);
//   * r_k is that function of ξ(δ_k, η, δ_{k+1}) with exp(ξ) = exp(δ_k) exp(R_k θ(hη))
//     exp(−D δ_{k+1}), θ(ε) = J_l(hω_k) ε + ½ θ''[ε, ε]. By BCH, exp(a) exp(b) exp(c) =
//     exp(a + b + c + ½ (a×b + a×c + b×c) + O(3)), so with μ = J_l⁻ᵀ(r) λ (the gradient in ξ):
//       Hess = Lᵀ K(λ) L,  L = [I, M, −D],  plus
//       (δ_k, ω_k):      −½ hat(μ) M         (from ½ μ·(δ_k × M η)),
//       (δ_k, δ_{k+1}):   ½ hat(μ) D         (from ½ μ·(δ_k × (−D δ_{k+1}))),
//       (ω_k, δ_{k+1}):   ½ Mᵀ hat(μ) D      (from ½ μ·(M η × (−D δ_{k+1}))),
//       (ω_k, ω_k):       h² C(h ω_k, R_kᵀ μ) (from μᵀ R_k ½ θ''[hη, hη]),
//     and the transposed blocks;
//   * t: R_target K(λ) R_targetᵀ;
//   * s: λᵀ h I⁻¹ (ω × I ω) = −ωᵀ hat(a) I ω with a = h I⁻¹ λ, so (ω_k, ω_k): I hat(a) − hat(a) I.
// The example checks every one of these against finite differences before solving
// (lie_check.hpp) and exits with status 1 if any disagrees by more than 1e-6 relative.
//
// Exit status 0 only if the derivative checks pass; all three solves converged (Ceres:
// IsSolutionUsable and termination CONVERGENCE; Ipopt: converged()); the soft solutions agree
// (objectives to 1e-6 relative; rotations to 1e-5 rad; ω and τ to 1e-5 of their largest
// entry); F_soft ≤ E_hard; the hard solution's constraint violation is below 1e-8; and
// simulating its torques forward with the same discrete dynamics ends within 1e-6 rad of
// R_target with ‖ω_N‖ < 1e-6 rad/s.

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <liedyn/lib/so3.hpp>
#include <liedyn/manifolds/lie_ipopt.hpp>
#include <liedyn/manifolds/rotation_vector.hpp>
#include <liedyn/manifolds/so3_manifold.hpp>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "lie_check.hpp"

namespace {

using liedyn::SO3Manifold;
using liedyn::so3::hat;
using Matrix3 = Eigen::Matrix3d;
using Vector3 = Eigen::Vector3d;
using Vector4 = Eigen::Vector4d;
using Matrix9 = Eigen::Matrix<double, 9, 9>;

constexpr int kSteps = 40;              // N
constexpr double kStep = 0.05;          // h, s: T = N h = 2 s
constexpr double kWeight = 1e4;         // w, of the dynamics and terminal residuals in F
const Vector3 kInertia(1.0, 2.0, 3.0);  // kg m², principal, body frame

Vector3 target_rotation_vector() {
  return (2.0 * std::numbers::pi / 3.0) * Vector3(1.0, 2.0, 2.0) / 3.0;
}

// Acceptance thresholds (see the top).
constexpr double kDerivativeTolerance = 1e-6;  // relative, analytic vs central differences
constexpr double kObjectiveAgreement = 1e-6;   // relative, Ceres vs Ipopt on F
constexpr double kSolutionAgreement = 1e-5;    // rad, and relative for ω and τ
constexpr double kConstraintViolation = 1e-8;  // hard problem
constexpr double kSimulationTolerance = 1e-6;  // rad and rad/s, hard torques simulated

// ---------------------------------------------------------------------------------------------
// The trajectory, and the LiePoint layout of its unknowns:
//   rotations  R_1 … R_N                        tangent columns 3(k − 1)
//   vector     [ω_1 … ω_N, τ_0 … τ_{N−1}]        tangent columns 3N + 3(k − 1), 6N + 3k.

struct Trajectory {
  std::vector<Matrix3> R;      // R_0 … R_N
  std::vector<Vector3> omega;  // ω_0 … ω_N
  std::vector<Vector3> tau;    // τ_0 … τ_{N−1}
};

int rotation_column(int k) { return k == 0 ? -1 : 3 * (k - 1); }            // −1: R_0 is data
int omega_column(int k) { return k == 0 ? -1 : 3 * kSteps + 3 * (k - 1); }  // −1: ω_0 is data
int tau_column(int k) { return 6 * kSteps + 3 * k; }

Trajectory trajectory_of(const liedyn::LiePoint& x) {
  Trajectory z;
  z.R.push_back(Matrix3::Identity());
  z.omega.push_back(Vector3::Zero());
  for (int k = 1; k <= kSteps; ++k) {
    z.R.push_back(x.rotations[k - 1]);
    z.omega.push_back(x.vector.segment<3>(omega_column(k) - 3 * kSteps));
  }
  for (int k = 0; k < kSteps; ++k) z.tau.push_back(x.vector.segment<3>(tau_column(k) - 3 * kSteps));
  return z;
}

liedyn::LiePoint point_of(const Trajectory& z) {
  liedyn::LiePoint x;
  x.rotations.assign(z.R.begin() + 1, z.R.end());
  x.vector.resize(6 * kSteps);
  for (int k = 1; k <= kSteps; ++k) x.vector.segment<3>(omega_column(k) - 3 * kSteps) = z.omega[k];
  for (int k = 0; k < kSteps; ++k) x.vector.segment<3>(tau_column(k) - 3 * kSteps) = z.tau[k];
  return x;
}

// ω_{k+1} of the discrete dynamics.
Vector3 next_omega(const Vector3& omega, const Vector3& tau) {
  const Vector3 momentum = kInertia.cwiseProduct(omega);
  return omega + kStep * (tau - omega.cross(momentum)).cwiseQuotient(kInertia);
}

// The torques applied from rest at R_0 = I, stepping the discrete dynamics exactly.
Trajectory simulate(const std::vector<Vector3>& tau) {
  Trajectory z;
  z.R.push_back(Matrix3::Identity());
  z.omega.push_back(Vector3::Zero());
  z.tau = tau;
  for (int k = 0; k < kSteps; ++k) {
    z.R.push_back(liedyn::so3::orthonormalize(z.R[k] * liedyn::so3::exp(kStep * z.omega[k])));
    z.omega.push_back(next_omega(z.omega[k], tau[k]));
  }
  return z;
}

// ---------------------------------------------------------------------------------------------
// Residual blocks: 3 rows over up to three 3-dimensional arguments (a rotation's Lie
// perturbation or a vector), with their Jacobians and the Lie Hessian of λᵀ(residual), as
// derived at the top.

struct Block {
  Vector3 value = Vector3::Zero();
  std::array<int, 3> columns{-1, -1, -1};  // tangent column of each argument; −1: data or none
  Eigen::Matrix<double, 3, 9> jacobian = Eigen::Matrix<double, 3, 9>::Zero();
  std::function<Matrix9(const Vector3& lambda)> hessian;  // over the three arguments
};

// K(λ): the Hessian of ξ ↦ λᵀ log(exp(ξ) exp(r)) at ξ = 0 (derived at the top).
Matrix3 log_hessian(const Vector3& r, const Matrix3& J_l_inverse, const Vector3& lambda) {
  const Vector3 mu = J_l_inverse.transpose() * lambda;
  return -J_l_inverse.transpose() * liedyn::rotvec::hessian_correction(r, mu) * J_l_inverse;
}

// r_k = log(R_k exp(h ω_k) R_{k+1}ᵀ); arguments (δ_k, ω_k, δ_{k+1}).
Block rotation_dynamics(const Matrix3& R_k, const Vector3& omega_k, const Matrix3& R_next) {
  Matrix3 J_exp, J_l_inverse;
  const Vector3 h_omega = kStep * omega_k;
  const Matrix3 D = R_k * liedyn::so3::exp(h_omega, &J_exp) * R_next.transpose();
  Block b;
  b.value = liedyn::so3::log(D, &J_l_inverse);
  const Matrix3 M = kStep * R_k * J_exp;
  b.jacobian << J_l_inverse, J_l_inverse * M, -J_l_inverse * D;
  const Vector3 r = b.value;
  b.hessian = [=](const Vector3& lambda) {
    Eigen::Matrix<double, 3, 9> L;
    L << Matrix3::Identity(), M, -D;
    Matrix9 H = L.transpose() * log_hessian(r, J_l_inverse, lambda) * L;
    // BCH's bracket terms: blocks (δ_k, ω_k), (δ_k, δ_{k+1}), (ω_k, δ_{k+1}) and transposes.
    const Vector3 mu = J_l_inverse.transpose() * lambda;
    const Matrix3 delta_omega = -0.5 * hat(mu) * M;
    const Matrix3 delta_next = 0.5 * hat(mu) * D;
    const Matrix3 omega_next = 0.5 * M.transpose() * hat(mu) * D;
    H.block<3, 3>(0, 3) += delta_omega;
    H.block<3, 3>(3, 0) += delta_omega.transpose();
    H.block<3, 3>(0, 6) += delta_next;
    H.block<3, 3>(6, 0) += delta_next.transpose();
    H.block<3, 3>(3, 6) += omega_next;
    H.block<3, 3>(6, 3) += omega_next.transpose();
    // The second-order term of exp(h(ω + η)) = exp(θ(hη)) exp(hω): block (ω_k, ω_k).
    H.block<3, 3>(3, 3) +=
        kStep * kStep * liedyn::rotvec::hessian_correction(h_omega, R_k.transpose() * mu);
    return H;
  };
  return b;
}

// s_k = ω_{k+1} − ω_k − h I⁻¹ (τ_k − ω_k × I ω_k); arguments (ω_k, τ_k, ω_{k+1}).
Block velocity_dynamics(const Vector3& omega_k, const Vector3& tau_k, const Vector3& omega_next) {
  const Matrix3 I = kInertia.asDiagonal();
  const Matrix3 I_inverse = kInertia.cwiseInverse().asDiagonal();
  Block b;
  b.value = omega_next - next_omega(omega_k, tau_k);
  b.jacobian << -Matrix3::Identity() + kStep * I_inverse * (hat(omega_k) * I - hat(I * omega_k)),
      -kStep * I_inverse, Matrix3::Identity();
  b.hessian = [=](const Vector3& lambda) {
    const Vector3 a = kStep * I_inverse * lambda;
    Matrix9 H = Matrix9::Zero();
    H.block<3, 3>(0, 0) = I * hat(a) - hat(a) * I;
    return H;
  };
  return b;
}

// t = log(R_targetᵀ R_N); argument δ_N.
Block terminal_rotation(const Matrix3& R_N, const Matrix3& R_target) {
  Matrix3 J_l_inverse;
  Block b;
  b.value = liedyn::so3::log(R_target.transpose() * R_N, &J_l_inverse);
  b.jacobian.leftCols<3>() = J_l_inverse * R_target.transpose();
  const Vector3 t = b.value;
  b.hessian = [=](const Vector3& lambda) {
    Matrix9 H = Matrix9::Zero();
    H.block<3, 3>(0, 0) = R_target * log_hessian(t, J_l_inverse, lambda) * R_target.transpose();
    return H;
  };
  return b;
}

// ω_N; argument ω_N.
Block terminal_velocity(const Vector3& omega_N) {
  Block b;
  b.value = omega_N;
  b.jacobian.leftCols<3>().setIdentity();
  b.hessian = [](const Vector3&) { return Matrix9::Zero().eval(); };
  return b;
}

// Every residual block of the trajectory, in constraint-row order: r_0, s_0, r_1, s_1, …, t, ω_N.
std::vector<Block> residual_blocks(const Trajectory& z, const Matrix3& R_target) {
  std::vector<Block> blocks;
  for (int k = 0; k < kSteps; ++k) {
    Block r = rotation_dynamics(z.R[k], z.omega[k], z.R[k + 1]);
    r.columns = {rotation_column(k), omega_column(k), rotation_column(k + 1)};
    blocks.push_back(std::move(r));
    Block s = velocity_dynamics(z.omega[k], z.tau[k], z.omega[k + 1]);
    s.columns = {omega_column(k), tau_column(k), omega_column(k + 1)};
    blocks.push_back(std::move(s));
  }
  Block t = terminal_rotation(z.R[kSteps], R_target);
  t.columns = {rotation_column(kSteps), -1, -1};
  blocks.push_back(std::move(t));
  Block v = terminal_velocity(z.omega[kSteps]);
  v.columns = {omega_column(kSteps), -1, -1};
  blocks.push_back(std::move(v));
  return blocks;
}

// Adds a block's 9×9 Hessian (times `scale`) into the tangent-space Hessian.
void scatter_hessian(const Block& b, const Matrix9& H, double scale, Eigen::MatrixXd& hessian) {
  for (int s = 0; s < 3; ++s) {
    for (int t = 0; t < 3; ++t) {
      if (b.columns[s] < 0 || b.columns[t] < 0) continue;
      hessian.block<3, 3>(b.columns[s], b.columns[t]) += scale * H.block<3, 3>(3 * s, 3 * t);
    }
  }
}

double effort(const Trajectory& z) {
  double e = 0.0;
  for (const Vector3& tau : z.tau) e += 0.5 * kStep * tau.squaredNorm();
  return e;
}

// E, and its Lie gradient (h τ_k on the torques, 0 elsewhere) when `gradient` is non-null;
// and its Lie Hessian (h I on each torque), times σ.
double effort(const Trajectory& z, int tangent_size, Eigen::VectorXd* gradient) {
  if (gradient) {
    gradient->setZero(tangent_size);
    for (int k = 0; k < kSteps; ++k) gradient->segment<3>(tau_column(k)) = kStep * z.tau[k];
  }
  return effort(z);
}
void add_effort_hessian(double sigma, Eigen::MatrixXd& hessian) {
  for (int k = 0; k < kSteps; ++k) {
    hessian.block<3, 3>(tau_column(k), tau_column(k)).diagonal().array() += sigma * kStep;
  }
}

// ---------------------------------------------------------------------------------------------
// Ipopt, soft: minimise F.

class SoftNlp final : public liedyn::LieNlp {
 public:
  explicit SoftNlp(const Matrix3& R_target) : R_target_(R_target) {}

  bool objective(const liedyn::LiePoint& x, double& f, Eigen::VectorXd* gradient) override {
    const Trajectory z = trajectory_of(x);
    f = effort(z, x.tangent_size(), gradient);
    for (const Block& b : residual_blocks(z, R_target_)) {
      f += 0.5 * kWeight * b.value.squaredNorm();
      if (!gradient) continue;
      const Eigen::Matrix<double, 9, 1> g = kWeight * b.jacobian.transpose() * b.value;
      for (int s = 0; s < 3; ++s) {
        if (b.columns[s] >= 0) gradient->segment<3>(b.columns[s]) += g.segment<3>(3 * s);
      }
    }
    return std::isfinite(f);
  }

  // ∇²F = Σ w (JᵀJ + Hess(λ = residual)) + h I on the torques.
  bool lagrangian_hessian(const liedyn::LiePoint& x, double sigma,
                          const Eigen::VectorXd& /*lambda*/, Eigen::MatrixXd& hessian) override {
    const Trajectory z = trajectory_of(x);
    hessian.setZero(x.tangent_size(), x.tangent_size());
    add_effort_hessian(sigma, hessian);
    for (const Block& b : residual_blocks(z, R_target_)) {
      const Matrix9 H = b.jacobian.transpose() * b.jacobian + b.hessian(b.value);
      scatter_hessian(b, H, sigma * kWeight, hessian);
    }
    return true;
  }

 private:
  Matrix3 R_target_;
};

// Ipopt, hard: minimise E subject to every residual block = 0. Its derivatives are banded
// (block k touches R_k, ω_k, τ_k and step k + 1 only): with `sparse` the adapter gets them as
// sparse matrices (LieNlp::sparse()), otherwise as dense ones; the same NLP either way.

class HardNlp final : public liedyn::LieNlp {
 public:
  HardNlp(const Matrix3& R_target, bool sparse) : R_target_(R_target), sparse_(sparse) {}

  int constraints() const override { return 6 * kSteps + 6; }  // r_k, s_k, t, ω_N; equalities
  bool sparse() const override { return sparse_; }

  bool objective(const liedyn::LiePoint& x, double& f, Eigen::VectorXd* gradient) override {
    const Trajectory z = trajectory_of(x);
    f = effort(z, x.tangent_size(), gradient);
    return std::isfinite(f);
  }

  bool constraint_values(const liedyn::LiePoint& x, Eigen::VectorXd& c,
                         Eigen::MatrixXd* jacobian) override {
    const std::vector<Block> blocks = residual_blocks(trajectory_of(x), R_target_);
    c.resize(constraints());
    for (std::size_t i = 0; i < blocks.size(); ++i) c.segment<3>(3 * static_cast<int>(i)) = blocks[i].value;
    if (jacobian) {
      jacobian->setZero(constraints(), x.tangent_size());
      jacobian_blocks(blocks, [&](int row, int column, const Matrix3& B) {
        jacobian->block<3, 3>(row, column) += B;
      });
    }
    return c.allFinite();
  }
  bool constraint_jacobian(const liedyn::LiePoint& x, Eigen::SparseMatrix<double>& jacobian) override {
    std::vector<Eigen::Triplet<double>> entries;
    jacobian_blocks(residual_blocks(trajectory_of(x), R_target_),
                    [&](int row, int column, const Matrix3& B) { add_entries(row, column, B, entries); });
    jacobian.setFromTriplets(entries.begin(), entries.end());
    return true;
  }

  // ∇²(σ E + λᵀc) = σ h I on the torques + Σ_blocks Hess(λ of the block's rows).
  bool lagrangian_hessian(const liedyn::LiePoint& x, double sigma, const Eigen::VectorXd& lambda,
                          Eigen::MatrixXd& hessian) override {
    hessian.setZero(x.tangent_size(), x.tangent_size());
    hessian_blocks(residual_blocks(trajectory_of(x), R_target_), sigma, lambda,
                   [&](int row, int column, const Matrix3& B) { hessian.block<3, 3>(row, column) += B; });
    return true;
  }
  bool lagrangian_hessian(const liedyn::LiePoint& x, double sigma, const Eigen::VectorXd& lambda,
                          Eigen::SparseMatrix<double>& hessian) override {
    std::vector<Eigen::Triplet<double>> entries;
    hessian_blocks(residual_blocks(trajectory_of(x), R_target_), sigma, lambda,
                   [&](int row, int column, const Matrix3& B) { add_entries(row, column, B, entries); });
    hessian.setFromTriplets(entries.begin(), entries.end());  // repeated entries are summed
    return true;
  }

 private:
  // f(row, column, B) for every 3×3 block B of the constraints' Lie Jacobian.
  template <class F>
  static void jacobian_blocks(const std::vector<Block>& blocks, F&& f) {
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const Block& b = blocks[i];
      for (int s = 0; s < 3; ++s) {
        if (b.columns[s] >= 0) f(3 * static_cast<int>(i), b.columns[s], b.jacobian.middleCols<3>(3 * s));
      }
    }
  }
  // f(row, column, B) for every 3×3 block B of ∇²(σ E + λᵀc) (a place may come more than once).
  template <class F>
  static void hessian_blocks(const std::vector<Block>& blocks, double sigma,
                             const Eigen::VectorXd& lambda, F&& f) {
    for (int k = 0; k < kSteps; ++k) {
      f(tau_column(k), tau_column(k), Matrix3(sigma * kStep * Matrix3::Identity()));
    }
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const Block& b = blocks[i];
      const Matrix9 H = b.hessian(lambda.segment<3>(3 * static_cast<int>(i)));
      for (int s = 0; s < 3; ++s) {
        for (int t = 0; t < 3; ++t) {
          if (b.columns[s] >= 0 && b.columns[t] >= 0) f(b.columns[s], b.columns[t], H.block<3, 3>(3 * s, 3 * t));
        }
      }
    }
  }
  // All nine entries, zeros too: the pattern the adapter records must hold every later value.
  static void add_entries(int row, int column, const Matrix3& B, std::vector<Eigen::Triplet<double>>& out) {
    for (int a = 0; a < 3; ++a) {
      for (int c = 0; c < 3; ++c) out.emplace_back(row + a, column + c, B(a, c));
    }
  }

  Matrix3 R_target_;
  bool sparse_;
};

// ---------------------------------------------------------------------------------------------
// Ceres, soft: the residual blocks of F, scaled by √w (√h for the torques). A rotation's
// parameter block is its unit quaternion under SO3Manifold; its ambient Jacobian is the Lie
// Jacobian times SO3Manifold::lie_to_ambient(q).

using RowMajor34 = Eigen::Matrix<double, 3, 4, Eigen::RowMajor>;
using RowMajor33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

class RotationDynamicsCost final : public ceres::SizedCostFunction<3, 4, 3, 4> {
 public:
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const Block b = rotation_dynamics(SO3Manifold::rotation(p[0]), Eigen::Map<const Vector3>(p[1]),
                                      SO3Manifold::rotation(p[2]));
    const double scale = std::sqrt(kWeight);
    Eigen::Map<Vector3>{residuals} = scale * b.value;
    if (!jacobians) return true;
    if (jacobians[0]) {
      Eigen::Map<RowMajor34>{jacobians[0]} =
          scale * b.jacobian.leftCols<3>() * SO3Manifold::lie_to_ambient(p[0]);
    }
    if (jacobians[1]) Eigen::Map<RowMajor33>{jacobians[1]} = scale * b.jacobian.middleCols<3>(3);
    if (jacobians[2]) {
      Eigen::Map<RowMajor34>{jacobians[2]} =
          scale * b.jacobian.rightCols<3>() * SO3Manifold::lie_to_ambient(p[2]);
    }
    return true;
  }
};

class VelocityDynamicsCost final : public ceres::SizedCostFunction<3, 3, 3, 3> {
 public:
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const Block b =
        velocity_dynamics(Eigen::Map<const Vector3>(p[0]), Eigen::Map<const Vector3>(p[1]),
                          Eigen::Map<const Vector3>(p[2]));
    const double scale = std::sqrt(kWeight);
    Eigen::Map<Vector3>{residuals} = scale * b.value;
    for (int i = 0; i < 3; ++i) {
      if (jacobians && jacobians[i]) {
        Eigen::Map<RowMajor33>{jacobians[i]} = scale * b.jacobian.middleCols<3>(3 * i);
      }
    }
    return true;
  }
};

class TerminalRotationCost final : public ceres::SizedCostFunction<3, 4> {
 public:
  explicit TerminalRotationCost(const Matrix3& R_target) : R_target_(R_target) {}
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const Block b = terminal_rotation(SO3Manifold::rotation(p[0]), R_target_);
    const double scale = std::sqrt(kWeight);
    Eigen::Map<Vector3>{residuals} = scale * b.value;
    if (jacobians && jacobians[0]) {
      Eigen::Map<RowMajor34>{jacobians[0]} =
          scale * b.jacobian.leftCols<3>() * SO3Manifold::lie_to_ambient(p[0]);
    }
    return true;
  }

 private:
  Matrix3 R_target_;
};

// scale · v: the torque effort (scale √h) and the terminal velocity (scale √w).
class ScaledVectorCost final : public ceres::SizedCostFunction<3, 3> {
 public:
  explicit ScaledVectorCost(double scale) : scale_(scale) {}
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    Eigen::Map<Vector3>{residuals} = scale_ * Eigen::Map<const Vector3>(p[0]);
    if (jacobians && jacobians[0]) {
      Eigen::Map<RowMajor33>{jacobians[0]} = scale_ * Matrix3::Identity();
    }
    return true;
  }

 private:
  double scale_;
};

// The trajectory as Ceres parameter blocks.
struct CeresVariables {
  std::vector<Vector4> q;      // R_0 … R_N as unit quaternions (x, y, z, w)
  std::vector<Vector3> omega;  // ω_0 … ω_N
  std::vector<Vector3> tau;    // τ_0 … τ_{N−1}

  explicit CeresVariables(const Trajectory& z) : omega(z.omega), tau(z.tau) {
    for (const Matrix3& R : z.R) q.push_back(SO3Manifold::quaternion(R));
  }
  Trajectory trajectory() const {
    Trajectory z{{}, omega, tau};
    for (const Vector4& qk : q) z.R.push_back(SO3Manifold::rotation(qk.data()));
    return z;
  }
};

struct CeresResidual {
  std::unique_ptr<ceres::CostFunction> cost;
  std::vector<double*> blocks;
};

std::vector<CeresResidual> ceres_residuals(CeresVariables& v, const Matrix3& R_target) {
  std::vector<CeresResidual> residuals;
  auto add = [&](ceres::CostFunction* cost, std::vector<double*> blocks) {
    residuals.push_back({std::unique_ptr<ceres::CostFunction>(cost), std::move(blocks)});
  };
  for (int k = 0; k < kSteps; ++k) {
    add(new RotationDynamicsCost, {v.q[k].data(), v.omega[k].data(), v.q[k + 1].data()});
    add(new VelocityDynamicsCost, {v.omega[k].data(), v.tau[k].data(), v.omega[k + 1].data()});
    add(new ScaledVectorCost(std::sqrt(kStep)), {v.tau[k].data()});
  }
  add(new TerminalRotationCost(R_target), {v.q[kSteps].data()});
  add(new ScaledVectorCost(std::sqrt(kWeight)), {v.omega[kSteps].data()});
  return residuals;
}

// ---------------------------------------------------------------------------------------------
// Checks of every derivative above against central differences, at a trajectory `z` away
// from any solution.

bool check_derivatives(const Trajectory& z, const Matrix3& R_target) {
  const liedyn::LiePoint x = point_of(z);
  SoftNlp soft(R_target);
  HardNlp hard(R_target, /*sparse=*/false);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  Eigen::VectorXd lambda(hard.constraints());
  for (int i = 0; i < lambda.size(); ++i) lambda[i] = normal(rng);
  const double sigma = 0.7;

  auto F = [&](const liedyn::LiePoint& y) {
    double f = 0.0;
    soft.objective(y, f, nullptr);
    return f;
  };
  auto grad_F = [&](const liedyn::LiePoint& y) {
    double f = 0.0;
    Eigen::VectorXd g;
    soft.objective(y, f, &g);
    return g;
  };
  auto c = [&](const liedyn::LiePoint& y) {
    Eigen::VectorXd values;
    hard.constraint_values(y, values, nullptr);
    return values;
  };
  // The gradient of the hard problem's Lagrangian σE + λᵀc.
  auto grad_L = [&](const liedyn::LiePoint& y) {
    double e = 0.0;
    Eigen::VectorXd g, values;
    Eigen::MatrixXd A;
    hard.objective(y, e, &g);
    hard.constraint_values(y, values, &A);
    return Eigen::VectorXd(sigma * g + A.transpose() * lambda);
  };

  Eigen::MatrixXd H_F, H_L, A;
  Eigen::VectorXd values;
  soft.lagrangian_hessian(x, 1.0, Eigen::VectorXd(), H_F);
  hard.lagrangian_hessian(x, sigma, lambda, H_L);
  hard.constraint_values(x, values, &A);
  double e = 0.0;
  Eigen::VectorXd grad_E;
  hard.objective(x, e, &grad_E);

  const double eps = 1e-5;
  const double gradient_error =
      lie_check::relative_error(grad_F(x), lie_check::gradient(F, x, eps));
  const double hessian_error = lie_check::relative_error(H_F, lie_check::hessian(grad_F, x, eps));
  const double effort_error = lie_check::relative_error(
      grad_E, lie_check::gradient(
                  [&](const liedyn::LiePoint& y) { return effort(trajectory_of(y)); }, x, eps));
  const double jacobian_error = lie_check::relative_error(A, lie_check::jacobian(c, x, eps));
  const double lagrangian_error =
      lie_check::relative_error(H_L, lie_check::hessian(grad_L, x, eps));
  // The sparse form gives the same matrices (to the round-off of summing in another order).
  HardNlp sparse(R_target, /*sparse=*/true);
  Eigen::SparseMatrix<double> A_sparse(A.rows(), A.cols()), H_sparse(H_L.rows(), H_L.cols());
  sparse.constraint_jacobian(x, A_sparse);
  sparse.lagrangian_hessian(x, sigma, lambda, H_sparse);
  const double sparse_error = std::max(lie_check::relative_error(Eigen::MatrixXd(A_sparse), A),
                                       lie_check::relative_error(Eigen::MatrixXd(H_sparse), H_L));

  SO3Manifold manifold;
  CeresVariables v(z);
  double ceres_error = 0.0;
  for (const CeresResidual& r : ceres_residuals(v, R_target)) {
    std::vector<const ceres::Manifold*> manifolds;
    for (const int32_t size : r.cost->parameter_block_sizes())
      manifolds.push_back(size == 4 ? &manifold : nullptr);
    ceres_error =
        std::max(ceres_error, lie_check::cost_function_error(*r.cost, r.blocks, manifolds, eps));
  }

  std::printf(
      "derivative checks (max |analytic - central difference| / max |entry|, tolerance %.0e):\n"
      "  soft F: Lie gradient %.1e, Lie Hessian %.1e; Ceres Jacobians along Plus %.1e\n"
      "  hard: effort gradient %.1e, constraint Lie Jacobian %.1e, Lagrangian Lie Hessian %.1e;"
      " sparse against dense form %.1e\n",
      kDerivativeTolerance, gradient_error, hessian_error, ceres_error, effort_error,
      jacobian_error, lagrangian_error, sparse_error);
  return std::max({gradient_error, hessian_error, ceres_error, effort_error, jacobian_error,
                   lagrangian_error}) <= kDerivativeTolerance &&
         sparse_error <= 1e-12;
}

// ---------------------------------------------------------------------------------------------

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double max_torque(const Trajectory& z) {
  double m = 0.0;
  for (const Vector3& tau : z.tau) m = std::max(m, tau.norm());
  return m;
}

// max_k ‖r_k‖, max_k ‖s_k‖ — how far a trajectory is from satisfying the dynamics.
double max_dynamics_residual(const Trajectory& z, const Matrix3& R_target) {
  const std::vector<Block> blocks = residual_blocks(z, R_target);
  double m = 0.0;
  for (int i = 0; i < 2 * kSteps; ++i) m = std::max(m, blocks[i].value.norm());
  return m;
}

// Largest differences between two trajectories: rotations (rad), and ω, τ relative to the
// largest |entry| of the first.
struct Difference {
  double rotation = 0.0, omega = 0.0, tau = 0.0;
};

Difference difference(const Trajectory& a, const Trajectory& b) {
  Difference d;
  double omega_scale = 0.0, tau_scale = 0.0;
  for (int k = 0; k <= kSteps; ++k) {
    d.rotation = std::max(d.rotation, liedyn::so3::distance(a.R[k], b.R[k]));
    d.omega = std::max(d.omega, (a.omega[k] - b.omega[k]).cwiseAbs().maxCoeff());
    omega_scale = std::max(omega_scale, a.omega[k].cwiseAbs().maxCoeff());
  }
  for (int k = 0; k < kSteps; ++k) {
    d.tau = std::max(d.tau, (a.tau[k] - b.tau[k]).cwiseAbs().maxCoeff());
    tau_scale = std::max(tau_scale, a.tau[k].cwiseAbs().maxCoeff());
  }
  d.omega /= omega_scale;
  d.tau /= tau_scale;
  return d;
}

void print_trajectory(const char* name, const Trajectory& z, const Matrix3& R_target) {
  const Trajectory simulated = simulate(z.tau);
  std::printf(
      "  %s: max |tau_k| %.6f N m; |log(R_target^T R_N)| %.2e rad, |omega_N| %.2e rad/s, "
      "max dynamics residual %.2e;\n"
      "    its torques simulated: orientation error %.2e rad, |omega_N| %.2e rad/s\n",
      name, max_torque(z), liedyn::so3::distance(z.R[kSteps], R_target), z.omega[kSteps].norm(),
      max_dynamics_residual(z, R_target), liedyn::so3::distance(simulated.R[kSteps], R_target),
      simulated.omega[kSteps].norm());
}

int run() {
  const Matrix3 R_target = liedyn::so3::exp(target_rotation_vector());
  std::printf(
      "attitude_control: inertia diag(1, 2, 3), rest at R_0 = I to rest at exp(%.4f, %.4f, %.4f) "
      "(120 deg), T = %.2f s, N = %d, w = %.0e\n",
      target_rotation_vector().x(), target_rotation_vector().y(), target_rotation_vector().z(),
      kSteps * kStep, kSteps, kWeight);

  // Initial guess for every solve: the smooth rest-to-rest turn about the target's axis,
  // R_k = exp(p(t_k) θ_T), p(t) = 3(t/T)² − 2(t/T)³, with the ω_k that make every rotation step
  // but the first (ω_0 = 0 is data) hold — all R_k share one axis, so body and world increments
  // agree — ω_N = 0, and τ = 0.
  Trajectory initial;
  auto p = [](int k) {
    const double s = static_cast<double>(k) / kSteps;
    return s * s * (3.0 - 2.0 * s);
  };
  for (int k = 0; k <= kSteps; ++k) {
    initial.R.push_back(liedyn::so3::exp(p(k) * target_rotation_vector()));
    const bool fixed = k == 0 || k == kSteps;
    initial.omega.push_back(fixed ? Vector3::Zero()
                                  : Vector3((p(k + 1) - p(k)) / kStep * target_rotation_vector()));
    if (k < kSteps) initial.tau.push_back(Vector3::Zero());
  }

  // Derivative checks away from any solution: the initial guess with each R_k turned by
  // 0.3 rad about a random axis and N(0, 1) added to each ω and τ entry.
  {
    std::mt19937 rng(11);
    std::normal_distribution<double> normal;
    auto random_vector = [&] { return Vector3(normal(rng), normal(rng), normal(rng)); };
    Trajectory rough = initial;
    for (int k = 1; k <= kSteps; ++k) {
      rough.R[k] = liedyn::so3::exp(0.3 * random_vector().normalized()) * rough.R[k];
      rough.omega[k] += random_vector();
    }
    for (Vector3& tau : rough.tau) tau += random_vector();
    if (!check_derivatives(rough, R_target)) {
      std::fprintf(stderr, "attitude_control: a derivative disagrees with finite differences\n");
      return 1;
    }
  }

  // Ceres, soft.
  CeresVariables v(initial);
  SO3Manifold manifold;  // one instance for every rotation block; the problem must not delete it
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (Vector4& q : v.q) problem.AddParameterBlock(q.data(), 4, &manifold);
  for (CeresResidual& r : ceres_residuals(v, R_target)) {
    problem.AddResidualBlock(r.cost.release(), nullptr, r.blocks);
  }
  problem.SetParameterBlockConstant(v.q[0].data());      // R_0 = I is data
  problem.SetParameterBlockConstant(v.omega[0].data());  // ω_0 = 0 is data
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  options.max_num_iterations = 200;
  ceres::Solver::Summary ceres_summary;
  auto start = std::chrono::steady_clock::now();
  ceres::Solve(options, &problem, &ceres_summary);
  const double ceres_seconds = seconds_since(start);
  const Trajectory ceres_solution = v.trajectory();
  const bool ceres_converged =
      ceres_summary.IsSolutionUsable() && ceres_summary.termination_type == ceres::CONVERGENCE;

  // Ipopt from the same guess, exact Hessians: the soft problem, the hard one with sparse
  // derivatives, and the same hard NLP with dense ones for comparison.
  struct IpoptRun {
    liedyn::LieIpoptSummary summary;
    Trajectory solution;
    double seconds = 0.0;
  };
  const auto solve = [&](liedyn::LieNlp& problem) {
    liedyn::LiePoint x = point_of(initial);
    liedyn::LieIpoptOptions options;
    options.hessian = "exact";
    const auto t0 = std::chrono::steady_clock::now();
    IpoptRun run;
    run.summary = liedyn::solve_with_ipopt(problem, x, options);
    run.seconds = seconds_since(t0);
    run.solution = trajectory_of(x);
    return run;
  };
  SoftNlp soft(R_target);
  HardNlp hard(R_target, /*sparse=*/true), hard_dense(R_target, /*sparse=*/false);
  const IpoptRun soft_run = solve(soft), hard_run = solve(hard), dense_run = solve(hard_dense);
  const liedyn::LieIpoptSummary &soft_summary = soft_run.summary, &hard_summary = hard_run.summary,
                                &dense_summary = dense_run.summary;
  const Trajectory &soft_solution = soft_run.solution, &hard_solution = hard_run.solution;
  const double soft_seconds = soft_run.seconds, hard_seconds = hard_run.seconds,
               dense_seconds = dense_run.seconds;
  const Difference sparse_vs_dense = difference(hard_solution, dense_run.solution);

  // F at both soft solutions, by the same function.
  double F_ceres = 0.0, F_ipopt = 0.0;
  soft.objective(point_of(ceres_solution), F_ceres, nullptr);
  soft.objective(point_of(soft_solution), F_ipopt, nullptr);
  const double E_hard = effort(hard_solution);
  const double objective_difference = std::abs(F_ceres - F_ipopt) / std::max(F_ceres, F_ipopt);
  const Difference soft_difference = difference(ceres_solution, soft_solution);
  const Difference hard_vs_soft = difference(hard_solution, soft_solution);
  const Trajectory simulated = simulate(hard_solution.tau);
  const double simulated_error = liedyn::so3::distance(simulated.R[kSteps], R_target);
  const double simulated_rest = simulated.omega[kSteps].norm();

  std::printf("Ceres, soft : %s, %d iterations, F = %.12g, %.0f ms  [%s]\n",
              ceres::TerminationTypeToString(ceres_summary.termination_type),
              ceres_summary.num_successful_steps + ceres_summary.num_unsuccessful_steps, F_ceres,
              1e3 * ceres_seconds, ceres_summary.message.c_str());
  std::printf("Ipopt, soft : %s, %d iterations, F = %.12g, %.0f ms  [%s]\n",
              soft_summary.converged() ? "converged" : "NOT converged", soft_summary.iterations,
              F_ipopt, 1e3 * soft_seconds, soft_summary.message.c_str());
  std::printf(
      "Ipopt, hard : %s, %d iterations, E = %.12g, constraint violation %.1e, %.0f ms  [%s]\n",
      hard_summary.converged() ? "converged" : "NOT converged", hard_summary.iterations, E_hard,
      hard_summary.constraint_violation, 1e3 * hard_seconds, hard_summary.message.c_str());
  std::printf(
      "  the same with dense derivatives: %s, %d iterations, %.0f ms; max differences from the "
      "sparse solve: rotations %.1e rad, omega %.1e, tau %.1e (relative)\n",
      dense_summary.converged() ? "converged" : "NOT converged", dense_summary.iterations,
      1e3 * dense_seconds, sparse_vs_dense.rotation, sparse_vs_dense.omega, sparse_vs_dense.tau);
  std::printf(
      "soft, Ceres vs Ipopt: F relative difference %.1e (tolerance %.0e); max differences: "
      "rotations %.1e rad, omega %.1e, tau %.1e (relative; tolerance %.0e)\n",
      objective_difference, kObjectiveAgreement, soft_difference.rotation, soft_difference.omega,
      soft_difference.tau, kSolutionAgreement);
  std::printf(
      "soft vs hard: F_soft = %.9f <= E_hard = %.9f; first-order prediction E_hard - "
      "|lambda|^2/(2w) "
      "= %.9f; max differences: rotations %.1e rad, omega %.1e, tau %.1e (relative)\n",
      F_ipopt, E_hard, E_hard - hard_summary.multipliers.squaredNorm() / (2.0 * kWeight),
      hard_vs_soft.rotation, hard_vs_soft.omega, hard_vs_soft.tau);
  print_trajectory("soft (Ipopt)", soft_solution, R_target);
  print_trajectory("hard (Ipopt)", hard_solution, R_target);

  bool ok = true;
  auto require = [&ok](bool condition, const char* what) {
    if (!condition) {
      std::fprintf(stderr, "attitude_control: FAILED: %s\n", what);
      ok = false;
    }
  };
  require(ceres_converged, "Ceres (soft) did not converge");
  require(soft_summary.converged(), "Ipopt (soft) did not converge");
  require(hard_summary.converged(), "Ipopt (hard) did not converge");
  require(dense_summary.converged(), "Ipopt (hard, dense derivatives) did not converge");
  require(std::max({sparse_vs_dense.rotation, sparse_vs_dense.omega, sparse_vs_dense.tau}) <=
              kSolutionAgreement,
          "the sparse and dense forms of the hard problem reach different solutions");
  require(objective_difference <= kObjectiveAgreement,
          "the soft objectives of Ceres and Ipopt differ");
  require(std::max({soft_difference.rotation, soft_difference.omega, soft_difference.tau}) <=
              kSolutionAgreement,
          "the soft solutions of Ceres and Ipopt differ");
  // Round-off slack only: F_soft ≤ E_hard holds exactly at the two minimisers.
  require(F_ipopt <= E_hard * (1.0 + 1e-12),
          "F_soft > E_hard: the soft solve missed the hard solution's basin");
  require(hard_summary.constraint_violation < kConstraintViolation,
          "the hard solution violates its constraints");
  require(simulated_error < kSimulationTolerance && simulated_rest < kSimulationTolerance,
          "the hard solution's torques, simulated, miss the target");
  if (ok) std::printf("attitude_control: passed\n");
  return ok ? 0 : 1;
}

}  // namespace

int main() {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "attitude_control: %s\n", e.what());
    return 1;
  }
}

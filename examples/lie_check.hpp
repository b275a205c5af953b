#pragma once
// Finite-difference checks of Lie derivatives, shared by the examples. Copy it into your own
// project: it needs only liedyn's headers, and a derivative you have not checked is a guess.
//
// Everything is in the tangent layout of <liedyn/manifolds/lie_ipopt.hpp>: for a LiePoint with
// r rotations and n vector entries, coordinate k < 3r is the world-frame (left) rotation vector
// of rotation k/3, component k mod 3; coordinate k ≥ 3r is vector entry k − 3r. Moving along
// coordinate k by s means
//   R_i ← exp(s e_{k mod 3}) R_i     (liedyn's left perturbation, lib/so3.hpp), or  v ← v + s e.
//
// Lie gradient and Jacobian: central differences of the function along each coordinate.
// Lie Hessian: the Hessian of the pulled-back function ψ(δ) = f(exp(δ_1) R_1, …, v + δ_v) at
// δ = 0. Its gradient is known exactly at δ ≠ 0 from the Lie gradient g at the moved point:
//   ∂ψ/∂δ_i = J_l(δ_i)ᵀ g_i(exp(δ) R),   because exp(δ + η) = exp(J_l(δ) η) exp(δ) + O(η²),
// so column k of the Hessian is the central difference of that along e_k. (Differencing the
// Lie gradient field alone, without the J_l(δ)ᵀ, gives H − ½ hat(g) instead:
// docs/conventions.md.) These checks use only values and first derivatives of ψ, so their
// errors are O(ε²) truncation plus O(round-off/ε) — far below the 1e-6 the examples demand.

#include <ceres/cost_function.h>
#include <ceres/manifold.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <liedyn/lib/so3.hpp>
#include <liedyn/manifolds/lie_ipopt.hpp>
#include <vector>

namespace lie_check {

// The point moved by s along tangent coordinate k.
inline liedyn::LiePoint moved(const liedyn::LiePoint& x, int k, double s) {
  liedyn::LiePoint y = x;
  const int rotation_coordinates = 3 * static_cast<int>(x.rotations.size());
  if (k < rotation_coordinates) {
    liedyn::so3::Vector3 delta = liedyn::so3::Vector3::Zero();
    delta[k % 3] = s;
    y.rotations[k / 3] = liedyn::so3::exp(delta) * x.rotations[k / 3];
  } else {
    y.vector[k - rotation_coordinates] += s;
  }
  return y;
}

// max |analytic − reference| over the entries, divided by the largest |reference| entry:
// an error relative to the size of the derivative, not to each entry (many entries are 0).
inline double relative_error(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& reference) {
  const double scale = reference.cwiseAbs().maxCoeff();
  const double error = (analytic - reference).cwiseAbs().maxCoeff();
  return scale > 0.0 ? error / scale : error;
}

// The Lie gradient of f by central differences. f: double(const LiePoint&).
template <class F>
Eigen::VectorXd gradient(F&& f, const liedyn::LiePoint& x, double eps) {
  Eigen::VectorXd g(x.tangent_size());
  for (int k = 0; k < g.size(); ++k) {
    g[k] = (f(moved(x, k, eps)) - f(moved(x, k, -eps))) / (2.0 * eps);
  }
  return g;
}

// The Lie Jacobian of c by central differences. c: Eigen::VectorXd(const LiePoint&).
template <class C>
Eigen::MatrixXd jacobian(C&& c, const liedyn::LiePoint& x, double eps) {
  const Eigen::VectorXd c0 = c(x);
  Eigen::MatrixXd A(c0.size(), x.tangent_size());
  for (int k = 0; k < A.cols(); ++k) {
    A.col(k) = (c(moved(x, k, eps)) - c(moved(x, k, -eps))) / (2.0 * eps);
  }
  return A;
}

// The Lie Hessian of a function from its Lie gradient, g: Eigen::VectorXd(const LiePoint&),
// through the pulled-back gradient described at the top.
template <class G>
Eigen::MatrixXd hessian(G&& g, const liedyn::LiePoint& x, double eps) {
  const int n = x.tangent_size();
  const int rotation_coordinates = 3 * static_cast<int>(x.rotations.size());
  // ∂ψ/∂δ at δ = s e_k: only the moved rotation's block changes, by J_l(s e_{k mod 3})ᵀ.
  auto pulled_back_gradient = [&](int k, double s) {
    Eigen::VectorXd gk = g(moved(x, k, s));
    if (k < rotation_coordinates) {
      liedyn::so3::Vector3 delta = liedyn::so3::Vector3::Zero();
      delta[k % 3] = s;
      const int i = 3 * (k / 3);
      gk.segment<3>(i) = liedyn::so3::left_jacobian(delta).transpose() * gk.segment<3>(i);
    }
    return gk;
  };
  Eigen::MatrixXd H(n, n);
  for (int k = 0; k < n; ++k) {
    H.col(k) = (pulled_back_gradient(k, eps) - pulled_back_gradient(k, -eps)) / (2.0 * eps);
  }
  return H;
}

// A Ceres cost function's Jacobians as Ceres uses them — ambient Jacobian times the
// manifold's PlusJacobian (the identity for a block without a manifold) — against central
// differences of the residuals along Plus(x, ±ε e_k). Returns the relative error (as above) of
// the residual block's whole tangent Jacobian. manifolds[i] may be nullptr (Euclidean block).
inline double cost_function_error(const ceres::CostFunction& cost,
                                  const std::vector<double*>& blocks,
                                  const std::vector<const ceres::Manifold*>& manifolds,
                                  double eps) {
  const int m = cost.num_residuals();
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  std::vector<RowMajor> ambient;
  std::vector<double*> jacobian_pointers;
  for (const int32_t size : sizes) ambient.emplace_back(m, size);
  for (RowMajor& a : ambient) jacobian_pointers.push_back(a.data());
  Eigen::VectorXd r(m);
  cost.Evaluate(blocks.data(), r.data(), jacobian_pointers.data());

  int tangent_total = 0;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    tangent_total += manifolds[i] ? manifolds[i]->TangentSize() : sizes[i];
  }
  Eigen::MatrixXd analytic(m, tangent_total), numeric(m, tangent_total);
  int column = 0;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    const ceres::Manifold* manifold = manifolds[i];
    const int tangent = manifold ? manifold->TangentSize() : sizes[i];
    if (manifold) {
      RowMajor plus_jacobian(sizes[i], tangent);
      manifold->PlusJacobian(blocks[i], plus_jacobian.data());
      analytic.middleCols(column, tangent) = ambient[i] * plus_jacobian;
    } else {
      analytic.middleCols(column, tangent) = ambient[i];
    }
    const std::vector<double> original(blocks[i], blocks[i] + sizes[i]);
    for (int k = 0; k < tangent; ++k) {
      Eigen::VectorXd r_side[2];
      for (int side = 0; side < 2; ++side) {
        Eigen::VectorXd delta = Eigen::VectorXd::Zero(tangent);
        delta[k] = side == 0 ? eps : -eps;
        if (manifold) {
          manifold->Plus(original.data(), delta.data(), blocks[i]);
        } else {
          for (int j = 0; j < sizes[i]; ++j) blocks[i][j] = original[j] + delta[j];
        }
        r_side[side].resize(m);
        cost.Evaluate(blocks.data(), r_side[side].data(), nullptr);
      }
      std::copy(original.begin(), original.end(), blocks[i]);
      numeric.col(column + k) = (r_side[0] - r_side[1]) / (2.0 * eps);
    }
    column += tangent;
  }
  return relative_error(analytic, numeric);
}

}  // namespace lie_check

#pragma once
// Finite-difference checks in the tangent space of a liedyn::State (conventions: lib/so3.hpp).
//
// A tangent vector δ stacks one 3-block per DOF listed in a `Dofs` vector; q ⊕ δ moves
//   points additively     x ← x + δ_i,
//   rotations on the left R ← exp(δ_j) R   (world frame).
// A block may be `no_dof()` (e.g. a spring's world anchor): it is never perturbed and its
// rows/columns are not compared.
//
// Derivatives are checked with central differences:
//   * gradient:  g_i ≈ (f(q ⊕ εe_i) − f(q ⊖ εe_i)) / 2ε.
//   * Hessian:   the Lie Hessian is the ordinary Hessian of the PULLED-BACK function
//                φ(δ) = f(q ⊕ δ) at δ = 0. It is checked two independent ways:
//       check_lie_hessian            central differences of ∇φ, with the analytic Lie
//                                    gradient pulled back: ∇φ(δ) = blockdiag(I, J_l(δ_j)ᵀ) g(q ⊕ δ)
//                                    (f(exp(δ+η)R) = f(exp(J_l(δ)η) exp(δ)R)). Differencing the
//                                    Lie gradient FIELD g(q ⊕ δ) instead would give H − ½hat(g)
//                                    (docs/design.md §1.4), which is why the J_l(δ)ᵀ factor is
//                                    there.
//       check_lie_hessian_from_value second differences of φ itself (needs no gradient).
//   * Jacobian of a State → State map: output rotations are differenced in the tangent space,
//     (log(Q(q ⊕ εe)Q(q)ᵀ) − log(Q(q ⊖ εe)Q(q)ᵀ)) / 2ε.
//
// Acceptance, entry by entry, for analytic a and finite difference d:
//   |a − d| ≤ rtol · max(|a|, |d|) + floor · scale + abs_floor + noise,
// scale = largest |entry| (analytic or FD) of the whole object compared. `floor` absorbs the
// FD round-off/truncation that entries near zero inherit from their large neighbours;
// `abs_floor` is for objects whose natural size is known to the caller but which may vanish
// at the test point (callers must say why in a comment). `noise` is computed, not chosen: the
// resolution of the difference quotient itself, kNoiseUlps·eps·max|differenced quantity|/ε
// (ε² for second differences of the value) — nothing below it can be told from round-off.
// A check also fails when the analytic object is (blockwise) not well above that whole
// floor, unless told otherwise: comparing zeros (or noise) proves nothing.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "lib/so3.hpp"
#include "lib/state.hpp"
#include "lib/term.hpp"

namespace liedyn::fd {

enum class DofKind { kNone, kPoint, kRotation };

struct Dof {
  DofKind kind = DofKind::kNone;
  int index = -1;
};

inline Dof point_dof(int i) { return {DofKind::kPoint, i}; }
inline Dof rotation_dof(int i) { return {DofKind::kRotation, i}; }
inline Dof no_dof() { return {}; }

using Dofs = std::vector<Dof>;

// What "non-zero" the analytic object must be, so that the comparison means something.
enum class NonZero {
  kEveryBlock,  // every compared 3-row block has an entry well above the tolerance floor
  kAny,         // some entry is well above the tolerance floor
  kNone,        // no requirement (the object is zero at this point by construction)
};

// Defaults for first differences, ε = 1e-6: round-off is covered by the computed noise floor;
// truncation is ε²/6·|third derivative| ≈ 2e-13 × (derivative scale) for O(1) geometry, far
// below floor = 1e-9 of the object's scale. rtol = 1e-6 leaves room for the round-off of the
// analytic side and of the perturbation itself (exp(εe)R carries O(eps) error).
struct FdOptions {
  double step = 1e-6;  // ε, in metres or radians
  double rtol = 1e-6;
  double floor = 1e-9;  // times the largest |entry| of the compared object
  double abs_floor = 0.0;
  NonZero require_nonzero = NonZero::kEveryBlock;
};

// Defaults for second differences of a value, ε = 1e-4: round-off eps·|f|/ε² ≈ 2e-8·|f| (the
// computed noise floor), truncation ε²/12·|f''''| ≈ 1e-9 × scale; floor and rtol 1e-5.
inline FdOptions value_hessian_defaults() {
  FdOptions o;
  o.step = 1e-4;
  o.rtol = 1e-5;
  o.floor = 1e-5;
  o.require_nonzero = NonZero::kAny;
  return o;
}

// Round-off of one evaluation of the differenced quantity, in ulps of its largest entry
// (sums of a few dozen terms of that size, with margin).
inline constexpr double kNoiseUlps = 16.0;

inline double noise_of(double magnitude, double divisor) {
  return kNoiseUlps * std::numeric_limits<double>::epsilon() * magnitude / divisor;
}

using ScalarFunction = std::function<double(const State&)>;
using GradientFunction = std::function<Eigen::VectorXd(const State&)>;
using StateFunction = std::function<State(const State&)>;

// q ⊕ δ.
inline State perturb(const State& q, const Dofs& dofs, const Eigen::VectorXd& delta) {
  State p = q;
  for (size_t b = 0; b < dofs.size(); ++b) {
    const Vector3 d = delta.segment<3>(3 * static_cast<Eigen::Index>(b));
    if (dofs[b].kind == DofKind::kPoint) p.points[dofs[b].index] += d;
    if (dofs[b].kind == DofKind::kRotation) {
      p.rotations[dofs[b].index] = so3::exp(d) * p.rotations[dofs[b].index];
    }
  }
  return p;
}

inline State perturb_one(const State& q, const Dofs& dofs, Eigen::Index i, double eps) {
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(dofs.size()));
  delta(i) = eps;
  return perturb(q, dofs, delta);
}

namespace detail {

inline std::string label(const Dofs& dofs, Eigen::Index row) {
  static const char* const kAxis[] = {"x", "y", "z"};
  const Dof& d = dofs[static_cast<size_t>(row / 3)];
  std::ostringstream s;
  s << "block " << row / 3 << " ("
    << (d.kind == DofKind::kPoint      ? "point "
        : d.kind == DofKind::kRotation ? "rotation "
                                       : "none ")
    << d.index << ")[" << kAxis[row % 3] << "]";
  return s.str();
}

inline bool compared(const Dofs& dofs, Eigen::Index row) {
  return dofs[static_cast<size_t>(row / 3)].kind != DofKind::kNone;
}

// Compares analytic a with finite differences d (same shape); rows belong to row_dofs, and
// columns to col_dofs (nullptr for a vector).
inline ::testing::AssertionResult compare(const std::string& what, const Eigen::MatrixXd& a,
                                          const Eigen::MatrixXd& d, const Dofs& row_dofs,
                                          const Dofs* col_dofs, const FdOptions& opt,
                                          double noise) {
  const auto col_ok = [&](Eigen::Index j) { return col_dofs == nullptr || compared(*col_dofs, j); };
  double scale = 0.0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      if (!compared(row_dofs, i) || !col_ok(j)) continue;
      if (!std::isfinite(a(i, j)) || !std::isfinite(d(i, j))) {
        return ::testing::AssertionFailure()
               << what << ": non-finite entry at " << label(row_dofs, i)
               << (col_dofs ? ", " + label(*col_dofs, j) : std::string()) << ": analytic "
               << a(i, j) << ", fd " << d(i, j);
      }
      scale = std::max({scale, std::abs(a(i, j)), std::abs(d(i, j))});
    }
  }
  const double base = opt.floor * scale + opt.abs_floor + noise;

  // The analytic object must stand well above the tolerance floor where required.
  const double significant = 100.0 * base;
  if (opt.require_nonzero != NonZero::kNone) {
    double largest = 0.0;
    for (Eigen::Index b = 0; b < a.rows() / 3; ++b) {
      if (!compared(row_dofs, 3 * b)) continue;
      double block = 0.0;
      for (Eigen::Index i = 3 * b; i < 3 * b + 3; ++i) {
        for (Eigen::Index j = 0; j < a.cols(); ++j) {
          if (col_ok(j)) block = std::max(block, std::abs(a(i, j)));
        }
      }
      largest = std::max(largest, block);
      if (opt.require_nonzero == NonZero::kEveryBlock && !(block > significant)) {
        return ::testing::AssertionFailure()
               << what << ": analytic rows of " << label(row_dofs, 3 * b) << " are "
               << (block == 0.0 ? "zero" : "negligible") << " (max " << block
               << ", tolerance floor " << base << "): the check would prove nothing";
      }
    }
    if (!(largest > significant) || largest == 0.0) {
      return ::testing::AssertionFailure()
             << what << ": analytic object is zero or negligible (max " << largest
             << "): the check would prove nothing";
    }
  }

  double worst_ratio = -1.0;
  Eigen::Index wi = 0, wj = 0;
  double worst_tol = 0.0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      if (!compared(row_dofs, i) || !col_ok(j)) continue;
      const double err = std::abs(a(i, j) - d(i, j));
      const double tol = opt.rtol * std::max(std::abs(a(i, j)), std::abs(d(i, j))) + base;
      const double ratio = tol > 0.0 ? err / tol : (err > 0.0 ? 1e300 : 0.0);
      if (ratio > worst_ratio) {
        worst_ratio = ratio;
        wi = i;
        wj = j;
        worst_tol = tol;
      }
    }
  }
  std::ostringstream msg;
  msg << what << ": worst entry " << label(row_dofs, wi)
      << (col_dofs ? ", " + label(*col_dofs, wj) : std::string()) << ": analytic " << a(wi, wj)
      << ", fd " << d(wi, wj) << ", |error| " << std::abs(a(wi, wj) - d(wi, wj)) << ", tolerance "
      << worst_tol << " (scale " << scale << ", round-off " << noise << ", step " << opt.step
      << ")";
  if (worst_ratio <= 1.0) return ::testing::AssertionSuccess() << msg.str();
  if (a.size() <= 144) {
    const Eigen::IOFormat fmt(6, 0, " ", "\n", "  [", "]");
    msg << "\nanalytic:\n" << a.format(fmt) << "\nfinite differences:\n" << d.format(fmt);
  }
  return ::testing::AssertionFailure() << msg.str();
}

// ∇φ(δ) = blockdiag(I, J_l(δ_j)ᵀ) g(q ⊕ δ): gradient of the pulled-back function.
inline Eigen::VectorXd pulled_back_gradient(const GradientFunction& grad, const State& q,
                                            const Dofs& dofs, const Eigen::VectorXd& delta) {
  Eigen::VectorXd g = grad(perturb(q, dofs, delta));
  for (size_t b = 0; b < dofs.size(); ++b) {
    if (dofs[b].kind != DofKind::kRotation) continue;
    const Eigen::Index o = 3 * static_cast<Eigen::Index>(b);
    const Vector3 gb = g.segment<3>(o);
    g.segment<3>(o) = so3::left_jacobian(delta.segment<3>(o)).transpose() * gb;
  }
  return g;
}

}  // namespace detail

// Analytic Lie gradient g (3·dofs.size()) of f at q against central differences of f.
inline ::testing::AssertionResult check_lie_gradient(const ScalarFunction& f, const State& q,
                                                     const Dofs& dofs, const Eigen::VectorXd& g,
                                                     const FdOptions& opt = {}) {
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(dofs.size());
  if (g.size() != n) return ::testing::AssertionFailure() << "gradient has the wrong size";
  Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
  double magnitude = std::abs(f(q));
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!detail::compared(dofs, i)) continue;
    const double fp = f(perturb_one(q, dofs, i, opt.step));
    const double fm = f(perturb_one(q, dofs, i, -opt.step));
    magnitude = std::max({magnitude, std::abs(fp), std::abs(fm)});
    d(i) = (fp - fm) / (2.0 * opt.step);
  }
  return detail::compare("Lie gradient", g, d, dofs, nullptr, opt, noise_of(magnitude, opt.step));
}

// Analytic Lie Hessian H of f at q against central differences of the pulled-back analytic
// gradient (grad returns the Lie gradient of f at any state).
inline ::testing::AssertionResult check_lie_hessian(const GradientFunction& grad, const State& q,
                                                    const Dofs& dofs, const Eigen::MatrixXd& H,
                                                    FdOptions opt = {}) {
  if (opt.require_nonzero == NonZero::kEveryBlock) opt.require_nonzero = NonZero::kAny;
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(dofs.size());
  if (H.rows() != n || H.cols() != n) {
    return ::testing::AssertionFailure() << "Hessian has the wrong size";
  }
  const double asym = (H - H.transpose()).cwiseAbs().maxCoeff();
  if (asym > 1e-13 * H.cwiseAbs().maxCoeff()) {  // symmetric by construction: round-off only
    return ::testing::AssertionFailure() << "Lie Hessian is not symmetric: max |H − Hᵀ| = " << asym;
  }
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  double magnitude = grad(q).cwiseAbs().maxCoeff();
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!detail::compared(dofs, j)) continue;
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(n);
    delta(j) = opt.step;
    const Eigen::VectorXd gp = detail::pulled_back_gradient(grad, q, dofs, delta);
    delta(j) = -opt.step;
    const Eigen::VectorXd gm = detail::pulled_back_gradient(grad, q, dofs, delta);
    magnitude = std::max({magnitude, gp.cwiseAbs().maxCoeff(), gm.cwiseAbs().maxCoeff()});
    d.col(j) = (gp - gm) / (2.0 * opt.step);
  }
  return detail::compare("Lie Hessian (FD of pulled-back gradient)", H, d, dofs, &dofs, opt,
                         noise_of(magnitude, opt.step));
}

// Analytic Lie Hessian H of f at q against second central differences of φ(δ) = f(q ⊕ δ):
//   H_ij ≈ (φ(εe_i+εe_j) − φ(εe_i−εe_j) − φ(−εe_i+εe_j) + φ(−εe_i−εe_j)) / 4ε².
inline ::testing::AssertionResult check_lie_hessian_from_value(
    const ScalarFunction& f, const State& q, const Dofs& dofs, const Eigen::MatrixXd& H,
    FdOptions opt = value_hessian_defaults()) {
  if (opt.require_nonzero == NonZero::kEveryBlock) opt.require_nonzero = NonZero::kAny;
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(dofs.size());
  if (H.rows() != n || H.cols() != n) {
    return ::testing::AssertionFailure() << "Hessian has the wrong size";
  }
  const double e = opt.step;
  double magnitude = std::abs(f(q));
  const auto phi = [&](Eigen::Index i, double si, Eigen::Index j, double sj) {
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(n);
    delta(i) += si * e;
    delta(j) += sj * e;
    const double v = f(perturb(q, dofs, delta));
    magnitude = std::max(magnitude, std::abs(v));
    return v;
  };
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!detail::compared(dofs, i)) continue;
    for (Eigen::Index j = 0; j <= i; ++j) {
      if (!detail::compared(dofs, j)) continue;
      d(i, j) = (phi(i, 1, j, 1) - phi(i, 1, j, -1) - phi(i, -1, j, 1) + phi(i, -1, j, -1)) /
                (4.0 * e * e);
      d(j, i) = d(i, j);
    }
  }
  return detail::compare("Lie Hessian (second differences of value)", H, d, dofs, &dofs, opt,
                         noise_of(magnitude, e * e));
}

// Analytic tangent Jacobian J (3·out.size() × 3·in.size()) of F: State → State at q.
inline ::testing::AssertionResult check_jacobian(const StateFunction& F, const State& q,
                                                 const Dofs& in, const Dofs& out,
                                                 const Eigen::MatrixXd& J, FdOptions opt = {}) {
  if (opt.require_nonzero == NonZero::kEveryBlock) opt.require_nonzero = NonZero::kAny;
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(in.size());
  const Eigen::Index m = 3 * static_cast<Eigen::Index>(out.size());
  if (J.rows() != m || J.cols() != n) {
    return ::testing::AssertionFailure() << "Jacobian has the wrong size";
  }
  const State y0 = F(q);
  // Output points are differenced directly; output rotations through log of a near-identity
  // product of matrices with entries ≤ 1, whose round-off is O(eps).
  double magnitude = 1.0;
  const auto tangent = [&](const State& y) {
    Eigen::VectorXd t = Eigen::VectorXd::Zero(m);
    for (size_t b = 0; b < out.size(); ++b) {
      const Eigen::Index o = 3 * static_cast<Eigen::Index>(b);
      if (out[b].kind == DofKind::kPoint) {
        t.segment<3>(o) = y.points[out[b].index];
        magnitude = std::max(magnitude, y.points[out[b].index].cwiseAbs().maxCoeff());
      }
      if (out[b].kind == DofKind::kRotation) {
        t.segment<3>(o) =
            so3::log(y.rotations[out[b].index] * y0.rotations[out[b].index].transpose());
      }
    }
    return t;
  };
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(m, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!detail::compared(in, j)) continue;
    d.col(j) = (tangent(F(perturb_one(q, in, j, opt.step))) -
                tangent(F(perturb_one(q, in, j, -opt.step)))) /
               (2.0 * opt.step);
  }
  // Columns of non-DOF inputs are zero on both sides; rows are filtered by `out`.
  Eigen::MatrixXd a = J;
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!detail::compared(in, j)) a.col(j).setZero();
  }
  return detail::compare("Jacobian", a, d, out, nullptr, opt, noise_of(magnitude, opt.step));
}

// Analytic tangent Jacobian J (m × 3·dofs.size()) of a vector-valued F: State → R^m (e.g. a
// term's least-squares residual, term.hpp) against central differences
//   J(:, j) ≈ (F(q ⊕ εe_j) − F(q ⊖ εe_j)) / 2ε.
// `value_scale` is the size of the quantities F is computed from, for the round-off floor
// kNoiseUlps·eps·max(value_scale, max|F|)/ε: pass it when F is a small difference of large
// quantities (e.g. (R − R̃)S near R = R̃), whose absolute round-off max|F| does not bound.
// Compared as Jᵀ, so that rows are the input DOF blocks: with the default kEveryBlock, every
// compared block must move F (a block whose column of J is zero by mistake is caught).
// Columns of non-DOF blocks are not compared.
using VectorFunction = std::function<Eigen::VectorXd(const State&)>;

inline ::testing::AssertionResult check_vector_jacobian(const VectorFunction& F, const State& q,
                                                        const Dofs& dofs, const Eigen::MatrixXd& J,
                                                        const FdOptions& opt = {},
                                                        double value_scale = 0.0) {
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(dofs.size());
  const Eigen::VectorXd f0 = F(q);
  const Eigen::Index m = f0.size();
  if (J.rows() != m || J.cols() != n) {
    return ::testing::AssertionFailure()
           << "Jacobian is " << J.rows() << "×" << J.cols() << ", expected " << m << "×" << n;
  }
  double magnitude = std::max(value_scale, f0.cwiseAbs().maxCoeff());
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(m, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!detail::compared(dofs, j)) continue;
    const Eigen::VectorXd fp = F(perturb_one(q, dofs, j, opt.step));
    const Eigen::VectorXd fm = F(perturb_one(q, dofs, j, -opt.step));
    magnitude = std::max({magnitude, fp.cwiseAbs().maxCoeff(), fm.cwiseAbs().maxCoeff()});
    d.col(j) = (fp - fm) / (2.0 * opt.step);
  }
  const Eigen::MatrixXd at = J.transpose(), dt = d.transpose();
  return detail::compare("Jacobian of a vector function (transposed: rows are input DOFs)", at, dt,
                         dofs, nullptr, opt, noise_of(magnitude, opt.step));
}

// A term's residual vector (its least-squares form, lib/term.hpp) as a function of the state,
// for check_vector_jacobian. `term` is captured by reference.
template <class Term>
VectorFunction residual_of(const Term& term) {
  return [&term](const State& s) {
    typename Term::Residual r;
    term.residual(s, r, nullptr);
    return Eigen::VectorXd(r);
  };
}

// The local gradient at q of a term that freezes data at the start of a step (begin_step), as
// a function of the previous state: what its mixed block ∂C/∂q_{k−1} is the Jacobian of. A
// copy of the term is lagged again at every previous state; `term` and `q` are captured by
// reference.
template <class Term>
VectorFunction lagged_gradient(const Term& term, const State& q) {
  return [&term, &q](const State& previous) {
    Term t = term;
    t.begin_step(previous, Step{});
    LocalGradient<Term::kBlocks> g;
    t.evaluate(q, &g, nullptr);
    return Eigen::VectorXd(g);
  };
}

// ---------------------------------------------------------------------------------------
// Energy terms (lib/term.hpp): value, Lie gradient and Lie Hessian of term.evaluate over all
// its blocks; `dofs` maps the term's local blocks to the state (no_dof() for world anchors).
struct TermCheckOptions {
  FdOptions gradient;
  FdOptions hessian;
  FdOptions hessian_from_value = value_hessian_defaults();
};

// A world-torque potential −τ·vee(R R_refᵀ) (ConstantTorque, RotationHistory) of |τ| up to
// `magnitude`: its derivatives of every order are bounded by |τ|, so the FD truncation is
// ≲ ε²|τ|, an absolute floor that matters only near R = R_ref, where the Hessian vanishes
// (V = −τ·θ + O(θ³) there) — and is not required to be non-zero within `near` of it.
inline TermCheckOptions torque_potential_options(double magnitude, bool near_reference) {
  TermCheckOptions o;
  o.hessian.abs_floor = o.hessian.step * o.hessian.step * magnitude;
  o.hessian_from_value.abs_floor =
      o.hessian_from_value.step * o.hessian_from_value.step * magnitude;
  if (near_reference) {
    o.hessian.require_nonzero = NonZero::kNone;
    o.hessian_from_value.require_nonzero = NonZero::kNone;
  }
  return o;
}

// Steps for a term checked where its smooth zone is only `zone` wide (friction's ε = ε_v h at
// a tiny h): 1e-4·zone for first differences (truncation ~step²/(y·zone)), 1e-3·zone for
// second differences of the value. Only some entry need be non-zero: at such scales the
// rotation rows (lever × force, levers of a few hundred zones) fall below what a check
// relative to the largest entry can call non-zero; they are compared all the same.
inline TermCheckOptions within_zone(double zone) {
  TermCheckOptions o;
  o.gradient.step = 1e-4 * zone;
  o.hessian.step = 1e-4 * zone;
  o.hessian_from_value.step = 1e-3 * zone;
  o.gradient.require_nonzero = NonZero::kAny;
  o.hessian.require_nonzero = NonZero::kAny;
  return o;
}

// Steps for a friction term (lib/friction.hpp) at O(1) geometry with slips y ≥ 3e-3 and a
// stick zone ε ~ 1e-2, its switch y = ε ≥ 1e-3 from every slip. D depends on y, whose fourth
// derivative is ~1/y³, so second differences of the value take a step 1e-5 ≤ y/300
// (truncation ≤ 1e-5 relative). Differences of the gradient have truncation step²/6 · ∂⁴D
// with ∂⁴D ~ 2μλ/(ε² y) ≈ 5e8 in the stick zone (its cubic through y): 1e-4 at the default
// step, ~1e-8 of the Hessian's scale; a step of 2e-7 brings it 25× below the 1e-9 floor,
// while the round-off 16 eps|g|/step stays ~1e-6.
inline TermCheckOptions stick_zone() {
  TermCheckOptions o;
  o.gradient.step = 2e-7;
  o.hessian.step = 2e-7;
  o.hessian_from_value.step = 1e-5;
  return o;
}

template <class Term>
::testing::AssertionResult check_term(const Term& term, const State& q, const Dofs& dofs,
                                      const TermCheckOptions& opt = {}) {
  constexpr int B = Term::kBlocks;
  if (static_cast<int>(dofs.size()) != B) {
    return ::testing::AssertionFailure() << "dofs must list the term's " << B << " blocks";
  }
  LocalGradient<B> g;
  LocalHessian<B> H;
  const double value = term.evaluate(q, &g, &H);
  const double value_only = term.evaluate(q, nullptr, nullptr);
  // The value must not depend on whether derivatives are requested (same formula: exact).
  if (value != value_only) {
    return ::testing::AssertionFailure()
           << "evaluate returns " << value << " with derivatives but " << value_only << " without";
  }
  const ScalarFunction f = [&term](const State& s) { return term.evaluate(s, nullptr, nullptr); };
  const GradientFunction grad = [&term](const State& s) {
    LocalGradient<B> gs;
    term.evaluate(s, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  ::testing::AssertionResult r = check_lie_gradient(f, q, dofs, g, opt.gradient);
  if (!r) return r;
  r = check_lie_hessian(grad, q, dofs, H, opt.hessian);
  if (!r) return r;
  return check_lie_hessian_from_value(f, q, dofs, H, opt.hessian_from_value);
}

// ---------------------------------------------------------------------------------------
// Constants shared by the suites, defined once: each test file's own copy would be a
// redefinition where a unity build compiles several test files as one.

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kEps = std::numeric_limits<double>::epsilon();
inline constexpr double kDeg = kPi / 180.0;  // one degree in radians
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------
// Test points shared by the term suites.

// Rotation angles every term is evaluated at: 0, tiny, the Taylor-branch switch, ordinary,
// near π and π, near 2π (docs/design.md §1.6: the extremes of the parameterisation).
inline const std::vector<double> kAngles = {
    0.0, 1e-9, 1e-4, 1.0, 2.5, std::numbers::pi - 1e-6, std::numbers::pi,
    2.0 * std::numbers::pi - 1e-3, 2.0 * std::numbers::pi - 1e-6};

inline Vector3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Vector3(normal(rng), normal(rng), normal(rng)).normalized();
}

inline Vector3 random_vector(std::mt19937& rng, double size) {
  std::uniform_real_distribution<double> u(-size, size);
  return Vector3(u(rng), u(rng), u(rng));
}

inline Matrix3 rotation_at(double angle, std::mt19937& rng) {
  return so3::exp(angle * random_unit(rng));
}

// A body-frame inertia tensor obeying the triangle inequality (1 + 1.6 > 2.2), rotated.
inline Matrix3 body_inertia(double scale, std::mt19937& rng) {
  const Matrix3 Q = rotation_at(1.3, rng);
  return scale * Q * Eigen::Vector3d(1.0, 1.6, 2.2).asDiagonal() * Q.transpose();
}

// A random unit vector perpendicular to the unit vector n.
inline Vector3 random_perpendicular(const Vector3& n, std::mt19937& rng) {
  const Vector3 u = random_unit(rng);
  return (u - u.dot(n) * n).normalized();
}

// The power of two nearest to x > 0 (scalings by it are exact).
inline double power_of_two_near(double x) { return std::exp2(std::round(std::log2(x))); }

// "what a b c" at full precision, for SCOPED_TRACE.
inline std::string trace(const char* what, double a, double b = 0.0, double c = 0.0) {
  std::ostringstream s;
  s.precision(17);
  s << what << " " << a << " " << b << " " << c;
  return s.str();
}

// "angle a, axis x y z" at full precision, for SCOPED_TRACE.
inline std::string where(double angle, const Vector3& axis) {
  std::ostringstream s;
  s.precision(17);
  s << "angle " << angle << ", axis " << axis.transpose();
  return s.str();
}

}  // namespace liedyn::fd

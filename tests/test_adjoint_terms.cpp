// The adjoint blocks of the energy terms and of the assembled potential (paper §5, docs/design.md
// §8): derivatives of a term's Lie gradient C (what evaluate() writes into g) with respect to
// things other than the current state q, against central finite differences of C itself,
// with the comparison, round-off floor and non-zero requirement of tests/fd_check.hpp.
//
//   * Step blocks. ∂C/∂q_{k−1} and ∂C/∂Δq_{k−1} with q held fixed: previous points and steps
//     are perturbed additively, previous rotations and steps on the LEFT,
//     R_{k−1} → exp(φ) R_{k−1}, ΔR_{k−1} → exp(ψ) ΔR_{k−1}; begin_step is called again and C
//     evaluated at the SAME q. C is then a plain vector (no pull-back: q does not move).
//   * Parameter blocks. ∂C/∂γ for the quantities the adjoint optimises (forces, torques, rest
//     Darboux vectors, stiffnesses; cable tensions at the potential level, the term's own
//     tension_gradient being checked in tests/test_cable.cpp). C is linear in each of them, so
//     the FD step may scale with the parameter: parameters are differenced in units of a power
//     of two near their size (exact scalings, as tests/test_rod_terms.cpp's ScaledPoints does
//     for positions), and the analytic Jacobian is scaled alike.
//   * The potential-level functions IncrementalPotential::add_step_adjoint and
//     add_parameter_adjoint (lib/adjoint.cpp): for random z, their outputs against the
//     gradient of the scalar z·C(·) by finite differences, C the assembled component gradient;
//     that gradient is Jᵀz.
//
// Tolerances: fd_check.hpp's defaults (rtol 1e-6, floor 1e-9 of the object's scale) and its
// computed round-off floor 16·eps·(size of what C is computed from)/ε. Where C is a small
// difference of large numbers (inertia near R = R̃, x = x̃; ω = vee(R_aᵀR_b)/l) that size is
// passed as check_vector_jacobian's value_scale and derived at the call.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "fd_check.hpp"
#include "lib/incremental_potential.hpp"
#include "lib/inertia.hpp"
#include "lib/joint_terms.hpp"
#include "lib/loads.hpp"
#include "lib/model.hpp"
#include "lib/rod_terms.hpp"
#include "lib/so3.hpp"
#include "lib/spring.hpp"
#include "lib/trajectory.hpp"
#include "models.hpp"
#include "rod_models.hpp"

namespace liedyn::adjoint_terms_tests {
namespace {

using fd::kAngles;
using fd::power_of_two_near;
using fd::random_perpendicular;
using fd::random_unit;
using fd::random_vector;
using fd::rotation_at;
using fd::trace;
using fd::kPi;
using fd::kDeg;
using fd::body_inertia;

Step as_step(const State& s) {
  Step step;
  step.points = s.points;
  step.rotations = s.rotations;
  return step;
}

State as_state(const Step& step) {
  State s;
  s.points = step.points;
  s.rotations = step.rotations;
  return s;
}

// ----------------------------------------------------------------------------------------
// Parameter Jacobians through fd::check_vector_jacobian.
//
// A parameter vector p ∈ Rⁿ is differenced in units u = p ./ unit (entrywise; `unit` holds
// powers of two, so p = unit .* u is exact). u is stored as the points of a State, 3 entries
// per point and zero-padded, so that check_vector_jacobian's additive point perturbations
// difference u. The analytic side is ∂F/∂u = J diag(unit) (padding columns zero). Blocks
// whose `compared` flag is false are not compared (their FD rows are not computed).
using ParameterFunction = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

Eigen::Index blocks_of(Eigen::Index n) { return (n + 2) / 3; }

State parameters_as_state(const Eigen::VectorXd& u) {
  State s;
  s.points.assign(static_cast<size_t>(blocks_of(u.size())), Vector3::Zero());
  for (Eigen::Index i = 0; i < u.size(); ++i) s.points[static_cast<size_t>(i / 3)](i % 3) = u(i);
  return s;
}

Eigen::VectorXd state_as_parameters(const State& s, Eigen::Index n) {
  Eigen::VectorXd u(n);
  for (Eigen::Index i = 0; i < n; ++i) u(i) = s.points[static_cast<size_t>(i / 3)](i % 3);
  return u;
}

::testing::AssertionResult check_parameter_jacobian(const ParameterFunction& F,
                                                    const Eigen::VectorXd& p,
                                                    const Eigen::VectorXd& unit,
                                                    const Eigen::MatrixXd& J,
                                                    const fd::FdOptions& opt = {},
                                                    double value_scale = 0.0,
                                                    const std::vector<bool>& compared = {}) {
  const Eigen::Index n = p.size();
  const Eigen::Index blocks = blocks_of(n);
  fd::Dofs dofs(static_cast<size_t>(blocks), fd::no_dof());
  for (Eigen::Index b = 0; b < blocks; ++b) {
    if (compared.empty() || compared[static_cast<size_t>(b)]) {
      dofs[static_cast<size_t>(b)] = fd::point_dof(static_cast<int>(b));
    }
  }
  const fd::VectorFunction G = [&](const State& s) {
    return F(unit.cwiseProduct(state_as_parameters(s, n)));
  };
  Eigen::MatrixXd J_u = Eigen::MatrixXd::Zero(J.rows(), 3 * blocks);
  J_u.leftCols(n) = J * unit.asDiagonal();
  return fd::check_vector_jacobian(G, parameters_as_state(p.cwiseQuotient(unit)), dofs, J_u, opt,
                                   value_scale);
}

// The unit of a parameter of size `size`: the nearest power of two (1 for size 0).
double unit_of(double size) { return size > 0.0 ? power_of_two_near(size) : 1.0; }

Eigen::VectorXd units_of(const Eigen::VectorXd& p) {
  Eigen::VectorXd unit(p.size());
  for (Eigen::Index i = 0; i < p.size(); ++i) unit(i) = unit_of(std::abs(p(i)));
  return unit;
}

// ----------------------------------------------------------------------------------------
// Translational inertia: C = m/h² (x − x_{k−1} − Δx_{k−1}), ∂C/∂x_{k−1} = ∂C/∂Δx_{k−1} = −m/h².

TEST(AdjointTermTranslationalInertia, StepJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(1001);
  int checked = 0;
  for (const double h : {1e-6, 1e-2, 1.0}) {
    for (const double mass : {1e-9, 1.0, 1e6}) {
      for (int run = 0; run < 3; ++run) {
        SCOPED_TRACE(trace("h, m, run", h, mass, run));
        TranslationalInertia term;
        term.point = 0;
        term.mass_over_h2 = mass / (h * h);
        State previous;
        previous.points = {random_vector(rng, 1.0)};
        Step step;
        step.points = {random_vector(rng, 0.5)};
        State q;
        q.points = {random_vector(rng, 1.0)};
        term.begin_step(previous, step);
        EXPECT_EQ(term.step_jacobian(), -term.mass_over_h2);
        const Eigen::MatrixXd J = term.step_jacobian() * Matrix3::Identity();

        // C = a (x − x̃) is computed from x and x̃ = x_{k−1} + Δx_{k−1}: round-off a few
        // eps·a·(|x| + |x̃|) however small x − x̃ is.
        const double value_scale = term.mass_over_h2 * (q.points[0].cwiseAbs().maxCoeff() +
                                                        term.x_tilde.cwiseAbs().maxCoeff());
        const fd::VectorFunction of_previous = [&](const State& s) {
          TranslationalInertia t = term;
          t.begin_step(s, step);
          LocalGradient<1> g;
          t.evaluate(q, &g, nullptr);
          return Eigen::VectorXd(g);
        };
        EXPECT_TRUE(fd::check_vector_jacobian(of_previous, previous, {fd::point_dof(0)}, J, {},
                                              value_scale));
        const fd::VectorFunction of_step = [&](const State& s) {
          TranslationalInertia t = term;
          t.begin_step(previous, as_step(s));
          LocalGradient<1> g;
          t.evaluate(q, &g, nullptr);
          return Eigen::VectorXd(g);
        };
        EXPECT_TRUE(fd::check_vector_jacobian(of_step, as_state(step), {fd::point_dof(0)}, J, {},
                                              value_scale));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 27);
}

// ----------------------------------------------------------------------------------------
// Rotational inertia: C = 2 vee(R J R̃ᵀ)/h², R̃ = (2I − ΔR_{k−1}ᵀ) R_{k−1}.

struct RotationalInertiaCase {
  RotationalInertia term;
  State previous;
  Step step;
  State q;
};

// step_jacobians at one point against FD in R_{k−1} and ΔR_{k−1}.
::testing::AssertionResult check_rotational_step_jacobians(const RotationalInertiaCase& c) {
  Matrix3 d_previous, d_step;
  c.term.step_jacobians(c.q, c.previous.rotations[0], c.step.rotations[0], d_previous, d_step);
  // C = 2 vee(M), M = R (J/h²) R̃ᵀ: its entries carry a few eps·‖J/h²‖‖R̃‖ of round-off however
  // small C is (R near R̃), ‖R̃‖ ≤ ‖2I − ΔRᵀ‖ ≤ 3. That is what the FD of C resolves.
  const double value_scale = c.term.J_over_h2.norm() * 3.0;
  const fd::VectorFunction of_previous = [&](const State& s) {
    RotationalInertia t = c.term;
    t.begin_step(s, c.step);
    LocalGradient<1> g;
    t.evaluate(c.q, &g, nullptr);
    return Eigen::VectorXd(g);
  };
  ::testing::AssertionResult r =
      fd::check_vector_jacobian(of_previous, c.previous, {fd::rotation_dof(0)},
                                Eigen::MatrixXd(d_previous), {}, value_scale);
  if (!r) return ::testing::AssertionFailure() << "dC/dR_{k-1}: " << r.message();
  const fd::VectorFunction of_step = [&](const State& s) {
    RotationalInertia t = c.term;
    t.begin_step(c.previous, as_step(s));
    LocalGradient<1> g;
    t.evaluate(c.q, &g, nullptr);
    return Eigen::VectorXd(g);
  };
  r = fd::check_vector_jacobian(of_step, as_state(c.step), {fd::rotation_dof(0)},
                                Eigen::MatrixXd(d_step), {}, value_scale);
  if (!r) return ::testing::AssertionFailure() << "dC/ddR_{k-1}: " << r.message();
  return ::testing::AssertionSuccess();
}

TEST(AdjointTermRotationalInertia, StepJacobiansMatchFiniteDifferencesOverAllAngles) {
  // Every triple of angles (R_{k−1}, ΔR_{k−1}, R) from kAngles, at extreme time steps and
  // inertias: J/h² spans 1e-9 … 1e18, and every comparison is relative to it.
  std::mt19937 rng(1002);
  int checked = 0;
  for (const double h : {1e-6, 1e-2, 1.0}) {
    for (const double scale : {1e-9, 1.0, 1e6}) {
      const Matrix3 J = rotational_mass(body_inertia(scale, rng));
      for (const double a_prev : kAngles) {
        for (const double a_step : kAngles) {
          for (const double a : kAngles) {
            SCOPED_TRACE(trace("angles R_{k-1}, dR_{k-1}, R", a_prev, a_step, a));
            SCOPED_TRACE(trace("h, inertia scale", h, scale));
            RotationalInertiaCase c;
            c.term.rotation = 0;
            c.term.J_over_h2 = J / (h * h);
            c.previous.rotations = {rotation_at(a_prev, rng)};
            c.step.rotations = {rotation_at(a_step, rng)};
            c.q.rotations = {rotation_at(a, rng)};
            c.term.begin_step(c.previous, c.step);
            EXPECT_TRUE(check_rotational_step_jacobians(c));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 9 * static_cast<int>(kAngles.size() * kAngles.size() * kAngles.size()));
}

TEST(AdjointTermRotationalInertia, StepJacobiansAtRestAndAlongASteadySpin) {
  // The points where C itself vanishes or is third order (R = R̃, a steady spin about a
  // symmetry axis; see tests/test_terms.cpp): the Jacobians do not vanish there, and must
  // still match. At ΔR = I, R = R_{k−1}: ∂C/∂φ = −2 vee(B hat(e_j)) column-wise, B = R J Rᵀ/h²
  // symmetric, i.e. −(tr(B) I − B) = −(world inertia)/h², and ∂C/∂ψ the same.
  std::mt19937 rng(1003);
  for (const double a : kAngles) {
    for (const double phi : {0.0, 1e-3, 1.0, 3.0}) {
      SCOPED_TRACE(trace("angle of R_{k-1}, spin angle", a, phi));
      RotationalInertiaCase c;
      c.term.rotation = 0;
      const Matrix3 Q = rotation_at(0.9, rng);
      const Matrix3 I_b = Q * Eigen::Vector3d(2.0, 2.0, 3.0).asDiagonal() * Q.transpose();
      c.term.J_over_h2 = rotational_mass(I_b) / 1e-4;
      c.previous.rotations = {rotation_at(a, rng)};
      const Vector3 n = c.previous.rotations[0] * Q * Vector3::UnitZ();
      c.step.rotations = {so3::exp(phi * n)};
      c.q.rotations = {c.step.rotations[0] * c.previous.rotations[0]};
      c.term.begin_step(c.previous, c.step);
      EXPECT_TRUE(check_rotational_step_jacobians(c));
      if (phi == 0.0) {
        Matrix3 d_previous, d_step;
        c.term.step_jacobians(c.q, c.previous.rotations[0], c.step.rotations[0], d_previous,
                              d_step);
        const Matrix3& R = c.previous.rotations[0];
        const Matrix3 B = R * c.term.J_over_h2 * R.transpose();
        const Matrix3 expected = -(B.trace() * Matrix3::Identity() - B);
        // Round-off of products of O(1) rotations with J/h²: a few eps·‖J/h²‖.
        const double tol = 64 * std::numeric_limits<double>::epsilon() * c.term.J_over_h2.norm();
        EXPECT_LE((d_previous - expected).norm(), tol);
        EXPECT_LE((d_step - expected).norm(), tol);
      }
    }
  }
}

// ----------------------------------------------------------------------------------------
// Constant torque: C = −½ s (tr(P) τ − Pᵀτ), P = R R_{k−1}ᵀ.

TEST(AdjointTermConstantTorque, TorqueJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(1004);
  int checked = 0;
  for (const double magnitude : {1e-3, 1.0, 1e6}) {
    for (const double scale : {1.0, 0.375}) {  // load factor λ (static mode) ≠ 1 too
      for (const double a_prev : kAngles) {
        for (const double a : kAngles) {
          SCOPED_TRACE(trace("|τ|, scale", magnitude, scale));
          SCOPED_TRACE(trace("angles R_{k-1}, R", a_prev, a));
          ConstantTorque term;
          term.rotation = 0;
          term.torque = magnitude * random_unit(rng);
          term.scale = scale;
          State previous;
          previous.rotations = {rotation_at(a_prev, rng)};
          term.begin_step(previous, Step{});
          State q;
          q.rotations = {rotation_at(a, rng)};
          const ParameterFunction of_torque = [&](const Eigen::VectorXd& tau) {
            ConstantTorque t = term;
            t.torque = tau;
            LocalGradient<1> g;
            t.evaluate(q, &g, nullptr);
            return Eigen::VectorXd(g);
          };
          const Eigen::VectorXd tau = term.torque;
          EXPECT_TRUE(check_parameter_jacobian(of_torque, tau,
                                               Eigen::Vector3d::Constant(unit_of(magnitude)),
                                               Eigen::MatrixXd(term.torque_jacobian(q))));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 6 * static_cast<int>(kAngles.size() * kAngles.size()));
}

TEST(AdjointTermConstantTorque, PreviousJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(1005);
  int checked = 0;
  for (const double magnitude : {1e-3, 1.0, 1e6}) {
    for (const double scale : {1.0, 0.375}) {
      for (const double a_prev : kAngles) {
        for (const double a : kAngles) {
          SCOPED_TRACE(trace("|τ|, scale", magnitude, scale));
          SCOPED_TRACE(trace("angles R_{k-1}, R", a_prev, a));
          ConstantTorque term;
          term.rotation = 0;
          term.torque = magnitude * random_unit(rng);
          term.scale = scale;
          State previous;
          previous.rotations = {rotation_at(a_prev, rng)};
          term.begin_step(previous, Step{});
          State q;
          q.rotations = {rotation_at(a, rng)};
          const fd::VectorFunction of_previous = [&](const State& s) {
            ConstantTorque t = term;
            t.begin_step(s, Step{});
            LocalGradient<1> g;
            t.evaluate(q, &g, nullptr);
            return Eigen::VectorXd(g);
          };
          // C is computed from P (entries ≤ 1) and sτ: round-off a few eps·s|τ|.
          EXPECT_TRUE(fd::check_vector_jacobian(of_previous, previous, {fd::rotation_dof(0)},
                                                Eigen::MatrixXd(term.previous_jacobian(q)), {},
                                                scale * magnitude));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 6 * static_cast<int>(kAngles.size() * kAngles.size()));
}

// ----------------------------------------------------------------------------------------
// Hinge motor (lib/joint_terms.hpp): τ ê on a, −τ ê on b, ê = R_{a,k−1} â. Its value,
// gradient and Hessian, and its two adjoint blocks — ∂C/∂(R_{a,k−1}, R_{b,k−1}) (through both
// P's and the lagged axis) and ∂C/∂τ — by finite differences, over the angle list for the
// previous and current rotations, |τ| from 1e-3 to 1e6, load scale 1 and 0.375, end b a body
// or the world.

struct MotorCase {
  JointMotor term;
  State previous, q;
};

MotorCase motor_case(double magnitude, double scale, double a_prev, double a, bool world_b,
                     std::mt19937& rng) {
  MotorCase c;
  c.term.rotation_a = 0;
  c.term.rotation_b = world_b ? -1 : 1;
  c.term.offsets = {0, world_b ? -1 : 3};
  c.term.axis_a = random_unit(rng);
  c.term.torque = magnitude * (rng() % 2 == 0 ? 1.0 : -1.0);
  c.term.scale = scale;
  c.previous.rotations = {rotation_at(a_prev, rng), rotation_at(0.7, rng)};
  c.q.rotations = {rotation_at(a, rng), rotation_at(a_prev, rng)};
  c.term.begin_step(c.previous, Step{});
  return c;
}

TEST(AdjointTermJointMotor, ValueGradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(1031);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double magnitude : {1e-3, 1.0, 1e6}) {
      for (const double a_prev : kAngles) {
        for (const double a : kAngles) {
          SCOPED_TRACE(trace("world b, |τ|", world_b, magnitude));
          SCOPED_TRACE(trace("angles R_{k-1}, R", a_prev, a));
          const MotorCase c = motor_case(magnitude, 0.375, a_prev, a, world_b, rng);
          // As for ConstantTorque (tests/test_terms.cpp): derivatives of every order are
          // bounded by |τ|, so FD truncation is ≲ ε²|τ|, and where a step P = R R_{k−1}ᵀ is
          // near I its block of the Hessian vanishes (V = −τ·θ + O(θ³)).
          fd::TermCheckOptions opt;
          opt.hessian.abs_floor = opt.hessian.step * opt.hessian.step * magnitude;
          opt.hessian_from_value.abs_floor =
              opt.hessian_from_value.step * opt.hessian_from_value.step * magnitude;
          const bool small_step_a = so3::distance(c.q.rotations[0], c.previous.rotations[0]) < 1e-3;
          const bool small_step_b = so3::distance(c.q.rotations[1], c.previous.rotations[1]) < 1e-3;
          if (small_step_a || (!world_b && small_step_b)) {
            opt.hessian.require_nonzero = small_step_a && (world_b || small_step_b)
                                              ? fd::NonZero::kNone
                                              : fd::NonZero::kAny;
            opt.hessian_from_value.require_nonzero = opt.hessian.require_nonzero;
          }
          EXPECT_TRUE(fd::check_term(c.term, c.q,
                                     {fd::rotation_dof(0), world_b ? fd::no_dof() : fd::rotation_dof(1)},
                                     opt));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 6 * static_cast<int>(kAngles.size() * kAngles.size()));
}

// Helpers of the two motors' adjoint checks (they differ in their ends' loads only).
// ∂C/∂(R_{k−1}) of the first `rotations` previous rotations, row by row from add_step_adjoint
// with unit z; a motor reads nothing else of the previous state or step (asserted).
template <class T>
Eigen::MatrixXd previous_rotations_jacobian(const T& term, const State& q, const State& previous,
                                            int rotations) {
  constexpr int n = 3 * T::kBlocks;
  Eigen::MatrixXd J(n, 3 * rotations);
  for (int i = 0; i < n; ++i) {
    LocalGradient<T::kBlocks> z = LocalGradient<T::kBlocks>::Zero();
    z(i) = 1.0;
    Eigen::VectorXd a_previous = Eigen::VectorXd::Zero(tangent_size(q));
    Eigen::VectorXd da_previous = Eigen::VectorXd::Zero(tangent_size(q));
    term.add_step_adjoint(q, previous, Step{}, z, a_previous, da_previous);
    EXPECT_EQ(da_previous.squaredNorm(), 0.0);  // no dependence on the previous step
    J.row(i) = a_previous.segment(tangent_rotation(q, 0), 3 * rotations).transpose();
    a_previous.segment(tangent_rotation(q, 0), 3 * rotations).setZero();
    EXPECT_EQ(a_previous.squaredNorm(), 0.0);
  }
  return J;
}

// C as a function of the previous state (begin_step again, C at the same q).
template <class T>
fd::VectorFunction gradient_of_previous(const T& term, const State& q) {
  return [term, &q](const State& s) {
    T t = term;
    t.begin_step(s, Step{});
    LocalGradient<T::kBlocks> g;
    t.evaluate(q, &g, nullptr);
    return Eigen::VectorXd(g);
  };
}

// ∂C/∂(the scheduled effort), from add_parameter_adjoint with unit z (slot 0 for frame 1).
template <class T>
Eigen::MatrixXd effort_jacobian(T term, const State& q) {
  constexpr int n = 3 * T::kBlocks;
  term.control.slot = 0;
  Eigen::MatrixXd J(n, 1);
  for (int i = 0; i < n; ++i) {
    LocalGradient<T::kBlocks> z = LocalGradient<T::kBlocks>::Zero();
    z(i) = 1.0;
    Eigen::VectorXd dgamma = Eigen::VectorXd::Zero(1);
    term.add_parameter_adjoint(q, 1, z, dgamma);
    J(i, 0) = dgamma(0);
  }
  return J;
}

// C as a function of the effort (a torque or force member `effort` of T).
template <class T>
ParameterFunction gradient_of_effort(const T& term, const State& q, double T::*effort) {
  return [term, &q, effort](const Eigen::VectorXd& value) {
    T t = term;
    t.*effort = value(0);
    LocalGradient<T::kBlocks> g;
    t.evaluate(q, &g, nullptr);
    return Eigen::VectorXd(g);
  };
}

TEST(AdjointTermJointMotor, PreviousStepAndTorqueJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(1032);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double magnitude : {1e-3, 1.0, 1e6}) {
      for (const double scale : {1.0, 0.375}) {
        for (const double a_prev : kAngles) {
          for (const double a : {0.0, 1e-9, 1.0, kPi - 1e-6, kPi}) {
            SCOPED_TRACE(trace("world b, |τ|, scale", world_b, magnitude, scale));
            SCOPED_TRACE(trace("angles R_{k-1}, R", a_prev, a));
            const MotorCase c = motor_case(magnitude, scale, a_prev, a, world_b, rng);
            // ∂C/∂(R_{a,k−1}, R_{b,k−1}). The world's (b's) previous rotation is not a DOF.
            Eigen::MatrixXd J = previous_rotations_jacobian(c.term, c.q, c.previous, world_b ? 1 : 2);
            if (world_b) J.conservativeResize(Eigen::NoChange, 6), J.rightCols<3>().setZero();
            // C is built from P and ê (entries ≤ 1) times s|τ|.
            EXPECT_TRUE(fd::check_vector_jacobian(
                gradient_of_previous(c.term, c.q), c.previous,
                {fd::rotation_dof(0), world_b ? fd::no_dof() : fd::rotation_dof(1)}, J, {},
                scale * magnitude));
            EXPECT_TRUE(check_parameter_jacobian(gradient_of_effort(c.term, c.q, &JointMotor::torque),
                                                 Eigen::VectorXd::Constant(1, c.term.torque),
                                                 Eigen::VectorXd::Constant(1, unit_of(magnitude)),
                                                 effort_jacobian(c.term, c.q)));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 12 * 5 * static_cast<int>(kAngles.size()));
}

// ----------------------------------------------------------------------------------------
// Slider motor (lib/joint_terms.hpp): −f ê at a's point, +f ê at b's, ê = R_{a,k−1} â. Its
// value, gradient and Hessian over (x_a, θ_a, x_b, θ_b), and its adjoint blocks ∂C/∂R_{a,k−1}
// (through the lagged axis) and ∂C/∂f, by finite differences over the angle list for the
// previous and current rotations of a (b at a generic angle), |f| from 1e-3 to 1e6, load
// scale 1 and 0.375, end b a body or the world.

struct ForceMotorCase {
  JointForceMotor term;
  State previous, q;
};

ForceMotorCase force_motor_case(double magnitude, double scale, double a_prev, double a,
                                bool world_b, std::mt19937& rng) {
  ForceMotorCase c;
  c.term.a = {0, 0, random_vector(rng, 1.0)};
  c.term.b = world_b ? AttachedPoint{-1, -1, random_vector(rng, 1.0)}
                     : AttachedPoint{1, 1, random_vector(rng, 1.0)};
  c.term.offsets = {0, 6, world_b ? -1 : 3, world_b ? -1 : 9};
  c.term.axis_a = random_unit(rng);
  c.term.force = magnitude * (rng() % 2 == 0 ? 1.0 : -1.0);
  c.term.scale = scale;
  c.previous.points = {random_vector(rng, 1.0), random_vector(rng, 1.0)};
  c.previous.rotations = {rotation_at(a_prev, rng), rotation_at(0.7, rng)};
  c.q.points = {random_vector(rng, 1.0), random_vector(rng, 1.0)};
  c.q.rotations = {rotation_at(a, rng), rotation_at(2.5, rng)};
  c.term.begin_step(c.previous, Step{});
  return c;
}

fd::Dofs force_motor_dofs(bool world_b) {
  return {fd::point_dof(0), fd::rotation_dof(0), world_b ? fd::no_dof() : fd::point_dof(1),
          world_b ? fd::no_dof() : fd::rotation_dof(1)};
}

TEST(AdjointTermJointForceMotor, ValueGradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(1033);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double magnitude : {1e-3, 1.0, 1e6}) {
      for (const double a_prev : kAngles) {
        for (const double a : kAngles) {
          SCOPED_TRACE(trace("world b, |f|", world_b, magnitude));
          SCOPED_TRACE(trace("angles R_{a,k-1}, R_a", a_prev, a));
          const ForceMotorCase c = force_motor_case(magnitude, 0.375, a_prev, a, world_b, rng);
          // Linear in x: the translation rows of the Hessian are zero, its rotation blocks
          // (the levers' curvature, eq. 23) are not.
          fd::TermCheckOptions opt;
          opt.hessian.require_nonzero = fd::NonZero::kAny;
          EXPECT_TRUE(fd::check_term(c.term, c.q, force_motor_dofs(world_b), opt));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 6 * static_cast<int>(kAngles.size() * kAngles.size()));
}

TEST(AdjointTermJointForceMotor, PreviousStepAndForceJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(1034);
  int checked = 0;
  for (const bool world_b : {false, true}) {
    for (const double magnitude : {1e-3, 1.0, 1e6}) {
      for (const double scale : {1.0, 0.375}) {
        for (const double a_prev : kAngles) {
          for (const double a : {0.0, 1e-9, 1.0, kPi - 1e-6, kPi}) {
            SCOPED_TRACE(trace("world b, |f|, scale", world_b, magnitude, scale));
            SCOPED_TRACE(trace("angles R_{a,k-1}, R_a", a_prev, a));
            const ForceMotorCase c = force_motor_case(magnitude, scale, a_prev, a, world_b, rng);
            // ∂C/∂R_{a,k−1} (only a's previous rotation is read: the lagged axis).
            EXPECT_TRUE(fd::check_vector_jacobian(gradient_of_previous(c.term, c.q), c.previous,
                                                  {fd::rotation_dof(0)},
                                                  previous_rotations_jacobian(c.term, c.q, c.previous, 1)));
            EXPECT_TRUE(check_parameter_jacobian(gradient_of_effort(c.term, c.q, &JointForceMotor::force),
                                                 Eigen::VectorXd::Constant(1, c.term.force),
                                                 Eigen::VectorXd::Constant(1, unit_of(magnitude)),
                                                 effort_jacobian(c.term, c.q)));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 12 * 5 * static_cast<int>(kAngles.size()));
}

// ----------------------------------------------------------------------------------------
// Constant force: C = s (−F, r × (−F)), blocks (x, θ).

enum class Lever { kRotating, kTranslating, kNone };

TEST(AdjointTermConstantForce, ForceJacobianMatchesFiniteDifferences) {
  // With a lever on a rotation (p = x + R p̄), a translating offset (rotation −1, p = x + p̄:
  // the θ rows are written by evaluate() but are not DOFs), and none (a rod node force).
  std::mt19937 rng(1006);
  int checked = 0;
  for (const Lever lever : {Lever::kRotating, Lever::kTranslating, Lever::kNone}) {
    for (const double magnitude : {1e-3, 1.0, 1e6}) {
      for (const double scale : {1.0, 0.375, 3.0}) {
        for (const double a : kAngles) {
          SCOPED_TRACE(trace("lever kind, |F|, scale", static_cast<double>(lever), magnitude,
                             scale));
          SCOPED_TRACE(trace("angle", a));
          ConstantForce term;
          term.at.point = 0;
          term.at.rotation = lever == Lever::kRotating ? 0 : -1;
          term.at.local = lever == Lever::kNone ? Vector3::Zero() : random_vector(rng, 1.0);
          term.force = magnitude * random_unit(rng);
          term.scale = scale;
          State q;
          q.points = {random_vector(rng, 1.0)};
          q.rotations = {rotation_at(a, rng)};
          const ParameterFunction of_force = [&](const Eigen::VectorXd& F) {
            ConstantForce t = term;
            t.force = F;
            LocalGradient<2> g;
            t.evaluate(q, &g, nullptr);
            return Eigen::VectorXd(g);
          };
          const Eigen::MatrixXd J = term.force_jacobian(q);
          if (lever == Lever::kNone) {
            EXPECT_TRUE(J.bottomRows<3>().isZero(0.0));
          }
          const Eigen::VectorXd F = term.force;
          EXPECT_TRUE(check_parameter_jacobian(
              of_force, F, Eigen::Vector3d::Constant(unit_of(magnitude)), J));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 27 * static_cast<int>(kAngles.size()));
}

// ----------------------------------------------------------------------------------------
// Rod bend/twist: C = (−W K Δω, W K Δω), W = Gᵀ R_a, Δω = vee(R_aᵀ R_b)/l − ω̄.

enum class Axis { kTwist, kBend, kRandom };

TEST(AdjointTermRodBendTwist, ParameterJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(1007);
  // Relative rotations Q = R_aᵀ R_b as in tests/test_rod_terms.cpp: straight (0, 1e-9, 1e-4),
  // generic, kinked to 170°, twisted to π − 1e-6 and π, near 2π.
  const std::vector<double> q_angles = {
      0.0, 1e-9, 1e-4, 1.0, 2.5, 170 * kDeg, kPi - 1e-6, kPi, 2.0 * kPi - 1e-6};
  int checked = 0;
  for (const double l : {1e-4, 1e-2, 1.0, 10.0}) {
    for (const double K_scale : {1e-3, 1.0, 1e9}) {
      for (const double angle : kAngles) {
        for (const Axis axis : {Axis::kTwist, Axis::kBend, Axis::kRandom}) {
          for (const double q_angle : q_angles) {
            for (const bool curved_rest : {true, false}) {
              SCOPED_TRACE(trace("l, K, angle of R_a", l, K_scale, angle));
              SCOPED_TRACE(trace("axis, angle of Q, curved rest", static_cast<double>(axis),
                                 q_angle, curved_rest));
              const Vector3 n = axis == Axis::kTwist  ? Vector3::UnitZ()
                                : axis == Axis::kBend ? random_perpendicular(Vector3::UnitZ(), rng)
                                                      : random_unit(rng);
              RodBendTwist term;
              term.edge0 = 0;
              term.edge1 = 1;
              term.rest_length = l;
              term.stiffness = K_scale * Vector3(1.0, 1.7, 0.6);  // all distinct
              // Rest curvature of a rest shape bent and twisted by 0.4 rad over one edge.
              term.rest_darboux = curved_rest
                                      ? darboux_vector(Matrix3::Identity(), rotation_at(0.4, rng), l)
                                      : Vector3::Zero();
              State q;
              const Matrix3 Ra = rotation_at(angle, rng);
              q.rotations = {Ra, Ra * so3::exp(q_angle * n)};
              const Vector3 omega = darboux_vector(q.rotations[0], q.rotations[1], l);
              const Vector3 dw = omega - term.rest_darboux;

              Eigen::Matrix<double, 6, 3> d_rest, d_stiffness;
              term.parameter_jacobians(q, &d_rest, &d_stiffness);
              // Each output alone gives the same blocks (nullptr for the other).
              Eigen::Matrix<double, 6, 3> d_rest_only, d_stiffness_only;
              term.parameter_jacobians(q, &d_rest_only, nullptr);
              term.parameter_jacobians(q, nullptr, &d_stiffness_only);
              EXPECT_TRUE(d_rest_only == d_rest);
              EXPECT_TRUE(d_stiffness_only == d_stiffness);

              // ∂C/∂ω̄. Only Δω = ω − ω̄ changes (ω is recomputed bit for bit), so C's
              // round-off is that of the subtraction, eps·(|ω| + |ω̄|), carried through
              // W K (‖W‖ ≤ ‖G‖ ≤ 2): value_scale 2 K_max (‖ω‖ + ‖ω̄‖). Differenced in units of
              // 1/l, the size of ω.
              const ParameterFunction of_rest = [&](const Eigen::VectorXd& rest) {
                RodBendTwist t = term;
                t.rest_darboux = rest;
                LocalGradient<2> g;
                t.evaluate(q, &g, nullptr);
                return Eigen::VectorXd(g);
              };
              const double K_max = term.stiffness.maxCoeff();
              const Eigen::VectorXd rest = term.rest_darboux;
              EXPECT_TRUE(check_parameter_jacobian(
                  of_rest, rest, Eigen::Vector3d::Constant(unit_of(1.0 / l)),
                  Eigen::MatrixXd(d_rest), {},
                  2.0 * K_max * (omega.norm() + term.rest_darboux.norm())));

              // ∂C/∂K, C linear in K with Δω fixed (recomputed bit for bit). C = Gᵀ m is
              // computed from the moment m = R_a (K ⊙ Δω), so its round-off is a few
              // eps·‖G‖‖m‖ ≤ 2 eps‖K ⊙ Δω‖ even where Gᵀ cancels most of m (twisted to
              // near π, G ≈ −n nᵀ: C ≈ −n (n·m) while ∂C/∂K₁,₂ are O(π − angle)): that is
              // the value_scale. ∂C/∂K = ±W diag(Δω) vanishes with Δω: exactly at rest
              // (ω̄ = 0, Q = I), where both sides are 0.
              const ParameterFunction of_stiffness = [&](const Eigen::VectorXd& K) {
                RodBendTwist t = term;
                t.stiffness = K;
                LocalGradient<2> g;
                t.evaluate(q, &g, nullptr);
                return Eigen::VectorXd(g);
              };
              fd::FdOptions opt;
              if (dw.isZero(0.0)) {
                EXPECT_TRUE(d_stiffness.isZero(0.0));
                opt.require_nonzero = fd::NonZero::kNone;
              }
              const Eigen::VectorXd K = term.stiffness;
              EXPECT_TRUE(check_parameter_jacobian(
                  of_stiffness, K, Eigen::Vector3d::Constant(unit_of(K_scale)),
                  Eigen::MatrixXd(d_stiffness), opt,
                  2.0 * term.stiffness.cwiseProduct(dw).norm()));
              ++checked;
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 4 * 3 * static_cast<int>(kAngles.size()) * 3 *
                         2 * static_cast<int>(q_angles.size()));
}

// ----------------------------------------------------------------------------------------
// Stiffness parameters of terms with Ψ ∝ k (Spring, RodStretch, RodShear): the adjoint
// (lib/adjoint.cpp, add_stiffness_adjoint) takes ∂C/∂k = C at k = 1. C is linear in k with
// everything else fixed, so its FD round-off is eps·|C| (fd's default floor); k is
// differenced in units of a power of two near k.

template <class Term>
::testing::AssertionResult check_stiffness_jacobian(const Term& term, const State& q) {
  Term unit = term;
  unit.stiffness = 1.0;
  LocalGradient<Term::kBlocks> g_unit;
  unit.evaluate(q, &g_unit, nullptr);
  const ParameterFunction of_stiffness = [&](const Eigen::VectorXd& k) {
    Term t = term;
    t.stiffness = k(0);
    LocalGradient<Term::kBlocks> g;
    t.evaluate(q, &g, nullptr);
    return Eigen::VectorXd(g);
  };
  return check_parameter_jacobian(of_stiffness, Eigen::VectorXd::Constant(1, term.stiffness),
                                  Eigen::VectorXd::Constant(1, unit_of(term.stiffness)),
                                  Eigen::MatrixXd(g_unit));
}

enum class Length { kStretched, kCompressed, kZeroRest };

TEST(AdjointTermStiffness, SpringGradientAtUnitStiffnessIsTheDerivative) {
  std::mt19937 rng(1008);
  int checked = 0;
  for (const bool anchored : {false, true}) {
    for (const Length length : {Length::kStretched, Length::kCompressed, Length::kZeroRest}) {
      for (const double k : {1e-3, 1.0, 1e9}) {
        for (size_t i = 0; i < kAngles.size(); ++i) {
          SCOPED_TRACE(trace("anchored, length, k", anchored, static_cast<double>(length), k));
          SCOPED_TRACE(trace("angles", kAngles[i], kAngles[(i + 4) % kAngles.size()]));
          Spring term;
          State q;
          q.points = {random_vector(rng, 1.0), random_vector(rng, 1.0)};
          q.rotations = {rotation_at(kAngles[i], rng),
                         rotation_at(kAngles[(i + 4) % kAngles.size()], rng)};
          term.a = {0, 0, 0.5 * random_unit(rng)};
          term.b = anchored ? AttachedPoint{-1, -1, random_vector(rng, 1.0)}
                            : AttachedPoint{1, 1, 0.5 * random_unit(rng)};
          const double d = (term.b.position(q) - term.a.position(q)).norm();
          term.stiffness = k;
          term.rest_length = length == Length::kStretched    ? 0.6 * d
                             : length == Length::kCompressed ? 1.5 * d
                                                             : 0.0;
          EXPECT_TRUE(check_stiffness_jacobian(term, q));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 2 * 3 * 3 * static_cast<int>(kAngles.size()));
}

TEST(AdjointTermStiffness, RodStretchGradientAtUnitStiffnessIsTheDerivative) {
  std::mt19937 rng(1009);
  int checked = 0;
  for (const double l : {1e-4, 1e-2, 1.0, 10.0}) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      for (const double ratio : {1e-6, 0.3, 0.9, 1.5, 3.0}) {  // ‖e‖/l
        SCOPED_TRACE(trace("l, k, |e|/l", l, k, ratio));
        RodStretch term;
        term.node0 = 0;
        term.node1 = 1;
        term.rest_length = l;
        term.stiffness = k;
        State q;
        const Vector3 x0 = random_vector(rng, ratio * l);
        q.points = {x0, x0 + ratio * l * random_unit(rng)};
        EXPECT_TRUE(check_stiffness_jacobian(term, q));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 4 * 3 * 5);
}

TEST(AdjointTermStiffness, RodShearGradientAtUnitStiffnessIsTheDerivative) {
  // The edge direction d at an angle from the frame's tangent t = R e_z: nearly aligned
  // (1e-4), generic, perpendicular, nearly opposite (π − 1e-3); R at every angle of kAngles.
  std::mt19937 rng(1010);
  int checked = 0;
  for (const double l : {1e-4, 1e-2, 1.0, 10.0}) {
    for (const double k : {1e-3, 1.0, 1e9}) {
      for (const double tilt : {1e-4, 0.7, kPi / 2, kPi - 1e-3}) {
        for (const double a : kAngles) {
          SCOPED_TRACE(trace("l, k, tilt", l, k, tilt));
          SCOPED_TRACE(trace("angle of R", a));
          RodShear term;
          term.node0 = 0;
          term.node1 = 1;
          term.edge = 0;
          term.rest_length = l;
          term.stiffness = k;
          State q;
          q.rotations = {rotation_at(a, rng)};
          const Vector3 t = q.rotations[0].col(2);
          const Vector3 d = so3::exp(tilt * random_perpendicular(t, rng)) * t;
          const Vector3 x0 = random_vector(rng, l);
          q.points = {x0, x0 + 1.1 * l * d};
          EXPECT_TRUE(check_stiffness_jacobian(term, q));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 4 * 3 * 4 * static_cast<int>(kAngles.size()));
}

// ----------------------------------------------------------------------------------------
// The assembled potential: IncrementalPotential::add_step_adjoint and add_parameter_adjoint.
//
// Scene: test_models::spring_chain(2) (two bodies, a world spring, a spring between them),
// torques on both bodies and a force on body 1, plus a 4-edge rod clamped at node 0 with a
// force on its last node and a cable routed over edges 1…3: two components (the bodies; the
// rod). Parameters γ (given slots by
// hand; kFrames steps; a stride > 0 marks per-step values):
//   γ[0…8]    force on body 1, per step (slot 0, stride 3)
//   γ[9…11]   torque on body 0, one value for all steps (slot 9, stride 0)
//   γ[12, 13] stiffnesses of springs 0 and 1
//   γ[14]     cable tension (stride 0)
//   γ[15, 16] rod stretch and shear stiffness              (γ[17] unused)
//   γ[18…20]  rod bending stiffness (K₁, K₂, K₃)
//   γ[21…47]  rod rest Darboux vectors of its 3 interior nodes, per step (slot 21 + 3j,
//             stride 9)
//   γ[48…50]  force on the rod's last node (slot 48, stride 0)
// The torque on body 1 is not a parameter.

constexpr int kFrames = 3;
constexpr int kGammaSize = 51;

// Scales: time step h and a mass factor m (bodies and rod). Every other force scales with
// the inertia m/h², by c = (m/h²)/(1/0.1²) (stiffnesses and loads), so that every kind of term
// keeps its share of the gradient: at the reference h = 0.1, m = 1 (c = 1) inertia, springs,
// rod elasticity, torques and forces are all within ~1e3 of each other. Over the grid
// (h = 1e-6 … 1, m = 1e-9 … 1e6) m/h² spans 1e-9 … 1e18 and the stiffnesses 1e-11 … 1e16
// times their reference values. A scene with one kind of term 1e12 times the others (h =
// 1e-6 with O(1) loads) cannot be checked by FD of the ASSEMBLED gradient: the small blocks
// drown in the round-off of the large ones. Each term's own blocks are checked at those
// extremes above; here it is the assembly (offsets, slots, frames, whole-state layout).
struct Scales {
  double h, mass;
  double c() const { return mass * 0.01 / (h * h); }
};

Model adjoint_scene(const Scales& s, std::mt19937& rng) {
  const double c = s.c();
  Model m = test_models::spring_chain(2);
  m.time_step = s.h;
  for (RigidBody& b : m.bodies) {
    b.mass *= s.mass;
    b.inertia *= s.mass;
  }
  for (SpringSpec& spring : m.springs) spring.stiffness *= c;
  m.torques.push_back({0, c * random_vector(rng, 1.0), {}});
  m.torques.push_back({1, c * random_vector(rng, 1.0), {}});
  m.forces.push_back({{1, random_vector(rng, 0.2)}, c * random_vector(rng, 1.0), {}});
  // A thick rod (radius 0.1 over edges of 0.25): its edges' rotational inertia is then not
  // negligible beside its elasticity.
  RodSpec rod = test_models::uniform_rod(4, 1.0, 2.0 * s.mass, 0.1, 50.0 * c, 20.0 * c, c);
  rod.bending_stiffness = c * Vector3(0.3, 0.4, 0.2);
  for (Vector3& x : rod.nodes) x += Vector3(0.0, 1.0, 0.0);
  rod.fixed_nodes = {0};
  rod.node_forces.push_back({4, c * random_vector(rng, 1.0), {}});
  rod.rest_darboux_controls.resize(3);
  CableSpec cable;  // on the rod's surface, turning around it
  for (int j = 1; j <= 3; ++j) {
    cable.route.push_back({j, 0.1 * Vector3(std::cos(1.1 * j), std::sin(1.1 * j), 0.0)});
  }
  cable.tension = 2.0 * c;
  rod.cables.push_back(cable);
  m.rods.push_back(rod);
  return m;
}

// Writes γ into the scene's parameters and sets their slots (layout above).
Model with_parameters(Model m, const Eigen::VectorXd& gamma) {
  const auto per_step = [&](ScheduledParameter<3>& p, int slot, int stride) {
    p.slot = slot;
    p.stride = stride;
    p.schedule.clear();
    for (int k = 1; k <= kFrames; ++k) p.schedule.push_back(gamma.segment<3>(p.slot_at(k)));
  };
  per_step(m.forces[0].control, 0, 3);
  per_step(m.torques[0].control, 9, 0);
  for (int i = 0; i < 2; ++i) {
    m.springs[static_cast<size_t>(i)].stiffness = gamma(12 + i);
    m.springs[static_cast<size_t>(i)].stiffness_slot = 12 + i;
  }
  RodSpec& rod = m.rods[0];
  rod.stretch_stiffness = gamma(15);
  rod.stretch_stiffness_slot = 15;
  rod.shear_stiffness = gamma(16);
  rod.shear_stiffness_slot = 16;
  rod.bending_stiffness = gamma.segment<3>(18);
  rod.bending_stiffness_slot = 18;
  for (int j = 0; j < 3; ++j) per_step(rod.rest_darboux_controls[static_cast<size_t>(j)], 21 + 3 * j, 9);
  per_step(rod.node_forces[0].control, 48, 0);
  CableSpec& cable = rod.cables[0];
  cable.tension = gamma(14);
  cable.control.slot = 14;
  cable.control.stride = 0;
  cable.control.schedule.assign(kFrames, Eigen::Matrix<double, 1, 1>(gamma(14)));
  return m;
}

// γ₀: the scene's own forces, torque and stiffnesses, random per-step forces and rest
// Darboux vectors.
Eigen::VectorXd initial_parameters(const Model& m, std::mt19937& rng) {
  Eigen::VectorXd gamma = Eigen::VectorXd::Zero(kGammaSize);
  const double c = m.forces[0].force.norm();  // the scene's force scale
  for (int k = 0; k < kFrames; ++k) gamma.segment<3>(3 * k) = c * random_vector(rng, 1.0);
  gamma.segment<3>(9) = m.torques[0].torque;
  gamma(12) = m.springs[0].stiffness;
  gamma(13) = m.springs[1].stiffness;
  gamma(14) = m.rods[0].cables[0].tension;
  gamma(15) = m.rods[0].stretch_stiffness;
  gamma(16) = m.rods[0].shear_stiffness;
  gamma.segment<3>(18) = m.rods[0].bending_stiffness;
  for (int i = 21; i < 48; i += 3) gamma.segment<3>(i) = random_vector(rng, 2.0);
  gamma.segment<3>(48) = m.rods[0].node_forces[0].force;
  return gamma;
}

// Whether γ's block b (entries 3b…3b+2) enters step `frame`.
bool block_in_frame(int b, int frame) {
  if (b <= 2) return b == frame - 1;                    // force on body 1, per step
  if (b >= 7 && b <= 15) return (b - 7) / 3 == frame - 1;  // rest Darboux vectors, per step
  return true;
}

Eigen::VectorXd component_gradient(const IncrementalPotential& p, const State& q, int dofs) {
  Eigen::VectorXd g(dofs);
  Eigen::MatrixXd H(dofs, dofs);
  p.assemble(q, g, H);
  return g;
}

// The size of the numbers a component's gradient is assembled from, for fd's round-off floor
// (check_vector_jacobian's value_scale; DOF sums of a few terms are covered by its 16 ulps):
// for the inertia terms their inputs (a (|x| + |x̃|), ‖J/h²‖‖R̃‖, whatever x − x̃ and R − R̃
// are), for the bend/twist terms K (|ω| + |ω̄|) (ω carries an absolute round-off), for the
// torques s|τ|, and for every other term its local gradient.
double gradient_scale(const IncrementalPotential& p, const State& q) {
  double s = 0.0;
  for (const TranslationalInertia& t : p.terms<TranslationalInertia>()) {
    s = std::max(s, t.mass_over_h2 * (q.points[static_cast<size_t>(t.point)].cwiseAbs().maxCoeff() +
                                      t.x_tilde.cwiseAbs().maxCoeff()));
  }
  for (const RotationalInertia& t : p.terms<RotationalInertia>()) {
    s = std::max(s, t.J_over_h2.norm() * std::max(1.0, t.R_tilde.norm()));
  }
  for (const ConstantTorque& t : p.terms<ConstantTorque>()) s = std::max(s, 2.0 * std::abs(t.scale) * t.torque.norm());
  for (const RodBendTwist& t : p.terms<RodBendTwist>()) {
    const Vector3 omega = darboux_vector(q.rotations[static_cast<size_t>(t.edge0)],
                                         q.rotations[static_cast<size_t>(t.edge1)], t.rest_length);
    s = std::max(s, 2.0 * t.stiffness.cwiseAbs().maxCoeff() * (omega.norm() + t.rest_darboux.norm()));
  }
  const auto local = [&]<class Term>(const std::vector<Term>& terms) {
    for (const Term& t : terms) {
      LocalGradient<Term::kBlocks> g;
      t.evaluate(q, &g, nullptr);
      s = std::max(s, g.cwiseAbs().maxCoeff());
    }
  };
  local(p.terms<Gravity>());
  local(p.terms<ConstantForce>());
  local(p.terms<Spring>());
  local(p.terms<RodStretch>());
  local(p.terms<RodShear>());
  local(p.terms<CableSegment>());
  return s;
}

// Which blocks of the whole-state tangent layout (points, then rotations) are DOFs of c.
std::vector<bool> owned_blocks(const Component& c, const State& q) {
  std::vector<bool> owned(q.points.size() + q.rotations.size(), false);
  for (const DofBlock& b : c.points) owned[static_cast<size_t>(b.index)] = true;
  for (const DofBlock& b : c.rotations) owned[q.points.size() + static_cast<size_t>(b.index)] = true;
  return owned;
}

fd::Dofs whole_state_dofs(const State& q, const std::vector<bool>& owned) {
  fd::Dofs dofs;
  for (size_t i = 0; i < q.points.size(); ++i) {
    dofs.push_back(owned[i] ? fd::point_dof(static_cast<int>(i)) : fd::no_dof());
  }
  for (size_t j = 0; j < q.rotations.size(); ++j) {
    dofs.push_back(owned[q.points.size() + j] ? fd::rotation_dof(static_cast<int>(j))
                                              : fd::no_dof());
  }
  return dofs;
}

// A scene at scales s with states around its initial one: q_{k−1}, Δq_{k−1} and q. Rotations
// take the angles of kAngles from `first` on, R directly (list_R) or R_{k−1} and ΔR_{k−1};
// the others 0.3 rad away (as in tests/test_terms.cpp).
struct SceneStates {
  Model model;
  State previous;
  Step step;
  State q;
};

SceneStates scene_states(const Scales& s, size_t first, bool list_R, std::mt19937& rng) {
  SceneStates c;
  c.model = adjoint_scene(s, rng);
  c.previous = c.model.initial_state();
  c.step = c.model.initial_step();
  c.q = c.previous;
  const size_t na = kAngles.size();
  for (size_t i = 0; i < c.q.points.size(); ++i) {
    c.previous.points[i] += random_vector(rng, 0.1);
    c.step.points[i] = random_vector(rng, 0.05);
    c.q.points[i] = c.previous.points[i] + c.step.points[i] + random_vector(rng, 0.05);
  }
  for (size_t j = 0; j < c.q.rotations.size(); ++j) {
    if (list_R) {
      c.q.rotations[j] = rotation_at(kAngles[(first + j) % na], rng);
      c.step.rotations[j] = rotation_at(kAngles[(first + 3 * j + 1) % na], rng);
      c.previous.rotations[j] =
          c.step.rotations[j].transpose() * rotation_at(0.3, rng) * c.q.rotations[j];
    } else {
      c.previous.rotations[j] = rotation_at(kAngles[(first + j) % na], rng);
      c.step.rotations[j] = rotation_at(kAngles[(first + 3 * j + 1) % na], rng);
      c.q.rotations[j] = rotation_at(0.3, rng) * c.step.rotations[j] * c.previous.rotations[j];
    }
  }
  return c;
}

Eigen::VectorXd random_z(int n, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::VectorXd z(n);
  for (int i = 0; i < n; ++i) z(i) = normal(rng);
  return z;
}

// Whether `twice` = 2·`once` up to 64 eps of the largest entry (see the callers).
bool doubled(const Eigen::VectorXd& once, const Eigen::VectorXd& twice) {
  return (twice - 2.0 * once).cwiseAbs().maxCoeff() <=
         64 * std::numeric_limits<double>::epsilon() * once.cwiseAbs().maxCoeff();
}

// add_step_adjoint of component c (begin_step(previous, step, frame) done) against FD of
// z·C with respect to q_{k−1} and Δq_{k−1}.
::testing::AssertionResult check_step_adjoint(const Component& c, const SceneStates& s, int frame,
                                              const Eigen::VectorXd& z) {
  const Eigen::Index n = tangent_size(s.q);
  Eigen::VectorXd a = Eigen::VectorXd::Zero(n), da = Eigen::VectorXd::Zero(n);
  c.potential.add_step_adjoint(s.q, s.previous, s.step, z, a, da);

  // It adds: a second call doubles, up to the rounding of the sums of several terms' parts
  // per block (inertia + torque), a few eps of the largest entry (one that overwrote its
  // output would leave it unchanged). And it writes nothing outside c's own blocks.
  Eigen::VectorXd a2 = a, da2 = da;
  c.potential.add_step_adjoint(s.q, s.previous, s.step, z, a2, da2);
  if (!doubled(a, a2) || !doubled(da, da2)) {
    return ::testing::AssertionFailure() << "add_step_adjoint does not add into its outputs";
  }
  const std::vector<bool> owned = owned_blocks(c, s.q);
  for (size_t b = 0; b < owned.size(); ++b) {
    const Eigen::Index o = 3 * static_cast<Eigen::Index>(b);
    if (!owned[b] && (!a.segment<3>(o).isZero(0.0) || !da.segment<3>(o).isZero(0.0))) {
      return ::testing::AssertionFailure()
             << "add_step_adjoint writes whole-state block " << b << ", not a DOF of the component";
    }
  }

  const double value_scale = z.lpNorm<1>() * gradient_scale(c.potential, s.q);
  const fd::Dofs dofs = whole_state_dofs(s.q, owned);
  const fd::FdOptions opt;  // kEveryBlock: every DOF block of q_{k−1}, Δq_{k−1} must count
  const fd::VectorFunction of_previous = [&](const State& previous) {
    IncrementalPotential p = c.potential;
    p.begin_step(previous, s.step, frame);
    return Eigen::VectorXd::Constant(1, z.dot(component_gradient(p, s.q, c.dofs)));
  };
  ::testing::AssertionResult r = fd::check_vector_jacobian(
      of_previous, s.previous, dofs, Eigen::MatrixXd(a.transpose()), opt, value_scale);
  if (!r) return ::testing::AssertionFailure() << "(dC/dq_{k-1})^T z: " << r.message();
  const fd::VectorFunction of_step = [&](const State& step) {
    IncrementalPotential p = c.potential;
    p.begin_step(s.previous, as_step(step), frame);
    return Eigen::VectorXd::Constant(1, z.dot(component_gradient(p, s.q, c.dofs)));
  };
  r = fd::check_vector_jacobian(of_step, as_state(s.step), dofs, Eigen::MatrixXd(da.transpose()),
                                opt, value_scale);
  if (!r) return ::testing::AssertionFailure() << "(dC/ddq_{k-1})^T z: " << r.message();
  return ::testing::AssertionSuccess();
}

// The scale grid (see Scales).
std::vector<Scales> scale_grid() {
  std::vector<Scales> grid;
  for (const double h : {1e-6, 1e-2, 0.1, 1.0}) {
    for (const double mass : {1e-9, 1.0, 1e6}) grid.push_back({h, mass});
  }
  return grid;
}

TEST(AdjointTermPotential, StepAdjointIsTransposedJacobianTimesZ) {
  std::mt19937 rng(1011);
  int checked = 0;
  for (const Scales& scales : scale_grid()) {
    for (size_t run = 0; run < 2 * kAngles.size(); run += 3) {
      const size_t first = run / 2;
      const bool list_R = run % 2 == 0;
      SCOPED_TRACE(trace("h, m, c", scales.h, scales.mass, scales.c()));
      SCOPED_TRACE(trace("first angle, angles for R", kAngles[first], list_R));
      const SceneStates s = scene_states(scales, first, list_R, rng);
      ASSERT_NO_THROW(s.model.validate());
      std::vector<Component> components = build_components(s.model);
      ASSERT_EQ(components.size(), 2u);
      for (Component& c : components) {
        for (const int frame : {1, kFrames}) {
          c.potential.begin_step(s.previous, s.step, frame);
          const Eigen::VectorXd z = random_z(c.dofs, rng);
          EXPECT_TRUE(check_step_adjoint(c, s, frame, z));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 12 * 6 * 2 * 2);
}

TEST(AdjointTermPotential, ParameterAdjointIsTransposedParameterJacobianTimesZ) {
  std::mt19937 rng(1012);
  int checked = 0;
  for (const Scales& scales : scale_grid()) {
    for (size_t run = 0; run < 2 * kAngles.size(); run += 5) {
      const size_t first = run / 2;
      const bool list_R = run % 2 == 0;
      SCOPED_TRACE(trace("h, m, c", scales.h, scales.mass, scales.c()));
      SCOPED_TRACE(trace("first angle, angles for R", kAngles[first], list_R));
      const SceneStates s = scene_states(scales, first, list_R, rng);
      const Eigen::VectorXd gamma = initial_parameters(s.model, rng);
      const Model model = with_parameters(s.model, gamma);
      ASSERT_NO_THROW(model.validate());
      const std::vector<Component> base = build_components(model);
      ASSERT_EQ(base.size(), 2u);
      std::vector<Eigen::VectorXd> z;
      for (const Component& c : base) z.push_back(random_z(c.dofs, rng));

      for (int frame = 1; frame <= kFrames; ++frame) {
        SCOPED_TRACE(trace("frame", frame));
        // Analytic: Σ over components of (∂C/∂γ)ᵀ z.
        Eigen::VectorXd dgamma = Eigen::VectorXd::Zero(kGammaSize);
        double scale = 0.0;
        std::vector<Component> components = base;
        for (size_t i = 0; i < components.size(); ++i) {
          components[i].potential.begin_step(s.previous, s.step, frame);
          components[i].potential.add_parameter_adjoint(s.q, frame, z[i], dgamma);
          scale += z[i].lpNorm<1>() * gradient_scale(components[i].potential, s.q);
        }
        // It adds: a second pass doubles (up to the rounding of sums over the terms that
        // share a slot).
        Eigen::VectorXd dgamma2 = dgamma;
        for (size_t i = 0; i < components.size(); ++i) {
          components[i].potential.add_parameter_adjoint(s.q, frame, z[i], dgamma2);
        }
        EXPECT_TRUE(doubled(dgamma, dgamma2));
        // Only step `frame`'s per-step values, and no unused entry, get a derivative.
        std::vector<bool> compared(kGammaSize / 3);
        for (int b = 0; b < kGammaSize / 3; ++b) {
          compared[static_cast<size_t>(b)] = block_in_frame(b, frame);
          if (!compared[static_cast<size_t>(b)]) {
            EXPECT_TRUE(dgamma.segment<3>(3 * b).isZero(0.0)) << "block " << b;
          }
        }
        EXPECT_EQ(dgamma(17), 0.0);

        const ParameterFunction of_gamma = [&](const Eigen::VectorXd& g) {
          const std::vector<Component> cs = build_components(with_parameters(s.model, g));
          double value = 0.0;
          for (size_t i = 0; i < cs.size(); ++i) {
            IncrementalPotential p = cs[i].potential;
            p.begin_step(s.previous, s.step, frame);
            value += z[i].dot(component_gradient(p, s.q, cs[i].dofs));
          }
          return Eigen::VectorXd::Constant(1, value);
        };
        EXPECT_TRUE(check_parameter_jacobian(of_gamma, gamma, units_of(gamma),
                                             Eigen::MatrixXd(dgamma.transpose()), {}, scale,
                                             compared));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 12 * 4 * kFrames);
}

}  // namespace
}  // namespace liedyn::adjoint_terms_tests

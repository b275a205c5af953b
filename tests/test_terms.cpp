// Energy terms (lib/inertia.hpp, lib/loads.hpp, lib/spring.hpp) and the assembled incremental
// potential (lib/incremental_potential.hpp): value vs Lie gradient vs Lie Hessian by finite
// differences in the tangent space over all blocks (tests/fd_check.hpp), at rotations from
// the identity to near 2π, over extreme time steps, masses and stiffnesses; plus physical
// facts derived by hand.
//
// Tolerances are relative (fd_check.hpp defaults: 1e-6 for ε = 1e-6 first differences, whose
// round-off is ~eps·|f|/ε ≈ 1e-10·|f| and truncation ~ε²; 1e-5 for ε = 1e-4 second
// differences of the value, round-off ~eps·|f|/ε² ≈ 2e-8·|f|). Geometry is kept O(1) so that
// |f| is comparable to its derivatives; energies then scale out. Where a derivative vanishes
// at the test point the absolute floor used is stated and derived next to the check.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "fd_check.hpp"
#include "lib/incremental_potential.hpp"
#include "lib/inertia.hpp"
#include "lib/loads.hpp"
#include "lib/model.hpp"
#include "lib/so3.hpp"
#include "lib/spring.hpp"

namespace liedyn::terms_tests {
namespace {

using fd::kAngles;
using fd::random_unit;
using fd::random_vector;
using fd::rotation_at;
using fd::trace;
using fd::kPi;
using fd::kEps;
using fd::body_inertia;

// ----------------------------------------------------------------------------------------
// Self-tests of the FD helpers: they must reject wrong derivatives, and the Lie Hessian is
// not the derivative of the Lie gradient field.

TEST(TermFdCheck, RejectsWrongDerivativesAndZeroComparisons) {
  std::mt19937 rng(21);
  RotationalInertia term;
  term.rotation = 0;
  term.J_over_h2 = rotational_mass(body_inertia(1.0, rng));
  term.R_tilde = rotation_at(0.7, rng);
  State q;
  q.rotations = {rotation_at(1.1, rng)};
  const fd::Dofs dofs = {fd::rotation_dof(0)};
  LocalGradient<1> g;
  LocalHessian<1> H;
  term.evaluate(q, &g, &H);
  const fd::ScalarFunction f = [&](const State& s) { return term.evaluate(s, nullptr, nullptr); };
  const fd::GradientFunction grad = [&](const State& s) {
    LocalGradient<1> gs;
    term.evaluate(s, &gs, nullptr);
    return Eigen::VectorXd(gs);
  };
  ASSERT_TRUE(fd::check_term(term, q, dofs));
  EXPECT_FALSE(fd::check_lie_gradient(f, q, dofs, -g));
  EXPECT_FALSE(fd::check_lie_gradient(f, q, dofs, Eigen::VectorXd(g * (1.0 + 1e-4))));
  EXPECT_FALSE(fd::check_lie_gradient(f, q, dofs, Eigen::VectorXd::Zero(3)));
  const Matrix3 half_hat_g = 0.5 * so3::hat(g);
  EXPECT_FALSE(fd::check_lie_hessian(grad, q, dofs, Eigen::MatrixXd(H - half_hat_g)));
  EXPECT_FALSE(fd::check_lie_hessian_from_value(f, q, dofs, Eigen::MatrixXd(H * (1.0 + 1e-3))));

  // docs/design.md §1.4: differentiating the Lie gradient FIELD R ↦ g(R) along left perturbations
  // gives H − ½hat(g) (not symmetric), because f(exp(θ+η)R) = f(exp(J_l(θ)η)exp(θ)R) and
  // J_l(θ)ᵀ = I − ½hat(θ) + O(θ²).
  const fd::StateFunction field = [&](const State& s) {
    State y;
    y.points = {grad(s)};
    return y;
  };
  EXPECT_TRUE(
      fd::check_jacobian(field, q, dofs, {fd::point_dof(0)}, Eigen::MatrixXd(H - half_hat_g)));
  EXPECT_FALSE(fd::check_jacobian(field, q, dofs, {fd::point_dof(0)}, Eigen::MatrixXd(H)));
}

// ----------------------------------------------------------------------------------------
// Translational inertia  m/(2h²)‖x − x̃‖².

TEST(TranslationalInertiaTerm, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(1);
  for (const double h : {1e-6, 1e-2, 1.0}) {
    for (const double mass : {1e-9, 1.0, 1e6}) {
      SCOPED_TRACE(trace("h, m", h, mass));
      TranslationalInertia term;
      term.point = 0;
      term.mass_over_h2 = mass / (h * h);
      State previous;
      previous.points = {random_vector(rng, 1.0)};
      Step step;
      step.points = {random_vector(rng, 0.5)};
      term.begin_step(previous, step);
      EXPECT_EQ(term.x_tilde, previous.points[0] + step.points[0]);  // x̃ = x_{k−1} + Δx_{k−1}
      State q;
      q.points = {random_vector(rng, 1.0)};
      EXPECT_TRUE(fd::check_term(term, q, {fd::point_dof(0)}));

      // At x = x̃ the inertia exerts nothing.
      q.points[0] = term.x_tilde;
      LocalGradient<1> g;
      EXPECT_EQ(term.evaluate(q, &g, nullptr), 0.0);
      EXPECT_TRUE(g.isZero(0.0));
    }
  }
}

// ----------------------------------------------------------------------------------------
// Rotational inertia  −tr(R J R̃ᵀ)/h² (+ const), R̃ = (2I − ΔR_{k−1}ᵀ) R_{k−1}.

TEST(RotationalInertiaTerm, DerivativesMatchFiniteDifferencesOverAllAngles) {
  std::mt19937 rng(2);
  int checked = 0;
  for (const double h : {1e-6, 1.0}) {
    for (const double scale : {1e-9, 1e6}) {
      const Matrix3 J = rotational_mass(body_inertia(scale, rng));
      for (const double a_prev : kAngles) {
        for (const double a_step : kAngles) {
          for (const double a : kAngles) {
            SCOPED_TRACE(trace("angles R_{k-1}, dR_{k-1}, R", a_prev, a_step, a));
            SCOPED_TRACE(trace("h, inertia scale", h, scale));
            RotationalInertia term;
            term.rotation = 0;
            term.J_over_h2 = J / (h * h);
            State previous;
            previous.rotations = {rotation_at(a_prev, rng)};
            Step step;
            step.rotations = {rotation_at(a_step, rng)};
            term.begin_step(previous, step);
            State q;
            q.rotations = {rotation_at(a, rng)};
            if (a_prev == 0.0 && a_step == 0.0 && a == 0.0) continue;  // R = R̃: see AtRest

            // The pulled-back value's third derivative is bounded by ~‖M‖ ≤ ‖J‖‖R̃‖/h², so
            // the central-difference truncation of the gradient is ≤ ε²‖J‖‖R̃‖/h²: an
            // absolute floor for the points where R is within ~1e-9 of R̃ and g is tiny.
            fd::TermCheckOptions opt;
            const double m_norm = term.J_over_h2.norm() * term.R_tilde.norm();
            opt.gradient.abs_floor = opt.gradient.step * opt.gradient.step * m_norm;
            EXPECT_TRUE(fd::check_term(term, q, {fd::rotation_dof(0)}, opt));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 2500);
}

TEST(RotationalInertiaTerm, AtRestHasZeroValueAndGradient) {
  // ΔR_{k−1} = I gives R̃ = R_{k−1}; at R = R_{k−1}, M = R J Rᵀ/h² is symmetric: g = 2 vee(A) = 0.
  std::mt19937 rng(3);
  for (const double a : kAngles) {
    RotationalInertia term;
    term.rotation = 0;
    term.J_over_h2 = rotational_mass(body_inertia(1.0, rng)) / 1e-4;
    State previous;
    previous.rotations = {rotation_at(a, rng)};
    Step step;
    step.rotations = {Matrix3::Identity()};
    term.begin_step(previous, step);
    LocalGradient<1> g;
    LocalHessian<1> H;
    EXPECT_EQ(term.evaluate(previous, &g, &H), 0.0) << a;
    // Round-off of R J Rᵀ: a few eps·‖J‖/h².
    EXPECT_LE(g.norm(), 16 * kEps * term.J_over_h2.norm()) << a;
    // And the Hessian tr(S) I − S, S = R J Rᵀ/h², is the world inertia tensor over h²:
    // tr(J) = ½ tr(I_b), so tr(J) I − J = I_b.
    const Matrix3 I_world = previous.rotations[0] *
                            (term.J_over_h2.trace() * Matrix3::Identity() - term.J_over_h2) *
                            previous.rotations[0].transpose();
    EXPECT_LE((H - I_world).norm(), 16 * kEps * term.J_over_h2.norm()) << a;
  }
}

TEST(RotationalInertiaTerm, SteadySpinAboutSymmetryAxisLeavesThirdOrderResidual) {
  // Derivation. I_b = diag(a, a, c) in body axes, spin axis n = R_{k−1} Q e_z (the symmetry
  // axis), ΔR_{k−1} = exp(φ n), and the candidate R = ΔR R_{k−1} continuing the spin.
  // J = ½ tr(I_b) − I_b has eigenvalue μ = c/2 perpendicular to the axis, so J_w = R_{k−1} J
  // R_{k−1}ᵀ commutes with ΔR, and
  //   M = R J R̃ᵀ/h² = ΔR J_w (2I − ΔR)/h² = J_w (2ΔR − ΔR²)/h².
  // With ΔR = n nᵀ + cos φ (I − n nᵀ) + sin φ hat(n) and J_w hat(n) = μ hat(n), the
  // antisymmetric part is μ (2 sin φ − sin 2φ) hat(n)/h², so
  //   g = 2 vee(A) = c (2 sin φ − sin 2φ)/h² n  =  c φ³/h² n + O(φ⁵).
  // A steady spin is NOT an exact equilibrium of the discrete step: the residual along +n
  // makes the Newton step slow the spin down (backward Euler's numerical dissipation).
  std::mt19937 rng(4);
  const double a_moment = 2.0, c_moment = 3.0, h = 0.01;
  for (const double phi : {1e-3, 0.1, 0.5, 1.0, 2.0}) {
    const Matrix3 Q = rotation_at(0.9, rng);
    const Matrix3 I_b =
        Q * Eigen::Vector3d(a_moment, a_moment, c_moment).asDiagonal() * Q.transpose();
    RotationalInertia term;
    term.rotation = 0;
    term.J_over_h2 = rotational_mass(I_b) / (h * h);
    State previous;
    previous.rotations = {rotation_at(1.7, rng)};
    const Vector3 n = previous.rotations[0] * Q * Vector3::UnitZ();
    Step step;
    step.rotations = {so3::exp(phi * n)};
    term.begin_step(previous, step);
    State q;
    q.rotations = {step.rotations[0] * previous.rotations[0]};
    LocalGradient<1> g;
    term.evaluate(q, &g, nullptr);
    const Vector3 expected = c_moment * (2.0 * std::sin(phi) - std::sin(2.0 * phi)) / (h * h) * n;
    // Round-off of M: a few eps·‖J‖‖R̃‖/h² (‖R̃‖ ≤ 3).
    EXPECT_LE((g - expected).norm(), 64 * kEps * term.J_over_h2.norm()) << phi;
    EXPECT_GT(g.dot(n), 0.0) << phi;
  }
}

// ----------------------------------------------------------------------------------------
// Gravity  −m g·x.

TEST(GravityTerm, GradientIsMinusWeightAndHessianZero) {
  std::mt19937 rng(5);
  for (const double mass : {1e-9, 1.0, 1e6}) {
    Gravity term;
    term.point = 0;
    term.weight = mass * Vector3(0.0, 0.0, -9.81);
    State q;
    q.points = {random_vector(rng, 1.0)};
    LocalGradient<1> g;
    LocalHessian<1> H;
    EXPECT_EQ(term.evaluate(q, &g, &H), mass * 9.81 * q.points[0].z());
    EXPECT_EQ(g, -term.weight);  // −m g, exactly
    EXPECT_TRUE(H.isZero(0.0));

    fd::TermCheckOptions opt;
    // The Hessian is exactly zero: FD of the (constant) gradient is exactly zero too, and
    // second differences of the linear value are pure round-off (under fd's noise floor).
    opt.hessian.require_nonzero = fd::NonZero::kNone;
    opt.hessian_from_value.require_nonzero = fd::NonZero::kNone;
    EXPECT_TRUE(fd::check_term(term, q, {fd::point_dof(0)}, opt)) << mass;
  }
}

// ----------------------------------------------------------------------------------------
// Constant force  −F·(x + R p̄).

TEST(ConstantForceTerm, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(6);
  for (const double magnitude : {1e-3, 1.0, 1e6}) {
    for (const double lever : {0.1, 1.0}) {
      for (const double a : kAngles) {
        SCOPED_TRACE(trace("|F|, |p̄|, angle", magnitude, lever, a));
        ConstantForce term;
        term.at.point = 0;
        term.at.rotation = 0;
        term.at.local = lever * random_unit(rng);
        term.force = magnitude * random_unit(rng);
        State q;
        q.points = {random_vector(rng, 1.0)};
        q.rotations = {rotation_at(a, rng)};
        // No mixed x–θ curvature and no ∂²/∂x²: only the θθ block is non-zero.
        EXPECT_TRUE(fd::check_term(term, q, {fd::point_dof(0), fd::rotation_dof(0)}));

        // Physics: ∂V/∂x = −F, and DV/DR = −(r × F), minus the torque about the centre.
        LocalGradient<2> g;
        term.evaluate(q, &g, nullptr);
        const Vector3 r = q.rotations[0] * term.at.local;
        EXPECT_EQ(Vector3(g.head<3>()), -term.force);
        EXPECT_LE((g.tail<3>() + r.cross(term.force)).norm(), 4 * kEps * magnitude * lever);
      }
    }
  }
}

TEST(ConstantForceTerm, NonRotatingPointHasOnlyTheTranslationalBlock) {
  std::mt19937 rng(7);
  ConstantForce term;
  term.at.point = 0;  // rotation = −1: a translating offset, p = x + p̄
  term.at.local = random_vector(rng, 1.0);
  term.force = random_unit(rng);
  State q;
  q.points = {random_vector(rng, 1.0)};
  EXPECT_TRUE(term.at.position(q).isApprox(q.points[0] + term.at.local, 1e-15));
  EXPECT_NEAR(term.evaluate(q, nullptr, nullptr), -term.force.dot(q.points[0] + term.at.local),
              1e-14);
  fd::TermCheckOptions opt;
  // V is linear in x: zero Hessian; value second differences are round-off only.
  opt.hessian.require_nonzero = fd::NonZero::kNone;
  opt.hessian_from_value.require_nonzero = fd::NonZero::kNone;
  EXPECT_TRUE(fd::check_term(term, q, {fd::point_dof(0), fd::no_dof()}, opt));
}

// ----------------------------------------------------------------------------------------
// Constant torque  −τ·vee(R R_{k−1}ᵀ).

TEST(ConstantTorqueTerm, DerivativesMatchFiniteDifferencesOverAllAngles) {
  std::mt19937 rng(8);
  for (const double magnitude : {1e-3, 1.0, 1e6}) {
    for (const double a_prev : kAngles) {
      for (const double a : kAngles) {
        SCOPED_TRACE(trace("|τ|, angles R_{k-1}, R", magnitude, a_prev, a));
        ConstantTorque term;
        term.rotation = 0;
        term.torque = magnitude * random_unit(rng);
        State previous;
        previous.rotations = {rotation_at(a_prev, rng)};
        term.begin_step(previous, Step{});
        EXPECT_EQ(term.R_previous, previous.rotations[0]);
        State q;
        q.rotations = {rotation_at(a, rng)};

        // Round-off is fd's noise floor; the truncation floor: fd::torque_potential_options.
        const fd::TermCheckOptions opt = fd::torque_potential_options(
            magnitude, so3::distance(q.rotations[0], previous.rotations[0]) < 1e-3);
        EXPECT_TRUE(fd::check_term(term, q, {fd::rotation_dof(0)}, opt));
      }
    }
  }
}

TEST(ConstantTorqueTerm, GradientIsMinusTorqueAtThePreviousRotation) {
  // P = I: −½(tr(I) τ − τ) = −τ, and the Hessian ¼(hat τ − hat τ) − ½ tr(hat τ) I = 0.
  std::mt19937 rng(9);
  for (const double a : kAngles) {
    ConstantTorque term;
    term.rotation = 0;
    term.torque = random_vector(rng, 2.0);
    State q;
    q.rotations = {rotation_at(a, rng)};
    term.begin_step(q, Step{});
    LocalGradient<1> g;
    LocalHessian<1> H;
    term.evaluate(q, &g, &H);
    // P = R Rᵀ is I up to a few eps, which is all that separates g from −τ.
    EXPECT_LE((g + term.torque).norm(), 8 * kEps * term.torque.norm()) << a;
    EXPECT_LE(H.norm(), 8 * kEps * term.torque.norm()) << a;
  }
}

// ----------------------------------------------------------------------------------------
// Spring  ½k(‖p_b − p_a‖ − L)².

enum class Ends { kBothBodies, kAnchorA, kAnchorB };
enum class Length { kStretched, kCompressed, kZeroRest };

struct SpringCase {
  Spring term;
  State q;
  fd::Dofs dofs;
};

SpringCase make_spring(Ends ends, Length length, double stiffness, double angle_a, double angle_b,
                       std::mt19937& rng) {
  SpringCase c;
  c.q.points = {random_vector(rng, 1.0), random_vector(rng, 1.0)};
  c.q.rotations = {rotation_at(angle_a, rng), rotation_at(angle_b, rng)};
  c.term.a = {0, 0, 0.5 * random_unit(rng)};
  c.term.b = {1, 1, 0.5 * random_unit(rng)};
  c.dofs = {fd::point_dof(0), fd::rotation_dof(0), fd::point_dof(1), fd::rotation_dof(1)};
  if (ends == Ends::kAnchorA) {
    c.term.a = {-1, -1, random_vector(rng, 1.0)};
    c.dofs[0] = c.dofs[1] = fd::no_dof();
  }
  if (ends == Ends::kAnchorB) {
    c.term.b = {-1, -1, random_vector(rng, 1.0)};
    c.dofs[2] = c.dofs[3] = fd::no_dof();
  }
  const double l = (c.term.b.position(c.q) - c.term.a.position(c.q)).norm();
  c.term.stiffness = stiffness;
  c.term.rest_length = length == Length::kStretched    ? 0.6 * l
                       : length == Length::kCompressed ? 1.5 * l
                                                       : 0.0;
  return c;
}

TEST(SpringTerm, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(10);
  int checked = 0;
  for (const Ends ends : {Ends::kBothBodies, Ends::kAnchorA, Ends::kAnchorB}) {
    for (const Length length : {Length::kStretched, Length::kCompressed, Length::kZeroRest}) {
      for (const double k : {1e-3, 1.0, 1e9}) {
        for (size_t i = 0; i < kAngles.size(); ++i) {
          const double angle_a = kAngles[i], angle_b = kAngles[(i + 4) % kAngles.size()];
          SCOPED_TRACE(
              trace("ends, length, k", static_cast<double>(ends), static_cast<double>(length), k));
          SCOPED_TRACE(trace("angles", angle_a, angle_b));
          SpringCase c = make_spring(ends, length, k, angle_a, angle_b, rng);
          EXPECT_TRUE(fd::check_term(c.term, c.q, c.dofs));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 3 * 3 * static_cast<int>(kAngles.size()));
}

TEST(SpringTerm, BetweenBodiesExertsNoNetForceOrTorque) {
  // V depends only on p_b − p_a, so it is invariant under a global translation x_i ← x_i + t
  // and a global rotation (x_i, R_i) ← (exp(θ)x_i, exp(θ)R_i). Differentiating at 0:
  //   Σ ∂V/∂x_i = 0,   Σ (x_i × ∂V/∂x_i + DV/DR_i) = 0.
  std::mt19937 rng(11);
  for (const Length length : {Length::kStretched, Length::kCompressed, Length::kZeroRest}) {
    for (const double a : kAngles) {
      SpringCase c = make_spring(Ends::kBothBodies, length, 10.0, a, 1.0, rng);
      LocalGradient<4> g;
      c.term.evaluate(c.q, &g, nullptr);
      const double scale = g.norm();
      ASSERT_GT(scale, 0.0);
      EXPECT_LE((g.segment<3>(0) + g.segment<3>(6)).norm(), 8 * kEps * scale);
      const Vector3 torque = c.q.points[0].cross(Vector3(g.segment<3>(0))) + g.segment<3>(3) +
                             c.q.points[1].cross(Vector3(g.segment<3>(6))) + g.segment<3>(9);
      EXPECT_LE(torque.norm(), 32 * kEps * scale);
    }
  }
}

TEST(SpringTerm, AtRestLengthGradientVanishes) {
  std::mt19937 rng(12);
  SpringCase c = make_spring(Ends::kBothBodies, Length::kStretched, 100.0, 1.0, 2.0, rng);
  c.term.rest_length = (c.term.b.position(c.q) - c.term.a.position(c.q)).norm();
  LocalGradient<4> g;
  LocalHessian<4> H;
  EXPECT_EQ(c.term.evaluate(c.q, &g, &H), 0.0);
  EXPECT_LE(g.norm(), 1e-13);  // k (l − L) with l − L a few ulps
  // At rest, V = ½k (n·δd)² + …: the Hessian is k Jdᵀ n nᵀ Jd, PSD of rank one.
  const Eigen::SelfAdjointEigenSolver<LocalHessian<4>> eig(H);
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-12);
  EXPECT_EQ((eig.eigenvalues().array().abs() > 1e-9).count(), 1);
}

// ----------------------------------------------------------------------------------------
// The assembled incremental potential of a whole model.

struct Scales {
  double h, mass, stiffness;
};

// Three bodies: springs 0–1, 1–2 (zero rest length), 0–world, 2–world; forces on 0 and 2,
// torques on 1 and 2, gravity. All joined by springs: one component of 18 DOFs.
Model make_model(const Scales& s, std::mt19937& rng) {
  Model m;
  m.time_step = s.h;
  m.gravity = Vector3(0.0, 0.0, -9.81);
  for (int i = 0; i < 3; ++i) {
    RigidBody b;
    b.name = "body" + std::to_string(i);
    b.mass = s.mass * (1.0 + 0.5 * i);
    b.inertia = body_inertia(s.mass, rng);
    b.position = Vector3(1.5 * i, 0.0, 0.0) + random_vector(rng, 0.3);
    m.bodies.push_back(b);
  }
  m.springs.push_back(
      {{0, random_vector(rng, 0.5)}, {1, random_vector(rng, 0.5)}, s.stiffness, 0.8});
  m.springs.push_back(
      {{1, random_vector(rng, 0.5)}, {2, random_vector(rng, 0.5)}, s.stiffness, 0.0});
  m.springs.push_back(
      {{-1, Vector3(0.0, 0.0, 2.0)}, {0, random_vector(rng, 0.5)}, 2.0 * s.stiffness, 1.0});
  m.springs.push_back(
      {{2, random_vector(rng, 0.5)}, {-1, Vector3(3.0, 1.0, 2.0)}, 0.5 * s.stiffness, 0.5});
  m.forces.push_back({{0, random_vector(rng, 0.5)}, random_vector(rng, 1.0), {}});
  m.forces.push_back({{2, random_vector(rng, 0.5)}, random_vector(rng, 1.0), {}});
  m.torques.push_back({1, random_vector(rng, 1.0), {}});
  m.torques.push_back({2, random_vector(rng, 1.0), {}});
  return m;
}

fd::Dofs component_dofs(const Component& c) {
  fd::Dofs dofs(static_cast<size_t>(c.dofs / 3));
  for (const DofBlock& b : c.points)
    dofs[static_cast<size_t>(b.offset / 3)] = fd::point_dof(b.index);
  for (const DofBlock& b : c.rotations) {
    dofs[static_cast<size_t>(b.offset / 3)] = fd::rotation_dof(b.index);
  }
  return dofs;
}

::testing::AssertionResult check_potential(const IncrementalPotential& potential, const State& q,
                                           const fd::Dofs& dofs) {
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(dofs.size());
  Eigen::VectorXd g(n);
  Eigen::MatrixXd H(n, n);
  const double value = potential.assemble(q, g, H);
  // Same terms, same order of summation.
  if (value != potential.value(q)) {
    return ::testing::AssertionFailure()
           << "assemble returns " << value << ", value() " << potential.value(q);
  }
  const fd::ScalarFunction f = [&](const State& s) { return potential.value(s); };
  const fd::GradientFunction grad = [&](const State& s) {
    Eigen::VectorXd gs(n);
    Eigen::MatrixXd Hs(n, n);
    potential.assemble(s, gs, Hs);
    return gs;
  };
  ::testing::AssertionResult r = fd::check_lie_gradient(f, q, dofs, g);
  if (!r) return r;
  r = fd::check_lie_hessian(grad, q, dofs, H);
  if (!r) return r;
  return fd::check_lie_hessian_from_value(f, q, dofs, H);
}

TEST(IncrementalPotential, AssembledDerivativesMatchFiniteDifferences) {
  // Every combination of extreme scales. Within one model the FD check resolves the terms
  // that dominate at that scale (e.g. h = 1e-6 makes inertia ~1e12 times the loads); each
  // term is checked on its own above, this checks assembly, offsets and begin_step.
  std::mt19937 rng(13);
  int checked = 0;
  for (const double h : {1e-6, 1e-2, 1.0}) {
    for (const double mass : {1e-9, 1.0, 1e6}) {
      for (const double k : {1e-3, 1.0, 1e9}) {
        for (size_t run = 0; run < 2 * kAngles.size(); ++run) {
          const size_t a = run / 2;
          const bool list_R = run % 2 == 0;
          SCOPED_TRACE(trace("h, m, k", h, mass, k));
          SCOPED_TRACE(
              trace("first angle, angles for R (else for R_{k-1}, dR_{k-1})", kAngles[a], list_R));
          const Model model = make_model({h, mass, k}, rng);
          ASSERT_NO_THROW(model.validate());
          std::vector<Component> components = build_components(model);
          ASSERT_EQ(components.size(), 1u);
          Component& c = components[0];
          ASSERT_EQ(c.dofs, 18);
          ASSERT_EQ(c.potential.terms<Spring>().size(), 4u);
          ASSERT_EQ(c.potential.terms<ConstantTorque>().size(), 2u);

          // Either R, or R_{k−1} and ΔR_{k−1} (hence R̃ and the torques' reference), take
          // every angle of the list across bodies and runs; the others are placed 0.3 rad
          // away, so that every rotation block of the gradient is well above the FD noise of
          // the heaviest term (at R ≈ R̃ the inertia gradient vanishes, see the term tests).
          State previous = model.initial_state();
          Step step = model.initial_step();
          State q = previous;
          const size_t na = kAngles.size();
          for (size_t i = 0; i < 3; ++i) {
            step.points[i] = random_vector(rng, 0.1);
            q.points[i] = previous.points[i] + random_vector(rng, 0.2);
            if (list_R) {
              q.rotations[i] = rotation_at(kAngles[(a + i) % na], rng);
              step.rotations[i] = rotation_at(kAngles[(a + 3 * i + 1) % na], rng);
              previous.rotations[i] =
                  step.rotations[i].transpose() * rotation_at(0.3, rng) * q.rotations[i];
            } else {
              previous.rotations[i] = rotation_at(kAngles[(a + i) % na], rng);
              step.rotations[i] = rotation_at(kAngles[(a + 3 * i + 1) % na], rng);
              q.rotations[i] = rotation_at(0.3, rng) * step.rotations[i] * previous.rotations[i];
            }
          }
          c.potential.begin_step(previous, step);
          EXPECT_TRUE(check_potential(c.potential, q, component_dofs(c)));
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 27 * 2 * static_cast<int>(kAngles.size()));
}

TEST(IncrementalPotential, SeparateComponentsEachMatchFiniteDifferences) {
  // Bodies 0–1 joined, body 2 alone on a world spring: two components, each checked over
  // its own DOFs with the other component's state left untouched.
  std::mt19937 rng(14);
  Model model = make_model({1e-2, 1.0, 10.0}, rng);
  model.springs.erase(model.springs.begin() + 1);  // drop 1–2
  ASSERT_NO_THROW(model.validate());
  std::vector<Component> components = build_components(model);
  ASSERT_EQ(components.size(), 2u);
  EXPECT_EQ(components[0].dofs, 12);
  EXPECT_EQ(components[1].dofs, 6);
  State previous = model.initial_state();
  Step step = model.initial_step();
  State q = previous;
  for (size_t i = 0; i < 3; ++i) {
    previous.rotations[i] = rotation_at(0.4 + i, rng);
    step.rotations[i] = rotation_at(0.2, rng);
    q.points[i] += random_vector(rng, 0.2);
    q.rotations[i] = rotation_at(1.0 + i, rng);
  }
  for (Component& c : components) {
    c.potential.begin_step(previous, step);
    EXPECT_TRUE(check_potential(c.potential, q, component_dofs(c)));
  }
}

// The capabilities of every term type (lib/term.hpp), as the consumers detect them: losing
// one silently would drop a term from the reported energy, from Ceres's residuals, from load
// stepping or from the adjoint.
TEST(TermCapabilities, EveryTermTypeHasExactlyItsCapabilities) {
  static_assert(HasResidual<TranslationalInertia> && HasResidual<RotationalInertia> &&
                HasResidual<Spring> && HasResidual<RodStretch> && HasResidual<RodShear> &&
                HasResidual<RodBendTwist> && HasResidual<Contact> && HasResidual<Friction>);
  static_assert(!HasResidual<Gravity> && !HasResidual<ConstantForce> &&
                !HasResidual<ConstantTorque> && !HasResidual<RegionForce> &&
                !HasResidual<CableSegment>);
  static_assert(EnergyOfState<Gravity> && EnergyOfState<ConstantForce> && EnergyOfState<Spring> &&
                EnergyOfState<RodStretch> && EnergyOfState<RodShear> &&
                EnergyOfState<RodBendTwist> && EnergyOfState<Contact>);
  static_assert(!EnergyOfState<TranslationalInertia> && !EnergyOfState<RotationalInertia> &&
                !EnergyOfState<ConstantTorque> && !EnergyOfState<RegionForce> &&
                !EnergyOfState<CableSegment> && !EnergyOfState<Friction>);
  static_assert(LoadScaled<Gravity> && LoadScaled<ConstantForce> && LoadScaled<ConstantTorque> &&
                LoadScaled<RegionForce> && !LoadScaled<Spring> && !LoadScaled<CableSegment>);
  static_assert(BeginsStep<TranslationalInertia> && BeginsStep<RotationalInertia> &&
                BeginsStep<ConstantTorque> && BeginsStep<RegionForce> && BeginsStep<Friction> &&
                !BeginsStep<Spring> && !BeginsStep<Contact>);
  static_assert(Scheduled<ConstantForce> && Scheduled<ConstantTorque> &&
                Scheduled<RodBendTwist> && Scheduled<CableSegment> && !Scheduled<Spring>);
  static_assert(ReadsPreviousStep<TranslationalInertia> && ReadsPreviousStep<RotationalInertia> &&
                ReadsPreviousStep<ConstantTorque> && ReadsPreviousStep<Friction> &&
                !ReadsPreviousStep<RegionForce> && !ReadsPreviousStep<Contact>);
  static_assert(HasParameters<ConstantForce> && HasParameters<ConstantTorque> &&
                HasParameters<RodBendTwist> && HasParameters<CableSegment> &&
                HasParameters<Spring> && HasParameters<RodStretch> && HasParameters<RodShear> &&
                !HasParameters<Gravity> && !HasParameters<Contact> && !HasParameters<Friction>);
  static_assert(PointLoad<Gravity> && PointLoad<ConstantForce> && !PointLoad<ConstantTorque>);
  // Joints: the three constraint parts, and the motors, loads like a torque and a force.
  static_assert(Constraint<JointPoint> && Constraint<JointAlignment> && Constraint<JointWeld> &&
                !Constraint<Spring> && !Constraint<JointMotor>);
  static_assert(HasResidual<JointPoint> && HasResidual<JointAlignment> && HasResidual<JointWeld> &&
                EnergyOfState<JointPoint> && EnergyOfState<JointAlignment> &&
                EnergyOfState<JointWeld> && !BeginsStep<JointPoint> && !HasParameters<JointPoint>);
  static_assert(!HasResidual<JointMotor> && !EnergyOfState<JointMotor> && BeginsStep<JointMotor> &&
                Scheduled<JointMotor> && LoadScaled<JointMotor> &&
                ReadsPreviousStep<JointMotor> && HasParameters<JointMotor>);
  static_assert(!HasResidual<JointForceMotor> && !EnergyOfState<JointForceMotor> &&
                BeginsStep<JointForceMotor> && Scheduled<JointForceMotor> &&
                LoadScaled<JointForceMotor> && ReadsPreviousStep<JointForceMotor> &&
                HasParameters<JointForceMotor> && !Constraint<JointForceMotor>);
  // A force with a lever arm is not a point load; one on a bare point is.
  ConstantForce on_body;
  on_body.at = {0, 0, Vector3(1, 0, 0)};
  on_body.force = Vector3(0, 0, -2);
  int point = -1;
  Vector3 force;
  EXPECT_FALSE(on_body.point_load(point, force));
  ConstantForce on_node = on_body;
  on_node.at.rotation = -1;
  on_node.scale = 0.5;
  EXPECT_TRUE(on_node.point_load(point, force));
  EXPECT_EQ(point, 0);
  EXPECT_EQ(force, Vector3(0, 0, -1));
}

}  // namespace
}  // namespace liedyn::terms_tests

// Contact, friction and contact-damping terms (lib/contact.hpp, lib/friction.hpp,
// lib/contact_damping.hpp): value vs Lie gradient vs
// Lie Hessian by central differences in the tangent space (tests/fd_check.hpp) for samples
// on rigid bodies (blocks x, θ) and rod nodes (x only), against planes, spheres and bowls,
// at every rotation of fd::kAngles, over stiffnesses, penetrations and time steps from tiny
// to huge; the residual forms; and the friction term's mixed block ∂C/∂q_{k−1} for the
// adjoint (and the damping's), by differences of the lagged step.
//
// Geometry is O(1) (levers ~0.5 m, penetrations 1e-3…0.1 m) so that the fd_check defaults
// (relative 1e-6 for first differences, 1e-5 for second differences of the value) apply as
// derived there; energies scale out of relative errors. Differences never straddle a
// non-smooth set: penetrations stay ≫ the FD step (1e-6; 1e-4 for the value's second
// differences), and friction slips stay ≥ 1e-3 ε away from the stick–slip switch y = ε.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "contact_references.hpp"
#include "fd_check.hpp"
#include "lib/contact.hpp"
#include "lib/contact_damping.hpp"
#include "lib/friction.hpp"
#include "lib/loads.hpp"
#include "lib/sdf.hpp"
#include "lib/so3.hpp"

namespace liedyn::contact_tests {
namespace {

using fd::kAngles;
using fd::random_unit;
using fd::rotation_at;
using fd::trace;

std::shared_ptr<const Collider> make_collider(Shape shape, const Vector3& position,
                                              const Matrix3& orientation, bool inside = false) {
  Collider c;
  c.name = "test";
  c.shape = std::move(shape);
  c.position = position;
  c.orientation = orientation;
  c.inside = inside;
  return std::make_shared<const Collider>(c);
}

// The colliders every term is checked against: a tilted plane, a ball, a bowl (the inside of
// a sphere) and a rounded box, each posed at random.
std::vector<std::shared_ptr<const Collider>> colliders(std::mt19937& rng) {
  return {make_collider(PlaneShape{}, fd::random_vector(rng, 1.0), rotation_at(0.6, rng)),
          make_collider(SphereShape{1.5}, fd::random_vector(rng, 1.0), rotation_at(1.1, rng)),
          make_collider(SphereShape{3.0}, fd::random_vector(rng, 1.0), rotation_at(2.0, rng), true),
          make_collider(BoxShape{Vector3(1.0, 1.5, 2.0), 0.3}, fd::random_vector(rng, 1.0),
                        rotation_at(0.9, rng))};
}

// Places the body (x, R) so that its sample p = x + R p̄ is `depth` inside the sphere of
// radius ρ around it touching `collider`: φ(p) = ρ − depth. Walks along the SDF gradient
// from a random start until φ matches (Newton on φ along ∇φ; φ is 1-Lipschitz).
Vector3 place_sample(const Collider& collider, double target_distance, std::mt19937& rng) {
  return test::onto_level_set(collider, collider.position + 0.5 * random_unit(rng), target_distance);
}

struct BodySample {
  State q;
  AttachedPoint at;
};

// A body with a sample at lever p̄ whose world position is `p`.
BodySample body_sample(const Vector3& p, double angle, std::mt19937& rng) {
  BodySample b;
  const Matrix3 R = rotation_at(angle, rng);
  const Vector3 local(0.3, -0.4, 0.2);
  b.q.points = {p - R * local};
  b.q.rotations = {R};
  b.at = {0, 0, local};
  return b;
}

const fd::Dofs kBodyDofs = {fd::point_dof(0), fd::rotation_dof(0)};
const fd::Dofs kNodeDofs = {fd::point_dof(0), fd::no_dof()};

// ----------------------------------------------------------------------------------------

TEST(Contact, LieDerivativesOfABodySampleMatchFiniteDifferences) {
  std::mt19937 rng(3);
  for (const auto& collider : colliders(rng)) {
    for (double angle : kAngles) {
      for (double depth : {1e-3, 0.05}) {
        SCOPED_TRACE(trace("angle depth", angle, depth));
        Contact term;
        term.collider = collider;
        term.radius = 0.1;
        term.stiffness = 1e4;
        const BodySample b =
            body_sample(place_sample(*collider, term.radius - depth, rng), angle, rng);
        term.at = b.at;
        term.offsets = {0, 3};
        ASSERT_NEAR(term.penetration(b.q), depth, 1e-12);
        EXPECT_TRUE(fd::check_term(term, b.q, kBodyDofs));
      }
    }
  }
}

TEST(Contact, RodNodeSampleAndExtremeStiffnesses) {
  std::mt19937 rng(4);
  for (const auto& collider : colliders(rng)) {
    for (double k : {1e-3, 1.0, 1e9}) {
      SCOPED_TRACE(trace("stiffness", k));
      Contact term;
      term.collider = collider;
      term.radius = 0.02;
      term.stiffness = k;
      State q;
      q.points = {place_sample(*collider, term.radius - 0.01, rng)};
      term.at = {0, -1, Vector3::Zero()};
      term.offsets = {0, -1};
      EXPECT_TRUE(fd::check_term(term, q, kNodeDofs));
    }
  }
}

TEST(Contact, IsZeroAndFlatOutsideTheCollider) {
  std::mt19937 rng(5);
  for (const auto& collider : colliders(rng)) {
    Contact term;
    term.collider = collider;
    term.radius = 0.1;
    term.stiffness = 1e4;
    const BodySample b = body_sample(place_sample(*collider, 0.3, rng), 1.0, rng);
    term.at = b.at;
    LocalGradient<2> g;
    LocalHessian<2> H;
    EXPECT_EQ(term.evaluate(b.q, &g, &H), 0.0);
    EXPECT_TRUE(g.isZero(0.0));
    EXPECT_TRUE(H.isZero(0.0));
    Contact::Residual r;
    Contact::ResidualJacobian J;
    term.residual(b.q, r, &J);
    EXPECT_EQ(r(0), 0.0);
    EXPECT_TRUE(J.isZero(0.0));
  }
}

TEST(Contact, PushesAlongTheNormalWithForceStiffnessTimesDepth) {
  // A plane z ≤ 0 and a node 1 cm deep: the force −∂V/∂x is k·d along +z.
  Contact term;
  term.collider = make_collider(PlaneShape{}, Vector3::Zero(), Matrix3::Identity());
  term.radius = 0.05;
  term.stiffness = 2e3;
  State q;
  q.points = {Vector3(0.3, -0.2, 0.04)};
  term.at = {0, -1, Vector3::Zero()};
  LocalGradient<2> g;
  const double V = term.evaluate(q, &g, nullptr);
  EXPECT_NEAR(V, 0.5 * 2e3 * 0.01 * 0.01, 1e-15);
  EXPECT_TRUE((-g.head<3>()).isApprox(Vector3(0, 0, 2e3 * 0.01), 1e-12));
}

TEST(Contact, ResidualFormReproducesValueAndGradientAndItsJacobian) {
  std::mt19937 rng(6);
  for (const auto& collider : colliders(rng)) {
    for (double angle : kAngles) {
      SCOPED_TRACE(trace("angle", angle));
      Contact term;
      term.collider = collider;
      term.radius = 0.1;
      term.stiffness = 3e2;
      const BodySample b = body_sample(place_sample(*collider, 0.04, rng), angle, rng);
      term.at = b.at;
      LocalGradient<2> g;
      const double V = term.evaluate(b.q, &g, nullptr);
      Contact::Residual r;
      Contact::ResidualJacobian J;
      term.residual(b.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), V, 1e-12 * V);
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12));
      const fd::VectorFunction F = fd::residual_of(term);
      EXPECT_TRUE(fd::check_vector_jacobian(F, b.q, kBodyDofs, J));
    }
  }
}

// ----------------------------------------------------------------------------------------
// Friction.

struct FrictionCase {
  Friction term;
  State previous, q;
};

// A friction term whose lagged state is a body sample `depth` inside `collider`, and whose
// current state has moved the sample by `slip` along the tangent plane (plus `normal_move`
// along the normal) and turned the body by a small rotation.
FrictionCase friction_case(const std::shared_ptr<const Collider>& collider, double angle,
                           double slip, double epsilon, std::mt19937& rng,
                           double normal_move = 0.0) {
  FrictionCase c;
  c.term.collider = collider;
  c.term.radius = 0.1;
  c.term.stiffness = 1e4;
  c.term.coefficient = 0.4;
  c.term.epsilon = epsilon;
  const BodySample b = body_sample(place_sample(*collider, c.term.radius - 0.02, rng), angle, rng);
  c.term.at = b.at;
  c.term.offsets = {0, 3};
  c.previous = b.q;
  Step step;  // unused by friction
  c.term.begin_step(c.previous, step);
  const Vector3 n = c.term.normal;
  const Vector3 t = fd::random_perpendicular(n, rng);
  // Turn the body about its sample point (so the sample's slip is set by the translation).
  const Matrix3 turn = so3::exp(0.2 * random_unit(rng));
  const Vector3 p = b.at.position(b.q);
  c.q.rotations = {turn * b.q.rotations[0]};
  c.q.points = {p - c.q.rotations[0] * b.at.local + slip * t + normal_move * n};
  return c;
}

TEST(Friction, LieDerivativesInStickAndSlipMatchFiniteDifferences) {
  std::mt19937 rng(7);
  const double epsilon = 1e-2;
  for (const auto& collider : colliders(rng)) {
    for (double angle : kAngles) {
      // Deep in the stick regime, near the switch on both sides, and sliding.
      for (double slip : {0.3 * epsilon, 0.9 * epsilon, 1.1 * epsilon, 20.0 * epsilon}) {
        SCOPED_TRACE(trace("angle slip", angle, slip));
        const FrictionCase c = friction_case(collider, angle, slip, epsilon, rng, 0.003);
        ASSERT_GT(c.term.normal_force, 0.0);
        fd::TermCheckOptions options;
        // Second differences of the value: D depends on y = ‖u‖, whose fourth derivative is
        // ~1/y³, so the truncation is ~(step/y)² relative: step 1e-5 ≤ y/300 gives ≤ 1e-5.
        // Its round-off eps·D/step² ≈ 2e-6·D stays below the floor (D ≲ H·ε²). The switch at
        // y = ε is ≥ 1e-3 away from every slip here, beyond any step.
        options.hessian_from_value.step = 1e-5;
        EXPECT_TRUE(fd::check_term(c.term, c.q, kBodyDofs, options));
      }
    }
  }
}

TEST(Friction, AtZeroSlipTheForceVanishesAndTheStiffnessIsTwoMuLambdaOverEpsilon) {
  std::mt19937 rng(8);
  const auto plane = make_collider(PlaneShape{}, Vector3::Zero(), Matrix3::Identity());
  FrictionCase c = friction_case(plane, 0.7, 0.0, 1e-3, rng);
  c.q = c.previous;
  LocalGradient<2> g;
  LocalHessian<2> H;
  const double D = c.term.evaluate(c.q, &g, &H);
  const double mu_lambda = c.term.coefficient * c.term.normal_force;
  EXPECT_NEAR(D, mu_lambda * c.term.epsilon / 3.0, 1e-15 * mu_lambda);
  EXPECT_TRUE(g.isZero(0.0));
  const Matrix3 expected = 2.0 * mu_lambda / c.term.epsilon * Vector3(1, 1, 0).asDiagonal();
  const Matrix3 H_xx = H.topLeftCorner<3, 3>();
  EXPECT_TRUE(H_xx.isApprox(expected, 1e-12));
  // The value's second differences see the same stiffness at y = 0 (no gradient to check).
  fd::FdOptions o = fd::value_hessian_defaults();
  // D = μλ(y²/ε − y³/(3ε²) + ε/3) with y = ‖u‖: the cubic is not smooth at u = 0 and shifts
  // second differences by ~step/ε relative; step 1e-8 makes that 1e-5, and the round-off
  // eps·D/step² ≈ 3e-2 is far below H ≈ 1.6e5.
  o.step = 1e-8;
  EXPECT_TRUE(fd::check_lie_hessian_from_value(
      [&c](const State& s) { return c.term.evaluate(s, nullptr, nullptr); }, c.q, kBodyDofs, H, o));
}

TEST(Friction, SlidingForceIsMuLambdaAgainstTheSlip) {
  const auto plane = make_collider(PlaneShape{}, Vector3::Zero(), Matrix3::Identity());
  Friction term;
  term.collider = plane;
  term.radius = 0.05;
  term.stiffness = 1e3;
  term.coefficient = 0.5;
  term.epsilon = 1e-4;
  term.at = {0, -1, Vector3::Zero()};
  State previous;
  previous.points = {Vector3(0, 0, 0.04)};  // 1 cm deep: λ = 10 N
  term.begin_step(previous, Step{});
  EXPECT_DOUBLE_EQ(term.normal_force, 10.0);
  State q;
  q.points = {Vector3(0.01, 0.0, 0.05)};  // slides 1 cm along x (and lifts: lagged λ stays)
  LocalGradient<2> g;
  term.evaluate(q, &g, nullptr);
  EXPECT_TRUE((-g.head<3>()).isApprox(Vector3(-5.0, 0.0, 0.0), 1e-12));
}

TEST(Friction, ResidualFormReproducesValueAndGradient) {
  std::mt19937 rng(9);
  for (const auto& collider : colliders(rng)) {
    for (double slip : {0.0, 0.3e-2, 5e-2}) {
      const FrictionCase c = friction_case(collider, 1.3, slip, 1e-2, rng);
      LocalGradient<2> g;
      const double D = c.term.evaluate(c.q, &g, nullptr);
      Friction::Residual r;
      Friction::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * D);
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12) || g.isZero(0.0));
      const fd::VectorFunction F = fd::residual_of(c.term);
      fd::FdOptions o;
      if (slip == 0.0) o.require_nonzero = fd::NonZero::kNone;  // J = 0 at zero slip
      EXPECT_TRUE(fd::check_vector_jacobian(F, c.q, kBodyDofs, J, o));
    }
  }
}

TEST(Friction, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  // C(q; q_{k−1}): the local gradient at the fixed current state, as a function of the
  // previous state through p̂, λ and n (begin_step re-run on every perturbed q_{k−1}).
  std::mt19937 rng(10);
  for (const auto& collider : colliders(rng)) {
    for (double angle : kAngles) {
      for (double slip : {0.3e-2, 5e-2}) {
        SCOPED_TRACE(trace("angle slip", angle, slip));
        const FrictionCase c = friction_case(collider, angle, slip, 1e-2, rng, 0.002);
        const fd::VectorFunction C = fd::lagged_gradient(c.term, c.q);
        const Eigen::MatrixXd J = c.term.previous_jacobian(c.q, c.previous);
        EXPECT_TRUE(fd::check_vector_jacobian(C, c.previous, kBodyDofs, J));
      }
    }
  }
}

TEST(Friction, TinyAndHugeTimeStepsKeepDerivativesExactAndTheForceBounded) {
  // ε = ε_v h over h from 1e-6 to 1 s at ε_v = 1e-3 m/s: a quadratic zone from 1e-9 m to
  // 1e-3 m. The geometry is scaled with ε (penetration 50 ε, lever 100 ε, slips 0.5 ε and
  // 3 ε) so that the state's own round-off, eps·|p|, stays far below the FD steps, which must
  // stay inside the zone: 1e-4 ε for first differences (truncation ~step²/(y ε) ≈ 2e-8
  // relative), 1e-3 ε for second differences of the value (~step²/y² ≈ 4e-6, rtol 1e-5).
  std::mt19937 rng(11);
  const Matrix3 frame = rotation_at(0.4, rng);
  const auto plane = make_collider(PlaneShape{}, Vector3::Zero(), frame);
  const Vector3 n = frame.col(2);
  for (double h : {1e-6, 1e-3, 1.0}) {
    const double epsilon = 1e-3 * h;
    for (double factor : {0.5, 3.0}) {
      SCOPED_TRACE(trace("h factor", h, factor));
      Friction term;
      term.collider = plane;
      term.stiffness = 1e4;
      term.coefficient = 0.4;
      term.epsilon = epsilon;
      term.at = {0, 0, 100.0 * epsilon * random_unit(rng)};
      term.offsets = {0, 3};
      State previous;
      previous.rotations = {rotation_at(2.0, rng)};
      previous.points = {-50.0 * epsilon * n - previous.rotations[0] * term.at.local};
      term.begin_step(previous, Step{});
      ASSERT_NEAR(term.normal_force, 1e4 * 50.0 * epsilon, 1e-9 * term.normal_force);
      State q = previous;
      q.points[0] += factor * epsilon * fd::random_perpendicular(n, rng);
      // The θ rows are r × f with |r| = 100 ε: at h = 1e-6 that is 1e-7 of the x rows; their
      // non-zero check is the O(1)-lever test above.
      EXPECT_TRUE(fd::check_term(term, q, kBodyDofs, fd::within_zone(epsilon)));
    }
    // At O(1) geometry the same ε gives a force that never exceeds Coulomb's μλ, whatever
    // the slip (f₁ ≤ 1), and finite derivatives.
    const FrictionCase c = friction_case(plane, 1.0, 0.7 * epsilon, epsilon, rng);
    for (double slip : {0.0, 0.5 * epsilon, epsilon, 1e3 * epsilon}) {
      State q = c.q;
      q.points[0] = c.previous.points[0] + slip * fd::random_perpendicular(n, rng);
      q.rotations = c.previous.rotations;
      LocalGradient<2> g;
      LocalHessian<2> H;
      c.term.evaluate(q, &g, &H);
      EXPECT_LE(g.head<3>().norm(), c.term.coefficient * c.term.normal_force * (1.0 + 1e-12));
      EXPECT_TRUE(H.allFinite());
    }
  }
}

// ----------------------------------------------------------------------------------------
// Contact damping (lib/contact_damping.hpp): D = c s²/(2h), s = nᵀ(p − p̂), lagged n and zone.

struct DampingCase {
  ContactDamping term;
  State previous, q;
};

// A damping term whose lagged state is a body sample `depth` inside `collider` (outside for
// depth < 0), and whose current state has moved the sample by `normal_move` along the lagged
// normal and `slide` across it, and turned the body.
DampingCase damping_case(const std::shared_ptr<const Collider>& collider, double angle,
                         double depth, double normal_move, double slide, double h,
                         std::mt19937& rng) {
  DampingCase c;
  c.term.collider = collider;
  c.term.radius = 0.1;
  c.term.stiffness = 1e4;
  c.term.time_constant = 30.0 / c.term.stiffness;  // c = 30 N·s/m
  c.term.time_step = h;
  const BodySample b = body_sample(place_sample(*collider, c.term.radius - depth, rng), angle, rng);
  c.term.at = b.at;
  c.term.offsets = {0, 3};
  c.previous = b.q;
  c.term.begin_step(c.previous, Step{});
  const Vector3 n = c.term.normal;
  const Matrix3 turn = so3::exp(0.2 * random_unit(rng));
  const Vector3 p = b.at.position(b.q);
  c.q.rotations = {turn * b.q.rotations[0]};
  c.q.points = {p - c.q.rotations[0] * b.at.local + normal_move * n +
                slide * fd::random_perpendicular(n, rng)};
  return c;
}

TEST(ContactDamping, LieDerivativesMatchFiniteDifferences) {
  std::mt19937 rng(21);
  for (const auto& collider : colliders(rng)) {
    for (double angle : kAngles) {
      // Approaching, receding, and sliding along the surface.
      for (double normal_move : {-0.01, 0.004}) {
        SCOPED_TRACE(trace("angle move", angle, normal_move));
        const DampingCase c = damping_case(collider, angle, 0.02, normal_move, 0.03, 1e-3, rng);
        ASSERT_TRUE(c.term.active);
        EXPECT_TRUE(fd::check_term(c.term, c.q, kBodyDofs));
      }
    }
  }
}

TEST(ContactDamping, IsTheDashpotForceOnTheNormalVelocityAndNothingOutsideTheZone) {
  const auto plane = make_collider(PlaneShape{}, Vector3::Zero(), Matrix3::Identity());
  ContactDamping term;
  term.collider = plane;
  term.radius = 0.05;
  term.stiffness = 1e3;
  term.time_constant = 40.0 / term.stiffness;  // c = 40 N·s/m
  term.time_step = 1e-3;
  term.at = {0, -1, Vector3::Zero()};
  term.offsets = {0, -1};
  State previous;
  previous.points = {Vector3(0, 0, 0.04)};  // 1 cm inside the zone
  term.begin_step(previous, Step{});
  ASSERT_TRUE(term.active);
  State q;
  q.points = {Vector3(0.3, -0.2, 0.038)};  // approaching at 2 m/s, sliding at 360 m/s
  LocalGradient<2> g;
  LocalHessian<2> H;
  const double D = term.evaluate(q, &g, &H);
  // −f = −c v_n n = −40 · (−2) e_z: the dashpot pushes back along the normal only.
  EXPECT_TRUE((-g.head<3>()).isApprox(Vector3(0.0, 0.0, 80.0), 1e-12));
  EXPECT_NEAR(D, 0.5 * 40.0 * 4.0 * 1e-3, 1e-15);  // h · ½ c v_n²
  const Matrix3 K = Vector3(0.0, 0.0, 4e4).asDiagonal();  // (c/h) n nᵀ
  const Matrix3 H_xx = H.topLeftCorner<3, 3>();
  EXPECT_TRUE(H_xx.isApprox(K, 1e-12));
  // The zone is the lagged one: outside it at q_{k−1}, nothing, wherever q is.
  previous.points = {Vector3(0, 0, 0.06)};
  term.begin_step(previous, Step{});
  EXPECT_FALSE(term.active);
  EXPECT_EQ(term.evaluate(q, &g, &H), 0.0);
  EXPECT_TRUE(g.isZero(0.0));
  EXPECT_TRUE(H.isZero(0.0));
  fd::TermCheckOptions zero;  // everything vanishes here by construction
  for (fd::FdOptions* o : {&zero.gradient, &zero.hessian, &zero.hessian_from_value}) {
    o->require_nonzero = fd::NonZero::kNone;
  }
  EXPECT_TRUE(fd::check_term(term, q, kNodeDofs, zero));
}

TEST(ContactDamping, ResidualFormReproducesValueAndGradient) {
  std::mt19937 rng(22);
  for (const auto& collider : colliders(rng)) {
    for (double normal_move : {-0.01, 0.0, 0.004}) {
      const DampingCase c = damping_case(collider, 1.3, 0.02, normal_move, 0.02, 1e-3, rng);
      LocalGradient<2> g;
      const double D = c.term.evaluate(c.q, &g, nullptr);
      ContactDamping::Residual r;
      ContactDamping::ResidualJacobian J;
      c.term.residual(c.q, r, &J);
      EXPECT_NEAR(0.5 * r.squaredNorm(), D, 1e-13 * std::max(D, 1e-300));
      EXPECT_TRUE((J.transpose() * r).isApprox(g, 1e-12) || g.isZero(0.0));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::residual_of(c.term), c.q, kBodyDofs, J));
    }
  }
}

TEST(ContactDamping, MixedBlockOfTheLaggedStepMatchesFiniteDifferences) {
  // C(q; q_{k−1}) through p̂ and n (begin_step re-run on every perturbed q_{k−1}; the zone does
  // not switch: the sample is 2 cm inside, far beyond the FD step).
  std::mt19937 rng(23);
  for (const auto& collider : colliders(rng)) {
    for (double angle : kAngles) {
      SCOPED_TRACE(trace("angle", angle));
      const DampingCase c = damping_case(collider, angle, 0.02, -0.006, 0.01, 1e-3, rng);
      const fd::VectorFunction C = fd::lagged_gradient(c.term, c.q);
      const Eigen::MatrixXd J = c.term.previous_jacobian(c.q, c.previous);
      EXPECT_TRUE(fd::check_vector_jacobian(C, c.previous, kBodyDofs, J));
    }
  }
}

TEST(ContactDamping, TinyAndHugeTimeStepsAndDampingsKeepDerivativesExact) {
  // D = c s²/(2h) is quadratic in the state for any c/h: c/h from 1e-3 (c = 1e-3, h = 1 s) to
  // 1e12 (c = 1e6, h = 1e-6 s); the derivatives scale with it and stay exact (relative).
  std::mt19937 rng(24);
  const auto plane = make_collider(PlaneShape{}, Vector3::Zero(), rotation_at(0.4, rng));
  for (double h : {1e-6, 1e-3, 1.0}) {
    for (double c : {1e-3, 1.0, 1e6}) {
      SCOPED_TRACE(trace("h c", h, c));
      DampingCase d = damping_case(plane, 2.0, 0.02, -0.005, 0.01, h, rng);
      d.term.time_constant = c / d.term.stiffness;
      EXPECT_TRUE(fd::check_term(d.term, d.q, kBodyDofs));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(d.term, d.q), d.previous, kBodyDofs,
                                            d.term.previous_jacobian(d.q, d.previous)));
    }
  }
}

// ----------------------------------------------------------------------------------------
// Region pushes (lib/loads.hpp): V = −a F·x with a lagged a ∈ {0, 1}.

TEST(RegionForce, PushesOnlyPointsThatWereInsideAndMatchesFiniteDifferences) {
  RegionForce term;
  term.point = 0;
  term.offsets = {0};
  term.force = Vector3(0.3, -0.2, 0.1);
  term.center = Vector3(1, 0, 0);
  term.radius = 0.5;
  State previous;
  previous.points = {Vector3(1.2, 0.1, 0.0)};  // inside
  term.begin_step(previous, Step{});
  ASSERT_TRUE(term.active);
  const fd::Dofs dofs = {fd::point_dof(0)};
  for (double scale : {1e-3, 1.0, 1e9}) {  // the load factor, from tiny to huge
    SCOPED_TRACE(trace("scale", scale));
    term.scale = scale;
    State q;
    q.points = {Vector3(3.0, -2.0, 1.0)};  // the state may leave the region: a stays lagged
    LocalGradient<1> g;
    LocalHessian<1> H;
    const double V = term.evaluate(q, &g, &H);
    EXPECT_NEAR(V, -scale * term.force.dot(q.points[0]), 1e-15 * scale);
    EXPECT_TRUE(fd::check_lie_gradient(
        [&term](const State& s) { return term.evaluate(s, nullptr, nullptr); }, q, dofs, g));
    EXPECT_TRUE(H.isZero(0.0));
    // ∇²V = 0: the gradient's differences vanish too.
    fd::FdOptions o;
    o.require_nonzero = fd::NonZero::kNone;
    EXPECT_TRUE(fd::check_lie_hessian(
        [&term](const State& s) {
          LocalGradient<1> gs;
          term.evaluate(s, &gs, nullptr);
          return Eigen::VectorXd(gs);
        },
        q, dofs, H, o));
  }
  previous.points = {Vector3(1.0, 0.6, 0.0)};  // outside: no force at all
  term.begin_step(previous, Step{});
  EXPECT_FALSE(term.active);
  LocalGradient<1> g;
  EXPECT_EQ(term.evaluate(previous, &g, nullptr), 0.0);
  EXPECT_TRUE(g.isZero(0.0));
}

}  // namespace
}  // namespace liedyn::contact_tests

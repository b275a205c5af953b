// Internal damping of rods (lib/rod_damping.hpp): value vs Lie gradient vs Lie Hessian by
// central differences in the tangent space (tests/fd_check.hpp) at every rotation of
// fd::kAngles and relative angles from 0 to π − 1e-6, over tiny to huge time steps and
// dampings; the residual forms; the mixed blocks ∂C/∂q_{k−1} of the lagged strains for the
// adjoint; the dashpot laws (force η_s ε̇, moment η ω̇, shear moment ½ η_x l γ̇) and the shear
// rate's objectivity; and a cantilever's first mode decaying at the damping ratio a Rayleigh
// damping gives it.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "adjoint_check.hpp"
#include "fd_check.hpp"
#include "lib/rod_damping.hpp"
#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "rod_models.hpp"
#include "solvers/simulator.hpp"
#include "trajectory_compare.hpp"

namespace liedyn {
namespace {

using fd::kAngles;
using fd::random_unit;
using fd::rotation_at;
using fd::trace;

const fd::Dofs kNodes = {fd::point_dof(0), fd::point_dof(1)};
const fd::Dofs kEdges = {fd::rotation_dof(0), fd::rotation_dof(1)};

// The checks of a lagged damping term: its derivatives (fd::check_term), its residual form
// (½‖r‖² = D and Jᵀr = the gradient to `rtol`, J by differences) and its mixed block
// previous_jacobian by differences of the lagged gradient.
template <class Term>
void expect_lagged_term_checks(const Term& term, const State& q, const State& previous,
                               const fd::Dofs& dofs, double rtol) {
  EXPECT_TRUE(fd::check_term(term, q, dofs));
  typename Term::Residual r;
  typename Term::ResidualJacobian J;
  term.residual(q, r, &J);
  LocalGradient<Term::kBlocks> g;
  const double D = term.evaluate(q, &g, nullptr);
  EXPECT_NEAR(0.5 * r.squaredNorm(), D, rtol * D);
  EXPECT_TRUE((J.transpose() * r).isApprox(g, 10.0 * rtol));
  EXPECT_TRUE(fd::check_vector_jacobian(fd::residual_of(term), q, dofs, J));
  EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(term, q), previous, dofs,
                                        term.previous_jacobian(q, previous)));
}

// ----------------------------------------------------------------------------------------
// Stretch rate: D = (η_s/(2 l h)) (L − L̂)².

struct StretchDampingCase {
  RodStretchDamping term;
  State previous, q;
};

// An edge of rest length 0.1 m, `L_previous` long at q_{k−1}, `L` long now and turned.
StretchDampingCase stretch_case(double L_previous, double L, double eta, double h, std::mt19937& rng) {
  StretchDampingCase c;
  c.term.node0 = 0;
  c.term.node1 = 1;
  c.term.offsets = {0, 3};
  c.term.rest_length = 0.1;
  c.term.damping = eta;
  c.term.time_step = h;
  const Vector3 x0 = fd::random_vector(rng, 0.1), d = random_unit(rng);
  c.previous.points = {x0, x0 + L_previous * d};
  c.term.begin_step(c.previous, Step{});
  const Vector3 y0 = x0 + fd::random_vector(rng, 0.02);
  c.q.points = {y0, y0 + L * so3::exp(0.3 * random_unit(rng)) * d};
  return c;
}

TEST(RodStretchDamping, DerivativesResidualAndMixedBlockMatchFiniteDifferences) {
  std::mt19937 rng(41);
  int checked = 0;
  for (double h : {1e-6, 1e-3, 1.0}) {
    for (double eta : {1e-3, 1.0, 1e6}) {
      // Lengthening, shortening, and a rate far larger than the strain.
      for (const auto& [L_previous, L] : {std::pair{0.1, 0.104}, {0.105, 0.098}, {0.01, 0.3}}) {
        SCOPED_TRACE(trace("h eta", h, eta));
        SCOPED_TRACE(trace("L_previous L", L_previous, L));
        const StretchDampingCase c = stretch_case(L_previous, L, eta, h, rng);
        expect_lagged_term_checks(c.term, c.q, c.previous, kNodes, 1e-13);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 27);
}

TEST(RodStretchDamping, PullsWithEtaTimesTheStrainRate) {
  // Along x, l = 0.1 m, stretching from 0.1 to 0.1002 m in h = 1 ms: the strain rate is
  // (ΔL/l)/h = 2 1/s, so the force is η_s ε̇ = 1.5 · 2 = 3 N, resisting.
  RodStretchDamping term;
  term.node0 = 0;
  term.node1 = 1;
  term.rest_length = 0.1;
  term.damping = 1.5;
  term.time_step = 1e-3;
  State previous;
  previous.points = {Vector3::Zero(), Vector3(0.1, 0, 0)};
  term.begin_step(previous, Step{});
  State q;
  q.points = {Vector3::Zero(), Vector3(0.1002, 0, 0)};
  LocalGradient<2> g;
  term.evaluate(q, &g, nullptr);
  EXPECT_TRUE((-g.tail<3>()).isApprox(Vector3(-3.0, 0, 0), 1e-12));  // on node 1
  EXPECT_TRUE((-g.head<3>()).isApprox(Vector3(3.0, 0, 0), 1e-12));
}

// ----------------------------------------------------------------------------------------
// Bend and twist rate: D = ½ w (ω − ω̂)ᵀ (η/h) (ω − ω̂).

struct BendDampingCase {
  RodBendTwistDamping term;
  State previous, q;
};

// Two edge frames at rotations of kAngles, `previous_angle` apart at q_{k−1}; now both turned
// and `change` radians further apart about a random axis. `junction_angle` ≠ 0: the second
// frame is seen times a constant T of that angle, as across a splice's junction.
BendDampingCase bend_case(double frame_angle, double previous_angle, double change, double eta_scale,
                          double h, std::mt19937& rng, double junction_angle = 0.0) {
  BendDampingCase c;
  c.term.offsets = {0, 3};
  c.term.damping = eta_scale * Vector3(1.0, 1.7, 0.6);  // bend, bend, twist: all distinct
  c.term.time_step = h;
  c.term.set(0, 1, 0.1);
  if (junction_angle != 0.0) {
    c.term.form.has_frame_offset = true;
    c.term.form.frame_offset = so3::exp(junction_angle * random_unit(rng));
  }
  const Matrix3 Ra = rotation_at(frame_angle, rng);
  c.previous.rotations = {Ra, Ra * so3::exp(previous_angle * random_unit(rng))};
  c.term.begin_step(c.previous, Step{});
  const Matrix3 turn = so3::exp(0.2 * random_unit(rng));
  c.q.rotations = {turn * c.previous.rotations[0],
                   turn * c.previous.rotations[1] * so3::exp(change * random_unit(rng))};
  return c;
}

TEST(RodBendTwistDamping, DerivativesResidualAndMixedBlockMatchFiniteDifferences) {
  std::mt19937 rng(42);
  int checked = 0;
  for (double frame_angle : kAngles) {
    for (double previous_angle : {0.0, 1e-9, 1e-4, 1.0, std::numbers::pi - 1e-6}) {
      SCOPED_TRACE(trace("frame angle, previous relative angle", frame_angle, previous_angle));
      const BendDampingCase c = bend_case(frame_angle, previous_angle, 0.3, 1.0, 1e-3, rng);
      expect_lagged_term_checks(c.term, c.q, c.previous, kEdges, 1e-12);
      ++checked;
    }
  }
  // Tiny and huge steps and dampings: η/h from 1e-3 to 1e12 N·m², the same form.
  for (double h : {1e-6, 1.0}) {
    for (double eta : {1e-3, 1e6}) {
      SCOPED_TRACE(trace("h eta", h, eta));
      const BendDampingCase c = bend_case(1.0, 0.5, 0.3, eta, h, rng);
      EXPECT_TRUE(fd::check_term(c.term, c.q, kEdges));
      EXPECT_TRUE(fd::check_vector_jacobian(fd::lagged_gradient(c.term, c.q), c.previous, kEdges,
                                            c.term.previous_jacobian(c.q, c.previous)));
      ++checked;
    }
  }
  // Across a splice's junction (b's frame times T, in ω̂ too): at rest over the step the
  // term vanishes (to round-off), and its derivatives and mixed block hold as above.
  for (double frame_angle : kAngles) {
    for (double junction_angle : {1e-4, 0.7, std::numbers::pi - 1e-6}) {
      SCOPED_TRACE(trace("frame angle, junction angle", frame_angle, junction_angle));
      const BendDampingCase c = bend_case(frame_angle, 0.4, 0.3, 1.0, 1e-3, rng, junction_angle);
      expect_lagged_term_checks(c.term, c.q, c.previous, kEdges, 1e-12);
      LocalGradient<2> g;
      EXPECT_LE(c.term.evaluate(c.previous, &g, nullptr), 1e-20);
      EXPECT_LE(g.norm(), 1e-12);
      ++checked;
    }
  }
  EXPECT_EQ(checked, static_cast<int>(kAngles.size()) * 8 + 4);
}

TEST(RodBendTwistDamping, ResistsWithEtaTimesTheCurvatureRate) {
  // A straight pair of edges along z bending about x by 1e-4 rad in h = 1 ms over w = 0.1 m:
  // the curvature rate is (1e-4/0.1)/1e-3 = 1 1/(m·s), the moment η₁ · 1 = 2 N·m on edge 1
  // (against the bend) and −2 N·m on edge 0; to first order in the small angle.
  RodBendTwistDamping term;
  term.damping = Vector3(2.0, 3.0, 4.0);
  term.time_step = 1e-3;
  term.set(0, 1, 0.1);
  State previous;
  previous.rotations = {Matrix3::Identity(), Matrix3::Identity()};
  term.begin_step(previous, Step{});
  State q;
  q.rotations = {Matrix3::Identity(), so3::exp(Vector3(1e-4, 0, 0))};
  LocalGradient<2> g;
  term.evaluate(q, &g, nullptr);
  EXPECT_TRUE((-g.tail<3>()).isApprox(Vector3(-2.0, 0, 0), 1e-7));
  EXPECT_TRUE((-g.head<3>()).isApprox(Vector3(2.0, 0, 0), 1e-7));
}

// ----------------------------------------------------------------------------------------
// Shear rate: D = ½ (η_x/h) l (1 − dᵀ R â),  â = R̂ᵀ d̂.

const fd::Dofs kShearDofs = {fd::point_dof(0), fd::point_dof(1), fd::rotation_dof(0)};

struct ShearDampingCase {
  RodShearDamping term;
  State previous, q;
};

// An edge of rest length 0.1 m whose frame (at a rotation of kAngles) is sheared by
// `previous_shear` radians off the edge at q_{k−1}; now the whole edge turned and moved and
// the frame `change` radians further off. `L_previous` = 0: a crushed edge at q_{k−1}.
ShearDampingCase shear_case(double frame_angle, double previous_shear, double change, double eta,
                            double h, std::mt19937& rng, double L_previous = 0.1) {
  ShearDampingCase c;
  c.term.offsets = {0, 3, 6};
  c.term.damping = eta;
  c.term.time_step = h;
  c.term.set(0, 1, 0, 0.1);
  const Matrix3 R = rotation_at(frame_angle, rng);
  const Vector3 x0 = fd::random_vector(rng, 0.1);
  const Vector3 d = so3::exp(previous_shear * random_unit(rng)) * R.col(2);
  c.previous.points = {x0, x0 + L_previous * d};
  c.previous.rotations = {R};
  c.term.begin_step(c.previous, Step{});
  const Matrix3 turn = so3::exp(0.2 * random_unit(rng));
  const Vector3 y0 = x0 + fd::random_vector(rng, 0.02);
  c.q.points = {y0, y0 + 0.103 * (turn * d)};
  c.q.rotations = {so3::exp(change * random_unit(rng)) * turn * R};
  return c;
}

TEST(RodShearDamping, DerivativesResidualAndMixedBlockMatchFiniteDifferences) {
  std::mt19937 rng(43);
  int checked = 0;
  for (double frame_angle : kAngles) {
    for (double previous_shear : {0.0, 1e-9, 1e-4, 1.0, std::numbers::pi - 1e-6}) {
      SCOPED_TRACE(trace("frame angle, previous shear", frame_angle, previous_shear));
      const ShearDampingCase c = shear_case(frame_angle, previous_shear, 0.3, 1.0, 1e-3, rng);
      expect_lagged_term_checks(c.term, c.q, c.previous, kShearDofs, 1e-12);
      ++checked;
    }
  }
  // Tiny and huge steps and dampings (η_x/h from 1e-3 to 1e12 N), no change over the step
  // (D and its gradient vanish), and a crushed edge at q_{k−1} (â = e_z, no mixed block).
  for (double h : {1e-6, 1.0}) {
    for (double eta : {1e-3, 1e6}) {
      SCOPED_TRACE(trace("h eta", h, eta));
      const ShearDampingCase c = shear_case(1.0, 0.5, 0.3, eta, h, rng);
      expect_lagged_term_checks(c.term, c.q, c.previous, kShearDofs, 1e-12);
      ++checked;
    }
  }
  {
    const ShearDampingCase c = shear_case(1.0, 0.5, 0.3, 1.0, 1e-3, rng);
    LocalGradient<3> g;
    EXPECT_LE(c.term.evaluate(c.previous, &g, nullptr), 1e-16);
    EXPECT_LE(g.norm(), 1e-12);
    const ShearDampingCase crushed = shear_case(1.0, 0.5, 0.3, 1.0, 1e-3, rng, 0.0);
    EXPECT_EQ(crushed.term.form.material_axis, Vector3::UnitZ());
    EXPECT_TRUE(fd::check_term(crushed.term, crushed.q, kShearDofs));
    EXPECT_EQ(crushed.term.previous_jacobian(crushed.q, crushed.previous).norm(), 0.0);
    checked += 2;
  }
  EXPECT_EQ(checked, static_cast<int>(kAngles.size()) * 5 + 6);
}

TEST(RodShearDamping, ResistsWithHalfEtaTimesTheShearRateAndIgnoresRigidMotion) {
  // An edge along z, l = 0.1 m, its frame turning about x by 1e-4 rad in h = 1 ms: the shear
  // rate is γ̇ = 0.1 1/s and the moment on the frame ½ η_x l γ̇ = ½ · 4 · 0.1 · 0.1 = 0.02 N·m,
  // against the turn (as the elastic ¼ k_x l ‖γ‖² gives ½ k_x l γ); to first order in the angle.
  RodShearDamping term;
  term.damping = 4.0;
  term.time_step = 1e-3;
  term.set(0, 1, 0, 0.1);
  State previous;
  previous.points = {Vector3::Zero(), Vector3(0, 0, 0.1)};
  previous.rotations = {Matrix3::Identity()};
  term.begin_step(previous, Step{});
  State q = previous;
  q.rotations[0] = so3::exp(Vector3(1e-4, 0, 0));
  LocalGradient<3> g;
  term.evaluate(q, &g, nullptr);
  EXPECT_TRUE((-g.tail<3>()).isApprox(Vector3(-0.02, 0, 0), 1e-7)) << g.transpose();
  // The shear is measured in the material frame: a sheared edge carried rigidly over the step
  // (turned by any angle, moved) has no shear rate, so neither value nor force.
  std::mt19937 rng(44);
  for (double angle : kAngles) {
    SCOPED_TRACE(trace("rigid turn", angle));
    State sheared;
    const Matrix3 R = rotation_at(1.0, rng);
    sheared.points = {Vector3(0.1, 0.2, 0.3), Vector3(0.1, 0.2, 0.3) + 0.1 * (so3::exp(Vector3(0.2, 0, 0)) * R.col(2))};
    sheared.rotations = {R};
    term.begin_step(sheared, Step{});
    const Matrix3 Q = rotation_at(angle, rng);
    State carried;
    carried.points = {Q * sheared.points[0] + Vector3(1, 2, 3), Q * sheared.points[1] + Vector3(1, 2, 3)};
    carried.rotations = {Q * R};
    EXPECT_LE(term.evaluate(carried, &g, nullptr), 1e-16);
    EXPECT_LE(g.norm(), 1e-10);
  }
}

// ----------------------------------------------------------------------------------------
// A damped cantilever's first mode.

// Mean |y| of the tip over the first and over the fifth period of the first mode of a
// cantilever started bent (test_models::bent_cantilever, as Trapezoidal.ReleasedRodKeeps…),
// with bending damping η = β EI: their ratio.
double damped_amplitude_ratio(double beta, Integrator integrator, double* period) {
  Model model;
  model.time_step = 2e-3;
  model.integrator = integrator;
  const double EI = 0.5;
  RodSpec rod = test_models::bent_cantilever(20, EI, 0.2);
  rod.bending_damping = beta * rod.bending_stiffness;
  model.rods.push_back(rod);
  SolverOptions options;
  options.tolerance = 1e-10;
  Simulator sim(model, options);
  const double omega = std::pow(test_models::cantilever_beta1(), 2) * std::sqrt(EI / 0.1);
  *period = 2.0 * std::numbers::pi / omega;
  const int steps = static_cast<int>(std::lround(*period / model.time_step));
  const int tip = 20;
  double first = 0.0, last = 0.0;
  for (int k = 1; k <= 5 * steps; ++k) {
    EXPECT_TRUE(sim.step().converged()) << k;
    const double y = std::abs(sim.state().points[model.rod_point(0, tip)].y());
    if (k <= steps) first += y;
    if (k > 4 * steps) last += y;
  }
  return last / first;
}

TEST(RodDamping, ACantileversFirstModeDecaysAtTheRayleighDampingRatio) {
  // η = β K gives mode n the damping ratio ζ_n = β ω_n/2 (lib/rod_damping.hpp): the first
  // mode (ω₁ = 1.8751² √(EI/(m L³)) = 7.86 rad/s for this rod) with β = 2.5e-3 s has
  // ζ₁ = 9.83e-3, and over four damped periods its amplitude falls by
  // exp(−2π ζ₁/√(1 − ζ₁²) · 4) = 0.781. The faster modes the bent start also excites are damped
  // far faster (ζ_n ∝ ω_n), so the tip's mean |y| per period follows the first mode's.
  // Errors: the discrete rod's ω₁ is 0.4 % off the continuum's at 20 edges (0.8 % of ζ₁ω₁);
  // the damping acts at the step's end, first order: ζ is off by O(ω₁h) = 1.6 %; the
  // trapezoidal rule's own amplitude error over four periods is 0.9 %
  // (Trapezoidal.ReleasedRodKeepsItsAmplitude). Together ≤ 4 % of the decay exponent 0.247:
  // ±0.01 on the ratio.
  const double beta = 2.5e-3;
  double period = 0.0;
  const double ratio = damped_amplitude_ratio(beta, Integrator::kTrapezoidal, &period);
  const double omega = 2.0 * std::numbers::pi / period;
  const double zeta = beta * omega / 2.0;
  const double expected = std::exp(-2.0 * std::numbers::pi * zeta / std::sqrt(1.0 - zeta * zeta) * 4.0);
  std::printf("damped cantilever: zeta_1 = %.4e, amplitude after four periods %.4f, expected %.4f\n",
              zeta, ratio, expected);
  EXPECT_NEAR(ratio, expected, 0.01);
}

TEST(RodDamping, TheAdjointGradientRunsBackThroughTheDampingTerms) {
  // A damped rod thrown through the air (no contact): γ = its initial node velocities, the loss
  // the distance of its final nodes to a target line; the gradient against central
  // differences (adjoint_check.hpp). Damping ratios ζ = (η/K) ω/2: 0.1 for the free rod's first
  // bending mode (ω ≈ 4.73² √(EI/(m L³)) ≈ 19 rad/s, η/K = 1e-2 s) and 0.3 for its first axial
  // mode (ω ≈ (π/L) √(k_s L/m) ≈ 810 rad/s, η_s/k_s = 7.5e-4 s); the shear rate is damped as
  // the stretch rate (η_x/k_x = 7.5e-4 s).
  const std::string text = R"({
    "time_step": 0.005, "frames": 60, "gravity": [0, 0, -9.81],
    "solver": { "tolerance": 1e-12, "max_iterations": 100 },
    "rods": [ { "name": "rod", "shape": { "type": "line", "start": [0, 0, 0.3], "end": [0.3, 0, 0.35], "edges": 6 },
                "mass": 0.05, "radius": 0.005, "stretch_stiffness": 1e3, "shear_stiffness": 1e3,
                "bending_stiffness": [1e-3, 1e-3, 1e-3], "stretch_damping": 0.75,
                "shear_damping": 0.75, "bending_damping": [1e-5, 1e-5, 1e-5],
                "node_velocities": [[0, 0, 1], [0, 0.2, 1], [0, 0.4, 1.5], [0, 0.2, 1], [0.1, 0, 1], [0, 0, 0.5], [0, -0.3, 1]] } ],
    "optimization": {
      "parameters": [ { "kind": "rod_node_velocities", "rod": "rod" } ],
      "objective": [ { "term": "point_targets", "rod": "rod", "frame": -1,
                       "polyline": [[0.1, 0.1, 0], [0.4, 0.1, 0]] } ] } })";
  EXPECT_TRUE(test::gradient_agrees(parse_scene(text, "damped_rod")));
}

TEST(RodDamping, TheThreeBackEndsAgreeOnADampedRod) {
  // Ceres takes the damping terms as their residuals, Ipopt as objective terms: a damped rod
  // swinging under gravity from a clamp, under both integrators, 40 frames within 1e-6 (m, rad)
  // of Newton's at the tolerance 1e-8 (Ceres stalls on rods at Newton steps of 1e-9 and above:
  // README, "Back-ends").
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0, 0, -9.81);
  RodSpec rod = test_models::uniform_rod(8, 0.5, 0.05, 0.005, 1e3, 1e3, 2e-3);
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  rod.stretch_damping = 0.2;
  rod.shear_damping = 0.2;
  rod.bending_damping = Vector3(1e-4, 2e-4, 1e-4);
  model.rods.push_back(rod);
  for (const Integrator integrator : {Integrator::kBackwardEuler, Integrator::kTrapezoidal}) {
    SCOPED_TRACE(to_string(integrator));
    model.integrator = integrator;
    SolverOptions options;
    options.tolerance = 1e-8;
    const test::Trajectory newton = test::run_frames(model, options, 40, "newton");
    for (const Backend b : {Backend::kCeres, Backend::kIpopt}) {
      SCOPED_TRACE(to_string(b));
      SolverOptions other = options;
      other.backend = b;
      const auto [dx, dR] = test::deviation(newton, test::run_frames(model, other, 40, to_string(b)));
      EXPECT_LE(dx, 1e-6);
      EXPECT_LE(dR, 1e-6);
    }
  }
}

// ----------------------------------------------------------------------------------------
// Scenes.

TEST(RodDamping, SceneKeysAreReadAndCheckedAndStaticModeHasNoTerms) {
  const std::string rod = R"("rods": [ { "name": "r", "shape": { "type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": 4 },
      "mass": 0.1, "radius": 0.01, "stretch_stiffness": 100, "shear_stiffness": 100, "bending_stiffness": [1, 1, 1],
      "fixed_nodes": [0], "fixed_edges": [0], )";
  const auto text = [&](const std::string& mode, const std::string& damping) {
    return R"({ "mode": ")" + mode + R"(", "time_step": 0.01, "frames": 2, )" + rod + damping + " } ] }";
  };
  const Scene s = parse_scene(text("dynamic", R"("stretch_damping": 0.5, "shear_damping": 0.25, "bending_damping": [1e-3, 2e-3, 3e-3])"), "d.json");
  EXPECT_EQ(s.model.rods[0].stretch_damping, 0.5);
  EXPECT_EQ(s.model.rods[0].shear_damping, 0.25);
  EXPECT_EQ(s.model.rods[0].bending_damping, Vector3(1e-3, 2e-3, 3e-3));
  const std::vector<Component> dynamic = build_components(s.model);
  ASSERT_EQ(dynamic.size(), 1u);
  EXPECT_EQ(dynamic[0].potential.terms<RodStretchDamping>().size(), 4u);  // every edge: node 1 moves
  EXPECT_EQ(dynamic[0].potential.terms<RodShearDamping>().size(), 4u);
  EXPECT_EQ(dynamic[0].potential.terms<RodBendTwistDamping>().size(), 3u);
  // Both ends of edge 0 clamped (nodes 0, 1) and edges 0 and 1 clamped: no stretch or shear
  // term for edge 0 and no bend term at node 1, whose rates are prescribed, not DOFs.
  const std::string clamped_rod = R"("rods": [ { "name": "r", "shape": { "type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": 4 },
      "mass": 0.1, "radius": 0.01, "stretch_stiffness": 100, "shear_stiffness": 100, "bending_stiffness": [1, 1, 1],
      "fixed_nodes": [0, 1], "fixed_edges": [0, 1], "stretch_damping": 0.5, "shear_damping": 0.25, "bending_damping": [1e-3, 2e-3, 3e-3] } ] })";
  const Scene held = parse_scene(R"({ "time_step": 0.01, "frames": 2, )" + clamped_rod, "h.json");
  const std::vector<Component> held_components = build_components(held.model);
  EXPECT_EQ(held_components[0].potential.terms<RodStretchDamping>().size(), 3u);
  EXPECT_EQ(held_components[0].potential.terms<RodShearDamping>().size(), 3u);
  EXPECT_EQ(held_components[0].potential.terms<RodBendTwistDamping>().size(), 2u);
  const Scene st = parse_scene(text("static", R"("stretch_damping": 0.5, "shear_damping": 0.25, "bending_damping": [1e-3, 2e-3, 3e-3])"), "s.json");
  const std::vector<Component> statics = build_components(st.model);
  EXPECT_TRUE(statics[0].potential.terms<RodStretchDamping>().empty());
  EXPECT_TRUE(statics[0].potential.terms<RodShearDamping>().empty());
  EXPECT_TRUE(statics[0].potential.terms<RodBendTwistDamping>().empty());
  for (const auto& [damping, field] :
       {std::pair{std::string(R"("stretch_damping": -1)"), "rods[0].stretch_damping"},
        std::pair{std::string(R"("shear_damping": -0.5)"), "rods[0].shear_damping"},
        std::pair{std::string(R"("bending_damping": [0, -1, 0])"), "rods[0].bending_damping[1]"}}) {
    try {
      parse_scene(text("dynamic", damping), "bad.json");
      ADD_FAILURE() << "accepted " << damping;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("≥ 0"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace liedyn

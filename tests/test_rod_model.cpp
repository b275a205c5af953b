// Rods in the model (lib/rod.hpp, lib/model.hpp, build_rod_component): discretisation,
// validation, and first checks against beam mechanics (docs/design.md §13). The full validation
// suite of issue 3 (elastica, vibration, convergence studies) is still to come.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "lib/incremental_potential.hpp"
#include "lib/so3.hpp"
#include "rod_models.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

RodSpec straight_rod(int edges, double length) {
  RodSpec rod;
  rod.name = "rod";
  for (int i = 0; i <= edges; ++i) rod.nodes.push_back(Vector3(length * i / edges, 0.0, 0.0));
  rod.mass = 0.1;
  rod.radius = 0.01;
  rod.stretch_stiffness = 1e5;
  rod.shear_stiffness = 1e5;
  rod.bending_stiffness = Vector3(1.0, 1.0, 1.0);
  return rod;
}

RodSpec helix_rod(int edges) {
  RodSpec rod = straight_rod(edges, 1.0);
  rod.nodes.clear();
  const double radius = 0.05, pitch = 0.02, turns = 3.0;
  for (int k = 0; k <= edges; ++k) {
    const double phi = 2.0 * std::numbers::pi * turns * k / edges;
    rod.nodes.push_back(Vector3(radius * std::cos(phi), radius * std::sin(phi),
                                pitch * phi / (2.0 * std::numbers::pi)));
  }
  return rod;
}

TEST(RodDiscretization, MassesFramesAndRestShape) {
  const RodSpec rod = helix_rod(60);
  const RodDiscretization d = discretize(rod);
  double total = 0.0;
  for (double m : d.node_mass) total += m;
  EXPECT_NEAR(total, rod.mass, 1e-15);
  ASSERT_EQ(d.frames.size(), 60u);
  for (int j = 0; j < 60; ++j) {
    const Matrix3& R = d.frames[j];
    EXPECT_LT((R.transpose() * R - Matrix3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
    const Vector3 t = (rod.nodes[j + 1] - rod.nodes[j]).normalized();
    EXPECT_LT((R * Vector3::UnitZ() - t).norm(), 1e-13) << "edge " << j;
  }
  // Parallel transport: each frame is the previous one turned by the minimal rotation
  // between the tangents, so the rest Darboux vector has no twist (third, material-z)
  // component, only curvature.
  ASSERT_EQ(d.rest_darboux.size(), 59u);
  for (const Vector3& w : d.rest_darboux) {
    EXPECT_LT(std::abs(w.z()), 1e-10 * w.norm());
    EXPECT_GT(w.norm(), 1.0);  // a helix of radius 5 cm is curved (κ ≈ 19.6 /m)
  }
}

TEST(RodDiscretization, MinimalRotationHandlesParallelAndAntiparallelVectors) {
  const Vector3 a = Vector3(1.0, 2.0, -0.5).normalized();
  for (const Vector3& b : {a, Vector3(-a), Vector3(Vector3(0.3, -1.0, 0.2).normalized())}) {
    const Matrix3 R = minimal_rotation(a, b);
    EXPECT_LT((R * a - b).norm(), 1e-14);
    EXPECT_LT((R.transpose() * R - Matrix3::Identity()).norm(), 1e-14);
  }
}

TEST(RodModel, ValidationNamesTheField) {
  Model model;
  model.rods.push_back(straight_rod(4, 1.0));
  model.rods[0].fixed_nodes = {0, 7};
  try {
    model.validate();
    FAIL() << "accepted a fixed node out of range";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "rods[0].fixed_nodes[1]");
  }
  model.rods[0].fixed_nodes = {0};
  model.rods[0].nodes[2] = model.rods[0].nodes[1];
  try {
    model.validate();
    FAIL() << "accepted a zero-length edge";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "rods[0].nodes[2]");
  }
}

// The bending lengths (lib/rod.hpp, discretize): Voronoi cells, and next to a clamped end edge
// (fixed, or welded to the world for the whole run, and not spliced) that edge's outer half too.
TEST(RodModel, BendingLengthsCoverTheClampedEndEdges) {
  const auto lengths = [](const Model& m, int r) { return m.discretize_rod(r).bending_length; };
  const auto expect = [](const std::vector<double>& got, const std::vector<double>& want) {
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-15) << "node " << i + 1;
  };
  Model m;
  m.rods = {straight_rod(6, 0.6)};  // l = 0.1 m
  expect(lengths(m, 0), {0.1, 0.1, 0.1, 0.1, 0.1});  // free ends
  m.rods[0].fixed_edges = {0};
  expect(lengths(m, 0), {0.15, 0.1, 0.1, 0.1, 0.1});
  m.rods[0].fixed_edges = {5};
  expect(lengths(m, 0), {0.1, 0.1, 0.1, 0.1, 0.15});
  m.rods[0].fixed_edges = {0, 1};  // two clamped edges: straight up to the middle of edge 1
  expect(lengths(m, 0), {0.15, 0.1, 0.1, 0.1, 0.1});
  m.rods[0].fixed_edges = {2};  // an interior clamp
  expect(lengths(m, 0), {0.1, 0.1, 0.1, 0.1, 0.1});
  // Welds of the last edge: to the world for the whole run, for some steps only, to a body.
  m.rods[0].fixed_edges = {};
  JointSpec weld;
  weld.type = JointSpec::Type::kWeld;
  weld.a = JointEnd::rod_edge(0, 5, Vector3::Zero());
  weld.b = JointEnd::world(Vector3(0.5, 0, 0));
  m.joints = {weld};
  expect(lengths(m, 0), {0.1, 0.1, 0.1, 0.1, 0.15});
  m.joints[0].last_frame = 10;
  expect(lengths(m, 0), {0.1, 0.1, 0.1, 0.1, 0.1});
  m.joints[0].last_frame = std::numeric_limits<int>::max();
  RigidBody body;
  body.name = "b";
  m.bodies = {body};
  m.joints[0].b = JointEnd::body(0, Vector3::Zero());
  expect(lengths(m, 0), {0.1, 0.1, 0.1, 0.1, 0.1});
  // A clamped first edge spliced to another rod's last node: the junction covers it.
  Model spliced;
  spliced.rods = {straight_rod(6, 0.6), straight_rod(6, 0.6)};
  spliced.rods[1].fixed_edges = {0};
  JointSpec splice;
  splice.type = JointSpec::Type::kSplice;
  splice.a = JointEnd::rod_node(0, 6);
  splice.b = JointEnd::rod_node(1, 0);
  spliced.joints = {splice};
  expect(lengths(spliced, 1), {0.1, 0.1, 0.1, 0.1, 0.1});
  spliced.joints.clear();
  expect(lengths(spliced, 1), {0.15, 0.1, 0.1, 0.1, 0.1});
  // Two edges clamped at both ends: the one hinge covers the whole rod.
  Model two;
  two.rods = {straight_rod(2, 0.2)};
  two.rods[0].fixed_edges = {0, 1};
  expect(lengths(two, 0), {0.2});
}

TEST(RodModel, ClampedDofsAreNotInTheComponent) {
  Model model;
  model.rods.push_back(straight_rod(5, 1.0));  // 6 nodes, 5 edges
  model.rods[0].fixed_nodes = {0, 5};
  model.rods[0].fixed_edges = {0};
  const std::vector<Component> components = build_components(model);
  ASSERT_EQ(components.size(), 1u);
  EXPECT_EQ(components[0].dofs, 3 * (6 - 2) + 3 * (5 - 1));
  EXPECT_EQ(components[0].potential.terms<RodStretch>().size(), 5u);
  EXPECT_EQ(components[0].potential.terms<RodBendTwist>().size(), 4u);
  EXPECT_EQ(components[0].potential.terms<TranslationalInertia>().size(), 4u);
}

// Simulates a clamped rod under a constant load until backward Euler's dissipation has
// brought it to rest; returns the simulator.
Simulator settle(const Model& model, int steps) {
  SolverOptions options;
  options.tolerance = 1e-12;
  Simulator sim(model, options);
  for (int k = 0; k < steps; ++k) {
    const StepReport r = sim.step();
    EXPECT_TRUE(r.converged()) << "step " << k << ": " << to_string(r.status);
    if (!r.state_updated()) break;
  }
  return sim;
}

TEST(RodMechanics, CantileverTipDeflectionUnderSmallLoad) {
  // Continuum: tip deflection F L³/(3 EI) of a clamped beam under a tip force F.
  // Discrete (small load): node 0 and edge 0 are clamped, so the rod bends at the interior
  // nodes i = 1…n−1, each a hinge carrying the moment F (L − i l) with stiffness EI/w_i: w_i = l,
  // but w_1 = 3l/2 next to the clamped end (lib/rod.hpp, discretize). Its kink
  // F (L − i l) w_i/EI moves the tip by that angle times (L − i l), so
  //   δ_bend = F l³/EI (Σ_{j=1}^{n−1} j² + ½ (n − 1)²) = F L³/(3EI) · (1 − 5/(2n²) + 3/(2n³))
  // (test_models::clamped_rod_tip_fraction), second order in 1/n. Shear adds compliance: each edge carries the transverse force F with
  // ½ k_x l (1 − dᵀ R e_z) ≈ ¼ k_x l γ², so γ = 2F/k_x and δ_shear = 2 F L / k_x.
  // Neglected: geometric non-linearity, O((F L²/EI)²) = 1e-6 relative.
  const double L = 1.0, EI = 1.0, F = 1e-3, kx = 1e5;
  std::vector<double> error;
  for (int edges : {10, 20, 40}) {
    Model model;
    model.time_step = 0.01;
    RodSpec rod = straight_rod(edges, L);
    rod.bending_stiffness = Vector3(EI, EI, EI);
    rod.shear_stiffness = kx;
    rod.fixed_nodes = {0};
    rod.fixed_edges = {0};
    rod.node_forces = {{edges, Vector3(0.0, 0.0, -F), {}}};
    model.rods.push_back(rod);
    const Simulator sim = settle(model, 3000);
    EXPECT_LT(sim.kinetic_energy(), 1e-18) << "not at rest yet";
    const double tip = -sim.state().points[model.rod_point(0, edges)].z();
    const double n = edges;
    const double continuum = F * L * L * L / (3.0 * EI);
    const double shear = 2.0 * F * L / kx;
    const double discrete = continuum * test_models::clamped_rod_tip_fraction(n) + shear;
    EXPECT_NEAR(tip / discrete, 1.0, 1e-5) << edges << " edges";
    error.push_back((tip - shear) / continuum - 1.0);
    std::printf("cantilever %d edges: tip %.9g m, discrete prediction %.9g, continuum %.9g\n",
                edges, tip, discrete, continuum);
  }
  // Second-order convergence to F L³/(3EI): e = −5/(2n²) + 3/(2n³) (the shear compliance
  // taken off, as it does not depend on n) gives e(n)/e(2n) = 4 (1 − 3/(5n))/(1 − 3/(10n)),
  // 3.88 from n = 10 and 3.94 from 20; ±0.2 of 4 tells it from first order (2).
  EXPECT_NEAR(error[0] / error[1], 4.0, 0.2);
  EXPECT_NEAR(error[1] / error[2], 4.0, 0.2);
}

TEST(RodMechanics, AxialStretchUnderTipForce) {
  // ΔL = F L / k_s for a rod pulled along its axis (stretch energy ½ k_s l (1 − ‖e‖/l)²
  // per edge: each edge is a spring of stiffness k_s/l in series, L/l of them).
  const double L = 0.8, ks = 2e3, F = 0.5;
  Model model;
  model.time_step = 0.01;
  RodSpec rod = straight_rod(16, L);
  rod.stretch_stiffness = ks;
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  rod.node_forces = {{16, Vector3(F, 0.0, 0.0), {}}};
  model.rods.push_back(rod);
  const Simulator sim = settle(model, 2000);
  const double stretch = sim.state().points[model.rod_point(0, 16)].x() - L;
  // Exact for this discretisation (each edge carries F): ΔL = F L / k_s.
  EXPECT_NEAR(stretch, F * L / ks, 1e-9);
  // The rod stays straight: no transverse displacement, no rotation of the edges.
  for (int i = 0; i <= 16; ++i) {
    EXPECT_LT(std::abs(sim.state().points[model.rod_point(0, i)].y()), 1e-12);
    EXPECT_LT(std::abs(sim.state().points[model.rod_point(0, i)].z()), 1e-12);
  }
}

TEST(RodMechanics, FreeRodUnderGravityFallsFreely) {
  // An unclamped rod is a free body: its centre of mass accelerates at g exactly (gravity
  // is linear, elastic forces are internal), whatever its shape does.
  Model model;
  model.time_step = 0.005;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  model.rods.push_back(helix_rod(30));
  Simulator sim(model, SolverOptions{});
  const RodDiscretization d = discretize(model.rods[0]);
  auto centre = [&]() {
    Vector3 c = Vector3::Zero();
    for (int i = 0; i <= 30; ++i) c += d.node_mass[i] * sim.state().points[model.rod_point(0, i)];
    return Vector3(c / model.rods[0].mass);
  };
  const Vector3 c0 = centre();
  const int steps = 100;
  for (int k = 0; k < steps; ++k) ASSERT_TRUE(sim.step().converged());
  // Backward Euler on a uniformly accelerated point: x_k = x_0 + g h² k(k+1)/2.
  const double h = model.time_step;
  const Vector3 expected = c0 + model.gravity * h * h * steps * (steps + 1) / 2.0;
  EXPECT_LT((centre() - expected).norm(), 1e-9);
}

// Static mode: no inertia, loads ramped over the load steps. In the linear regime each load
// step's tip deflection is λ_k times the discrete prediction of the dynamic test above.
TEST(RodStatics, CantileverLoadStepsFollowTheLinearPrediction) {
  const double L = 1.0, EI = 1.0, F = 1e-3, kx = 1e5;
  const int edges = 20, load_steps = 4;
  Model model;
  model.static_equilibrium = true;
  model.load_steps = load_steps;
  RodSpec rod = straight_rod(edges, L);
  rod.bending_stiffness = Vector3(EI, EI, EI);
  rod.shear_stiffness = kx;
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  rod.node_forces = {{edges, Vector3(0.0, 0.0, -F), {}}};
  model.rods.push_back(rod);
  SolverOptions options;
  options.tolerance = 1e-12;
  Simulator sim(model, options);
  const double n = edges;
  const double full =
      F * L * L * L / (3.0 * EI) * test_models::clamped_rod_tip_fraction(n) + 2.0 * F * L / kx;
  for (int k = 1; k <= load_steps + 1; ++k) {  // one step past the ramp: λ stays 1
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << "load step " << k << ": " << to_string(r.status);
    const double lambda = std::min(1.0, double(k) / load_steps);
    const double tip = -sim.state().points[model.rod_point(0, edges)].z();
    // Non-linearity: O((λ F L²/EI)²) = 1e-6 relative; tolerance 1e-5.
    EXPECT_NEAR(tip / (lambda * full), 1.0, 1e-5) << "load step " << k;
    EXPECT_EQ(sim.kinetic_energy(), 0.0);  // equilibria have no velocity
  }
}

TEST(RodStatics, LargeDeflectionStaticEqualsTheDynamicRestState) {
  // The same minimiser reached two ways: load steps without inertia, and backward Euler
  // dissipating until rest (F L²/EI = 2, dead load).
  const double L = 1.0, EI = 1.0, F = 2.0;
  const int edges = 20;
  auto cantilever = [&](bool statics) {
    Model model;
    model.time_step = 0.05;
    model.static_equilibrium = statics;
    model.load_steps = 10;
    RodSpec rod = straight_rod(edges, L);
    rod.bending_stiffness = Vector3(EI, EI, EI);
    rod.fixed_nodes = {0};
    rod.fixed_edges = {0};
    rod.node_forces = {{edges, Vector3(0.0, 0.0, -F), {}}};
    model.rods.push_back(rod);
    return model;
  };
  SolverOptions options;
  options.tolerance = 1e-10;
  options.max_iterations = 200;
  Simulator statics(cantilever(true), options);
  for (int k = 0; k < 10; ++k) ASSERT_TRUE(statics.step().converged()) << "load step " << k;
  Simulator dynamics(cantilever(false), options);
  for (int k = 0; k < 600; ++k) ASSERT_TRUE(dynamics.step().state_updated());
  ASSERT_LT(dynamics.kinetic_energy(), 1e-16);
  const int tip = cantilever(true).rod_point(0, edges);
  // Both stop within the Newton tolerance (1e-10 m per DOF, per step) of the minimiser; the
  // dynamic run's residual motion (kinetic energy < 1e-16 J) is below 1e-8 m.
  EXPECT_LT((statics.state().points[tip] - dynamics.state().points[tip]).norm(), 1e-7);
  EXPECT_GT(-statics.state().points[tip].z(), 0.4);  // a large deflection indeed
}

TEST(RodStatics, UnanchoredPartsAreRejected) {
  Model model;
  model.static_equilibrium = true;
  model.rods.push_back(straight_rod(4, 1.0));
  try {
    model.validate();
    FAIL() << "accepted a free rod in static mode";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "rods[0].fixed_nodes");
  }
  model.rods[0].fixed_nodes = {0};
  RigidBody body;
  model.bodies.push_back(body);
  try {
    model.validate();
    FAIL() << "accepted a free body in static mode";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "bodies[0]");
  }
  SpringSpec anchor;
  anchor.b.body = 0;
  anchor.stiffness = 10.0;
  model.springs.push_back(anchor);
  EXPECT_NO_THROW(model.validate());
}

}  // namespace
}  // namespace liedyn

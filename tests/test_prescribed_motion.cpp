// Prescribed motion of clamped rod nodes and edges (lib/prescribed_motion.hpp): the keyframe
// path itself, its validation, and rods twisted and pulled by it against exact discrete
// equilibria, in static mode and in dynamics.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>
#include <numbers>

#include "lib/so3.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

TEST(PrescribedMotion, InterpolatesKeyframesLinearlyFromTheIdentityAndHolds) {
  PrescribedMotion m;
  m.keyframes = {{1.0, Vector3(0.0, 0.0, 2.0), Vector3(0.0, 0.0, 3.0 * std::numbers::pi)},
                 {3.0, Vector3(1.0, 0.0, 2.0), Vector3(0.0, 0.0, 3.0 * std::numbers::pi)}};
  EXPECT_EQ(m.duration(), 3.0);
  for (double t : {-1.0, 0.0}) {
    const RigidTransform T = m.at(t);
    EXPECT_EQ(T.translation, Vector3::Zero());
    EXPECT_EQ(T.rotation, Matrix3::Identity());
  }
  // Half way to the first keyframe: half the translation, half of a 3π twist (1.5π about z,
  // i.e. −π/2: the rotation vector interpolates, so multi-turn twists are expressible).
  const RigidTransform half = m.at(0.5);
  EXPECT_LT((half.translation - Vector3(0.0, 0.0, 1.0)).norm(), 1e-15);
  EXPECT_LT(so3::distance(half.rotation, so3::exp(Vector3(0.0, 0.0, -0.5 * std::numbers::pi))),
            1e-14);
  const RigidTransform second = m.at(2.0);
  EXPECT_LT((second.translation - Vector3(0.5, 0.0, 2.0)).norm(), 1e-15);
  const RigidTransform after = m.at(10.0);  // held
  EXPECT_LT((after.translation - Vector3(1.0, 0.0, 2.0)).norm(), 1e-15);
  EXPECT_LT(so3::distance(after.rotation, so3::exp(Vector3(0.0, 0.0, std::numbers::pi))), 1e-14);
  // Points turn about the pivot.
  m.center = Vector3(1.0, 0.0, 0.0);
  const RigidTransform quarter = {Vector3::Zero(),
                                  so3::exp(Vector3(0.0, 0.0, 0.5 * std::numbers::pi))};
  EXPECT_LT((m.move_point(quarter, Vector3(2.0, 0.0, 0.0)) - Vector3(1.0, 1.0, 0.0)).norm(),
            1e-15);
}

// A straight rod of `edges` edges along z from the origin to (0, 0, L), clamped at both
// ends (nodes 0 and n, edges 0 and n − 1); the top end (node n, edge n − 1) moved by one
// keyframe at t = 1. `bow` bends it sideways by x = bow · sin(π z/L), an imperfection.
Model clamped_rod(int edges, double L, const Vector3& translation, const Vector3& rotation,
                  double bow = 0.0) {
  Model model;
  RodSpec rod;
  rod.name = "rod";
  for (int i = 0; i <= edges; ++i) {
    rod.nodes.push_back(Vector3(bow * std::sin(std::numbers::pi * i / edges), 0.0, L * i / edges));
  }
  rod.mass = 0.2;
  rod.radius = 0.01;
  rod.stretch_stiffness = 1e3;
  rod.shear_stiffness = 1e3;
  rod.bending_stiffness = Vector3(2.0, 2.0, 1.0);
  rod.fixed_nodes = {0, edges};
  rod.fixed_edges = {0, edges - 1};
  PrescribedMotion top;
  top.nodes = {edges};
  top.edges = {edges - 1};
  top.center = rod.nodes.back();
  top.keyframes = {{1.0, translation, rotation}};
  rod.prescribed_motions = {top};
  model.rods.push_back(rod);
  return model;
}

// The twists α_j between consecutive edges when a rod of `edges` edges, clamped at both ends,
// is twisted by φ: each hinge's measure sin α/w_j gives it the moment K sin α cos α/w_j, the
// same along the rod, so sin 2α_j ∝ w_j, with w_j = l inside and 3l/2 at the two hinges next to
// the clamped end edges (lib/rod.hpp); Σ α_j = φ fixes the common moment (by bisection on the
// inner hinges' α).
std::vector<double> twist_shares(int edges, double phi) {
  const auto end_share = [](double inner) { return 0.5 * std::asin(1.5 * std::sin(2.0 * inner)); };
  double lo = 0.0, hi = phi / (edges - 1);  // Σ α at hi ≥ φ: the end shares exceed the inner
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (2.0 * end_share(mid) + (edges - 3) * mid < phi ? lo : hi) = mid;
  }
  std::vector<double> alpha(edges - 1, 0.5 * (lo + hi));
  alpha.front() = alpha.back() = end_share(alpha[1]);
  return alpha;
}

TEST(PrescribedMotion, StaticTwistOfOneAndAHalfTurnsSpreadsAlongTheRodByItsCells) {
  // Turning one clamped end by φ about the axis: by symmetry the equilibrium shares the twist
  // between the n − 1 edge-to-edge rotations, R_{j−1}ᵀ R_j = Rz(α_j) (twist_shares: evenly
  // inside, more at the two hinges next to the clamps, whose cells are longer), and the rod
  // stays straight. It is a minimum while each share is below π/4 (the discrete twist
  // measure is sin α / w) and φ is below Greenhill's buckling twist, 2.86π K_bend/K_twist =
  // 5.7π here. φ = 3π in 12 load steps, 40 edges: α = 0.24 rad inside, 0.37 rad at the ends.
  const int edges = 40;
  const double phi = 3.0 * std::numbers::pi;
  Model model = clamped_rod(edges, 1.0, Vector3::Zero(), Vector3(0.0, 0.0, phi));
  model.static_equilibrium = true;
  model.load_steps = 12;
  SolverOptions options;
  options.tolerance = 1e-11;
  Simulator sim(model, options);
  for (int k = 1; k <= model.load_steps; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << "load step " << k << ": " << to_string(r.status);
    // Every load step is an equilibrium with the twist so far: λ φ.
    const std::vector<double> alpha = twist_shares(edges, double(k) / model.load_steps * phi);
    for (int j = 1; j < edges; ++j) {
      const Matrix3 Q = sim.state().rotations[j - 1].transpose() * sim.state().rotations[j];
      EXPECT_LT((so3::log(Q) - Vector3(0.0, 0.0, alpha[j - 1])).norm(), 1e-8)
          << "load step " << k << ", edges " << j - 1 << "–" << j;
    }
  }
  for (int i = 0; i <= edges; ++i) {
    EXPECT_LT(sim.state().points[i].head<2>().norm(), 1e-9) << "node " << i << " left the axis";
  }
  // The moved edge carries the full twist.
  EXPECT_LT(so3::distance(sim.state().rotations[edges - 1],
                          so3::exp(Vector3(0.0, 0.0, phi)) * sim.state().rotations[0]),
            1e-12);
}

TEST(PrescribedMotion, StaticPullStretchesEveryEdgeEqually) {
  // Pulling the top end by ΔL along the axis: the stretch energy Σ ½ k_s l (1 − ‖e‖/l)² is
  // minimised with every edge at l (1 + ΔL/L), exactly (the rod stays straight).
  const int edges = 30;
  const double L = 0.6, dL = 0.05 * L;
  Model model = clamped_rod(edges, L, Vector3(0.0, 0.0, dL), Vector3::Zero());
  model.static_equilibrium = true;
  model.load_steps = 3;
  SolverOptions options;
  options.tolerance = 1e-12;
  Simulator sim(model, options);
  for (int k = 0; k < model.load_steps; ++k) ASSERT_TRUE(sim.step().converged());
  for (int i = 0; i <= edges; ++i) {
    EXPECT_LT((sim.state().points[i] - Vector3(0.0, 0.0, (L + dL) * i / edges)).norm(), 1e-12)
        << "node " << i;
  }
}

TEST(PrescribedMotion, DynamicEndFollowsThePathAndDrivesTheRod) {
  // The top end is pushed down by 0.3 m and twisted by π/2 over 1 s (h = 0.01 s). A 1 mm
  // bow: a perfectly straight rod under compression stays on the axially symmetric saddle,
  // where Newton (rightly) reports no convergence to a minimum.
  const int edges = 20;
  const Vector3 d(0.0, 0.0, -0.3), r(0.0, 0.0, 0.5 * std::numbers::pi);
  Model model = clamped_rod(edges, 1.0, d, r, 1e-3);
  model.time_step = 0.01;
  Simulator sim(model, SolverOptions{});
  const PrescribedMotion& motion = model.rods[0].prescribed_motions[0];
  const Vector3 top0 = sim.state().points[edges];
  const Matrix3 edge0 = sim.state().rotations[edges - 1];
  for (int k = 1; k <= 150; ++k) {
    const StepReport report = sim.step();
    ASSERT_TRUE(report.converged()) << "step " << k << ": " << to_string(report.status);
    const RigidTransform T = motion.at(k * model.time_step);
    EXPECT_LT((sim.state().points[edges] - motion.move_point(T, top0)).norm(), 1e-15);
    EXPECT_LT(so3::distance(sim.state().rotations[edges - 1], T.rotation * edge0), 1e-14);
    // The reported velocity of the moved node is the path's slope (d/1 s before t = 1 s).
    const Vector3 expected_velocity = k <= 100 ? d : Vector3::Zero();
    EXPECT_LT((sim.linear_velocity(edges) - expected_velocity).norm(), 1e-12) << "step " << k;
  }
  // Pushed 30 %, the clamped rod has buckled sideways: its middle left the axis.
  EXPECT_GT(sim.state().points[edges / 2].head<2>().norm(), 0.05);
}

TEST(PrescribedMotion, RejectsMotionsOfFreeOrTwiceMovedItemsAndBadKeyframes) {
  const auto error_of = [](const Model& model) -> std::string {
    try {
      model.validate();
    } catch (const ModelError& e) {
      return e.field() + ": " + e.what();
    }
    return "";
  };
  Model model = clamped_rod(10, 1.0, Vector3::Zero(), Vector3(0.0, 0.0, 1.0));
  EXPECT_EQ(error_of(model), "");
  {
    Model m = model;
    m.rods[0].prescribed_motions[0].nodes = {5};
    EXPECT_NE(error_of(m).find("rods[0].prescribed_motions[0].nodes[0]"), std::string::npos);
    EXPECT_NE(error_of(m).find("not in fixed_nodes"), std::string::npos);
  }
  {
    Model m = model;
    m.rods[0].prescribed_motions.push_back(m.rods[0].prescribed_motions[0]);
    EXPECT_NE(error_of(m).find("rods[0].prescribed_motions[1].nodes[0]"), std::string::npos);
    EXPECT_NE(error_of(m).find("moved twice"), std::string::npos);
  }
  {
    Model m = model;
    m.rods[0].prescribed_motions[0].edges = {11};
    EXPECT_NE(error_of(m).find("refers to edge 11"), std::string::npos);
  }
  {
    Model m = model;
    m.rods[0].prescribed_motions[0].keyframes.push_back({0.5, Vector3::Zero(), Vector3::Zero()});
    EXPECT_NE(error_of(m).find("keyframes[1].time"), std::string::npos);
  }
  {
    Model m = model;
    m.rods[0].prescribed_motions[0].keyframes[0].time = 0.0;
    EXPECT_NE(error_of(m).find("keyframes[0].time"), std::string::npos);
  }
  {
    Model m = model;  // 400 rad in 1 s at h = 0.01: 4 rad per step
    m.rods[0].prescribed_motions[0].keyframes[0].rotation = Vector3(0.0, 0.0, 400.0);
    EXPECT_NE(error_of(m).find("below π"), std::string::npos);
    m.static_equilibrium = true;  // load steps have no velocity: accepted
    EXPECT_EQ(error_of(m), "");
  }
  {
    Model m = model;
    m.rods[0].rest_nodes = {Vector3::Zero(), Vector3::UnitZ()};
    EXPECT_NE(error_of(m).find("rods[0].rest_nodes: has 2 nodes"), std::string::npos);
  }
}

TEST(RestShape, ARodStartsStraightWithTheRestCurvatureOfItsRestShape) {
  // The same helix as rest shape of a rod that starts straight, and as the initial shape of
  // another: equal rest lengths, masses and rest Darboux vectors; the straight one starts
  // with straight frames (ω = 0) and so is bent away from rest.
  RodSpec helix;
  const int edges = 24;
  for (int k = 0; k <= edges; ++k) {
    const double phi = 4.0 * std::numbers::pi * k / edges;
    helix.nodes.push_back(Vector3(0.1 * std::cos(phi), 0.1 * std::sin(phi), 0.02 * phi));
  }
  helix.mass = 0.3;
  helix.radius = 0.005;
  const double chord = (helix.nodes[1] - helix.nodes[0]).norm();
  RodSpec straightened = helix;
  straightened.rest_nodes = helix.nodes;
  for (int k = 0; k <= edges; ++k) straightened.nodes[k] = Vector3(0.0, 0.0, chord * k);
  const RodDiscretization a = discretize(helix), b = discretize(straightened);
  for (int j = 0; j < edges; ++j) EXPECT_NEAR(a.rest_length[j], b.rest_length[j], 1e-15);
  for (int i = 0; i <= edges; ++i) EXPECT_NEAR(a.node_mass[i], b.node_mass[i], 1e-15);
  for (std::size_t i = 0; i < a.rest_darboux.size(); ++i) {
    EXPECT_LT((a.rest_darboux[i] - b.rest_darboux[i]).norm(), 1e-12);
    EXPECT_GT(a.rest_darboux[i].norm(), 1.0);  // the helix is curved: κ = 8 1/m
    EXPECT_LT(darboux_vector(b.frames[i], b.frames[i + 1], b.bending_length[i]).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace liedyn

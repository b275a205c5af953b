// Rotation parameterisations in the Newton solver (solvers/newton.hpp, manifolds/):
//   * the assembled gradient and Hessian in the rotation-vector chart are the derivatives of
//     (x, r) ↦ Ψ(x, exp(r)), by central finite differences, on every linear system (dense
//     fixed, dense dynamic, banded, CHOLMOD, banded in parts), with ‖r‖ from 0 to near 2π;
//   * Lie, rotation vectors and quaternions reach the same converged steps.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "lib/so3.hpp"
#include "models.hpp"
#include "problems/scene.hpp"
#include "rod_models.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

// A body on a spring to a world anchor with a torque, spinning: every rigid-body term type.
Model loaded_body(const Vector3& orientation) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  RigidBody body;
  body.name = "body";
  body.mass = 2.0;
  body.inertia = Vector3(0.1, 0.2, 0.25).asDiagonal();
  body.orientation = so3::exp(orientation);
  body.angular_velocity = Vector3(1.0, 4.0, -2.0);
  model.bodies.push_back(body);
  SpringSpec spring;
  spring.a = BodyPoint{-1, Vector3(0.0, 0.0, 0.5)};
  spring.b = BodyPoint{0, Vector3(0.1, 0.05, 0.2)};
  spring.stiffness = 300.0;
  spring.rest_length = 0.3;
  model.springs.push_back(spring);
  TorqueSpec torque;
  torque.body = 0;
  torque.torque = Vector3(0.3, -0.1, 0.2);
  model.torques.push_back(torque);
  return model;
}

// A clamped, curved rod under gravity.
Model curved_rod(int edges) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  RodSpec rod = test_models::uniform_rod(edges, 1.0, 0.2, 0.01, 1e4, 1e4, 0.05);
  for (std::size_t i = 0; i < rod.nodes.size(); ++i) rod.nodes[i].z() = 0.1 * std::sin(0.5 * i);
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  model.rods.push_back(rod);
  return model;
}

// Rotation vectors for the FD checks: magnitudes from 0 to near 2π, several axes.
Vector3 test_rotation_vector(std::size_t i) {
  const double magnitudes[] = {0.0, 1e-9, 1e-4, 1.0, std::numbers::pi - 1e-6, std::numbers::pi,
                               2.0 * std::numbers::pi - 0.3};
  const Vector3 axis = Vector3(1.0 + 0.3 * i, -0.7, 0.2 * double(i % 3) + 0.1).normalized();
  return magnitudes[i % 7] * axis;
}

// Checks the charted assembly of `System` on the first component of `model` against central
// differences of Ψ in (x, r) (gradient) and of the charted gradient (Hessian).
// The first component of `model` at the start of its first step, its positions moved on by
// two steps (so that no term sits at its minimum).
struct StartedComponent {
  Component c;
  State q;
  explicit StartedComponent(const Model& model)
      : c(std::move(build_components(model).front())), q(model.initial_state()) {
    const Step dq = model.initial_step();
    c.potential.begin_step(q, dq);
    for (std::size_t i = 0; i < q.points.size(); ++i) q.points[i] += 2.0 * dq.points[i];
  }
};

template <class System, class... SystemArgs>
void expect_charted_derivatives(const Model& model, SystemArgs... args) {
  StartedComponent started(model);
  Component& c = started.c;
  State& q = started.q;
  RotationVectorChart chart(c);
  std::vector<Vector3> r(c.rotations.size());
  for (std::size_t i = 0; i < c.rotations.size(); ++i) {
    r[i] = test_rotation_vector(i);
    q.rotations[c.rotations[i].index] = chart.set(i, r[i]);
  }
  System system(c, args...);
  system.assemble(c.potential, q, nullptr, &chart);
  const Eigen::VectorXd g = system.gradient();
  Eigen::MatrixXd H;
  system.dense_hessian(H);

  // Moves DOF `dof` by `h`: a position coordinate, or a rotation-vector coordinate.
  auto moved = [&](int dof, double h) {
    State p = q;
    for (const DofBlock& b : c.points) {
      if (dof / 3 == b.offset / 3) p.points[b.index][dof % 3] += h;
    }
    for (std::size_t i = 0; i < c.rotations.size(); ++i) {
      const DofBlock& b = c.rotations[i];
      Vector3 ri = r[i];
      if (dof / 3 == b.offset / 3) ri[dof % 3] += h;
      p.rotations[b.index] = chart.set(i, ri);
    }
    return p;
  };
  const double h = 1e-6;
  const double g_scale = g.cwiseAbs().maxCoeff();
  const double H_scale = H.cwiseAbs().maxCoeff();
  for (int k = 0; k < c.dofs; ++k) {
    const double fd = (c.potential.value(moved(k, h)) - c.potential.value(moved(k, -h))) / (2 * h);
    // Ψ's round-off (≈ 1e-16 |Ψ|/h) dominates the FD error of a 1e-6 step.
    EXPECT_NEAR(g[k], fd, 1e-6 * g_scale) << "gradient entry " << k;
    System plus(c, args...), minus(c, args...);
    plus.assemble(c.potential, moved(k, h), nullptr, &chart);
    minus.assemble(c.potential, moved(k, -h), nullptr, &chart);
    const Eigen::VectorXd column = (plus.gradient() - minus.gradient()) / (2 * h);
    for (int i = 0; i < c.dofs; ++i) {
      EXPECT_NEAR(H(i, k), column[i], 1e-6 * H_scale) << "Hessian entry " << i << ", " << k;
    }
  }
  for (std::size_t i = 0; i < c.rotations.size(); ++i) chart.set(i, r[i]);
}

TEST(RotationVectorChart, DenseFixedSystemHasTheDerivativesOfPsiOfExpR) {
  expect_charted_derivatives<DenseSystem<6>>(loaded_body(Vector3(0.3, -2.0, 1.0)));
}

TEST(RotationVectorChart, DenseDynamicSystemHasTheDerivativesOfPsiOfExpR) {
  expect_charted_derivatives<DenseSystem<Eigen::Dynamic>>(test_models::spring_chain(3));
}

TEST(RotationVectorChart, SparseSystemsHaveTheDerivativesOfPsiOfExpR) {
  const Model rod = curved_rod(8);
  expect_charted_derivatives<SparseSystem>(rod, SparseSystem::Factorization::kBanded, 1);
  expect_charted_derivatives<SparseSystem>(rod, SparseSystem::Factorization::kCholmod, 1);
  expect_charted_derivatives<SparseSystem>(rod, SparseSystem::Factorization::kBanded, 2);
}

// The paper's own rotation-vector gradient of the inertial potential (appendix B, eq. 37),
// written out independently of the chart: Ψ_R = −tr(exp(r) M), M = J R̃ᵀ/h², split as
// M = S + A (symmetric, antisymmetric), a = vee(A) (the paper's skew⁻¹), K = tr(S) I − S:
//   ∂Ψ_R/∂r = 2 (aᵀr) σ'(t) r/t + 2 σ(t) a + ½ (rᵀK r) σ(t/2) σ'(t/2) r/t + σ²(t/2) K r.
// The chart's J_l(r)ᵀ g of the RotationalInertia term must equal it.
TEST(RotationVectorChart, InertialGradientMatchesThePapersAppendixB) {
  RotationalInertia term;
  term.offsets = {0};
  term.rotation = 0;
  term.J_over_h2 = Eigen::Vector3d(0.2, 0.3, 0.45).asDiagonal();
  term.J_over_h2 *= 1e4;
  term.R_tilde = so3::exp(Vector3(0.4, -1.1, 0.7));
  const Matrix3 M = term.J_over_h2 * term.R_tilde.transpose();
  const Matrix3 S = 0.5 * (M + M.transpose());
  const Vector3 a = so3::vee(M);  // vee of the antisymmetric part
  const Matrix3 K = S.trace() * Matrix3::Identity() - S;
  auto sigma = [](double t) { return std::sin(t) / t; };
  auto sigma_prime = [](double t) { return (t * std::cos(t) - std::sin(t)) / (t * t); };
  for (const double angle : {0.3, 1.0, 2.0, std::numbers::pi - 1e-6, 4.0, 5.5}) {
    const Vector3 r = angle * Vector3(0.2, -0.5, 0.84).normalized();
    const double t = r.norm();
    const Vector3 paper = 2.0 * a.dot(r) * sigma_prime(t) * r / t + 2.0 * sigma(t) * a +
                          0.5 * r.dot(K * r) * sigma(t / 2) * sigma_prime(t / 2) * r / t +
                          sigma(t / 2) * sigma(t / 2) * (K * r);
    State q;
    Matrix3 J_l;
    q.rotations = {so3::exp(r, &J_l)};
    LocalGradient<1> g;
    term.evaluate(q, &g, nullptr);
    const Vector3 chart = J_l.transpose() * g;
    EXPECT_LT((chart - paper).norm(), 1e-12 * paper.norm()) << "angle " << angle;
  }
}

// Quaternions: the Lie gradient and Hessian the systems assemble are the derivatives of
// δ ↦ Ψ(x, R(retract(q, δ))) at δ = 0 (manifolds/quaternion.hpp), for every term type.
void expect_quaternion_derivatives(const Model& model) {
  StartedComponent started(model);
  Component& c = started.c;
  State& q = started.q;
  std::vector<quat::Vector4> quaternions(c.rotations.size());
  for (std::size_t i = 0; i < c.rotations.size(); ++i) {
    // ±q alternately: both signs must give the same derivatives.
    quaternions[i] = (i % 2 == 0 ? 1.0 : -1.0) *
                     quat::from_rotation(so3::exp(test_rotation_vector(i)));
    q.rotations[c.rotations[i].index] = quat::rotation(quaternions[i]);
  }
  DenseSystem<Eigen::Dynamic> system(c);
  system.assemble(c.potential, q, nullptr);
  Eigen::MatrixXd H;
  system.dense_hessian(H);
  auto value = [&](const Eigen::VectorXd& delta) {
    State p = q;
    for (const DofBlock& b : c.points) p.points[b.index] += delta.segment<3>(b.offset);
    for (std::size_t i = 0; i < c.rotations.size(); ++i) {
      const DofBlock& b = c.rotations[i];
      p.rotations[b.index] =
          quat::rotation(quat::retract(quaternions[i], delta.segment<3>(b.offset)));
    }
    return c.potential.value(p);
  };
  const double h = 1e-4;  // second differences: error O(h²) against round-off O(ε Ψ/h²)
  const double g_scale = system.gradient().cwiseAbs().maxCoeff();
  const double H_scale = H.cwiseAbs().maxCoeff();
  for (int k = 0; k < c.dofs; ++k) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(c.dofs);
    e[k] = h;
    EXPECT_NEAR(system.gradient()[k], (value(e) - value(-e)) / (2 * h), 1e-6 * g_scale) << k;
    for (int l = 0; l <= k; ++l) {
      Eigen::VectorXd f = Eigen::VectorXd::Zero(c.dofs);
      f[l] = h;
      const double fd = (value(e + f) - value(e - f) - value(f - e) + value(-e - f)) / (4 * h * h);
      EXPECT_NEAR(H(k, l), fd, 1e-5 * H_scale) << k << ", " << l;
    }
  }
}

TEST(Parameterizations, QuaternionDerivativesAreTheLieOnesForEveryTerm) {
  expect_quaternion_derivatives(loaded_body(Vector3(0.3, -2.0, 1.0)));
  expect_quaternion_derivatives(test_models::spring_chain(3));
  expect_quaternion_derivatives(curved_rod(6));
}

// Steps of `model` under `rotation` and under Lie, both to a tight tolerance: the minimiser
// of each step is the same point whatever the coordinates, but each converged step stops
// within `tolerance` of it (the last Newton step, ‖δ‖ ≤ tolerance, is not taken), and the
// dynamics amplify those differences from step to step. Measured: the deviation scales with
// the tolerance (rotation vectors at a rotation by π, 300 steps: 2.8e-6, 1.7e-7, 4.2e-9 rad
// for tolerances 1e-9, 1e-11, 1e-13), so a bug, which would not, cannot hide below `bound`.
void expect_same_trajectory(const Model& model, RotationParameterization rotation, int steps,
                            double tolerance = 1e-11, double bound = 1e-8) {
  SolverOptions lie_options;
  lie_options.tolerance = tolerance;
  SolverOptions options = lie_options;
  options.rotation = rotation;
  Simulator lie(model, lie_options), other(model, options);
  double position = 0.0, angle = 0.0;
  for (int k = 0; k < steps; ++k) {
    ASSERT_TRUE(lie.step().converged());
    const StepReport report = other.step();
    ASSERT_TRUE(report.converged()) << "step " << k << ": " << to_string(report.status);
    for (std::size_t i = 0; i < lie.state().points.size(); ++i) {
      position = std::max(position, (lie.state().points[i] - other.state().points[i]).norm());
    }
    for (std::size_t i = 0; i < lie.state().rotations.size(); ++i) {
      angle = std::max(angle, so3::distance(lie.state().rotations[i], other.state().rotations[i]));
      // Orthonormal without re-orthonormalisation: exp(r) and R(q) are rotations.
      const Matrix3& R = other.state().rotations[i];
      EXPECT_LT((R.transpose() * R - Matrix3::Identity()).norm(), 1e-14);
    }
  }
  EXPECT_LT(position, bound);
  EXPECT_LT(angle, bound);
}

TEST(Parameterizations, RotationVectorsAndQuaternionsFollowTheLieTrajectory) {
  for (const auto rotation :
       {RotationParameterization::kRotationVector, RotationParameterization::kQuaternion}) {
    SCOPED_TRACE(to_string(rotation));
    expect_same_trajectory(loaded_body(Vector3(0.3, -2.0, 1.0)), rotation, 200);
    expect_same_trajectory(test_models::spring_chain(3), rotation, 100);
    expect_same_trajectory(curved_rod(20), rotation, 50);
  }
}

// A body starting at a rotation by π − 1e-6 and spinning: its rotation vector passes π and is
// re-wrapped between steps (r = log R at the start of each solve), and the quaternion's sign
// flips; the trajectory must not notice.
TEST(Parameterizations, RotationsThroughPiFollowTheLieTrajectory) {
  for (const auto rotation :
       {RotationParameterization::kRotationVector, RotationParameterization::kQuaternion}) {
    SCOPED_TRACE(to_string(rotation));
    expect_same_trajectory(loaded_body((std::numbers::pi - 1e-6) * Vector3(0.0, 0.6, 0.8)),
                           rotation, 300, 1e-13, 1e-7);
    expect_same_trajectory(loaded_body(std::numbers::pi * Vector3(1.0, 0.0, 0.0)), rotation, 300,
                           1e-13, 1e-7);
  }
}

// Every bundled scene (bodies, rods, static load steps, prescribed motions) runs under each
// parameterisation, its first 40 frames converged and within 1e-6 (m, rad) of the Lie run:
// the scenes' tolerances are 1e-9 or tighter, and 40 frames give little room for amplification.
TEST(Parameterizations, EveryBundledSceneRunsUnderEachParameterisation) {
  const std::filesystem::path scenes = std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes";
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(scenes)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().filename().string());
    const Scene scene = load_scene(entry.path());
    const int frames = std::min(scene.frames, 40);
    Simulator lie(scene.model, scene.solver);
    std::vector<Simulator> others;
    for (const auto rotation :
         {RotationParameterization::kRotationVector, RotationParameterization::kQuaternion}) {
      SolverOptions options = scene.solver;
      options.rotation = rotation;
      others.emplace_back(scene.model, options);
    }
    double deviation = 0.0;
    for (int k = 0; k < frames; ++k) {
      ASSERT_TRUE(lie.step().converged());
      for (Simulator& other : others) {
        ASSERT_TRUE(other.step().converged()) << "frame " << k + 1;
        for (std::size_t i = 0; i < lie.state().points.size(); ++i) {
          deviation = std::max(
              deviation, (lie.state().points[i] - other.state().points[i]).cwiseAbs().maxCoeff());
        }
        for (std::size_t i = 0; i < lie.state().rotations.size(); ++i) {
          deviation = std::max(
              deviation, so3::distance(lie.state().rotations[i], other.state().rotations[i]));
        }
      }
    }
    EXPECT_LT(deviation, 1e-6);
    ++count;
  }
  EXPECT_GE(count, 10);
}

}  // namespace
}  // namespace liedyn

// End-to-end checks of the adjoint gradient (solvers/adjoint.hpp) against central finite
// differences of the loss, for every parameter kind (lib/parameters.hpp) and objective term
// (lib/objective.hpp), under the three rotation parameterisations, a loose and a tight
// forward tolerance and the three time integrators (the trapezoidal rule's history blocks and
// skew solve, docs/design.md §14.1; BDF2's three-state history and start, §15.1); and the measured dependence of the gradient error on the
// tolerance.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

#include "lib/so3.hpp"
#include "lib/stability.hpp"
#include "models.hpp"
#include "rod_models.hpp"
#include "solvers/gradient_check.hpp"

namespace liedyn::adjoint_tests {
namespace {

// A thrown box (the die of paper Fig. 8, without contact): gravity, 30 frames.
Model thrown_box() {
  Model m;
  m.time_step = 0.01;
  m.gravity = Vector3(0.0, 0.0, -9.81);
  RigidBody b;
  b.mass = 0.02;
  b.inertia = Vector3(0.5e-5, 0.7e-5, 0.9e-5).asDiagonal();
  b.position = Vector3(0.0, 0.0, 0.3);
  b.orientation = so3::exp(Vector3(0.3, -0.2, 0.5));
  b.linear_velocity = Vector3(0.5, 0.1, 2.0);
  b.angular_velocity = Vector3(4.0, -7.0, 10.0);
  m.bodies.push_back(b);
  return m;
}

// A free 7-node rod with initial node velocities, no gravity.
Model moving_rod() {
  Model m;
  m.time_step = 0.01;
  RodSpec rod = test_models::uniform_rod(6, 0.6, 0.3, 0.01, 4e2, 1e2, 0.5);
  rod.node_velocities.assign(7, Vector3(0.0, 0.1, 0.05));
  rod.node_velocities[3] = Vector3(0.0, 0.6, -0.2);
  m.rods.push_back(rod);
  return m;
}

// Its nodes against a curved target shape at the last frame.
Objective rod_targets(const Model& m) {
  std::vector<int> points;
  std::vector<Vector3> targets;
  for (int i = 0; i < 7; ++i) {
    points.push_back(m.rod_point(0, i));
    targets.push_back(Vector3(0.1 * i, 0.05 * std::sin(i), 0.02 * i * i));
  }
  Objective g;
  g.add(std::make_shared<PointTargets>(points, targets, -1, 1.0));
  return g;
}

SolverOptions options_for(RotationParameterization rotation, double tolerance) {
  SolverOptions o = test_models::newton(tolerance);
  o.rotation = rotation;
  return o;
}

struct Case {
  RotationParameterization rotation;
  double tolerance;
  Integrator integrator = Integrator::kBackwardEuler;
};

// The adjoint gradient at the forward tolerance under test against central differences of
// the loss at a tight tolerance (1e-12: the reference gradient; FD of a loosely converged
// loss would measure the solver's noise, not the gradient).
double adjoint_error(const DifferentiableSimulation& adjoint,
                     const DifferentiableSimulation& reference, std::string* worst_name) {
  GradientCheckOptions o;
  o.step = 1e-5;
  const Eigen::VectorXd gamma = adjoint.initial_parameters();
  const GradientCheckResult fd = check_gradient(reference, gamma, o);
  Eigen::VectorXd g;
  adjoint.evaluate(gamma, &g);
  double largest = 0.0;
  for (const auto& e : fd.entries) largest = std::max(largest, std::abs(e.finite_difference));
  EXPECT_GT(largest, 1e-6 * std::abs(fd.loss)) << "the gradient is negligible: the check means nothing";
  double worst = 0.0;
  for (const auto& e : fd.entries) {
    const double d = std::abs(g(e.index) - e.finite_difference) /
                     std::max({std::abs(g(e.index)), std::abs(e.finite_difference), o.floor * largest});
    if (d >= worst) {
      worst = d;
      if (worst_name != nullptr) {
        std::ostringstream os;
        os << adjoint.parameters().describe(adjoint.base_model(), e.index) << ": adjoint "
           << g(e.index) << " FD " << e.finite_difference;
        *worst_name = os.str();
      }
    }
  }
  return worst;
}

void PrintTo(const Case& c, std::ostream* os) {
  *os << to_string(c.rotation) << ", tolerance " << c.tolerance << ", " << to_string(c.integrator);
}

class AdjointGradient : public ::testing::TestWithParam<Case> {
 protected:
  void expect_matches(Model m, const ParameterSet& p, const Objective& g) {
    m.integrator = GetParam().integrator;
    if (m.integrator == Integrator::kFoxGoodwin) {
      // It runs only below its stable step (lib/stability.hpp), which the rods' stretch puts
      // below their h here: they take 0.8 of it (a shorter horizon, the same terms). (ωh)²
      // scales with h².
      double s = 0.0;
      for (const Component& c : build_components(m)) s = std::max(s, largest_mode_step_squared(c, m.initial_state()));
      m.time_step = std::min(m.time_step, 0.8 * m.time_step * std::sqrt(6.0 / s));
    }
    const DifferentiableSimulation sim(m, p, g, options());
    const DifferentiableSimulation reference(
        m, p, g, options_for(RotationParameterization::kLie, 1e-12));
    std::string worst;
    const double error = adjoint_error(sim, reference, &worst);
    EXPECT_LE(error, expected()) << worst;
  }
  SolverOptions options() const { return options_for(GetParam().rotation, GetParam().tolerance); }
  // Tight: the resolution of the differences (step 1e-5: truncation ~1e-10 relative, noise of
  // the 1e-12-converged loss ~1e-7), with margin. Loose (1e-6): the adjoint is exact only at
  // converged steps, and AdjointAccuracy.ErrorFollowsTheNewtonTolerance measures how far off
  // it is: 1e-6 gives ~4e-4 on a rod.
  double expected() const { return GetParam().tolerance <= 1e-10 ? 1e-5 : 1e-2; }
};

TEST_P(AdjointGradient, ThrownBodyInitialConditionsAndPose) {
  const Model m = thrown_box();
  ParameterSet p(30);
  p.add(m, ParameterKind::kBodyLinearVelocity, 0, -1, "p[0]");
  p.add(m, ParameterKind::kBodyAngularVelocity, 0, -1, "p[1]");
  p.add(m, ParameterKind::kBodyPosition, 0, -1, "p[2]");
  p.add(m, ParameterKind::kBodyOrientation, 0, -1, "p[3]");
  Objective g;
  g.add(std::make_shared<BodyPose>(0, -1, Vector3(0.4, 0.0, 0.1), Vector3(0.0, 0.0, 1.0),
                                   so3::exp(Vector3(0.0, 1.0, 0.0)), 1.0));
  std::vector<Eigen::Vector2d> curve;
  for (int k = 1; k <= 30; ++k) curve.emplace_back(0.01 * k, 0.3 + 0.005 * k);
  Eigen::Matrix<double, 2, 3> xz;
  xz << 1, 0, 0, 0, 0, 1;
  g.add(std::make_shared<ProjectedTrajectory>(0, xz, curve, 0.5));
  expect_matches(m, p, g);
}

TEST_P(AdjointGradient, SpringChainForcesTorquesAndStiffness) {
  Model m = test_models::spring_chain(2);
  m.forces.push_back({BodyPoint{1, Vector3(0.05, 0.02, 0.0)}, Vector3(0.2, 0.0, 0.5), {}});
  m.torques.push_back({0, Vector3(0.01, -0.02, 0.03), {}});
  ParameterSet p(15);
  p.add(m, ParameterKind::kForce, 0, -1, "p[0]");
  p.add(m, ParameterKind::kTorque, 0, -1, "p[1]");
  p.add(m, ParameterKind::kSpringStiffness, 1, -1, "p[2]");
  const int tensions = p.size();
  Objective g;
  g.add(std::make_shared<BodyPose>(1, -1, Vector3(0.3, 0.1, -0.1), Vector3(1.0, 1.0, 1.0),
                                   so3::exp(Vector3(0.2, 0.0, 0.0)), 0.1));
  g.add(std::make_shared<Effort>(0, tensions - 1, 1e-3));
  expect_matches(m, p, g);
}

// A free rod whose initial node velocities, rest shape and stiffnesses are parameters, against
// a target shape (the letters of paper Fig. 1 in miniature).
TEST_P(AdjointGradient, RodNodeVelocitiesRestShapeAndStiffness) {
  const Model m = moving_rod();
  ParameterSet p(12);
  p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "p[0]");
  p.add(m, ParameterKind::kRestDarboux, 0, -1, "p[1]");
  p.add(m, ParameterKind::kStretchStiffness, 0, -1, "p[2]");
  p.add(m, ParameterKind::kShearStiffness, 0, -1, "p[3]");
  p.add(m, ParameterKind::kBendingStiffness, 0, -1, "p[4]");
  const Objective g = rod_targets(m);
  expect_matches(m, p, g);
}

// A cantilever steered by per-frame node forces and per-frame rest Darboux vectors, its tip
// against a curve under orthographic projection (paper Fig. 10, 11 in miniature).
TEST_P(AdjointGradient, CantileverPerFrameControls) {
  Model m;
  m.time_step = 0.01;
  m.gravity = Vector3(0.0, 0.0, -9.81);
  RodSpec rod = test_models::uniform_rod(5, 0.5, 0.15, 0.01, 5e2, 50, 1.0);
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  rod.node_forces.push_back({5, Vector3(0.0, 0.05, 0.0), {}});
  m.rods.push_back(rod);
  const int frames = 10;
  ParameterSet p(frames);
  p.add(m, ParameterKind::kNodeForce, 0, 0, "p[0]");
  p.add(m, ParameterKind::kRestDarbouxPerFrame, 0, -1, "p[1]");
  std::vector<Eigen::Vector2d> curve;
  for (int k = 1; k <= frames; ++k) curve.emplace_back(0.5 - 0.002 * k, 0.01 * k);
  Eigen::Matrix<double, 2, 3> xy;
  xy << 1, 0, 0, 0, 1, 0;
  Objective g;
  g.add(std::make_shared<ProjectedTrajectory>(m.rod_point(0, 5), xy, curve, 10.0));
  g.add(std::make_shared<Effort>(0, 3 * frames, 1e-2));
  expect_matches(m, p, g);
}

// How the adjoint's error depends on the forward Newton tolerance (docs/design.md §8.5): the rod of
// RodNodeVelocitiesRestShapeAndStiffness, tolerances 1e-4 … 1e-12 against the tight reference.
// Measured (Release): 1e-4 → 8.9e-3, 1e-6 → 3.8e-4, 1e-8 … 1e-12 → 4.9e-8 (the resolution of
// the differences; see the README); asserted: the error falls by at least 100× from 1e-4 to
// 1e-12 and ends below 1e-5.
TEST(AdjointAccuracy, ErrorFollowsTheNewtonTolerance) {
  const Model m = moving_rod();
  ParameterSet p(12);
  p.add(m, ParameterKind::kRodNodeVelocities, 0, -1, "p[0]");
  const Objective g = rod_targets(m);
  const DifferentiableSimulation reference(m, p, g, options_for(RotationParameterization::kLie, 1e-12));
  std::vector<double> errors;
  for (double tolerance : {1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
    const DifferentiableSimulation sim(m, p, g, options_for(RotationParameterization::kLie, tolerance));
    errors.push_back(adjoint_error(sim, reference, nullptr));
    std::cout << "[ measured ] Newton tolerance " << tolerance << ": adjoint relative error "
              << errors.back() << "\n";
  }
  EXPECT_GT(errors.front(), 100.0 * errors.back());
  EXPECT_LT(errors.back(), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(
    Parameterizations, AdjointGradient,
    ::testing::Values(Case{RotationParameterization::kLie, 1e-12},
                      Case{RotationParameterization::kLie, 1e-6},
                      Case{RotationParameterization::kRotationVector, 1e-12},
                      Case{RotationParameterization::kQuaternion, 1e-12},
                      Case{RotationParameterization::kLie, 1e-12, Integrator::kTrapezoidal},
                      Case{RotationParameterization::kLie, 1e-6, Integrator::kTrapezoidal},
                      Case{RotationParameterization::kRotationVector, 1e-12,
                           Integrator::kTrapezoidal},
                      Case{RotationParameterization::kQuaternion, 1e-12,
                           Integrator::kTrapezoidal},
                      Case{RotationParameterization::kLie, 1e-12, Integrator::kFoxGoodwin},
                      Case{RotationParameterization::kLie, 1e-6, Integrator::kFoxGoodwin},
                      Case{RotationParameterization::kLie, 1e-12, Integrator::kBdf2},
                      Case{RotationParameterization::kLie, 1e-6, Integrator::kBdf2},
                      Case{RotationParameterization::kRotationVector, 1e-12, Integrator::kBdf2},
                      Case{RotationParameterization::kQuaternion, 1e-12, Integrator::kBdf2}),
    [](const auto& info) {
      return std::string(to_string(info.param.rotation)) +
             (info.param.tolerance <= 1e-10 ? "_tight" : "_loose") +
             (info.param.integrator == Integrator::kBackwardEuler
                  ? std::string()
                  : "_" + std::string(to_string(info.param.integrator)));
    });

}  // namespace
}  // namespace liedyn::adjoint_tests

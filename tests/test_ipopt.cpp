// The Ipopt back-end (solvers/ipopt_step.hpp): exact charted derivatives by Ipopt's own
// derivative checker, the same converged steps as Newton (exact and limited-memory Hessians,
// tangent increments and global rotation vectors), a whole trajectory through the simulator,
// and failures reported without moving the state.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "lib/so3.hpp"
#include "models.hpp"
#include "rod_models.hpp"
#include "solvers/ipopt_step.hpp"
#include "solvers/newton.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::ipopt_tests {
namespace {

// A free asymmetric body tumbling about all three axes, oriented far from the identity (so
// that its global rotation vector is large: ‖r‖ ≈ 2.3), drifting; no loads.
Model free_body() {
  Model model;
  model.time_step = 0.01;
  RigidBody body;
  body.name = "tumbler";
  body.mass = 2.0;
  body.inertia = Vector3(0.1, 0.2, 0.25).asDiagonal();
  body.position = Vector3(0.3, -0.2, 0.5);
  body.orientation = so3::exp(Vector3(0.3, -2.0, 1.0));
  body.linear_velocity = Vector3(0.5, 0.2, -0.1);
  body.angular_velocity = Vector3(3.0, 8.0, -5.0);
  model.bodies.push_back(body);
  return model;
}

// Two spinning links under gravity, hung from a world anchor and joined by a spring.
Model spring_pair() { return test_models::spring_chain(2); }

// A curved rod clamped at one end (node 0, edge 0) under gravity: 6 free nodes and 5 free
// edges, 33 DOFs (Newton's check runs on the sparse, banded system).
Model small_rod() {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  RodSpec rod = test_models::uniform_rod(6, 1.0, 0.2, 0.01, 1e4, 1e4, 0.05);
  for (std::size_t i = 0; i < rod.nodes.size(); ++i) rod.nodes[i].z() = 0.1 * std::sin(0.5 * i);
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  model.rods.push_back(rod);
  return model;
}

// Four links under gravity, all oriented far from the identity, joined by exact joints of
// every equality type: link 0 hinged to the world (point + axis alignment), link 1 on a ball
// joint to it, link 2 welded to link 1, link 3 on a slider along link 2's x axis (line +
// weld). Each link has its own initial velocity, so the predicted start of the step violates
// every joint (Ipopt starts infeasible).
Model jointed_links() {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  const Matrix3 R0 = so3::exp(Vector3(0.3, -2.0, 1.0));
  for (int i = 0; i < 4; ++i) {
    RigidBody body;
    body.name = "link" + std::to_string(i);
    body.mass = 0.5;
    body.inertia = Vector3(0.01, 0.02, 0.025).asDiagonal();
    body.position = Vector3(0.25 + 0.5 * i, 0.0, 0.0);
    body.orientation = R0;
    body.linear_velocity = Vector3(0.1 * i, 0.3, -0.2);
    body.angular_velocity = Vector3(1.0, -2.0, 0.5) * (0.5 + 0.3 * i);
    model.bodies.push_back(body);
  }
  // The joint between links i − 1 (b; the world for i = 0) and i (a) at world x = 0.5 i.
  const auto joint = [&](JointSpec::Type type, int i) {
    JointSpec j;
    j.type = type;
    const Vector3 w(0.5 * i, 0.0, 0.0);
    j.a = JointEnd::body(i, R0.transpose() * (w - model.bodies[i].position));
    j.b = i == 0 ? JointEnd::world(w)
                 : JointEnd::body(i - 1, R0.transpose() * (w - model.bodies[i - 1].position));
    return j;
  };
  JointSpec hinge = joint(JointSpec::Type::kHinge, 0);
  hinge.axis_a = R0.transpose() * Vector3::UnitY();
  hinge.axis_b = Vector3::UnitY();
  model.joints.push_back(hinge);
  model.joints.push_back(joint(JointSpec::Type::kBall, 1));
  model.joints.push_back(joint(JointSpec::Type::kWeld, 2));
  JointSpec slider = joint(JointSpec::Type::kSlider, 3);
  slider.axis_a = R0.transpose() * Vector3::UnitX();
  model.joints.push_back(slider);
  return model;
}

struct NamedModel {
  const char* name;
  Model (*make)();
};
constexpr NamedModel kModels[] = {
    {"free body", free_body}, {"spring pair", spring_pair}, {"small rod", small_rod}};
constexpr RotationParameterization kRotations[] = {RotationParameterization::kLie,
                                                   RotationParameterization::kRotationVector,
                                                   RotationParameterization::kQuaternion};

// The single component of `model` at its first step (begin_step done), and the state to
// start from: the simulator's prediction q_0 ⊕ Δq_0, or (perturbed) positions moved on by a
// further 0.5 Δq_0 and rotations turned by a further 0.05 rad, so that no term sits at its
// minimum where the derivatives are checked.
struct Started {
  Component component;
  State q;
};
Started started(const Model& model, bool perturbed) {
  std::vector<Component> components = build_components(model);
  EXPECT_EQ(components.size(), 1u);
  Started s{std::move(components.front()), model.initial_state()};
  const Step dq = model.initial_step();
  s.component.potential.begin_step(s.q, dq);
  const double extra = perturbed ? 1.5 : 1.0;
  for (std::size_t i = 0; i < s.q.points.size(); ++i) s.q.points[i] += extra * dq.points[i];
  for (std::size_t i = 0; i < s.q.rotations.size(); ++i) {
    Matrix3 R = dq.rotations[i] * s.q.rotations[i];
    if (perturbed) R = so3::exp(0.05 * Vector3(1.0, -0.5, 0.3 * double(i % 3)).normalized()) * R;
    s.q.rotations[i] = so3::orthonormalize(R);
  }
  return s;
}

SolverOptions ipopt_options(RotationParameterization rotation, double tolerance = 1e-10) {
  SolverOptions options;
  options.backend = Backend::kIpopt;
  options.rotation = rotation;
  options.tolerance = tolerance;
  options.validate();
  return options;
}

// Largest difference between the components' DOFs of two states: metres and radians.
double max_difference(const Component& c, const State& a, const State& b) {
  double d = 0.0;
  for (const DofBlock& p : c.points) {
    d = std::max(d, (a.points[p.index] - b.points[p.index]).cwiseAbs().maxCoeff());
  }
  for (const DofBlock& r : c.rotations) {
    d = std::max(d, so3::distance(a.rotations[r.index], b.rotations[r.index]));
  }
  return d;
}

// A fresh directory for Ipopt's output files, removed with the object.
struct TemporaryDirectory {
  std::filesystem::path path;
  TemporaryDirectory() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path = std::filesystem::temp_directory_path() /
           ("liedyn_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TemporaryDirectory() { std::filesystem::remove_all(path); }
};

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(IpoptStep, DerivativeCheckerFindsNoErrors) {
  const TemporaryDirectory dir;
  for (const NamedModel& m : kModels) {
    for (const RotationParameterization rotation : kRotations) {
      SCOPED_TRACE(std::string(m.name) + ", " + to_string(rotation));
      const std::filesystem::path log =
          dir.path / (std::string(m.name) + "_" + to_string(rotation) + ".txt");
      SolverOptions options = ipopt_options(rotation);
      options.ipopt.derivative_test = "second-order";
      options.ipopt.output_file = log.string();
      Started s = started(m.make(), /*perturbed=*/true);
      StepReport report;
      {
        auto solver = make_ipopt_step_solver(std::move(s.component), options);
        report = solver->solve(s.q);
      }  // the solver closes its output file
      EXPECT_TRUE(report.converged()) << report.message;
      // Nothing is compared at rest: the start is off the minimiser (and the checker moves it
      // further, by up to 0.1 per variable at random — ipopt_step.hpp — so θ ≠ 0 under lie).
      EXPECT_GT(report.first_gradient_norm, 1.0);
      const std::string text = read_file(log);
      // Ipopt 3.11's checker (IpTNLPAdapter.cpp) prints these two lines and, at the end,
      // either "No errors detected by derivative checker." or "Derivative checker detected
      // %d error(s)." (with a '*' line per suspicious entry).
      EXPECT_GE(count(text, "Starting derivative checker for first derivatives."), 1);
      EXPECT_GE(count(text, "Starting derivative checker for second derivatives."), 1);
      EXPECT_EQ(count(text, "No errors detected by derivative checker."),
                count(text, "Starting derivative checker for second derivatives."))
          << text.substr(0, 6000);
      EXPECT_EQ(count(text, "Derivative checker detected"), 0);
    }
  }
}

TEST(IpoptStep, MatchesNewtonsStep) {
  for (const NamedModel& m : kModels) {
    for (const RotationParameterization rotation : kRotations) {
      SCOPED_TRACE(std::string(m.name) + ", " + to_string(rotation));
      const SolverOptions options = ipopt_options(rotation);
      const Model model = m.make();
      Started a = started(model, /*perturbed=*/false);
      Started b = started(model, /*perturbed=*/false);
      const State start = a.q;
      auto ipopt = make_ipopt_step_solver(std::move(a.component), options);
      SolverOptions newton_options = options;
      newton_options.backend = Backend::kNewton;
      auto newton = make_newton(std::move(b.component), newton_options);
      const StepReport ri = ipopt->solve(a.q);
      const StepReport rn = newton->solve(b.q);
      ASSERT_TRUE(ri.converged()) << to_string(ri.status) << ": " << ri.message;
      ASSERT_TRUE(rn.converged());
      EXPECT_LE(ri.step_norm, options.tolerance);
      EXPECT_GT(ri.iterations, 0);
      EXPECT_GE(ri.assemblies, ri.iterations + 1);
      EXPECT_TRUE(ri.message.empty()) << ri.message;
      // Both stop where the Lie Newton step δ has ‖δ‖∞ ≤ tol, i.e. each is within
      // tol (+ O(tol²)) of the minimiser in every position coordinate and every tangent
      // coordinate; a rotation is then within √3 tol in angle. Apart: ≤ 2√3 tol < 4 tol.
      const Component& c = ipopt->component();
      EXPECT_LT(max_difference(c, a.q, b.q), 4.0 * options.tolerance);
      // And the step really moved the state (the comparison is not between two starts).
      EXPECT_GT(max_difference(c, a.q, start), 1e-4);
      for (const DofBlock& r : c.rotations) {
        const Matrix3& R = a.q.rotations[r.index];
        EXPECT_LT((R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff(), 1e-14);
      }
    }
  }
}

// One step of `model` under Ipopt from the perturbed start (which violates every joint), its
// derivative checker at `level` writing into `log`; the solver's exact forces after it.
StepReport ipopt_step_with_checker(const Model& model, RotationParameterization rotation,
                                   const std::string& level, const std::filesystem::path& log,
                                   State& q, std::vector<Vector3>& forces) {
  SolverOptions options = ipopt_options(rotation);
  options.ipopt.derivative_test = level;
  options.ipopt.output_file = log.string();
  Started s = started(model, /*perturbed=*/true);
  EXPECT_GT(s.component.potential.constraint_violation(s.q), 1e-3);
  auto ipopt = make_ipopt_step_solver(std::move(s.component), options);
  const StepReport report = ipopt->solve(s.q);
  forces.clear();
  ipopt->component().potential.exact_forces(s.q, forces);
  q = s.q;
  return report;  // the solver closes its output file
}

::testing::AssertionResult checker_found_no_errors(const std::filesystem::path& log,
                                                   const std::string& level) {
  const std::string text = read_file(log);
  const std::string started =
      level == "second-order" ? "Starting derivative checker for second derivatives."
                              : "Starting derivative checker for first derivatives.";
  const int runs = count(text, started);
  if (runs < 1 || count(text, "No errors detected by derivative checker.") != runs ||
      count(text, "Derivative checker detected") != 0) {
    return ::testing::AssertionFailure() << text.substr(0, 6000);
  }
  return ::testing::AssertionSuccess();
}

TEST(IpoptStep, ExactJointsAreItsEqualityConstraints) {
  // Ipopt's checker on the constraints' Jacobian (first order: every exact joint part, and
  // under quat the norms) and on the Lagrangian's Hessian (second order: the multipliers'
  // part ∇²(λᵀc) of every part, the weld's included — its own FD test off E = I is in
  // test_joint_adjoint.cpp), from a start that violates every joint. Then the step Ipopt ends
  // with (no multiplier update: its own constraints) against Newton's augmented Lagrangian
  // from the same start, and the joints' forces: Ipopt's P λ̃ against ρ(c + s), as the
  // generalised forces Jᵀλ they exert (the alignment's and the line's λ along their axis,
  // where c is second order, exert none and differ).
  const TemporaryDirectory dir;
  for (const RotationParameterization rotation : kRotations) {
    SCOPED_TRACE(to_string(rotation));
    const std::filesystem::path log = dir.path / (to_string(rotation) + std::string(".txt"));
    State q;
    std::vector<Vector3> forces_ipopt, forces_newton;
    const Model model = jointed_links();
    const StepReport ri =
        ipopt_step_with_checker(model, rotation, "second-order", log, q, forces_ipopt);
    EXPECT_TRUE(checker_found_no_errors(log, "second-order"));
    Started b = started(model, /*perturbed=*/true);
    const State start = b.q;
    ASSERT_EQ(b.component.potential.exact_equalities(), 7);  // hinge 2, ball 1, weld 2, slider 2
    SolverOptions newton_options = ipopt_options(rotation);
    newton_options.backend = Backend::kNewton;
    auto newton = make_newton(std::move(b.component), newton_options);
    const StepReport rn = newton->solve(b.q);
    newton->component().potential.exact_forces(b.q, forces_newton);
    ASSERT_TRUE(ri.converged()) << to_string(ri.status) << ": " << ri.message;
    ASSERT_TRUE(rn.converged()) << rn.message;
    EXPECT_EQ(ri.multiplier_updates, 0);
    EXPECT_GT(rn.multiplier_updates, 0);
    EXPECT_LE(ri.constraint_violation, newton_options.tolerance);
    const Component& c = newton->component();
    EXPECT_GT(max_difference(c, q, start), 1e-3);
    EXPECT_LT(max_difference(c, q, b.q), 10.0 * newton_options.tolerance);
    ASSERT_EQ(forces_ipopt.size(), forces_newton.size());
    Eigen::MatrixXd J(3 * static_cast<Eigen::Index>(forces_newton.size()), c.dofs);
    c.potential.constraint_jacobian(b.q, J);
    Eigen::VectorXd li(J.rows()), ln(J.rows());
    for (std::size_t i = 0; i < forces_newton.size(); ++i) {
      li.segment<3>(3 * static_cast<Eigen::Index>(i)) = forces_ipopt[i];
      ln.segment<3>(3 * static_cast<Eigen::Index>(i)) = forces_newton[i];
    }
    const double generalised = (J.transpose() * ln).norm();
    EXPECT_GT(generalised, 1.0);
    EXPECT_LT((J.transpose() * (li - ln)).norm(), 1e-6 * generalised);
  }
}

TEST(IpoptStep, LimitedMemoryHessianConvergesOnAFreeBody) {
  for (const RotationParameterization rotation : kRotations) {
    SCOPED_TRACE(to_string(rotation));
    SolverOptions options = ipopt_options(rotation, 1e-9);
    options.ipopt.hessian_approximation = "limited-memory";
    options.max_iterations = 200;
    const Model model = free_body();
    Started a = started(model, /*perturbed=*/true);
    Started b = started(model, /*perturbed=*/true);
    auto lbfgs = make_ipopt_step_solver(std::move(a.component), options);
    options.ipopt.hessian_approximation = "exact";
    auto exact = make_ipopt_step_solver(std::move(b.component), options);
    const StepReport rl = lbfgs->solve(a.q);
    const StepReport re = exact->solve(b.q);
    ASSERT_TRUE(rl.converged()) << to_string(rl.status) << ": " << rl.message;
    ASSERT_TRUE(re.converged()) << to_string(re.status) << ": " << re.message;
    EXPECT_LT(max_difference(lbfgs->component(), a.q, b.q), 4.0 * options.tolerance);
    // Quasi-Newton needs more iterations than the exact Hessian from the same start.
    EXPECT_GT(rl.iterations, re.iterations);
  }
}

TEST(IpoptStep, FollowsNewtonsTrajectoryThroughTheSimulator) {
  // 50 steps of the tumbling body and 20 of the rod: one IpoptApplication per component,
  // reused by every step; the trajectories agree to a small multiple of the tolerance.
  const std::pair<Model, int> runs[] = {{free_body(), 50}, {small_rod(), 20}};
  for (const auto& [model, steps] : runs) {
    for (const RotationParameterization rotation : kRotations) {
      SCOPED_TRACE(std::to_string(steps) + " steps, " + to_string(rotation));
      const SolverOptions options = ipopt_options(rotation);
      SolverOptions newton_options = options;
      newton_options.backend = Backend::kNewton;
      Simulator ipopt(model, options), newton(model, newton_options);
      double difference = 0.0;
      for (int k = 0; k < steps; ++k) {
        const StepReport ri = ipopt.step();
        ASSERT_TRUE(ri.converged()) << "step " << k << ": " << ri.message;
        ASSERT_TRUE(newton.step().converged()) << "step " << k;
        const State& a = ipopt.state();
        const State& b = newton.state();
        for (std::size_t i = 0; i < a.points.size(); ++i) {
          difference = std::max(difference, (a.points[i] - b.points[i]).cwiseAbs().maxCoeff());
        }
        for (std::size_t i = 0; i < a.rotations.size(); ++i) {
          difference = std::max(difference, so3::distance(a.rotations[i], b.rotations[i]));
        }
      }
      // Per step the two are within 4 tol of each other (MatchesNewtonsStep); backward
      // Euler carries the differences of earlier steps without amplifying them (it is
      // dissipative), so after n steps they are within n · 4 tol.
      EXPECT_LT(difference, steps * 4.0 * options.tolerance);
    }
  }
}

TEST(IpoptStep, NonFinitePotentialFailsWithoutMovingTheState) {
  for (const RotationParameterization rotation : kRotations) {
    SCOPED_TRACE(to_string(rotation));
    Started s = started(free_body(), /*perturbed=*/true);
    // A load whose weight is NaN: Ψ and g are NaN everywhere.
    Gravity nan_load;
    nan_load.offsets = {s.component.points.front().offset};
    nan_load.point = s.component.points.front().index;
    nan_load.weight = Vector3(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
    s.component.potential.terms<Gravity>().push_back(nan_load);
    const State entry = s.q;
    auto solver = make_ipopt_step_solver(std::move(s.component), ipopt_options(rotation));
    const StepReport report = solver->solve(s.q);
    EXPECT_EQ(report.status, StepStatus::kNonFinite);
    EXPECT_FALSE(report.state_updated());
    EXPECT_FALSE(report.message.empty());
    EXPECT_EQ(s.q.points, entry.points);
    EXPECT_EQ(s.q.rotations, entry.rotations);
  }
}

TEST(IpoptStep, AFailedStepGivesTheExactJointsTheirPenaltiesBack) {
  // While Ipopt evaluates, the exact joints are held at ρ = 0 (ipopt_step.hpp); a step that
  // fails without a final point must leave them with their own ρ and no multiplier, as every
  // consumer outside a solve (the shared test, the next step, the forces) expects.
  Started s = started(jointed_links(), /*perturbed=*/true);
  std::vector<double> penalties;
  s.component.potential.for_each_exact_equality([&](const auto& t) { penalties.push_back(t.stiffness); });
  ASSERT_EQ(penalties.size(), 7u);
  Gravity huge;  // as in IpoptErrorIsSolverFailedAndNamesTheStatus below
  huge.offsets = {s.component.points.front().offset};
  huge.point = s.component.points.front().index;
  huge.weight = Vector3(1e300, 0.0, 0.0);
  s.component.potential.terms<Gravity>().push_back(huge);
  auto solver = make_ipopt_step_solver(std::move(s.component), ipopt_options(RotationParameterization::kLie));
  const StepReport report = solver->solve(s.q);
  ASSERT_EQ(report.status, StepStatus::kSolverFailed) << report.message;
  std::size_t i = 0;
  solver->component().potential.for_each_exact_equality([&](const auto& t) {
    EXPECT_EQ(t.stiffness, penalties[i++]);
    EXPECT_EQ(t.multiplier, Vector3::Zero());
  });
  std::vector<Vector3> forces;
  solver->component().potential.exact_forces(s.q, forces);
  for (const Vector3& f : forces) EXPECT_EQ(f, Vector3::Zero());
}

TEST(IpoptStep, IpoptErrorIsSolverFailedAndNamesTheStatus) {
  for (const RotationParameterization rotation : kRotations) {
    SCOPED_TRACE(to_string(rotation));
    Started s = started(free_body(), /*perturbed=*/true);
    // A weight of 1e300 N at the origin: Ψ, g and H are finite at the start (Ψ stays finite
    // for ‖x‖ ≲ 1), but the first Newton step is ~1e296 m, where Ψ overflows; no step
    // length Ipopt can reach gives a finite decrease.
    Gravity huge;
    huge.offsets = {s.component.points.front().offset};
    huge.point = s.component.points.front().index;
    huge.weight = Vector3(1e300, 0.0, 0.0);
    s.component.potential.terms<Gravity>().push_back(huge);
    const State entry = s.q;
    auto solver = make_ipopt_step_solver(std::move(s.component), ipopt_options(rotation));
    const StepReport report = solver->solve(s.q);
    EXPECT_EQ(report.status, StepStatus::kSolverFailed) << to_string(report.status);
    EXPECT_FALSE(report.state_updated());
    // Ipopt 3.11.9 gives up in its restoration phase (Restoration_Failed); any error status
    // is acceptable here as long as the message names it.
    const char* errors[] = {"Restoration_Failed",          "Error_In_Step_Computation",
                            "Invalid_Number_Detected",     "Diverging_Iterates",
                            "Infeasible_Problem_Detected", "Unrecoverable_Exception",
                            "NonIpopt_Exception_Thrown",   "Internal_Error"};
    EXPECT_TRUE(std::any_of(std::begin(errors), std::end(errors), [&](const char* name) {
      return report.message.find(std::string("Ipopt: ") + name) != std::string::npos;
    })) << report.message;
    EXPECT_EQ(s.q.points, entry.points);
    EXPECT_EQ(s.q.rotations, entry.rotations);
  }
}

TEST(IpoptStep, IterationLimitIsMaxIterationsWithTheStateUpdated) {
  for (const RotationParameterization rotation : kRotations) {
    SCOPED_TRACE(to_string(rotation));
    SolverOptions options = ipopt_options(rotation);
    options.max_iterations = 1;
    Started s = started(free_body(), /*perturbed=*/true);
    auto solver = make_ipopt_step_solver(std::move(s.component), options);
    // Twice from the same start: the second solve reuses the IpoptApplication, whose
    // iteration limit must hold again (and no re-centring may add iterations beyond it).
    const State entry = s.q;
    for (int k = 0; k < 2; ++k) {
      s.q = entry;
      const StepReport report = solver->solve(s.q);
      EXPECT_EQ(report.status, StepStatus::kMaxIterations) << report.message;
      EXPECT_TRUE(report.state_updated());
      EXPECT_EQ(report.iterations, 1);
      EXPECT_GT(report.step_norm, options.tolerance);
      EXPECT_NE(report.message.find("Maximum_Iterations_Exceeded"), std::string::npos)
          << report.message;
      EXPECT_GT(max_difference(solver->component(), s.q, entry), 1e-6);
    }
  }
}

TEST(IpoptStep, UnwritableOutputFileIsAnOptionError) {
  SolverOptions options = ipopt_options(RotationParameterization::kLie);
  options.ipopt.output_file = "/nonexistent-directory/ipopt.txt";
  Started s = started(free_body(), false);
  try {
    make_ipopt_step_solver(std::move(s.component), options);
    FAIL() << "expected a ModelError";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "solver.ipopt.output_file");
  }
}

}  // namespace
}  // namespace liedyn::ipopt_tests

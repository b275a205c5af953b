// spin_up: a tiny control problem solved through the simulation.
//
// A butterfly bolt (body inertia diag(1, 2, 2.8)) starts at rest. Which constant world
// torque τ makes its angular velocity equal ω* after N time steps?
//
// The map τ ↦ ω_N(τ) is the simulator itself (backward Euler, Newton per step). It is
// nonlinear: the body turns while it spins up, so its world inertia R I Rᵀ changes.
// We solve ω_N(τ) = ω* by Newton's method with a finite-difference Jacobian
// (3 extra simulations per iteration), starting from the guess that ignores rotation,
// τ₀ = I ω*/T (angular momentum L(T) = τ T for a constant world torque).
//
// Exit status: 0 if ‖ω_N(τ) − ω*‖ < tolerance within the iteration budget, 1 otherwise.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>

#include <liedyn/lib/model.hpp>
#include <liedyn/solvers/newton.hpp>
#include <liedyn/solvers/simulator.hpp>

namespace {

constexpr int kSteps = 100;         // N
constexpr double kTimeStep = 0.01;  // h: T = N h = 1 s
constexpr double kTolerance = 1e-9; // rad/s
constexpr int kMaxIterations = 12;

liedyn::Model make_model(const liedyn::Vector3& torque) {
  liedyn::Model model;
  model.time_step = kTimeStep;
  liedyn::RigidBody bolt;
  bolt.name = "bolt";
  bolt.mass = 0.5;
  bolt.inertia = liedyn::Vector3(1.0, 2.0, 2.8).asDiagonal();
  model.bodies.push_back(bolt);
  liedyn::TorqueSpec tau;
  tau.body = 0;
  tau.torque = torque;
  model.torques.push_back(tau);
  return model;
}

// ω_N(τ), or nothing if a time step fails.
std::optional<liedyn::Vector3> final_angular_velocity(const liedyn::Vector3& torque) {
  liedyn::SolverOptions options;
  options.tolerance = 1e-12;
  liedyn::Simulator sim(make_model(torque), options);
  for (int k = 0; k < kSteps; ++k) {
    const liedyn::StepReport report = sim.step();
    if (!report.state_updated()) {
      std::fprintf(stderr, "step %d failed: %s\n", k, liedyn::to_string(report.status));
      return std::nullopt;
    }
  }
  return sim.angular_velocity(0);
}

int run() {
  const liedyn::Vector3 target(1.0, 2.0, -0.5);  // ω*, rad/s, world frame
  const double T = kSteps * kTimeStep;
  const liedyn::Vector3 inertia(1.0, 2.0, 2.8);
  liedyn::Vector3 torque = inertia.cwiseProduct(target) / T;  // τ₀

  std::printf("spin_up: target omega = (%.6f, %.6f, %.6f) rad/s after %d steps of h = %g s\n",
              target.x(), target.y(), target.z(), kSteps, kTimeStep);
  for (int it = 0; it <= kMaxIterations; ++it) {
    const std::optional<liedyn::Vector3> omega = final_angular_velocity(torque);
    if (!omega) return 1;
    const liedyn::Vector3 residual = *omega - target;
    std::printf("  iter %2d  tau = (%+.9f, %+.9f, %+.9f)  |omega - target| = %.3e\n", it,
                torque.x(), torque.y(), torque.z(), residual.norm());
    if (!residual.allFinite()) return 1;
    if (residual.norm() < kTolerance) {
      std::printf("spin_up: converged, torque = (%.9f, %.9f, %.9f) N m, "
                  "omega = (%.9f, %.9f, %.9f) rad/s\n",
                  torque.x(), torque.y(), torque.z(), omega->x(), omega->y(), omega->z());
      return 0;
    }
    if (it == kMaxIterations) break;

    // Forward-difference Jacobian ∂ω_N/∂τ.
    Eigen::Matrix3d J;
    for (int j = 0; j < 3; ++j) {
      const double eps = 1e-6 * std::max(1.0, std::abs(torque[j]));
      liedyn::Vector3 perturbed = torque;
      perturbed[j] += eps;
      const std::optional<liedyn::Vector3> omega_j = final_angular_velocity(perturbed);
      if (!omega_j) return 1;
      J.col(j) = (*omega_j - *omega) / eps;
    }
    const Eigen::PartialPivLU<Eigen::Matrix3d> lu(J);
    const liedyn::Vector3 delta = lu.solve(-residual);
    if (!delta.allFinite()) {
      std::fprintf(stderr, "spin_up: singular Jacobian\n");
      return 1;
    }
    torque += delta;
  }
  std::fprintf(stderr, "spin_up: no convergence in %d iterations\n", kMaxIterations);
  return 1;
}

}  // namespace

int main() {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "spin_up: %s\n", e.what());
    return 1;
  }
}

#pragma once
// The backward-Euler step as a manifold nonlinear least-squares problem for Ceres
// (DESIGN.md §8). Placeholder while the back-end is written.

#include <memory>

#include "step_solver.hpp"

namespace liedyn {

std::unique_ptr<StepSolver> make_ceres_step_solver(Component component,
                                                   const SolverOptions& options);

}  // namespace liedyn

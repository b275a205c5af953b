#pragma once
// The backward-Euler step as an unconstrained NLP for Ipopt (DESIGN.md §8). Placeholder while
// the back-end is written.

#include <memory>

#include "step_solver.hpp"

namespace liedyn {

std::unique_ptr<StepSolver> make_ipopt_step_solver(Component component,
                                                   const SolverOptions& options);

}  // namespace liedyn

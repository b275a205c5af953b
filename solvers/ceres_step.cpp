#include "ceres_step.hpp"

#include <stdexcept>

namespace liedyn {

// PLACEHOLDER (being written): not a working back-end.
std::unique_ptr<StepSolver> make_ceres_step_solver(Component, const SolverOptions&) {
  throw std::logic_error("the ceres back-end is not implemented yet");
}

}  // namespace liedyn

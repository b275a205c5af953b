#include "ipopt_step.hpp"

#include <stdexcept>

namespace liedyn {

// PLACEHOLDER (being written): not a working back-end.
std::unique_ptr<StepSolver> make_ipopt_step_solver(Component, const SolverOptions&) {
  throw std::logic_error("the ipopt back-end is not implemented yet");
}

}  // namespace liedyn

#pragma once
// Two runs of one scene under different solver options, compared frame by frame: what the
// back-end suites check when they say two ways of solving a step agree.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "lib/model.hpp"
#include "lib/so3.hpp"
#include "solvers/simulator.hpp"

namespace liedyn::test {

struct Trajectory {
  std::vector<State> states;  // after each frame
  int iterations = 0;
};

// `frames` steps of `model` under `options`, each expected to converge (`label` names the run
// in a failure).
inline Trajectory run_frames(const Model& model, const SolverOptions& options, int frames,
                             const std::string& label) {
  Simulator sim(model, options);
  Trajectory out;
  for (int k = 1; k <= frames; ++k) {
    const StepReport r = sim.step();
    EXPECT_TRUE(r.converged()) << label << " frame " << k << ": " << to_string(r.status) << " "
                               << r.message;
    if (!r.state_updated()) break;
    out.iterations += r.iterations;
    out.states.push_back(sim.state());
  }
  return out;
}

// Largest position (m) and rotation (rad) difference over all frames.
inline std::pair<double, double> deviation(const Trajectory& a, const Trajectory& b) {
  double dx = 0.0, dR = 0.0;
  EXPECT_EQ(a.states.size(), b.states.size());
  for (std::size_t k = 0; k < std::min(a.states.size(), b.states.size()); ++k) {
    for (std::size_t i = 0; i < a.states[k].points.size(); ++i) {
      dx = std::max(dx, (a.states[k].points[i] - b.states[k].points[i]).cwiseAbs().maxCoeff());
    }
    for (std::size_t i = 0; i < a.states[k].rotations.size(); ++i) {
      dR = std::max(dR, so3::distance(a.states[k].rotations[i], b.states[k].rotations[i]));
    }
  }
  return {dx, dR};
}

}  // namespace liedyn::test

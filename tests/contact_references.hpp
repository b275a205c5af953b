#pragma once
// Reference computations shared by the contact test suites: what the broad phase must find
// (every pair of boxes tested), and points at a chosen signed distance from a shape.

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "lib/broad_phase.hpp"
#include "lib/sdf.hpp"

namespace liedyn::test {

// Every overlapping pair (i < j) of `boxes`, closed boxes, sorted: the broad phase's
// reference (an unbounded box, ±∞, overlaps every box).
inline std::vector<std::pair<int, int>> every_overlap(const std::vector<Aabb>& boxes) {
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < static_cast<int>(boxes.size()); ++i) {
    for (int j = i + 1; j < static_cast<int>(boxes.size()); ++j) {
      if ((boxes[i].lo.array() <= boxes[j].hi.array()).all() && (boxes[j].lo.array() <= boxes[i].hi.array()).all()) {
        out.emplace_back(i, j);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The point at signed distance `target` from `shape` reached from `start` by Newton's method
// on φ along its gradient (to 1e-13, at most 100 steps; the caller starts where φ is smooth).
inline Vector3 onto_level_set(const Collider& shape, Vector3 start, double target) {
  for (int i = 0; i < 100; ++i) {
    const SdfValue s = shape.evaluate(start, false);
    const double error = s.distance - target;
    if (std::abs(error) < 1e-13) break;
    start -= error * s.gradient / s.gradient.squaredNorm();
  }
  return start;
}

}  // namespace liedyn::test

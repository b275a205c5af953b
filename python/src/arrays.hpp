#pragma once
// NumPy arrays that own their data (bindings.hpp: nothing handed to Python aliases C++ state).

#include <pybind11/numpy.h>

#include <vector>

#include "lib/so3.hpp"
#include "lib/state.hpp"

namespace liedyn::python {

namespace py = pybind11;

// An array of the given shape that takes `data` over (no copy; freed with the array).
inline py::array_t<double> owned_array(std::vector<double>&& data, std::vector<py::ssize_t> shape) {
  auto* held = new std::vector<double>(std::move(data));
  py::capsule free_it(held, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>(std::move(shape), held->data(), free_it);
}

// Appends x, y, z of each point; w, x, y, z of each rotation's unit quaternion (the CLI's
// trajectory.csv convention, so3::to_quaternion); the 9 entries of each rotation, row-major.
inline void append_points(const State& q, std::vector<double>& out) {
  for (const Vector3& x : q.points) out.insert(out.end(), {x.x(), x.y(), x.z()});
}
inline void append_quaternions(const State& q, std::vector<double>& out) {
  for (const Matrix3& R : q.rotations) {
    const Eigen::Quaterniond u = so3::to_quaternion(R);
    out.insert(out.end(), {u.w(), u.x(), u.y(), u.z()});
  }
}
inline void append_rotations(const State& q, std::vector<double>& out) {
  for (const Matrix3& R : q.rotations) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) out.push_back(R(i, j));
    }
  }
}

}  // namespace liedyn::python

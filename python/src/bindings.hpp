#pragma once
// The Python module `liedyn._liedyn` (the package `liedyn` re-exports it, python/liedyn/):
// one bind_* function per concept, each in its own file, called by module.cpp.
//
// Conventions of every binding:
//   * arrays handed to Python are copies (NumPy arrays that own their memory): nothing a
//     Python object holds can outlive or alias the C++ state it came from;
//   * calls that run simulations release the GIL (one object per thread: a Simulator or a
//     DifferentiableProblem is not safe to share between threads that call it at once);
//   * errors are the package's exceptions (module.cpp): SceneError and ModelError with
//     `.field` and `.reason`, SimulationFailed with `.frame`.

#include <pybind11/pybind11.h>

#include <string>

#include "problems/scene.hpp"

namespace liedyn::python {

namespace py = pybind11;

// A parsed scene with the JSON text it came from: what to_dict returns and what pickling
// stores (a scene is re-parsed, never serialised field by field). `source` names it in
// messages; relative mesh paths in it are resolved against source's folder.
struct SceneHandle {
  std::string json;
  Scene scene;
  std::filesystem::path folder;  // where its relative mesh paths are read from
};

// Parses JSON text (SceneError on bad input); relative mesh paths from `folder`, by default
// the folder of `source` taken as a path.
SceneHandle parse_scene_handle(const std::string& json, const std::string& source,
                               const std::filesystem::path& folder = {});

void bind_scene(py::module_& m);
void bind_simulator(py::module_& m);
void bind_problem(py::module_& m);
void bind_studies(py::module_& m);

}  // namespace liedyn::python

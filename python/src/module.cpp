// The module `liedyn._liedyn`: its exceptions and the bindings of each concept (bindings.hpp).

#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "lib/model.hpp"
#include "solvers/adjoint.hpp"

namespace py = pybind11;

namespace {

// Raises `type(message)` with the given attributes set on the instance.
void raise_with(const py::object& type, const char* message,
                std::initializer_list<std::pair<const char*, py::object>> attributes) {
  py::object error = type(message);
  for (const auto& [name, value] : attributes) error.attr(name) = value;
  PyErr_SetObject(type.ptr(), error.ptr());
}

}  // namespace

PYBIND11_MODULE(_liedyn, m) {
  m.doc() = "liedyn's C++ core: scenes, the simulator and the adjoint gradient. Use the "
            "package `liedyn`, which re-exports everything here.";
  // Bad input: ValueError subclasses carrying where (file, field) and why (reason).
  static py::exception<liedyn::SceneError> scene_error(m, "SceneError", PyExc_ValueError);
  static py::exception<liedyn::ModelError> model_error(m, "ModelError", PyExc_ValueError);
  // A run that cannot go on: a step that did not update the state, a Hessian of the backward
  // pass that is not positive definite.
  static py::exception<liedyn::SimulationFailed> simulation_failed(m, "SimulationFailed",
                                                                   PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const liedyn::SceneError& e) {
      raise_with(scene_error, e.what(),
                 {{"file", py::str(e.file())}, {"field", py::str(e.field())},
                  {"reason", py::str(e.reason())}});
    } catch (const liedyn::ModelError& e) {
      raise_with(model_error, e.what(),
                 {{"file", py::none()}, {"field", py::str(e.field())},
                  {"reason", py::str(e.reason())}});
    } catch (const liedyn::SimulationFailed& e) {
      raise_with(simulation_failed, e.what(), {{"frame", py::int_(e.frame())}});
    }
  });
  liedyn::python::bind_scene(m);
  liedyn::python::bind_simulator(m);
  liedyn::python::bind_problem(m);
  liedyn::python::bind_studies(m);
}

// liedyn.Scene: a scene file's model, solver options and optimisation block, parsed and
// validated exactly as the command line does it (problems/scene.hpp).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <nlohmann/json.hpp>

#include "bindings.hpp"
#include "problems/scene_settings.hpp"

namespace liedyn::python {

SceneHandle parse_scene_handle(const std::string& json, const std::string& source,
                               const std::filesystem::path& folder) {
  const std::filesystem::path from = folder.empty() ? std::filesystem::path(source).parent_path() : folder;
  return SceneHandle{json, parse_scene(json, source, from), from};
}

namespace {

// JSON text of a Python object (dicts, lists, numbers, strings; NumPy arrays and scalars
// through their tolist()).
std::string dumps(const py::handle& value) {
  const py::module_ json = py::module_::import("json");
  const py::cpp_function to_list([](const py::object& o) -> py::object {
    if (py::hasattr(o, "tolist")) return o.attr("tolist")();
    throw py::type_error("not JSON serializable: " + std::string(py::str(py::type::of(o))));
  });
  return json.attr("dumps")(value, py::arg("default") = to_list).cast<std::string>();
}

py::object loads(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}

std::vector<std::string> names_of(const auto& objects) {
  std::vector<std::string> names;
  for (const auto& o : objects) names.push_back(o.name);
  return names;
}

}  // namespace

void bind_scene(py::module_& m) {
  py::class_<SceneHandle>(m, "Scene", R"doc(
A scene: bodies, rods, colliders, loads, solver options and (optionally) an optimisation
problem, parsed and validated as ``liedyn simulate`` does it (docs/scene-format.md).
Bad input raises SceneError naming the file, the field and the reason.

Build one with Scene.from_file, Scene.from_json or Scene.from_dict; change fields with
with_settings. A scene is immutable and pickles through its JSON text.)doc")
      .def_static(
          "from_file",
          [](const std::filesystem::path& path) {
            return parse_scene_handle(read_scene_file(path), path.string());
          },
          py::arg("path"),
          "Reads and validates a scene file (JSON). Relative mesh paths are resolved against "
          "the file's folder.")
      .def_static(
          "from_json",
          [](const std::string& text, const std::string& source) { return parse_scene_handle(text, source); },
          py::arg("text"), py::arg("source") = "<json>",
                  "Parses and validates scene JSON text. `source` names it in error messages; "
                  "relative mesh paths are resolved against its folder.")
      .def_static(
          "from_dict",
          [](const py::dict& d, const std::string& source) {
            return parse_scene_handle(dumps(d), source);
          },
          py::arg("d"), py::arg("source") = "<dict>",
          "Validates a scene given as a dict (the JSON document as Python objects; NumPy "
          "arrays are accepted where the format has arrays).")
      .def("to_json", [](const SceneHandle& s) { return s.json; },
           "The JSON text the scene was parsed from (with its settings applied).")
      .def("to_dict", [](const SceneHandle& s) { return loads(s.json); },
           "The scene as a dict (a fresh copy: changing it does not change the scene).")
      .def(
          "with_settings",
          [](const SceneHandle& s, const py::dict& settings) {
            nlohmann::json root = nlohmann::json::parse(s.json);
            std::string label;
            for (const auto& [key, value] : settings) {
              const std::string path = py::str(key);
              const std::string text = dumps(value);
              set_scene_path(root, path, nlohmann::json::parse(text), s.scene.source);
              label += (label.empty() ? "" : " ") + path + "=" + text;
            }
            return parse_scene_handle(root.dump(), s.scene.source + " [" + label + "]", s.folder);
          },
          py::arg("settings"),
          "A new scene with values at dotted paths of the JSON document, as the command "
          "line's --set PATH=VALUE: {'integrator': 'bdf2', 'solver.tolerance': 1e-12, "
          "'rods.0.bending_stiffness': [1, 1, 2]}. Validated as a file would be.")
      .def_property_readonly("source", [](const SceneHandle& s) { return s.scene.source; },
                             "The file name or label used in messages.")
      .def_property_readonly("description",
                             [](const SceneHandle& s) { return s.scene.description; })
      .def_property_readonly("frames", [](const SceneHandle& s) { return s.scene.frames; },
                             "Time steps a run takes (frame 0 is the initial state).")
      .def_property_readonly("time_step",
                             [](const SceneHandle& s) { return s.scene.model.time_step; },
                             "h, in seconds.")
      .def_property_readonly(
          "integrator",
          [](const SceneHandle& s) { return std::string(to_string(s.scene.model.integrator)); },
          "'backward_euler', 'trapezoidal' or 'bdf2'.")
      .def_property_readonly("static_equilibrium",
                             [](const SceneHandle& s) { return s.scene.model.static_equilibrium; })
      .def_property_readonly("bodies", [](const SceneHandle& s) { return names_of(s.scene.model.bodies); },
                             "Body names, in state order (body i is point i and rotation i).")
      .def_property_readonly("rods", [](const SceneHandle& s) { return names_of(s.scene.model.rods); },
                             "Rod names, in state order.")
      .def_property_readonly("has_optimization",
                             [](const SceneHandle& s) { return s.scene.optimization.has_value(); })
      .def_property_readonly("identity", [](const SceneHandle& s) { return s.scene.identity; },
                             "A hash of the scene's content.")
      .def("__repr__",
           [](const SceneHandle& s) {
             return "<liedyn.Scene " + s.scene.source + ": " +
                    std::to_string(s.scene.model.bodies.size()) + " bodies, " +
                    std::to_string(s.scene.model.rods.size()) + " rods, " +
                    std::to_string(s.scene.frames) + " frames>";
           })
      .def(py::pickle(
          [](const SceneHandle& s) { return py::make_tuple(s.json, s.scene.source, s.folder.string()); },
          [](const py::tuple& t) {
            return parse_scene_handle(t[0].cast<std::string>(), t[1].cast<std::string>(),
                                      std::filesystem::path(t[2].cast<std::string>()));
          }));
}

}  // namespace liedyn::python

#pragma once
// Settings over a scene file from the command line, `--set PATH=VALUE`: the value goes to the
// dotted PATH of the scene's JSON (`integrator`, `solver.tolerance`, `rods.0.bending_stiffness`;
// numbers index arrays, missing object keys are created) before the scene is parsed and
// validated, so a bad value is the same SceneError a bad file would give. VALUE is JSON
// (`1e-4`, `[1, 1, 2]`, `"lie"`) or else a bare string (`trapezoidal`). `liedyn sweep` takes a
// list of values per path (an axis of its grid, sweep.hpp); the commands of one run take one.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "scene.hpp"

namespace liedyn {

// VALUE as JSON if it is JSON, else as a string.
nlohmann::json parse_setting_value(const std::string& text);

// root[path] = value. Throws SceneError(source, "--set PATH", reason) for a path that does not
// lead into the document (an index out of range, a key into a number).
void set_scene_path(nlohmann::json& root, const std::string& path, const nlohmann::json& value,
                    const std::string& source);

// "PATH=VALUE" split at the first '=', nothing when either side is empty.
std::optional<std::pair<std::string, std::string>> split_setting(const std::string& text);

// load_scene (scene.hpp) with each "PATH=VALUE" of `settings` applied in order; messages name
// the source as "FILE [PATH=VALUE …]".
Scene load_scene(const std::filesystem::path& file, const std::vector<std::string>& settings);

}  // namespace liedyn

#include "scene_settings.hpp"


namespace liedyn {

using nlohmann::json;

json parse_setting_value(const std::string& text) {
  try {
    return json::parse(text);
  } catch (const json::exception&) {
    return json(text);
  }
}

void set_scene_path(json& root, const std::string& path, const json& value,
                    const std::string& source) {
  const std::string field = "--set " + path;
  json* node = &root;
  std::size_t begin = 0;
  std::string walked;
  while (true) {
    const std::size_t end = path.find('.', begin);
    const std::string key = path.substr(begin, end == std::string::npos ? end : end - begin);
    if (key.empty()) throw SceneError(source, field, "empty segment in the dotted path");
    const bool last = end == std::string::npos;
    if (node->is_array()) {
      if (key.find_first_not_of("0123456789") != std::string::npos || key.size() > 9) {
        throw SceneError(source, field,
                         "\"" + walked + "\" is an array: \"" + key + "\" must be an index");
      }
      const std::size_t index = std::stoul(key);
      if (index >= node->size()) {
        throw SceneError(source, field,
                         "index " + key + " is out of range (\"" + walked + "\" has " +
                             std::to_string(node->size()) + " items)");
      }
      node = &(*node)[index];
    } else if (node->is_object()) {
      if (!last && !node->contains(key)) (*node)[key] = json::object();
      node = &(*node)[key];
    } else {
      throw SceneError(
          source, field,
          "\"" + walked + "\" is a " + node->type_name() + ", not an object or an array");
    }
    walked += (walked.empty() ? "" : ".") + key;
    if (last) break;
    begin = end + 1;
  }
  *node = value;
}

std::optional<std::pair<std::string, std::string>> split_setting(const std::string& text) {
  const std::size_t equals = text.find('=');
  if (equals == std::string::npos || equals == 0 || equals + 1 == text.size()) return std::nullopt;
  return std::pair{text.substr(0, equals), text.substr(equals + 1)};
}

Scene load_scene(const std::filesystem::path& file, const std::vector<std::string>& settings) {
  if (settings.empty()) return load_scene(file);
  const std::string text = read_scene_file(file);
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception&) {
    return parse_scene(text, file.string(), file.parent_path());  // its message says where the JSON breaks
  }
  std::string label;
  for (const std::string& setting : settings) {
    const auto split = split_setting(setting);
    if (!split) throw SceneError(file.string(), "--set " + setting, "expected PATH=VALUE");
    const auto& [path, value] = *split;
    set_scene_path(root, path, parse_setting_value(value), file.string());
    label += (label.empty() ? "" : " ") + setting;
  }
  return parse_scene(root.dump(), file.string() + " [" + label + "]", file.parent_path());
}

}  // namespace liedyn

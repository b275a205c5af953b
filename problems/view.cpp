#include "view.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "output_folder.hpp"
#include "scene.hpp"
#include "view_template.hpp"  // kViewTemplate: problems/viewer/view_template.html, generated

namespace liedyn {
namespace {

using ordered_json = nlohmann::ordered_json;
constexpr std::uintmax_t kMaxInput = std::uintmax_t(4) << 30;  // 4 GiB: a long rod run

std::string read(const std::filesystem::path& file, const char* kind) {
  return read_named_input(file, kMaxInput, kind);
}

// The fields of one CSV line (RFC 4180 quoting, as csv_field writes).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

// The lines of a file's text, each with its number (from 1), the header first.
class Lines {
 public:
  Lines(std::string text, std::string source) : text_(std::move(text)), source_(std::move(source)) {}
  bool next(std::string& line) {
    if (at_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', at_);
    line = text_.substr(at_, end == std::string::npos ? std::string::npos : end - at_);
    at_ = end == std::string::npos ? text_.size() : end + 1;
    ++number_;
    return true;
  }
  int line() const { return number_; }
  [[noreturn]] void fail(const std::string& reason, int line = 0) const {
    throw SceneError(source_, "line " + std::to_string(line > 0 ? line : number_), reason);
  }
  double number(const std::string& field, const char* what, int line = 0) const {
    char* end = nullptr;
    const double value = std::strtod(field.c_str(), &end);
    if (field.empty() || end != field.c_str() + field.size()) {
      fail(std::string(what) + " \"" + field + "\" is not a number", line);
    }
    return value;
  }
  // A frame number: a whole number from 0 to 2³¹ − 1.
  int frame(const std::string& field, int line = 0) const {
    const double value = number(field, "frame", line);
    if (!(value >= 0.0 && value <= 2147483647.0 && value == std::floor(value))) {
      fail("frame \"" + field + "\" is not a frame number", line);
    }
    return static_cast<int>(value);
  }

 private:
  std::string text_, source_;
  std::size_t at_ = 0;
  int number_ = 0;
};

// What trajectory.csv's rows of one frame must be, from shapes.json: (object, kind, index).
struct Row {
  std::string object, kind;
  int index;
};

// Far more rows per frame than any scene has (a rod of 10⁶ edges): an edited shapes.json
// must not make us allocate for ever.
constexpr std::size_t kMaxRowsPerFrame = 10'000'000;

std::vector<Row> expected_rows(const ordered_json& shapes, const std::string& source) {
  std::vector<Row> rows;
  try {
    if (!shapes.is_object()) throw SceneError(source, "", "must be an object");
    if (shapes.contains("title") && !shapes["title"].is_string()) {
      throw SceneError(source, "title", "must be a string");
    }
    if (shapes.contains("time_step") && !shapes["time_step"].is_number()) {
      throw SceneError(source, "time_step", "must be a number");
    }
    for (const ordered_json& b : shapes.at("bodies")) rows.push_back({b.at("name").get<std::string>(), "body", 0});
    for (const ordered_json& r : shapes.at("rods")) {
      const std::string name = r.at("name").get<std::string>();
      const std::int64_t nodes = r.at("nodes").get<std::int64_t>();
      if (nodes < 2 || rows.size() + 2 * std::size_t(nodes) > kMaxRowsPerFrame) {
        throw SceneError(source, "rods", "rod " + name + " has " + std::to_string(nodes) +
                                             " nodes (at least 2, and at most " +
                                             std::to_string(kMaxRowsPerFrame / 2) + " in all)");
      }
      for (int i = 0; i < nodes; ++i) rows.push_back({name, "node", i});
      for (int j = 0; j + 1 < nodes; ++j) rows.push_back({name, "edge", j});
    }
  } catch (const nlohmann::json::exception& e) {
    throw SceneError(source, "", std::string("is not a run's shapes.json (") + e.what() + ")");
  }
  if (rows.empty()) throw SceneError(source, "bodies", "no body and no rod: nothing to show");
  return rows;
}

// Standard base64 (RFC 4648) of raw bytes.
std::string base64(const unsigned char* data, std::size_t size) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const unsigned n = (unsigned(data[i]) << 16) | (i + 1 < size ? unsigned(data[i + 1]) << 8 : 0u) |
                       (i + 2 < size ? unsigned(data[i + 2]) : 0u);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(n >> 6) & 63] : '=';
    out += i + 2 < size ? kAlphabet[n & 63] : '=';
  }
  return out;
}

// Script text that cannot end its <script> element early: every "</script", in any letter
// case, becomes "<\/script" (still "</" inside a JS string, regex or comment).
std::string script_safe(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '<' && text.size() - i >= 8 && text[i + 1] == '/' &&
        std::equal(text.begin() + i + 2, text.begin() + i + 8, "script",
                   [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; })) {
      out += '\\';
    }
  }
  return out;
}

// JSON inside a <script> element: "<" only occurs within strings, where \u003c is the same
// character; so neither "</script" nor "<!--" (user text: names, titles) can reach the parser.
std::string json_script_safe(const std::string& json_text) {
  std::string out;
  out.reserve(json_text.size());
  for (const char c : json_text) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

// The template with each placeholder (exactly once in it) replaced by its text, in one pass:
// inserted text is never searched for the next placeholder.
std::string fill_template(const std::string& page, const std::vector<std::pair<std::string, std::string>>& values) {
  std::vector<std::pair<std::size_t, const std::pair<std::string, std::string>*>> at;
  for (const auto& v : values) {
    const std::size_t i = page.find(v.first);
    if (i == std::string::npos || page.find(v.first, i + 1) != std::string::npos) {
      throw std::logic_error("view template: " + v.first + " must appear exactly once");
    }
    at.emplace_back(i, &v);
  }
  std::sort(at.begin(), at.end());
  std::string out;
  std::size_t from = 0;
  for (const auto& [i, v] : at) {
    out.append(page, from, i - from);
    out += v->second;
    from = i + v->first.size();
  }
  out.append(page, from, std::string::npos);
  return out;
}

}  // namespace

ViewSummary write_view(const std::filesystem::path& run_dir, const ViewOptions& options) {
  const std::filesystem::path shapes_file = run_dir / "shapes.json";
  ordered_json shapes;
  try {
    shapes = ordered_json::parse(read(shapes_file, "shapes.json"));
  } catch (const nlohmann::json::exception& e) {
    throw SceneError(shapes_file.string(), "", std::string("is not JSON (") + e.what() + ")");
  }
  const std::vector<Row> rows = expected_rows(shapes, shapes_file.string());

  // trajectory.csv: every written frame's rows, the objects of shapes.json in order.
  const std::filesystem::path trajectory_file = run_dir / "trajectory.csv";
  Lines lines(read(trajectory_file, "trajectory.csv"), trajectory_file.string());
  std::string line;
  if (!lines.next(line) || line != "frame,time,object,kind,index,x,y,z,qw,qx,qy,qz") {
    lines.fail("is not trajectory.csv's header");
  }
  std::vector<float> poses;
  std::vector<int> frame_numbers;
  std::vector<double> times;
  std::size_t row = 0;
  while (lines.next(line)) {
    if (line.empty()) continue;
    const std::vector<std::string> f = csv_fields(line);
    if (f.size() != 12) lines.fail("has " + std::to_string(f.size()) + " fields, not 12");
    const Row& expected = rows[row];
    if (f[2] != expected.object || f[3] != expected.kind || f[4] != std::to_string(expected.index)) {
      lines.fail("is " + f[2] + " " + f[3] + " " + f[4] + " where shapes.json has " + expected.object + " " +
                 expected.kind + " " + std::to_string(expected.index) + " (not the same run?)");
    }
    if (row == 0) {
      frame_numbers.push_back(lines.frame(f[0]));
      times.push_back(lines.number(f[1], "time"));
    }
    // Bodies: position and orientation; nodes: position; edges: the frame (their midpoint
    // follows from the nodes).
    const int first = expected.kind == "edge" ? 8 : 5;
    const int last = expected.kind == "node" ? 8 : 12;
    for (int c = first; c < last; ++c) poses.push_back(static_cast<float>(lines.number(f[c], "a coordinate")));
    row = (row + 1) % rows.size();
  }
  if (row != 0) lines.fail("ends within a frame");
  if (frame_numbers.empty()) lines.fail("holds no frame");

  // frames.csv: the series at the written frames.
  ordered_json series = ordered_json::object();
  const std::filesystem::path frames_file = run_dir / "frames.csv";
  if (std::filesystem::exists(frames_file)) {
    Lines frames(read(frames_file, "frames.csv"), frames_file.string());
    std::string header;
    frames.next(header);
    const std::vector<std::string> names = csv_fields(header);
    const std::map<std::string, std::string> wanted = {{"kinetic_energy", "kinetic_energy"},
                                                       {"potential_energy", "potential_energy"},
                                                       {"newton_iterations", "iterations"},
                                                       {"max_penetration", "max_penetration"}};
    std::map<int, std::pair<int, std::vector<std::string>>> by_frame;  // frame: line, fields
    while (frames.next(line)) {
      if (line.empty()) continue;
      std::vector<std::string> f = csv_fields(line);
      if (f.size() != names.size()) frames.fail("has " + std::to_string(f.size()) + " fields, the header " + std::to_string(names.size()));
      const int frame = frames.frame(f[0]);  // before f is moved
      by_frame[frame] = {frames.line(), std::move(f)};
    }
    for (std::size_t c = 0; c < names.size(); ++c) {
      const auto key = wanted.find(names[c]);
      if (key == wanted.end()) continue;
      ordered_json values = ordered_json::array();
      for (const int k : frame_numbers) {
        const auto it = by_frame.find(k);
        values.push_back(it == by_frame.end() ? ordered_json(nullptr)
                                              : ordered_json(frames.number(it->second.second[c], names[c].c_str(),
                                                                           it->second.first)));
      }
      series[key->second] = values;
    }
  }

  ordered_json meta = {{"title", shapes.value("title", run_dir.string())},
                       {"time_step", shapes.value("time_step", 0.0)},
                       {"frame_numbers", frame_numbers},
                       {"times", times},
                       {"bodies", shapes.at("bodies")},
                       {"rods", shapes.at("rods")},
                       {"colliders", shapes.value("colliders", ordered_json::array())},
                       {"series", series}};

  const std::filesystem::path three = options.three_dir / "three.min.js";
  const std::filesystem::path orbit = options.three_dir / "examples" / "js" / "controls" / "OrbitControls.js";
  for (const auto& file : {three, orbit}) {
    if (!std::filesystem::is_regular_file(file)) {
      throw SceneError(file.string(), "", "is missing: the viewer inlines three.js from Debian's libjs-three "
                                          "(scripts/install-deps.sh installs it)");
    }
  }
  // The page reads a Float32Array, in the machine's byte order: little-endian everywhere
  // a browser runs.
  static_assert(sizeof(float) == 4 && std::endian::native == std::endian::little);
  const std::string page = fill_template(
      kViewTemplate,
      {{"/*LIEDYN_THREE_JS*/", script_safe(read(three, "three.js"))},
       {"/*LIEDYN_ORBIT_CONTROLS_JS*/", script_safe(read(orbit, "OrbitControls.js"))},
       {"/*LIEDYN_META_JSON*/", json_script_safe(meta.dump())},
       {"/*LIEDYN_FRAMES_BASE64*/",
        base64(reinterpret_cast<const unsigned char*>(poses.data()), poses.size() * sizeof(float))}});

  OutputFolder folder(run_dir, "view", nullptr);
  folder.add("view.html") << page;
  folder.commit();
  ViewSummary summary;
  summary.frames = static_cast<int>(frame_numbers.size());
  summary.objects = static_cast<int>(meta["bodies"].size() + meta["rods"].size() + meta["colliders"].size());
  summary.bytes = page.size();
  return summary;
}

}  // namespace liedyn

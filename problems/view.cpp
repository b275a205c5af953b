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
#include "recorded_run.hpp"
#include "scene.hpp"
#include "view_template.hpp"  // kViewTemplate: problems/viewer/view_template.html, generated

namespace liedyn {
namespace {

using ordered_json = nlohmann::ordered_json;
constexpr std::uintmax_t kMaxScript = std::uintmax_t(64) << 20;  // three.js is 0.6 MB

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
  const RecordedRun run = read_recorded_run(run_dir);
  // Bodies: position and orientation; nodes: position; edges: the frame (their midpoint
  // follows from the nodes).
  std::vector<float> poses;
  for (std::size_t f = 0; f < run.frame_count(); ++f) {
    for (std::size_t r = 0; r < run.rows.size(); ++r) {
      const std::string& kind = run.rows[r].kind;
      const double* pose = run.pose(f, r);
      for (int c = kind == "edge" ? 3 : 0; c < (kind == "node" ? 3 : 7); ++c) poses.push_back(static_cast<float>(pose[c]));
    }
  }

  // frames.csv: the series at the written frames (null where it has no row).
  ordered_json series = ordered_json::object();
  if (run.frames) {
    const std::map<std::string, std::string> wanted = {{"kinetic_energy", "kinetic_energy"},
                                                       {"potential_energy", "potential_energy"},
                                                       {"newton_iterations", "iterations"},
                                                       {"max_penetration", "max_penetration"}};
    std::map<int, std::size_t> row_of_frame;
    for (std::size_t i = 0; i < run.frames->frames.size(); ++i) row_of_frame[run.frames->frames[i]] = i;
    for (const auto& [column, key] : wanted) {
      if (!run.frames->has(column)) continue;
      const std::vector<double> numbers = run.frames->numbers(column);
      ordered_json values = ordered_json::array();
      for (const int k : run.frame_numbers) {
        const auto it = row_of_frame.find(k);
        values.push_back(it == row_of_frame.end() ? ordered_json(nullptr) : ordered_json(numbers[it->second]));
      }
      series[key] = values;
    }
  }

  const ordered_json& shapes = run.shapes;
  ordered_json meta = {{"title", shapes.value("title", run_dir.string())},
                       {"time_step", shapes.value("time_step", 0.0)},
                       {"frame_numbers", run.frame_numbers},
                       {"times", run.times},
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
      {{"/*LIEDYN_THREE_JS*/", script_safe(read_named_input(three, kMaxScript, "three.js"))},
       {"/*LIEDYN_ORBIT_CONTROLS_JS*/", script_safe(read_named_input(orbit, kMaxScript, "OrbitControls.js"))},
       {"/*LIEDYN_META_JSON*/", json_script_safe(meta.dump())},
       {"/*LIEDYN_FRAMES_BASE64*/",
        base64(reinterpret_cast<const unsigned char*>(poses.data()), poses.size() * sizeof(float))}});

  OutputFolder folder(run_dir, "view", nullptr);
  folder.add("view.html") << page;
  folder.commit();
  ViewSummary summary;
  summary.frames = static_cast<int>(run.frame_count());
  summary.objects = static_cast<int>(meta["bodies"].size() + meta["rods"].size() + meta["colliders"].size());
  summary.bytes = page.size();
  return summary;
}

}  // namespace liedyn

#include "recorded_run.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "scene.hpp"

namespace liedyn {
namespace {

using ordered_json = nlohmann::ordered_json;
constexpr std::uintmax_t kMaxInput = std::uintmax_t(4) << 30;  // 4 GiB: a long rod run

// Far more rows per frame than any scene has (a rod of 10⁶ edges): an edited shapes.json
// must not make us allocate for ever.
constexpr std::size_t kMaxRowsPerFrame = 10'000'000;

[[noreturn]] void fail_at(const std::string& source, int line, const std::string& reason) {
  throw SceneError(source, "line " + std::to_string(line), reason);
}

double number_at(const std::string& field, const char* what, const std::string& source, int line) {
  char* end = nullptr;
  const double value = std::strtod(field.c_str(), &end);
  if (field.empty() || end != field.c_str() + field.size()) {
    fail_at(source, line, std::string(what) + " \"" + field + "\" is not a number");
  }
  return value;
}

// A frame number: a whole number from 0 to 2³¹ − 1.
int frame_at(const std::string& field, const std::string& source, int line) {
  const double value = number_at(field, "frame", source, line);
  if (!(value >= 0.0 && value <= 2147483647.0 && value == std::floor(value))) {
    fail_at(source, line, "frame \"" + field + "\" is not a frame number");
  }
  return static_cast<int>(value);
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
  const std::string& source() const { return source_; }
  [[noreturn]] void fail(const std::string& reason) const { fail_at(source_, number_, reason); }

 private:
  std::string text_, source_;
  std::size_t at_ = 0;
  int number_ = 0;
};

std::vector<RecordedRun::Row> expected_rows(const ordered_json& shapes, const std::string& source) {
  std::vector<RecordedRun::Row> rows;
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

}  // namespace

CsvTable read_csv_table(const std::filesystem::path& file, const std::string& what,
                        const std::string& first_column) {
  return parse_csv_table(read_named_input(file, kMaxInput, what), file.string(), what, first_column);
}

CsvTable parse_csv_table(std::string text, const std::string& source, const std::string& what,
                         const std::string& first_column) {
  CsvTable table;
  table.source = source;
  Lines lines(std::move(text), table.source);
  std::string line;
  if (!lines.next(line)) lines.fail("is empty (no header)");
  table.names = csv_fields(line);
  if (table.names[0] != first_column) {
    lines.fail("is not " + what + "'s header (no " + first_column + " column first)");
  }
  while (lines.next(line)) {
    if (line.empty()) continue;
    std::vector<std::string> f = csv_fields(line);
    if (f.size() != table.names.size()) {
      lines.fail("has " + std::to_string(f.size()) + " fields, the header " + std::to_string(table.names.size()));
    }
    table.lines.push_back(lines.line());
    table.rows.push_back(std::move(f));
  }
  return table;
}

FramesTable read_frames_table(const std::filesystem::path& file) {
  FramesTable table{read_csv_table(file, "frames.csv", "frame"), {}};
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    table.frames.push_back(frame_at(table.rows[r][0], table.source, table.lines[r]));
  }
  return table;
}

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

bool CsvTable::has(const std::string& column) const {
  for (const std::string& name : names) {
    if (name == column) return true;
  }
  return false;
}

std::size_t CsvTable::column(const std::string& name) const {
  std::size_t c = 0;
  while (c < names.size() && names[c] != name) ++c;
  if (c == names.size()) throw SceneError(source, name, "is not a column of this file");
  return c;
}

std::vector<double> CsvTable::numbers(const std::string& column) const {
  const std::size_t c = this->column(column);
  std::vector<double> values;
  values.reserve(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    values.push_back(rows[r][c].empty() ? std::numeric_limits<double>::quiet_NaN()
                                        : number_at(rows[r][c], column.c_str(), source, lines[r]));
  }
  return values;
}

RecordedRun read_recorded_run(const std::filesystem::path& run_dir) {
  RecordedRun run;
  run.dir = run_dir;
  const std::filesystem::path shapes_file = run_dir / "shapes.json";
  try {
    run.shapes = ordered_json::parse(read_named_input(shapes_file, kMaxInput, "shapes.json"));
  } catch (const nlohmann::json::exception& e) {
    throw SceneError(shapes_file.string(), "", std::string("is not JSON (") + e.what() + ")");
  }
  run.rows = expected_rows(run.shapes, shapes_file.string());

  // trajectory.csv: every written frame's rows, the objects of shapes.json in order.
  const std::filesystem::path trajectory_file = run_dir / "trajectory.csv";
  Lines lines(read_named_input(trajectory_file, kMaxInput, "trajectory.csv"), trajectory_file.string());
  std::string line;
  if (!lines.next(line) || line != "frame,time,object,kind,index,x,y,z,qw,qx,qy,qz") {
    lines.fail("is not trajectory.csv's header");
  }
  std::size_t row = 0;
  const std::string& source = lines.source();
  while (lines.next(line)) {
    if (line.empty()) continue;
    const std::vector<std::string> f = csv_fields(line);
    if (f.size() != 12) lines.fail("has " + std::to_string(f.size()) + " fields, not 12");
    const RecordedRun::Row& expected = run.rows[row];
    if (f[2] != expected.object || f[3] != expected.kind || f[4] != std::to_string(expected.index)) {
      lines.fail("is " + f[2] + " " + f[3] + " " + f[4] + " where shapes.json has " + expected.object + " " +
                 expected.kind + " " + std::to_string(expected.index) + " (not the same run?)");
    }
    if (row == 0) {
      run.frame_numbers.push_back(frame_at(f[0], source, lines.line()));
      run.times.push_back(number_at(f[1], "time", source, lines.line()));
    }
    // Nodes have no rotation: their qw … qz fields are empty.
    const int last = expected.kind == "node" ? 8 : 12;
    for (int c = 5; c < 12; ++c) {
      run.poses.push_back(c < last ? number_at(f[c], "a coordinate", source, lines.line())
                                   : std::numeric_limits<double>::quiet_NaN());
    }
    row = (row + 1) % run.rows.size();
  }
  if (row != 0) lines.fail("ends within a frame");
  if (run.frame_numbers.empty()) lines.fail("holds no frame");

  const std::filesystem::path frames_file = run_dir / "frames.csv";
  if (std::filesystem::exists(frames_file)) run.frames = read_frames_table(frames_file);
  return run;
}

}  // namespace liedyn

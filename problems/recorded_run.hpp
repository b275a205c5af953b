#pragma once
// A run's output folder read back: shapes.json, trajectory.csv and frames.csv as `liedyn
// simulate` (or optimize's best run, or Python's Trajectory.to_csv) writes them, checked to be
// one run — every written frame's trajectory rows are the objects of shapes.json, in order.
// What `liedyn view`, `liedyn export` and `liedyn plot` draw from. The CSV tables are read
// by one reader, frames.csv's and `liedyn optimize`'s history.csv and starts.csv alike.
//
// Bad or missing files are a SceneError naming the file, the line or field, and the reason.

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace liedyn {

// The fields of one CSV line (RFC 4180 quoting, as csv_field writes).
std::vector<std::string> csv_fields(const std::string& line);

// A CSV file with a header line, its rows by column name; every row has the header's fields.
struct CsvTable {
  std::string source;                      // the file, for messages
  std::vector<std::string> names;          // the header
  std::vector<std::vector<std::string>> rows;
  std::vector<int> lines;                  // each row's line in the file

  bool has(const std::string& column) const;
  // The index of a column; SceneError naming file and column if there is none.
  std::size_t column(const std::string& name) const;
  // A numeric column; a field that is not a number is a SceneError naming file, line and
  // column; an empty field is NaN (e.g. min_rod_separation where rods cannot touch).
  std::vector<double> numbers(const std::string& column) const;
};

// frames.csv: one row per simulated frame (every frame, whatever --every), by column name.
struct FramesTable : CsvTable {
  std::vector<int> frames;                 // each row's frame number (column "frame")
};

// FILE as a CSV table whose header's first column is `first_column`; `what` names the file in
// messages ("history.csv"). Empty lines are skipped.
CsvTable read_csv_table(const std::filesystem::path& file, const std::string& what,
                        const std::string& first_column);
// The same of CSV text (a file about to be written), `source` naming it in messages.
CsvTable parse_csv_table(std::string text, const std::string& source, const std::string& what,
                         const std::string& first_column);
// A frames.csv alone, without the trajectory (`liedyn plot` needs no more).
FramesTable read_frames_table(const std::filesystem::path& file);

struct RecordedRun {
  // One frame's rows of trajectory.csv, from shapes.json: bodies, then each rod's nodes and
  // then its edges.
  struct Row {
    std::string object, kind;  // kind: "body", "node" or "edge"
    int index = 0;
  };
  static constexpr int kPoseSize = 7;  // x, y, z, qw, qx, qy, qz (nodes: no rotation, NaN)

  std::filesystem::path dir;
  nlohmann::ordered_json shapes;  // shapes.json (problems/shapes.hpp)
  std::vector<Row> rows;
  std::vector<int> frame_numbers;  // the written frames (trajectory.csv's)
  std::vector<double> times;
  std::vector<double> poses;       // frame-major: poses[(f · rows + r) · 7 + c]
  std::optional<FramesTable> frames;  // frames.csv, when the folder has it

  std::size_t frame_count() const { return frame_numbers.size(); }
  const double* pose(std::size_t frame, std::size_t row) const {
    return poses.data() + (frame * rows.size() + row) * kPoseSize;
  }
};

// Reads RUN_DIR's shapes.json and trajectory.csv (both required) and frames.csv (if present).
RecordedRun read_recorded_run(const std::filesystem::path& run_dir);

}  // namespace liedyn

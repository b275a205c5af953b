#pragma once
// Output files written atomically: rows (or binary data, e.g. a PNG: the stream is opened in
// binary mode) go to "<name>.tmp-<pid>" beside the target, and commit() renames it over the
// target, so an existing file is replaced only by a complete one. A file that is never
// committed is removed.

#include <filesystem>
#include <fstream>
#include <string>

namespace liedyn {

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ostream& stream() { return stream_; }
  // Flushes, checks for write errors and renames into place; throws std::runtime_error.
  void commit();

 private:
  std::filesystem::path target_, temporary_;
  std::ofstream stream_;
  bool committed_ = false;
};

// RFC 4180: a field holding a comma, a quote or a line break is quoted, its quotes doubled.
std::string csv_field(const std::string& text);

// `value` with `digits` significant digits; "nan" for NaN.
std::string format_number(double value, int digits);

// `text` as a JSON string literal, quotes included (", \ and control characters escaped).
std::string json_quoted(const std::string& text);

}  // namespace liedyn

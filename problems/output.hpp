#pragma once
// Output files written atomically: rows go to "<name>.tmp-<pid>" beside the target, and
// commit() renames it over the target, so an existing file is replaced only by a complete
// one. A file that is never committed is removed.

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

// `text` as a JSON string literal, quotes included (", \ and control characters escaped).
std::string json_quoted(const std::string& text);

}  // namespace liedyn

#pragma once
// Output files that cannot be clobbered, half-written or redirected.
//
// A scene file is untrusted input and output folders may be shared with other users or runs,
// so every file liedyn writes is first written to a temporary whose name nobody can predict,
// created with O_CREAT | O_EXCL | O_NOFOLLOW (a planted file or symlink of that name makes the
// open fail instead of redirecting the write), in the folder of its target, and renamed over
// the target only once it is complete. rename(2) replaces a symlink at the target rather than
// writing through it. Temporaries are removed on every exit path: by the destructor, and on
// SIGINT, SIGTERM and SIGHUP by a handler that removes them and exits with 128 + signal
// (install_output_signal_handlers, called once by the command-line driver).
//
// A single file is an AtomicFile; the files of one run, replaced together, are an
// OutputFolder (output_folder.hpp).

#include <filesystem>
#include <memory>
#include <ostream>
#include <string>

namespace liedyn {

// An ostream writing to a file descriptor it owns, with the first write error kept (errno
// text) so that commit() can report it; ENOSPC and EFBIG surface here, or at fsync.
class FileStream {
 public:
  explicit FileStream(int fd);
  ~FileStream();
  FileStream(const FileStream&) = delete;
  FileStream& operator=(const FileStream&) = delete;

  std::ostream& stream();
  // Flushes, fsyncs (delayed allocation reports a full disk only there) and closes; throws
  // std::runtime_error naming `what` and the reason if any write failed.
  void finish(const std::string& what);

 private:
  class Buffer;
  std::unique_ptr<Buffer> buffer_;
  std::ostream stream_;
};

class AtomicFile {
 public:
  // The temporary is ".<name>.liedyn-XXXXXX" beside `target` (created now; throws
  // std::runtime_error if the folder is not writable).
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ostream& stream() { return file_->stream(); }
  // Flushes, checks for write errors and renames into place; throws std::runtime_error
  // (the target is then untouched and the temporary removed).
  void commit();

 private:
  std::filesystem::path target_;
  std::string temporary_;  // name inside the target's folder
  int dirfd_ = -1;         // the target's folder: renamed within it whatever its path does
  std::unique_ptr<FileStream> file_;
  int cleanup_slot_ = -1;
  bool committed_ = false;
};

// Installs the SIGINT / SIGTERM / SIGHUP handler that removes every temporary and staging
// folder still registered, then exits with 128 + signal; and ignores SIGXFSZ, so that a file
// size limit (ulimit -f) is a write error reported like a full disk, not a crash.
void install_output_signal_handlers();

// RFC 4180: a field holding a comma, a quote or a line break is quoted, its quotes doubled.
std::string csv_field(const std::string& text);

// `value` with `digits` significant digits; "nan" for NaN.
std::string format_number(double value, int digits);

// `text` as a JSON string literal, quotes included (", \ and control characters escaped).
std::string json_quoted(const std::string& text);

}  // namespace liedyn

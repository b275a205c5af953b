#pragma once
// Files liedyn is given to read (scenes, meshes): untrusted, so read only when they are
// regular files below a size limit. A FIFO would block for ever, /dev/zero would be read
// until memory runs out, and a huge file would be held whole in memory before any check.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace liedyn {

// Why an input file was not read; what() is the reason alone (callers name the file).
class InputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The whole content of `file`. Throws InputFileError when it does not exist, is a directory
// ("is a directory, not a <kind>"), is not a regular file (a FIFO, socket or device), cannot
// be opened or read, or holds more than max_bytes (tested on the size and again while
// reading, for a file that grows).
std::string read_input_file(const std::filesystem::path& file, std::uintmax_t max_bytes,
                            const std::string& kind);

}  // namespace liedyn

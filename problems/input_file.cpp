#include "input_file.hpp"

#include <fstream>
#include <system_error>

namespace liedyn {

std::string read_input_file(const std::filesystem::path& file, std::uintmax_t max_bytes,
                            const std::string& kind) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) throw InputFileError("no such file");
  if (std::filesystem::is_directory(status)) {
    throw InputFileError("is a directory, not a " + kind);
  }
  if (!std::filesystem::is_regular_file(status)) {
    throw InputFileError("is not a regular file (a FIFO, socket or device)");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputFileError("cannot open the file for reading");
  const auto too_large = [&](std::uintmax_t size, bool exact) {
    return InputFileError("is " + std::string(exact ? "" : "at least ") + std::to_string(size) +
                          " bytes, more than a " + kind +
                          " may be (" + std::to_string(max_bytes) + ")");
  };
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (!ec && size > max_bytes) throw too_large(size, true);
  std::string text;
  text.reserve(ec ? 0 : static_cast<std::size_t>(size));
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes) throw too_large(text.size(), false);
  }
  if (in.bad()) throw InputFileError("read error");
  return text;
}

}  // namespace liedyn

#include "output.hpp"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include <unistd.h>

#include <stdexcept>
#include <system_error>

namespace liedyn {

AtomicFile::AtomicFile(std::filesystem::path target)
    : target_(std::move(target)),
      temporary_(target_.string() + ".tmp-" + std::to_string(::getpid())) {
  stream_.open(temporary_, std::ios::out | std::ios::trunc | std::ios::binary);
  if (!stream_) throw std::runtime_error(temporary_.string() + ": cannot open for writing");
  stream_.precision(17);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    stream_.close();
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
  }
}

void AtomicFile::commit() {
  stream_.flush();
  const bool ok = static_cast<bool>(stream_);
  stream_.close();
  if (!ok) throw std::runtime_error(temporary_.string() + ": write failed");
  std::error_code error;
  std::filesystem::rename(temporary_, target_, error);
  if (error) {
    throw std::runtime_error(target_.string() + ": cannot rename into place: " + error.message());
  }
  committed_ = true;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char ch : text) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return out + "\"";
}

std::string format_number(double value, int digits) {
  if (std::isnan(value)) return "nan";
  std::ostringstream os;
  os << std::setprecision(digits) << value;
  return os.str();
}

std::string json_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char ch : text) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", static_cast<unsigned>(ch));
      out += code;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

}  // namespace liedyn

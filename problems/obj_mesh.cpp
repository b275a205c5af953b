#include "obj_mesh.hpp"

#include <tiny_obj_loader.h>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include "input_file.hpp"

// Coordinates are parsed in double precision: build against the tinyobjloader_double library
// (CMake target tinyobjloader::tinyobjloader_double, which defines TINYOBJLOADER_USE_DOUBLE).
// Both libraries export the same symbols, so mixing this header setting with the float library
// would link silently and misread every vertex: the check below makes it a compile error, and
// double_library_linked() a runtime error for a hand-made build that defines the macro but
// links -ltinyobjloader.
static_assert(std::is_same_v<tinyobj::real_t, double>,
              "problems/obj_mesh.cpp needs TINYOBJLOADER_USE_DOUBLE and libtinyobjloader_double "
              "(CMake: link tinyobjloader::tinyobjloader_double)");

namespace liedyn {
namespace {

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& reason) {
  throw std::runtime_error("load_obj_mesh: '" + file.string() + "': " + reason);
}

// A library parsing into float vectors hands back a vector<float> read as vector<double>:
// 3 floats look like 1 double. Parsed once.
bool double_library_linked() {
  static const bool ok = [] {
    tinyobj::ObjReader reader;
    tinyobj::ObjReaderConfig config;
    config.vertex_color = false;
    if (!reader.ParseFromString("v 0.25 0.5 2\n", "", config)) return false;
    const std::vector<tinyobj::real_t>& v = reader.GetAttrib().vertices;
    return v.size() == 3 && v[0] == 0.25 && v[1] == 0.5 && v[2] == 2.0;
  }();
  return ok;
}

// The text of one OBJ token for a message: at most 40 bytes, control bytes as '?'.
std::string quoted(std::string_view token) {
  std::string s(token.substr(0, 40));
  for (char& ch : s) {
    if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) ch = '?';
  }
  return "'" + s + (token.size() > 40 ? "...'" : "'");
}

// Reads one coordinate token strictly: the whole token must be a decimal number (an optional
// sign, digits with an optional point, an optional exponent), as std::from_chars reads it
// (locale-independent, correctly rounded), and finite. tinyobjloader's own parser reads "abc",
// "nan" and "0x10" as 0 and "1.5.3" as 1.5 without a word: each would put a vertex somewhere
// the file does not say. Returns an empty string, or the reason the token is refused.
std::string check_coordinate(std::string_view token) {
  std::string_view digits = token;
  // from_chars takes no '+' (and "+-1" is no number).
  if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-') digits.remove_prefix(1);
  double value = 0.0;
  const char* const end = digits.data() + digits.size();
  const auto [ptr, ec] = std::from_chars(digits.data(), end, value);
  if (ptr != end || (ec != std::errc() && ec != std::errc::result_out_of_range)) {
    return quoted(token) + " is not a number";
  }
  if (ec == std::errc::result_out_of_range) {
    // Underflow (1e-400) is a tiny number, as tinyobjloader reads it; overflow is not finite.
    value = std::strtod(std::string(digits).c_str(), nullptr);
  }
  if (!std::isfinite(value)) return quoted(token) + " is not finite";
  return {};
}

// Checks what tinyobjloader does not (it reads text as C strings, and a malformed coordinate
// as 0): no NUL byte anywhere, and every vertex line `v x y z ...` with three coordinates that
// are finite decimal numbers (check_coordinate). Lines are split as tinyobjloader splits them
// (at "\n", "\r\n" or a lone "\r"), and a vertex line is what it takes for one (optional
// spaces or tabs, 'v', a space or tab), so the k-th vertex line found here is its k-th vertex:
// returns the 1-based line of every vertex, for the messages. Values after z (w, or the r g b
// of the vertex-colour extension) are not read.
std::vector<std::size_t> check_text(const std::filesystem::path& file, const std::string& text) {
  std::vector<std::size_t> vertex_lines;
  std::size_t line = 1;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find_first_of("\r\n", begin);
    if (end == std::string::npos) end = text.size();
    const std::string_view row(text.data() + begin, end - begin);
    if (const std::size_t nul = row.find('\0'); nul != std::string_view::npos) {
      fail(file, "line " + std::to_string(line) + ": a NUL byte (byte " +
                     std::to_string(begin + nul + 1) + " of the file): not a text OBJ file");
    }
    std::size_t i = row.find_first_not_of(" \t");
    if (i != std::string_view::npos && row[i] == 'v' && i + 1 < row.size() &&
        (row[i + 1] == ' ' || row[i + 1] == '\t')) {
      const auto where = [&] {  // built only for a message
        return "line " + std::to_string(line) + ": vertex " +
               std::to_string(vertex_lines.size() + 1) + " (1-based): ";
      };
      i += 2;
      static const char* const kAxis[] = {"x", "y", "z"};
      for (int axis = 0; axis < 3; ++axis) {
        i = row.find_first_not_of(" \t", i);
        if (i == std::string_view::npos) {
          fail(file, where() + "has " + std::to_string(axis) +
                         " coordinates, expected x y z (a missing one is not read as 0)");
        }
        std::size_t stop = row.find_first_of(" \t", i);
        if (stop == std::string_view::npos) stop = row.size();
        const std::string reason = check_coordinate(row.substr(i, stop - i));
        if (!reason.empty()) fail(file, where() + kAxis[axis] + " = " + reason);
        i = stop;
      }
      vertex_lines.push_back(line);
    }
    if (end == text.size()) break;
    begin = end + (text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n' ? 2 : 1);
    ++line;
  }
  return vertex_lines;
}

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s;
}

}  // namespace

TriangleMesh load_obj_mesh(const std::filesystem::path& file, double scale) {
  if (!std::isfinite(scale) || !(scale > 0.0)) {
    std::ostringstream s;
    s.precision(17);
    s << "load_obj_mesh: scale must be finite and > 0, got " << scale;
    throw std::invalid_argument(s.str());
  }
  std::string text;
  try {
    text = read_input_file(file, kMaxMeshFileBytes, "mesh file");
  } catch (const InputFileError& e) {
    fail(file, e.what());
  }
  if (!double_library_linked()) {
    fail(file,
         "tinyobjloader does not parse in double precision: link libtinyobjloader_double "
         "(CMake target tinyobjloader::tinyobjloader_double), not libtinyobjloader");
  }

  const std::vector<std::size_t> vertex_lines = check_text(file, text);

  // ParseFromString ignores `mtllib`: materials are never read.
  tinyobj::ObjReader reader;
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  if (!reader.ParseFromString(text, "", config)) {
    fail(file, "parse error: " + trimmed(reader.Error()));
  }

  const std::vector<tinyobj::real_t>& coords = reader.GetAttrib().vertices;
  if (coords.size() != 3 * vertex_lines.size()) {
    fail(file, "tinyobjloader read " + std::to_string(coords.size() / 3) + " vertices, but the file has " +
                   std::to_string(vertex_lines.size()) + " vertex lines");
  }
  TriangleMesh mesh;
  mesh.vertices.reserve(coords.size() / 3);
  for (std::size_t i = 0; i + 2 < coords.size(); i += 3) {
    const Vector3 x = scale * Vector3(coords[i], coords[i + 1], coords[i + 2]);
    if (!x.allFinite()) {
      std::ostringstream s;
      s << "line " << vertex_lines[i / 3] << ": vertex " << i / 3 + 1
        << " (1-based) is not finite after scaling by " << scale << ": ("
        << coords[i] << ", " << coords[i + 1] << ", " << coords[i + 2] << ")";
      fail(file, s.str());
    }
    mesh.vertices.push_back(x);
  }
  const long nv = static_cast<long>(mesh.vertices.size());
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    const std::vector<tinyobj::index_t>& idx = shape.mesh.indices;
    std::size_t offset = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
      const std::size_t n = shape.mesh.num_face_vertices[f];
      if (n != 3) {
        fail(file, "face " + std::to_string(f + 1) + " of shape '" + shape.name + "' has " +
                       std::to_string(n) + " vertices after triangulation (expected 3)");
      }
      if (offset + n > idx.size()) fail(file, "tinyobjloader returned truncated face indices");
      std::array<int, 3> t{};
      for (std::size_t k = 0; k < 3; ++k) {
        const int i = idx[offset + k].vertex_index;
        if (i < 0 || i >= nv) {
          fail(file, "face " + std::to_string(f + 1) + " of shape '" + shape.name +
                         "' uses vertex " + std::to_string(static_cast<long>(i) + 1) +
                         " (1-based), but the file has " + std::to_string(nv) + " vertices");
        }
        t[k] = i;
      }
      mesh.triangles.push_back(t);
      offset += n;
    }
  }
  if (mesh.triangles.empty()) {
    const std::string warning = trimmed(reader.Warning());
    fail(file, "no faces (no 'f' lines with 3 or more vertices)" +
                   (warning.empty() ? std::string() : "; tinyobjloader: " + warning));
  }
  return mesh;
}

}  // namespace liedyn

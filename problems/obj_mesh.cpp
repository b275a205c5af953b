#include "obj_mesh.hpp"

#include <tiny_obj_loader.h>

#include <cmath>
#include <cstddef>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>

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
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) fail(file, "no such file");
  if (std::filesystem::is_directory(status)) fail(file, "is a directory, not an OBJ file");
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, "cannot be opened for reading");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(file, "read error");
  if (!double_library_linked()) {
    fail(file,
         "tinyobjloader does not parse in double precision: link libtinyobjloader_double "
         "(CMake target tinyobjloader::tinyobjloader_double), not libtinyobjloader");
  }

  // ParseFromString ignores `mtllib`: materials are never read.
  tinyobj::ObjReader reader;
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  if (!reader.ParseFromString(text, "", config)) {
    fail(file, "parse error: " + trimmed(reader.Error()));
  }

  const std::vector<tinyobj::real_t>& coords = reader.GetAttrib().vertices;
  TriangleMesh mesh;
  mesh.vertices.reserve(coords.size() / 3);
  for (std::size_t i = 0; i + 2 < coords.size(); i += 3) {
    const Vector3 x = scale * Vector3(coords[i], coords[i + 1], coords[i + 2]);
    if (!x.allFinite()) {
      std::ostringstream s;
      s << "vertex " << i / 3 + 1 << " (1-based) is not finite after scaling by " << scale << ": ("
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

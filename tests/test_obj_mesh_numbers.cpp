// Bad numbers and bytes in OBJ files (problems/obj_mesh.hpp; issue 17, item 10): a vertex
// coordinate that is not a finite decimal number, a missing coordinate and a NUL byte are
// refused naming the file and the line — tinyobjloader alone reads "nan" and "abc" as 0 —
// and in a scene the refusal is a SceneError on the collider's "file".

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>

#include "problems/obj_mesh.hpp"
#include "problems/scene.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;

// A fresh directory for files a test writes, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device rd;
    path_ = fs::temp_directory_path() /
            ("liedyn_test_obj_numbers_" + std::string(info->name()) + "_" + std::to_string(rd()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = path_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

 private:
  fs::path path_;
};

// A closed tetrahedron (outward faces) with its first vertex line replaced by `first`, and
// `before` in front: the bad line is line 1 + (lines in `before`).
std::string tetrahedron(const std::string& first, const std::string& before = "") {
  return before + first + "\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
}

// "'<file>': <rest>", as the loader's messages name a file. (Appended, not by operator+ on a
// literal: GCC 12 warns falsely, -Wrestrict, about the inlined copies of the latter.)
std::string in_file(const fs::path& file, const std::string& rest) {
  std::string s = "'";
  s += file.string();
  s += "': ";
  s += rest;
  return s;
}

std::string loader_error(const fs::path& file) {
  try {
    load_obj_mesh(file);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(ObjMeshNumbers, TheTetrahedronLoads) {
  TempDir dir;
  const TriangleMesh m = load_obj_mesh(dir.write("ok.obj", tetrahedron("v 0 0 0")));
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.triangles.size(), 4u);
  // Forms tinyobjloader and from_chars both read: signs, leading or trailing points,
  // exponents, a w, vertex colours, tabs, CRLF, an underflowing tiny number.
  const TriangleMesh n = load_obj_mesh(dir.write(
      "forms.obj", "v\t+0.0 -0. .0 1.0\r\nv 1e0 0 0 0.5 0.5 0.5\nv 0 1 0 # comment\nv 0 1e-400 1\n"
                   "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"));
  EXPECT_EQ(n.vertices[1].x(), 1.0);
  EXPECT_EQ(n.vertices[3], Vector3(0, 0, 1));
}

TEST(ObjMeshNumbers, NonNumbersAndNonFiniteCoordinatesNameTheFileAndLine) {
  TempDir dir;
  struct Case {
    const char* name;
    std::string text;
    std::string expected;  // in the message, after the file name
  };
  const Case cases[] = {
      {"nan.obj", tetrahedron("v nan 0 0"), "line 1: vertex 1 (1-based): x = 'nan' is not finite"},
      {"abc.obj", tetrahedron("v 0 abc 0", "# a comment\n\n"),
       "line 3: vertex 1 (1-based): y = 'abc' is not a number"},
      {"inf.obj", tetrahedron("v 0 0 -inf"), "line 1: vertex 1 (1-based): z = '-inf' is not finite"},
      {"huge.obj", tetrahedron("v 1e999 0 0"), "line 1: vertex 1 (1-based): x = '1e999' is not finite"},
      {"hex.obj", tetrahedron("v 0x10 0 0"), "line 1: vertex 1 (1-based): x = '0x10' is not a number"},
      {"dots.obj", tetrahedron("v 1.5.3 0 0"), "line 1: vertex 1 (1-based): x = '1.5.3' is not a number"},
      {"signs.obj", tetrahedron("v +-1 0 0"), "line 1: vertex 1 (1-based): x = '+-1' is not a number"},
      {"missing.obj", tetrahedron("v 0 0"), "line 1: vertex 1 (1-based): has 2 coordinates"},
      // The second vertex, on line 2 (CR line ends count as tinyobjloader counts them).
      {"second.obj", "v 0 0 0\rv 1 NaN 0\rv 0 1 0\rv 0 0 1\rf 1 3 2\rf 1 2 4\rf 1 4 3\rf 2 3 4\r",
       "line 2: vertex 2 (1-based): y = 'NaN' is not finite"},
  };
  for (const Case& c : cases) {
    const fs::path file = dir.write(c.name, c.text);
    const std::string msg = loader_error(file);
    EXPECT_NE(msg.find(in_file(file, c.expected)), std::string::npos)
        << c.name << ": " << msg;
  }
}

TEST(ObjMeshNumbers, NulBytesAreRefused) {
  TempDir dir;
  // After the vertices (tinyobjloader would stop reading the line there), and inside a number.
  const fs::path after = dir.write("nul.obj", tetrahedron("v 0 0 0") + std::string("f 1 2\0 3\n", 9));
  std::string msg = loader_error(after);
  EXPECT_NE(msg.find(in_file(after, "line 9: a NUL byte")), std::string::npos) << msg;
  const fs::path inside = dir.write("nul2.obj", tetrahedron(std::string("v 0 0 1\0", 8) + "5"));
  msg = loader_error(inside);
  EXPECT_NE(msg.find("line 1: a NUL byte (byte 8 of the file)"), std::string::npos) << msg;
}

TEST(ObjMeshNumbers, InASceneTheRefusalIsASceneErrorOnTheColliderFile) {
  TempDir dir;
  const fs::path file = dir.write("bad.obj", tetrahedron("v 0 0 0", "v 0 0 0\nv 0 0 abc\n"));
  const std::string text = R"({"time_step": 0.01, "frames": 5, "colliders": [
      {"type": "mesh", "file": ")" + file.string() + R"(", "cell_size": 0.1}],
      "bodies": [{"name": "a", "mass": 2, "inertia": [1, 2, 2.5]}]})";
  try {
    parse_scene(text, "unit_scene.json");
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), "unit_scene.json");
    EXPECT_EQ(e.field(), "colliders[0].file");
    EXPECT_NE(e.reason().find(in_file(file, "line 2: vertex 2 (1-based): z = 'abc'")),
              std::string::npos)
        << e.reason();
  }
}

}  // namespace
}  // namespace liedyn

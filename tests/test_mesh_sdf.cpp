// Grid signed distance fields from closed triangle meshes (lib/mesh_sdf.hpp) and the OBJ
// loader (problems/obj_mesh.hpp).
//
// * Node values are exact distances: against the box SDF of lib/sdf.hpp (unit cube), against
//   an independent brute-force reference written here (plane projection + segment distances,
//   and the convex-polytope sign) for icospheres, and against the union of box SDFs for
//   non-convex voxel solids whose grid nodes sit exactly on mesh vertices, edges, faces and
//   the diagonal planes between them (the sign at edges and vertices is what pseudonormals
//   must get right).
// * Interpolation error bounds, derived beside each test, and their sign.
// * Derivatives of the interpolant against central differences (tests/fd_check.hpp) inside
//   cells and for the continuation outside the grid.
// * The continuation outside the grid: finite, continuous at the box, positive and growing.
// * Every documented error, by message.
//
// Finite differences (fd_check defaults: ε = 1e-6, rtol 1e-6, floor 1e-9 × largest entry,
// plus the computed round-off floor 16 eps·max|f|/ε). Inside a cell the interpolant is linear
// along every coordinate line, so the central difference of φ along an axis is EXACT but for
// round-off, and so is that of ∇φ (∂φ/∂x does not depend on x and is linear in y and z): no
// truncation error at all, only the round-off floor. Test points keep ≥ 1e-3 cells (5e-5 m ≫
// ε) from every cell face, so no difference straddles a face where ∇φ and ∇²φ jump. Outside
// the grid, the distance term d = ‖p − q‖ has third derivatives ~1/d² and fourth ~1/d³; with
// d ≥ 0.05 the truncation ε²/6·|∂³φ| ≤ 1e-10 (gradient) and ε²/6·|∂⁴φ| ≤ 2e-9 against
// |∇²φ| ~ 1/d = 20 (Hessian), far inside rtol; those points also keep ≥ 1e-3 cells from the
// box planes, so the set of clamped axes does not change within ±ε.

#include <gtest/gtest.h>
#include <sys/stat.h>  // mkfifo

#include <Eigen/Geometry>  // cross
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fd_check.hpp"
#include "lib/mesh_sdf.hpp"
#include "lib/sdf.hpp"
#include "problems/obj_mesh.hpp"
#include "problems/scene.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;

const fs::path kData = fs::path(LIEDYN_SOURCE_DIR) / "tests/data";

// ---------------------------------------------------------------------------------------
// Fixtures.

// A fresh directory for files a test writes, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device rd;
    path_ = fs::temp_directory_path() /
            ("liedyn_test_mesh_sdf_" + std::string(info->name()) + "_" + std::to_string(rd()));
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
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Unit icosahedron (outward, counter-clockwise) subdivided `level` times, vertices projected
// to the sphere of radius r about the origin: 20·4^level triangles.
TriangleMesh icosphere(int level, double r) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vector3> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                            {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                            {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (Vector3& x : v) x.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      const int id = static_cast<int>(v.size()) - 1;
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& t : f) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
  TriangleMesh m;
  for (const Vector3& x : v) m.vertices.push_back(r * x);
  m.triangles = f;
  return m;
}

// The surface of a union of unit voxels [i, i+1]×[j, j+1]×[k, k+1] (vertices on the integer
// lattice, shared), each boundary square split into two triangles, outward. Closed and
// manifold unless two voxels touch only along an edge or at a corner.
using Voxel = std::array<int, 3>;

TriangleMesh voxel_mesh(const std::vector<Voxel>& voxels) {
  const std::set<Voxel> filled(voxels.begin(), voxels.end());
  std::map<Voxel, int> ids;
  TriangleMesh m;
  const auto vertex = [&](const Voxel& x) {
    const auto it = ids.find(x);
    if (it != ids.end()) return it->second;
    m.vertices.emplace_back(x[0], x[1], x[2]);
    const int id = static_cast<int>(m.vertices.size()) - 1;
    ids.emplace(x, id);
    return id;
  };
  for (const Voxel& c : voxels) {
    for (std::size_t a = 0; a < 3; ++a) {
      for (const int s : {-1, 1}) {
        Voxel n = c;
        n[a] += s;
        if (filled.count(n)) continue;
        // Square at x_a = c_a + (s > 0), corners (0,0), (1,0), (1,1), (0,1) in the cyclic
        // axes (b, d) = (a + 1, a + 2): normal e_b × e_d = +e_a; reversed for s < 0.
        const std::size_t b = (a + 1) % 3, d = (a + 2) % 3;
        std::array<int, 4> q{};
        const int corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int k = 0; k < 4; ++k) {
          Voxel x = c;
          x[a] += s > 0 ? 1 : 0;
          x[b] += corner[k][0];
          x[d] += corner[k][1];
          q[static_cast<std::size_t>(k)] = vertex(x);
        }
        if (s < 0) std::swap(q[1], q[3]);
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
      }
    }
  }
  return m;
}

// The exact SDF of a union of voxels outside it (min of the box SDFs); inside, min of the box
// SDFs is ≥ the true (negative) φ (the true depth is at least the depth in any one box), with
// the same sign. Box SDFs from lib/sdf.hpp.
double voxel_union_bound(const std::vector<Voxel>& voxels, const Vector3& p) {
  double phi = std::numeric_limits<double>::infinity();
  for (const Voxel& c : voxels) {
    Collider box;
    box.shape = BoxShape{Vector3::Constant(0.5), 0.0};
    box.position = Vector3(c[0] + 0.5, c[1] + 0.5, c[2] + 0.5);
    phi = std::min(phi, box.evaluate(p, false).distance);
  }
  return phi;
}

TriangleMesh read_cube() { return load_obj_mesh(kData / "unit_cube.obj"); }

// The unit cube [0, 1]³ of tests/data/unit_cube.obj as a lib/sdf.hpp collider.
Collider cube_collider() {
  Collider c;
  c.name = "cube";
  c.shape = BoxShape{Vector3::Constant(0.5), 0.0};
  c.position = Vector3::Constant(0.5);
  return c;
}

// ---------------------------------------------------------------------------------------
// Independent reference geometry (not lib/mesh_sdf.cpp's Ericson regions).

double point_segment(const Vector3& p, const Vector3& a, const Vector3& b) {
  const Vector3 e = b - a;
  const double t = std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * e)).norm();
}

// Distance to a triangle: to its plane if the projection falls inside, else to its edges.
double point_triangle(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
  const Vector3 n = (b - a).cross(c - a).normalized();
  const double h = (p - a).dot(n);
  const Vector3 x = p - h * n;
  const bool inside = (b - a).cross(x - a).dot(n) >= 0.0 && (c - b).cross(x - b).dot(n) >= 0.0 &&
                      (a - c).cross(x - c).dot(n) >= 0.0;
  if (inside) return std::abs(h);
  return std::min({point_segment(p, a, b), point_segment(p, b, c), point_segment(p, c, a)});
}

// Exact SDF of a CONVEX closed outward mesh: inside, the largest (negative) signed plane
// distance; outside (some plane distance > 0), the brute-force minimum over triangles.
double convex_mesh_sdf(const TriangleMesh& m, const Vector3& p) {
  double plane = -std::numeric_limits<double>::infinity();
  double nearest = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    const Vector3& a = m.vertices[static_cast<std::size_t>(t[0])];
    const Vector3& b = m.vertices[static_cast<std::size_t>(t[1])];
    const Vector3& c = m.vertices[static_cast<std::size_t>(t[2])];
    plane = std::max(plane, (p - a).dot((b - a).cross(c - a).normalized()));
    nearest = std::min(nearest, point_triangle(p, a, b, c));
  }
  return plane < 0.0 ? plane : nearest;
}

// Lipschitz bound of trilinear interpolation at p for any 1-Lipschitz φ:
//   |Iφ(p) − φ(p)| = |Σ w_abc (φ(x_abc) − φ(p))| ≤ Σ_abc w_abc ‖x_abc − p‖.
double lipschitz_bound(const Vector3& cell_lo, double h, const Vector3& p) {
  const Vector3 t = (p - cell_lo) / h;
  double s = 0.0;
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      for (int c = 0; c < 2; ++c) {
        const double w =
            (a ? t.x() : 1 - t.x()) * (b ? t.y() : 1 - t.y()) * (c ? t.z() : 1 - t.z());
        s += w * (cell_lo + h * Vector3(a, b, c) - p).norm();
      }
    }
  }
  return s;
}

// A random point in cell (i, j, k), ≥ `margin` cells from its faces.
Vector3 point_in_cell(const GridSdf& g, const Eigen::Vector3i& cell, double margin,
                      std::mt19937& rng) {
  std::uniform_real_distribution<double> t(margin, 1.0 - margin);
  return g.node_position(cell.x(), cell.y(), cell.z()) +
         g.cell_size() * Vector3(t(rng), t(rng), t(rng));
}

Eigen::Vector3i random_cell(const GridSdf& g, std::mt19937& rng) {
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a) {
    std::uniform_int_distribution<int> u(0, g.dimensions()(a) - 2);
    c(a) = u(rng);
  }
  return c;
}

// ∇φ and ∇²φ of g at p against central differences (header of this file).
void expect_derivatives(const GridSdf& g, const Vector3& p, int& nonzero_hessians) {
  SCOPED_TRACE(fd::trace("p", p.x(), p.y(), p.z()));
  State q;
  q.points = {p};
  const fd::Dofs dofs = {fd::point_dof(0)};
  const SdfValue v = g.evaluate(p);
  ASSERT_TRUE(std::isfinite(v.distance));
  ASSERT_GT(v.gradient.norm(), 1e-3) << "gradient must not vanish for the check to mean much";
  EXPECT_TRUE(fd::check_lie_gradient(
      [&](const State& s) { return g.evaluate(s.points[0], false).distance; }, q, dofs,
      Eigen::VectorXd(v.gradient)));
  // The Hessian is zero where the node values are affine over the cell (a flat face of the
  // cube): then the check still compares FD of a constant gradient with 0.
  fd::FdOptions opt;
  const bool nonzero = v.hessian.cwiseAbs().maxCoeff() > 1e-3;
  opt.require_nonzero = nonzero ? fd::NonZero::kAny : fd::NonZero::kNone;
  nonzero_hessians += nonzero ? 1 : 0;
  EXPECT_TRUE(fd::check_lie_hessian(
      [&](const State& s) { return Eigen::VectorXd(g.evaluate(s.points[0], false).gradient); }, q,
      dofs, Eigen::MatrixXd(v.hessian), opt));
  // with_hessian = false leaves the Hessian zero and changes nothing else.
  const SdfValue w = g.evaluate(p, false);
  EXPECT_EQ(w.distance, v.distance);
  EXPECT_EQ(w.gradient, v.gradient);
  EXPECT_EQ(w.hessian, Matrix3::Zero());
}

// Message of the std::invalid_argument thrown by GridSdf(mesh, ...), or "" if none.
std::string grid_error(const TriangleMesh& mesh, double h = 0.1, double padding = 0.1,
                       long max_cells = 20000000) {
  try {
    GridSdf g(mesh, h, padding, max_cells);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::string loader_error(const fs::path& file) {
  try {
    load_obj_mesh(file);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

constexpr double kExact = 1e-12;  // round-off of O(1) distances

// ---------------------------------------------------------------------------------------
// The OBJ loader.

TEST(ObjMesh, CubeQuadsAreTriangulatedKeepingOrientation) {
  const TriangleMesh m = read_cube();
  ASSERT_EQ(m.vertices.size(), 8u);
  ASSERT_EQ(m.triangles.size(), 12u);  // 6 quads
  for (const auto& t : m.triangles) {
    const Vector3& a = m.vertices[static_cast<std::size_t>(t[0])];
    const Vector3& b = m.vertices[static_cast<std::size_t>(t[1])];
    const Vector3& c = m.vertices[static_cast<std::size_t>(t[2])];
    const Vector3 n = (b - a).cross(c - a);
    EXPECT_NEAR(n.norm(), 1.0, kExact);                                 // half a unit square
    EXPECT_GT(n.dot((a + b + c) / 3.0 - Vector3::Constant(0.5)), 0.4);  // outward
  }
  const TriangleMesh scaled = load_obj_mesh(kData / "unit_cube.obj", 2.5);
  ASSERT_EQ(scaled.vertices.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(scaled.vertices[i], 2.5 * m.vertices[i]);
  EXPECT_EQ(scaled.triangles, m.triangles);
}

// A hexagonal prism written with hexagon caps (6-gons), negative (relative) indices and
// texture/normal indices: triangulated into a closed mesh whose SDF is negative inside.
TEST(ObjMesh, PolygonsRelativeIndicesAndRoundTrip) {
  TempDir dir;
  std::ostringstream obj;
  obj.precision(17);
  obj << "mtllib missing.mtl\no prism\nvt 0 0\nvn 0 0 1\n";
  for (const double z : {0.0, 1.0}) {
    for (int k = 0; k < 6; ++k) {
      const double a = k * std::numbers::pi / 3.0;
      obj << "v " << std::cos(a) << " " << std::sin(a) << " " << z << "\n";
    }
  }
  obj << "f 6 5 4 3 2 1\n";  // bottom, seen from below: clockwise from above
  obj << "f 7/1/1 8/1/1 9/1/1 10/1/1 11/1/1 12/1/1\n";  // top
  obj << "g sides\n";
  for (int k = 0; k < 6; ++k) {
    const int a = k + 1, b = (k + 1) % 6 + 1;
    // Relative indices: -12 is vertex 1 (12 vertices so far).
    obj << "f " << a - 13 << " " << b - 13 << " " << b + 6 - 13 << " " << a + 6 - 13 << "\n";
  }
  const TriangleMesh m = load_obj_mesh(dir.write("prism.obj", obj.str()));
  EXPECT_EQ(m.vertices.size(), 12u);
  EXPECT_EQ(m.triangles.size(), 2u * 4u + 6u * 2u);
  const GridSdf g(m, 0.1, 0.2);
  EXPECT_NEAR(g.evaluate(Vector3(0, 0, 0.5)).distance, -0.5, kExact);  // nearest: the caps
  EXPECT_NEAR(g.evaluate(Vector3(0, 0, 1.2)).distance, 0.2, kExact);   // above the top cap
  // 0.9 along the normal of a side (apothem √3/2) at mid-height: φ is affine over the cells
  // around (one face nearest), so exact.
  const Vector3 side(0.9 * std::cos(std::numbers::pi / 6), 0.9 * std::sin(std::numbers::pi / 6),
                     0.5);
  EXPECT_NEAR(g.evaluate(side).distance, 0.9 - std::sqrt(3.0) / 2.0, kExact);

  // An icosphere written at full precision and read back is the same mesh.
  const TriangleMesh s = icosphere(2, 0.7);
  std::ostringstream text;
  text.precision(17);
  for (const Vector3& x : s.vertices) text << "v " << x.x() << " " << x.y() << " " << x.z() << "\n";
  for (const auto& t : s.triangles)
    text << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  // tinyobjloader's number parser is not correctly rounded: allow an ulp or two.
  const TriangleMesh back = load_obj_mesh(dir.write("sphere.obj", text.str()));
  ASSERT_EQ(back.vertices.size(), s.vertices.size());
  for (std::size_t i = 0; i < s.vertices.size(); ++i) {
    EXPECT_LE((back.vertices[i] - s.vertices[i]).cwiseAbs().maxCoeff(), 4e-16) << i;
  }
  EXPECT_EQ(back.triangles, s.triangles);
}

TEST(ObjMesh, ErrorsNameTheFileAndTheReason) {
  TempDir dir;
  const auto expect_error = [](const fs::path& file, const std::string& reason) {
    const std::string msg = loader_error(file);
    EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find(reason), std::string::npos) << "expected '" << reason << "' in: " << msg;
  };
  expect_error(dir.path() / "absent.obj", "no such file");
  expect_error(dir.path(), "is a directory");
  // tinyobjloader rejects a non-numeric (or zero) face index.
  expect_error(dir.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n"), "parse error");
  expect_error(dir.write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), "parse error");
  expect_error(dir.write("garbage.obj", "this is not an OBJ file\n\x01\x02{}\n"), "no faces");
  expect_error(dir.write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "no faces");
  expect_error(dir.write("empty.obj", ""), "no faces");
  expect_error(dir.write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
               "uses vertex 9 (1-based), but the file has 3 vertices");
  expect_error(dir.write("inf.obj", "v 1e999 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "not finite");
  // A finite file overflowing once scaled.
  try {
    load_obj_mesh(dir.write("big.obj", "v 1e300 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), 1e10);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not finite after scaling"), std::string::npos)
        << e.what();
  }
  for (const double scale : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      load_obj_mesh(kData / "unit_cube.obj", scale);
      ADD_FAILURE() << "no exception for scale " << scale;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("scale must be finite and > 0"), std::string::npos)
          << e.what();
    }
  }
}

// ---------------------------------------------------------------------------------------
// The unit cube: exact nodes, exact interpolation where the SDF is affine, bounded elsewhere.

TEST(GridSdf, CubeGridLayout) {
  // Padded extent 1 + 2·0.25 = 1.5 = 15 cells of 0.1 (1.5/0.1 = 15.000000000000002 rounds to
  // 15, header), centred: the origin is the padded box's corner.
  const GridSdf g(read_cube(), 0.1, 0.25);
  EXPECT_EQ(g.dimensions(), Eigen::Vector3i(16, 16, 16));
  EXPECT_EQ(g.cell_size(), 0.1);
  EXPECT_TRUE(g.origin().isApprox(Vector3::Constant(-0.25), 1e-14)) << g.origin().transpose();
  EXPECT_TRUE(g.max_corner().isApprox(Vector3::Constant(1.25), 1e-14));
  EXPECT_EQ(g.node_position(15, 15, 15), g.max_corner());
  EXPECT_THROW(g.node_value(16, 0, 0), std::out_of_range);
  EXPECT_THROW(g.node_position(0, -1, 0), std::out_of_range);
  // A cell size not dividing the extent: ⌈1.5/0.4⌉ = 4 cells, centred (1.6 − 1.5)/2 beyond.
  const GridSdf coarse(read_cube(), 0.4, 0.25);
  EXPECT_EQ(coarse.dimensions(), Eigen::Vector3i(5, 5, 5));
  EXPECT_TRUE(coarse.origin().isApprox(Vector3::Constant(-0.3), 1e-14));
  // No padding and a cell larger than the mesh: one cell per axis.
  const GridSdf one(read_cube(), 5.0, 0.0);
  EXPECT_EQ(one.dimensions(), Eigen::Vector3i(2, 2, 2));
}

TEST(GridSdf, CubeNodesAreTheExactBoxSdf) {
  const Collider box = cube_collider();
  const TriangleMesh cube = read_cube();
  for (const double h : {0.1, 0.037, 1.5 / 63.0}) {  // the last: 64³ nodes
    const auto start = std::chrono::steady_clock::now();
    const GridSdf g(cube, h, 0.25);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "cube, " << g.dimensions().transpose() << " nodes: built in " << seconds << " s\n";
    int inside = 0, outside = 0;
    for (int k = 0; k < g.dimensions().z(); ++k) {
      for (int j = 0; j < g.dimensions().y(); ++j) {
        for (int i = 0; i < g.dimensions().x(); ++i) {
          const Vector3 x = g.node_position(i, j, k);
          const double exact = box.evaluate(x, false).distance;
          ASSERT_NEAR(g.node_value(i, j, k), exact, kExact)
              << "h " << h << " node " << i << " " << j << " " << k;
          inside += exact < -kExact;
          outside += exact > kExact;
        }
      }
    }
    EXPECT_GT(inside, 0);
    EXPECT_GT(outside, inside);
  }
}

// Whether x is in the region of the cube [0, 1]³ where its SDF is the affine s·(x_a − ½) − ½
// of ONE face (axis a, side s): with y = x − ½, the pyramid from the centre to the face
// (s y_a ≥ |y_b|) joined to the slab beyond it (|y_b| ≤ ½), i.e. |y_b| ≤ min(s y_a, ½) for
// both other axes b — an intersection of half-spaces, so convex. Returns 2a + (s > 0), or −1.
int face_region(const Vector3& x) {
  const Vector3 y = x - Vector3::Constant(0.5);
  for (int a = 0; a < 3; ++a) {
    for (const int s : {-1, 1}) {
      const double reach = std::min(s * y(a), 0.5);
      if (std::abs(y((a + 1) % 3)) <= reach && std::abs(y((a + 2) % 3)) <= reach) {
        return 2 * a + (s > 0);
      }
    }
  }
  return -1;
}

TEST(GridSdf, CubeInterpolationBounds) {
  // Bounds for the interpolant Iφ of the exact box SDF φ (exact at the nodes):
  //  (a) a cell whose 8 corners lie in one face region (face_region) lies in it (convex), φ is
  //      affine there and trilinear interpolation reproduces affine functions: Iφ = φ to
  //      round-off — e.g. across a face of the cube, inside and outside;
  //  (b) everywhere: φ is convex (the SDF of a convex set) and the trilinear weights are ≥ 0,
  //      sum to 1 and reproduce p (Σ w x_abc = p), so Iφ ≥ φ (Jensen); and φ is 1-Lipschitz,
  //      so Iφ − φ ≤ Σ w ‖x_abc − p‖ (≤ √3 h/2 at a cell centre) — the bound at edges and
  //      corners of the cube (kinks) and at the medial planes inside;
  //  (c) a cell at distance r > 0 from the cube: φ is C¹ there with ‖∇²φ‖ ≤ 1/r (cylinder or
  //      sphere about the nearest edge or corner, 0 near a face), so per axis the linear
  //      interpolation error is ≤ h²/8 · max|∂²φ/∂x_i²| and Iφ − φ ≤ 3h²/(8r).
  const Collider box = cube_collider();
  const double h = 0.1;
  const GridSdf g(read_cube(), h, 0.25);
  std::mt19937 rng(7);
  int affine_cells = 0, smooth_cells = 0, kink_cells = 0;
  double worst_kink = 0.0;
  for (int k = 0; k + 1 < g.dimensions().z(); ++k) {
    for (int j = 0; j + 1 < g.dimensions().y(); ++j) {
      for (int i = 0; i + 1 < g.dimensions().x(); ++i) {
        const Vector3 lo = g.node_position(i, j, k), hi = g.node_position(i + 1, j + 1, k + 1);
        int region = face_region(lo);
        for (int c = 1; c < 8 && region >= 0; ++c) {
          const Vector3 corner(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(),
                               c & 4 ? hi.z() : lo.z());
          if (face_region(corner) != region) region = -1;
        }
        const Vector3 gap = (-hi).cwiseMax(lo - Vector3::Ones()).cwiseMax(Vector3::Zero());
        const double r = gap.norm();  // distance from the cell to the cube
        affine_cells += region >= 0;
        smooth_cells += region < 0 && r > 0.0;
        kink_cells += region < 0 && r == 0.0;
        for (int n = 0; n < 4; ++n) {
          const Vector3 p = point_in_cell(g, Eigen::Vector3i(i, j, k), 0.0, rng);
          const double exact = box.evaluate(p, false).distance;
          const double err = g.evaluate(p).distance - exact;
          SCOPED_TRACE(fd::trace("p", p.x(), p.y(), p.z()));
          if (region >= 0) {
            ASSERT_NEAR(err, 0.0, kExact) << "face region " << region;
          }
          ASSERT_GE(err, -kExact);
          ASSERT_LE(err, lipschitz_bound(lo, h, p) + kExact);
          if (r > 0.0) {
            ASSERT_LE(err, 3.0 * h * h / (8.0 * r) + kExact) << "r " << r;
          }
          if (region < 0 && r == 0.0) worst_kink = std::max(worst_kink, err);
          // Sign: correct wherever |φ| exceeds the error bound.
          if (std::abs(exact) > lipschitz_bound(lo, h, p)) {
            ASSERT_EQ(g.evaluate(p).distance < 0.0, exact < 0.0);
          }
        }
      }
    }
  }
  EXPECT_GT(affine_cells, 1000);
  EXPECT_GT(smooth_cells, 100);
  EXPECT_GT(kink_cells, 100);
  EXPECT_GT(worst_kink, 1e-3);  // the kinks really are interpolated with an error
  std::cout << "cube: " << affine_cells << " affine, " << smooth_cells << " smooth, " << kink_cells
            << " kinked cells; worst error at a kink " << worst_kink << " (h = " << h << ")\n";
  // The centre (−½) is a kink (all medial planes) in the middle of a cell: −0.45 from the
  // corners at −0.45, within the Lipschitz bound √3 h/2.
  EXPECT_NEAR(g.evaluate(Vector3::Constant(0.5)).distance, -0.5, std::sqrt(3.0) * h / 2.0);
  EXPECT_NEAR(g.evaluate(Vector3(0.5, 0.5, 1.2)).distance, 0.2, kExact);
}

// Flipping every triangle (normals inward) gives the same field: the solid is the bounded side.
TEST(GridSdf, InwardNormalsAreFlipped) {
  const TriangleMesh cube = read_cube();
  TriangleMesh flipped = cube;
  for (auto& t : flipped.triangles) std::swap(t[1], t[2]);
  const GridSdf a(cube, 0.1, 0.25), b(flipped, 0.1, 0.25);
  for (int k = 0; k < a.dimensions().z(); ++k) {
    for (int j = 0; j < a.dimensions().y(); ++j) {
      for (int i = 0; i < a.dimensions().x(); ++i) {
        ASSERT_NEAR(a.node_value(i, j, k), b.node_value(i, j, k), kExact);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// Icospheres: exact nodes (brute force) and the approximation of the sphere.

TEST(GridSdf, IcosphereNodesMatchBruteForce) {
  // Every node of a small grid, and random nodes of the 64³ grid of a 5120-triangle sphere:
  // checks the block culling (header, "Build cost") and the signs against convex_mesh_sdf.
  {
    const TriangleMesh m = icosphere(2, 1.0);
    const GridSdf g(m, 0.11, 0.3);
    for (int k = 0; k < g.dimensions().z(); ++k) {
      for (int j = 0; j < g.dimensions().y(); ++j) {
        for (int i = 0; i < g.dimensions().x(); ++i) {
          ASSERT_NEAR(g.node_value(i, j, k), convex_mesh_sdf(m, g.node_position(i, j, k)), kExact)
              << i << " " << j << " " << k;
        }
      }
    }
  }
  const TriangleMesh m = icosphere(4, 1.0);
  ASSERT_EQ(m.triangles.size(), 5120u);
  const auto start = std::chrono::steady_clock::now();
  const GridSdf g(m, 2.06 / 63.0, 0.03);  // extent 2 + 0.06: 63 cells, 64³ nodes
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "icosphere, 5120 triangles, " << g.dimensions().transpose() << " nodes: built in "
            << seconds << " s\n";
  EXPECT_EQ(g.dimensions(), Eigen::Vector3i(64, 64, 64));
  std::mt19937 rng(3);
  for (int n = 0; n < 300; ++n) {
    const Eigen::Vector3i c = random_cell(g, rng);
    ASSERT_NEAR(g.node_value(c.x(), c.y(), c.z()),
                convex_mesh_sdf(m, g.node_position(c.x(), c.y(), c.z())), kExact);
  }
  // The nodes nearest the centre, where every triangle is almost equally near.
  const Eigen::Vector3i mid = g.dimensions() / 2;
  for (int k = mid.z() - 1; k <= mid.z() + 1; ++k) {
    for (int j = mid.y() - 1; j <= mid.y() + 1; ++j) {
      for (int i = mid.x() - 1; i <= mid.x() + 1; ++i) {
        ASSERT_NEAR(g.node_value(i, j, k), convex_mesh_sdf(m, g.node_position(i, j, k)), kExact);
      }
    }
  }
}

TEST(GridSdf, IcosphereApproximatesTheSphere) {
  // Bound for Iφ_m (the grid of the mesh SDF φ_m) against the sphere's φ_s = ‖p‖ − R:
  //   Iφ_m − φ_s = I(φ_m − φ_s) + (Iφ_s − φ_s).
  // Chord error: the mesh is inscribed (vertices on the sphere, flat faces inside), every
  // mesh point z has R − δ ≤ ‖z‖ ≤ R with δ = R − min_t dist(0, t) ≤ R − min_t dist(0, plane
  // of t) (the sagitta, ≈ circumradius²/2R of the largest triangle), and both surfaces are
  // star-shaped about 0; along the ray through p both φ differ by at most δ (p outside both or
  // inside both: the distances to the surfaces differ by ≤ the Hausdorff distance δ; p between
  // them: |φ_m| + |φ_s| ≤ the radial gap ≤ δ). So |φ_m − φ_s| ≤ δ everywhere, and
  // |I(φ_m − φ_s)| ≤ δ (I is a convex combination).
  // Interpolation of the sphere SDF: φ_s is convex, so Iφ_s ≥ φ_s; its Hessian (I − u uᵀ)/‖p‖
  // has |∂²φ_s/∂x_i²| ≤ 1/r on a cell at distance r from the centre, so Iφ_s − φ_s ≤ 3h²/(8r)
  // (per-axis linear interpolation error h²/8 · |f''|); at the centre (the cone's kink) the
  // Lipschitz bound Σ w ‖x_abc − p‖ applies instead. Together:
  //   −δ ≤ Iφ_m − φ_s ≤ δ + 3h²/(8r)      (r = distance from the cell to the centre > 0),
  // with R = 1, level 3 (1280 triangles): δ ≈ 4.5e-3; h = 0.05: 3h²/8 ≈ 9e-4 at r = 1.
  const double R = 1.0, h = 0.05;
  const TriangleMesh m = icosphere(3, R);
  double min_plane = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    const Vector3& a = m.vertices[static_cast<std::size_t>(t[0])];
    const Vector3 n = (m.vertices[static_cast<std::size_t>(t[1])] - a)
                          .cross(m.vertices[static_cast<std::size_t>(t[2])] - a)
                          .normalized();
    min_plane = std::min(min_plane, std::abs(a.dot(n)));
  }
  const double delta = R - min_plane;
  std::cout << "icosphere level 3: chord error bound delta = " << delta << "\n";
  ASSERT_GT(delta, 1e-3);
  ASSERT_LT(delta, 5e-3);
  const GridSdf g(m, h, 0.15);
  std::mt19937 rng(11);
  double worst = 0.0;
  for (int n = 0; n < 20000; ++n) {
    const Eigen::Vector3i c = random_cell(g, rng);
    const Vector3 lo = g.node_position(c.x(), c.y(), c.z());
    const Vector3 hi = lo + Vector3::Constant(h);
    const double r = lo.cwiseMax(-hi).cwiseMax(Vector3::Zero()).norm();
    const Vector3 p = point_in_cell(g, c, 0.0, rng);
    const double exact = p.norm() - R;
    const double err = g.evaluate(p).distance - exact;
    const double upper = r > 0.0 ? 3.0 * h * h / (8.0 * r) : lipschitz_bound(lo, h, p);
    SCOPED_TRACE(fd::trace("p", p.x(), p.y(), p.z()));
    ASSERT_GE(err, -delta - kExact);
    ASSERT_LE(err, delta + upper + kExact);
    if (std::abs(exact) > delta + upper) {
      ASSERT_EQ(g.evaluate(p).distance < 0.0, exact < 0.0);
    }
    if (std::abs(exact) < 0.2) worst = std::max(worst, std::abs(err));
  }
  std::cout << "icosphere level 3, h = " << h << ": worst |error| near the surface " << worst
            << " (bound " << delta + 3.0 * h * h / (8.0 * 0.8) << ")\n";
}

// ---------------------------------------------------------------------------------------
// Non-convex solids with grid nodes on vertices, edges and faces: the pseudonormal sign.

TEST(GridSdf, SignAtEdgesAndVerticesOfNonConvexSolids) {
  // Nodes at multiples of 0.25 from −0.5: exactly on the lattice of the mesh vertices, on
  // every edge, face and on the diagonal (medial) planes between them, including the concave
  // edges and the saddle and concave vertices of these shapes.
  const std::vector<std::pair<std::string, std::vector<Voxel>>> shapes = {
      {"L", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}},
      {"tripod", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
      {"cube minus a corner",
       {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}}},
      {"staircase",
       {{0, 0, 0},
        {1, 0, 0},
        {2, 0, 0},
        {1, 1, 0},
        {2, 1, 0},
        {2, 2, 0},
        {2, 0, 1},
        {2, 1, 1},
        {2, 0, 2}}},
  };
  for (const auto& [name, voxels] : shapes) {
    SCOPED_TRACE(name);
    const TriangleMesh m = voxel_mesh(voxels);
    const GridSdf g(m, 0.25, 0.5);
    ASSERT_EQ(g.node_position(0, 0, 0), Vector3::Constant(-0.5));
    int on = 0, in = 0, out = 0;
    for (int k = 0; k < g.dimensions().z(); ++k) {
      for (int j = 0; j < g.dimensions().y(); ++j) {
        for (int i = 0; i < g.dimensions().x(); ++i) {
          const Vector3 x = g.node_position(i, j, k);
          const double bound = voxel_union_bound(voxels, x);
          const double phi = g.node_value(i, j, k);
          SCOPED_TRACE(fd::trace("node", x.x(), x.y(), x.z()));
          if (bound > kExact) {  // outside: the union's SDF is exact
            ASSERT_NEAR(phi, bound, kExact);
            ++out;
            continue;
          }
          // In the closed union: on its surface iff a step of 1e-6 towards one of the 26
          // lattice neighbours leaves it (bound = 0 also on the faces between two voxels,
          // which are interior; a concave edge is left only diagonally).
          bool surface = false;
          for (int d = 0; d < 27; ++d) {
            const Vector3 dir(d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1);
            surface = surface || voxel_union_bound(voxels, x + 1e-6 * dir) > 0.0;
          }
          if (surface) {
            ASSERT_NEAR(phi, 0.0, kExact);
            ++on;
          } else {  // inside: negative, at least as deep as in any one voxel
            ASSERT_LT(phi, 0.0);
            ASSERT_LE(phi, bound + kExact);
            ++in;
          }
        }
      }
    }
    EXPECT_GT(on, 10);
    EXPECT_GT(in, 10);
    EXPECT_GT(out, 100);
  }
}

// A tall square pyramid whose −y side is fanned into 8 triangles at the apex. The apex's
// normal cone is almost a half-space (the side normals are ±84° from the axis), so only the
// ANGLE-weighted sum of the face normals (each face counted by its angle at the apex, not by
// its number of triangles) keeps the sign right above the apex: an unweighted sum tilts
// towards −y and calls the nodes above the apex on the +y side inside.
TEST(GridSdf, AngleWeightedPseudonormalAtASharpApex) {
  const double a = 0.5, H = 4.0;
  const int k = 8;
  TriangleMesh m;
  m.vertices = {{-a, -a, 0}, {a, -a, 0}, {a, a, 0}, {-a, a, 0}, {0, 0, H}};  // c0..c3, apex
  const int apex = 4;
  std::vector<int> base = {0};  // the base polygon counter-clockwise from above
  for (int j = 1; j < k; ++j) {
    m.vertices.emplace_back(-a + 2.0 * a * j / k, -a, 0.0);
    base.push_back(static_cast<int>(m.vertices.size()) - 1);
  }
  base.insert(base.end(), {1, 2, 3});
  for (int j = 0; j < k; ++j) m.triangles.push_back({base[j], base[j + 1], apex});  // −y side
  m.triangles.push_back({1, 2, apex});
  m.triangles.push_back({2, 3, apex});
  m.triangles.push_back({3, 0, apex});
  for (std::size_t i = 0; i + 2 < base.size(); ++i) {  // fan from c3, normal −z
    m.triangles.push_back({3, base[i + 1], base[i]});
  }
  const GridSdf g(m, 0.1, 0.5);
  int above_apex = 0;
  for (int kz = 0; kz < g.dimensions().z(); ++kz) {
    for (int j = 0; j < g.dimensions().y(); ++j) {
      for (int i = 0; i < g.dimensions().x(); ++i) {
        const Vector3 x = g.node_position(i, j, kz);
        ASSERT_NEAR(g.node_value(i, j, kz), convex_mesh_sdf(m, x), kExact) << x.transpose();
        above_apex += x.z() > H;
      }
    }
  }
  EXPECT_GT(above_apex, 100);
}

// ---------------------------------------------------------------------------------------
// Derivatives of the interpolant and of its continuation.

TEST(GridSdf, DerivativesMatchFiniteDifferencesInsideCells) {
  std::mt19937 rng(5);
  const GridSdf cube(read_cube(), 0.05, 0.2);
  const GridSdf sphere(icosphere(3, 1.0), 0.05, 0.15);
  for (const GridSdf* g : {&cube, &sphere}) {
    int nonzero = 0;
    for (int n = 0; n < 200; ++n) {
      expect_derivatives(*g, point_in_cell(*g, random_cell(*g, rng), 1e-3, rng), nonzero);
      if (HasFatalFailure()) return;
    }
    EXPECT_GT(nonzero, 20);  // enough points where the Hessian is really compared
  }
  // Points 1e-3 cells from a face, and the lowest and highest cells.
  int nonzero = 0;
  const double h = cube.cell_size();
  for (const Vector3& t :
       {Vector3(1e-3, 0.5, 0.5), Vector3(0.5, 1 - 1e-3, 0.3), Vector3(0.2, 0.7, 1 - 1e-3)}) {
    expect_derivatives(cube, cube.node_position(0, 0, 0) + h * t, nonzero);
    const Eigen::Vector3i top = cube.dimensions() - Eigen::Vector3i::Constant(2);
    expect_derivatives(cube, cube.node_position(top.x(), top.y(), top.z()) + h * t, nonzero);
    expect_derivatives(cube, Vector3(0.9, 0.95, 0.2) + h * t, nonzero);  // near an edge
  }
}

TEST(GridSdf, DerivativesAtCellFacesAreThoseOfTheLowerCell) {
  // Exactly on the face p_a = x_a,i between cells i − 1 and i (as node_position gives it),
  // ∇φ and ∇²φ are the lower cell's (the limits from below), and the value is continuous.
  const GridSdf g(icosphere(3, 1.0), 0.05, 0.15);
  std::mt19937 rng(9);
  int jumps = 0;
  for (int n = 0; n < 60; ++n) {
    const int a = n % 3;
    Eigen::Vector3i c = random_cell(g, rng);
    c(a) = std::max(c(a), 1);
    Vector3 p = point_in_cell(g, c, 1e-3, rng);
    p(a) = g.node_position(c.x(), c.y(), c.z())(a);  // the face between cells c_a − 1 and c_a
    const Vector3 step = 1e-9 * Vector3::Unit(a);
    const SdfValue on = g.evaluate(p), below = g.evaluate(p - step), above = g.evaluate(p + step);
    EXPECT_NEAR(on.distance, below.distance, 1e-8);
    EXPECT_NEAR(on.distance, above.distance, 1e-8);  // C⁰ across the face
    // Within a cell, ∇φ and ∇²φ change by O(1e-9 |∇²φ|) over the step.
    EXPECT_LT((on.gradient - below.gradient).norm(), 1e-6) << a;
    EXPECT_LT((on.hessian - below.hessian).norm(), 1e-4) << a;
    jumps += (on.gradient - above.gradient).norm() > 1e-6;
  }
  EXPECT_GT(jumps, 40);  // the upper cell's derivatives do differ: the test can tell
}

TEST(GridSdf, OutsideTheGridDerivativesMatchFiniteDifferences) {
  std::mt19937 rng(13);
  const GridSdf g(icosphere(3, 1.0), 0.05, 0.15);
  std::uniform_real_distribution<double> away(0.05, 0.5);
  std::uniform_int_distribution<int> subset(1, 7);
  int nonzero = 0;
  for (int n = 0; n < 150; ++n) {
    Vector3 p = point_in_cell(g, random_cell(g, rng), 1e-3, rng);
    const int axes = subset(rng);  // non-empty set of clamped axes
    for (int a = 0; a < 3; ++a) {
      if (!(axes & (1 << a))) continue;
      p(a) = rng() % 2 ? g.max_corner()(a) + away(rng) : g.origin()(a) - away(rng);
    }
    expect_derivatives(g, p, nonzero);
    if (HasFatalFailure()) return;
  }
  EXPECT_GT(nonzero, 100);  // the distance term's (P_A − u uᵀ)/d, and the sphere's curvature
}

TEST(GridSdf, OutsideTheGridContinuation) {
  const GridSdf g(icosphere(3, 1.0), 0.05, 0.15);
  const Vector3 lo = g.origin(), hi = g.max_corner(), mid = 0.5 * (lo + hi);
  // Continuous at the box: on a face, an edge and a corner, just inside vs just outside.
  for (const Vector3& q : {Vector3(hi.x(), 0.1, -0.2), Vector3(lo.x(), hi.y(), 0.3), hi, lo}) {
    const Vector3 n = (q - mid).cwiseSign().cwiseProduct(
        ((q - lo).array() == 0.0 || (q - hi).array() == 0.0).cast<double>().matrix());
    const double inside = g.evaluate(q - 1e-9 * n).distance;
    const double outside = g.evaluate(q + 1e-9 * n).distance;
    EXPECT_NEAR(inside, outside, 1e-8) << q.transpose();
    EXPECT_NEAR(g.evaluate(q).distance, inside, 1e-8);
    EXPECT_GT(outside, 0.0);
  }
  // The continuation: φ(p) = φ(clamp(p)) + ‖p − clamp(p)‖.
  const Vector3 p(hi.x() + 0.3, lo.y() - 0.4, 0.2);
  const Vector3 q(hi.x(), lo.y(), 0.2);
  EXPECT_NEAR(g.evaluate(p).distance, g.evaluate(q).distance + 0.5, kExact);
  // Far away: finite, positive, growing at unit rate along any ray.
  std::mt19937 rng(17);
  for (int n = 0; n < 20; ++n) {
    const Vector3 u = fd::random_unit(rng);
    double last = g.evaluate(u).distance;
    for (const double s : {2.0, 10.0, 1e3, 1e6, 1e12, 1e100, 1e300}) {
      const SdfValue v = g.evaluate(s * u);
      ASSERT_TRUE(std::isfinite(v.distance) && v.gradient.allFinite() && v.hessian.allFinite())
          << s;
      EXPECT_GT(v.distance, last) << s;
      EXPECT_GT(v.distance, 0.0);
      if (s >= 1e3) {  // ‖su − corner‖ ≈ s
        EXPECT_NEAR(v.distance / s, 1.0, 3.0 / s + 1e-12);
      }
      last = v.distance;
    }
  }
  // Non-finite input: NaN, not undefined behaviour.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(std::isnan(g.evaluate(Vector3(nan, 0, 0)).distance));
  EXPECT_TRUE(std::isnan(g.evaluate(Vector3(0, inf, 0)).distance));
  EXPECT_TRUE(std::isnan(g.evaluate(Vector3(0, 0, -inf)).distance));
  // Outside by less than kCoreDistance: the value at the box.
  const Vector3 tiny(hi.x() + 1e-300, 0.1, 0.1);
  EXPECT_EQ(g.evaluate(tiny).distance, g.evaluate(Vector3(hi.x(), 0.1, 0.1)).distance);
}

// ---------------------------------------------------------------------------------------
// Errors.

TEST(GridSdf, ErrorsNameTheReason) {
  const auto expect = [](const std::string& msg, const std::string& reason) {
    EXPECT_NE(msg.find(reason), std::string::npos)
        << "expected '" << reason << "' in: '" << msg << "'";
  };
  const TriangleMesh cube = read_cube();
  ASSERT_EQ(grid_error(cube), "");

  // Arguments.
  expect(grid_error(cube, 0.0), "cell_size must be finite and > 0, got 0");
  expect(grid_error(cube, -0.1), "cell_size must be finite and > 0, got -0.1");
  expect(grid_error(cube, std::numeric_limits<double>::quiet_NaN()), "cell_size");
  expect(grid_error(cube, std::numeric_limits<double>::infinity()), "cell_size");
  expect(grid_error(cube, 0.1, -1.0), "padding must be finite and >= 0, got -1");
  expect(grid_error(cube, 0.1, std::numeric_limits<double>::infinity()), "padding");
  expect(grid_error(cube, 0.1, 0.1, 0), "max_cells must be >= 1");
  // 1.2 / 0.1 = 12 cells per axis = 1728 > 1000; and the default limit 2e7 < 1000³.
  expect(grid_error(cube, 0.1, 0.1, 1000),
         "the grid needs 12 x 12 x 12 = 1728 cells, more than max_cells = 1000");
  expect(grid_error(cube, 0.0012, 0.1), "more than max_cells = 20000000");
  expect(grid_error(cube, 1e-300, 0.1), "more than 2^31 - 2 nodes along an axis");

  // Mesh contents.
  expect(grid_error(TriangleMesh{}), "the mesh has no vertices");
  expect(grid_error(TriangleMesh{cube.vertices, {}}), "the mesh has no triangles");
  TriangleMesh bad = cube;
  bad.triangles[5][1] = 9;
  expect(grid_error(bad), "has vertex index 9, outside [0, 8)");
  expect(grid_error(bad), "triangle 5 (vertices ");
  bad = cube;
  bad.triangles[2][2] = -1;
  expect(grid_error(bad), "triangle 2 (vertices ");
  expect(grid_error(bad), "has vertex index -1");
  bad = cube;
  bad.vertices[3].y() = std::numeric_limits<double>::quiet_NaN();
  expect(grid_error(bad), "vertex 3 is not finite");
  bad = cube;
  bad.triangles[4][2] = bad.triangles[4][0];
  expect(grid_error(bad), "triangle 4 (vertices ");
  expect(grid_error(bad), "is degenerate: it repeats a vertex");
  // Zero area with distinct vertices: vertex 8 on the segment from vertex 0 to vertex 1.
  bad = cube;
  bad.vertices.push_back(0.5 * (cube.vertices[0] + cube.vertices[1]));
  bad.triangles.push_back({0, 8, 1});
  expect(grid_error(bad), "triangle 12 (vertices 0, 8, 1) is degenerate: zero area");

  // Topology: a face removed (two triangles of one quad), an extra face on an edge, a flipped
  // triangle, a flat closed surface.
  bad = cube;
  bad.triangles.erase(bad.triangles.begin(), bad.triangles.begin() + 2);  // the z = 0 quad
  const std::string open = grid_error(bad);
  expect(open, "the mesh is not closed: edge (");
  expect(open, "belongs to no other triangle (every edge must be shared by exactly two");
  bad = cube;
  bad.triangles[7] = {bad.triangles[7][0], bad.triangles[7][2], bad.triangles[7][1]};
  expect(grid_error(bad), "the mesh is not consistently oriented: triangles ");
  expect(grid_error(bad), "7");
  // Two voxels touching along an edge only: that edge belongs to 4 triangles.
  expect(grid_error(voxel_mesh({{0, 0, 0}, {1, 1, 0}})), "is shared by 4 triangles (");
  // A double-sided triangle: closed and consistently oriented, but flat.
  const TriangleMesh flat{{Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(0, 1, 0)},
                          {{0, 1, 2}, {0, 2, 1}}};
  expect(grid_error(flat), "the mesh encloses no volume (signed volume 0)");
  // Every message starts with the class.
  EXPECT_EQ(grid_error(flat).rfind("GridSdf: ", 0), 0u);
}

// ---------------------------------------------------------------------------------------
// The work budget of GridSdf (lib/mesh_sdf.hpp, "Work budget"): the build's point-triangle
// distances are estimated before the build, a grid beyond max_build_work is refused at once
// (GridSdfTooCostly, naming the estimate and what to change), and in a scene that refusal is a
// SceneError on the collider's cell_size.

// The axis-aligned box [0, a] (12 triangles, outward).
TriangleMesh box(const Vector3& a) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1) ? a.x() : 0.0, (i & 2) ? a.y() : 0.0, (i & 4) ? a.z() : 0.0);
  }
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

std::string what_of(const TriangleMesh& mesh, double h, double padding, double max_work) {
  try {
    GridSdf g(mesh, h, padding, 20000000, max_work);
  } catch (const GridSdfTooCostly& e) {
    return e.what();
  }
  return "";
}

TEST(GridSdfBudget, TheEstimateIsCloseToTheWorkDone) {
  struct Case {
    const char* name;
    TriangleMesh mesh;
    double h, budget;  // a budget below 3 N T, so that the work is estimated
  };
  const Case cases[] = {
      {"icosphere 5120, 64^3", icosphere(4, 1.0), 2.06 / 63.0, kDefaultMaxBuildWork},
      {"icosphere 20480, 35^3", icosphere(5, 1.0), 0.065, kDefaultMaxBuildWork},
      {"box 12, 203 x 103 x 53", box(Vector3(2.0, 1.0, 0.5)), 0.01, 2e7},
  };
  for (const Case& c : cases) {
    const GridSdf g(c.mesh, c.h, 0.03, 20000000, c.budget);
    ASSERT_GT(g.estimated_build_work(), 0.0) << c.name << ": 3 N T is within the budget";
    EXPECT_NEAR(g.estimated_build_work() / g.build_work(), 1.0, 0.25)
        << c.name << ": estimated " << g.estimated_build_work() << ", done " << g.build_work();
    EXPECT_LE(g.build_work(), c.budget) << c.name;
  }
  // Where 3 N T is within the budget nothing is estimated.
  const GridSdf small(box(Vector3::Ones()), 0.1, 0.1);
  EXPECT_EQ(small.estimated_build_work(), 0.0);
  EXPECT_GT(small.build_work(), 0.0);
  EXPECT_LE(small.build_work(), 3.0 * 13 * 13 * 13 * 12);
}

TEST(GridSdfBudget, BeyondTheBudgetTheGridIsRefusedWithWhatToChange) {
  const TriangleMesh sphere = icosphere(4, 1.0);  // ~3e7 distances at 64³ nodes
  const double h = 2.06 / 63.0;
  const std::string msg = what_of(sphere, h, 0.03, 1e7);
  EXPECT_NE(msg.find("GridSdf: building the grid of 64 x 64 x 64 nodes for 5120 triangles "
                     "needs about "),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("point-triangle distances (estimated from"), std::string::npos) << msg;
  EXPECT_NE(msg.find("more than max_build_work = 1e+07"), std::string::npos) << msg;
  EXPECT_NE(msg.find("increase cell_size = "), std::string::npos) << msg;
  EXPECT_NE(msg.find("or use a mesh with fewer triangles"), std::string::npos) << msg;
  // The same grid within a budget builds.
  EXPECT_EQ(what_of(sphere, h, 0.03, 1e8), "");
  // A budget below 1 is bad input, not a too costly grid.
  try {
    GridSdf g(sphere, 0.1, 0.1, 20000000, 0.5);
    ADD_FAILURE() << "no error";
  } catch (const GridSdfTooCostly& e) {
    ADD_FAILURE() << e.what();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_build_work must be >= 1"), std::string::npos);
  }
  // The cell cap is a GridSdfTooCostly too.
  EXPECT_NE(what_of(sphere, 0.0012, 0.1, 1e9).find("more than max_cells"), std::string::npos);
}

// A 327680-triangle mesh (once seen to take minutes to load): 327680 triangles on a sphere of radius 0.1 m, 0.8 mm cells (255³ nodes,
// ~2e10 distances, minutes to build). In a scene, refused at once naming cell_size.
TEST(GridSdfBudget, AFineGridOfALargeMeshInASceneIsRefusedNamingCellSize) {
  TempDir temp;
  const fs::path& dir = temp.path();
  {
    const TriangleMesh m = icosphere(7, 0.1);
    ASSERT_EQ(m.triangles.size(), 327680u);
    std::ofstream obj(dir / "sphere.obj");
    obj.precision(12);
    for (const Vector3& x : m.vertices) obj << "v " << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
    for (const auto& t : m.triangles) obj << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
  const std::string text = R"({"time_step": 0.01, "frames": 5, "colliders": [
      {"type": "mesh", "file": "sphere.obj", "cell_size": 0.0008}],
      "bodies": [{"name": "a", "mass": 2, "inertia": [1, 2, 2.5]}]})";
  const std::string source = (dir / "scene.json").string();
  try {
    parse_scene(text, source);
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), source);
    EXPECT_EQ(e.field(), "colliders[0].cell_size");
    EXPECT_NE(e.reason().find("255 x 255 x 255 nodes for 327680 triangles needs about"),
              std::string::npos)
        << e.reason();
    EXPECT_NE(e.reason().find("increase cell_size = 0.0008 to about"), std::string::npos)
        << e.reason();
  }
}

// ---------------------------------------------------------------------------------------
// Bad numbers and bytes in OBJ files: a vertex coordinate that is not a finite decimal number,
// a missing coordinate and a NUL byte are refused naming the file and the line (tinyobjloader
// alone reads "nan" and "abc" as 0), and in a scene the refusal is a SceneError on the
// collider's "file".

// A closed tetrahedron (outward faces) with its first vertex line replaced by `first`, and
// `before` in front: the bad line is line 1 + (lines in `before`).
std::string tetrahedron_obj(const std::string& first, const std::string& before = "") {
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

// A FIFO would block the loader for ever and /dev/zero would be read until memory runs out:
// only regular files are read.
TEST(ObjMeshFiles, DevicesAndFifosAreNotRead) {
  TempDir dir;
  const fs::path fifo = dir.path() / "pipe.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const fs::path& file : {fifo, fs::path("/dev/zero")}) {
    const std::string msg = loader_error(file);
    EXPECT_NE(msg.find(in_file(file, "is not a regular file (a FIFO, socket or device)")),
              std::string::npos)
        << msg;
  }
}

TEST(ObjMeshNumbers, TheTetrahedronLoads) {
  TempDir dir;
  const TriangleMesh m = load_obj_mesh(dir.write("ok.obj", tetrahedron_obj("v 0 0 0")));
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
      {"nan.obj", tetrahedron_obj("v nan 0 0"), "line 1: vertex 1 (1-based): x = 'nan' is not finite"},
      {"abc.obj", tetrahedron_obj("v 0 abc 0", "# a comment\n\n"),
       "line 3: vertex 1 (1-based): y = 'abc' is not a number"},
      {"inf.obj", tetrahedron_obj("v 0 0 -inf"), "line 1: vertex 1 (1-based): z = '-inf' is not finite"},
      {"huge.obj", tetrahedron_obj("v 1e999 0 0"), "line 1: vertex 1 (1-based): x = '1e999' is not finite"},
      {"hex.obj", tetrahedron_obj("v 0x10 0 0"), "line 1: vertex 1 (1-based): x = '0x10' is not a number"},
      {"dots.obj", tetrahedron_obj("v 1.5.3 0 0"), "line 1: vertex 1 (1-based): x = '1.5.3' is not a number"},
      {"signs.obj", tetrahedron_obj("v +-1 0 0"), "line 1: vertex 1 (1-based): x = '+-1' is not a number"},
      {"missing.obj", tetrahedron_obj("v 0 0"), "line 1: vertex 1 (1-based): has 2 coordinates"},
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
  const fs::path after = dir.write("nul.obj", tetrahedron_obj("v 0 0 0") + std::string("f 1 2\0 3\n", 9));
  std::string msg = loader_error(after);
  EXPECT_NE(msg.find(in_file(after, "line 9: a NUL byte")), std::string::npos) << msg;
  const fs::path inside = dir.write("nul2.obj", tetrahedron_obj(std::string("v 0 0 1\0", 8) + "5"));
  msg = loader_error(inside);
  EXPECT_NE(msg.find("line 1: a NUL byte (byte 8 of the file)"), std::string::npos) << msg;
}

TEST(ObjMeshNumbers, InASceneTheRefusalIsASceneErrorOnTheColliderFile) {
  TempDir dir;
  const fs::path file = dir.write("bad.obj", tetrahedron_obj("v 0 0 0", "v 0 0 0\nv 0 0 abc\n"));
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

// Mass and inertia from a shape and a density (lib/mass_properties.hpp): the closed forms
// against the textbook ones where they exist (sphere, sharp box, a capsule of zero length),
// against a midpoint-rule integration over the shape's SDF (every part of a heavily rounded
// box and of a capsule matters), turned by the shape's orientation; and a scene's "density".

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>

#include "fd_check.hpp"
#include "mesh_models.hpp"
#include "lib/mass_properties.hpp"
#include "lib/mesh_sdf.hpp"
#include "lib/model.hpp"
#include "problems/scene.hpp"

namespace liedyn {
namespace {

using test::box_mesh;

Collider solid(const Shape& shape, const Matrix3& orientation = Matrix3::Identity()) {
  Collider c;
  c.shape = shape;
  c.orientation = orientation;
  return c;
}

// Midpoint rule over n³ cells of the box [−L, L]³ (shape axes), each cell counted by the
// fraction of it inside, 1/2 − φ/cell clamped to [0, 1] (exact for a face parallel to the
// cell's, first order in the angle otherwise): a counted-or-not cell would be off by up to
// half a layer of cells on a flat face, ~1e-2 here. What remains is the fraction's error
// where the surface is oblique to the cells: ~5e-4 relative at n = 160 on these O(1) shapes,
// against the percent or more that dropping any one part of the closed forms costs.
MassProperties integrated(const Collider& c, double half_width, double density, int n) {
  const double cell = 2.0 * half_width / n, dV = cell * cell * cell;
  double volume = 0.0;
  Matrix3 second = Matrix3::Zero();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) {
        const Vector3 p = Vector3(i + 0.5, j + 0.5, k + 0.5) * cell - Vector3::Constant(half_width);
        const double inside = std::clamp(0.5 - c.evaluate(p, false).distance / cell, 0.0, 1.0);
        volume += inside * dV;
        second += inside * dV * p * p.transpose();
      }
    }
  }
  MassProperties m;
  m.mass = density * volume;
  m.inertia = density * (second.trace() * Matrix3::Identity() - second);
  return m;
}

TEST(MassProperties, TextbookSolids) {
  const double rho = 7.0;
  const MassProperties s = mass_properties(solid(SphereShape{0.3}), rho, "bodies[0]");
  const double m_s = rho * 4.0 / 3.0 * std::numbers::pi * 0.027;
  EXPECT_NEAR(s.mass, m_s, 1e-14 * m_s);
  EXPECT_TRUE(s.inertia.isApprox(0.4 * m_s * 0.09 * Matrix3::Identity(), 1e-14));
  const MassProperties b = mass_properties(solid(BoxShape{Vector3(0.1, 0.2, 0.3), 0.0}), rho, "bodies[0]");
  const double m_b = rho * 0.2 * 0.4 * 0.6;
  EXPECT_NEAR(b.mass, m_b, 1e-14 * m_b);
  EXPECT_TRUE(b.inertia.isApprox(Matrix3(Vector3(0.16 + 0.36, 0.04 + 0.36, 0.04 + 0.16).asDiagonal()) * (m_b / 12.0), 1e-14));
  // A capsule of zero length is a sphere; a box rounded all the way to a cube's half extent
  // would be one too, and at rounding → e it tends to it.
  const MassProperties c = mass_properties(solid(CapsuleShape{0.0, 0.3}), rho, "bodies[0]");
  EXPECT_NEAR(c.mass, s.mass, 1e-14 * m_s);
  EXPECT_TRUE(c.inertia.isApprox(s.inertia, 1e-14));
  const MassProperties r = mass_properties(solid(BoxShape{Vector3::Constant(0.3), 0.3 * (1 - 1e-9)}), rho, "bodies[0]");
  EXPECT_NEAR(r.mass, s.mass, 1e-7 * m_s);
  EXPECT_TRUE(r.inertia.isApprox(s.inertia, 1e-7));
}

TEST(MassProperties, TorusCylinderAndLinkClosedForms) {
  const double rho = 3.0, pi = std::numbers::pi;
  // Torus R = 0.5, r = 0.2 (Pappus): V = 2π²Rr², I_zz = m(R² + ¾r²), I_xx = m(½R² + ⅝r²).
  const double R = 0.5, r = 0.2, m_t = rho * 2 * pi * pi * R * r * r;
  const MassProperties t = mass_properties(solid(TorusShape{R, r}), rho, "bodies[0]");
  EXPECT_NEAR(t.mass, m_t, 1e-14 * m_t);
  const double across = m_t * (R * R / 2 + 5 * r * r / 8);
  EXPECT_TRUE(t.inertia.isApprox(
      Matrix3(Vector3(across, across, m_t * (R * R + 0.75 * r * r)).asDiagonal()), 1e-14))
      << t.inertia;
  // A link of zero length is that torus.
  const MassProperties l0 = mass_properties(solid(LinkShape{0.0, R, r}), rho, "bodies[0]");
  EXPECT_NEAR(l0.mass, t.mass, 1e-14 * m_t);
  EXPECT_TRUE(l0.inertia.isApprox(t.inertia, 1e-14));
  // Solid cylinder ρ_c = 0.3, length 2h = 1.2: I_zz = ½mρ², I_xx = m(3ρ² + (2h)²)/12.
  const double rc = 0.3, h = 0.6, m_c = rho * pi * rc * rc * 2 * h;
  const MassProperties c = mass_properties(solid(CylinderShape{rc, h}), rho, "bodies[0]");
  EXPECT_NEAR(c.mass, m_c, 1e-14 * m_c);
  const double c_across = m_c * (3 * rc * rc + 4 * h * h) / 12;
  EXPECT_TRUE(c.inertia.isApprox(
      Matrix3(Vector3(c_across, c_across, 0.5 * m_c * rc * rc).asDiagonal()), 1e-14));
  // A thin link (r → 0) is a wire of λ = ρπr² per unit length: two straight pieces of length
  // 2L at y = ±R and two half circles of radius R about (±L, 0, 0) (the tube's own moments
  // are (r/R)² = 4e-10 smaller).
  const double L = 0.4, thin = 1e-5, lambda = rho * pi * thin * thin;
  const MassProperties w = mass_properties(solid(LinkShape{L, R, thin}), rho, "bodies[0]");
  const double wire_mass = lambda * (4 * L + 2 * pi * R);
  // Arcs: x = ±(L + R cos θ), y = R sin θ, θ ∈ [−π/2, π/2], ds = R dθ:
  // ∫x² = R ∫(L + R cos θ)² dθ = R(πL² + 4LR + πR²/2) and ∫y² = πR³/2, each.
  const double arcs_x2 = 2 * R * (pi * L * L + 4 * L * R + pi * R * R / 2),
               arcs_y2 = pi * R * R * R;
  const double sides_x2 = 2 * (2 * L) * (L * L / 3), sides_y2 = 2 * (2 * L) * R * R;
  const double Sx = lambda * (arcs_x2 + sides_x2), Sy = lambda * (arcs_y2 + sides_y2);
  EXPECT_NEAR(w.mass, wire_mass, 1e-12 * wire_mass);
  EXPECT_TRUE(w.inertia.isApprox(Matrix3(Vector3(Sy, Sx, Sx + Sy).asDiagonal()), 1e-8))
      << w.inertia;
}

TEST(MassProperties, AgreeWithIntegrationOverTheShapeAndTurnWithIt) {
  std::mt19937 rng(3);
  const double rho = 1000.0;
  struct Case {
    Shape shape;
    double half_width;
  };
  for (const Case& k :
       {Case{BoxShape{Vector3(0.3, 0.5, 0.7), 0.25}, 0.71},
        Case{BoxShape{Vector3(0.3, 0.5, 0.7), 0.1}, 0.71}, Case{CapsuleShape{0.4, 0.25}, 0.66},
        Case{TorusShape{0.45, 0.2}, 0.66}, Case{CylinderShape{0.35, 0.5}, 0.62},
        Case{LinkShape{0.25, 0.3, 0.15}, 0.71}}) {
    const Matrix3 Q = fd::rotation_at(1.1, rng);
    const MassProperties exact = mass_properties(solid(k.shape, Q), rho, "bodies[0]");
    const MassProperties axes = mass_properties(solid(k.shape), rho, "bodies[0]");
    const MassProperties numeric = integrated(solid(k.shape), k.half_width, rho, 160);
    EXPECT_NEAR(axes.mass, numeric.mass, 1e-3 * numeric.mass);
    EXPECT_TRUE(axes.inertia.isApprox(numeric.inertia, 1e-3)) << axes.inertia << "\n\n" << numeric.inertia;
    EXPECT_TRUE(exact.inertia.isApprox(Q * axes.inertia * Q.transpose(), 1e-13));
    EXPECT_NEAR(exact.mass, axes.mass, 1e-14 * axes.mass);
  }
}

// Closed meshes by their triangles (signed tetrahedra): against the closed forms of a box,
// a regular tetrahedron (I = m a²/20 about any axis through its centroid, edge a) and a
// regular octahedron |x| + |y| + |z| ≤ c (I = m c²/5); turned with the shape; inward normals
// give the same; a mesh not centred on its centroid is refused, saying by how much.
TriangleMesh tetrahedron() {
  return {{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}},
          {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}}};
}

TriangleMesh octahedron(double c) {
  TriangleMesh m;
  m.vertices = {{c, 0, 0}, {-c, 0, 0}, {0, c, 0}, {0, -c, 0}, {0, 0, c}, {0, 0, -c}};
  for (const int x : {0, 1}) {
    for (const int y : {2, 3}) {
      for (const int z : {4, 5}) {
        // Counter-clockwise seen from outside the octant (x, y, z): each negative axis flips it.
        const bool even = ((x == 1) + (y == 3) + (z == 5)) % 2 == 0;
        m.triangles.push_back(even ? std::array<int, 3>{x, y, z} : std::array<int, 3>{x, z, y});
      }
    }
  }
  return m;
}

Collider mesh_solid(const TriangleMesh& mesh, const Matrix3& orientation = Matrix3::Identity()) {
  const auto shared = std::make_shared<const TriangleMesh>(mesh);
  return solid(MeshShape{std::make_shared<const GridSdf>(mesh, 0.1, 0.1), shared}, orientation);
}

TEST(MassProperties, ClosedMeshesByTheirTriangles) {
  std::mt19937 rng(9);
  const double rho = 800.0;
  const Vector3 h(0.1, 0.2, 0.3);
  const MassProperties box = mass_properties(mesh_solid(box_mesh(h)), rho, "bodies[0]");
  const MassProperties exact = mass_properties(solid(BoxShape{h, 0.0}), rho, "bodies[0]");
  EXPECT_NEAR(box.mass, exact.mass, 1e-13 * exact.mass);
  EXPECT_TRUE(box.inertia.isApprox(exact.inertia, 1e-13)) << box.inertia;

  const double m_tet = rho * 8.0 / 3.0;  // edge 2√2: V = a³/(6√2)
  const MassProperties tet = mass_properties(mesh_solid(tetrahedron()), rho, "bodies[0]");
  EXPECT_NEAR(tet.mass, m_tet, 1e-13 * m_tet);
  EXPECT_TRUE(tet.inertia.isApprox(m_tet * 8.0 / 20.0 * Matrix3::Identity(), 1e-13)) << tet.inertia;

  const double c = 0.7, m_oct = rho * 4.0 / 3.0 * c * c * c;
  const Matrix3 Q = fd::rotation_at(2.0, rng);
  const MassProperties oct = mass_properties(mesh_solid(octahedron(c), Q), rho, "bodies[0]");
  EXPECT_NEAR(oct.mass, m_oct, 1e-13 * m_oct);
  EXPECT_TRUE(oct.inertia.isApprox(m_oct * c * c / 5.0 * Matrix3::Identity(), 1e-13))
      << oct.inertia;

  // A rotated box mesh: the full tensor, Q I Qᵀ; with every triangle reversed, the same.
  TriangleMesh inward = box_mesh(h);
  for (std::array<int, 3>& t : inward.triangles) std::swap(t[1], t[2]);
  const MassProperties turned = mass_properties(mesh_solid(inward, Q), rho, "bodies[0]");
  EXPECT_NEAR(turned.mass, exact.mass, 1e-13 * exact.mass);
  EXPECT_TRUE(turned.inertia.isApprox(Q * exact.inertia * Q.transpose(), 1e-13));
  // The same box meshed with its vertices rotated (an unsymmetric mesh of a symmetric solid).
  TriangleMesh rotated = box_mesh(h);
  for (Vector3& v : rotated.vertices) v = Q * v;
  EXPECT_TRUE(mass_properties(mesh_solid(rotated), rho, "bodies[0]")
                  .inertia.isApprox(turned.inertia, 1e-13));

  // Off-centre: refused beyond 1e-6 of its size (half the diagonal, 0.374 m here).
  const auto moved = [&](double shift) {
    TriangleMesh m = box_mesh(h);
    for (Vector3& v : m.vertices) v += Vector3(shift, 0, 0);
    return mesh_solid(m);
  };
  EXPECT_NO_THROW(mass_properties(moved(3e-7), rho, "bodies[0]"));
  try {
    mass_properties(moved(0.05), rho, "bodies[3]");
    ADD_FAILURE() << "an off-centre mesh was accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.field(), "bodies[3].contact.shape.file");
    EXPECT_NE(std::string(e.what()).find("is 0.05 m from its origin"), std::string::npos)
        << e.what();
  }
}

TEST(MassProperties, ASceneMayGiveADensityInsteadOfMassAndInertia) {
  const auto body = [](const std::string& mass, const std::string& shape) {
    return parse_scene(R"({"time_step": 0.01, "frames": 1, "bodies": [{"name": "b", )" + mass +
                           R"(, "contact": {"stiffness": 1e4, "shape": )" + shape + "}}]}",
                       "density.json");
  };
  const Scene s = body(R"("density": 500)", R"({"type": "box", "half_extents": [0.1, 0.2, 0.3]})");
  EXPECT_NEAR(s.model.bodies[0].mass, 500 * 0.2 * 0.4 * 0.6, 1e-12);
  const auto error = [&](const std::string& mass, const std::string& shape) {
    try {
      body(mass, shape);
    } catch (const SceneError& e) {
      return e.field() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  const std::string box = R"({"type": "box", "half_extents": [0.1, 0.2, 0.3]})";
  EXPECT_EQ(error(R"("density": 500, "mass": 1)", box), "bodies[0].mass: give \"density\" or \"mass\" and \"inertia\", not both");
  EXPECT_EQ(error(R"("density": -1)", box), "bodies[0].density: must be a finite positive number of kg/m³");
  EXPECT_EQ(error(R"("density": 500)", R"({"type": "sphere", "radius": 0.1, "position": [0, 0, 0.1]})"),
            "bodies[0].contact.shape.position: must be the body's origin (its centre of mass) when the body gives a \"density\"");
  EXPECT_EQ(error(R"("mass": 1)", box), "bodies[0].inertia: is required but missing");
  // The new solids, and a mesh: a cube centred on its origin, and the unit cube [0, 1]³ of
  // tests/data, whose centroid is (½, ½, ½).
  const Scene torus =
      body(R"("density": 500)", R"({"type": "torus", "major_radius": 0.3, "minor_radius": 0.1})");
  EXPECT_NEAR(torus.model.bodies[0].mass,
              500 * 2 * std::numbers::pi * std::numbers::pi * 0.3 * 0.01, 1e-12);
  const Scene link =
      body(R"("density": 500)",
           R"({"type": "link", "half_length": 0.2, "major_radius": 0.3, "minor_radius": 0.1})");
  EXPECT_GT(link.model.bodies[0].mass, torus.model.bodies[0].mass);
  const Scene cylinder =
      body(R"("density": 500)", R"({"type": "cylinder", "radius": 0.1, "half_length": 0.5})");
  EXPECT_NEAR(cylinder.model.bodies[0].mass, 500 * std::numbers::pi * 0.01, 1e-12);
  const std::filesystem::path cube =
      std::filesystem::temp_directory_path() / "liedyn_test_mass_properties_cube.obj";
  std::ofstream(cube)
      << "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
         "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
  const Scene mesh = body(R"("density": 500)", R"({"type": "mesh", "file": ")" + cube.string() +
                                                   R"(", "scale": 0.1, "cell_size": 0.05})");
  EXPECT_NEAR(mesh.model.bodies[0].mass, 500 * 0.008, 1e-12);
  EXPECT_TRUE(
      mesh.model.bodies[0].inertia.isApprox(500 * 0.008 * 0.08 / 12 * Matrix3::Identity(), 1e-12));
  std::filesystem::remove(cube);
  const std::string unit_cube = std::string(LIEDYN_SOURCE_DIR) + "/tests/data/unit_cube.obj";
  EXPECT_EQ(error(R"("density": 500)",
                  R"({"type": "mesh", "file": ")" + unit_cube + R"(", "cell_size": 0.1})")
                .rfind("bodies[0].contact.shape.file: the mesh's centroid (0.5, 0.5, 0.5) is "
                       "0.866025 m from its origin",
                       0),
            0u);
}

}  // namespace
}  // namespace liedyn

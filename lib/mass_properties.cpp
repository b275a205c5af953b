#include "mass_properties.hpp"

#include <Eigen/Geometry>  // cross
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <variant>

#include "mesh_sdf.hpp"
#include "model.hpp"

namespace liedyn {
namespace {

constexpr double kPi = std::numbers::pi;

struct Moments {
  double volume = 0.0;
  Matrix3 second = Matrix3::Zero();  // S = ∫ x xᵀ about the centre, shape axes
};

Moments diagonal(double volume, const Vector3& second) {
  return {volume, Matrix3(second.asDiagonal())};
}

Moments sphere(double r) {
  return diagonal(4.0 * kPi * r * r * r / 3.0,
                  Vector3::Constant(4.0 * kPi * std::pow(r, 5) / 15.0));
}

// Along z, flat ends at z = ±h.
Moments cylinder(double h, double r) {
  const double r2 = r * r;
  const double across = kPi * r2 * r2 * h / 2.0;
  return diagonal(2.0 * kPi * r2 * h, Vector3(across, across, 2.0 * kPi * r2 * h * h * h / 3.0));
}

Moments capsule(double h, double r) {
  const double r2 = r * r, r4 = r2 * r2, r5 = r4 * r;
  const double half_sphere = 2.0 * kPi * r2 * r / 3.0;
  Moments m = cylinder(h, r);
  m.volume += 2.0 * half_sphere;
  const double across = 2.0 * (2.0 * kPi * r5 / 15.0);
  const double along =
      2.0 * (h * h * half_sphere + 2.0 * h * kPi * r4 / 4.0 + 2.0 * kPi * r5 / 15.0);
  m.second.diagonal() += Vector3(across, across, along);
  return m;
}

Moments rounded_box(const Vector3& outer, double r) {
  const Vector3 a = outer - Vector3::Constant(r);
  const double disc = kPi * r * r / 4.0, disc_u = r * r * r / 3.0, disc_u2 = kPi * std::pow(r, 4) / 16.0;
  const double octant = kPi * r * r * r / 6.0, octant_u = kPi * std::pow(r, 4) / 16.0,
               octant_u2 = kPi * std::pow(r, 5) / 30.0;
  const double volume = 8.0 * a.prod() + 8.0 * r * (a.y() * a.z() + a.x() * a.z() + a.x() * a.y()) +
                        4.0 * disc * 2.0 * a.sum() + 8.0 * octant;
  Vector3 second;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const double ai = a[i], aj = a[j], ak = a[k];
    const double core_i2 = 2.0 * ai * ai * ai / 3.0;  // ∫x_i² over [−a_i, a_i]
    double s = core_i2 * 4.0 * aj * ak;                                     // inner box
    s += 2.0 * (std::pow(ai + r, 3) - ai * ai * ai) / 3.0 * 4.0 * aj * ak;  // the two slabs across i
    s += 2.0 * core_i2 * r * 2.0 * ak + 2.0 * core_i2 * r * 2.0 * aj;       // the slabs across j and k
    const double beyond_disc = ai * ai * disc + 2.0 * ai * disc_u + disc_u2;
    s += 4.0 * 2.0 * ak * beyond_disc + 4.0 * 2.0 * aj * beyond_disc;  // edges along k and j
    s += 4.0 * disc * core_i2;                                         // edges along i
    s += 8.0 * (ai * ai * octant + 2.0 * ai * octant_u + octant_u2);   // corners
    second[i] = s;
  }
  return diagonal(volume, second);
}

// Link (torus: L = 0; header).
Moments link(double L, double R, double r) {
  const double r2 = r * r, r4 = r2 * r2;
  const double half_torus = kPi * kPi * R * r2;
  const double torus_across = kPi * kPi * R * R * R * r2 + 0.75 * kPi * kPi * R * r4;  // ∫x², ∫y²
  const double torus_along = 0.5 * kPi * kPi * R * r4;                                 // ∫z²
  const double first = 2.0 * kPi * r2 * R * R + 0.5 * kPi * r4;  // ∫x' over a half, x' ≥ 0
  const Moments side = cylinder(L, r);                           // along z: its x, x, z moments
  const double side_across = side.second(0, 0), side_along = side.second(2, 2);
  Moments m;
  m.volume = 2.0 * side.volume + 2.0 * half_torus;
  m.second.diagonal() = Vector3(
      2.0 * side_along + torus_across + 4.0 * L * first + 2.0 * L * L * half_torus,
      2.0 * (side_across + R * R * side.volume) + torus_across, 2.0 * side_across + torus_along);
  return m;
}

std::string text(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

// Closed triangle mesh: signed tetrahedra from the origin (header). The grid built from the
// mesh checked it closed and consistently oriented; inward normals (V < 0) flip every sign.
Moments mesh(const TriangleMesh& mesh, const std::string& field) {
  Moments m;
  Vector3 first = Vector3::Zero();  // ∫x
  Vector3 low = mesh.vertices.front(), high = low;
  for (const Vector3& v : mesh.vertices) {
    low = low.cwiseMin(v);
    high = high.cwiseMax(v);
  }
  for (const std::array<int, 3>& t : mesh.triangles) {
    const Vector3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Vector3& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Vector3& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    const double v = a.dot(b.cross(c)) / 6.0;
    const Vector3 s = a + b + c;
    m.volume += v;
    first += (v / 4.0) * s;
    m.second += (v / 20.0) *
                (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  if (m.volume < 0.0) {
    m.volume = -m.volume;
    first = -first;
    m.second = -m.second;
  }
  const Vector3 centroid = first / m.volume;
  const double size = 0.5 * (high - low).norm();
  if (!(centroid.norm() <= kMeshCentroidTolerance * size)) {
    throw ModelError(
        field, "the mesh's centroid (" + text(centroid.x()) + ", " + text(centroid.y()) + ", " +
                   text(centroid.z()) + ") is " + text(centroid.norm()) +
                   " m from its origin, more than " + text(kMeshCentroidTolerance) +
                   " × its size " + text(size) +
                   " m (half its bounding box's diagonal): a body's origin is its centre "
                   "of mass, so the mesh must be centred on its centroid");
  }
  m.second -= m.volume * centroid * centroid.transpose();  // about the centroid
  return m;
}

}  // namespace

MassProperties mass_properties(const Collider& shape, double density, const std::string& path) {
  if (!std::isfinite(density) || !(density > 0.0)) {
    throw ModelError(path + ".density", "must be a finite positive number of kg/m³");
  }
  if (shape.position.norm() != 0.0) {
    throw ModelError(path + ".contact.shape.position",
                     "must be the body's origin (its centre of mass) when the body gives a \"density\"");
  }
  validate_body_shape(shape, path + ".contact.shape");
  const Moments m = std::visit(
      [&](const auto& s) -> Moments {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, SphereShape>) return sphere(s.radius);
        if constexpr (std::is_same_v<S, CapsuleShape>) return capsule(s.half_length, s.radius);
        if constexpr (std::is_same_v<S, BoxShape>) return rounded_box(s.half_extents, s.rounding);
        if constexpr (std::is_same_v<S, TorusShape>)
          return link(0.0, s.major_radius, s.minor_radius);
        if constexpr (std::is_same_v<S, CylinderShape>) return cylinder(s.half_length, s.radius);
        if constexpr (std::is_same_v<S, LinkShape>)
          return link(s.half_length, s.major_radius, s.minor_radius);
        if constexpr (std::is_same_v<S, MeshShape>)
          return mesh(*s.mesh, path + ".contact.shape.file");
        // Not body shapes: validate_body_shape refused them above.
        if constexpr (std::is_same_v<S, PlaneShape> || std::is_same_v<S, TubeShape>)
          return Moments{};
      },
      shape.shape);
  MassProperties out;
  out.mass = density * m.volume;
  const Matrix3 about_centre = density * (m.second.trace() * Matrix3::Identity() - m.second);
  const Matrix3 turned = shape.orientation * about_centre * shape.orientation.transpose();
  out.inertia = 0.5 * (turned + turned.transpose());
  return out;
}

}  // namespace liedyn

#include "shapes.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <type_traits>

#include "../lib/so3.hpp"

namespace liedyn {
namespace {

using ordered_json = nlohmann::ordered_json;

ordered_json vec(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

ordered_json quat(const Matrix3& R) {
  const Eigen::Quaterniond q = so3::to_quaternion(R);
  return {q.w(), q.x(), q.y(), q.z()};
}

ordered_json flat(const std::vector<Vector3>& points) {
  ordered_json out = ordered_json::array();
  for (const Vector3& p : points) {
    out.push_back(p.x());
    out.push_back(p.y());
    out.push_back(p.z());
  }
  return out;
}

// A mesh's vertices mapped by x → position + orientation x, with its triangles.
ordered_json mesh_json(const TriangleMesh& mesh, const Vector3& position, const Matrix3& orientation) {
  std::vector<Vector3> vertices;
  vertices.reserve(mesh.vertices.size());
  for (const Vector3& v : mesh.vertices) vertices.push_back(position + orientation * v);
  ordered_json triangles = ordered_json::array();
  for (const auto& t : mesh.triangles) {
    for (const int i : t) triangles.push_back(i);
  }
  return {{"type", "mesh"}, {"vertices", flat(vertices)}, {"triangles", triangles}};
}

constexpr int kSegments = 24;  // around every circle of a tessellated shape

// A ring of `segments` points of radius r about each point of a closed curve (points c_i,
// in-plane unit normals n_i, the curve in the xy plane), stitched into triangles whose normals
// point away from the curve (ring points c + r (cos v n + sin v e_z); with the curve run
// counter-clockwise, ∂/∂s × ∂/∂v is the outward radius).
TriangleMesh swept_circle(const std::vector<Vector3>& curve, const std::vector<Vector3>& normals,
                          double r, int segments) {
  TriangleMesh mesh;
  const int n = static_cast<int>(curve.size());
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < segments; ++j) {
      const double v = 2.0 * M_PI * j / segments;
      mesh.vertices.push_back(curve[i] + r * (std::cos(v) * normals[i] + std::sin(v) * Vector3::UnitZ()));
    }
  }
  const auto at = [&](int i, int j) { return (i % n) * segments + (j % segments); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < segments; ++j) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
      mesh.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return mesh;
}

// The stadium curve of a link (lib/sdf.hpp): half circles of radius R about (±L, 0, 0)
// joined by straight sides, counter-clockwise seen from +z; a circle when L = 0.
TriangleMesh link_surface(double L, double R, double r, int segments) {
  std::vector<Vector3> curve, normals;
  const auto arc = [&](double cx, double from) {
    for (int k = 0; k < segments; ++k) {
      const double a = from + M_PI * k / segments;
      const Vector3 n(std::cos(a), std::sin(a), 0.0);
      curve.push_back(Vector3(cx, 0.0, 0.0) + R * n);
      normals.push_back(n);
    }
  };
  arc(L, -M_PI / 2);  // the straight sides are the spans between the arcs' ends
  arc(-L, M_PI / 2);
  return swept_circle(curve, normals, r, segments);
}

// A closed cylinder along z: its side, then a fan for each cap.
TriangleMesh cylinder_surface(double r, double h, int segments) {
  TriangleMesh mesh;
  for (const double z : {-h, h}) {
    for (int j = 0; j < segments; ++j) {
      const double a = 2.0 * M_PI * j / segments;
      mesh.vertices.emplace_back(r * std::cos(a), r * std::sin(a), z);
    }
  }
  const int bottom = 2 * segments, top = 2 * segments + 1;
  mesh.vertices.emplace_back(0.0, 0.0, -h);
  mesh.vertices.emplace_back(0.0, 0.0, h);
  for (int j = 0; j < segments; ++j) {
    const int a = j, b = (j + 1) % segments;  // bottom ring; the top ring is + segments
    mesh.triangles.push_back({a, b, a + segments});
    mesh.triangles.push_back({b, b + segments, a + segments});
    mesh.triangles.push_back({top, a + segments, b + segments});
    mesh.triangles.push_back({bottom, b, a});
  }
  return mesh;
}

// The body's drawing in body coordinates (shapes.hpp): its solid in the solid's own frame,
// with that frame's pose in the body when it is not the body's.
ordered_json body_shape(const RigidBody& body) {
  if (body.shape && !std::holds_alternative<PlaneShape>(body.shape->shape) &&
      !std::holds_alternative<TubeShape>(body.shape->shape)) {
    const Collider& c = *body.shape;
    ordered_json j = std::visit(
        [&](const auto& s) -> ordered_json {
          using S = std::decay_t<decltype(s)>;
          if constexpr (std::is_same_v<S, SphereShape>) {
            return {{"type", "sphere"}, {"radius", s.radius}};
          } else if constexpr (std::is_same_v<S, BoxShape>) {
            return {{"type", "box"}, {"half_extents", vec(s.half_extents)}, {"rounding", s.rounding}};
          } else if constexpr (std::is_same_v<S, CapsuleShape>) {
            return {{"type", "capsule"}, {"radius", s.radius}, {"half_length", s.half_length}};
          } else if constexpr (std::is_same_v<S, CylinderShape>) {
            return {{"type", "cylinder"}, {"radius", s.radius}, {"half_length", s.half_length}};
          } else if constexpr (std::is_same_v<S, TorusShape>) {
            return {{"type", "torus"}, {"major_radius", s.major_radius}, {"minor_radius", s.minor_radius}};
          } else {
            return mesh_json(tessellate(s, kSegments), Vector3::Zero(), Matrix3::Identity());
          }
        },
        c.shape);
    if (!c.position.isZero(0.0) || !c.orientation.isIdentity(0.0)) {
      j["position"] = vec(c.position);
      j["rotation"] = quat(c.orientation);
    }
    return j;
  }
  // No solid (or a kinematic body's plane or tube, which has no extent to draw): its contact
  // samples, else a triad.
  if (!body.contact_points.empty()) {
    return {{"type", "points"}, {"points", flat(body.contact_points)},
            {"radius", std::max(body.contact.radius, 1e-3)}};
  }
  // The radius of the ball with the body's mass and inertia trace (tr I = 6/5 m r²).
  const double size = std::sqrt(5.0 * body.inertia.trace() / (6.0 * body.mass));
  return {{"type", "axes"}, {"size", std::isfinite(size) && size > 0.0 ? size : 0.1}};
}

ordered_json collider_json(const Collider& c) {
  const Vector3& o = c.position;
  const Matrix3& R = c.orientation;
  ordered_json j = std::visit(
      [&](const auto& s) -> ordered_json {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, PlaneShape>) {
          return {{"type", "plane"}, {"point", vec(o)}, {"normal", vec(R.col(2))}};
        } else if constexpr (std::is_same_v<S, SphereShape>) {
          return {{"type", "sphere"}, {"center", vec(o)}, {"radius", s.radius}};
        } else if constexpr (std::is_same_v<S, BoxShape>) {
          return {{"type", "box"}, {"center", vec(o)}, {"half_extents", vec(s.half_extents)},
                  {"rotation", quat(R)}, {"rounding", s.rounding}};
        } else if constexpr (std::is_same_v<S, CapsuleShape>) {
          return {{"type", "capsule"}, {"a", vec(o - s.half_length * R.col(2))},
                  {"b", vec(o + s.half_length * R.col(2))}, {"radius", s.radius}};
        } else if constexpr (std::is_same_v<S, TubeShape>) {
          std::vector<Vector3> points;
          for (const Vector3& p : s.polyline) points.push_back(o + R * p);
          return {{"type", "tube"}, {"points", flat(points)}, {"radius", s.radius}};
        } else if constexpr (std::is_same_v<S, MeshShape>) {
          if (!s.mesh) return {{"type", "mesh"}, {"vertices", ordered_json::array()}, {"triangles", ordered_json::array()}};
          return mesh_json(*s.mesh, o, R);
        } else {
          return mesh_json(tessellate(s, kSegments), o, R);
        }
      },
      c.shape);
  j["name"] = c.name;
  j["inside"] = c.inside;
  return j;
}

}  // namespace

TriangleMesh tessellate(const Shape& shape, int segments) {
  if (segments < 3) throw std::invalid_argument("tessellate: segments must be ≥ 3");
  return std::visit(
      [&](const auto& s) -> TriangleMesh {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, TorusShape>) {
          return link_surface(0.0, s.major_radius, s.minor_radius, segments);
        } else if constexpr (std::is_same_v<S, LinkShape>) {
          return link_surface(s.half_length, s.major_radius, s.minor_radius, segments);
        } else if constexpr (std::is_same_v<S, CylinderShape>) {
          return cylinder_surface(s.radius, s.half_length, segments);
        } else if constexpr (std::is_same_v<S, MeshShape>) {
          if (!s.mesh) throw std::invalid_argument("tessellate: a mesh without its triangles");
          return *s.mesh;
        } else {
          throw std::invalid_argument("tessellate: this shape is drawn as a primitive, not a mesh");
        }
      },
      shape);
}

nlohmann::ordered_json scene_shapes(const Scene& scene, int trajectory_every) {
  const Model& model = scene.model;
  ordered_json j = {{"title", scene.source},
                    {"time_step", model.time_step},
                    {"trajectory_every", trajectory_every},
                    {"bodies", ordered_json::array()},
                    {"rods", ordered_json::array()},
                    {"colliders", ordered_json::array()}};
  for (const RigidBody& b : model.bodies) j["bodies"].push_back({{"name", b.name}, {"shape", body_shape(b)}});
  for (const RodSpec& r : model.rods) {
    j["rods"].push_back({{"name", r.name}, {"nodes", r.node_count()}, {"radius", r.radius}});
  }
  for (const Collider& c : model.colliders) j["colliders"].push_back(collider_json(c));
  return j;
}

}  // namespace liedyn

#include "shapes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
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

// A ring of the swept surface below: `radius` about `center` in the plane of the unit vectors
// n, b, with t = n × b the direction the rings advance in.
struct Ring {
  Vector3 center, n, b;
  double radius;
};

// The surface through a sequence of rings, each of `segments` points c + r (cos v n + sin v b),
// stitched to the next; a ring of radius 0 (only the first or the last) is one vertex, a pole
// closing the surface. With (n, b, t) right-handed, ∂/∂v = −sin v n + cos v b and (∂/∂v) × t
// is the outward radius: triangles (ring i at v, at v + dv, ring i+1 at v + dv) face outwards.
TriangleMesh ring_surface(const std::vector<Ring>& rings, int segments) {
  TriangleMesh mesh;
  std::vector<int> first;  // each ring's first vertex
  for (const Ring& ring : rings) {
    first.push_back(static_cast<int>(mesh.vertices.size()));
    if (ring.radius == 0.0) {
      mesh.vertices.push_back(ring.center);
      continue;
    }
    for (int j = 0; j < segments; ++j) {
      const double v = 2.0 * M_PI * j / segments;
      mesh.vertices.push_back(ring.center + ring.radius * (std::cos(v) * ring.n + std::sin(v) * ring.b));
    }
  }
  for (std::size_t i = 0; i + 1 < rings.size(); ++i) {
    const bool pole_here = rings[i].radius == 0.0, pole_next = rings[i + 1].radius == 0.0;
    for (int j = 0; j < segments; ++j) {
      const int k = (j + 1) % segments;
      const int a = first[i] + (pole_here ? 0 : j), b = first[i] + (pole_here ? 0 : k);
      const int c = first[i + 1] + (pole_next ? 0 : j), d = first[i + 1] + (pole_next ? 0 : k);
      if (!pole_here) mesh.triangles.push_back({a, b, d});
      if (!pole_next) mesh.triangles.push_back({a, d, c});
    }
  }
  return mesh;
}

// Rings of a hemisphere of radius r about `center` whose pole is at center + r t, segments/4
// steps of latitude (at least 2) without the equator: from the equator to the pole if
// towards_pole, else from the pole to the equator.
void hemisphere_rings(std::vector<Ring>& rings, const Vector3& center, const Vector3& n, const Vector3& b,
                      const Vector3& t, double r, int segments, bool towards_pole) {
  const int steps = std::max(2, segments / 4);
  for (int s = 1; s <= steps; ++s) {
    const int k = towards_pole ? s : steps + 1 - s;  // latitude step k: angle k/steps · π/2
    const double phi = 0.5 * M_PI * k / steps;
    rings.push_back({center + r * std::sin(phi) * t, n, b, k == steps ? 0.0 : r * std::cos(phi)});
  }
}

// A capsule about the polyline (a sphere: one point): rings at every point, perpendicular to
// the mean direction of its segments, turned by parallel transport (no twist), and a
// hemisphere at each end. For drawing: at a sharp bend the rings of neighbouring points may
// cross.
TriangleMesh swept_tube(const std::vector<Vector3>& polyline, double r, int segments) {
  const std::size_t n = polyline.size();
  std::vector<Vector3> tangents(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vector3 before = i > 0 ? (polyline[i] - polyline[i - 1]).normalized() : Vector3::Zero();
    const Vector3 after = i + 1 < n ? (polyline[i + 1] - polyline[i]).normalized() : Vector3::Zero();
    const Vector3 sum = before + after;
    // One point (a sphere): any axis will do.
    tangents[i] = sum.norm() > 1e-12 ? sum.normalized()
                  : after.norm() > 0.0 ? after
                  : before.norm() > 0.0 ? before
                                        : Vector3::UnitZ();
  }
  // A normal of the first tangent: the coordinate axis least along it, made perpendicular.
  Eigen::Index axis = 0;
  tangents[0].cwiseAbs().minCoeff(&axis);
  Vector3 normal = (Vector3::Unit(axis) - tangents[0][axis] * tangents[0]).normalized();
  std::vector<Ring> rings;
  hemisphere_rings(rings, polyline[0], normal, tangents[0].cross(normal), -tangents[0], r, segments, false);
  for (std::size_t i = 0; i < n; ++i) {
    const Vector3 projected = normal - normal.dot(tangents[i]) * tangents[i];
    if (projected.norm() > 1e-12) normal = projected.normalized();
    rings.push_back({polyline[i], normal, tangents[i].cross(normal), r});
  }
  hemisphere_rings(rings, polyline[n - 1], normal, tangents[n - 1].cross(normal), tangents[n - 1], r,
                   segments, true);
  return ring_surface(rings, segments);
}

// A box of outer half extents h whose edges are rounded by r (BoxShape's convention: the inner
// box b = h − r inflated by r). The surface of a box subdivided along each axis at
// ±(b + r tan θ_k), θ_k = k/m · π/4 (m = segments/8 per face and edge: a quarter circle in
// 2m steps, half on each face), each point p then moved to q + r (p − q)/‖p − q‖, q = the
// nearest point of the inner box: flat faces stay where they are, the bands become the
// rounded edges and corners. r = 0: a plain box of 12 triangles.
TriangleMesh box_surface(const Vector3& h, double r, int segments) {
  const Vector3 b = h - Vector3::Constant(r);
  const int m = r > 0.0 ? std::max(1, segments / 8) : 0;
  std::array<std::vector<double>, 3> at;  // the coordinates along each axis, increasing
  for (int a = 0; a < 3; ++a) {
    for (int k = m; k >= 1; --k) at[a].push_back(-(b[a] + r * std::tan(0.25 * M_PI * k / m)));
    at[a].push_back(-b[a]);
    at[a].push_back(b[a]);
    for (int k = 1; k <= m; ++k) at[a].push_back(b[a] + r * std::tan(0.25 * M_PI * k / m));
  }
  TriangleMesh mesh;
  std::map<std::array<int, 3>, int> index;  // grid point → vertex (shared by the faces)
  const auto vertex = [&](const std::array<int, 3>& g) {
    const auto [it, added] = index.emplace(g, static_cast<int>(mesh.vertices.size()));
    if (added) {
      const Vector3 p(at[0][g[0]], at[1][g[1]], at[2][g[2]]);
      const Vector3 q = p.cwiseMax(-b).cwiseMin(b);
      mesh.vertices.push_back(r > 0.0 ? Vector3(q + r * (p - q).normalized()) : p);
    }
    return it->second;
  };
  for (int a = 0; a < 3; ++a) {
    // Face ±e_a spanned by the next two axes in cyclic order (e_u × e_w = e_a): counter-
    // clockwise seen from outside on the + face, reversed on the − face.
    const int u = (a + 1) % 3, w = (a + 2) % 3;
    const int nu = static_cast<int>(at[u].size()), nw = static_cast<int>(at[w].size());
    for (const int side : {0, static_cast<int>(at[a].size()) - 1}) {
      for (int i = 0; i + 1 < nu; ++i) {
        for (int j = 0; j + 1 < nw; ++j) {
          std::array<int, 3> g00{}, g10{}, g11{}, g01{};
          for (auto* g : {&g00, &g10, &g11, &g01}) (*g)[a] = side;
          g00[u] = i, g00[w] = j;
          g10[u] = i + 1, g10[w] = j;
          g11[u] = i + 1, g11[w] = j + 1;
          g01[u] = i, g01[w] = j + 1;
          const int v00 = vertex(g00), v10 = vertex(g10), v11 = vertex(g11), v01 = vertex(g01);
          if (side > 0) {
            mesh.triangles.push_back({v00, v10, v11});
            mesh.triangles.push_back({v00, v11, v01});
          } else {
            mesh.triangles.push_back({v00, v11, v10});
            mesh.triangles.push_back({v00, v01, v11});
          }
        }
      }
    }
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
        } else if constexpr (std::is_same_v<S, SphereShape>) {
          return swept_tube({Vector3::Zero()}, s.radius, segments);
        } else if constexpr (std::is_same_v<S, CapsuleShape>) {
          if (s.half_length == 0.0) return swept_tube({Vector3::Zero()}, s.radius, segments);
          return swept_tube({-s.half_length * Vector3::UnitZ(), s.half_length * Vector3::UnitZ()}, s.radius,
                            segments);
        } else if constexpr (std::is_same_v<S, TubeShape>) {
          if (s.polyline.empty()) throw std::invalid_argument("tessellate: a tube without points");
          return swept_tube(s.polyline, s.radius, segments);
        } else if constexpr (std::is_same_v<S, BoxShape>) {
          return box_surface(s.half_extents, s.rounding, segments);
        } else if constexpr (std::is_same_v<S, MeshShape>) {
          if (!s.mesh) throw std::invalid_argument("tessellate: a mesh without its triangles");
          return *s.mesh;
        } else {
          throw std::invalid_argument("tessellate: a plane is unbounded (no surface to tessellate)");
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

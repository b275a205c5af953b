#include "export_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "../lib/model.hpp"
#include "json_reader.hpp"
#include "shapes.hpp"

namespace liedyn {
namespace {

using scene_json::item_path;
using scene_json::ObjectReader;
using json = nlohmann::json;

// A CSV or JSON quaternion may be a few digits short of unit length (Python's writer, an
// edited file), never far from it: that is a different file, not rounding.
constexpr double kUnitTolerance = 1e-3;

// A flat array of 3k finite numbers as points.
std::vector<Vector3> points_of(ObjectReader& r, const std::string& key) {
  const json& flat = r.array(key);
  if (flat.size() % 3 != 0) r.fail(r.field(key), "must hold 3 numbers per point (x0, y0, z0, x1, …)");
  std::vector<Vector3> points(flat.size() / 3);
  for (std::size_t i = 0; i < flat.size(); ++i) {
    points[i / 3][static_cast<int>(i % 3)] = r.to_number(flat[i], item_path(r.field(key), i));
  }
  return points;
}

// "rotation": (qw, qx, qy, qz) of unit length.
Eigen::Quaterniond rotation_of(ObjectReader& r, const std::string& key) {
  const Eigen::Vector4d q = r.vector<4>(key);
  if (std::abs(q.norm() - 1.0) > kUnitTolerance) {
    r.fail(r.field(key), "is not a unit quaternion (norm " + std::to_string(q.norm()) + ")");
  }
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}

double positive(ObjectReader& r, const std::string& key) {
  const double value = r.number(key);
  if (!(value > 0.0)) r.fail(r.field(key), "must be positive");
  return value;
}

// A mesh from "vertices" and "triangles" (indices into the vertices).
TriangleMesh mesh_of(ObjectReader& r) {
  TriangleMesh mesh;
  mesh.vertices = points_of(r, "vertices");
  const json& flat = r.array("triangles");
  if (flat.size() % 3 != 0) r.fail(r.field("triangles"), "must hold 3 vertex indices per triangle");
  const int last = static_cast<int>(std::min<std::size_t>(mesh.vertices.size(), std::numeric_limits<int>::max())) - 1;
  for (std::size_t i = 0; i < flat.size(); i += 3) {
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      if (last < 0) r.fail(item_path(r.field("triangles"), i), "indexes a mesh without vertices");
      t[k] = r.to_integer(flat[i + k], item_path(r.field("triangles"), i + k), 0, last);
    }
    mesh.triangles.push_back(t);
  }
  return mesh;
}

void append(TriangleMesh& to, const TriangleMesh& mesh, const RigidPose& pose) {
  const int base = static_cast<int>(to.vertices.size());
  for (const Vector3& v : mesh.vertices) to.vertices.push_back(pose.apply(v));
  for (const auto& t : mesh.triangles) to.triangles.push_back({base + t[0], base + t[1], base + t[2]});
}

// The collider's shape checked as the simulator checks it (ModelError → SceneError).
void validate(const Collider& c, const std::string& source, const std::string& path) {
  try {
    c.validate(path);
  } catch (const ModelError& e) {
    throw SceneError(source, e.field(), e.reason());
  }
}

Eigen::Quaterniond turning_z_to(const Vector3& direction) {
  return direction.norm() > 0.0 ? Eigen::Quaterniond::FromTwoVectors(Vector3::UnitZ(), direction)
                                : Eigen::Quaterniond::Identity();
}

TriangleMesh body_mesh(const json& value, const std::string& path, const std::string& source, int segments) {
  ObjectReader r(value, path, source, {"position", "rotation"},
                 {"type",
                  {{"box", {"half_extents", "rounding"}},
                   {"sphere", {"radius"}},
                   {"capsule", {"radius", "half_length"}},
                   {"cylinder", {"radius", "half_length"}},
                   {"torus", {"major_radius", "minor_radius"}},
                   {"mesh", {"vertices", "triangles"}},
                   {"points", {"points", "radius"}},
                   {"axes", {"size"}}}});
  const std::string type = r.string("type");
  // The solid's frame in the body's.
  const RigidPose placed{r.vector<3>("position", Vector3::Zero()),
                         r.has("rotation") ? rotation_of(r, "rotation") : Eigen::Quaterniond::Identity()};
  TriangleMesh mesh;
  if (type == "mesh") {
    append(mesh, mesh_of(r), placed);
  } else if (type == "points") {
    // Contact samples: a small sphere each (a third of the segments: they are many).
    const std::vector<Vector3> points = points_of(r, "points");
    const TriangleMesh ball = tessellate(SphereShape{positive(r, "radius")}, std::max(3, segments / 3));
    for (const Vector3& p : points) append(mesh, ball, RigidPose{placed.apply(p), placed.rotation});
  } else if (type == "axes") {
    // A triad: slim boxes from the origin along +x, +y, +z.
    const double size = positive(r, "size");
    for (int axis = 0; axis < 3; ++axis) {
      Vector3 half = Vector3::Constant(size / 40);
      half[axis] = size / 2;
      append(mesh, tessellate(BoxShape{half, 0.0}, segments),
             RigidPose{placed.apply(0.5 * size * Vector3::Unit(axis)), placed.rotation});
    }
  } else {
    Collider solid;
    solid.position = placed.position;
    solid.orientation = placed.rotation.toRotationMatrix();
    if (type == "box") {
      solid.shape = BoxShape{r.vector<3>("half_extents"), r.number("rounding", 0.0)};
    } else if (type == "sphere") {
      solid.shape = SphereShape{r.number("radius")};
    } else if (type == "capsule") {
      solid.shape = CapsuleShape{r.number("half_length"), r.number("radius")};
    } else if (type == "cylinder") {
      solid.shape = CylinderShape{r.number("radius"), r.number("half_length")};
    } else if (type == "torus") {
      solid.shape = TorusShape{r.number("major_radius"), r.number("minor_radius")};
    } else {
      r.fail(r.field("type"), "unknown shape type \"" + type +
                                  "\" (box, sphere, capsule, cylinder, torus, mesh, points or axes)");
    }
    validate(solid, source, path);
    append(mesh, tessellate(solid.shape, segments), placed);
  }
  r.finish();
  return mesh;
}

// A collider's surface (world) and, except for meshes, its signed distance. Planes get their
// square later, when the scene's extent is known (an empty mesh until then).
ExportGeometry::Obstacle obstacle(const json& value, const std::string& path, const std::string& source,
                                  int segments) {
  ObjectReader r(value, path, source, {"name", "inside"},
                 {"type",
                  {{"plane", {"point", "normal"}},
                   {"sphere", {"center", "radius"}},
                   {"box", {"center", "half_extents", "rotation", "rounding"}},
                   {"capsule", {"a", "b", "radius"}},
                   {"tube", {"points", "radius"}},
                   {"mesh", {"vertices", "triangles"}}}});
  ExportGeometry::Obstacle out;
  out.name = r.string("name");
  out.type = r.string("type");
  Collider c;
  c.name = out.name;
  c.inside = r.boolean("inside", false);
  if (out.type == "mesh") {
    out.mesh = mesh_of(r);
    r.finish();
    return out;
  }
  if (out.type == "plane") {
    c.shape = PlaneShape{};
    c.position = r.vector<3>("point");
    const Vector3 normal = r.vector<3>("normal");
    if (!(normal.norm() > 0.0) || !std::isfinite(normal.norm())) r.fail(r.field("normal"), "must be a non-zero vector");
    c.orientation = turning_z_to(normal.normalized()).toRotationMatrix();
  } else if (out.type == "sphere") {
    c.shape = SphereShape{r.number("radius")};
    c.position = r.vector<3>("center");
  } else if (out.type == "box") {
    c.shape = BoxShape{r.vector<3>("half_extents"), r.number("rounding", 0.0)};
    c.position = r.vector<3>("center");
    if (r.has("rotation")) c.orientation = rotation_of(r, "rotation").toRotationMatrix();
  } else if (out.type == "capsule") {
    const Vector3 a = r.vector<3>("a"), b = r.vector<3>("b");
    c.shape = CapsuleShape{0.5 * (b - a).norm(), r.number("radius")};
    c.position = 0.5 * (a + b);
    c.orientation = turning_z_to(b - a).toRotationMatrix();
  } else if (out.type == "tube") {
    c.shape = TubeShape{points_of(r, "points"), r.number("radius")};
  } else {
    r.fail(r.field("type"), "unknown collider type \"" + out.type + "\" (plane, sphere, box, capsule, tube or mesh)");
  }
  r.finish();
  validate(c, source, path);
  if (out.type != "plane") {
    const Eigen::Quaterniond q(c.orientation);
    append(out.mesh, tessellate(c.shape, segments), RigidPose{c.position, q});
  }
  out.distance = c;
  return out;
}

// The square drawn for a plane: about the projection of the centre of `lo`…`hi` (all that
// moves, and the bounded colliders), 3× their diagonal on a side, facing the plane's normal.
TriangleMesh plane_square(const Collider& plane, const Vector3& lo, const Vector3& hi) {
  const bool empty = !(lo.array() <= hi.array()).all();
  const Vector3 n = plane.orientation.col(2), u = plane.orientation.col(0), v = plane.orientation.col(1);
  Vector3 centre = empty ? plane.position : Vector3(0.5 * (lo + hi));
  centre -= n * n.dot(centre - plane.position);
  const double diagonal = empty ? 0.0 : (hi - lo).norm();
  const double half = diagonal > 0.0 ? 1.5 * diagonal : 1.0;
  TriangleMesh square;
  for (const double a : {-half, half}) {
    for (const double b : {-half, half}) square.vertices.push_back(centre + a * u + b * v);
  }
  // Vertices (−,−), (−,+), (+,−), (+,+) in (u, v): counter-clockwise seen from +n (u × v = n).
  square.triangles = {{0, 2, 3}, {0, 3, 1}};
  return square;
}

[[noreturn]] void bad_row(const RecordedRun& run, std::size_t frame, int row, const std::string& reason) {
  const RecordedRun::Row& r = run.rows[static_cast<std::size_t>(row)];
  throw SceneError((run.dir / "trajectory.csv").string(),
                   "frame " + std::to_string(run.frame_numbers[frame]) + ", " + r.object + " " + r.kind + " " +
                       std::to_string(r.index),
                   reason);
}

// Every pose finite, every quaternion of unit length.
void check_poses(const RecordedRun& run) {
  for (std::size_t f = 0; f < run.frame_count(); ++f) {
    if (!std::isfinite(run.times[f])) bad_row(run, f, 0, "time is not finite");
    for (std::size_t row = 0; row < run.rows.size(); ++row) {
      const double* p = run.pose(f, row);
      const int columns = run.rows[row].kind == "node" ? 3 : 7;
      for (int c = 0; c < columns; ++c) {
        if (!std::isfinite(p[c])) bad_row(run, f, static_cast<int>(row), "is not finite (a diverged run?)");
      }
      if (columns == 7) {
        const double norm = Eigen::Vector4d(p[3], p[4], p[5], p[6]).norm();
        if (std::abs(norm - 1.0) > kUnitTolerance) {
          bad_row(run, f, static_cast<int>(row), "is not a unit quaternion (norm " + std::to_string(norm) + ")");
        }
      }
    }
  }
}

}  // namespace

RigidPose row_pose(const RecordedRun& run, std::size_t frame, int row) {
  const double* p = run.pose(frame, static_cast<std::size_t>(row));
  return {Vector3(p[0], p[1], p[2]), Eigen::Quaterniond(p[3], p[4], p[5], p[6]).normalized()};
}

Vector3 node_position(const RecordedRun& run, std::size_t frame, int row) {
  const double* p = run.pose(frame, static_cast<std::size_t>(row));
  return {p[0], p[1], p[2]};
}

bool ExportGeometry::penetration_known() const {
  return !colliders.empty() &&
         std::all_of(colliders.begin(), colliders.end(), [](const Obstacle& c) { return c.distance.has_value(); });
}

double ExportGeometry::penetration(const Vector3& p, double radius) const {
  double deepest = -std::numeric_limits<double>::infinity();
  for (const Obstacle& c : colliders) deepest = std::max(deepest, radius - c.distance->evaluate(p, false).distance);
  return deepest;
}

ExportGeometry export_geometry(const RecordedRun& run, int segments) {
  check_poses(run);
  const std::string source = (run.dir / "shapes.json").string();
  // ObjectReader reads nlohmann::json; the run keeps shapes.json in file order.
  const json shapes = json::parse(run.shapes.dump());
  ExportGeometry g;
  const json& bodies = shapes.at("bodies");  // present: read_recorded_run checked
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const std::string path = item_path("bodies", i);
    ObjectReader r(bodies[i], path, source, {"name", "shape"});
    g.bodies.push_back({r.string("name"), static_cast<int>(i), body_mesh(r.get("shape"), path + ".shape", source, segments)});
    r.finish();
  }
  int row = static_cast<int>(g.bodies.size());
  const json& rods = shapes.at("rods");
  for (std::size_t i = 0; i < rods.size(); ++i) {
    ObjectReader r(rods[i], item_path("rods", i), source, {"name", "nodes", "radius"});
    ExportGeometry::Rod rod;
    rod.name = r.string("name");
    rod.nodes = r.integer("nodes", 2);  // its range: read_recorded_run checked
    rod.radius = positive(r, "radius");
    rod.first_node_row = row;
    rod.first_edge_row = row + rod.nodes;
    row += 2 * rod.nodes - 1;
    r.finish();
    g.rods.push_back(rod);
  }
  if (shapes.contains("colliders")) {
    const json& colliders = shapes.at("colliders");
    if (!colliders.is_array()) throw SceneError(source, "colliders", "must be an array");
    for (std::size_t i = 0; i < colliders.size(); ++i) {
      g.colliders.push_back(obstacle(colliders[i], item_path("colliders", i), source, segments));
    }
  }

  // The extent of everything drawn but the planes, for their squares.
  Vector3 lo = Vector3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  const auto add = [&](const Vector3& p, double r) {
    lo = lo.cwiseMin(p - Vector3::Constant(r));
    hi = hi.cwiseMax(p + Vector3::Constant(r));
  };
  for (const ExportGeometry::Body& b : g.bodies) {
    double reach = 0.0;
    for (const Vector3& v : b.mesh.vertices) reach = std::max(reach, v.norm());
    for (std::size_t f = 0; f < run.frame_count(); ++f) add(row_pose(run, f, b.row).position, reach);
  }
  for (const ExportGeometry::Rod& rod : g.rods) {
    for (std::size_t f = 0; f < run.frame_count(); ++f) {
      for (int k = 0; k < rod.nodes; ++k) add(node_position(run, f, rod.first_node_row + k), rod.radius);
    }
  }
  for (const ExportGeometry::Obstacle& c : g.colliders) {
    for (const Vector3& v : c.mesh.vertices) add(v, 0.0);
  }
  for (ExportGeometry::Obstacle& c : g.colliders) {
    if (c.type == "plane") c.mesh = plane_square(*c.distance, lo, hi);
  }
  return g;
}

}  // namespace liedyn

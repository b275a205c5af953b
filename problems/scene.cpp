#include "scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "../lib/body_contact.hpp"
#include "../lib/mass_properties.hpp"
#include "../lib/so3.hpp"
#include "../lib/stability.hpp"
#include "analytic.hpp"
#include "input_file.hpp"
#include "json_reader.hpp"
#include "obj_mesh.hpp"
#include "optimization.hpp"

namespace liedyn {

SceneError::SceneError(std::string file, std::string field, std::string reason)
    : std::runtime_error(file + ": " + (field.empty() ? std::string() : field + ": ") + reason),
      file_(std::move(file)),
      field_(std::move(field)),
      reason_(std::move(reason)) {}

namespace {

using nlohmann::json;
using scene_json::item_path;
using scene_json::ObjectReader;

// Body name → index, for springs, forces and torques. `rods` holds the rod names (which
// loads cannot refer to: rods take node_forces instead).
int body_index(ObjectReader& r, const std::string& key, const std::map<std::string, int>& names,
               const std::set<std::string>& rods, bool allow_world) {
  const std::string name = allow_world ? r.string(key, "world") : r.string(key);
  if (allow_world && name == "world") return -1;
  const auto it = names.find(name);
  if (it == names.end()) {
    if (rods.count(name)) {
      r.fail(r.field(key), "names the rod \"" + name +
                               "\"; springs, forces and torques act on bodies only (load a rod "
                               "with its node_forces)");
    }
    std::string known;
    for (const auto& [n, i] : names) known += (known.empty() ? "" : ", ") + n;
    r.fail(r.field(key), "names no body \"" + name + "\" (bodies: " + known +
                             (allow_world ? "; or \"world\")" : ")"));
  }
  return it->second;
}

// Names of bodies and rods share one namespace (trajectory.csv's `object` column). Checks a
// new name at `field` and records it as belonging to `owner` (e.g. "bodies[0]").
// Names end up in CSV and JSON outputs and in terminal messages: commas and quotes are
// quoted there (RFC 4180), but a control character (a line break, NUL, ESC) would split a
// row or rewrite the terminal, so it is refused here.
void check_printable_name(const ObjectReader& r, const std::string& name, const std::string& field) {
  for (const char ch : name) {
    const auto byte = static_cast<unsigned char>(ch);
    if (byte < 0x20 || byte == 0x7f) {
      char code[8];
      std::snprintf(code, sizeof code, "0x%02x", byte);
      r.fail(field, std::string("must not contain control characters (found ") + code + ")");
    }
  }
}

void claim_name(const ObjectReader& r, const std::string& name, const std::string& field,
                const std::string& owner, std::map<std::string, std::string>& taken) {
  if (name.empty() || name == "world") {
    r.fail(field, "must be a non-empty name other than \"world\"");
  }
  check_printable_name(r, name, field);
  const auto [it, inserted] = taken.emplace(name, owner);
  if (!inserted) r.fail(field, "repeats the name \"" + name + "\" of " + it->second);
}

// World position of a body point at the start (or the world point itself).
Vector3 initial_world_point(const Model& model, const BodyPoint& p) {
  if (p.body < 0) return p.point;
  return model.bodies[p.body].position + model.bodies[p.body].orientation * p.point;
}

// A unit vector from `key` (any finite non-zero length), scaled by its largest |component|
// before normalising: ‖v‖² of a finite v overflows from ~1.4e154 (v/‖v‖ = 0: a plane normal
// would turn horizontal) and underflows below ~1e-154.
Vector3 unit_vector(ObjectReader& r, const std::string& key) {
  const Vector3 v = r.vector<3>(key);
  const double largest = v.cwiseAbs().maxCoeff();
  if (!(largest > 0.0)) r.fail(r.field(key), "must be a non-zero vector");
  return (v / largest).normalized();
}

// A joint (docs/scene-format.md#joints). Its end b defaults to the world at a's point, b's
// point to where a's point is at the start, b's hinge axis to a's axis at the start, and a
// weld keeps the initial relative orientation: the joint starts at rest.
JointSpec parse_joint(const json& value, const std::string& path, const std::string& source,
                      const Model& model, const std::map<std::string, int>& names,
                      const std::set<std::string>& rod_names) {
  ObjectReader j(value, path, source,
                 {"name", "type", "a", "b", "compliance", "compliance_rotation", "limits", "motor",
                  "active_frames"});
  if (j.has("name")) check_printable_name(j, j.string("name"), j.field("name"));
  JointSpec spec;
  const std::string type = j.string("type");
  if (type == "ball") {
    spec.type = JointSpec::Type::kBall;
  } else if (type == "hinge") {
    spec.type = JointSpec::Type::kHinge;
  } else if (type == "weld") {
    spec.type = JointSpec::Type::kWeld;
  } else if (type == "slider") {
    spec.type = JointSpec::Type::kSlider;
  } else if (type == "splice") {
    spec.type = JointSpec::Type::kSplice;
    if (j.has("compliance_rotation")) {
      j.fail(j.field("compliance_rotation"), "a splice bends and twists as the rods do (their bending_stiffness)");
    }
  } else {
    j.fail(j.field("type"), "unknown joint type \"" + type +
                                "\" (expected \"ball\", \"hinge\", \"slider\", \"weld\" or \"splice\")");
  }
  if (j.has("limits")) {
    const Eigen::Vector2d limits = j.vector<2>("limits");  // [lo, hi]
    spec.has_limits = true;
    spec.lower_limit = limits(0);
    spec.upper_limit = limits(1);
  }
  if (j.has("motor")) {
    ObjectReader m(j.get("motor"), j.field("motor"), source, {"torque", "force"});
    if (spec.type == JointSpec::Type::kHinge) {
      if (m.has("force")) m.fail(m.field("force"), "a hinge's motor is a torque (\"torque\": τ about its axis)");
      spec.motor_effort = m.number("torque");
    } else if (spec.type == JointSpec::Type::kSlider) {
      if (m.has("torque")) m.fail(m.field("torque"), "a slider's motor is a force (\"force\": f along its axis)");
      spec.motor_effort = m.number("force");
    } else {
      m.fail(j.field("motor"), "only a hinge (a torque about its axis) or a slider (a force along it) has a motor");
    }
    spec.has_motor = true;
    m.finish();
  }
  if (j.has("active_frames")) {  // [first, last], last −1: to the end of the run
    const json& frames = j.get("active_frames");
    const std::string field = j.field("active_frames");
    if (!frames.is_array() || frames.size() != 2) {
      j.fail(field, "must be [first, last]: the steps in which the joint holds (last -1: to the end)");
    }
    spec.first_frame = j.to_integer(frames[0], field + "[0]", 1);
    const int last = j.to_integer(frames[1], field + "[1]", -1);
    if (last == 0 || (last > 0 && last < spec.first_frame)) {
      j.fail(field + "[1]", "must be -1 (to the end) or a step >= first (" + std::to_string(spec.first_frame) + ")");
    }
    spec.last_frame = last < 0 ? std::numeric_limits<int>::max() : last;
  }
  spec.compliance = j.number("compliance", 0.0);
  spec.compliance_rotation = j.number("compliance_rotation", spec.compliance);
  const bool hinge = spec.type == JointSpec::Type::kHinge;
  // An end: {"body": name, "point", "axis"}, {"rod": name, "node": i},
  // {"rod": name, "edge": j, "point", "axis"} or, for b only, {"world": point, "axis"}.
  const auto parse_end = [&](const char* key, bool is_b) {
    ObjectReader e(j.get(key), j.field(key), source, {"body", "point", "axis", "world", "rod", "node", "edge"});
    const int kinds = e.has("body") + e.has("world") + e.has("rod");
    if (kinds != 1) {
      e.fail(e.field(kinds == 0 ? "body" : "world"),
             is_b ? "give one of \"body\", \"rod\" or \"world\"" : "give one of \"body\" or \"rod\"");
    }
    JointEnd end;
    if (e.has("world")) {
      if (!is_b) e.fail(e.field("world"), "end a must be a body or a rod (put the world at end b)");
      end = JointEnd::world(e.vector<3>("world"));
    } else if (e.has("rod")) {
      const std::string rod = e.string("rod");
      const auto& rods = model.rods;
      const auto it = std::find_if(rods.begin(), rods.end(), [&](const RodSpec& r) { return r.name == rod; });
      if (it == rods.end()) e.fail(e.field("rod"), "names no rod \"" + rod + "\"");
      const int r = static_cast<int>(it - rods.begin());
      if (e.has("node") == e.has("edge")) {
        e.fail(e.field("node"), "give one of \"node\" (a position) or \"edge\" (a frame) of the rod");
      }
      if (e.has("node")) {
        end = JointEnd::rod_node(r, e.integer("node", 0, it->node_count() - 1));
        if (e.has("point") || e.has("axis")) {
          e.fail(e.field(e.has("point") ? "point" : "axis"),
                 "a rod node end has no point or axis of its own (a rod edge has)");
        }
      } else {
        const int edge = e.integer("edge", 0, it->edge_count() - 1);
        // The edge's midpoint at the start, in its material frame (whose z axis is the edge).
        end = JointEnd::rod_edge(r, edge, Vector3(0, 0, 0.5 * (it->nodes[edge + 1] - it->nodes[edge]).norm()));
      }
    } else {
      if (e.has("node") || e.has("edge")) {
        e.fail(e.field(e.has("node") ? "node" : "edge"), "a node or an edge belongs to a \"rod\", not a body");
      }
      const std::string name = e.string("body");
      if (rod_names.count(name)) {
        e.fail(e.field("body"), "names the rod \"" + name +
                                    "\" (a joint holds a rod by {\"rod\": name, \"node\": i} or "
                                    "{\"rod\": name, \"edge\": j})");
      }
      end = JointEnd::body(body_index(e, "body", names, rod_names, false), Vector3::Zero());
    }
    const Matrix3 R = model.initial_rotation(end);
    if (end.kind == JointEnd::Kind::kBody || end.kind == JointEnd::Kind::kRodEdge) {
      if (e.has("point")) {
        end.point = e.vector<3>("point");
      } else if (is_b) {  // where a's point is at the start, in b's coordinates
        end.point = R.transpose() * (model.initial_position(spec.a) - model.initial_origin(end));
      }
    }
    if (hinge) {
      if (e.has("axis")) {
        (is_b ? spec.axis_b : spec.axis_a) = unit_vector(e, "axis");
      } else if (!is_b) {
        e.fail(e.field("axis"), "a hinge needs its axis on end a (in a's coordinates)");
      } else {  // a's axis at the start, in b's coordinates
        spec.axis_b = R.transpose() * model.initial_rotation(spec.a) * spec.axis_a;
      }
    } else if (spec.type == JointSpec::Type::kSlider) {
      if (is_b && e.has("axis")) {
        e.fail(e.field("axis"), "a slider's axis is end a's (it turns with a)");
      } else if (!is_b) {
        if (!e.has("axis")) e.fail(e.field("axis"), "a slider needs its axis on end a (in a's coordinates)");
        spec.axis_a = unit_vector(e, "axis");
      }
    } else if (e.has("axis")) {
      e.fail(e.field("axis"), "only a hinge or a slider has an axis");
    }
    e.finish();
    return end;
  };
  spec.a = parse_end("a", false);
  if (j.has("b")) {
    spec.b = parse_end("b", true);
  } else {
    spec.b = JointEnd::world(model.initial_position(spec.a));  // the world, where a's point is at the start
    if (hinge) spec.axis_b = model.initial_rotation(spec.a) * spec.axis_a;
  }
  // Weld: F_a = R_a, F_b = R_b R_b0ᵀ R_a0, so that E = F_a F_bᵀ = I at the start.
  spec.frame_b = model.initial_rotation(spec.b).transpose() * model.initial_rotation(spec.a);
  j.finish();
  return spec;
}


// Most edges a rod shape generator may produce (a typo such as 1e9 edges would otherwise
// exhaust memory before any check).
constexpr int kMaxGeneratedEdges = 1000000;

// What all rods of a scene may generate together, so that a few bytes of JSON cannot ask for
// gigabytes (many rods, or many cables, of kMaxGeneratedEdges edges each).
struct RodBudget {
  int edges = 2 * kMaxGeneratedEdges;  // produced by the "shape" and "rest_shape" generators
  int cable_points = kMaxGeneratedEdges;  // routed through by the "cables"
};

// Takes `count` items from `budget` (of `limit` for the whole scene), or fails at `field`.
void spend(const ObjectReader& r, int& budget, int count, int limit, const std::string& field,
           const std::string& what) {
  if (count > budget) {
    r.fail(field, "would bring " + what + " beyond " + std::to_string(limit) +
                      " (the limit for the whole scene)");
  }
  budget -= count;
}

// A generator's "edges": 1 … kMaxGeneratedEdges, taken from the scene's budget.
int generator_edges(ObjectReader& g, RodBudget& budget) {
  const int edges = g.integer("edges", 1, kMaxGeneratedEdges);
  spend(g, budget.edges, edges, 2 * kMaxGeneratedEdges, g.field("edges"),
        "the edges generated by the scene's shapes");
  return edges;
}

// Node positions from a "shape" generator object at `path` (docs/scene-format.md#rods).
std::vector<Vector3> rod_shape(const json& value, const std::string& path,
                               const std::string& source, RodBudget& budget) {
  // Its "type" selects the members allowed with it.
  ObjectReader g(value, path, source, {},
                 {"type",
                  {{"line", {"start", "end", "edges"}},
                   {"helix", {"radius", "pitch", "turns", "edges", "center"}}}});
  const std::string type = g.string("type");
  std::vector<Vector3> nodes;
  double size = 0.0;  // of the shape: consecutive nodes closer than 1e-12 · size coincide
  if (type == "line") {
    const Vector3 start = g.vector<3>("start");
    const Vector3 end = g.vector<3>("end");
    const int edges = generator_edges(g, budget);
    size = (end - start).norm();
    if (!(size > 0.0)) g.fail(g.field("end"), "must differ from \"start\"");
    nodes.reserve(edges + 1);
    for (int k = 0; k < edges; ++k) {
      nodes.push_back(start + (static_cast<double>(k) / edges) * (end - start));
    }
    nodes.push_back(end);
  } else if (type == "helix") {
    const double radius = g.number("radius");
    if (radius <= 0.0) g.fail(g.field("radius"), "must be positive");
    const double pitch = g.number("pitch");
    const double turns = g.number("turns");
    if (turns <= 0.0) g.fail(g.field("turns"), "must be positive");
    const int edges = generator_edges(g, budget);
    const Vector3 center = g.vector<3>("center", Vector3::Zero());
    size = radius + std::abs(pitch) * turns;
    nodes.reserve(edges + 1);
    for (int k = 0; k <= edges; ++k) {
      const double fraction = turns * k / edges;  // turns completed at node k: φ/(2π)
      const double phi = 2.0 * std::numbers::pi * fraction;
      nodes.push_back(center + Vector3(radius * std::cos(phi), radius * std::sin(phi),
                                       pitch * fraction));
    }
  } else {
    g.fail(g.field("type"),
           "unknown shape type \"" + type + "\" (expected \"line\" or \"helix\")");
  }
  g.finish();
  for (std::size_t k = 1; k < nodes.size(); ++k) {
    if (!((nodes[k] - nodes[k - 1]).norm() > 1e-12 * size)) {
      g.fail(path, "generates coincident nodes " + std::to_string(k - 1) + " and " +
                       std::to_string(k) + " (zero-length edge)");
    }
  }
  return nodes;
}

// Indices as written; their range is checked by Model::validate_rod (which names the item).
std::vector<int> index_list(ObjectReader& r, const std::string& key) {
  std::vector<int> out;
  if (!r.has(key)) return out;
  const json& items = r.array(key);
  for (std::size_t i = 0; i < items.size(); ++i) {
    out.push_back(r.to_integer(items[i], item_path(r.field(key), i),
                               std::numeric_limits<int>::min()));
  }
  return out;
}

// A prescribed motion of `rod`'s clamped nodes and edges (docs/scene-format.md#rods). The
// pivot defaults to the centroid of the moved nodes, or of the moved edges' midpoints.
PrescribedMotion parse_motion(const json& value, const std::string& path,
                              const std::string& source, const RodSpec& rod) {
  ObjectReader m(value, path, source, {"nodes", "edges", "center", "keyframes"});
  PrescribedMotion motion;
  motion.nodes = index_list(m, "nodes");
  motion.edges = index_list(m, "edges");
  if (motion.nodes.empty() && motion.edges.empty()) {
    m.fail(m.field("nodes"), "a motion must move at least one node or edge (give \"nodes\", "
                             "\"edges\" or both)");
  }
  if (m.has("center")) {
    motion.center = m.vector<3>("center");
  } else {
    // Indices are range-checked by Model::validate_rod; skip bad ones here.
    Vector3 sum = Vector3::Zero();
    int count = 0;
    const auto add = [&](int i, int j) {
      if (i < 0 || j >= rod.node_count()) return;
      sum += 0.5 * (rod.nodes[i] + rod.nodes[j]);
      ++count;
    };
    for (int i : motion.nodes) add(i, i);
    if (motion.nodes.empty()) {
      for (int j : motion.edges) add(j, j + 1);
    }
    if (count > 0) motion.center = sum / count;
  }
  const json& keys = m.array("keyframes");
  for (std::size_t k = 0; k < keys.size(); ++k) {
    ObjectReader f(keys[k], item_path(m.field("keyframes"), k), source,
                   {"time", "translation", "rotation"});
    Keyframe key;
    key.time = f.number("time");
    key.translation = f.vector<3>("translation", Vector3::Zero());
    key.rotation = f.vector<3>("rotation", Vector3::Zero());
    f.finish();
    motion.keyframes.push_back(key);
  }
  m.finish();
  return motion;
}

// Unit quaternion [w, x, y, z] at `key` as a rotation matrix (identity when absent).
Matrix3 orientation_of(ObjectReader& r, const std::string& key) {
  if (!r.has(key)) return Matrix3::Identity();
  const Eigen::Vector4d wxyz = r.vector<4>(key);
  if (std::abs(wxyz.norm() - 1.0) > kQuaternionNormTolerance) {
    std::ostringstream os;
    os << "must be a unit quaternion [w, x, y, z] (norm " << wxyz.norm() << ", tolerance "
       << kQuaternionNormTolerance << ")";
    r.fail(r.field(key), os.str());
  }
  return so3::from_quaternion(Eigen::Quaterniond(wxyz(0), wxyz(1), wxyz(2), wxyz(3)));
}

// A "kinematic" block (lib/kinematic.hpp) of an object that starts at (x0, R0): constant
// "linear_velocity" / "angular_velocity", or "keyframes" of "time", "position" and
// "orientation" (each pose member defaults to the keyframe before, or the object's own pose).
KinematicMotion parse_kinematic(const json& value, const std::string& path, const std::string& source,
                                const Vector3& x0, const Matrix3& R0) {
  ObjectReader k(value, path, source, {"linear_velocity", "angular_velocity", "keyframes"});
  KinematicMotion motion;
  if (k.has("keyframes")) {
    for (const char* key : {"linear_velocity", "angular_velocity"}) {
      if (k.has(key)) k.fail(k.field(key), "give velocities or \"keyframes\", not both");
    }
    const json& keys = k.array("keyframes");
    if (keys.empty()) k.fail(k.field("keyframes"), "must list at least one pose");
    for (std::size_t i = 0; i < keys.size(); ++i) {
      ObjectReader f(keys[i], item_path(k.field("keyframes"), i), source, {"time", "position", "orientation"});
      KinematicPose pose;
      pose.time = f.number("time");
      pose.position = f.has("position") ? f.vector<3>("position") : (i == 0 ? x0 : motion.keyframes.back().position);
      pose.orientation =
          f.has("orientation") ? orientation_of(f, "orientation") : (i == 0 ? R0 : motion.keyframes.back().orientation);
      f.finish();
      motion.keyframes.push_back(pose);
    }
  } else {
    if (!k.has("linear_velocity") && !k.has("angular_velocity")) {
      k.fail(path, "needs \"linear_velocity\", \"angular_velocity\" or \"keyframes\"");
    }
    motion.linear_velocity = k.vector<3>("linear_velocity", Vector3::Zero());
    motion.angular_velocity = k.vector<3>("angular_velocity", Vector3::Zero());
  }
  k.finish();
  return motion;
}

// Most points a scene's generated contact samples and tube polylines may hold together.
constexpr int kMaxContactSamples = 1000000;

// A collider (lib/sdf.hpp): "type" plane | sphere | box | capsule | tube | torus | cylinder |
// link | mesh, its parameters, pose ("position", "orientation"; a plane may give its "normal"
// instead) and "inside".
Collider parse_collider(const json& value, const std::string& path, const std::string& source,
                        const std::filesystem::path& folder, int& budget) {
  ObjectReader c(value, path, source, {"name", "position", "orientation", "inside"},
                 {"type",
                  {{"plane", {"normal"}},
                   {"sphere", {"radius"}},
                   {"box", {"half_extents", "rounding"}},
                   {"capsule", {"half_length", "radius"}},
                   {"tube", {"points", "samples_per_segment", "radius"}},
                   {"torus", {"major_radius", "minor_radius"}},
                   {"cylinder", {"radius", "half_length"}},
                   {"link", {"half_length", "major_radius", "minor_radius"}},
                   {"mesh", {"file", "scale", "cell_size", "padding"}}}});
  Collider collider;
  collider.name = c.string("name", path);
  check_printable_name(c, collider.name, c.field("name"));
  collider.position = c.vector<3>("position", Vector3::Zero());
  collider.orientation = orientation_of(c, "orientation");
  collider.inside = c.boolean("inside", false);
  const std::string type = c.string("type");
  if (type == "plane") {
    if (c.has("normal")) {
      if (c.has("orientation")) c.fail(c.field("normal"), "give \"normal\" or \"orientation\", not both");
      collider.orientation = minimal_rotation(Vector3::UnitZ(), unit_vector(c, "normal"));
    }
    collider.shape = PlaneShape{};
  } else if (type == "sphere") {
    collider.shape = SphereShape{c.number("radius")};
  } else if (type == "box") {
    collider.shape = BoxShape{c.vector<3>("half_extents"), c.number("rounding", 0.0)};
  } else if (type == "capsule") {
    collider.shape = CapsuleShape{c.number("half_length"), c.number("radius")};
  } else if (type == "tube") {
    // Through control "points": a Catmull–Rom spline sampled `samples_per_segment` times per
    // span (1: the polyline itself).
    const json& points = c.array("points");
    const int samples = c.has("samples_per_segment")
                            ? c.integer("samples_per_segment", 1, kMaxContactSamples)
                            : 1;
    const long long count = static_cast<long long>(points.size()) * samples;
    if (count > budget) {
      c.fail(c.field("points"), "would bring the scene's tube points and contact samples beyond " +
                                    std::to_string(kMaxContactSamples));
    }
    budget -= static_cast<int>(count);
    std::vector<Vector3> control;
    for (std::size_t i = 0; i < points.size(); ++i) {
      control.push_back(c.to_vector<3>(points[i], item_path(c.field("points"), i)));
    }
    if (control.size() < 2) c.fail(c.field("points"), "must list at least 2 points");
    for (std::size_t i = 1; i < control.size(); ++i) {
      if (!((control[i] - control[i - 1]).norm() > 0.0)) {
        c.fail(item_path(c.field("points"), i), "coincides with the previous point");
      }
    }
    TubeShape tube;
    tube.radius = c.number("radius");
    tube.polyline = samples == 1 ? control : catmull_rom_polyline(control, samples);
    collider.shape = std::move(tube);
  } else if (type == "torus") {
    collider.shape = TorusShape{c.number("major_radius"), c.number("minor_radius")};
  } else if (type == "cylinder") {
    collider.shape = CylinderShape{c.number("radius"), c.number("half_length")};
  } else if (type == "link") {
    collider.shape =
        LinkShape{c.number("half_length"), c.number("major_radius"), c.number("minor_radius")};
  } else if (type == "mesh") {
    // A closed OBJ mesh ("file", relative to the scene file's folder, times "scale") sampled on
    // a grid of "cell_size" over its bounding box grown by "padding" (lib/mesh_sdf.hpp).
    std::filesystem::path file = c.string("file");
    if (file.is_relative()) file = folder / file;
    const double scale = c.number("scale", 1.0);
    if (!(scale > 0.0)) c.fail(c.field("scale"), "must be positive");
    const double cell_size = c.number("cell_size");
    if (!(cell_size > 0.0)) c.fail(c.field("cell_size"), "must be positive");
    const double padding = c.number("padding", 2.0 * cell_size);
    if (!(padding >= 0.0)) c.fail(c.field("padding"), "must be ≥ 0");
    try {
      // The triangles stay with the grid: a body with this shape is sampled and weighed on them.
      auto mesh = std::make_shared<const TriangleMesh>(load_obj_mesh(file, scale));
      collider.shape = MeshShape{std::make_shared<const GridSdf>(*mesh, cell_size, padding), mesh};
    } catch (const GridSdfTooCostly& e) {  // too many cells, or too much work: cell_size
      c.fail(c.field("cell_size"), e.what());
    } catch (const std::exception& e) {
      c.fail(c.field("file"), e.what());
    }
  } else {
    c.fail(c.field("type"),
           "unknown collider type \"" + type +
               "\" (expected plane, sphere, box, capsule, tube, torus, cylinder, link or mesh)");
  }
  c.finish();
  return collider;
}

// The shapes a body of "bodies" can have (lib/sdf.hpp, validate_body_shape decides): its
// shape may be sampled ("sample_spacing") or filled ("density"); `path` is the shape's object
// (its "type" and "inside" are named in the error).
void require_body_shape(const ObjectReader& r, const Collider& solid, const std::string& path) {
  try {
    validate_body_shape(solid, path);
  } catch (const ModelError& e) {
    r.fail(e.field(), e.reason());
  }
}

// "contact" of a body (with "points", a "box" sample generator, or a "shape" for other bodies
// to touch with its "sample_spacing") or of a rod (every free node, and its edges against
// other rods' and, with "self_contact", its own; radius defaults to the rod's). Units and
// defaults: lib/contact.hpp, lib/body_contact.hpp, lib/edge_contact.hpp.
ContactMaterial parse_contact(ObjectReader& owner, const std::filesystem::path& folder, double default_radius,
                              std::vector<Vector3>* points, std::shared_ptr<const Collider>* shape,
                              int& budget, RodSpec* rod = nullptr) {
  // A body's contact gives its samples and its shape; a rod's samples are its nodes.
  ObjectReader::Keys keys = {"stiffness", "radius", "friction", "friction_velocity", "damping", "collides_with", "ignores"};
  if (points != nullptr) keys.insert(keys.end(), {"points", "box", "shape", "sample_spacing"});
  if (rod != nullptr) keys.insert(keys.end(), {"self_contact", "self_contact_skip"});
  ObjectReader c(owner.get("contact"), owner.field("contact"), owner.source(), keys);
  ContactMaterial m;
  m.stiffness = c.number("stiffness");
  if (!(m.stiffness > 0.0)) c.fail(c.field("stiffness"), "must be positive");
  m.radius = c.number("radius", default_radius);
  m.friction = c.number("friction", m.friction);
  m.friction_velocity = c.number("friction_velocity", m.friction_velocity);
  m.damping = c.number("damping", m.damping);
  if (rod != nullptr) {
    rod->self_contact = c.boolean("self_contact", false);
    if (c.has("self_contact_skip")) rod->self_contact_skip = c.integer("self_contact_skip", 1, 1 << 20);
  }
  // Names, resolved once every object is read (Model::validate_contact_names).
  for (const auto& [key, names] : {std::pair{"collides_with", &m.collides_with}, std::pair{"ignores", &m.ignores}}) {
    if (!c.has(key)) continue;
    const json& list = c.array(key);
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (!list[i].is_string()) c.fail(item_path(c.field(key), i), "must be the name of a body or a collider");
      names->push_back(list[i].get<std::string>());
    }
  }
  if (points != nullptr) {
    if (c.has("points")) {
      const json& list = c.array("points");
      for (std::size_t i = 0; i < list.size(); ++i) {
        points->push_back(c.to_vector<3>(list[i], item_path(c.field("points"), i)));
      }
    }
    if (c.has("box")) {
      // Samples on a box's surface: its 8 corners, `per_edge` evenly spaced points inside
      // each of its 12 edges and a per_edge × per_edge grid inside each of its 6 faces.
      ObjectReader b(c.get("box"), c.field("box"), owner.source(), {"half_extents", "per_edge"});
      const Vector3 half = b.vector<3>("half_extents");
      if (!(half.minCoeff() > 0.0)) b.fail(b.field("half_extents"), "must be positive");
      const int per_edge = b.has("per_edge") ? b.integer("per_edge", 0, 1000) : 0;
      b.finish();
      const int count = 8 + 12 * per_edge + 6 * per_edge * per_edge;
      if (count > budget) {
        b.fail(b.field("per_edge"), "would bring the scene's contact samples beyond " +
                                        std::to_string(kMaxContactSamples));
      }
      budget -= count;
      // Along each axis: the two faces (±1) and per_edge interior coordinates.
      std::vector<double> interior;
      for (int i = 1; i <= per_edge; ++i) interior.push_back(-1.0 + 2.0 * i / (per_edge + 1));
      std::vector<double> all = interior;
      all.push_back(-1.0);
      all.push_back(1.0);
      for (double u : all) {
        for (double v : all) {
          for (double w : all) {
            const int on_faces = (std::abs(u) == 1.0) + (std::abs(v) == 1.0) + (std::abs(w) == 1.0);
            if (on_faces >= 1) points->push_back(Vector3(u, v, w).cwiseProduct(half));
          }
        }
      }
    }
    if (c.has("shape")) {
      // The body's solid for other bodies (body coordinates), and with "sample_spacing" its
      // samples on its surface.
      // A tube is read against what is left of the budget, on a copy: it is refused right
      // after as a body's shape (its "type" named), not for its points (with no budget).
      int tube_points = budget;
      Collider solid = parse_collider(c.get("shape"), c.field("shape"), owner.source(), folder, tube_points);
      require_body_shape(c, solid, c.field("shape"));
      if (c.has("sample_spacing")) {
        try {
          const std::vector<Vector3> on_surface =
              surface_samples(solid, c.number("sample_spacing"), budget, owner.field("contact"));
          budget -= static_cast<int>(on_surface.size());
          points->insert(points->end(), on_surface.begin(), on_surface.end());
        } catch (const ModelError& e) {
          c.fail(c.field("sample_spacing"), e.reason());
        }
      }
      *shape = std::make_shared<const Collider>(std::move(solid));
    } else if (c.has("sample_spacing")) {
      c.fail(c.field("sample_spacing"), "samples a \"shape\": give one");
    }
    if (points->empty() && *shape == nullptr) {
      c.fail(c.field("points"), "a body's contact needs \"points\", a \"box\" of samples or a \"shape\"");
    }
  }
  c.finish();
  return m;
}

RodSpec parse_rod(const json& value, const std::string& path, const std::string& source,
                  std::map<std::string, std::string>& taken, RodBudget& budget) {
  ObjectReader r(value, path, source,
                 {"name", "nodes", "shape", "rest_nodes", "rest_shape", "mass", "radius",
                  "stretch_stiffness", "shear_stiffness", "bending_stiffness", "stretch_damping",
                  "shear_damping", "bending_damping", "fixed_nodes",
                  "fixed_edges", "node_velocities", "node_forces", "cables", "region_pushes",
                  "contact", "prescribed_motions"});
  RodSpec rod;
  rod.name = r.string("name");
  claim_name(r, rod.name, r.field("name"), path, taken);
  const bool has_nodes = r.has("nodes");
  const bool has_shape = r.has("shape");
  if (has_nodes && has_shape) {
    r.fail(path, "gives both \"nodes\" and \"shape\"; give exactly one of them");
  }
  if (has_nodes) {
    const json& nodes = r.array("nodes");
    // Explicit nodes draw on the same budget as generated ones (1e6 explicit nodes used to
    // pass and take 2.7 GB in the first step).
    spend(r, budget.edges, static_cast<int>(std::min<std::size_t>(nodes.size(), 2u * kMaxGeneratedEdges + 1u)),
          2 * kMaxGeneratedEdges, r.field("nodes"), "the nodes of the scene's rods");
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      rod.nodes.push_back(r.to_vector<3>(nodes[i], item_path(r.field("nodes"), i)));
    }
  } else if (has_shape) {
    rod.nodes = rod_shape(r.get("shape"), r.field("shape"), source, budget);
  } else {
    r.fail(r.field("nodes"), "is required but missing (give \"nodes\" or a \"shape\")");
  }
  // Optional rest shape, in the same two forms.
  if (r.has("rest_nodes") && r.has("rest_shape")) {
    r.fail(path, "gives both \"rest_nodes\" and \"rest_shape\"; give at most one of them");
  }
  if (r.has("rest_nodes")) {
    const json& nodes = r.array("rest_nodes");
    // Explicit nodes draw on the same budget as generated ones (1e6 explicit nodes used to
    // pass and take 2.7 GB in the first step).
    spend(r, budget.edges, static_cast<int>(std::min<std::size_t>(nodes.size(), 2u * kMaxGeneratedEdges + 1u)),
          2 * kMaxGeneratedEdges, r.field("rest_nodes"), "the nodes of the scene's rods");
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      rod.rest_nodes.push_back(r.to_vector<3>(nodes[i], item_path(r.field("rest_nodes"), i)));
    }
  } else if (r.has("rest_shape")) {
    rod.rest_nodes = rod_shape(r.get("rest_shape"), r.field("rest_shape"), source, budget);
  }
  if (!rod.rest_nodes.empty() && rod.rest_nodes.size() != rod.nodes.size()) {
    r.fail(r.field(r.has("rest_shape") ? "rest_shape" : "rest_nodes"),
           "has " + std::to_string(rod.rest_nodes.size()) + " nodes, but the initial shape has " +
               std::to_string(rod.nodes.size()));
  }
  rod.mass = r.number("mass");
  rod.radius = r.number("radius");
  rod.stretch_stiffness = r.number("stretch_stiffness");
  rod.shear_stiffness = r.number("shear_stiffness");
  rod.bending_stiffness = r.vector<3>("bending_stiffness");
  rod.stretch_damping = r.number("stretch_damping", 0.0);
  rod.shear_damping = r.number("shear_damping", 0.0);
  rod.bending_damping = r.vector<3>("bending_damping", Vector3::Zero());
  rod.fixed_nodes = index_list(r, "fixed_nodes");
  rod.fixed_edges = index_list(r, "fixed_edges");
  if (r.has("node_velocities")) {
    // One velocity per node; a clamped node's must be zero (Model::validate_rod, which names
    // the entry, after checking fixed_nodes).
    const json& velocities = r.array("node_velocities");
    if (velocities.size() != rod.nodes.size()) {
      r.fail(r.field("node_velocities"),
             "has " + std::to_string(velocities.size()) + " entries, but the rod has " +
                 std::to_string(rod.nodes.size()) + " nodes (give one velocity per node)");
    }
    for (std::size_t i = 0; i < velocities.size(); ++i) {
      rod.node_velocities.push_back(
          r.to_vector<3>(velocities[i], item_path(r.field("node_velocities"), i)));
    }
  }
  if (r.has("node_forces")) {
    const json& forces = r.array("node_forces");
    for (std::size_t i = 0; i < forces.size(); ++i) {
      ObjectReader f(forces[i], item_path(r.field("node_forces"), i), source, {"node", "force"});
      NodeForce force;
      force.node = f.integer("node", std::numeric_limits<int>::min());
      force.force = f.vector<3>("force");
      f.finish();
      rod.node_forces.push_back(force);
    }
  }
  if (r.has("cables")) {
    // A cable along edges first…last on the rod's surface at `angle` degrees about the edge
    // frames' z axis (0: along the frame's x axis), `radius` from the axis (default: the rod's).
    const json& cables = r.array("cables");
    for (std::size_t i = 0; i < cables.size(); ++i) {
      ObjectReader c(cables[i], item_path(r.field("cables"), i), source,
                     {"edges", "angle", "radius", "tension"});
      const Eigen::Vector2d edges = c.vector<2>("edges");
      // Range-checked before the conversion: converting 1e300 to int is undefined behaviour.
      const bool in_range =
          (edges.array() >= 0.0).all() && (edges.array() < rod.edge_count()).all();
      const int first = in_range ? static_cast<int>(edges(0)) : -1;
      const int last = in_range ? static_cast<int>(edges(1)) : -1;
      if (!in_range || first != edges(0) || last != edges(1) || last <= first) {
        c.fail(c.field("edges"), "must be two edge indices first < last < " +
                                     std::to_string(rod.edge_count()));
      }
      spend(c, budget.cable_points, last - first + 1, kMaxGeneratedEdges, c.field("edges"),
            "the points routed by the scene's cables");
      const double angle = c.number("angle", 0.0) * std::numbers::pi / 180.0;
      const double radius = c.number("radius", rod.radius);
      if (!(radius >= 0.0)) c.fail(c.field("radius"), "must be ≥ 0");
      CableSpec cable;
      cable.tension = c.number("tension", 0.0);
      if (cable.tension < 0.0) c.fail(c.field("tension"), "must be ≥ 0 (a cable cannot push)");
      for (int e = first; e <= last; ++e) {
        cable.route.push_back({e, Vector3(radius * std::cos(angle), radius * std::sin(angle), 0.0)});
      }
      c.finish();
      rod.cables.push_back(cable);
    }
  }
  if (r.has("region_pushes")) {
    const json& pushes = r.array("region_pushes");
    for (std::size_t i = 0; i < pushes.size(); ++i) {
      ObjectReader f(pushes[i], item_path(r.field("region_pushes"), i), source,
                     {"force", "center", "radius"});
      RegionPush push;
      push.force = f.vector<3>("force");
      push.center = f.vector<3>("center");
      push.radius = f.number("radius");
      f.finish();
      rod.region_pushes.push_back(push);
    }
  }
  if (r.has("contact")) {
    int no_samples = 0;  // a rod's samples are its nodes
    rod.contact = parse_contact(r, {}, rod.radius, nullptr, nullptr, no_samples, &rod);
  }
  if (r.has("prescribed_motions")) {
    const json& motions = r.array("prescribed_motions");
    for (std::size_t i = 0; i < motions.size(); ++i) {
      rod.prescribed_motions.push_back(
          parse_motion(motions[i], item_path(r.field("prescribed_motions"), i), source, rod));
    }
  }
  r.finish();
  return rod;
}

// A string field naming one value of an enumeration: parsed by `parse`, else an error naming
// `field` (the dotted path), the value and the `expected` names.
template <class Enum>
Enum named_value(ObjectReader& reader, const std::string& key, const std::string& field,
                 const std::string& fallback, std::optional<Enum> (*parse)(std::string_view),
                 const std::string& what, const std::string& expected) {
  const std::string value = reader.string(key, fallback);
  const std::optional<Enum> parsed = parse(value);
  if (!parsed) reader.fail(field, "unknown " + what + " \"" + value + "\" (expected " + expected + ")");
  return *parsed;
}

Scene parse(const json& root, const std::string& source, const std::filesystem::path& folder) {
  Scene scene;
  scene.source = source;
  ObjectReader top(root, "", source,
                   {"description", "time_step", "integrator", "frames", "gravity", "mode", "solver", "bodies",
                    "rods", "colliders", "springs", "joints", "forces", "torques", "optimization",
                    "analytic"});
  scene.description = top.string("description", "");
  scene.model.time_step = top.number("time_step");
  if (scene.model.time_step <= 0.0) top.fail("time_step", "must be positive");
  scene.frames = top.integer("frames", 0, kMaxFrames);
  scene.model.gravity = top.vector<3>("gravity", Vector3::Zero());
  const std::string mode = top.string("mode", "dynamic");
  if (mode != "dynamic" && mode != "static") {
    top.fail("mode", "must be \"dynamic\" or \"static\" (got \"" + mode + "\")");
  }
  scene.model.static_equilibrium = mode == "static";
  scene.model.integrator = named_value(top, "integrator", "integrator", "backward_euler",
                                       &parse_integrator, "integrator",
                                       "\"backward_euler\", \"trapezoidal\" or \"bdf2\"");
  scene.model.load_steps = std::max(scene.frames, 1);

  if (top.has("solver")) {
    ObjectReader s(top.get("solver"), "solver", source,
                   {"backend", "rotation", "tolerance", "max_iterations", "armijo",
                    "min_step_length", "convergence_check", "hessian_reuse", "assembly_threads",
                    "island_threads", "ceres", "ipopt"});
    scene.solver.backend = named_value(s, "backend", "solver.backend", "newton", &parse_backend,
                                       "backend", "\"newton\", \"ceres\" or \"ipopt\"");
    scene.solver.rotation =
        named_value(s, "rotation", "solver.rotation", "lie", &parse_rotation,
                    "rotation parameterisation", "\"lie\", \"rotvec\" or \"quat\"");
    scene.solver.tolerance = s.number("tolerance", scene.solver.tolerance);
    if (s.has("max_iterations")) scene.solver.max_iterations = s.integer("max_iterations", 1);
    scene.solver.armijo = s.number("armijo", scene.solver.armijo);
    scene.solver.min_step_length = s.number("min_step_length", scene.solver.min_step_length);
    scene.solver.convergence_check =
        named_value(s, "convergence_check", "solver.convergence_check", "estimated",
                    &parse_convergence_check, "convergence check", "\"estimated\" or \"assembled\"");
    if (s.has("hessian_reuse")) scene.solver.hessian_reuse = s.integer("hessian_reuse", 1);
    if (s.has("assembly_threads")) {
      scene.solver.assembly_threads =
          s.integer("assembly_threads", 0, SolverOptions::kMaxAssemblyThreads);
    }
    if (s.has("island_threads")) {
      scene.solver.island_threads =
          s.integer("island_threads", 0, SolverOptions::kMaxAssemblyThreads);
    }
    // Back-end options: accepted whichever back-end runs, so that `liedyn compare
    // --backends` can switch; their values are checked by SolverOptions::validate.
    if (s.has("ceres")) {
      ObjectReader c(s.get("ceres"), "solver.ceres", source,
                     {"linear_solver", "trust_region_strategy", "lie_blocks", "verbose"});
      CeresOptions& o = scene.solver.ceres;
      o.linear_solver = c.string("linear_solver", o.linear_solver);
      o.trust_region_strategy = c.string("trust_region_strategy", o.trust_region_strategy);
      o.lie_blocks = c.string("lie_blocks", o.lie_blocks);
      o.verbose = c.boolean("verbose", o.verbose);
      c.finish();
    }
    if (s.has("ipopt")) {
      // "output_file" is declared to be refused with its reason below.
      ObjectReader i(s.get("ipopt"), "solver.ipopt", source,
                     {"hessian_approximation", "print_level", "derivative_test", "output_file",
                      "max_recentrings"});
      IpoptOptions& o = scene.solver.ipopt;
      o.hessian_approximation = i.string("hessian_approximation", o.hessian_approximation);
      if (i.has("print_level")) o.print_level = i.integer("print_level", 0, 12);
      o.derivative_test = i.string("derivative_test", o.derivative_test);
      // A scene is untrusted input and never chooses where liedyn writes: Ipopt's log file
      // is named on the command line (--ipopt-log), not here.
      if (i.has("output_file")) {
        i.fail(i.field("output_file"),
               "is not read from scene files (a scene must not choose where liedyn writes); "
               "give the log file on the command line: --ipopt-log FILE");
      }
      if (i.has("max_recentrings")) o.max_recentrings = i.integer("max_recentrings", 0);
      i.finish();
    }
    s.finish();
  }

  std::map<std::string, int> names;              // body name → index
  std::map<std::string, std::string> taken;      // body and rod names → owner, e.g. "rods[0]"
  const bool has_bodies = top.has("bodies");
  const bool has_rods = top.has("rods");
  if (!has_bodies && !has_rods) {
    top.fail("bodies", "is required but missing (a scene needs \"bodies\", \"rods\" or both)");
  }
  const json no_items = json::array();
  const json& bodies = has_bodies ? top.array("bodies") : no_items;
  int contact_budget = kMaxContactSamples;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    ObjectReader b(bodies[i], item_path("bodies", i), source,
                   {"name", "mass", "inertia", "density", "position", "orientation", "linear_velocity",
                    "angular_velocity", "contact", "kinematic"});
    RigidBody body;
    body.name = b.string("name");
    claim_name(b, body.name, b.field("name"), item_path("bodies", i), taken);
    names.emplace(body.name, static_cast<int>(i));
    body.position = b.vector<3>("position", Vector3::Zero());
    body.orientation = orientation_of(b, "orientation");
    body.linear_velocity = b.vector<3>("linear_velocity", Vector3::Zero());
    body.angular_velocity = b.vector<3>("angular_velocity", Vector3::Zero());
    if (b.has("contact")) {
      body.contact = parse_contact(b, folder, 0.0, &body.contact_points, &body.shape, contact_budget);
    }
    if (b.has("kinematic")) {
      for (const char* key : {"mass", "inertia", "density", "linear_velocity", "angular_velocity"}) {
        if (b.has(key)) {
          b.fail(b.field(key), "a kinematic body follows its motion: it has no mass or inertia, and its "
                               "velocities are given in \"kinematic\"");
        }
      }
      body.kinematic = parse_kinematic(b.get("kinematic"), b.field("kinematic"), source, body.position, body.orientation);
    } else if (b.has("density")) {
      // Mass and inertia of the body's shape, filled with that density.
      for (const char* key : {"mass", "inertia"}) {
        if (b.has(key)) b.fail(b.field(key), "give \"density\" or \"mass\" and \"inertia\", not both");
      }
      if (body.shape == nullptr) b.fail(b.field("density"), "needs the body's \"contact\": {\"shape\"} to fill");
      try {
        const MassProperties m = mass_properties(*body.shape, b.number("density"), item_path("bodies", i));
        body.mass = m.mass;
        body.inertia = m.inertia;
      } catch (const ModelError& e) {
        b.fail(e.field(), e.reason());
      }
    } else {
      body.mass = b.number("mass");
      body.inertia = b.inertia("inertia");
    }
    b.finish();
    scene.model.bodies.push_back(body);
  }

  std::set<std::string> rod_names;
  const json& rods = has_rods ? top.array("rods") : no_items;
  RodBudget budget;
  for (std::size_t i = 0; i < rods.size(); ++i) {
    scene.model.rods.push_back(parse_rod(rods[i], item_path("rods", i), source, taken, budget));
    rod_names.insert(scene.model.rods.back().name);
  }
  if (bodies.empty() && rods.empty()) {
    top.fail(has_bodies ? "bodies" : "rods",
             "the scene must contain at least one body or rod");
  }
  if (top.has("colliders")) {
    const json& colliders = top.array("colliders");
    for (std::size_t i = 0; i < colliders.size(); ++i) {
      const std::string path = item_path("colliders", i);
      if (!colliders[i].is_object() || !colliders[i].contains("kinematic")) {
        scene.model.colliders.push_back(parse_collider(colliders[i], path, source, folder, contact_budget));
        continue;
      }
      // A moving collider is a kinematic body with that shape and no samples (appended after
      // the scene's bodies, under the collider's name): what touches it, touches its shape.
      // Nothing samples or weighs that shape, so it may be any collider, a plane or a tube or
      // an inside-out one included (validate_body_shape is for the bodies' own shapes).
      json fixed = colliders[i];
      fixed.erase("kinematic");
      Collider solid = parse_collider(fixed, path, source, folder, contact_budget);
      json motion_part = json::object();  // what the collider reader above did not read
      for (const char* key : {"name", "kinematic"}) {
        if (colliders[i].contains(key)) motion_part[key] = colliders[i][key];
      }
      ObjectReader c(motion_part, path, source, {"name", "kinematic"});
      if (!c.has("name")) c.fail(c.field("name"), "a kinematic collider needs a name (it is reported as a body)");
      try {
        solid.validate(path);  // here, while its fields are the collider's
      } catch (const ModelError& e) {
        c.fail(e.field(), e.reason());
      }
      claim_name(c, solid.name, c.field("name"), path, taken);
      RigidBody body;
      body.name = solid.name;
      body.position = solid.position;
      body.orientation = solid.orientation;
      body.kinematic = parse_kinematic(c.get("kinematic"), c.field("kinematic"), source, body.position, body.orientation);
      solid.position = Vector3::Zero();
      solid.orientation = Matrix3::Identity();
      body.shape = std::make_shared<const Collider>(std::move(solid));
      names.emplace(body.name, static_cast<int>(scene.model.bodies.size()));
      scene.model.bodies.push_back(std::move(body));
    }
  }

  if (top.has("springs")) {
    const json& springs = top.array("springs");
    for (std::size_t i = 0; i < springs.size(); ++i) {
      ObjectReader s(springs[i], item_path("springs", i), source,
                     {"body_a", "point_a", "body_b", "point_b", "stiffness", "rest_length"});
      SpringSpec spec;
      spec.a.body = body_index(s, "body_a", names, rod_names, true);
      spec.a.point = s.vector<3>("point_a", Vector3::Zero());
      spec.b.body = body_index(s, "body_b", names, rod_names, true);
      spec.b.point = s.vector<3>("point_b", Vector3::Zero());
      spec.stiffness = s.number("stiffness");
      if (s.has("rest_length")) {
        spec.rest_length = s.number("rest_length");
      } else {
        // Default: the initial distance between the two points.
        spec.rest_length = (initial_world_point(scene.model, spec.b) -
                            initial_world_point(scene.model, spec.a))
                               .norm();
      }
      s.finish();
      scene.model.springs.push_back(spec);
    }
  }
  if (top.has("joints")) {
    const json& joints = top.array("joints");
    for (std::size_t i = 0; i < joints.size(); ++i) {
      scene.model.joints.push_back(
          parse_joint(joints[i], item_path("joints", i), source, scene.model, names, rod_names));
    }
  }
  if (top.has("forces")) {
    const json& forces = top.array("forces");
    for (std::size_t i = 0; i < forces.size(); ++i) {
      ObjectReader f(forces[i], item_path("forces", i), source, {"body", "point", "force"});
      ForceSpec spec;
      spec.at.body = body_index(f, "body", names, rod_names, false);
      spec.at.point = f.vector<3>("point", Vector3::Zero());
      spec.force = f.vector<3>("force");
      f.finish();
      scene.model.forces.push_back(spec);
    }
  }
  if (top.has("torques")) {
    const json& torques = top.array("torques");
    for (std::size_t i = 0; i < torques.size(); ++i) {
      ObjectReader t(torques[i], item_path("torques", i), source, {"body", "torque"});
      TorqueSpec spec;
      spec.body = body_index(t, "body", names, rod_names, false);
      spec.torque = t.vector<3>("torque");
      t.finish();
      scene.model.torques.push_back(spec);
    }
  }
  const json* optimization = top.has("optimization") ? &top.get("optimization") : nullptr;
  const std::string analytic = top.string("analytic", "none");
  if (const auto parsed = parse_analytic(analytic)) {
    scene.analytic = *parsed;
  } else {
    top.fail("analytic", "unknown solution \"" + analytic +
                             "\" (expected \"none\", \"free_body\", \"cantilever\" or "
                             "\"axial_stretch\")");
  }
  top.finish();

  // Physical checks (positivity, inertia, …) live with the model, which names the field.
  try {
    scene.model.validate();
    check_stable_start(scene.model);
    scene.solver.validate();
    if (optimization != nullptr) scene.optimization = parse_optimization(*optimization, scene);
  } catch (const ModelError& e) {
    throw SceneError(source, e.field(), e.reason());
  }
  check_analytic(scene);
  return scene;
}

// Follows the dotted path of the value being parsed, so that errors raised while parsing
// (number overflow, repeated keys) can name their field like the checks after it.
class PathTracker {
 public:
  explicit PathTracker(const std::string& source) : source_(source) {}

  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        frames_.push_back({true, 0, {}, {}});
        break;
      case json::parse_event_t::array_start:
        frames_.push_back({false, 0, {}, {}});
        break;
      case json::parse_event_t::key: {
        Frame& top = frames_.back();
        top.key = parsed.get<std::string>();
        // nlohmann::json silently keeps the last of repeated keys; reject them instead.
        if (!top.keys.insert(top.key).second) {
          throw SceneError(source_, path(), "appears twice in the same object");
        }
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        next();
        break;
      case json::parse_event_t::value:
        next();
        break;
    }
    return true;
  }

  // Dotted path of the value being parsed now.
  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) {
      if (f.object) {
        p += (p.empty() ? "" : ".") + f.key;
      } else {
        p += "[" + std::to_string(f.index) + "]";
      }
    }
    return p;
  }

 private:
  struct Frame {
    bool object;
    std::size_t index;           // arrays: index of the element being parsed
    std::string key;             // objects: key of the member being parsed
    std::set<std::string> keys;  // objects: keys seen so far
  };
  void next() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
  }

  const std::string& source_;
  std::vector<Frame> frames_;
};

}  // namespace

// FNV-1a (64 bits) of the scene's JSON as nlohmann dumps it (keys sorted, numbers at full
// precision: one text per content, whatever the file's layout), without
// optimization.max_iterations, so that continuing a run for longer is the same problem. An
// identity, not a signature: the checkpoint it guards is also re-evaluated on resume.
namespace {

std::string identity_of(json root) {
  if (root.is_object() && root.contains("optimization") && root["optimization"].is_object()) {
    root["optimization"].erase("max_iterations");
  }
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char ch : root.dump()) {
    hash ^= static_cast<unsigned char>(ch);
    hash *= 0x100000001b3ULL;
  }
  char text[20];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

}  // namespace

Scene parse_scene(const std::string& json_text, const std::string& source, const std::filesystem::path& folder) {
  // The JSON parser would stop at a NUL byte and ignore what follows.
  if (const std::size_t nul = json_text.find('\0'); nul != std::string::npos) {
    throw SceneError(source, "", "contains a NUL byte at offset " + std::to_string(nul) +
                                     " (not a text file)");
  }
  json root;
  PathTracker tracker(source);
  try {
    root = json::parse(json_text, std::ref(tracker));
  } catch (const json::out_of_range& e) {
    // e.g. 1e999 overflows a double (JSON has no Inf or NaN literals).
    throw SceneError(source, tracker.path(), std::string("must be a finite number: ") + e.what());
  } catch (const json::exception& e) {
    throw SceneError(source, "", std::string("invalid JSON: ") + e.what());
  }
  Scene scene = parse(root, source, folder.empty() ? std::filesystem::path(source).parent_path() : folder);
  scene.identity = identity_of(root);
  return scene;
}

std::string read_named_input(const std::filesystem::path& file, std::uintmax_t max_bytes,
                             const std::string& kind) {
  try {
    return read_input_file(file, max_bytes, kind);
  } catch (const InputFileError& e) {
    throw SceneError(file.string(), "", e.what());
  }
}

std::string read_scene_file(const std::filesystem::path& file) {
  return read_named_input(file, kMaxSceneFileBytes, "scene file");
}

Scene load_scene(const std::filesystem::path& file) {
  return parse_scene(read_scene_file(file), file.string(), file.parent_path());
}

}  // namespace liedyn

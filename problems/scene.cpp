#include "scene.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "../lib/so3.hpp"
#include "analytic.hpp"
#include "json_reader.hpp"
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
void claim_name(const ObjectReader& r, const std::string& name, const std::string& field,
                const std::string& owner, std::map<std::string, std::string>& taken) {
  if (name.empty() || name == "world") {
    r.fail(field, "must be a non-empty name other than \"world\"");
  }
  const auto [it, inserted] = taken.emplace(name, owner);
  if (!inserted) r.fail(field, "repeats the name \"" + name + "\" of " + it->second);
}

// Most edges a rod shape generator may produce (a typo such as 1e9 edges would otherwise
// exhaust memory before any check).
constexpr int kMaxGeneratedEdges = 1000000;

// Node positions from a "shape" generator object at `path` (docs/scene-format.md#rods).
std::vector<Vector3> rod_shape(const json& value, const std::string& path,
                               const std::string& source) {
  ObjectReader g(value, path, source);
  const std::string type = g.string("type");
  std::vector<Vector3> nodes;
  double size = 0.0;  // of the shape: consecutive nodes closer than 1e-12 · size coincide
  if (type == "line") {
    const Vector3 start = g.vector<3>("start");
    const Vector3 end = g.vector<3>("end");
    const int edges = g.integer("edges", 1, kMaxGeneratedEdges);
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
    const int edges = g.integer("edges", 1, kMaxGeneratedEdges);
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
  ObjectReader m(value, path, source);
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
    ObjectReader f(keys[k], item_path(m.field("keyframes"), k), source);
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

RodSpec parse_rod(const json& value, const std::string& path, const std::string& source,
                  std::map<std::string, std::string>& taken) {
  ObjectReader r(value, path, source);
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
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      rod.nodes.push_back(r.to_vector<3>(nodes[i], item_path(r.field("nodes"), i)));
    }
  } else if (has_shape) {
    rod.nodes = rod_shape(r.get("shape"), r.field("shape"), source);
  } else {
    r.fail(r.field("nodes"), "is required but missing (give \"nodes\" or a \"shape\")");
  }
  // Optional rest shape, in the same two forms.
  if (r.has("rest_nodes") && r.has("rest_shape")) {
    r.fail(path, "gives both \"rest_nodes\" and \"rest_shape\"; give at most one of them");
  }
  if (r.has("rest_nodes")) {
    const json& nodes = r.array("rest_nodes");
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      rod.rest_nodes.push_back(r.to_vector<3>(nodes[i], item_path(r.field("rest_nodes"), i)));
    }
  } else if (r.has("rest_shape")) {
    rod.rest_nodes = rod_shape(r.get("rest_shape"), r.field("rest_shape"), source);
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
  rod.fixed_nodes = index_list(r, "fixed_nodes");
  rod.fixed_edges = index_list(r, "fixed_edges");
  if (r.has("node_forces")) {
    const json& forces = r.array("node_forces");
    for (std::size_t i = 0; i < forces.size(); ++i) {
      ObjectReader f(forces[i], item_path(r.field("node_forces"), i), source);
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
      ObjectReader c(cables[i], item_path(r.field("cables"), i), source);
      const Eigen::Vector2d edges = c.vector<2>("edges");
      const int first = static_cast<int>(edges(0)), last = static_cast<int>(edges(1));
      if (first != edges(0) || last != edges(1) || first < 0 || last <= first ||
          last >= rod.edge_count()) {
        c.fail(c.field("edges"), "must be two edge indices first < last < " +
                                     std::to_string(rod.edge_count()));
      }
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

Scene parse(const json& root, const std::string& source) {
  Scene scene;
  scene.source = source;
  ObjectReader top(root, "", source);
  scene.description = top.string("description", "");
  scene.model.time_step = top.number("time_step");
  if (scene.model.time_step <= 0.0) top.fail("time_step", "must be positive");
  scene.frames = top.integer("frames", 0);
  scene.model.gravity = top.vector<3>("gravity", Vector3::Zero());
  const std::string mode = top.string("mode", "dynamic");
  if (mode != "dynamic" && mode != "static") {
    top.fail("mode", "must be \"dynamic\" or \"static\" (got \"" + mode + "\")");
  }
  scene.model.static_equilibrium = mode == "static";
  scene.model.load_steps = std::max(scene.frames, 1);

  if (top.has("solver")) {
    ObjectReader s(top.get("solver"), "solver", source);
    const std::string backend = s.string("backend", "newton");
    if (const auto parsed = parse_backend(backend)) {
      scene.solver.backend = *parsed;
    } else {
      s.fail("solver.backend", "unknown backend \"" + backend +
                                   "\" (expected \"newton\", \"ceres\" or \"ipopt\")");
    }
    const std::string rotation = s.string("rotation", "lie");
    if (const auto parsed = parse_rotation(rotation)) {
      scene.solver.rotation = *parsed;
    } else {
      s.fail("solver.rotation", "unknown rotation parameterisation \"" + rotation +
                                    "\" (expected \"lie\", \"rotvec\" or \"quat\")");
    }
    scene.solver.tolerance = s.number("tolerance", scene.solver.tolerance);
    if (s.has("max_iterations")) scene.solver.max_iterations = s.integer("max_iterations", 1);
    scene.solver.armijo = s.number("armijo", scene.solver.armijo);
    scene.solver.min_step_length = s.number("min_step_length", scene.solver.min_step_length);
    if (s.has("assembly_threads")) {
      scene.solver.assembly_threads =
          s.integer("assembly_threads", 0, SolverOptions::kMaxAssemblyThreads);
    }
    // Back-end options: accepted whichever back-end runs, so that `liedyn compare
    // --backends` can switch; their values are checked by SolverOptions::validate.
    if (s.has("ceres")) {
      ObjectReader c(s.get("ceres"), "solver.ceres", source);
      CeresOptions& o = scene.solver.ceres;
      o.linear_solver = c.string("linear_solver", o.linear_solver);
      o.trust_region_strategy = c.string("trust_region_strategy", o.trust_region_strategy);
      o.verbose = c.boolean("verbose", o.verbose);
      c.finish();
    }
    if (s.has("ipopt")) {
      ObjectReader i(s.get("ipopt"), "solver.ipopt", source);
      IpoptOptions& o = scene.solver.ipopt;
      o.hessian_approximation = i.string("hessian_approximation", o.hessian_approximation);
      if (i.has("print_level")) o.print_level = i.integer("print_level", 0, 12);
      o.derivative_test = i.string("derivative_test", o.derivative_test);
      o.output_file = i.string("output_file", o.output_file);
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
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    ObjectReader b(bodies[i], item_path("bodies", i), source);
    RigidBody body;
    body.name = b.string("name");
    claim_name(b, body.name, b.field("name"), item_path("bodies", i), taken);
    names.emplace(body.name, static_cast<int>(i));
    body.mass = b.number("mass");
    body.inertia = b.inertia("inertia");
    body.position = b.vector<3>("position", Vector3::Zero());
    if (b.has("orientation")) {
      const Eigen::Vector4d wxyz = b.vector<4>("orientation");
      if (std::abs(wxyz.norm() - 1.0) > kQuaternionNormTolerance) {
        std::ostringstream os;
        os << "must be a unit quaternion [w, x, y, z] (norm " << wxyz.norm()
           << ", tolerance " << kQuaternionNormTolerance << ")";
        b.fail(b.field("orientation"), os.str());
      }
      body.orientation =
          so3::from_quaternion(Eigen::Quaterniond(wxyz(0), wxyz(1), wxyz(2), wxyz(3)));
    }
    body.linear_velocity = b.vector<3>("linear_velocity", Vector3::Zero());
    body.angular_velocity = b.vector<3>("angular_velocity", Vector3::Zero());
    b.finish();
    scene.model.bodies.push_back(body);
  }

  std::set<std::string> rod_names;
  const json& rods = has_rods ? top.array("rods") : no_items;
  for (std::size_t i = 0; i < rods.size(); ++i) {
    scene.model.rods.push_back(parse_rod(rods[i], item_path("rods", i), source, taken));
    rod_names.insert(scene.model.rods.back().name);
  }
  if (bodies.empty() && rods.empty()) {
    top.fail(has_bodies ? "bodies" : "rods",
             "the scene must contain at least one body or rod");
  }

  if (top.has("springs")) {
    const json& springs = top.array("springs");
    for (std::size_t i = 0; i < springs.size(); ++i) {
      ObjectReader s(springs[i], item_path("springs", i), source);
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
        const auto world = [&](const BodyPoint& p) -> Vector3 {
          if (p.body < 0) return p.point;
          const RigidBody& body = scene.model.bodies[p.body];
          return body.position + body.orientation * p.point;
        };
        spec.rest_length = (world(spec.b) - world(spec.a)).norm();
      }
      s.finish();
      scene.model.springs.push_back(spec);
    }
  }
  if (top.has("forces")) {
    const json& forces = top.array("forces");
    for (std::size_t i = 0; i < forces.size(); ++i) {
      ObjectReader f(forces[i], item_path("forces", i), source);
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
      ObjectReader t(torques[i], item_path("torques", i), source);
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
    scene.solver.validate();
    if (optimization != nullptr) scene.optimization = parse_optimization(*optimization, scene);
  } catch (const ModelError& e) {
    const std::string prefix = e.field() + ": ";
    std::string reason = e.what();
    if (reason.rfind(prefix, 0) == 0) reason = reason.substr(prefix.size());
    throw SceneError(source, e.field(), reason);
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

Scene parse_scene(const std::string& json_text, const std::string& source) {
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
  return parse(root, source);
}

std::string read_scene_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw SceneError(file.string(), "", "is a directory, not a scene file");
  }
  std::ifstream in(file);
  if (!in) throw SceneError(file.string(), "", "cannot open the file for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Scene load_scene(const std::filesystem::path& file) {
  return parse_scene(read_scene_file(file), file.string());
}

}  // namespace liedyn

// Unknown keys in scene files (problems/json_reader.hpp): every object's keys are checked
// when its reader is made, so a misspelt key is reported before any other error of the same
// object — beside an invalid value of a known key, the typo is named, not the other field.
// Keys of another kind of the object (a helix's "pitch" in a line shape, a
// projected_trajectory's "node" in point_targets) are unknown there too; keys allowed but
// not read on the path taken are still refused by finish(); every bundled scene loads.

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "problems/scene.hpp"

namespace liedyn {
namespace {

using nlohmann::json;

constexpr const char* kSource = "keys_scene.json";

// A valid scene holding one object of every kind that has keys: top level, solver (with
// ceres and ipopt), a body with box contact samples, a collider, a spring, a force, a torque,
// a rod (line shape, node force, cable, region push, contact, prescribed motion with a
// keyframe) and an optimization block (one parameter, one point_targets term).
json base_scene() {
  return json::parse(R"({
    "time_step": 0.01, "frames": 5,
    "solver": { "backend": "newton", "ceres": { "verbose": false }, "ipopt": { "print_level": 0 } },
    "bodies": [ { "name": "box", "mass": 2, "inertia": [0.2, 0.3, 0.4], "position": [0, 0, 1],
                  "contact": { "stiffness": 1000,
                               "box": { "half_extents": [0.1, 0.1, 0.1], "per_edge": 1 } } } ],
    "colliders": [ { "name": "floor", "type": "plane", "normal": [0, 0, 1] } ],
    "springs": [ { "body_a": "box", "point_b": [0, 0, 2], "stiffness": 10 } ],
    "forces": [ { "body": "box", "force": [0, 1, 0] } ],
    "torques": [ { "body": "box", "torque": [0, 0, 0.1] } ],
    "rods": [ { "name": "arm",
                "shape": { "type": "line", "start": [0, 0, 2], "end": [0.3, 0, 2], "edges": 3 },
                "mass": 0.1, "radius": 0.01, "stretch_stiffness": 100, "shear_stiffness": 10,
                "bending_stiffness": [1, 2, 3], "fixed_nodes": [0], "fixed_edges": [0],
                "node_forces": [ { "node": 3, "force": [0, 0, -1] } ],
                "cables": [ { "edges": [0, 2], "tension": 1.5 } ],
                "region_pushes": [ { "force": [0, 0, 1], "center": [0.3, 0, 2], "radius": 0.05 } ],
                "contact": { "stiffness": 100 },
                "prescribed_motions": [
                  { "nodes": [0], "keyframes": [{ "time": 1, "translation": [0, 0, 0.1] }] } ] } ],
    "optimization": {
      "parameters": [ { "kind": "node_force", "rod": "arm", "node_force": 0 } ],
      "objective": [ { "term": "point_targets", "rod": "arm",
                       "targets": [[0, 0, 2], [0.1, 0, 2], [0.2, 0, 2], [0.3, 0, 2]] } ] }
  })");
}

// Parses `scene`, which must be rejected; returns the error (nothing after failing the test).
std::optional<SceneError> rejected(const json& scene) {
  try {
    parse_scene(scene.dump(), kSource);
  } catch (const SceneError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected a SceneError, got another exception: " << e.what();
    return std::nullopt;
  }
  ADD_FAILURE() << "scene was accepted:\n" << scene.dump(2);
  return std::nullopt;
}

// The error names exactly `field`, and its reason starts with `reason_start`.
void expect_error(const json& scene, const std::string& field, const std::string& reason_start) {
  const std::optional<SceneError> e = rejected(scene);
  if (!e) return;
  EXPECT_EQ(e->file(), kSource) << e->what();
  EXPECT_EQ(e->field(), field) << e->what();
  EXPECT_EQ(e->reason().rfind(reason_start, 0), 0u)
      << "reason \"" << e->reason() << "\" does not start with \"" << reason_start << "\"";
}

void expect_unknown_key(const json& scene, const std::string& field) {
  expect_error(scene, field, "unknown key (allowed here: ");
}

std::string dotted(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// One object of the scene: a bad value of one of its known keys, and a key it does not take.
struct Case {
  std::function<json&(json&)> object;  // the object in the scene
  std::string path;                    // its dotted path
  std::string bad_key;                 // set to bad_value: an error while parsing the object
  json bad_value;
  std::string unknown;  // a key the object does not take
};

std::vector<Case> cases() {
  // Copied into the cases (which outlive this function).
  const auto rod = [](json& s) -> json& { return s["rods"][0]; };
  const auto opt = [](json& s) -> json& { return s["optimization"]; };
  return {
      {[](json& s) -> json& { return s; }, "", "time_step", -1, "gravty"},
      {[](json& s) -> json& { return s["solver"]; }, "solver", "backend", "magic", "tol"},
      {[](json& s) -> json& { return s["solver"]["ceres"]; }, "solver.ceres", "verbose", 3,
       "linear_sover"},
      {[](json& s) -> json& { return s["solver"]["ipopt"]; }, "solver.ipopt", "print_level", 99,
       "print_levle"},
      {[](json& s) -> json& { return s["bodies"][0]; }, "bodies[0]", "inertia", "big", "colour"},
      {[](json& s) -> json& { return s["bodies"][0]["contact"]; }, "bodies[0].contact",
       "stiffness", -1, "frction"},
      {[](json& s) -> json& { return s["bodies"][0]["contact"]["box"]; },
       "bodies[0].contact.box", "half_extents", json::array({0, 1, 1}), "per_edges"},
      {[](json& s) -> json& { return s["colliders"][0]; }, "colliders[0]", "normal",
       json::array({0, 0, 0}), "colour"},
      {[](json& s) -> json& { return s["springs"][0]; }, "springs[0]", "body_a", "nobody",
       "damping"},
      {[](json& s) -> json& { return s["forces"][0]; }, "forces[0]", "body", "nobody", "torque"},
      {[](json& s) -> json& { return s["torques"][0]; }, "torques[0]", "body", "nobody", "point"},
      {rod, "rods[0]", "mass", "heavy", "colour"},
      {[=](json& s) -> json& { return rod(s)["shape"]; }, "rods[0].shape", "end",
       json::array({0, 0, 2}), "egdes"},
      // A helix's member in a line shape.
      {[=](json& s) -> json& { return rod(s)["shape"]; }, "rods[0].shape", "end",
       json::array({0, 0, 2}), "pitch"},
      {[=](json& s) -> json& { return rod(s)["node_forces"][0]; }, "rods[0].node_forces[0]",
       "node", 1.5, "point"},
      {[=](json& s) -> json& { return rod(s)["cables"][0]; }, "rods[0].cables[0]", "edges",
       json::array({2, 0}), "angel"},
      {[=](json& s) -> json& { return rod(s)["region_pushes"][0]; }, "rods[0].region_pushes[0]",
       "force", 1, "radious"},
      // A body's contact samples: a rod samples its nodes.
      {[=](json& s) -> json& { return rod(s)["contact"]; }, "rods[0].contact", "stiffness", -1,
       "points"},
      {[=](json& s) -> json& { return rod(s)["prescribed_motions"][0]; },
       "rods[0].prescribed_motions[0]", "keyframes", 1, "centre"},
      {[=](json& s) -> json& { return rod(s)["prescribed_motions"][0]["keyframes"][0]; },
       "rods[0].prescribed_motions[0].keyframes[0]", "time", "soon", "rotaton"},
      {opt, "optimization", "parameters", json::array(), "max_iteration"},
      {[=](json& s) -> json& { return opt(s)["parameters"][0]; }, "optimization.parameters[0]",
       "node_force", -1, "nodeforce"},
      // A body kind's member in a rod kind.
      {[=](json& s) -> json& { return opt(s)["parameters"][0]; }, "optimization.parameters[0]",
       "node_force", -1, "body"},
      {[=](json& s) -> json& { return opt(s)["objective"][0]; }, "optimization.objective[0]",
       "targets", json::array({json::array({0, 0, 0})}), "wieght"},
  };
}

TEST(SceneUnknownKeys, BaseSceneLoads) {
  const Scene s = parse_scene(base_scene().dump(), kSource);
  EXPECT_EQ(s.model.bodies.size(), 1u);
  EXPECT_EQ(s.model.rods.size(), 1u);
  EXPECT_TRUE(s.optimization.has_value());
}

// Each error alone: the bad value is an error at its key, the unknown key an unknown key.
TEST(SceneUnknownKeys, EachErrorAlone) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(dotted(c.path, c.unknown));
    json bad = base_scene();
    c.object(bad)[c.bad_key] = c.bad_value;
    expect_error(bad, dotted(c.path, c.bad_key), "");
    json unknown = base_scene();
    c.object(unknown)[c.unknown] = 1;
    expect_unknown_key(unknown, dotted(c.path, c.unknown));
  }
}

// Both together: the unknown key is reported, not the bad value (which is parsed first).
TEST(SceneUnknownKeys, UnknownKeyBeforeOtherErrorsOfTheObject) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(dotted(c.path, c.unknown));
    json scene = base_scene();
    c.object(scene)[c.bad_key] = c.bad_value;
    c.object(scene)[c.unknown] = 1;
    expect_unknown_key(scene, dotted(c.path, c.unknown));
  }
}

// The case that hid a typo: a point_targets term with a "node" (a projected_trajectory's
// member) and targets that are not points was reported at "targets".
TEST(SceneUnknownKeys, NodeBesideBadTargetsOfPointTargets) {
  json scene = base_scene();
  json& term = scene["optimization"]["objective"][0];
  term["node"] = 3;
  term["targets"] = json::array({json::array({0, 0, 0})});
  expect_error(scene, "optimization.objective[0].node",
               "unknown key (allowed here: frame, height, letter, origin, polyline, rod, "
               "targets, term, weight)");
  term.erase("targets");  // no source of targets at all
  expect_unknown_key(scene, "optimization.objective[0].node");
}

// Keys of another kind of the object are unknown in this one, named with the keys it takes.
TEST(SceneUnknownKeys, KeysOfAnotherKindAreUnknown) {
  json pitch = base_scene();
  pitch["rods"][0]["shape"]["pitch"] = 0.1;
  expect_error(pitch, "rods[0].shape.pitch", "unknown key (allowed here: edges, end, start, type)");
  json radius = base_scene();
  radius["colliders"][0]["radius"] = 1;
  expect_error(radius, "colliders[0].radius",
               "unknown key (allowed here: inside, name, normal, orientation, position, type)");
  json rod_of_force = base_scene();
  rod_of_force["optimization"]["parameters"][0] = {{"kind", "force"}, {"index", 0}, {"rod", "arm"}};
  expect_error(rod_of_force, "optimization.parameters[0].rod",
               "unknown key (allowed here: index, kind, lower, upper)");
}

// A kind that does not exist (or none) allows the keys of every kind: its own error is
// reported, unless a key no kind takes is there too.
TEST(SceneUnknownKeys, UnknownKindReportsTheKindOrAKeyNoKindTakes) {
  json cone = base_scene();
  cone["colliders"][0] = {{"type", "cone"}, {"radius", 1}, {"half_length", 1}};
  expect_error(cone, "colliders[0].type", "unknown collider type \"cone\"");
  cone["colliders"][0]["colour"] = "red";
  expect_unknown_key(cone, "colliders[0].colour");
  json untyped = base_scene();
  untyped["rods"][0]["shape"].erase("type");
  expect_error(untyped, "rods[0].shape.type", "is required but missing");
  json term = base_scene();
  term["optimization"]["objective"][0]["term"] = "distance";
  expect_error(term, "optimization.objective[0].term", "unknown objective term \"distance\"");
}

// Keys allowed for the object's kind but not read on the path its other keys take are
// refused by finish(), naming the keys that path read.
TEST(SceneUnknownKeys, KeysOffThePathTakenAreRefusedByFinish) {
  json height = base_scene();  // "height" goes with a "letter", not with "targets"
  height["optimization"]["objective"][0]["height"] = 2;
  expect_error(height, "optimization.objective[0].height",
               "unknown key (allowed here: frame, letter, polyline, rod, targets, term, weight)");
  json node = base_scene();  // a projected_trajectory's "node" is a rod's, not a body's
  node["optimization"]["objective"][0] = {{"term", "projected_trajectory"},
                                          {"body", "box"},
                                          {"node", 1},
                                          {"curve", json::array({json::array({0, 0}),
                                                                 json::array({1, 1})})}};
  expect_error(node, "optimization.objective[0].node",
               "unknown key (allowed here: body, curve, plane, term, weight)");
  node["optimization"]["objective"][0].erase("node");
  EXPECT_NO_THROW(parse_scene(node.dump(), kSource));
}

// Every scene under problems/scenes loads: the declared keys cover everything they use.
TEST(SceneUnknownKeys, EveryBundledSceneLoads) {
  int scenes = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(
           std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes")) {
    if (entry.path().extension() != ".json") continue;
    ++scenes;
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(load_scene(entry.path()));
  }
  EXPECT_GT(scenes, 20);
}

}  // namespace
}  // namespace liedyn

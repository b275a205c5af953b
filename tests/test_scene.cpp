// Scene files: parse_scene / load_scene (problems/scene.hpp), documented in
// docs/scene-format.md. Valid scenes must produce exactly the Model they describe (with the
// documented defaults); every kind of bad input must raise a SceneError that names the file
// and the exact dotted path of the offending field.

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/LU>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "problems/scene.hpp"
#include "problems/scene_settings.hpp"

namespace liedyn::scene_tests {
namespace {

constexpr const char* kSource = "unit_scene.json";

const std::string kBody = R"("name": "a", "mass": 2, "inertia": [1, 2, 2.5])";

// A scene with one body (its members given by `body`) and extra top-level members `extra`,
// which must end with ", " when not empty.
std::string scene(const std::string& body = kBody, const std::string& extra = "") {
  return R"({"time_step": 0.01, "frames": 5, )" + extra + R"("bodies": [{)" + body + "}]}";
}

// Parses text that must be rejected; returns the error (or fails the test).
SceneError rejected(const std::string& text) {
  try {
    parse_scene(text, kSource);
  } catch (const SceneError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected a SceneError, got another exception: " << e.what();
    return SceneError("", "", "");
  }
  ADD_FAILURE() << "scene was accepted:\n" << text;
  return SceneError("", "", "");
}

// The error names the file and `field` (exactly), and its reason contains `reason_part`.
void expect_rejected(const std::string& text, const std::string& field,
                     const std::string& reason_part = "") {
  SCOPED_TRACE(text);
  const SceneError e = rejected(text);
  EXPECT_EQ(e.field(), field) << e.what();
  EXPECT_EQ(e.file(), kSource);
  const std::string what = e.what();
  EXPECT_EQ(what.rfind(std::string(kSource) + ": ", 0), 0u) << what;
  if (!field.empty()) {
    EXPECT_NE(what.find(": " + field + ": "), std::string::npos) << what;
  }
  EXPECT_NE(e.reason().find(reason_part), std::string::npos)
      << "reason \"" << e.reason() << "\" lacks \"" << reason_part << "\"";
}

// --- Valid scenes ----------------------------------------------------------------------

TEST(SceneParse, MinimalSceneGetsDefaults) {
  const Scene s = parse_scene(scene(), kSource);
  EXPECT_EQ(s.source, kSource);
  EXPECT_EQ(s.description, "");
  EXPECT_EQ(s.frames, 5);
  EXPECT_DOUBLE_EQ(s.model.time_step, 0.01);
  EXPECT_TRUE(s.model.gravity.isZero(0.0));
  ASSERT_EQ(s.model.bodies.size(), 1u);
  const RigidBody& b = s.model.bodies[0];
  EXPECT_EQ(b.name, "a");
  EXPECT_DOUBLE_EQ(b.mass, 2.0);
  EXPECT_TRUE(b.inertia.isApprox(Vector3(1, 2, 2.5).asDiagonal().toDenseMatrix(), 0.0));
  EXPECT_TRUE(b.position.isZero(0.0));
  EXPECT_TRUE(b.orientation.isIdentity(0.0));
  EXPECT_TRUE(b.linear_velocity.isZero(0.0));
  EXPECT_TRUE(b.angular_velocity.isZero(0.0));
  EXPECT_TRUE(s.model.springs.empty());
  EXPECT_TRUE(s.model.forces.empty());
  EXPECT_TRUE(s.model.torques.empty());
  EXPECT_DOUBLE_EQ(s.solver.tolerance, 1e-9);
  EXPECT_EQ(s.solver.max_iterations, 50);
  EXPECT_DOUBLE_EQ(s.solver.armijo, 1e-4);
  EXPECT_DOUBLE_EQ(s.solver.min_step_length, 1e-10);
}

TEST(SceneParse, FullSceneGivesTheDescribedModel) {
  const std::string text = R"({
    "description": "two bodies",
    "time_step": 0.005,
    "frames": 7,
    "gravity": [0, 0, -9.81],
    "solver": { "backend": "newton", "rotation": "lie", "tolerance": 1e-8,
                "max_iterations": 12, "armijo": 0.01, "min_step_length": 1e-6 },
    "bodies": [
      { "name": "a", "mass": 1.5, "inertia": [1, 2, 2.5],
        "position": [1, 2, 3], "orientation": [1, 0, 0, 0],
        "linear_velocity": [0.1, 0.2, 0.3], "angular_velocity": [-1, 0, 4] },
      { "name": "b", "mass": 3, "inertia": [[2, 0.1, 0], [0.1, 2, 0], [0, 0, 3]],
        "position": [4, 2, 3] }
    ],
    "springs": [
      { "body_a": "a", "point_a": [0, 0, 0.5], "body_b": "b", "point_b": [0, 0, -0.5],
        "stiffness": 100, "rest_length": 1.25 },
      { "point_a": [0, 0, 10], "body_b": "b", "stiffness": 5 }
    ],
    "forces": [ { "body": "b", "point": [0, 1, 0], "force": [1, 0, 0] },
                { "body": "a", "force": [0, 0, 2] } ],
    "torques": [ { "body": "a", "torque": [0, 0, 0.5] } ]
  })";
  const Scene s = parse_scene(text, kSource);
  EXPECT_EQ(s.description, "two bodies");
  EXPECT_EQ(s.frames, 7);
  EXPECT_DOUBLE_EQ(s.model.time_step, 0.005);
  EXPECT_TRUE(s.model.gravity.isApprox(Vector3(0, 0, -9.81), 0.0));
  EXPECT_DOUBLE_EQ(s.solver.tolerance, 1e-8);
  EXPECT_EQ(s.solver.max_iterations, 12);
  EXPECT_DOUBLE_EQ(s.solver.armijo, 0.01);
  EXPECT_DOUBLE_EQ(s.solver.min_step_length, 1e-6);

  ASSERT_EQ(s.model.bodies.size(), 2u);
  const RigidBody& a = s.model.bodies[0];
  EXPECT_EQ(a.name, "a");
  EXPECT_DOUBLE_EQ(a.mass, 1.5);
  EXPECT_TRUE(a.position.isApprox(Vector3(1, 2, 3), 0.0));
  EXPECT_TRUE(a.orientation.isIdentity(1e-15));
  EXPECT_TRUE(a.linear_velocity.isApprox(Vector3(0.1, 0.2, 0.3), 0.0));
  EXPECT_TRUE(a.angular_velocity.isApprox(Vector3(-1, 0, 4), 0.0));
  const RigidBody& b = s.model.bodies[1];
  EXPECT_EQ(b.name, "b");
  Matrix3 Ib;
  Ib << 2, 0.1, 0, 0.1, 2, 0, 0, 0, 3;
  EXPECT_TRUE(b.inertia.isApprox(Ib, 0.0));
  EXPECT_TRUE(b.linear_velocity.isZero(0.0));

  ASSERT_EQ(s.model.springs.size(), 2u);
  const SpringSpec& s0 = s.model.springs[0];
  EXPECT_EQ(s0.a.body, 0);
  EXPECT_EQ(s0.b.body, 1);
  EXPECT_TRUE(s0.a.point.isApprox(Vector3(0, 0, 0.5), 0.0));
  EXPECT_TRUE(s0.b.point.isApprox(Vector3(0, 0, -0.5), 0.0));
  EXPECT_DOUBLE_EQ(s0.stiffness, 100.0);
  EXPECT_DOUBLE_EQ(s0.rest_length, 1.25);
  const SpringSpec& s1 = s.model.springs[1];
  EXPECT_EQ(s1.a.body, -1);  // omitted body_a: a world anchor
  EXPECT_EQ(s1.b.body, 1);
  EXPECT_TRUE(s1.b.point.isZero(0.0));
  // Default rest length: initial distance from the anchor (0,0,10) to b's centre (4,2,3).
  EXPECT_NEAR(s1.rest_length, std::sqrt(16.0 + 4.0 + 49.0), 1e-14);

  ASSERT_EQ(s.model.forces.size(), 2u);
  EXPECT_EQ(s.model.forces[0].at.body, 1);
  EXPECT_TRUE(s.model.forces[0].at.point.isApprox(Vector3(0, 1, 0), 0.0));
  EXPECT_TRUE(s.model.forces[0].force.isApprox(Vector3(1, 0, 0), 0.0));
  EXPECT_EQ(s.model.forces[1].at.body, 0);
  EXPECT_TRUE(s.model.forces[1].at.point.isZero(0.0));
  ASSERT_EQ(s.model.torques.size(), 1u);
  EXPECT_EQ(s.model.torques[0].body, 0);
  EXPECT_TRUE(s.model.torques[0].torque.isApprox(Vector3(0, 0, 0.5), 0.0));
}

TEST(SceneParse, SpringRestLengthDefaultsToInitialDistanceOfRotatedPoints) {
  // Body a is turned 90° about z, so its body point (1,0,0) sits at world (0,1,0); body b's
  // centre is at (3,1,0). The distance is 3 only if the orientation is applied (unrotated
  // it would be √5).
  const std::string text = R"({"time_step": 0.01, "frames": 1, "bodies": [
      {"name": "a", "mass": 1, "inertia": [1, 1, 1],
       "orientation": [0.70710678118654752, 0, 0, 0.70710678118654752]},
      {"name": "b", "mass": 1, "inertia": [1, 1, 1], "position": [3, 1, 0]}],
    "springs": [{"body_a": "a", "point_a": [1, 0, 0], "body_b": "b",
                 "stiffness": 10}]})";
  const Scene s = parse_scene(text, kSource);
  ASSERT_EQ(s.model.springs.size(), 1u);
  EXPECT_NEAR(s.model.springs[0].rest_length, 3.0, 1e-14);
}

TEST(SceneParse, InertiaAsMomentsOrMatrix) {
  const Scene moments =
      parse_scene(scene(R"("name": "a", "mass": 1, "inertia": [3, 4, 5])"), kSource);
  Matrix3 expected = Matrix3::Zero();
  expected.diagonal() << 3, 4, 5;
  EXPECT_TRUE(moments.model.bodies[0].inertia.isApprox(expected, 0.0));

  const Scene matrix = parse_scene(
      scene(R"("name": "a", "mass": 1, "inertia": [[3, 0.5, -0.25], [0.5, 4, 0], [-0.25, 0, 5]])"),
      kSource);
  expected << 3, 0.5, -0.25, 0.5, 4, 0, -0.25, 0, 5;
  EXPECT_TRUE(matrix.model.bodies[0].inertia.isApprox(expected, 0.0));
}

TEST(SceneParse, InertiaLimitsOfTheTriangleInequality) {
  // A thin rod has one moment → 0 (moments must stay > 0): near the limit is accepted.
  EXPECT_NO_THROW(
      parse_scene(scene(R"("name": "a", "mass": 1, "inertia": [1e-9, 1, 1])"), kSource));
  // A flat plate meets the triangle inequality with equality (I3 = I1 + I2).
  EXPECT_NO_THROW(parse_scene(scene(R"("name": "a", "mass": 1, "inertia": [1, 1, 2])"), kSource));
}

TEST(SceneParse, QuaternionIsWxyzBodyToWorld) {
  // 90° about z: [w, x, y, z] = [cos 45°, 0, 0, sin 45°] maps the body x axis to world y.
  const double c = std::cos(std::numbers::pi / 4), sn = std::sin(std::numbers::pi / 4);
  char orientation[128];
  std::snprintf(orientation, sizeof orientation, R"("orientation": [%.17g, 0, 0, %.17g])", c, sn);
  const Scene s = parse_scene(scene(kBody + ", " + orientation), kSource);
  const Matrix3& R = s.model.bodies[0].orientation;
  EXPECT_TRUE((R * Vector3::UnitX()).isApprox(Vector3::UnitY(), 1e-15)) << R;
  EXPECT_TRUE((R * Vector3::UnitY()).isApprox(-Vector3::UnitX(), 1e-15)) << R;
  EXPECT_TRUE((R * Vector3::UnitZ()).isApprox(Vector3::UnitZ(), 1e-15)) << R;

  // [0, 0, 0, 1] is w = 0, z = 1: half a turn about z (in [x, y, z, w] order it would be
  // the identity).
  const Scene half = parse_scene(scene(kBody + R"(, "orientation": [0, 0, 0, 1])"), kSource);
  EXPECT_TRUE(
      (half.model.bodies[0].orientation * Vector3::UnitX()).isApprox(-Vector3::UnitX(), 1e-15));
}

TEST(SceneParse, NearlyUnitQuaternionIsNormalised) {
  // ‖q‖ − 1 = 5e-7 is within kQuaternionNormTolerance = 1e-6.
  const Scene s = parse_scene(
      scene(kBody + R"(, "orientation": [0.7071071367811865, 0, 0, 0.7071071367811865])"), kSource);
  const Matrix3& R = s.model.bodies[0].orientation;
  EXPECT_LT((R.transpose() * R - Matrix3::Identity()).norm(), 1e-14);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
  EXPECT_TRUE((R * Vector3::UnitX()).isApprox(Vector3::UnitY(), 1e-12)) << R;
}

// A relative mesh path is read from the scene file's folder, also when --set values (with a
// '/' in them) label the scene: the label is not a path.
TEST(SceneParse, RelativeMeshPathsAreReadFromTheSceneFolderWhateverTheSettings) {
  const std::filesystem::path file =
      std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact/mesh_slab.json";
  const Scene s = load_scene(file, {"colliders.0.file=meshes/slab.obj", "frames=3"});
  EXPECT_EQ(s.source, file.string() + " [colliders.0.file=meshes/slab.obj frames=3]");
  ASSERT_EQ(s.model.colliders.size(), 1u);
  // A file that is not beside the scene is named as the scene's folder's.
  try {
    load_scene(file, {"colliders.0.file=meshes/none.obj"});
    FAIL() << "a missing mesh loaded";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find((file.parent_path() / "meshes/none.obj").string()), std::string::npos)
        << e.what();
  }
}

TEST(SceneParse, LoadsTheButterflyBoltExample) {
  const std::filesystem::path file =
      std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/butterfly_bolt.json";
  const Scene s = load_scene(file);
  EXPECT_EQ(s.source, file.string());
  EXPECT_EQ(s.frames, 1000);
  EXPECT_DOUBLE_EQ(s.model.time_step, 0.01);
  ASSERT_EQ(s.model.bodies.size(), 1u);
  EXPECT_EQ(s.model.bodies[0].name, "bolt");
  Matrix3 expected = Matrix3::Zero();
  expected.diagonal() << 1.0, 2.0, 2.8;
  EXPECT_TRUE(s.model.bodies[0].inertia.isApprox(expected, 0.0));
  EXPECT_TRUE(s.model.bodies[0].angular_velocity.isApprox(Vector3(0, 2, 0.01), 0.0));
}

// --- Bad input: every error names the file and the field ------------------------------

TEST(SceneErrors, MessageIsFileFieldReason) {
  const SceneError e = rejected(scene(R"("name": "a", "mass": -1, "inertia": [1, 1, 1])"));
  EXPECT_EQ(std::string(e.what()), std::string(kSource) + ": bodies[0].mass: " + e.reason());
}

TEST(SceneErrors, MissingFields) {
  expect_rejected(R"({"frames": 1, "bodies": [{)" + kBody + "}]}", "time_step", "missing");
  expect_rejected(R"({"time_step": 0.01, "bodies": [{)" + kBody + "}]}", "frames", "missing");
  expect_rejected(R"({"time_step": 0.01, "frames": 1})", "bodies", "missing");
  expect_rejected(scene(R"("mass": 1, "inertia": [1, 1, 1])"), "bodies[0].name", "missing");
  expect_rejected(scene(R"("name": "a", "inertia": [1, 1, 1])"), "bodies[0].mass", "missing");
  expect_rejected(scene(R"("name": "a", "mass": 1)"), "bodies[0].inertia", "missing");
  expect_rejected(scene(kBody, R"("springs": [{"body_b": "a"}], )"), "springs[0].stiffness",
                  "missing");
  expect_rejected(scene(kBody, R"("forces": [{"body": "a"}], )"), "forces[0].force", "missing");
  expect_rejected(scene(kBody, R"("forces": [{"force": [1, 0, 0]}], )"), "forces[0].body",
                  "missing");
  expect_rejected(scene(kBody, R"("torques": [{"body": "a"}], )"), "torques[0].torque", "missing");
}

TEST(SceneErrors, WrongTypes) {
  expect_rejected(R"({"time_step": "0.01", "frames": 1, "bodies": [{)" + kBody + "}]}", "time_step",
                  "number");
  expect_rejected(scene(R"("name": "a", "mass": "2", "inertia": [1, 1, 1])"), "bodies[0].mass",
                  "number");
  expect_rejected(scene(R"("name": "a", "mass": null, "inertia": [1, 1, 1])"), "bodies[0].mass",
                  "null");
  expect_rejected(scene(R"("name": 3, "mass": 1, "inertia": [1, 1, 1])"), "bodies[0].name",
                  "string");
  expect_rejected(scene(kBody + R"(, "position": [0, 0])"), "bodies[0].position", "3 numbers");
  expect_rejected(scene(kBody + R"(, "position": [0, "1", 0])"), "bodies[0].position[1]", "number");
  expect_rejected(scene(kBody + R"(, "angular_velocity": {"x": 1})"), "bodies[0].angular_velocity",
                  "3 numbers");
  expect_rejected(scene(kBody + R"(, "orientation": [1, 0, 0])"), "bodies[0].orientation",
                  "4 numbers");
  expect_rejected(scene(R"("name": "a", "mass": 1, "inertia": "big")"), "bodies[0].inertia", "3×3");
  expect_rejected(scene(R"("name": "a", "mass": 1, "inertia": [[1, 0, 0], [0, 1], [0, 0, 1]])"),
                  "bodies[0].inertia[1]", "3 numbers");
  expect_rejected(scene(R"("name": "a", "mass": 1, "inertia": [[1, 0, 0], [0, 1, 0]])"),
                  "bodies[0].inertia", "3×3");
  expect_rejected(scene(kBody, R"("gravity": 9.81, )"), "gravity", "3 numbers");
  expect_rejected(scene(kBody, R"("description": 5, )"), "description", "string");
  expect_rejected(scene(kBody, R"("solver": "newton", )"), "solver", "object");
  expect_rejected(scene(kBody, R"("springs": {"body_b": "a"}, )"), "springs", "array");
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": {"a": {}}})", "bodies", "array");
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody + "}, 7]}",
                  "bodies[1]", "object");
  expect_rejected(R"([1, 2, 3])", "", "object");
}

TEST(SceneErrors, NonFiniteNumbers) {
  // JSON has no Inf: an overflowing literal must not become one.
  expect_rejected(scene(R"("name": "a", "mass": 1e999, "inertia": [1, 1, 1])"), "bodies[0].mass",
                  "finite");
  expect_rejected(scene(kBody, R"("gravity": [0, 0, -1e999], )"), "gravity[2]", "finite");
  expect_rejected(scene(kBody + R"(, "linear_velocity": [1e999, 0, 0])"),
                  "bodies[0].linear_velocity[0]", "finite");
  expect_rejected(R"({"time_step": 1e999, "frames": 1, "bodies": [{)" + kBody + "}]}", "time_step",
                  "finite");
  // Nor NaN or Infinity literals: they are JSON syntax errors, reported against the file.
  expect_rejected(scene(R"("name": "a", "mass": NaN, "inertia": [1, 1, 1])"), "", "invalid JSON");
  expect_rejected(scene(kBody + R"(, "position": [Infinity, 0, 0])"), "", "invalid JSON");
}

TEST(SceneErrors, NonPositiveMass) {
  expect_rejected(scene(R"("name": "a", "mass": 0, "inertia": [1, 1, 1])"), "bodies[0].mass",
                  "positive");
  expect_rejected(scene(R"("name": "a", "mass": -2, "inertia": [1, 1, 1])"), "bodies[0].mass",
                  "positive");
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody +
                      R"(}, {"name": "b", "mass": -1e-300, "inertia": [1, 1, 1]}]})",
                  "bodies[1].mass", "positive");
}

TEST(SceneErrors, BadInertia) {
  const auto second_body = [](const std::string& inertia) {
    return R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody +
           R"(}, {"name": "b", "mass": 1, "inertia": )" + inertia + "}]}";
  };
  expect_rejected(second_body("[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]"), "bodies[1].inertia",
                  "symmetric");
  // Symmetric with eigenvalues 3, −1, 1.
  expect_rejected(second_body("[[1, 2, 0], [2, 1, 0], [0, 0, 1]]"), "bodies[1].inertia",
                  "positive definite");
  expect_rejected(second_body("[-1, 2, 2]"), "bodies[1].inertia", "positive definite");
  expect_rejected(second_body("[0.0, 1, 1]"), "bodies[1].inertia", "positive definite");
  expect_rejected(second_body("[1, 1, 3]"), "bodies[1].inertia", "triangle");
  expect_rejected(second_body("[1, 1, 2.001]"), "bodies[1].inertia", "triangle");
  // Rotated so the violation is not visible on the diagonal alone: moments 1, 1, 3 about
  // axes turned 45° about z.
  expect_rejected(second_body("[[2, 1, 0], [1, 2, 0], [0, 0, 1]]"), "bodies[1].inertia",
                  "triangle");
  expect_rejected(second_body("[[1, 0, 0], [0, 1, 0], [0, 0, 1e999]]"), "bodies[1].inertia[2][2]",
                  "finite");
}

TEST(SceneErrors, NonUnitQuaternion) {
  expect_rejected(scene(kBody + R"(, "orientation": [1.00001, 0, 0, 0])"), "bodies[0].orientation",
                  "unit quaternion");
  expect_rejected(scene(kBody + R"(, "orientation": [1, 1, 0, 0])"), "bodies[0].orientation",
                  "unit quaternion");
  expect_rejected(scene(kBody + R"(, "orientation": [0, 0, 0, 0])"), "bodies[0].orientation",
                  "unit quaternion");
  EXPECT_NO_THROW(parse_scene(scene(kBody + R"(, "orientation": [1.0000005, 0, 0, 0])"), kSource));
}

TEST(SceneErrors, UnknownKeys) {
  expect_rejected(scene(kBody, R"("gravty": [0, 0, -9.81], )"), "gravty", "unknown key");
  expect_rejected(scene(kBody + R"(, "colour": "red")"), "bodies[0].colour", "unknown key");
  expect_rejected(scene(kBody + R"(, "angular_velocity_body": [0, 0, 1])"),
                  "bodies[0].angular_velocity_body", "unknown key");
  expect_rejected(scene(kBody, R"("solver": {"tol": 1e-6}, )"), "solver.tol", "unknown key");
  expect_rejected(scene(kBody, R"("springs": [{"body_b": "a", "stiffness": 1, "damping": 2}], )"),
                  "springs[0].damping", "unknown key");
  expect_rejected(scene(kBody, R"("forces": [{"body": "a", "force": [0, 0, 1], "torque": 1}], )"),
                  "forces[0].torque", "unknown key");
  // The reason lists what is allowed.
  const SceneError e = rejected(scene(kBody + R"(, "colour": "red")"));
  EXPECT_NE(e.reason().find("inertia"), std::string::npos) << e.reason();
}

TEST(SceneErrors, RepeatedKeysAreNotSilentlyMerged) {
  expect_rejected(scene(R"("name": "a", "mass": 1, "mass": -1, "inertia": [1, 1, 1])"),
                  "bodies[0].mass", "twice");
  expect_rejected(
      R"({"time_step": 0.01, "time_step": 0.02, "frames": 1, "bodies": [{)" + kBody + "}]}",
      "time_step", "twice");
  // The same key in different objects is fine.
  EXPECT_NO_THROW(parse_scene(R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody +
                                  R"(}, {"name": "b", "mass": 2, "inertia": [1, 1, 1]}]})",
                              kSource));
}

TEST(SceneErrors, UnknownBodyNames) {
  expect_rejected(
      scene(kBody, R"("springs": [{"body_a": "a", "body_b": "ghost", "stiffness": 1}], )"),
      "springs[0].body_b", "ghost");
  expect_rejected(scene(kBody, R"("springs": [{"body_b": "a", "stiffness": 1},
                                              {"body_a": "A", "body_b": "a", "stiffness": 1}], )"),
                  "springs[1].body_a", "\"A\"");
  expect_rejected(scene(kBody, R"("forces": [{"body": "b", "force": [0, 0, 1]}], )"),
                  "forces[0].body", "\"b\"");
  expect_rejected(scene(kBody, R"("torques": [{"body": "ghost", "torque": [0, 0, 1]}], )"),
                  "torques[0].body", "ghost");
  // Forces and torques act on bodies; only springs may end at the world.
  expect_rejected(scene(kBody, R"("forces": [{"body": "world", "force": [0, 0, 1]}], )"),
                  "forces[0].body", "world");
  expect_rejected(scene(kBody, R"("springs": [{"body_b": 3, "stiffness": 1}], )"),
                  "springs[0].body_b", "string");
  // A spring between two world points connects nothing.
  expect_rejected(scene(kBody, R"("springs": [{"point_a": [0, 0, 1], "stiffness": 1}], )"),
                  "springs[0].body_b", "two world anchors");
  // Both ends on one body: a rigid body cannot stretch it, so it would silently do nothing.
  expect_rejected(scene(kBody, R"("springs": [{"body_a": "a", "body_b": "a", "stiffness": 1,)"
                               R"( "point_b": [0, 0, 1]}], )"),
                  "springs[0].body_b", "itself");
}

TEST(SceneErrors, SpinTooFastForTheTimeStep) {
  // h |ω| = 0.01 · 400 = 4 rad per step > π: exp(h ω) would alias to a slower spin.
  expect_rejected(scene(std::string(kBody) + R"(, "angular_velocity": [0, 0, 400])"),
                  "bodies[0].angular_velocity", "below π");
  // Just below the limit is accepted.
  EXPECT_NO_THROW(
      parse_scene(scene(std::string(kBody) + R"(, "angular_velocity": [0, 0, 314])"), kSource));
}

TEST(SceneErrors, BadSpringValues) {
  expect_rejected(scene(kBody, R"("springs": [{"body_b": "a", "stiffness": -1}], )"),
                  "springs[0].stiffness", "≥ 0");
  expect_rejected(
      scene(kBody, R"("springs": [{"body_b": "a", "stiffness": 1, "rest_length": -0.5}], )"),
      "springs[0].rest_length", "≥ 0");
}

TEST(SceneErrors, BodyNames) {
  expect_rejected(
      R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody + "}, {" + kBody + "}]}",
      "bodies[1].name", "repeats");
  expect_rejected(scene(R"("name": "world", "mass": 1, "inertia": [1, 1, 1])"), "bodies[0].name",
                  "world");
  expect_rejected(scene(R"("name": "", "mass": 1, "inertia": [1, 1, 1])"), "bodies[0].name",
                  "non-empty");
}

TEST(SceneErrors, EmptyBodies) {
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": []})", "bodies", "at least one");
}

TEST(SceneErrors, UnknownSolverChoices) {
  expect_rejected(scene(kBody, R"("solver": {"backend": "gauss-seidel"}, )"), "solver.backend",
                  "unknown backend");
  expect_rejected(scene(kBody, R"("solver": {"rotation": "euler"}, )"), "solver.rotation",
                  "unknown");
  expect_rejected(scene(kBody, R"("solver": {"backend": 1}, )"), "solver.backend", "string");
}

TEST(Scene, BackendsAndTheirOptions) {
  const Scene ceres = parse_scene(
      scene(kBody, R"("solver": {"backend": "ceres", "ceres": {"linear_solver": "dense_qr",
            "trust_region_strategy": "dogleg", "lie_blocks": "chart", "verbose": true}}, )"),
      kSource);
  EXPECT_EQ(ceres.solver.backend, Backend::kCeres);
  EXPECT_EQ(ceres.solver.ceres.linear_solver, "dense_qr");
  EXPECT_EQ(ceres.solver.ceres.trust_region_strategy, "dogleg");
  EXPECT_EQ(ceres.solver.ceres.lie_blocks, "chart");
  EXPECT_TRUE(ceres.solver.ceres.verbose);
  const Scene ipopt = parse_scene(
      scene(kBody, R"("solver": {"backend": "ipopt", "rotation": "rotvec", "ipopt": {
            "hessian_approximation": "limited-memory", "print_level": 3,
            "derivative_test": "second-order", "max_recentrings": 1}}, )"),
      kSource);
  EXPECT_EQ(ipopt.solver.backend, Backend::kIpopt);
  EXPECT_EQ(ipopt.solver.ipopt.hessian_approximation, "limited-memory");
  EXPECT_EQ(ipopt.solver.ipopt.print_level, 3);
  EXPECT_EQ(ipopt.solver.ipopt.derivative_test, "second-order");
  EXPECT_EQ(ipopt.solver.ipopt.output_file, "");  // never from a scene (test_output.cpp)
  EXPECT_EQ(ipopt.solver.ipopt.max_recentrings, 1);
  // Defaults.
  const Scene plain = parse_scene(scene(), kSource);
  EXPECT_EQ(plain.solver.backend, Backend::kNewton);
  EXPECT_EQ(plain.solver.ceres.linear_solver, "auto");
  EXPECT_EQ(plain.solver.ceres.lie_blocks, "manifold");
  EXPECT_EQ(plain.solver.ipopt.hessian_approximation, "exact");
}

TEST(SceneErrors, BackendOptions) {
  expect_rejected(scene(kBody, R"("solver": {"ceres": {"linear_solver": "cholesky"}}, )"),
                  "solver.ceres.linear_solver", "unknown linear solver");
  expect_rejected(scene(kBody, R"("solver": {"ceres": {"trust_region_strategy": "lbfgs"}}, )"),
                  "solver.ceres.trust_region_strategy", "unknown strategy");
  expect_rejected(scene(kBody, R"("solver": {"ceres": {"lie_blocks": "quat"}}, )"),
                  "solver.ceres.lie_blocks", "unknown rotation blocks");
  expect_rejected(scene(kBody, R"("solver": {"ceres": {"verbose": 1}}, )"), "solver.ceres.verbose",
                  "true or false");
  expect_rejected(scene(kBody, R"("solver": {"ceres": {"threads": 2}}, )"), "solver.ceres.threads");
  expect_rejected(scene(kBody, R"("solver": {"ipopt": {"hessian_approximation": "bfgs"}}, )"),
                  "solver.ipopt.hessian_approximation", "unknown approximation");
  expect_rejected(scene(kBody, R"("solver": {"ipopt": {"print_level": 13}}, )"),
                  "solver.ipopt.print_level", "[0, 12]");
  expect_rejected(scene(kBody, R"("solver": {"ipopt": {"derivative_test": "yes"}}, )"),
                  "solver.ipopt.derivative_test", "unknown test");
  expect_rejected(scene(kBody, R"("solver": {"ipopt": {"max_recentrings": -1}}, )"),
                  "solver.ipopt.max_recentrings");
}

TEST(Scene, RotationParameterisations) {
  const std::pair<const char*, RotationParameterization> cases[] = {
      {"lie", RotationParameterization::kLie},
      {"rotvec", RotationParameterization::kRotationVector},
      {"quat", RotationParameterization::kQuaternion}};
  for (const auto& [name, rotation] : cases) {
    const Scene s =
        parse_scene(scene(kBody, std::string(R"("solver": {"rotation": ")") + name + "\"}, "),
                    "inline.json");
    EXPECT_EQ(s.solver.rotation, rotation) << name;
    // Every back-end takes every parameterisation.
    for (const char* backend : {"newton", "ceres", "ipopt"}) {
      const Scene b = parse_scene(scene(kBody, std::string(R"("solver": {"backend": ")") + backend +
                                                   R"(", "rotation": ")" + name + "\"}, "),
                                  "inline.json");
      EXPECT_EQ(b.solver.rotation, rotation) << backend << "/" << name;
    }
  }
}

TEST(SceneErrors, BadSolverNumbers) {
  expect_rejected(scene(kBody, R"("solver": {"tolerance": 0}, )"), "solver.tolerance", "positive");
  expect_rejected(scene(kBody, R"("solver": {"tolerance": -1e-9}, )"), "solver.tolerance",
                  "positive");
  expect_rejected(scene(kBody, R"("solver": {"tolerance": "tight"}, )"), "solver.tolerance",
                  "number");
  expect_rejected(scene(kBody, R"("solver": {"max_iterations": 0}, )"), "solver.max_iterations",
                  "integer");
  expect_rejected(scene(kBody, R"("solver": {"max_iterations": 2.5}, )"), "solver.max_iterations",
                  "integer");
  expect_rejected(scene(kBody, R"("solver": {"armijo": 0.5}, )"), "solver.armijo", "(0, 0.5)");
  expect_rejected(scene(kBody, R"("solver": {"armijo": 0}, )"), "solver.armijo", "(0, 0.5)");
  expect_rejected(scene(kBody, R"("solver": {"min_step_length": 1}, )"), "solver.min_step_length",
                  "(0, 1)");
}

TEST(SceneErrors, BadAssemblyThreads) {
  expect_rejected(scene(kBody, R"("solver": {"assembly_threads": -1}, )"),
                  "solver.assembly_threads", "integer in [0, 256]");
  expect_rejected(scene(kBody, R"("solver": {"assembly_threads": 257}, )"),
                  "solver.assembly_threads", "integer in [0, 256]");
  expect_rejected(scene(kBody, R"("solver": {"assembly_threads": 1.5}, )"),
                  "solver.assembly_threads", "integer");
  const Scene s = parse_scene(scene(kBody, R"("solver": {"assembly_threads": 2}, )"), "inline.json");
  EXPECT_EQ(s.solver.assembly_threads, 2);
}

TEST(SceneErrors, BadFrames) {
  const auto with_frames = [](const std::string& frames) {
    return R"({"time_step": 0.01, "frames": )" + frames + R"(, "bodies": [{)" + kBody + "}]}";
  };
  expect_rejected(with_frames("-1"), "frames", "integer");
  expect_rejected(with_frames("2.5"), "frames", "integer");
  expect_rejected(with_frames("\"20\""), "frames", "integer");
  expect_rejected(with_frames("3000000000"), "frames", "integer");
  // Beyond the range of a signed 64-bit integer: must not wrap around to −1.
  const SceneError e = rejected(with_frames("18446744073709551615"));
  EXPECT_EQ(e.field(), "frames");
  EXPECT_EQ(e.reason().find("-1"), std::string::npos) << e.reason();
  EXPECT_EQ(parse_scene(with_frames("0"), kSource).frames, 0);
}

TEST(SceneParse, StaticModeMakesFramesLoadSteps) {
  const Scene s = parse_scene(
      R"({"mode": "static", "time_step": 0.01, "frames": 7, "rods": [{"name": "r",)"
      R"( "nodes": [[0,0,0],[1,0,0]], "mass": 1, "radius": 0.01, "stretch_stiffness": 1,)"
      R"( "shear_stiffness": 1, "bending_stiffness": [1,1,1], "fixed_nodes": [0]}]})",
      kSource);
  EXPECT_TRUE(s.model.static_equilibrium);
  EXPECT_EQ(s.model.load_steps, 7);
  EXPECT_FALSE(parse_scene(scene(), kSource).model.static_equilibrium);  // default: dynamic
  expect_rejected(scene(kBody, R"("mode": "quasistatic", )"), "mode", "static");
  // A free body has no equilibrium.
  expect_rejected(scene(kBody, R"("mode": "static", )"), "bodies[0]", "world anchor");
}

TEST(SceneErrors, NonPositiveTimeStep) {
  for (const char* h : {"0", "-0.01", "-0"}) {
    expect_rejected(
        std::string(R"({"time_step": )") + h + R"(, "frames": 1, "bodies": [{)" + kBody + "}]}",
        "time_step", "positive");
  }
}

TEST(SceneErrors, InvalidJson) {
  expect_rejected(scene(kBody + ","), "", "invalid JSON");  // trailing comma
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody + "}],}", "",
                  "invalid JSON");
  expect_rejected("", "", "invalid JSON");
  expect_rejected(scene() + " {}", "", "invalid JSON");
  // A syntax error says where.
  const SceneError e = rejected(scene(kBody + ","));
  EXPECT_NE(e.reason().find("line 1"), std::string::npos) << e.reason();
}

// --- Rods ---------------------------------------------------------------------------------

// Members of a valid three-node rod along z (explicit nodes).
const std::string kRod =
    R"("name": "r", "nodes": [[0, 0, 0], [0, 0, 0.5], [0, 0, 1]], "mass": 0.3,)"
    R"( "radius": 0.01, "stretch_stiffness": 2000, "shear_stiffness": 1000,)"
    R"( "bending_stiffness": [1, 2, 3])";
// The same rod's members other than its nodes (to combine with a "shape").
const std::string kRodMaterial =
    R"("name": "r", "mass": 0.3, "radius": 0.01, "stretch_stiffness": 2000,)"
    R"( "shear_stiffness": 1000, "bending_stiffness": [1, 2, 3])";

// A scene with one rod (members `rod`), no bodies, and extra top-level members `extra`
// (ending with ", " when not empty).
std::string rod_scene(const std::string& rod = kRod, const std::string& extra = "") {
  return R"({"time_step": 0.01, "frames": 5, )" + extra + R"("rods": [{)" + rod + "}]}";
}

TEST(SceneRods, RodWithoutBodiesGetsDefaults) {
  const Scene s = parse_scene(rod_scene(), kSource);
  EXPECT_TRUE(s.model.bodies.empty());
  ASSERT_EQ(s.model.rods.size(), 1u);
  const RodSpec& r = s.model.rods[0];
  EXPECT_EQ(r.name, "r");
  ASSERT_EQ(r.nodes.size(), 3u);
  EXPECT_TRUE(r.nodes[0].isZero(0.0));
  EXPECT_TRUE(r.nodes[1].isApprox(Vector3(0, 0, 0.5), 0.0));
  EXPECT_TRUE(r.nodes[2].isApprox(Vector3(0, 0, 1), 0.0));
  EXPECT_DOUBLE_EQ(r.mass, 0.3);
  EXPECT_DOUBLE_EQ(r.radius, 0.01);
  EXPECT_DOUBLE_EQ(r.stretch_stiffness, 2000.0);
  EXPECT_DOUBLE_EQ(r.shear_stiffness, 1000.0);
  EXPECT_TRUE(r.bending_stiffness.isApprox(Vector3(1, 2, 3), 0.0));
  EXPECT_TRUE(r.fixed_nodes.empty());
  EXPECT_TRUE(r.fixed_edges.empty());
  EXPECT_TRUE(r.node_forces.empty());
}

TEST(SceneRods, BodiesAndRodsTogether) {
  const std::string text = R"({"time_step": 0.01, "frames": 2,
    "bodies": [{)" + kBody + R"(}],
    "rods": [{)" + kRod + R"(, "fixed_nodes": [2, 0], "fixed_edges": [1],
               "node_forces": [{"node": 1, "force": [0.5, 0, -1]},
                               {"node": 2, "force": [0, 2, 0]}]},
             {"name": "s", "nodes": [[1, 0, 0], [2, 0, 0]], "mass": 1, "radius": 0.1,
              "stretch_stiffness": 1, "shear_stiffness": 0, "bending_stiffness": [0, 0, 0]}]})";
  const Scene s = parse_scene(text, kSource);
  ASSERT_EQ(s.model.bodies.size(), 1u);
  ASSERT_EQ(s.model.rods.size(), 2u);
  const RodSpec& r = s.model.rods[0];
  EXPECT_EQ(r.fixed_nodes, (std::vector<int>{2, 0}));
  EXPECT_EQ(r.fixed_edges, (std::vector<int>{1}));
  ASSERT_EQ(r.node_forces.size(), 2u);
  EXPECT_EQ(r.node_forces[0].node, 1);
  EXPECT_TRUE(r.node_forces[0].force.isApprox(Vector3(0.5, 0, -1), 0.0));
  EXPECT_EQ(r.node_forces[1].node, 2);
  EXPECT_TRUE(r.node_forces[1].force.isApprox(Vector3(0, 2, 0), 0.0));
  EXPECT_EQ(s.model.rods[1].name, "s");
  EXPECT_EQ(s.model.rods[1].node_count(), 2);
  // State layout: the body first, then rod r's three nodes, then rod s's.
  EXPECT_EQ(s.model.rod_point(0, 0), 1);
  EXPECT_EQ(s.model.rod_point(1, 0), 4);
  EXPECT_EQ(s.model.rod_rotation(1, 0), 3);
}

TEST(SceneRods, LineGenerator) {
  const Scene s = parse_scene(
      rod_scene(kRodMaterial + R"(, "shape": {"type": "line", "start": [1, 2, 3],)"
                               R"( "end": [1, 0, 5], "edges": 4})"),
      kSource);
  ASSERT_EQ(s.model.rods.size(), 1u);
  const std::vector<Vector3>& nodes = s.model.rods[0].nodes;
  ASSERT_EQ(nodes.size(), 5u);
  for (int k = 0; k <= 4; ++k) {
    EXPECT_TRUE(nodes[k].isApprox(Vector3(1, 2 - 0.5 * k, 3 + 0.5 * k), 1e-15))
        << k << ": " << nodes[k].transpose();
  }
  EXPECT_EQ(nodes.front(), Vector3(1, 2, 3));  // the ends exactly
  EXPECT_EQ(nodes.back(), Vector3(1, 0, 5));
}

TEST(SceneRods, HelixGenerator) {
  const double r = 0.1, p = 0.02, turns = 2.5;
  const int n = 40;
  const Vector3 center(1, -1, 0.5);
  const Scene s = parse_scene(
      rod_scene(kRodMaterial + R"(, "shape": {"type": "helix", "radius": 0.1, "pitch": 0.02,)"
                               R"( "turns": 2.5, "edges": 40, "center": [1, -1, 0.5]})"),
      kSource);
  const std::vector<Vector3>& nodes = s.model.rods[0].nodes;
  ASSERT_EQ(nodes.size(), static_cast<std::size_t>(n + 1));
  for (int k = 0; k <= n; ++k) {
    const double phi = 2 * std::numbers::pi * turns * k / n;
    const Vector3 expected =
        center + Vector3(r * std::cos(phi), r * std::sin(phi), p * phi / (2 * std::numbers::pi));
    EXPECT_LT((nodes[k] - expected).norm(), 1e-15) << k << ": " << nodes[k].transpose();
  }
  // 2.5 turns end half way round, 2.5 pitches up.
  EXPECT_LT((nodes.back() - Vector3(0.9, -1, 0.55)).norm(), 1e-14) << nodes.back().transpose();

  // The centre defaults to the origin; a quarter turn in two edges.
  const Scene q = parse_scene(
      rod_scene(kRodMaterial + R"(, "shape": {"type": "helix", "radius": 2, "pitch": 4,)"
                               R"( "turns": 0.25, "edges": 2})"),
      kSource);
  const std::vector<Vector3>& m = q.model.rods[0].nodes;
  ASSERT_EQ(m.size(), 3u);
  EXPECT_LT((m[0] - Vector3(2, 0, 0)).norm(), 1e-15);
  EXPECT_LT((m[1] - Vector3(std::sqrt(2.0), std::sqrt(2.0), 0.5)).norm(), 1e-15);
  EXPECT_LT((m[2] - Vector3(0, 2, 1)).norm(), 1e-15);
}

TEST(SceneRods, LoadsTheCantileverExample) {
  const Scene s =
      load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/cantilever.json");
  EXPECT_TRUE(s.model.bodies.empty());
  ASSERT_EQ(s.model.rods.size(), 1u);
  const RodSpec& r = s.model.rods[0];
  ASSERT_EQ(r.node_count(), 21);
  EXPECT_TRUE(r.nodes.back().isApprox(Vector3(1, 0, 0), 0.0));
  EXPECT_EQ(r.fixed_nodes, std::vector<int>{0});
  EXPECT_EQ(r.fixed_edges, std::vector<int>{0});
  ASSERT_EQ(r.node_forces.size(), 1u);
  EXPECT_EQ(r.node_forces[0].node, 20);
  EXPECT_TRUE(s.model.gravity.isZero(0.0));
  EXPECT_DOUBLE_EQ(s.model.time_step, 0.01);
  EXPECT_EQ(s.frames, 300);
}

TEST(SceneRodErrors, MissingAndMistypedFields) {
  expect_rejected(rod_scene(R"("name": "r", "nodes": [[0, 0, 0], [0, 0, 1]], "radius": 0.01,)"
                            R"( "stretch_stiffness": 1, "shear_stiffness": 1,)"
                            R"( "bending_stiffness": [1, 1, 1])"),
                  "rods[0].mass", "missing");
  expect_rejected(rod_scene(R"("nodes": [[0, 0, 0], [0, 0, 1]], "mass": 1, "radius": 0.01,)"
                            R"( "stretch_stiffness": 1, "shear_stiffness": 1,)"
                            R"( "bending_stiffness": [1, 1, 1])"),
                  "rods[0].name", "missing");
  expect_rejected(rod_scene(kRodMaterial), "rods[0].nodes", "missing");
  expect_rejected(rod_scene(kRodMaterial + R"(, "nodes": [[0, 0, 0], [0, 1]])"),
                  "rods[0].nodes[1]", "3 numbers");
  expect_rejected(rod_scene(kRodMaterial + R"(, "nodes": [[0, 0, 0], [0, 1, "x"]])"),
                  "rods[0].nodes[1][2]", "number");
  expect_rejected(rod_scene(kRodMaterial + R"(, "nodes": {"a": 1})"), "rods[0].nodes", "array");
  expect_rejected(rod_scene(kRod + R"(, "fixed_nodes": [0.5])"), "rods[0].fixed_nodes[0]",
                  "integer");
  expect_rejected(rod_scene(kRod + R"(, "fixed_edges": 0)"), "rods[0].fixed_edges", "array");
  expect_rejected(rod_scene(kRod + R"(, "node_forces": [{"node": 1}])"),
                  "rods[0].node_forces[0].force", "missing");
  expect_rejected(rod_scene(kRod + R"(, "node_forces": [{"force": [0, 0, 1]}])"),
                  "rods[0].node_forces[0].node", "missing");
  expect_rejected(
      R"({"time_step": 0.01, "frames": 5, "rods": [{)" + kRod + R"(, "bending_stiffness": 1}]})",
      "rods[0].bending_stiffness", "twice");
  expect_rejected(rod_scene(R"("name": "r", "nodes": [[0, 0, 0], [0, 0, 1]], "mass": 1,)"
                            R"( "radius": 0.01, "stretch_stiffness": 1, "shear_stiffness": 1,)"
                            R"( "bending_stiffness": [1, 1])"),
                  "rods[0].bending_stiffness", "3 numbers");
}

TEST(SceneRodErrors, NodesAndShapeAreExclusive) {
  // Both: the rod itself is named (neither member alone is wrong).
  expect_rejected(rod_scene(kRod + R"(, "shape": {"type": "line", "start": [0, 0, 0],)"
                                   R"( "end": [1, 0, 0], "edges": 2})"),
                  "rods[0]", "both");
}

TEST(SceneRodErrors, PhysicalChecksNameTheRodField) {
  expect_rejected(rod_scene(kRod + R"(, "fixed_nodes": [3])"), "rods[0].fixed_nodes[0]",
                  "node 3");
  expect_rejected(rod_scene(kRod + R"(, "fixed_nodes": [0, -1])"), "rods[0].fixed_nodes[1]",
                  "node -1");
  expect_rejected(rod_scene(kRod + R"(, "fixed_nodes": [1, 1])"), "rods[0].fixed_nodes[1]",
                  "repeats");
  expect_rejected(rod_scene(kRod + R"(, "fixed_edges": [2])"), "rods[0].fixed_edges[0]",
                  "edge 2");
  expect_rejected(rod_scene(kRod + R"(, "node_forces": [{"node": 3, "force": [0, 0, 1]}])"),
                  "rods[0].node_forces[0].node", "node 3");
  expect_rejected(rod_scene(R"("name": "r", "nodes": [[0, 0, 0], [0, 0, 1]], "mass": -1,)"
                            R"( "radius": 0.01, "stretch_stiffness": 1, "shear_stiffness": 1,)"
                            R"( "bending_stiffness": [1, 1, 1])"),
                  "rods[0].mass", "positive");
  expect_rejected(rod_scene(R"("name": "r", "nodes": [[0, 0, 0], [0, 0, 1]], "mass": 1,)"
                            R"( "radius": 0, "stretch_stiffness": 1, "shear_stiffness": 1,)"
                            R"( "bending_stiffness": [1, 1, 1])"),
                  "rods[0].radius", "positive");
  expect_rejected(rod_scene(R"("name": "r", "nodes": [[0, 0, 0], [0, 0, 1]], "mass": 1,)"
                            R"( "radius": 0.1, "stretch_stiffness": 1, "shear_stiffness": -1,)"
                            R"( "bending_stiffness": [1, 1, 1])"),
                  "rods[0].shear_stiffness", "≥ 0");
  expect_rejected(rod_scene(R"("name": "r", "nodes": [[0, 0, 0], [0, 0, 1]], "mass": 1,)"
                            R"( "radius": 0.1, "stretch_stiffness": 1, "shear_stiffness": 1,)"
                            R"( "bending_stiffness": [1, 1, -1])"),
                  "rods[0].bending_stiffness[2]", "≥ 0");
  expect_rejected(rod_scene(kRodMaterial + R"(, "nodes": [[0, 0, 0]])"), "rods[0].nodes",
                  "at least 2");
  expect_rejected(rod_scene(kRodMaterial + R"(, "nodes": [[0, 0, 0], [0, 0, 1], [0, 0, 1]])"),
                  "rods[0].nodes[2]", "coincides");
  // The second rod is named by its own index.
  expect_rejected(
      R"({"time_step": 0.01, "frames": 1, "rods": [{)" + kRod + R"(}, {"name": "t",)" +
          R"( "nodes": [[0, 0, 0], [1, 0, 0]], "mass": 1, "radius": 0.1, "stretch_stiffness": 1,)"
          R"( "shear_stiffness": 1, "bending_stiffness": [1, 1, 1], "fixed_edges": [1]}]})",
      "rods[1].fixed_edges[0]", "edge 1");
}

TEST(SceneRodErrors, NamesAreSharedWithBodies) {
  // A rod named like a body.
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody +
                      R"(}], "rods": [{"name": "a", "nodes": [[0, 0, 0], [1, 0, 0]], "mass": 1,)"
                      R"( "radius": 0.1, "stretch_stiffness": 1, "shear_stiffness": 1,)"
                      R"( "bending_stiffness": [1, 1, 1]}]})",
                  "rods[0].name", "repeats the name \"a\" of bodies[0]");
  // Two rods with one name.
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "rods": [{)" + kRod + "}, {" + kRod + "}]}",
                  "rods[1].name", "of rods[0]");
  expect_rejected(rod_scene(R"("name": "world", "nodes": [[0, 0, 0], [1, 0, 0]], "mass": 1,)"
                            R"( "radius": 0.1, "stretch_stiffness": 1, "shear_stiffness": 1,)"
                            R"( "bending_stiffness": [1, 1, 1])"),
                  "rods[0].name", "world");
  // Springs, forces and torques act on bodies only, and say so when given a rod.
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": [{)" + kBody +
                      R"(}], "rods": [{)" + kRod +
                      R"(}], "springs": [{"body_a": "a", "body_b": "r", "stiffness": 1}]})",
                  "springs[0].body_b", "names the rod \"r\"");
  expect_rejected(rod_scene(kRod, R"("forces": [{"body": "r", "force": [0, 0, 1]}], )"),
                  "forces[0].body", "node_forces");
}

TEST(SceneRodErrors, UnknownKeys) {
  expect_rejected(rod_scene(kRod + R"(, "colour": "red")"), "rods[0].colour", "unknown key");
  expect_rejected(rod_scene(kRod + R"(, "node_forces": [{"node": 1, "force": [0, 0, 1],)"
                                   R"( "point": [0, 0, 0]}])"),
                  "rods[0].node_forces[0].point", "unknown key");
  expect_rejected(rod_scene(kRodMaterial + R"(, "shape": {"type": "helix", "radius": 1,)"
                                           R"( "pitch": 1, "turns": 1, "edges": 8,)"
                                           R"( "axis": [0, 0, 1]})"),
                  "rods[0].shape.axis", "unknown key");
  // A helix member in a line shape is unknown there.
  expect_rejected(rod_scene(kRodMaterial + R"(, "shape": {"type": "line", "start": [0, 0, 0],)"
                                           R"( "end": [1, 0, 0], "edges": 2, "turns": 3})"),
                  "rods[0].shape.turns", "unknown key");
}

TEST(SceneRodErrors, BadShapes) {
  const auto with_shape = [](const std::string& shape) {
    return rod_scene(kRodMaterial + R"(, "shape": )" + shape);
  };
  expect_rejected(with_shape(R"({"type": "spiral"})"), "rods[0].shape.type", "unknown shape");
  expect_rejected(with_shape(R"({"start": [0, 0, 0]})"), "rods[0].shape.type", "missing");
  expect_rejected(with_shape("[1, 2]"), "rods[0].shape", "object");
  expect_rejected(with_shape(R"({"type": "line", "start": [0, 0, 0], "edges": 2})"),
                  "rods[0].shape.end", "missing");
  expect_rejected(with_shape(R"({"type": "line", "start": [0, 0, 0], "end": [1, 0, 0]})"),
                  "rods[0].shape.edges", "missing");
  expect_rejected(
      with_shape(R"({"type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": 0})"),
      "rods[0].shape.edges", "integer in [1, 1000000]");
  expect_rejected(
      with_shape(R"({"type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": 2.5})"),
      "rods[0].shape.edges", "integer");
  expect_rejected(
      with_shape(R"({"type": "line", "start": [0, 0, 0], "end": [1, 0, 0], "edges": 1000001})"),
      "rods[0].shape.edges", "1000000");
  expect_rejected(
      with_shape(R"({"type": "line", "start": [1, 1, 1], "end": [1, 1, 1], "edges": 2})"),
      "rods[0].shape.end", "differ");
  expect_rejected(
      with_shape(R"({"type": "helix", "radius": 0, "pitch": 1, "turns": 1, "edges": 8})"),
      "rods[0].shape.radius", "positive");
  expect_rejected(
      with_shape(R"({"type": "helix", "radius": 1, "pitch": 1, "turns": -1, "edges": 8})"),
      "rods[0].shape.turns", "positive");
  expect_rejected(with_shape(R"({"type": "helix", "radius": 1, "turns": 1, "edges": 8})"),
                  "rods[0].shape.pitch", "missing");
  // A flat helix with a whole turn per edge puts every node on the same point.
  expect_rejected(
      with_shape(R"({"type": "helix", "radius": 1, "pitch": 0, "turns": 2, "edges": 2})"),
      "rods[0].shape", "coincident");
  // A flat helix otherwise is a circle (allowed), and a negative pitch winds downwards.
  EXPECT_NO_THROW(parse_scene(
      with_shape(R"({"type": "helix", "radius": 1, "pitch": 0, "turns": 0.5, "edges": 8})"),
      kSource));
  const Scene down = parse_scene(
      with_shape(R"({"type": "helix", "radius": 1, "pitch": -2, "turns": 1, "edges": 4})"),
      kSource);
  EXPECT_NEAR(down.model.rods[0].nodes.back().z(), -2.0, 1e-15);
}

TEST(SceneRods, RestShapeAndPrescribedMotions) {
  const Scene s = parse_scene(
      rod_scene(kRod + R"(, "rest_nodes": [[0, 0, 0], [0, 0.5, 0], [0, 1, 0]],)"
                       R"( "fixed_nodes": [0, 2], "fixed_edges": [0, 1],)"
                       R"( "prescribed_motions": [)"
                       R"(  {"nodes": [2], "edges": [1], "keyframes": [)"
                       R"(    {"time": 1, "translation": [0, 0, -0.5]},)"
                       R"(    {"time": 2.5, "translation": [0, 0, -0.2], "rotation": [0, 0, 7]}]},)"
                       R"(  {"edges": [0], "center": [1, 2, 3],)"
                       R"(   "keyframes": [{"time": 0.5, "rotation": [0.1, 0, 0]}]}])"),
      kSource);
  const RodSpec& r = s.model.rods[0];
  ASSERT_EQ(r.rest_nodes.size(), 3u);
  EXPECT_EQ(r.rest_nodes[1], Vector3(0.0, 0.5, 0.0));
  ASSERT_EQ(r.prescribed_motions.size(), 2u);
  const PrescribedMotion& top = r.prescribed_motions[0];
  EXPECT_EQ(top.nodes, std::vector<int>{2});
  EXPECT_EQ(top.edges, std::vector<int>{1});
  EXPECT_EQ(top.center, Vector3(0.0, 0.0, 1.0));  // default: centroid of the moved nodes
  ASSERT_EQ(top.keyframes.size(), 2u);
  EXPECT_EQ(top.keyframes[0].time, 1.0);
  EXPECT_EQ(top.keyframes[0].translation, Vector3(0.0, 0.0, -0.5));
  EXPECT_EQ(top.keyframes[0].rotation, Vector3::Zero());  // default
  EXPECT_EQ(top.keyframes[1].rotation, Vector3(0.0, 0.0, 7.0));
  const PrescribedMotion& base = r.prescribed_motions[1];
  EXPECT_TRUE(base.nodes.empty());
  EXPECT_EQ(base.center, Vector3(1.0, 2.0, 3.0));
  // Without nodes, the default pivot is the centroid of the moved edges' midpoints.
  const Scene e = parse_scene(
      rod_scene(kRod + R"(, "fixed_edges": [1], "prescribed_motions": [)"
                       R"({"edges": [1], "keyframes": [{"time": 1, "rotation": [0, 0, 1]}]}])"),
      kSource);
  EXPECT_EQ(e.model.rods[0].prescribed_motions[0].center, Vector3(0.0, 0.0, 0.75));
  // A rest shape from a generator.
  const Scene g = parse_scene(
      rod_scene(kRod + R"(, "rest_shape": {"type": "line", "start": [0, 0, 0],)"
                       R"( "end": [2, 0, 0], "edges": 2})"),
      kSource);
  EXPECT_EQ(g.model.rods[0].rest_nodes[2], Vector3(2.0, 0.0, 0.0));
}

TEST(SceneRodErrors, BadRestShapesAndMotions) {
  expect_rejected(rod_scene(kRod + R"(, "rest_nodes": [[0, 0, 0], [0, 0, 1]])"),
                  "rods[0].rest_nodes", "has 2 nodes, but the initial shape has 3");
  expect_rejected(rod_scene(kRod + R"(, "rest_shape": {"type": "line", "start": [0, 0, 0],)"
                                   R"( "end": [2, 0, 0], "edges": 5})"),
                  "rods[0].rest_shape", "has 6 nodes");
  expect_rejected(rod_scene(kRod + R"(, "rest_nodes": [[0, 0, 0], [0, 0, 0], [0, 0, 1]])"),
                  "rods[0].rest_nodes[1]", "coincides");
  expect_rejected(rod_scene(kRod + R"(, "rest_nodes": [], "rest_shape": {})"), "rods[0]",
                  "both");
  const std::string clamped = kRod + R"(, "fixed_nodes": [2], "fixed_edges": [1], )";
  expect_rejected(rod_scene(clamped + R"("prescribed_motions": [{"nodes": [1],)"
                                      R"( "keyframes": [{"time": 1}]}])"),
                  "rods[0].prescribed_motions[0].nodes[0]", "not in fixed_nodes");
  expect_rejected(rod_scene(clamped + R"("prescribed_motions": [{"keyframes": [{"time": 1}]}])"),
                  "rods[0].prescribed_motions[0].nodes", "at least one node or edge");
  expect_rejected(rod_scene(clamped + R"("prescribed_motions": [{"nodes": [2],)"
                                      R"( "keyframes": []}])"),
                  "rods[0].prescribed_motions[0].keyframes", "at least one keyframe");
  expect_rejected(rod_scene(clamped + R"("prescribed_motions": [{"nodes": [2], "keyframes":)"
                                      R"( [{"time": 2}, {"time": 2}]}])"),
                  "rods[0].prescribed_motions[0].keyframes[1].time", "later than");
  expect_rejected(rod_scene(clamped + R"("prescribed_motions": [{"nodes": [2], "keyframes":)"
                                      R"( [{"time": 1, "translation": [0, 1]}]}])"),
                  "rods[0].prescribed_motions[0].keyframes[0].translation", "3");
  expect_rejected(rod_scene(clamped + R"("prescribed_motions": [{"nodes": [2], "keyframes":)"
                                      R"( [{"time": 1, "rotatoin": [0, 0, 1]}]}])"),
                  "rods[0].prescribed_motions[0].keyframes[0].rotatoin", "unknown");
  expect_rejected(rod_scene(clamped + R"("prescribed_motions": [{"edges": [1], "keyframes":)"
                                      R"( [{"time": 0.01, "rotation": [0, 0, 4]}]}])"),
                  "rods[0].prescribed_motions[0].keyframes[0].rotation", "below π");
}

TEST(SceneRodErrors, SceneNeedsABodyOrARod) {
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "rods": []})", "rods", "at least one");
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "bodies": [], "rods": []})", "bodies",
                  "at least one body or rod");
  expect_rejected(R"({"time_step": 0.01, "frames": 1, "rods": {}})", "rods", "array");
  // Empty bodies are fine next to a rod.
  EXPECT_NO_THROW(parse_scene(
      R"({"time_step": 0.01, "frames": 1, "bodies": [], "rods": [{)" + kRod + "}]}", kSource));
}

class SceneFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("liedyn_scene_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path write(const std::string& name, const std::string& text) {
    const std::filesystem::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  std::filesystem::path dir_;
};

TEST_F(SceneFile, LoadNamesTheFileInErrors) {
  const std::filesystem::path p =
      write("bad_mass.json", scene(R"("name": "a", "mass": -1, "inertia": [1, 1, 1])"));
  try {
    load_scene(p);
    FAIL() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), p.string());
    EXPECT_EQ(e.field(), "bodies[0].mass");
    EXPECT_EQ(std::string(e.what()).rfind(p.string() + ": bodies[0].mass: ", 0), 0u) << e.what();
  }
}

TEST_F(SceneFile, LoadValidFile) {
  const Scene s = load_scene(write("ok.json", scene()));
  EXPECT_EQ(s.source, (dir_ / "ok.json").string());
  EXPECT_EQ(s.frames, 5);
}

TEST_F(SceneFile, InvalidJsonInFileNamesTheFile) {
  const std::filesystem::path p = write("trailing_comma.json", scene(kBody + ","));
  try {
    load_scene(p);
    FAIL() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), p.string());
    EXPECT_NE(std::string(e.what()).find("trailing_comma.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("invalid JSON"), std::string::npos) << e.what();
  }
}

TEST_F(SceneFile, UnreadableFile) {
  const std::filesystem::path missing = dir_ / "no_such_scene.json";
  try {
    load_scene(missing);
    FAIL() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), missing.string());
    EXPECT_EQ(e.reason(), "no such file") << e.what();
    EXPECT_NE(std::string(e.what()).find("no_such_scene.json"), std::string::npos) << e.what();
  }
  // A directory is not a scene either.
  try {
    load_scene(dir_);
    FAIL() << "accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), dir_.string());
    EXPECT_NE(e.reason().find("directory"), std::string::npos) << e.what();
  }
  // No read permission (meaningless for root, who reads anyway).
  if (::geteuid() != 0) {
    const std::filesystem::path locked = write("locked.json", scene());
    std::filesystem::permissions(locked, std::filesystem::perms::none);
    try {
      load_scene(locked);
      ADD_FAILURE() << "accepted";
    } catch (const SceneError& e) {
      EXPECT_EQ(e.file(), locked.string());
    }
    std::filesystem::permissions(locked, std::filesystem::perms::owner_all);
  }
}

// --- Colliders and contact (docs/scene-format.md "Colliders and contact") ---------------

const std::string kContactBody =
    kBody + R"(, "contact": {"stiffness": 1e4, "radius": 0.01, "friction": 0.3, "points": [[0, 0, -1]]})";

TEST(SceneParse, CollidersAndContactGiveTheDescribedModel) {
  const Scene s = parse_scene(
      scene(kBody + R"(, "contact": {"stiffness": 2e3, "friction": 0.5, "friction_velocity": 0.01, "damping": 4.5,
                                     "points": [[0, 0, -1]], "box": {"half_extents": [1, 2, 3], "per_edge": 1}})",
            R"("colliders": [
                 {"name": "floor", "type": "plane", "normal": [0, 1, 1]},
                 {"type": "sphere", "radius": 2, "position": [1, 2, 3], "inside": true},
                 {"type": "box", "half_extents": [1, 1, 2], "rounding": 0.1},
                 {"type": "capsule", "half_length": 0.5, "radius": 0.1},
                 {"type": "tube", "radius": 0.1, "points": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "samples_per_segment": 4}], )"),
      kSource);
  const Model& m = s.model;
  ASSERT_EQ(m.colliders.size(), 5u);
  EXPECT_EQ(m.colliders[0].name, "floor");
  EXPECT_EQ(m.colliders[1].name, "colliders[1]");  // default name
  // The plane's frame maps z onto the normal.
  EXPECT_TRUE((m.colliders[0].orientation.col(2) - Vector3(0, 1, 1).normalized()).isZero(1e-15));
  EXPECT_TRUE(m.colliders[1].inside);
  EXPECT_EQ(std::get<SphereShape>(m.colliders[1].shape).radius, 2.0);
  EXPECT_EQ(std::get<BoxShape>(m.colliders[2].shape).rounding, 0.1);
  EXPECT_EQ(std::get<CapsuleShape>(m.colliders[3].shape).half_length, 0.5);
  EXPECT_EQ(std::get<TubeShape>(m.colliders[4].shape).polyline.size(), 2u * 4u + 1u);  // spline
  const RigidBody& b = m.bodies[0];
  EXPECT_EQ(b.contact.stiffness, 2e3);
  EXPECT_EQ(b.contact.radius, 0.0);  // bodies: 0 by default
  EXPECT_EQ(b.contact.friction, 0.5);
  EXPECT_EQ(b.contact.friction_velocity, 0.01);
  EXPECT_EQ(b.contact.damping, 4.5);
  // One explicit point, then the box: 8 corners, 12 edge midpoints, 6 face centres.
  ASSERT_EQ(b.contact_points.size(), 1u + 26u);
  int corners = 0;
  for (std::size_t i = 1; i < b.contact_points.size(); ++i) {
    const Vector3 u = b.contact_points[i].cwiseQuotient(Vector3(1, 2, 3)).cwiseAbs();
    EXPECT_EQ(u.maxCoeff(), 1.0);  // on the surface
    if (u.minCoeff() == 1.0) ++corners;
  }
  EXPECT_EQ(corners, 8);
}

TEST(SceneParse, RodContactDefaultsToTheRodRadiusAndRegionPushes) {
  const Scene s = parse_scene(R"({"time_step": 0.01, "frames": 1,
      "colliders": [{"type": "plane"}],
      "rods": [{"name": "r", "nodes": [[0, 0, 1], [0, 0, 2]], "mass": 1, "radius": 0.02,
                "stretch_stiffness": 1, "shear_stiffness": 1, "bending_stiffness": [1, 1, 1],
                "contact": {"stiffness": 100},
                "region_pushes": [{"force": [1, 0, 0], "center": [0, 0, 1], "radius": 0.5}]}]})",
                              kSource);
  EXPECT_EQ(s.model.rods[0].contact.radius, 0.02);
  EXPECT_EQ(s.model.rods[0].contact.friction, 0.0);
  ASSERT_EQ(s.model.rods[0].region_pushes.size(), 1u);
  EXPECT_EQ(s.model.rods[0].region_pushes[0].radius, 0.5);
}

TEST(SceneParse, TorusCylinderAndLinkCollidersBodiesAndMovingColliders) {
  const Scene s = parse_scene(
      scene(
          R"("name": "chain", "density": 7800, "contact": {"stiffness": 1e4, "sample_spacing": 0.01,
                "shape": {"type": "link", "half_length": 0.02, "major_radius": 0.015, "minor_radius": 0.004}})",
          R"("colliders": [
                 {"name": "ring", "type": "torus", "major_radius": 1, "minor_radius": 0.25, "position": [0, 0, 1]},
                 {"type": "cylinder", "radius": 0.5, "half_length": 2, "inside": true},
                 {"name": "spool", "type": "cylinder", "radius": 0.1, "half_length": 0.3,
                  "kinematic": {"angular_velocity": [0, 0, 1]}},
                 {"name": "hook", "type": "link", "half_length": 0.1, "major_radius": 0.05, "minor_radius": 0.01,
                  "kinematic": {"linear_velocity": [0, 0, 1]}},
                 {"name": "loop", "type": "torus", "major_radius": 0.1, "minor_radius": 0.02,
                  "kinematic": {"linear_velocity": [0, 0, 1]}}], )"),
      kSource);
  const Model& m = s.model;
  ASSERT_EQ(m.colliders.size(), 2u);
  EXPECT_EQ(std::get<TorusShape>(m.colliders[0].shape).minor_radius, 0.25);
  EXPECT_EQ(std::get<CylinderShape>(m.colliders[1].shape).half_length, 2.0);
  EXPECT_TRUE(m.colliders[1].inside);
  ASSERT_EQ(m.bodies.size(), 4u);
  const LinkShape& link = std::get<LinkShape>(m.bodies[0].shape->shape);
  EXPECT_EQ(link.half_length, 0.02);
  EXPECT_EQ(link.major_radius, 0.015);
  EXPECT_GT(m.bodies[0].contact_points.size(), 20u);
  EXPECT_GT(m.bodies[0].mass, 0.0);
  EXPECT_TRUE(std::holds_alternative<CylinderShape>(m.bodies[1].shape->shape));
  EXPECT_TRUE(m.bodies[1].kinematic.has_value());
  EXPECT_TRUE(std::holds_alternative<LinkShape>(m.bodies[2].shape->shape));
  EXPECT_TRUE(std::holds_alternative<TorusShape>(m.bodies[3].shape->shape));
}

TEST(SceneErrors, BodyShapesAreTheSolidsABodyMayHave) {
  const auto with_shape = [](const std::string& shape) {
    return scene(kBody + R"(, "contact": {"stiffness": 1, "shape": )" + shape + "}");
  };
  const std::string allowed =
      "a body's shape must be a sphere, box, capsule, torus, cylinder, link or mesh";
  expect_rejected(with_shape(R"({"type": "plane"})"), "bodies[0].contact.shape.type", allowed);
  expect_rejected(
      with_shape(R"({"type": "torus", "major_radius": 1, "minor_radius": 0.1, "inside": true})"),
      "bodies[0].contact.shape.inside", "solid");
  expect_rejected(
      with_shape(R"({"type": "link", "half_length": 1, "major_radius": 1, "minor_radius": 1.5})"),
      "bodies[0].contact.shape.minor_radius", "below major_radius");
  expect_rejected(with_shape(R"({"type": "cylinder", "radius": 1, "half_length": -1})"),
                  "bodies[0].contact.shape.half_length", "positive");
  // A moving collider's shape is only touched: any collider, a plane or a complement too
  // (tests/test_moving_colliders.cpp); its parameters are still checked.
  const std::string moving = R"(, "kinematic": {"linear_velocity": [1, 0, 0]}}], )";
  EXPECT_EQ(parse_scene(scene(kBody, R"("colliders": [{"name": "p", "type": "plane")" + moving), kSource)
                .model.bodies.size(),
            2u);
  EXPECT_EQ(parse_scene(scene(kBody,
                              R"("colliders": [{"name": "t", "type": "torus", "major_radius": 1, "minor_radius": 0.1,
                                                "inside": true)" +
                                  moving),
                        kSource)
                .model.bodies[1]
                .shape->inside,
            true);
  expect_rejected(
      scene(kBody,
            R"("colliders": [{"name": "t", "type": "torus", "major_radius": 1, "minor_radius": 0)" +
                moving),
      "colliders[0].minor_radius", "positive");
}

TEST(SceneErrors, BadCollidersAndContact) {
  const auto with_collider = [](const std::string& c) {
    return scene(kBody, R"("colliders": [)" + c + "], ");
  };
  expect_rejected(with_collider(R"({"radius": 1})"), "colliders[0].type", "missing");
  expect_rejected(with_collider(R"({"type": "cone"})"), "colliders[0].type", "unknown collider type");
  expect_rejected(with_collider(R"({"type": "sphere"})"), "colliders[0].radius", "missing");
  expect_rejected(with_collider(R"({"type": "sphere", "radius": -1})"), "colliders[0].radius", "");
  expect_rejected(with_collider(R"({"type": "sphere", "radius": 1, "colour": 1})"), "colliders[0].colour",
                  "unknown key");
  expect_rejected(with_collider(R"({"type": "box", "half_extents": [1, 0, 1]})"),
                  "colliders[0].half_extents", "");
  expect_rejected(with_collider(R"({"type": "box", "half_extents": [1, 1, 1], "rounding": 1})"),
                  "colliders[0].rounding", "");
  expect_rejected(with_collider(R"({"type": "tube", "radius": 1, "points": [[0, 0, 0]]})"),
                  "colliders[0].points", "at least 2");
  expect_rejected(with_collider(R"({"type": "tube", "radius": 1, "points": [[0, 0, 0], [0, 0, 0]]})"),
                  "colliders[0].points[1]", "coincides");
  expect_rejected(with_collider(R"({"type": "tube", "radius": 1, "points": [[0, 0, 0], [1, 0, 0]], "samples_per_segment": 0})"),
                  "colliders[0].samples_per_segment", "integer");
  expect_rejected(with_collider(R"({"type": "plane", "normal": [0, 0, 0]})"), "colliders[0].normal",
                  "non-zero");
  expect_rejected(with_collider(R"({"type": "plane", "normal": [0, 0, 1], "orientation": [1, 0, 0, 0]})"),
                  "colliders[0].normal", "not both");
  expect_rejected(with_collider(R"({"type": "plane", "orientation": [2, 0, 0, 0]})"),
                  "colliders[0].orientation", "unit quaternion");
  expect_rejected(with_collider(R"({"type": "mesh", "file": "no_such_mesh.obj", "cell_size": 0.01})"),
                  "colliders[0].file", "no_such_mesh.obj");
  expect_rejected(with_collider(R"({"type": "mesh", "file": "x.obj", "cell_size": 0})"),
                  "colliders[0].cell_size", "positive");
  expect_rejected(with_collider(R"({"type": "mesh", "cell_size": 0.1})"), "colliders[0].file",
                  "missing");
  // Torus, cylinder, link: their keys, ranges, and no key of another type.
  expect_rejected(with_collider(R"({"type": "torus", "minor_radius": 0.1})"),
                  "colliders[0].major_radius", "missing");
  expect_rejected(with_collider(R"({"type": "torus", "major_radius": 1})"),
                  "colliders[0].minor_radius", "missing");
  expect_rejected(with_collider(R"({"type": "torus", "major_radius": 1, "minor_radius": 1})"),
                  "colliders[0].minor_radius", "below major_radius");
  expect_rejected(with_collider(R"({"type": "torus", "major_radius": -1, "minor_radius": 0.1})"),
                  "colliders[0].major_radius", "positive");
  expect_rejected(
      with_collider(R"({"type": "torus", "major_radius": 1, "minor_radius": 0.1, "radius": 1})"),
      "colliders[0].radius", "unknown key");
  expect_rejected(with_collider(R"({"type": "cylinder", "radius": 1})"), "colliders[0].half_length",
                  "missing");
  expect_rejected(with_collider(R"({"type": "cylinder", "radius": 0, "half_length": 1})"),
                  "colliders[0].radius", "positive");
  expect_rejected(with_collider(R"({"type": "cylinder", "radius": 1, "half_length": 0})"),
                  "colliders[0].half_length", "positive");
  expect_rejected(with_collider(R"({"type": "link", "major_radius": 1, "minor_radius": 0.1})"),
                  "colliders[0].half_length", "missing");
  expect_rejected(
      with_collider(
          R"({"type": "link", "half_length": -0.5, "major_radius": 1, "minor_radius": 0.1})"),
      "colliders[0].half_length", "≥ 0");
  expect_rejected(
      with_collider(
          R"({"type": "link", "half_length": 0.5, "major_radius": 1, "minor_radius": 2})"),
      "colliders[0].minor_radius", "below major_radius");

  const auto with_contact = [](const std::string& c) {
    return scene(kBody + R"(, "contact": )" + c);
  };
  expect_rejected(with_contact(R"({"points": [[0, 0, 0]]})"), "bodies[0].contact.stiffness", "missing");
  expect_rejected(with_contact(R"({"stiffness": 0, "points": [[0, 0, 0]]})"), "bodies[0].contact.stiffness",
                  "positive");
  expect_rejected(with_contact(R"({"stiffness": 1})"), "bodies[0].contact.points", "points");
  expect_rejected(with_contact(R"({"stiffness": 1, "friction": -0.1, "points": [[0, 0, 0]]})"),
                  "bodies[0].contact.friction", "≥ 0");
  expect_rejected(with_contact(R"({"stiffness": 1, "friction_velocity": 0, "points": [[0, 0, 0]]})"),
                  "bodies[0].contact.friction_velocity", "positive");
  expect_rejected(with_contact(R"({"stiffness": 1, "radius": -1, "points": [[0, 0, 0]]})"),
                  "bodies[0].contact.radius", "≥ 0");
  expect_rejected(with_contact(R"({"stiffness": 1, "damping": -2, "points": [[0, 0, 0]]})"),
                  "bodies[0].contact.damping", "≥ 0");
  expect_rejected(with_contact(R"({"stiffness": 1, "damping": 1e999, "points": [[0, 0, 0]]})"),
                  "bodies[0].contact.damping", "finite");
  expect_rejected(with_contact(R"({"stiffness": 1, "points": [[0, 0, 1e999]]})"),
                  "bodies[0].contact.points[0][2]", "finite");
  expect_rejected(with_contact(R"({"stiffness": 1, "box": {"half_extents": [1, 1, 1], "per_edge": 1001}})"),
                  "bodies[0].contact.box.per_edge", "integer");
  expect_rejected(with_contact(R"({"stiffness": 1, "box": {"half_extents": [1, -1, 1]}})"),
                  "bodies[0].contact.box.half_extents", "positive");
  expect_rejected(scene(kContactBody + R"(, "contact": {})"), "bodies[0].contact", "appears twice");
}

}  // namespace
}  // namespace liedyn::scene_tests

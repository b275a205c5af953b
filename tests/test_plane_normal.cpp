// A plane collider's "normal" (problems/scene.cpp, parse_collider): any
// finite non-zero vector gives its direction. ‖n‖² overflows from components ~1.4e154 and
// underflows below ~1e-154; normalising through it made such a plane horizontal (n/∞ = 0:
// the identity frame) or refused a non-zero normal as zero.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "problems/scene.hpp"

namespace liedyn {
namespace {

// The frame's z axis (the plane's normal) of a scene's only collider, a plane with `normal`.
Vector3 plane_normal(const std::string& normal) {
  const Scene s = parse_scene(R"({"time_step": 0.01, "frames": 5, "colliders": [
      {"type": "plane", "normal": )" + normal + R"(}],
      "bodies": [{"name": "a", "mass": 2, "inertia": [1, 2, 2.5]}]})",
                              "unit_scene.json");
  return s.model.colliders.at(0).orientation.col(2);
}

TEST(PlaneNormal, HugeAndTinyComponentsKeepTheirDirection) {
  const Vector3 diagonal = Vector3(1, 0, 1).normalized();
  for (const char* n : {"[1, 0, 1]", "[1.4e154, 0, 1.4e154]", "[1e300, 0, 1e300]",
                        "[1.7976931348623157e308, 0, 1.7976931348623157e308]",
                        "[1e-200, 0, 1e-200]", "[5e-324, 0, 5e-324]"}) {
    const Vector3 z = plane_normal(n);
    EXPECT_LE((z - diagonal).norm(), 1e-15) << n << ": " << z.transpose();
  }
  // One huge component among ordinary ones: that axis.
  EXPECT_LE((plane_normal("[3, -1e200, 4]") - Vector3(0, -1, 0)).norm(), 1e-15);
  // Uneven magnitudes stay exact in direction.
  EXPECT_LE((plane_normal("[3e180, 0, 4e180]") - Vector3(0.6, 0, 0.8)).norm(), 1e-15);
}

TEST(PlaneNormal, ZeroIsStillRefused) {
  try {
    plane_normal("[0, 0, 0]");
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.field(), "colliders[0].normal");
    EXPECT_NE(e.reason().find("non-zero"), std::string::npos) << e.reason();
  }
}

}  // namespace
}  // namespace liedyn

#pragma once
// Models shared by the test and benchmark executables.

#include <string>

#include "lib/model.hpp"

namespace liedyn::test_models {

// n spinning links in a row along x under gravity, the first hung from a world anchor, each
// joined to the next by a spring between body points: one component of 6n DOFs (dense up to
// kDenseLimit, sparse beyond). The springs start at their rest length.
inline Model spring_chain(int n) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  for (int i = 0; i < n; ++i) {
    RigidBody b;
    b.name = "link" + std::to_string(i);
    b.inertia = Vector3(0.02, 0.03, 0.04).asDiagonal();
    b.position = Vector3(0.3 * i, 0.0, 0.0);
    b.angular_velocity = Vector3(0.5, -1.0, 2.0);
    model.bodies.push_back(b);
  }
  SpringSpec anchor;
  anchor.a = BodyPoint{-1, Vector3(-0.2, 0.0, 0.0)};
  anchor.b = BodyPoint{0, Vector3(-0.1, 0.0, 0.0)};
  anchor.stiffness = 1e3;
  anchor.rest_length = 0.1;
  model.springs.push_back(anchor);
  for (int i = 0; i + 1 < n; ++i) {
    SpringSpec s;
    s.a = BodyPoint{i, Vector3(0.1, 0.0, 0.0)};
    s.b = BodyPoint{i + 1, Vector3(-0.1, 0.0, 0.0)};
    s.stiffness = 1e3;
    s.rest_length = 0.1;
    model.springs.push_back(s);
  }
  return model;
}

}  // namespace liedyn::test_models

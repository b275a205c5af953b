// Kinematic bodies and moving colliders (lib/kinematic.hpp): the motion itself, its checks,
// and whole runs in which a driven body pushes, carries, lifts and swings what it touches or
// holds without being pushed back.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "adjoint_check.hpp"
#include "lib/so3.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

TEST(KinematicMotion, VelocitiesMoveFromTheInitialPoseAtConstantRates) {
  KinematicMotion m;
  m.linear_velocity = Vector3(1.0, -2.0, 0.5);
  m.angular_velocity = Vector3(0.0, 0.0, -100.0);  // many turns: the pose is exp(ω t) R0, not aliased
  const Vector3 x0(0.1, 0.2, 0.3);
  const Matrix3 R0 = so3::exp(Vector3(0.3, -0.2, 0.1));
  Vector3 x;
  Matrix3 R;
  for (double t : {-1.0, 0.0}) {
    m.pose(t, x0, R0, x, R);
    EXPECT_EQ(x, x0);
    EXPECT_EQ(R, R0);
  }
  for (double t : {1e-3, 0.05, 2.7}) {
    m.pose(t, x0, R0, x, R);
    EXPECT_LT((x - (x0 + t * m.linear_velocity)).norm(), 1e-14);
    const Matrix3 expected = so3::exp(Vector3(0.0, 0.0, -100.0 * t)) * R0;
    EXPECT_LT((R - expected).norm(), 1e-12) << t;
  }
  EXPECT_EQ(m.duration(), 0.0);
}

TEST(KinematicMotion, KeyframesInterpolateAlongTheGeodesicFromTheInitialPoseAndHold) {
  KinematicMotion m;
  const Vector3 x0(0.0, 0.0, 1.0);
  const Matrix3 R0 = Matrix3::Identity();
  const Matrix3 R1 = so3::exp(Vector3(0.0, 0.0, 2.0));  // 2 rad about z in the first second
  const Matrix3 R2 = so3::exp(Vector3(1.0, 0.0, 0.0)) * R1;
  m.keyframes = {{1.0, Vector3(1.0, 0.0, 1.0), R1}, {3.0, Vector3(1.0, 2.0, 1.0), R2}};
  EXPECT_EQ(m.duration(), 3.0);
  Vector3 x;
  Matrix3 R;
  m.pose(0.25, x0, R0, x, R);
  EXPECT_LT((x - Vector3(0.25, 0.0, 1.0)).norm(), 1e-15);
  EXPECT_LT((R - so3::exp(Vector3(0.0, 0.0, 0.5))).norm(), 1e-14);
  m.pose(1.0, x0, R0, x, R);  // at a keyframe: that pose
  EXPECT_LT((x - m.keyframes[0].position).norm(), 1e-15);
  EXPECT_LT((R - R1).norm(), 1e-14);
  m.pose(2.0, x0, R0, x, R);  // half-way along the second span: half of its rotation, in the world
  EXPECT_LT((x - Vector3(1.0, 1.0, 1.0)).norm(), 1e-15);
  EXPECT_LT((R - so3::exp(Vector3(0.5, 0.0, 0.0)) * R1).norm(), 1e-14);
  // Constant angular velocity along a span: equal steps turn by equal rotations.
  Matrix3 Ra, Rb, Rc;
  m.pose(1.5, x0, R0, x, Ra);
  m.pose(1.7, x0, R0, x, Rb);
  m.pose(1.9, x0, R0, x, Rc);
  EXPECT_LT((Rb * Ra.transpose() - Rc * Rb.transpose()).norm(), 1e-13);
  for (double t : {3.0, 10.0}) {
    m.pose(t, x0, R0, x, R);
    EXPECT_LT((x - Vector3(1.0, 2.0, 1.0)).norm(), 1e-15);
    EXPECT_LT((R - R2).norm(), 1e-14);
  }
}

// Each bad motion is refused naming its field.
TEST(KinematicMotion, ValidateNamesTheFieldOfEachBadMotion) {
  const auto field_of = [](const KinematicMotion& m, bool static_mode = false, double h = 0.01) {
    try {
      m.validate(Matrix3::Identity(), h, static_mode, "bodies[2].kinematic");
    } catch (const ModelError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  KinematicMotion spin;
  spin.angular_velocity = Vector3(0.0, 0.0, 100.0);
  EXPECT_EQ(field_of(spin), "accepted");  // 1 rad per step
  EXPECT_EQ(field_of(spin, false, 0.04), "bodies[2].kinematic.angular_velocity");  // 4 rad per step
  EXPECT_EQ(field_of(spin, true), "bodies[2].kinematic.linear_velocity");         // static mode: no end
  spin.linear_velocity = Vector3(NAN, 0.0, 0.0);
  EXPECT_EQ(field_of(spin), "bodies[2].kinematic.linear_velocity");

  const auto keyed = [](std::vector<KinematicPose> keys) {
    KinematicMotion m;
    m.keyframes = std::move(keys);
    return m;
  };
  const Matrix3 half_turn = so3::exp(Vector3(0.0, 0.0, std::numbers::pi));
  const Matrix3 near_half = so3::exp(Vector3(0.0, 0.0, std::numbers::pi - 1e-3));
  EXPECT_EQ(field_of(keyed({{1.0, Vector3::Zero(), near_half}})), "accepted");
  EXPECT_EQ(field_of(keyed({{0.0, Vector3::Zero(), Matrix3::Identity()}})), "bodies[2].kinematic.keyframes[0].time");
  EXPECT_EQ(field_of(keyed({{1.0, Vector3::Zero(), Matrix3::Identity()}, {1.0, Vector3::Zero(), Matrix3::Identity()}})),
            "bodies[2].kinematic.keyframes[1].time");
  EXPECT_EQ(field_of(keyed({{1.0, Vector3::Zero(), half_turn}})), "bodies[2].kinematic.keyframes[0].orientation");
  EXPECT_EQ(field_of(keyed({{1.0, Vector3::Zero(), 2.0 * Matrix3::Identity()}})),
            "bodies[2].kinematic.keyframes[0].orientation");
  EXPECT_EQ(field_of(keyed({{1.0, Vector3(0.0, INFINITY, 0.0), Matrix3::Identity()}})),
            "bodies[2].kinematic.keyframes[0].position");
  EXPECT_EQ(field_of(keyed({{0.01, Vector3::Zero(), near_half}})), "accepted");  // 3.14 rad in one step of 0.01
  EXPECT_EQ(field_of(keyed({{0.005, Vector3::Zero(), near_half}})),              // … in half a step: too fast
            "bodies[2].kinematic.keyframes[0].orientation");
  EXPECT_EQ(field_of(keyed({{0.005, Vector3::Zero(), near_half}}), true), "accepted");  // static: no speed
  KinematicMotion both = keyed({{1.0, Vector3::Zero(), Matrix3::Identity()}});
  both.angular_velocity = Vector3(1.0, 0.0, 0.0);
  EXPECT_EQ(field_of(both), "bodies[2].kinematic.linear_velocity");
}

// A ball on a floor, a kinematic box (a pusher) moving at 1 m/s and a capsule collider that
// sweeps across on keyframes.
std::string pusher_scene(const std::string& extra_bodies = "", const std::string& ball_extra = "") {
  return R"({"time_step": 0.01, "frames": 100, "gravity": [0, 0, -9.81],
    "bodies": [
      {"name": "ball", "position": [0.5, 0, 0.1], "density": 1000,
       "contact": {"stiffness": 1e5, "friction": 0.3, "shape": {"type": "sphere", "radius": 0.1},
                   "sample_spacing": 0.03})" + ball_extra + R"(},
      {"name": "pusher", "position": [0, 0, 0.15], "kinematic": {"linear_velocity": [1, 0, 0]},
       "contact": {"stiffness": 1e5, "shape": {"type": "box", "half_extents": [0.1, 0.3, 0.15]},
                   "sample_spacing": 0.05}})" + extra_bodies + R"(],
    "colliders": [{"name": "floor", "type": "plane"},
      {"name": "paddle", "type": "capsule", "half_length": 0.3, "radius": 0.05, "position": [1.5, -0.5, 0.1],
       "orientation": [0.7071067811865476, 0.7071067811865476, 0, 0],
       "kinematic": {"keyframes": [{"time": 0.5, "position": [1.5, 0, 0.1]}, {"time": 1.0, "position": [1.5, 0.5, 0.1]}]}}]})";
}

// The pusher and the paddle follow their motions to round-off whatever they touch (they are
// not pushed back); the ball is pushed ahead of the box, its centre one radius in front of
// the box's face at the end; the kinematic bodies hold no kinetic energy.
TEST(KinematicScenes, APusherPushesABallAndIsNotPushedBack) {
  const Scene scene = parse_scene(pusher_scene(), "push.json");
  ASSERT_EQ(scene.model.bodies.size(), 3u);  // the moving collider is a body, after the scene's
  EXPECT_EQ(scene.model.bodies[2].name, "paddle");
  EXPECT_EQ(scene.model.colliders.size(), 1u);
  Simulator sim(scene.model, scene.solver);
  EXPECT_EQ(sim.kinetic_energy(), 0.0);  // the ball rests; the pusher's speed is not the system's
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    const double t = k * scene.model.time_step;
    EXPECT_NEAR(sim.state().points[1].x(), t, 1e-12) << k;
    EXPECT_NEAR(sim.state().points[1].z(), 0.15, 1e-15);
    EXPECT_LT((sim.state().rotations[1] - Matrix3::Identity()).norm(), 1e-15);
    EXPECT_NEAR(sim.linear_velocity(1).x(), 1.0, 1e-9);
    const double paddle_y = t <= 0.5 ? -0.5 + t : t - 0.5;
    EXPECT_NEAR(sim.state().points[2].y(), paddle_y, 1e-12) << k;
    // Contact keeps the ball ahead of the face (x = t + 0.1), within its penetration.
    EXPECT_GT(sim.state().points[0].x() - (t + 0.1), 0.1 - 5e-3) << k;
  }
  EXPECT_NEAR(sim.state().points[0].x(), 1.0 + 0.1 + 0.1, 5e-3);   // carried along at the face
  EXPECT_NEAR(sim.linear_velocity(0).x(), 1.0, 0.05);               // at the pusher's speed
}

// A box resting on a kinematic conveyor belt (a slab moving sideways) with friction is
// carried at the belt's speed; without friction it stays where it is.
TEST(KinematicScenes, FrictionCarriesABoxOnAConveyor) {
  const auto run = [](double friction) {
    const Scene scene = parse_scene(R"({"time_step": 0.005, "frames": 200, "gravity": [0, 0, -9.81],
      "bodies": [
        {"name": "box", "position": [0, 0, 0.05], "density": 1000,
         "contact": {"stiffness": 1e5, "friction": )" + std::to_string(friction) + R"(,
                     "shape": {"type": "box", "half_extents": [0.05, 0.05, 0.05]}, "sample_spacing": 0.025}},
        {"name": "belt", "position": [0, 0, -0.05], "kinematic": {"linear_velocity": [0.5, 0, 0]},
         "contact": {"stiffness": 1e5, "shape": {"type": "box", "half_extents": [5, 1, 0.05]}}}]})",
                                    "conveyor.json");
    Simulator sim(scene.model, scene.solver);
    for (int k = 1; k <= scene.frames; ++k) EXPECT_TRUE(sim.step().converged()) << k;
    return sim.linear_velocity(0).x();
  };
  EXPECT_NEAR(run(0.5), 0.5, 1e-3);  // sticking: up to the lagged law's creep below ε_v = 1 mm/s
  EXPECT_NEAR(run(0.0), 0.0, 1e-9);
}

// Two balls each resting on the same kinematic belt are two islands: the belt, moved, couples
// nothing to anything (as the world).
TEST(KinematicScenes, WhatTouchesAKinematicBodyIsNotCoupledThroughIt) {
  const Scene scene = parse_scene(R"({"time_step": 0.01, "frames": 20, "gravity": [0, 0, -9.81],
    "bodies": [
      {"name": "a", "position": [-1, 0, 0.1], "mass": 1, "inertia": [0.004, 0.004, 0.004],
       "contact": {"stiffness": 1e5, "shape": {"type": "sphere", "radius": 0.1}, "sample_spacing": 0.02}},
      {"name": "b", "position": [1, 0, 0.1], "mass": 1, "inertia": [0.004, 0.004, 0.004],
       "contact": {"stiffness": 1e5, "shape": {"type": "sphere", "radius": 0.1}, "sample_spacing": 0.02}},
      {"name": "belt", "position": [0, 0, -0.05], "kinematic": {"linear_velocity": [0, 0, 0.1]},
       "contact": {"stiffness": 1e5, "shape": {"type": "box", "half_extents": [5, 1, 0.05]}}}]})",
                                  "belt.json");
  Simulator sim(scene.model, scene.solver);
  for (int k = 1; k <= scene.frames; ++k) ASSERT_TRUE(sim.step().converged()) << k;
  EXPECT_EQ(sim.islands(), 2);
  // The belt rose 2 cm and lifted both balls (they rest on it: z = 0.1 + 0.02, less their sag).
  for (int i : {0, 1}) EXPECT_NEAR(sim.state().points[i].z(), 0.12, 2e-3) << i;
}

// A rod hanging over a kinematic capsule that rises is lifted by it (rod edges against a
// moving body's shape); a pendulum hung by a ball joint from a kinematic pivot that moves
// sideways follows it, swinging behind.
TEST(KinematicScenes, AKinematicBodyLiftsARodAndCarriesAPendulum) {
  const Scene lift = parse_scene(R"({"time_step": 0.005, "frames": 200, "gravity": [0, 0, -9.81],
    "rods": [{"name": "rope", "shape": {"type": "line", "start": [-0.3, 0, 0.06], "end": [0.3, 0, 0.06], "edges": 12},
              "mass": 0.05, "radius": 0.005, "stretch_stiffness": 1e3, "shear_stiffness": 1e3, "bending_stiffness": [1e-4, 1e-4, 1e-4],
              "contact": {"stiffness": 1e3}}],
    "colliders": [{"name": "bar", "type": "capsule", "half_length": 0.2, "radius": 0.05,
                   "orientation": [0.7071067811865476, 0.7071067811865476, 0, 0],
                   "kinematic": {"keyframes": [{"time": 1.0, "position": [0, 0, 0.3]}]}}]})",
                                 "lift.json");
  Simulator sim(lift.model, lift.solver);
  for (int k = 1; k <= lift.frames; ++k) ASSERT_TRUE(sim.step().converged()) << k;
  const int middle = lift.model.rod_point(0, 6);
  EXPECT_NEAR(sim.state().points[0].z(), 0.3, 1e-12);                  // the bar where its motion put it
  // The rope on top of it: its edges (capsules, 5 cm long) lie on the circle of radius
  // 0.05 + 0.005 about the bar's axis, so the middle node stands between that circle and the
  // corner of edges tangent to it at their midpoints, 0.055 / cos(asin(0.025 / 0.055)) above.
  const double on_circle = 0.3 + 0.055, tangent_edges = 0.3 + 0.055 / std::cos(std::asin(0.025 / 0.055));
  EXPECT_GT(sim.state().points[middle].z(), on_circle - 1e-3);
  EXPECT_LT(sim.state().points[middle].z(), tangent_edges);

  // The pivot moves at a constant velocity, so in its frame (inertial) the bob swings as a
  // pendulum started with the opposite velocity: θ'' = −(g/L) sin θ, θ(0) = 0, θ'(0) = −v/L,
  // integrated here by RK4 as the reference.
  const Scene swing = parse_scene(R"({"time_step": 0.001, "frames": 1000, "gravity": [0, 0, -9.81],
    "bodies": [
      {"name": "pivot", "position": [0, 0, 1], "kinematic": {"linear_velocity": [0.5, 0, 0]}},
      {"name": "bob", "position": [0, 0, 0.5], "mass": 1, "inertia": [1e-4, 1e-4, 1e-4]}],
    "joints": [{"type": "ball", "a": {"body": "bob", "point": [0, 0, 0.5]}, "b": {"body": "pivot"}}]})",
                                  "swing.json");
  Simulator pendulum(swing.model, swing.solver);
  for (int k = 1; k <= swing.frames; ++k) ASSERT_TRUE(pendulum.step().converged()) << k;
  EXPECT_NEAR(pendulum.state().points[0].x(), 0.5, 1e-12);
  const Vector3 arm = pendulum.state().points[1] - pendulum.state().points[0];
  EXPECT_NEAR(arm.norm(), 0.5, 1e-6);  // still hanging from it
  double theta = 0.0, rate = -0.5 / 0.5;
  const double dt = 1e-4, g_over_L = 9.81 / 0.5;
  for (int i = 0; i < 10000; ++i) {
    const auto f = [&](double th) { return -g_over_L * std::sin(th); };
    const double k1t = rate, k1r = f(theta);
    const double k2t = rate + 0.5 * dt * k1r, k2r = f(theta + 0.5 * dt * k1t);
    const double k3t = rate + 0.5 * dt * k2r, k3r = f(theta + 0.5 * dt * k2t);
    const double k4t = rate + dt * k3r, k4r = f(theta + dt * k3t);
    theta += dt / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t);
    rate += dt / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r);
  }
  EXPECT_GT(std::abs(std::sin(theta)), 0.1);  // a point of the swing far from the bottom
  EXPECT_NEAR(arm.x(), 0.5 * std::sin(theta), 3e-3);  // backward Euler's damping: ~1 % over 1 s
}

// The adjoint runs through contact with a kinematic body: the billiard's cue ball, shot at a
// moving kinematic bumper instead of a ball.
TEST(KinematicAdjoint, TheGradientRunsThroughContactWithAMovingBody) {
  const Scene scene = parse_scene(R"({"time_step": 0.001, "frames": 150, "solver": {"tolerance": 1e-12, "max_iterations": 50},
    "bodies": [
      {"name": "cue", "mass": 1, "inertia": [0.004, 0.004, 0.004], "position": [-0.3, 0.05, 0], "linear_velocity": [2, 0, 0],
       "contact": {"stiffness": 1e5, "radius": 0.005, "friction": 0.5, "shape": {"type": "sphere", "radius": 0.1},
                   "sample_spacing": 0.02}},
      {"name": "bumper", "kinematic": {"linear_velocity": [-0.5, 0.3, 0], "angular_velocity": [0, 0, 3]},
       "contact": {"stiffness": 1e5, "radius": 0.005, "friction": 0.5, "shape": {"type": "box", "half_extents": [0.05, 0.2, 0.1]},
                   "sample_spacing": 0.03}}],
    "optimization": {"parameters": [{"kind": "body_linear_velocity", "body": "cue"}],
                     "objective": [{"term": "body_pose", "body": "cue", "frame": -1, "position": [0.3, -0.1, 0]}]}})",
                                  "bumper.json");
  // The shot does reach the bumper (otherwise the check would not be through contact).
  Simulator sim(scene.model, scene.solver);
  double fastest = 0.0;
  for (int k = 1; k <= scene.frames; ++k) {
    ASSERT_TRUE(sim.step().converged()) << k;
    fastest = std::max(fastest, sim.contact_pairs() > 0 ? 1.0 : 0.0);
  }
  EXPECT_EQ(fastest, 1.0);
  EXPECT_LT(sim.linear_velocity(0).x(), 0.0);  // bounced back
  EXPECT_TRUE(test::gradient_agrees(scene));
}

// Each misuse is refused naming its field.
TEST(KinematicScenes, MisusesAreRefusedNamingTheField) {
  const auto field_of = [](const std::string& text) {
    try {
      parse_scene(text, "bad.json");
    } catch (const SceneError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  const std::string head = R"({"time_step": 0.01, "frames": 10, "bodies": [
      {"name": "ball", "mass": 1, "inertia": [1, 1, 1]},)";
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {"angular_velocity": [0, 0, 1]}}]})"), "accepted");
  EXPECT_EQ(field_of(head + R"({"name": "k", "mass": 1, "kinematic": {"angular_velocity": [0, 0, 1]}}]})"),
            "bodies[1].mass");
  EXPECT_EQ(field_of(head + R"({"name": "k", "linear_velocity": [1, 0, 0], "kinematic": {"angular_velocity": [0, 0, 1]}}]})"),
            "bodies[1].linear_velocity");
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {}}]})"), "bodies[1].kinematic");
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {"angular_velocity": [0, 0, 1], "keyframes": [{"time": 1}]}}]})"),
            "bodies[1].kinematic.angular_velocity");
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {"keyframes": [{"time": 1, "orientation": [0, 0, 0, 1]}]}}]})"),
            "bodies[1].kinematic.keyframes[0].orientation");  // a half turn: which way?
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {"angular_velocity": [0, 0, 1]}}],
                     "forces": [{"body": "k", "force": [1, 0, 0]}]})"),
            "forces[0].body");
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {"angular_velocity": [0, 0, 1]}}],
                     "springs": [{"body_a": "k", "body_b": "world", "stiffness": 1}]})"),
            "springs[0].body_b");
  const std::string collider = R"({"time_step": 0.01, "frames": 10, "bodies": [{"name": "ball", "mass": 1, "inertia": [1, 1, 1]}],
      "colliders": [)";
  EXPECT_EQ(field_of(collider + R"({"type": "sphere", "radius": 1, "kinematic": {"linear_velocity": [1, 0, 0]}}]})"),
            "colliders[0].name");
  EXPECT_EQ(field_of(collider + R"({"name": "ball", "type": "sphere", "radius": 1, "kinematic": {"linear_velocity": [1, 0, 0]}}]})"),
            "colliders[0].name");  // the name of a body already
  // Any collider may move, a plane or an inside-out shape too (tests/test_moving_colliders.cpp).
  EXPECT_EQ(field_of(collider + R"({"name": "p", "type": "plane", "kinematic": {"linear_velocity": [1, 0, 0]}}]})"),
            "accepted");
  EXPECT_EQ(field_of(collider + R"({"name": "p", "type": "sphere", "radius": 1, "inside": true,
                                    "kinematic": {"linear_velocity": [1, 0, 0]}}]})"),
            "accepted");
  EXPECT_EQ(field_of(collider + R"({"name": "p", "type": "sphere", "radius": -1, "kinematic": {"linear_velocity": [1, 0, 0]}}]})"),
            "colliders[0].radius");
  // A body's shape is checked as a collider is (whether kinematic or not).
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {"angular_velocity": [0, 0, 1]},
                               "contact": {"stiffness": 1, "shape": {"type": "box", "half_extents": [1, 0, 1]}}}]})"),
            "bodies[1].contact.shape.half_extents");
  // An optimisation cannot control a kinematic body's initial state.
  EXPECT_EQ(field_of(head + R"({"name": "k", "kinematic": {"angular_velocity": [0, 0, 1]}}],
                     "optimization": {"parameters": [{"kind": "body_linear_velocity", "body": "k"}],
                                      "objective": [{"term": "body_pose", "body": "ball", "frame": -1, "position": [0, 0, 0]}]}})"),
            "optimization.parameters[0]");
}

}  // namespace
}  // namespace liedyn

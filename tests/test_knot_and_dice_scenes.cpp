// Two bundled contact scenes in whole runs: an overhand knot pulled tight (contact/knot.json,
// written by scripts/make_knot_scene.py; rod self-contact, lib/edge_contact.hpp) and a die
// thrown onto a die resting on a table (contact/die_on_die.json; body–body contact,
// lib/body_contact.hpp). Each runs the whole scene file.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <numbers>
#include <variant>
#include <vector>

#include "lib/body_contact.hpp"
#include "problems/scene.hpp"
#include "solvers/simulator.hpp"

namespace liedyn {
namespace {

Scene bundled(const char* name) {
  return load_scene(std::filesystem::path(LIEDYN_SOURCE_DIR) / "problems/scenes/contact" / name);
}

std::vector<Vector3> rod_nodes(const Simulator& sim, int rod) {
  std::vector<Vector3> x;
  for (int i = 0; i < sim.model().rods[rod].node_count(); ++i)
    x.push_back(sim.state().points[sim.model().rod_point(rod, i)]);
  return x;
}

// Where the knot is along the cord: its edges that turn more than 45° away from the pull (the
// line through the two ends), and the cord between the first and the last of them. The tails,
// straight and along the pull, stay out of it (also as they vibrate once taut: a few degrees);
// the knot's loops wind about the pull and cross it. Its length, and the largest distance of
// its nodes from their centroid (the radius of a sphere about it that holds the knot).
struct KnotExtent {
  double length = 0.0;
  double radius = 0.0;
};

KnotExtent knot_extent(const std::vector<Vector3>& x) {
  const Vector3 pull = (x.back() - x.front()).normalized();
  const double cos_limit = std::cos(std::numbers::pi / 4.0);
  int first = -1, last = -1;
  for (int e = 0; e + 1 < static_cast<int>(x.size()); ++e) {
    if ((x[e + 1] - x[e]).normalized().dot(pull) < cos_limit) {
      if (first < 0) first = e;
      last = e;
    }
  }
  KnotExtent k;
  if (first < 0) return k;  // straight: no knot at all
  Vector3 centroid = Vector3::Zero();
  for (int i = first; i <= last + 1; ++i) centroid += x[i];
  centroid /= last + 2 - first;
  for (int i = first; i <= last + 1; ++i) {
    if (i <= last) k.length += (x[i + 1] - x[i]).norm();
    k.radius = std::max(k.radius, (x[i] - centroid).norm());
  }
  return k;
}

// Σ of the angles between consecutive edges.
double total_turning(const std::vector<Vector3>& x) {
  double turning = 0.0;
  for (std::size_t i = 1; i + 1 < x.size(); ++i) {
    const Vector3 a = (x[i] - x[i - 1]).normalized(), b = (x[i + 1] - x[i]).normalized();
    turning += std::atan2(a.cross(b).norm(), a.dot(b));
  }
  return turning;
}

// The bundled knot: a loose open overhand knot in a soft cord whose clamped ends are pulled
// 0.26 m further apart. Over every frame no two edges more than self_contact_skip apart come
// closer than the cord's radius, centre line to centre line (a surface separation above −r),
// and no node moves by a radius or more in a step. Together these rule out a crossing hidden
// between two frames: move the nodes linearly over the step (all that is known of the motion
// within it); every point of an edge then moves by at most m, the largest node motion, so
// the distance between two edges' centre lines changes by at most 2m over the step, at a
// steady rate. To cross, it would have to fall from ≥ r (at the frame before) to 0 at some
// s* in (0, 1) of the step and rise again to ≥ r (at the frame after): r ≤ 2m s* and
// r ≤ 2m (1 − s*), so m ≥ r. With m < r the knot the cord starts in is the knot it ends in.
// It ends tight: the rope in the knot and the sphere about it shrink by more than 3 times,
// while the strands press on one another (surfaces overlapping, that is in contact) and the
// cord still turns by more than 2π in all (Fáry–Milnor: closed by a far arc from one tail
// around to the other, adding about 2π, a knotted curve turns by more than 4π; an untied
// cord pulled straight would turn by nearly nothing).
TEST(KnotAndDiceScenes, AnOverhandKnotPulledTightNeverPassesThroughItself) {
  const Scene scene = bundled("knot.json");
  ASSERT_EQ(scene.model.rods.size(), 1u);
  const RodSpec& cord = scene.model.rods[0];
  ASSERT_TRUE(cord.self_contact);
  const double radius = cord.contact.radius;
  ASSERT_EQ(radius, cord.radius);

  Simulator sim(scene.model, scene.solver);
  ASSERT_TRUE(sim.has_rod_contact());
  const std::vector<Vector3> start = rod_nodes(sim, 0);
  const KnotExtent loose = knot_extent(start);
  const double initial_separation = sim.min_rod_separation();
  double closest = initial_separation, fastest = 0.0;
  int fastest_frame = 0, closest_frame = 0;
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << k << ": " << r.message;
    if (sim.min_rod_separation() < closest) {
      closest = sim.min_rod_separation();
      closest_frame = k;
    }
    for (int i = 0; i < cord.node_count(); ++i) {
      const double moved = sim.last_step().points[sim.model().rod_point(0, i)].norm();
      if (moved > fastest) {
        fastest = moved;
        fastest_frame = k;
      }
    }
  }
  const std::vector<Vector3> end = rod_nodes(sim, 0);
  const KnotExtent tight = knot_extent(end);

  EXPECT_GT(initial_separation, 0.0);  // loose: nothing touches at the start
  EXPECT_GT(closest, -radius);
  EXPECT_LT(fastest, radius);
  EXPECT_GT((end.back() - end.front()).norm(), (start.back() - start.front()).norm() + 0.25);
  EXPECT_LT(tight.length, loose.length / 3.0);
  EXPECT_LT(tight.radius, loose.radius / 3.0);
  EXPECT_LT(sim.min_rod_separation(), 0.0);
  EXPECT_GT(total_turning(end), 2.0 * std::numbers::pi);
  std::cout << "knot: closest surfaces " << closest << " m (frame " << closest_frame << "; radius "
            << radius << "), largest node motion in a step " << fastest << " m (frame "
            << fastest_frame << "); rope in the knot " << loose.length << " -> " << tight.length
            << " m, sphere about it " << loose.radius << " -> " << tight.radius << " m; ends "
            << (start.back() - start.front()).norm() << " -> " << (end.back() - end.front()).norm()
            << " m apart; total turning " << total_turning(end) / std::numbers::pi << " pi; "
            << sim.contact_pairs() << " pairs of edges in contact at the end\n";
}

// The bundled dice: the thrown die lands on the resting one's top face at 0.87 m/s, moving
// sideways at 0.15 m/s. With μ = 0.5, friction stops the slide at the impact (μ times the
// impact speed exceeds the sideways speed), and even the weight alone would stop it within
// v²/(2 μ g) = 2.3 mm: so after it first touches, its centre moves less than that sideways;
// it lands 2.3 mm off the bottom die's axis, within the flat part of the top face (the half
// extent less the rounding, 8.5 mm), so it stays there, face down, its centre ρ + 2 half
// extents above the bottom die's (its samples' spheres on the face). Nothing does work on the
// pair but gravity, so kinetic plus potential energy (penalties and gravity) never rises
// above round-off (friction and backward Euler only dissipate). No sample sinks by its radius
// into a die or the table, both come to rest with at least 0.1 s of the run to spare, and the
// bottom die, held by friction on the table, hardly moves.
TEST(KnotAndDiceScenes, ADieThrownOntoARestingDieComesToRestOnIt) {
  const Scene scene = bundled("die_on_die.json");
  ASSERT_EQ(scene.model.bodies.size(), 2u);
  ASSERT_EQ(scene.model.body_pairs().size(), 1u);
  const int bottom = 0, top = 1;
  const RigidBody& die = scene.model.bodies[top];
  const double rho = die.contact.radius, mu = die.contact.friction;
  const BoxShape& box = std::get<BoxShape>(die.shape->shape);
  const double half = box.half_extents.x();
  ASSERT_EQ(box.half_extents, Vector3::Constant(half));
  // Nothing acts sideways in flight: it lands moving sideways as it was thrown.
  const double sideways = die.linear_velocity.head<2>().norm();
  const double slide_limit = sideways * sideways / (2.0 * mu * -scene.model.gravity.z());

  Simulator sim(scene.model, scene.solver);
  const TouchingPairs dice(scene.model);
  const Vector3 bottom_start = sim.state().points[bottom];
  const double energy0 = sim.kinetic_energy() + sim.potential_energy();
  double energy = energy0, rise = 0.0, deepest = 0.0,
         lowest_top_sample = std::numeric_limits<double>::infinity();
  double bottom_moved = 0.0;
  int touching = 0, rest_since = 0;
  Vector3 landing = Vector3::Constant(std::numeric_limits<double>::quiet_NaN());
  for (int k = 1; k <= scene.frames; ++k) {
    const StepReport r = sim.step();
    ASSERT_TRUE(r.converged()) << k << ": " << r.message;
    const double e = sim.kinetic_energy() + sim.potential_energy();
    rise = std::max(rise, e - energy);
    energy = e;
    EXPECT_LE(e, energy0 + 1e-12) << k;
    deepest = std::max(deepest, sim.max_penetration());
    if (dice.penetrates(sim.state(), 0)) {
      if (touching++ == 0) landing = sim.state().points[top];
    }
    for (const Vector3& s : die.contact_points) {
      lowest_top_sample = std::min(lowest_top_sample,
                                   (sim.state().points[top] + sim.state().rotations[top] * s).z());
    }
    bottom_moved = std::max(bottom_moved, (sim.state().points[bottom] - bottom_start).norm());
    bool at_rest = true;
    for (int b : {bottom, top}) {
      at_rest =
          at_rest && sim.linear_velocity(b).norm() < 1e-5 && sim.angular_velocity(b).norm() < 1e-3;
    }
    if (!at_rest) rest_since = k;
  }
  const Vector3 x_bottom = sim.state().points[bottom], x_top = sim.state().points[top];
  // The axis of each die nearest the vertical, and how far it is from it.
  const auto tilt = [&](int b) {
    return std::acos(std::min(
        1.0, (sim.state().rotations[b].transpose() * Vector3::UnitZ()).cwiseAbs().maxCoeff()));
  };

  EXPECT_LT(rise, 1e-12);
  EXPECT_LT(deepest, rho);
  EXPECT_GT(touching, scene.frames / 2);  // they met, and stayed in contact
  EXPECT_GT(lowest_top_sample, rho);      // the thrown die never reached the table
  EXPECT_LT((x_top - landing).head<2>().norm(), slide_limit);
  EXPECT_LT((x_top - x_bottom).head<2>().norm(), half - box.rounding);
  EXPECT_NEAR(x_top.z() - x_bottom.z(), 2.0 * half + rho, 1e-5);
  EXPECT_LT(tilt(top), 1e-3);
  EXPECT_LT(tilt(bottom), 1e-3);
  EXPECT_LT(bottom_moved, 1e-3);
  EXPECT_LE(rest_since, scene.frames - static_cast<int>(0.1 / scene.model.time_step));
  std::cout << "dice: the thrown die rests at (" << x_top.transpose() << "), "
            << (x_top - x_bottom).head<2>().norm() << " m off the bottom die's axis and "
            << x_top.z() - x_bottom.z() << " m above its centre, having slid "
            << (x_top - landing).head<2>().norm() << " m after landing; the bottom die at ("
            << x_bottom.transpose() << "), moved at most " << bottom_moved
            << " m; both at rest from frame " << rest_since + 1 << " of " << scene.frames
            << "; deepest sample " << deepest << " m; energy rose by at most " << rise
            << " J in a step (" << energy0 << " -> " << energy << " J); dice in contact for "
            << touching << " frames\n";
}

}  // namespace
}  // namespace liedyn

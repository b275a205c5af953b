#include "analytic.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "../lib/so3.hpp"

namespace liedyn {
namespace {

// Two principal moments count as equal within this fraction of tr I_b: round-off of a tensor
// given in a rotated frame is ~1e-16 tr, and an asymmetry of 1e-10 moves ω by ~1e-10 |ω|.
constexpr double kAxisymmetryTolerance = 1e-10;
// Nodes count as on one line within this fraction of the rod's length.
constexpr double kStraightnessTolerance = 1e-9;

[[noreturn]] void reject(const Scene& scene, const std::string& reason) {
  throw SceneError(scene.source, "analytic",
                   std::string("\"") + to_string(scene.analytic) + "\" needs " + reason);
}

// The symmetry axis a (body frame) and the moments (I⊥, I_a) of an axisymmetric inertia.
struct Axisymmetric {
  Vector3 axis;
  double perpendicular = 0.0, axial = 0.0;
};

Axisymmetric axisymmetric(const Scene& scene) {
  const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(scene.model.bodies[0].inertia);
  const Vector3 moments = eigen.eigenvalues();  // ascending
  const double tolerance = kAxisymmetryTolerance * moments.sum();
  // Two equal moments: the third one's eigenvector is the axis (any axis for a sphere).
  if (moments(1) - moments(0) <= tolerance) {
    return {eigen.eigenvectors().col(2), moments(0), moments(2)};
  }
  if (moments(2) - moments(1) <= tolerance) {
    return {eigen.eigenvectors().col(0), moments(1), moments(0)};
  }
  reject(scene, "an axisymmetric inertia (two equal principal moments)");
}

void check_free_body(const Scene& scene) {
  const Model& m = scene.model;
  if (m.static_equilibrium) reject(scene, "\"mode\": \"dynamic\"");
  if (m.bodies.size() != 1 || !m.rods.empty()) reject(scene, "exactly one body and no rods");
  if (!m.springs.empty() || !m.forces.empty() || !m.torques.empty()) {
    reject(scene, "no springs, forces or torques (torque-free motion)");
  }
  if (!m.colliders.empty()) reject(scene, "no colliders (free motion)");
  axisymmetric(scene);
}

// The straight rod of the static rod solutions: its direction, the load and node arc lengths.
struct StraightRod {
  Vector3 direction;
  Vector3 force;
  std::vector<double> s;  // distance of each node from node 0
};

StraightRod straight_rod(const Scene& scene) {
  const Model& m = scene.model;
  if (!m.static_equilibrium) reject(scene, "\"mode\": \"static\"");
  if (m.rods.size() != 1 || !m.bodies.empty()) reject(scene, "exactly one rod and no bodies");
  if (!m.gravity.isZero()) reject(scene, "zero gravity (a tip load only)");
  const RodSpec& rod = m.rods[0];
  const int last = rod.node_count() - 1;
  if (rod.node_forces.size() != 1 || rod.node_forces[0].node != last ||
      !rod.node_forces[0].control.schedule.empty()) {
    reject(scene, "exactly one constant node force, on the last node");
  }
  if (!rod.cables.empty() || !rod.prescribed_motions.empty()) {
    reject(scene, "no cables and no prescribed motions");
  }
  if (!m.colliders.empty() || !rod.region_pushes.empty()) {
    reject(scene, "no colliders and no region pushes");
  }
  StraightRod r;
  const Vector3 span = rod.nodes[last] - rod.nodes[0];
  const double length = span.norm();
  r.direction = span / length;
  r.force = rod.node_forces[0].force;
  for (const Vector3& x : rod.nodes) {
    const Vector3 offset = x - rod.nodes[0];
    const double s = offset.dot(r.direction);
    if ((offset - s * r.direction).norm() > kStraightnessTolerance * length) {
      reject(scene, "a straight rod (every node on the line from the first to the last)");
    }
    r.s.push_back(s);
  }
  const bool straight_rest = rod.rest_nodes.empty() || rod.rest_nodes == rod.nodes;
  const bool no_curvature = std::all_of(rod.rest_darboux.begin(), rod.rest_darboux.end(),
                                        [](const Vector3& w) { return w.isZero(); });
  if (!straight_rest || !no_curvature || !rod.rest_darboux_controls.empty()) {
    reject(scene, "a straight rest shape (no rest_nodes or rest Darboux vectors of its own)");
  }
  return r;
}

void check_cantilever(const Scene& scene) {
  const StraightRod r = straight_rod(scene);
  const RodSpec& rod = scene.model.rods[0];
  if (rod.fixed_nodes != std::vector<int>{0} || rod.fixed_edges != std::vector<int>{0}) {
    reject(scene, "\"fixed_nodes\": [0] and \"fixed_edges\": [0] (a clamp at node 0 only)");
  }
  if (rod.bending_stiffness(0) != rod.bending_stiffness(1)) {
    reject(scene, "isotropic bending (bending_stiffness[0] = bending_stiffness[1])");
  }
  if (std::abs(r.force.dot(r.direction)) > 1e-12 * r.force.norm()) {
    reject(scene, "a tip force perpendicular to the rod");
  }
}

void check_axial_stretch(const Scene& scene) {
  const StraightRod r = straight_rod(scene);
  const RodSpec& rod = scene.model.rods[0];
  if (rod.fixed_nodes != std::vector<int>{0}) reject(scene, "\"fixed_nodes\": [0]");
  if ((r.force - r.force.dot(r.direction) * r.direction).norm() > 1e-12 * r.force.norm()) {
    reject(scene, "a tip force along the rod");
  }
}

// λ_k of Model::static_equilibrium.
double load_scale(const Scene& scene, int k) {
  return std::min(1.0, double(k) / scene.model.load_steps);
}

std::vector<ExactFrame> free_body(const Scene& scene) {
  const RigidBody& b = scene.model.bodies[0];
  const Axisymmetric inertia = axisymmetric(scene);
  const Vector3 L = b.orientation * b.inertia * b.orientation.transpose() * b.angular_velocity;
  const double lambda = (1.0 / inertia.axial - 1.0 / inertia.perpendicular) *
                        inertia.axis.dot(b.orientation.transpose() * L);
  std::vector<ExactFrame> frames(scene.frames + 1);
  for (int k = 0; k <= scene.frames; ++k) {
    const double t = k * scene.model.time_step;
    frames[k].points = {
        {0, b.position + t * b.linear_velocity + 0.5 * t * t * scene.model.gravity}};
    frames[k].rotations = {{0, so3::exp(t / inertia.perpendicular * L) * b.orientation *
                                   so3::exp(t * lambda * inertia.axis)}};
  }
  return frames;
}

// The static rod solutions: node displacement u(s) and edge rotation angle θ(s) (about
// `axis`) at full load, scaled by λ_k.
template <class Displacement, class Angle>
std::vector<ExactFrame> static_rod(const Scene& scene, const StraightRod& r, const Vector3& axis,
                                   Displacement u, Angle theta) {
  const Model& m = scene.model;
  const RodSpec& rod = m.rods[0];
  const std::vector<Matrix3> frames0 = parallel_transport_frames(rod.nodes);
  std::vector<ExactFrame> frames(scene.frames + 1);
  for (int k = 0; k <= scene.frames; ++k) {
    const double lambda = load_scale(scene, k);
    for (int i = 0; i < rod.node_count(); ++i) {
      frames[k].points.emplace_back(m.rod_point(0, i), rod.nodes[i] + lambda * u(r.s[i]));
    }
    for (int j = 0; j < rod.edge_count(); ++j) {
      // A clamped edge keeps its frame: it holds the rod's tangent at the clamp.
      const bool clamped = std::find(rod.fixed_edges.begin(), rod.fixed_edges.end(), j) != rod.fixed_edges.end();
      const double midpoint = 0.5 * (r.s[j] + r.s[j + 1]);
      const double angle = clamped ? 0.0 : lambda * theta(midpoint);
      frames[k].rotations.emplace_back(m.rod_rotation(0, j), so3::exp(angle * axis) * frames0[j]);
    }
  }
  return frames;
}

std::vector<ExactFrame> cantilever(const Scene& scene) {
  const StraightRod r = straight_rod(scene);
  const double EI = scene.model.rods[0].bending_stiffness(0);
  const double F = r.force.norm();
  const double L = r.s.back();
  const Vector3 along_force = F > 0.0 ? Vector3(r.force / F) : Vector3::Zero();
  const Vector3 axis = r.direction.cross(along_force);
  return static_rod(
      scene, r, axis,
      [&](double s) -> Vector3 { return F * s * s * (3.0 * L - s) / (6.0 * EI) * along_force; },
      [&](double s) { return F * s * (2.0 * L - s) / (2.0 * EI); });
}

std::vector<ExactFrame> axial_stretch(const Scene& scene) {
  const StraightRod r = straight_rod(scene);
  const double ks = scene.model.rods[0].stretch_stiffness;
  return static_rod(
      scene, r, Vector3::Zero(), [&](double s) -> Vector3 { return s / ks * r.force; },
      [](double) { return 0.0; });
}

}  // namespace

std::optional<AnalyticSolution> parse_analytic(std::string_view name) {
  for (const AnalyticSolution s :
       {AnalyticSolution::kNone, AnalyticSolution::kFreeBody, AnalyticSolution::kCantilever,
        AnalyticSolution::kAxialStretch}) {
    if (name == to_string(s)) return s;
  }
  return std::nullopt;
}

const char* to_string(AnalyticSolution solution) {
  switch (solution) {
    case AnalyticSolution::kNone:
      return "none";
    case AnalyticSolution::kFreeBody:
      return "free_body";
    case AnalyticSolution::kCantilever:
      return "cantilever";
    case AnalyticSolution::kAxialStretch:
      return "axial_stretch";
  }
  return "?";
}

void check_analytic(const Scene& scene) {
  switch (scene.analytic) {
    case AnalyticSolution::kNone:
      return;
    case AnalyticSolution::kFreeBody:
      return check_free_body(scene);
    case AnalyticSolution::kCantilever:
      return check_cantilever(scene);
    case AnalyticSolution::kAxialStretch:
      return check_axial_stretch(scene);
  }
}

std::vector<ExactFrame> exact_trajectory(const Scene& scene) {
  check_analytic(scene);
  switch (scene.analytic) {
    case AnalyticSolution::kNone:
      return {};
    case AnalyticSolution::kFreeBody:
      return free_body(scene);
    case AnalyticSolution::kCantilever:
      return cantilever(scene);
    case AnalyticSolution::kAxialStretch:
      return axial_stretch(scene);
  }
  return {};
}

}  // namespace liedyn

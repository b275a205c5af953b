#include "rod.hpp"

#include <algorithm>
#include <cmath>

#include "rod_terms.hpp"
#include "so3.hpp"

namespace liedyn {

Matrix3 minimal_rotation(const Vector3& a, const Vector3& b) {
  const Vector3 axis = a.cross(b);
  const double s = axis.norm();
  const double c = a.dot(b);
  if (s < 1e-12 && c < 0.0) {
    // Antiparallel: a half turn about any axis perpendicular to a.
    Vector3 perpendicular = a.cross(Vector3::UnitX());
    if (perpendicular.norm() < 0.5) perpendicular = a.cross(Vector3::UnitY());
    return so3::exp(std::acos(-1.0) * perpendicular.normalized());
  }
  if (s == 0.0) return Matrix3::Identity();
  return so3::exp(std::atan2(s, c) / s * axis);
}

std::vector<Matrix3> parallel_transport_frames(const std::vector<Vector3>& nodes) {
  std::vector<Matrix3> frames;
  Vector3 previous_tangent = Vector3::UnitZ();
  Matrix3 frame = Matrix3::Identity();
  for (std::size_t j = 0; j + 1 < nodes.size(); ++j) {
    const Vector3 tangent = (nodes[j + 1] - nodes[j]).normalized();
    frame = so3::orthonormalize(minimal_rotation(previous_tangent, tangent) * frame);
    frames.push_back(frame);
    previous_tangent = tangent;
  }
  return frames;
}

RodDiscretization discretize(const RodSpec& rod, RodEnds ends) {
  RodDiscretization d;
  const std::vector<Vector3>& rest = rod.rest_shape();
  const int n = rod.node_count();
  const int edges = rod.edge_count();
  double total_length = 0.0;
  for (int j = 0; j < edges; ++j) {
    d.rest_length.push_back((rest[j + 1] - rest[j]).norm());
    total_length += d.rest_length.back();
  }
  d.node_mass.assign(n, 0.0);
  const double r2 = rod.radius * rod.radius;
  for (int j = 0; j < edges; ++j) {
    const double l = d.rest_length[j];
    const double m = rod.mass * l / total_length;
    d.node_mass[j] += 0.5 * m;
    d.node_mass[j + 1] += 0.5 * m;
    const double transverse = m * (3.0 * r2 + l * l) / 12.0;
    d.edge_inertia.push_back(Vector3(transverse, transverse, 0.5 * m * r2).asDiagonal());
  }
  d.frames = parallel_transport_frames(rod.nodes);
  const std::vector<Matrix3> rest_frames =
      rod.rest_nodes.empty() ? d.frames : parallel_transport_frames(rest);
  const auto fixed = [&](int edge) {
    return std::find(rod.fixed_edges.begin(), rod.fixed_edges.end(), edge) != rod.fixed_edges.end();
  };
  const bool first_clamped = (fixed(0) || ends.first_welded) && !ends.first_spliced;
  const bool last_clamped = (fixed(edges - 1) || ends.last_welded) && !ends.last_spliced;
  for (int i = 1; i + 1 < n; ++i) {
    double l = 0.5 * (d.rest_length[i - 1] + d.rest_length[i]);
    if (i == 1 && first_clamped) l += 0.5 * d.rest_length[0];
    if (i == n - 2 && last_clamped) l += 0.5 * d.rest_length[edges - 1];
    d.bending_length.push_back(l);
    d.rest_darboux.push_back(rod.rest_darboux.empty()
                                 ? darboux_vector(rest_frames[i - 1], rest_frames[i], l)
                                 : rod.rest_darboux[i - 1]);
  }
  return d;
}

}  // namespace liedyn

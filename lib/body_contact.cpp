#include "body_contact.hpp"

#include <cmath>
#include <algorithm>
#include <limits>
#include <numbers>
#include <variant>

#include "point_pair.hpp"
#include "so3.hpp"

namespace liedyn {

SdfValue BodyContact::field(const State& q, Vector3& w, bool with_hessian) const {
  const Matrix3& R_b = q.rotations[body_b];
  w = at.position(q) - q.points[body_b];
  SdfValue s = shape->evaluate(R_b.transpose() * w, with_hessian);  // in B's coordinates
  s.gradient = R_b * s.gradient;
  if (with_hessian) s.hessian = R_b * s.hessian * R_b.transpose();
  return s;
}

double BodyContact::penetration(const State& q) const {
  Vector3 w;
  return radius - field(q, w, false).distance;
}

double BodyContact::evaluate(const State& q, LocalGradient<kBlocks>* g,
                             LocalHessian<kBlocks>* H) const {
  Vector3 w;
  const SdfValue s = field(q, w, H != nullptr);
  const double d = radius - s.distance;
  if (!(d > 0.0)) {
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  if (g == nullptr && H == nullptr) return 0.5 * stiffness * d * d;
  const Vector3 r = at.lever(q);
  const Vector3 f = -stiffness * d * s.gradient;  // ∂V/∂p
  Eigen::Matrix<double, 3, 12> J;
  J << Matrix3::Identity(), -so3::hat(r), -Matrix3::Identity(), so3::hat(w);
  if (g != nullptr) *g = J.transpose() * f;
  if (H != nullptr) {
    const Matrix3 K = stiffness * (s.gradient * s.gradient.transpose() - d * s.hessian);
    const Eigen::Matrix<double, 12, 3> JtK = J.transpose() * K;
    H->noalias() = JtK.lazyProduct(J);
    const Matrix3 F = so3::hat(f);
    H->block<3, 3>(3, 3) += rotated_point_curvature(r, f);
    H->block<3, 3>(9, 9) += rotated_point_curvature(w, f);
    H->block<3, 3>(9, 0) += F;
    H->block<3, 3>(0, 9) -= F;  // (hat f)ᵀ
    H->block<3, 3>(9, 6) -= F;
    H->block<3, 3>(6, 9) += F;
    const Matrix3 FS = F * so3::hat(r);
    H->block<3, 3>(9, 3) -= FS;
    H->block<3, 3>(3, 9) -= FS.transpose();
  }
  return 0.5 * stiffness * d * d;
}

void BodyContact::residual(const State& q, Residual& res, ResidualJacobian* J) const {
  Vector3 w;
  const SdfValue s = field(q, w, false);
  const double d = radius - s.distance;
  if (!(d > 0.0)) {
    res(0) = 0.0;
    if (J != nullptr) J->setZero();
    return;
  }
  const double root_k = std::sqrt(stiffness);
  res(0) = root_k * d;
  if (J != nullptr) {
    const Vector3& n = s.gradient;
    const Vector3 r = at.lever(q);
    // −√k nᵀ [I, −hat(r), −I, hat(w)]: nᵀ(−hat(r)) = (r × n)ᵀ, nᵀ hat(w) = −(w × n)ᵀ.
    J->block<1, 3>(0, 0) = -root_k * n.transpose();
    J->block<1, 3>(0, 3) = -root_k * r.cross(n).transpose();
    J->block<1, 3>(0, 6) = root_k * n.transpose();
    J->block<1, 3>(0, 9) = root_k * w.cross(n).transpose();
  }
}

void BodyFriction::begin_step(const State& previous, const Step&) {
  const Matrix3& R_b = previous.rotations[body_b];
  contact_point = R_b.transpose() * (at.position(previous) - previous.points[body_b]);
  const SdfValue s = shape->evaluate(contact_point, false);
  normal_force = stiffness * std::max(0.0, radius - s.distance);
  const double length = s.gradient.norm();
  normal = length > 0.0 ? Vector3(R_b * s.gradient / length) : Vector3::UnitZ();
}

SmoothedSlip BodyFriction::slip(const State& q, Vector3& lever_b) const {
  lever_b = q.rotations[body_b] * contact_point;
  const Vector3 d = q.points[body_b] + lever_b - at.position(q);
  return SmoothedSlip(d - normal.dot(d) * normal, epsilon);
}

double BodyFriction::evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
  if (normal_force == 0.0) {
    if (g != nullptr) g->setZero();
    if (H != nullptr) H->setZero();
    return 0.0;
  }
  Vector3 r_b;
  const SmoothedSlip s = slip(q, r_b);
  const double scale = coefficient * normal_force;  // μλ
  if (g != nullptr || H != nullptr) {
    Matrix3 K = Matrix3::Zero();
    if (H != nullptr) K = scale * s.curvature(Matrix3::Identity() - normal * normal.transpose());
    point_pair_derivatives(at.lever(q), r_b, scale * s.phi1 * s.u, K, g, H);
  }
  return scale * s.f0;
}

void BodyFriction::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  friction_residual(*this, q, r, J);
}

Eigen::Matrix<double, 12, 12> BodyFriction::previous_jacobian(const State& q, const State& previous) const {
  using Block = Eigen::Matrix<double, 3, 12>;
  Eigen::Matrix<double, 12, 12> out = Eigen::Matrix<double, 12, 12>::Zero();
  if (normal_force == 0.0) return out;
  Vector3 r_b;
  const SmoothedSlip s = slip(q, r_b);
  const Matrix3& R_b_previous = previous.rotations[body_b];
  const Vector3 w_previous = at.position(previous) - previous.points[body_b];
  const SdfValue lagged = shape->evaluate(contact_point, true);
  const double g_norm = lagged.gradient.norm();
  const Vector3 G = R_b_previous * lagged.gradient;  // world
  const Matrix3 N = R_b_previous * lagged.hessian * R_b_previous.transpose();
  Block J_previous;  // Ĵ
  J_previous << Matrix3::Identity(), -so3::hat(at.lever(previous)), -Matrix3::Identity(), so3::hat(w_previous);
  const Block du_contact = R_b_previous.transpose() * J_previous;  // ∂û/∂q̂
  const Eigen::Matrix<double, 1, 12> dlambda = -stiffness * G.transpose() * J_previous;
  const Matrix3 P = Matrix3::Identity() - normal * normal.transpose();
  Block dn = Block::Zero();
  if (g_norm > 0.0) dn = (P * N / g_norm) * J_previous;
  dn.rightCols<3>() -= so3::hat(normal);
  const Matrix3& R_b = q.rotations[body_b];
  const Block dd = R_b * du_contact;
  const Vector3 d = q.points[body_b] + r_b - at.position(q);
  const Block du = P * dd - (normal * d.transpose() + normal.dot(d) * Matrix3::Identity()) * dn;
  const Block df = coefficient * (s.phi1 * s.u * dlambda + normal_force * s.jacobian() * du);
  const Vector3 f = coefficient * normal_force * s.phi1 * s.u;
  out.middleRows<3>(0) = -df;
  out.middleRows<3>(3) = -so3::hat(at.lever(q)) * df;
  out.middleRows<3>(6) = df;
  out.middleRows<3>(9) = so3::hat(r_b) * df - so3::hat(f) * dd;
  return out;
}

void BodyFriction::add_step_adjoint(const State& q, const State& previous, const Step&,
                                    const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                                    Eigen::VectorXd&) const {
  if (normal_force == 0.0) return;
  const LocalGradient<kBlocks> w = previous_jacobian(q, previous).transpose() * z;
  a_previous.segment<3>(tangent_point(at.point)) += w.segment<3>(0);
  if (at.rotation >= 0) a_previous.segment<3>(tangent_rotation(q, at.rotation)) += w.segment<3>(3);  // a rod node has none
  a_previous.segment<3>(tangent_point(body_b)) += w.segment<3>(6);
  a_previous.segment<3>(tangent_rotation(q, body_b)) += w.segment<3>(9);
}

namespace {

// The radius about the body's origin that the shape fits in.
double bounding_radius(const Collider& shape) {
  const double offset = shape.position.norm();
  if (const auto* s = std::get_if<SphereShape>(&shape.shape)) return offset + s->radius;
  if (const auto* b = std::get_if<BoxShape>(&shape.shape)) return offset + b->half_extents.norm();
  if (const auto* c = std::get_if<CapsuleShape>(&shape.shape)) return offset + c->half_length + c->radius;
  throw ModelError("contact.shape", "a body's shape must be a sphere, a box or a capsule");
}

}  // namespace

namespace {

// n points on the unit sphere, the part with z ≥ z_min (−1: all of it), by the Fibonacci
// lattice: evenly spread, no poles doubled.
void fibonacci(int n, double z_min, const Vector3& centre, double radius, std::vector<Vector3>& out) {
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (1.0 - z_min) * (i + 0.5) / n;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    out.push_back(centre + radius * Vector3(rho * std::cos(golden * i), rho * std::sin(golden * i), z));
  }
}

int divisions(double length, double spacing) { return std::max(1, static_cast<int>(std::ceil(length / spacing))); }

}  // namespace

std::vector<Vector3> surface_samples(const Collider& shape, double spacing, int budget,
                                     const std::string& path) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw ModelError(path + ".sample_spacing", "must be a positive number of metres");
  }
  // Counts first, in doubles (a tiny spacing must fail here, not in an allocation).
  double count = 0.0;
  const double pi = std::numbers::pi;
  if (const auto* s = std::get_if<SphereShape>(&shape.shape)) {
    count = std::ceil(4.0 * pi * s->radius * s->radius / (spacing * spacing));
  } else if (const auto* b = std::get_if<BoxShape>(&shape.shape)) {
    const Vector3 n = 2.0 * b->half_extents / spacing;
    count = 2.0 * ((n.x() + 2) * (n.y() + 2) + (n.y() + 2) * (n.z() + 2) + (n.x() + 2) * (n.z() + 2));
  } else if (const auto* c = std::get_if<CapsuleShape>(&shape.shape)) {
    count = 4.0 * pi * c->radius * c->radius / (spacing * spacing) +
            (2.0 * c->half_length / spacing + 2) * (2.0 * pi * c->radius / spacing + 1);
  } else {
    throw ModelError(path + ".shape", "a body's shape must be a sphere, a box or a capsule");
  }
  if (count > budget) {
    throw ModelError(path + ".sample_spacing", "would give about " + std::to_string(static_cast<long long>(count)) +
                                                   " samples, more than the scene's budget of " + std::to_string(budget));
  }
  std::vector<Vector3> points;
  if (const auto* s = std::get_if<SphereShape>(&shape.shape)) {
    fibonacci(static_cast<int>(count), -1.0, Vector3::Zero(), s->radius, points);
  } else if (const auto* b = std::get_if<BoxShape>(&shape.shape)) {
    // A grid on each face: n_i + 1 coordinates along axis i, the points with at least one
    // coordinate on a face (each once).
    const Vector3& h = b->half_extents;
    const int nx = divisions(2 * h.x(), spacing), ny = divisions(2 * h.y(), spacing), nz = divisions(2 * h.z(), spacing);
    for (int i = 0; i <= nx; ++i) {
      for (int j = 0; j <= ny; ++j) {
        for (int k = 0; k <= nz; ++k) {
          if (i != 0 && i != nx && j != 0 && j != ny && k != 0 && k != nz) continue;
          points.emplace_back(-h.x() + 2 * h.x() * i / nx, -h.y() + 2 * h.y() * j / ny, -h.z() + 2 * h.z() * k / nz);
        }
      }
    }
  } else if (const auto* c = std::get_if<CapsuleShape>(&shape.shape)) {
    // Rings along the side (both ends included), then the two caps beyond them.
    const int rings = divisions(2 * c->half_length, spacing);
    const int around = std::max(3, static_cast<int>(std::ceil(2 * pi * c->radius / spacing)));
    for (int i = 0; i <= rings && c->half_length > 0.0; ++i) {
      const double z = -c->half_length + 2 * c->half_length * i / rings;
      for (int j = 0; j < around; ++j) {
        const double a = 2 * pi * j / around;
        points.emplace_back(c->radius * std::cos(a), c->radius * std::sin(a), z);
      }
    }
    const int cap = std::max(1, static_cast<int>(std::ceil(2 * pi * c->radius * c->radius / (spacing * spacing))));
    const std::size_t first = points.size();
    fibonacci(cap, c->half_length > 0.0 ? 0.0 : -1.0, Vector3(0, 0, c->half_length), c->radius, points);
    if (c->half_length > 0.0) {
      for (std::size_t i = first, n = points.size(); i < n; ++i) {
        const Vector3 p = points[i];
        points.emplace_back(p.x(), -p.y(), -p.z());  // the other cap, turned by π about x
      }
    }
  }
  for (Vector3& p : points) p = shape.position + shape.orientation * p;
  if (const auto* b = std::get_if<BoxShape>(&shape.shape); b != nullptr && b->rounding > 0.0) {
    // The grid is on the outer box; a rounded box's edges and corners lie inside it. Each
    // point goes onto the surface along the SDF's gradient (exact outside: φ is a distance),
    // or a body resting on an edge row would stand on samples that touch nothing.
    for (Vector3& p : points) {
      const SdfValue s = shape.evaluate(p, false);
      p -= s.distance * s.gradient;
    }
  }
  return points;
}

TouchingPairs::TouchingPairs(const Model& model) : pairs_(model.body_pairs()) {
  for (const RigidBody& body : model.bodies) {
    Body b;
    if (body.contact.enabled()) b.samples = body.contact_points;
    b.radius = body.contact.radius;
    b.shape = body.shape;
    double reach = 0.0;
    for (const Vector3& s : b.samples) reach = std::max(reach, s.norm() + b.radius);
    if (b.shape != nullptr) reach = std::max(reach, bounding_radius(*b.shape));
    reach_.push_back(reach);
    bodies_.push_back(std::move(b));
  }
}

double TouchingPairs::overlap(const State& q, int a, int b) const {
  const Body& sampled = bodies_[a];
  const Body& solid = bodies_[b];
  double deepest = -std::numeric_limits<double>::infinity();
  if (solid.shape == nullptr) return deepest;
  const Matrix3& R_a = q.rotations[a];
  const Matrix3& R_b = q.rotations[b];
  for (const Vector3& s : sampled.samples) {
    const Vector3 u = R_b.transpose() * (q.points[a] + R_a * s - q.points[b]);
    deepest = std::max(deepest, sampled.radius - solid.shape->evaluate(u, false).distance);
  }
  return deepest;
}

bool TouchingPairs::near(const State& q, int p, double margin) const {
  const auto [a, b] = pairs_[p];
  if ((q.points[a] - q.points[b]).norm() > reach_[a] + reach_[b] + margin) return false;
  return overlap(q, a, b) > -margin || overlap(q, b, a) > -margin;
}

void TouchingPairs::find(const State& q, const std::vector<double>& margin,
                         std::vector<bool>& touching) const {
  for (std::size_t p = 0; p < pairs_.size(); ++p) touching[p] = touches(q, static_cast<int>(p), margin);
}

TouchingRodsAndBodies::TouchingRodsAndBodies(const Model& model) {
  for (const auto& [r, b] : model.rod_body_pairs()) {
    const RodSpec& rod = model.rods[r];
    Pair p;
    p.body = b;
    for (int i = 0; i < rod.node_count(); ++i) {
      if (std::find(rod.fixed_nodes.begin(), rod.fixed_nodes.end(), i) == rod.fixed_nodes.end()) {
        p.nodes.push_back(model.rod_point(r, i));
      }
    }
    p.radius = rod.contact.radius;
    p.shape = model.bodies[b].shape;
    p.reach = bounding_radius(*p.shape);
    pairs_.push_back(std::move(p));
  }
}

double TouchingRodsAndBodies::overlap(const State& q, std::size_t index, double margin) const {
  const Pair& p = pairs_[index];
  const Vector3& x_b = q.points[p.body];
  const Matrix3& R_b = q.rotations[p.body];
  const double within = p.reach + p.radius + margin;
  double deepest = -std::numeric_limits<double>::infinity();
  for (int node : p.nodes) {
    const Vector3 w = q.points[node] - x_b;
    if (w.squaredNorm() > within * within) continue;
    deepest = std::max(deepest, p.radius - p.shape->evaluate(R_b.transpose() * w, false).distance);
  }
  return deepest;
}

bool TouchingRodsAndBodies::touches(const State& q, const Step& step, const std::vector<double>& body_margin,
                                    std::size_t p) const {
  double moved = 0.0;
  for (int node : pairs_[p].nodes) moved = std::max(moved, step.points.empty() ? 0.0 : step.points[node].norm());
  const double margin = body_margin[pairs_[p].body] + moved;
  return overlap(q, p, margin) > -margin;
}

void TouchingRodsAndBodies::find(const State& q, const Step& step, const std::vector<double>& body_margin,
                                 std::vector<bool>& touching, std::size_t first) const {
  for (std::size_t p = 0; p < pairs_.size(); ++p) touching[first + p] = touches(q, step, body_margin, p);
}

}  // namespace liedyn

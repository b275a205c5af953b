#include "body_contact.hpp"

#include <cmath>
#include <algorithm>
#include <limits>
#include <numbers>
#include <variant>

#include "so3.hpp"

namespace liedyn {

SampledPoint SampledPoint::on_frame(const AttachedPoint& at, const State& q) {
  SampledPoint out;
  out.lever = at.lever(q);
  out.position = at.position(q);
  out.map << Matrix3::Identity(), -so3::hat(out.lever);
  return out;
}

SampledPoint SampledPoint::on_edge(const Vector3& x0, const Vector3& x1, double s) {
  SampledPoint out;
  out.position = (1.0 - s) * x0 + s * x1;
  out.map << (1.0 - s) * Matrix3::Identity(), s * Matrix3::Identity();
  out.lever.setZero();
  return out;
}

namespace {

using Jacobian = Eigen::Matrix<double, 3, 12>;  // of a 3-vector with respect to the four blocks
using MixedBlock = Eigen::Matrix<double, 12, 12>;

// φ_B's value and world-frame derivatives at p; w = p − x_B.
SdfValue field(const Collider& shape, const State& q, int body_b, const Vector3& p, Vector3& w,
               bool with_hessian) {
  const Matrix3& R_b = q.rotations[body_b];
  w = p - q.points[body_b];
  SdfValue s = shape.evaluate(R_b.transpose() * w, with_hessian);  // in B's coordinates
  s.gradient = R_b * s.gradient;
  if (with_hessian) s.hessian = R_b * s.hessian * R_b.transpose();
  return s;
}

// J = [A, −I, hat(w)]: u's motion (times R_B) under the four blocks.
Jacobian field_jacobian(const SampledPoint& p, const Vector3& w) {
  Jacobian J;
  J << p.map, -Matrix3::Identity(), so3::hat(w);
  return J;
}

// The penalty ½ k max(0, ρ − φ)² of a sample of stiffness k, returned; its gradient and
// Hessian (body_contact.hpp) are ADDED to g and H where non-null.
double add_penalty(const SampledPoint& p, const State& q, int body_b, const Collider& shape,
                   double k, double radius, LocalGradient<4>* g, LocalHessian<4>* H) {
  Vector3 w;
  const SdfValue s = field(shape, q, body_b, p.position, w, H != nullptr);
  const double d = radius - s.distance;
  if (!(d > 0.0)) return 0.0;
  if (g != nullptr || H != nullptr) {
    const Vector3 f = -k * d * s.gradient;  // ∂V/∂p
    const Jacobian J = field_jacobian(p, w);
    if (g != nullptr) g->noalias() += J.transpose() * f;
    if (H != nullptr) {
      const Matrix3 K = k * (s.gradient * s.gradient.transpose() - d * s.hessian);
      // Coefficient-based (lazy) product, as in point_pair.hpp: cheaper than Eigen's GEMM here.
      const Eigen::Matrix<double, 12, 3> JtK = J.transpose() * K;
      H->noalias() += JtK.lazyProduct(J);
      H->block<3, 3>(3, 3) += rotated_point_curvature(p.lever, f);
      H->block<3, 3>(9, 9) += rotated_point_curvature(w, f);
      const Eigen::Matrix<double, 3, 9> cross = so3::hat(f) * J.leftCols<9>();  // θ_B × (0, 1, x_B)
      H->block<3, 9>(9, 0) += cross;
      H->block<9, 3>(0, 9) += cross.transpose();
    }
  }
  return 0.5 * k * d * d;
}

// The penalty's residual √k max(0, ρ − φ) and, where `row` is non-null, its derivative
// −√k nᵀ J (0 where there is no contact).
double penalty_residual(const SampledPoint& p, const State& q, int body_b, const Collider& shape,
                        double k, double radius, Eigen::Matrix<double, 1, 12>* row) {
  Vector3 w;
  const SdfValue s = field(shape, q, body_b, p.position, w, false);
  const double d = radius - s.distance;
  if (!(d > 0.0)) {
    if (row != nullptr) row->setZero();
    return 0.0;
  }
  const double root_k = std::sqrt(k);
  if (row != nullptr) *row = (-root_k * s.gradient.transpose()) * field_jacobian(p, w);
  return root_k * d;
}

// The lagged contact of a sample of stiffness k that was at p̂ in `previous`.
LaggedContact lag(const Vector3& previous_position, const State& previous, int body_b,
                  const Collider& shape, double k, double radius) {
  LaggedContact out;
  const Matrix3& R_b = previous.rotations[body_b];
  out.contact_point = R_b.transpose() * (previous_position - previous.points[body_b]);
  const SdfValue s = shape.evaluate(out.contact_point, false);
  out.normal_force = k * std::max(0.0, radius - s.distance);
  const double length = s.gradient.norm();
  out.normal = length > 0.0 ? Vector3(R_b * s.gradient / length) : Vector3::UnitZ();
  return out;
}

// The slip law of a sample at p: d = x_B + R_B û − p (written), r_B = R_B û (written), u = P d.
SmoothedSlip slip(const Vector3& p, const LaggedContact& l, const State& q, int body_b,
                  double epsilon, Vector3& lever_b, Vector3& d) {
  lever_b = q.rotations[body_b] * l.contact_point;
  d = q.points[body_b] + lever_b - p;
  return SmoothedSlip(d - l.normal.dot(d) * l.normal, epsilon);
}

// A sample's friction D = μλ f₀(‖P d‖), returned; its gradient and Hessian are ADDED to g
// and H where non-null.
double add_friction(const SampledPoint& p, const LaggedContact& l, const State& q, int body_b,
                    double coefficient, double epsilon, LocalGradient<4>* g, LocalHessian<4>* H) {
  if (l.normal_force == 0.0) return 0.0;
  Vector3 r_b, d;
  const SmoothedSlip s = slip(p.position, l, q, body_b, epsilon, r_b, d);
  const double scale = coefficient * l.normal_force;  // μλ
  if (g != nullptr || H != nullptr) {
    const Vector3 f = scale * s.phi1 * s.u;  // ∂D/∂d
    Jacobian Jd;                             // ∂d/∂(blocks)
    Jd << -p.map, Matrix3::Identity(), -so3::hat(r_b);
    if (g != nullptr) g->noalias() += Jd.transpose() * f;
    if (H != nullptr) {
      const Matrix3 K = scale * s.curvature(Matrix3::Identity() - l.normal * l.normal.transpose());
      const Eigen::Matrix<double, 12, 3> JtK = Jd.transpose() * K;
      H->noalias() += JtK.lazyProduct(Jd);
      H->block<3, 3>(3, 3) += rotated_point_curvature(p.lever, -f);  // ∂D/∂p = −f
      H->block<3, 3>(9, 9) += rotated_point_curvature(r_b, f);
    }
  }
  return scale * s.f0;
}

// Adds a sample's ∂C/∂q̂ (body_contact.hpp) to `out`: `now` is the sample at q, `before` at
// `previous`, k its stiffness.
void add_friction_previous_jacobian(const SampledPoint& now, const SampledPoint& before,
                                    const LaggedContact& l, const State& q, const State& previous,
                                    int body_b, const Collider& shape, double k, double coefficient,
                                    double epsilon, MixedBlock& out) {
  if (l.normal_force == 0.0) return;
  Vector3 r_b, d;
  const SmoothedSlip s = slip(now.position, l, q, body_b, epsilon, r_b, d);
  const Matrix3& R_b_previous = previous.rotations[body_b];
  const SdfValue lagged = shape.evaluate(l.contact_point, true);
  const double g_norm = lagged.gradient.norm();
  const Vector3 G = R_b_previous * lagged.gradient;  // world
  const Matrix3 N = R_b_previous * lagged.hessian * R_b_previous.transpose();
  const Jacobian J_previous = field_jacobian(before, before.position - previous.points[body_b]);  // Ĵ
  const Jacobian du_contact = R_b_previous.transpose() * J_previous;                              // ∂û/∂q̂
  // λ = k(ρ − φ_B(û)) > 0 here.
  const Eigen::Matrix<double, 1, 12> dlambda = -k * G.transpose() * J_previous;
  const Vector3& n = l.normal;
  const Matrix3 P = Matrix3::Identity() - n * n.transpose();
  Jacobian dn = Jacobian::Zero();
  if (g_norm > 0.0) dn = (P * N / g_norm) * J_previous;
  dn.rightCols<3>() -= so3::hat(n);
  const Jacobian dd = q.rotations[body_b] * du_contact;
  const Jacobian du = P * dd - (n * d.transpose() + n.dot(d) * Matrix3::Identity()) * dn;
  const Jacobian df = coefficient * (s.phi1 * s.u * dlambda + l.normal_force * s.jacobian() * du);
  const Vector3 f = coefficient * l.normal_force * s.phi1 * s.u;
  out.topRows<6>() -= now.map.transpose() * df;
  out.middleRows<3>(6) += df;
  out.middleRows<3>(9) += so3::hat(r_b) * df - so3::hat(f) * dd;
}

// a_previous += Mᵀ z, the four blocks' columns at the whole-state indices `at` (−1: not a
// state entry, a rod node's rotation).
void add_previous(const MixedBlock& M, const LocalGradient<4>& z, const std::array<int, 4>& at,
                  Eigen::VectorXd& a_previous) {
  const LocalGradient<4> w = M.transpose() * z;
  for (int b = 0; b < 4; ++b) {
    if (at[b] >= 0) a_previous.segment<3>(at[b]) += w.segment<3>(3 * b);
  }
}

}  // namespace

double BodyContact::penetration(const State& q) const {
  Vector3 w;
  return radius - field(*shape, q, body_b, at.position(q), w, false).distance;
}

double BodyContact::evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  return add_penalty(SampledPoint::on_frame(at, q), q, body_b, *shape, stiffness, radius, g, H);
}

void BodyContact::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  r(0) = penalty_residual(SampledPoint::on_frame(at, q), q, body_b, *shape, stiffness, radius, J);
}

void BodyFriction::begin_step(const State& previous, const Step&) {
  const LaggedContact l = lag(at.position(previous), previous, body_b, *shape, stiffness, radius);
  contact_point = l.contact_point;
  normal_force = l.normal_force;
  normal = l.normal;
}

double BodyFriction::evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  return add_friction(SampledPoint::on_frame(at, q), lagged(), q, body_b, coefficient, epsilon, g, H);
}

void BodyFriction::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  friction_residual(*this, q, r, J);
}

Eigen::Matrix<double, 12, 12> BodyFriction::previous_jacobian(const State& q, const State& previous) const {
  MixedBlock out = MixedBlock::Zero();
  add_friction_previous_jacobian(SampledPoint::on_frame(at, q), SampledPoint::on_frame(at, previous), lagged(), q,
                                 previous, body_b, *shape, stiffness, coefficient, epsilon, out);
  return out;
}

void BodyFriction::add_step_adjoint(const State& q, const State& previous, const Step&,
                                    const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                                    Eigen::VectorXd&) const {
  if (normal_force == 0.0) return;
  // A rod node has no rotation.
  add_previous(previous_jacobian(q, previous), z,
               {tangent_point(at.point), at.rotation >= 0 ? tangent_rotation(q, at.rotation) : -1,
                tangent_point(body_b), tangent_rotation(q, body_b)},
               a_previous);
}

namespace {

// Calls visit(k, s_k, c_k κ) for every Gauss point of the edge: s_k its place along the edge,
// c_k κ = w_k ℓ̄ κ its stiffness.
template <int N, class Visit>
void for_each_gauss_point(const EdgeBodySample& edge, Visit&& visit) {
  const QuadratureRule& rule = gauss_legendre(N);
  for (int k = 0; k < N; ++k) visit(k, rule.nodes[k], rule.weights[k] * edge.rest_length * edge.stiffness);
}

// The edge's point at s, at q.
SampledPoint edge_point(const EdgeBodySample& edge, const State& q, double s) {
  return SampledPoint::on_edge(q.points[edge.nodes[0]], q.points[edge.nodes[1]], s);
}

}  // namespace

template <int N>
double BasicEdgeBodyContact<N>::penetration(const State& q) const {
  double deepest = -std::numeric_limits<double>::infinity();
  for_each_gauss_point<N>(*this, [&](int, double s, double) {
    Vector3 w;
    deepest = std::max(deepest, radius - field(*shape, q, body_b, edge_point(*this, q, s).position, w, false).distance);
  });
  return deepest;
}

template <int N>
double BasicEdgeBodyContact<N>::evaluate(const State& q, LocalGradient<kBlocks>* g,
                                         LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  double value = 0.0;
  for_each_gauss_point<N>(*this, [&](int, double s, double k) {
    value += add_penalty(edge_point(*this, q, s), q, body_b, *shape, k, radius, g, H);
  });
  return value;
}

template <int N>
void BasicEdgeBodyContact<N>::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  for_each_gauss_point<N>(*this, [&](int k, double s, double stiffness_k) {
    Eigen::Matrix<double, 1, 12> row;
    r(k) = penalty_residual(edge_point(*this, q, s), q, body_b, *shape, stiffness_k, radius,
                            J != nullptr ? &row : nullptr);
    if (J != nullptr) J->row(k) = row;
  });
}

template <int N>
void BasicEdgeBodyFriction<N>::begin_step(const State& previous, const Step&) {
  for_each_gauss_point<N>(*this, [&](int k, double s, double stiffness_k) {
    lagged[k] = lag(edge_point(*this, previous, s).position, previous, body_b, *shape, stiffness_k, radius);
  });
}

template <int N>
double BasicEdgeBodyFriction<N>::evaluate(const State& q, LocalGradient<kBlocks>* g,
                                          LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  double value = 0.0;
  for_each_gauss_point<N>(*this, [&](int k, double s, double) {
    value += add_friction(edge_point(*this, q, s), lagged[k], q, body_b, coefficient, epsilon, g, H);
  });
  return value;
}

template <int N>
void BasicEdgeBodyFriction<N>::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  friction_residual(*this, q, r, J);
}

template <int N>
Eigen::Matrix<double, 12, 12> BasicEdgeBodyFriction<N>::previous_jacobian(const State& q,
                                                                          const State& previous) const {
  MixedBlock out = MixedBlock::Zero();
  for_each_gauss_point<N>(*this, [&](int k, double s, double stiffness_k) {
    add_friction_previous_jacobian(edge_point(*this, q, s), edge_point(*this, previous, s), lagged[k], q, previous,
                                   body_b, *shape, stiffness_k, coefficient, epsilon, out);
  });
  return out;
}

template <int N>
void BasicEdgeBodyFriction<N>::add_step_adjoint(const State& q, const State& previous, const Step&,
                                                const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                                                Eigen::VectorXd&) const {
  if (std::all_of(lagged.begin(), lagged.end(), [](const LaggedContact& l) { return l.normal_force == 0.0; })) return;
  add_previous(previous_jacobian(q, previous), z,
               {tangent_point(nodes[0]), tangent_point(nodes[1]), tangent_point(body_b), tangent_rotation(q, body_b)},
               a_previous);
}

template struct BasicEdgeBodyContact<1>;
template struct BasicEdgeBodyContact<4>;
template struct BasicEdgeBodyContact<8>;
template struct BasicEdgeBodyFriction<4>;

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
  for (std::size_t p = 0; p < pairs_.size(); ++p) {
    touching[p] = near(q, static_cast<int>(p), margin[pairs_[p].first] + margin[pairs_[p].second]);
  }
}

bool TouchingPairs::add_penetrating(const State& q, std::vector<bool>& touching) const {
  bool added = false;
  for (std::size_t p = 0; p < pairs_.size(); ++p) {
    if (!touching[p] && near(q, static_cast<int>(p), 0.0)) touching[p] = added = true;
  }
  return added;
}

TouchingRodsAndBodies::TouchingRodsAndBodies(const Model& model) {
  for (const auto& [r, b] : model.rod_body_pairs()) {
    const RodSpec& rod = model.rods[r];
    std::vector<bool> free(rod.node_count(), true);
    for (int i : rod.fixed_nodes) free[i] = false;
    Pair p;
    p.body = b;
    for (int i = 0; i < rod.node_count(); ++i) {
      if (free[i]) p.nodes.push_back(model.rod_point(r, i));
    }
    for (int e = 0; e < rod.edge_count(); ++e) {
      if (free[e] || free[e + 1]) p.edges.push_back({model.rod_point(r, e), model.rod_point(r, e + 1)});
    }
    for (int i : {0, rod.node_count() - 1}) {
      if (free[i]) p.tips.push_back(model.rod_point(r, i));
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
  const auto sample = [&](const Vector3& x) {
    deepest = std::max(deepest, p.radius - p.shape->evaluate(R_b.transpose() * (x - x_b), false).distance);
  };
  for (int node : p.tips) {
    if ((q.points[node] - x_b).squaredNorm() <= within * within) sample(q.points[node]);
  }
  const QuadratureRule& rule = gauss_legendre(EdgeBodyContact::kQuadraturePoints);
  for (const auto& [a, b] : p.edges) {
    const Vector3& x0 = q.points[a];
    const Vector3& x1 = q.points[b];
    if (point_segment_distance(x_b, x0, x1) > within) continue;
    for (int k = 0; k < rule.size; ++k) sample(SampledPoint::on_edge(x0, x1, rule.nodes[k]).position);
  }
  return deepest;
}

void TouchingRodsAndBodies::find(const State& q, const Step& step, const std::vector<double>& body_margin,
                                 std::vector<bool>& touching, std::size_t first) const {
  for (std::size_t i = 0; i < pairs_.size(); ++i) {
    double moved = 0.0;
    for (int node : pairs_[i].nodes) moved = std::max(moved, step.points.empty() ? 0.0 : step.points[node].norm());
    const double margin = body_margin[pairs_[i].body] + moved;
    touching[first + i] = overlap(q, i, margin) > -margin;
  }
}

bool TouchingRodsAndBodies::add_penetrating(const State& q, std::vector<bool>& touching, std::size_t first) const {
  bool added = false;
  for (std::size_t i = 0; i < pairs_.size(); ++i) {
    if (!touching[first + i] && overlap(q, i, 0.0) > 0.0) touching[first + i] = added = true;
  }
  return added;
}

}  // namespace liedyn

#include "body_contact.hpp"

#include <Eigen/Geometry>  // cross
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <type_traits>
#include <unordered_map>
#include <variant>

#include "mesh_sdf.hpp"
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

// The sample's displacement over the step from the point of B it touched: d = x_B + R_B û − p,
// with r_B = R_B û (written).
Vector3 displacement(const Vector3& p, const LaggedContact& l, const State& q, int body_b, Vector3& lever_b) {
  lever_b = q.rotations[body_b] * l.contact_point;
  return q.points[body_b] + lever_b - p;
}

// ∂d/∂(blocks) = [−A, I, −hat(r_B)].
Jacobian displacement_jacobian(const SampledPoint& p, const Vector3& lever_b) {
  Jacobian Jd;
  Jd << -p.map, Matrix3::Identity(), -so3::hat(lever_b);
  return Jd;
}

// A sample's dissipation D(d) under `law` (k: its stiffness), returned; its gradient and Hessian
// are ADDED to g and H where non-null.
template <class Law>
double add_dissipation(const SampledPoint& p, const LaggedContact& l, const State& q, int body_b, double k,
                       const Law& law, LocalGradient<4>* g, LocalHessian<4>* H) {
  if (l.normal_force == 0.0) return 0.0;
  Vector3 r_b;
  const Vector3 d = displacement(p.position, l, q, body_b, r_b);
  Vector3 f;  // ∂D/∂d
  Matrix3 K;
  const bool derivatives = g != nullptr || H != nullptr;
  const double D = law.evaluate(d, l.normal_force, l.normal, k, derivatives ? &f : nullptr, H != nullptr ? &K : nullptr);
  if (derivatives) {
    const Jacobian Jd = displacement_jacobian(p, r_b);
    if (g != nullptr) g->noalias() += Jd.transpose() * f;
    if (H != nullptr) {
      const Eigen::Matrix<double, 12, 3> JtK = Jd.transpose() * K;
      H->noalias() += JtK.lazyProduct(Jd);
      H->block<3, 3>(3, 3) += rotated_point_curvature(p.lever, -f);  // ∂D/∂p = −f
      H->block<3, 3>(9, 9) += rotated_point_curvature(r_b, f);
    }
  }
  return D;
}

// A dashpot sample's residual √r s (dissipation_law.hpp), its row of ∂r/∂(blocks) written where
// non-null; 0 outside the lagged zone.
double dashpot_residual(const SampledPoint& p, const LaggedContact& l, const State& q, int body_b, double k,
                        const NormalDashpot& law, Eigen::Matrix<double, 1, 12>* row) {
  if (l.normal_force == 0.0) {
    if (row != nullptr) row->setZero();
    return 0.0;
  }
  Vector3 r_b;
  const Vector3 d = displacement(p.position, l, q, body_b, r_b);
  Eigen::RowVector3d dr;  // ∂r/∂d
  const double r = law.residual(d, l.normal, k, dr);
  if (row != nullptr) *row = dr * displacement_jacobian(p, r_b);
  return r;
}

// Adds a sample's ∂C/∂q̂ (body_contact.hpp) to `out`: `now` is the sample at q, `before` at
// `previous`, k its stiffness.
template <class Law>
void add_dissipation_previous_jacobian(const SampledPoint& now, const SampledPoint& before, const LaggedContact& l,
                                       const State& q, const State& previous, int body_b, const Collider& shape,
                                       double k, const Law& law, MixedBlock& out) {
  if (l.normal_force == 0.0) return;
  Vector3 r_b;
  const Vector3 d = displacement(now.position, l, q, body_b, r_b);
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
  const Jacobian df = law.force_jacobian(d, l.normal_force, n, k, dd, dlambda, dn);
  Vector3 f;
  law.evaluate(d, l.normal_force, n, k, &f, nullptr);
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

template <class Law>
void BodyDissipation<Law>::begin_step(const State& previous, const Step&) {
  const LaggedContact l = lag(at.position(previous), previous, body_b, *shape, stiffness, radius);
  contact_point = l.contact_point;
  normal_force = l.normal_force;
  normal = l.normal;
}

template <class Law>
double BodyDissipation<Law>::evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  return add_dissipation(SampledPoint::on_frame(at, q), lagged(), q, body_b, stiffness, static_cast<const Law&>(*this),
                         g, H);
}

template <class Law>
void BodyDissipation<Law>::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  if constexpr (Law::kResidualPerSample) {
    r(0) = dashpot_residual(SampledPoint::on_frame(at, q), lagged(), q, body_b, stiffness, *this, J);
  } else {
    friction_residual(*this, q, r, J);
  }
}

template <class Law>
Eigen::Matrix<double, 12, 12> BodyDissipation<Law>::previous_jacobian(const State& q, const State& previous) const {
  MixedBlock out = MixedBlock::Zero();
  add_dissipation_previous_jacobian(SampledPoint::on_frame(at, q), SampledPoint::on_frame(at, previous), lagged(), q,
                                    previous, body_b, *shape, stiffness, static_cast<const Law&>(*this), out);
  return out;
}

template <class Law>
void BodyDissipation<Law>::add_step_adjoint(const State& q, const State& previous, const Step&,
                                            const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                                            Eigen::VectorXd&) const {
  if (normal_force == 0.0) return;
  // A rod node has no rotation.
  add_previous(previous_jacobian(q, previous), z,
               {tangent_point(at.point), at.rotation >= 0 ? tangent_rotation(q, at.rotation) : -1,
                tangent_point(body_b), tangent_rotation(q, body_b)},
               a_previous);
}

template struct BodyDissipation<SlipFriction>;
template struct BodyDissipation<NormalDashpot>;

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

template <int N, class Law>
void BasicEdgeBodyDissipation<N, Law>::begin_step(const State& previous, const Step&) {
  for_each_gauss_point<N>(*this, [&](int k, double s, double stiffness_k) {
    lagged[k] = lag(edge_point(*this, previous, s).position, previous, body_b, *shape, stiffness_k, radius);
  });
}

template <int N, class Law>
double BasicEdgeBodyDissipation<N, Law>::evaluate(const State& q, LocalGradient<kBlocks>* g,
                                                  LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  double value = 0.0;
  for_each_gauss_point<N>(*this, [&](int k, double s, double stiffness_k) {
    value += add_dissipation(edge_point(*this, q, s), lagged[k], q, body_b, stiffness_k,
                             static_cast<const Law&>(*this), g, H);
  });
  return value;
}

template <int N, class Law>
void BasicEdgeBodyDissipation<N, Law>::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  if constexpr (Law::kResidualPerSample) {
    for_each_gauss_point<N>(*this, [&](int k, double s, double stiffness_k) {
      Eigen::Matrix<double, 1, 12> row;
      r(k) = dashpot_residual(edge_point(*this, q, s), lagged[k], q, body_b, stiffness_k, *this,
                              J != nullptr ? &row : nullptr);
      if (J != nullptr) J->row(k) = row;
    });
  } else {
    friction_residual(*this, q, r, J);
  }
}

template <int N, class Law>
Eigen::Matrix<double, 12, 12> BasicEdgeBodyDissipation<N, Law>::previous_jacobian(const State& q,
                                                                                  const State& previous) const {
  MixedBlock out = MixedBlock::Zero();
  for_each_gauss_point<N>(*this, [&](int k, double s, double stiffness_k) {
    add_dissipation_previous_jacobian(edge_point(*this, q, s), edge_point(*this, previous, s), lagged[k], q, previous,
                                      body_b, *shape, stiffness_k, static_cast<const Law&>(*this), out);
  });
  return out;
}

template <int N, class Law>
void BasicEdgeBodyDissipation<N, Law>::add_step_adjoint(const State& q, const State& previous, const Step&,
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
template struct BasicEdgeBodyDissipation<4, SlipFriction>;
template struct BasicEdgeBodyDissipation<4, NormalDashpot>;

namespace {

// The radius about the body's origin that the shape fits in: every point where φ ≤ 0 is
// within it. +∞ for an unbounded solid, which only a kinematic body may have (lib/sdf.hpp,
// validate_body_shape): a plane's half-space, and any inside-out shape (the complement of a
// bounded set). A tube's solid is within its radius of its polyline, whose segments (each the
// convex hull of its two ends) lie within its farthest point. A mesh's grid interpolant is
// within √3 h of the mesh's true distance (the Lipschitz bound of lib/mesh_sdf.hpp, also
// outside the grid), so φ ≤ 0 only within √3 h of the triangles, which lie within the largest
// vertex norm, or without the triangles (a kinematic body's mesh) within the grid's box.
double bounding_radius(const Collider& shape) {
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  if (shape.inside) return kUnbounded;
  const double offset = shape.position.norm();
  return offset + std::visit(
                      [](const auto& s) -> double {
                        using S = std::decay_t<decltype(s)>;
                        if constexpr (std::is_same_v<S, PlaneShape>) return kUnbounded;
                        if constexpr (std::is_same_v<S, SphereShape>) return s.radius;
                        if constexpr (std::is_same_v<S, BoxShape>) return s.half_extents.norm();
                        if constexpr (std::is_same_v<S, CapsuleShape>)
                          return s.half_length + s.radius;
                        if constexpr (std::is_same_v<S, TubeShape>) {
                          double farthest = 0.0;
                          for (const Vector3& v : s.polyline) farthest = std::max(farthest, v.norm());
                          return farthest + s.radius;
                        }
                        if constexpr (std::is_same_v<S, TorusShape>)
                          return s.major_radius + s.minor_radius;
                        if constexpr (std::is_same_v<S, CylinderShape>) {
                          return Eigen::Vector2d(s.radius, s.half_length).norm();
                        }
                        if constexpr (std::is_same_v<S, LinkShape>) {
                          return s.half_length + s.major_radius + s.minor_radius;
                        }
                        if constexpr (std::is_same_v<S, MeshShape>) {
                          double farthest = 0.0;
                          if (s.mesh != nullptr) {
                            for (const Vector3& v : s.mesh->vertices)
                              farthest = std::max(farthest, v.norm());
                          } else {  // the grid box's farthest corner
                            const Vector3 corner =
                                s.grid->origin().cwiseAbs().cwiseMax(s.grid->max_corner().cwiseAbs());
                            farthest = corner.norm();
                          }
                          return farthest + std::sqrt(3.0) * s.grid->cell_size();
                        }
                      },
                      shape.shape);
}

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

// Points about a circle of the tube (radius r) about the core point c, whose plane is spanned
// by the unit n (⟂ e_z) and e_z: c + r (cos v n + sin v e_z), v = 2π j/around.
void ring(const Vector3& c, const Vector3& n, double r, int around, std::vector<Vector3>& out) {
  for (int j = 0; j < around; ++j) {
    const double v = 2.0 * std::numbers::pi * j / around;
    out.push_back(c + r * (std::cos(v) * n + std::sin(v) * Vector3::UnitZ()));
  }
}

// Rings about the core curve of a link (a torus: L = 0): for each side σ = ±1, the half
// circle about (σL, 0, 0) (arc_rings steps, from the outer equator's length), then the
// straight side at y = σR back to the other arc; each ring ends where the next part starts.
struct LinkRings {
  int arc = 0, straight = 0, around = 0;
  LinkRings(double L, double R, double r, double spacing)
      : arc(std::max(2, static_cast<int>(std::ceil(std::numbers::pi * (R + r) / spacing)))),
        straight(L > 0.0 ? divisions(2.0 * L, spacing) : 0),
        around(std::max(3, static_cast<int>(std::ceil(2.0 * std::numbers::pi * r / spacing)))) {}
};

double link_count(double L, double R, double r, double spacing) {
  const double pi = std::numbers::pi;
  return 2.0 *
         (std::ceil(pi * (R + r) / spacing) + 2.0 + (L > 0.0 ? 2.0 * L / spacing + 1.0 : 0.0)) *
         (2.0 * pi * r / spacing + 3.0);
}

void link_samples(double L, double R, double r, double spacing, std::vector<Vector3>& out) {
  const LinkRings n(L, R, r, spacing);
  const double pi = std::numbers::pi;
  for (const double side : {1.0, -1.0}) {
    for (int k = 0; k < n.arc; ++k) {
      const double theta = -pi / 2 + (side < 0.0 ? pi : 0.0) + pi * k / n.arc;
      const Vector3 normal(std::cos(theta), std::sin(theta), 0.0);
      ring(Vector3(side * L, 0, 0) + R * normal, normal, r, n.around, out);
    }
    for (int k = 0; k < n.straight; ++k) {
      ring(Vector3(side * (L - 2.0 * L * k / n.straight), side * R, 0.0), side * Vector3::UnitY(),
           r, n.around, out);
    }
  }
}

// A cylinder: rings along the side (both rims included), then on each cap its centre and
// concentric rings inside the rim.
double cylinder_count(double radius, double h, double spacing) {
  const double pi = std::numbers::pi;
  const double rings = std::ceil(radius / spacing);  // on a cap, the rim's included
  return (2.0 * h / spacing + 2.0) * (2.0 * pi * radius / spacing + 3.0) +
         2.0 * (1.0 + (rings - 1.0) * (pi * radius / spacing + 3.0));
}

void cylinder_samples(double radius, double h, double spacing, std::vector<Vector3>& out) {
  const double pi = std::numbers::pi;
  const int rings = divisions(2.0 * h, spacing);
  const int around = std::max(3, static_cast<int>(std::ceil(2.0 * pi * radius / spacing)));
  for (int i = 0; i <= rings; ++i) {
    const double z = -h + 2.0 * h * i / rings;
    for (int j = 0; j < around; ++j) {
      const double a = 2.0 * pi * j / around;
      out.emplace_back(radius * std::cos(a), radius * std::sin(a), z);
    }
  }
  const int circles = divisions(radius, spacing);
  for (const double z : {h, -h}) {
    out.emplace_back(0.0, 0.0, z);
    for (int k = 1; k < circles; ++k) {
      const double rho = radius * k / circles;
      const int count = std::max(3, static_cast<int>(std::ceil(2.0 * pi * rho / spacing)));
      for (int j = 0; j < count; ++j) {
        const double a = 2.0 * pi * j / count;
        out.emplace_back(rho * std::cos(a), rho * std::sin(a), z);
      }
    }
  }
}

// A mesh: greedy thinning of dense candidates (below), a candidate kept unless a kept sample
// is within kMeshSampleGap × spacing of it. Candidates δ = spacing/4 apart, in this order: the
// vertices, the points dividing each edge into ⌈len/δ⌉ equal parts, and on each triangle
// (a, b, c) the inner points (i a + j b + k c)/m, i, j, k ≥ 1, i + j + k = m = ⌈longest
// edge/δ⌉. Every point of a triangle lies in a sub-triangle of sides ≤ δ, within δ/√3 of one
// of its corners, which is a candidate or on an edge within δ/2 of one: within 1.08 δ = 0.27
// spacing of a candidate, so within (kMeshSampleGap + 0.27) spacing < spacing of a sample.
// The samples are ≥ kMeshSampleGap × spacing apart; the vertices (corners) come first.
constexpr double kMeshSampleGap = 0.7;

double mesh_area(const TriangleMesh& mesh) {
  double area = 0.0;
  for (const std::array<int, 3>& t : mesh.triangles) {
    const Vector3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    area += 0.5 * (mesh.vertices[static_cast<std::size_t>(t[1])] - a)
                      .cross(mesh.vertices[static_cast<std::size_t>(t[2])] - a)
                      .norm();
  }
  return area;
}

class Thinning {
 public:
  Thinning(double gap, int budget, std::vector<Vector3>& out)
      : gap_(gap), budget_(budget), out_(out) {}
  // Keeps p unless a kept sample is within the gap; false once more than the budget is kept.
  bool offer(const Vector3& p) {
    const Eigen::Array3d cell = (p / gap_).array().floor();
    const Key key{static_cast<long long>(cell.x()), static_cast<long long>(cell.y()),
                  static_cast<long long>(cell.z())};
    for (long long i = -1; i <= 1; ++i) {
      for (long long j = -1; j <= 1; ++j) {
        for (long long k = -1; k <= 1; ++k) {
          const auto found = cells_.find(Key{key[0] + i, key[1] + j, key[2] + k});
          if (found == cells_.end()) continue;
          for (const std::size_t s : found->second) {
            if ((out_[s] - p).squaredNorm() < gap_ * gap_) return true;
          }
        }
      }
    }
    cells_[key].push_back(out_.size());
    out_.push_back(p);
    return static_cast<long long>(out_.size()) <= budget_;
  }

 private:
  using Key = std::array<long long, 3>;
  struct Hash {
    std::size_t operator()(const Key& k) const {
      return std::hash<long long>()(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
    }
  };
  double gap_;
  int budget_;
  std::vector<Vector3>& out_;
  std::unordered_map<Key, std::vector<std::size_t>, Hash> cells_;
};

// false once the budget is passed.
bool mesh_samples(const TriangleMesh& mesh, double spacing, int budget, std::vector<Vector3>& out) {
  const double delta = spacing / 4.0;
  Thinning thin(kMeshSampleGap * spacing, budget, out);
  const auto point = [&mesh](int i) -> const Vector3& {
    return mesh.vertices[static_cast<std::size_t>(i)];
  };
  for (const Vector3& v : mesh.vertices) {
    if (!thin.offer(v)) return false;
  }
  // Each edge once: closed and consistently oriented, the mesh runs along it once each way.
  for (const std::array<int, 3>& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int from = t[static_cast<std::size_t>(k)],
                to = t[static_cast<std::size_t>((k + 1) % 3)];
      if (from > to) continue;
      const Vector3 &a = point(from), &b = point(to);
      const int m = divisions((b - a).norm(), delta);
      for (int i = 1; i < m; ++i) {
        if (!thin.offer(a + (static_cast<double>(i) / m) * (b - a))) return false;
      }
    }
  }
  for (const std::array<int, 3>& t : mesh.triangles) {
    const Vector3 &a = point(t[0]), &b = point(t[1]), &c = point(t[2]);
    const int m = divisions(std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()}), delta);
    for (int i = 1; i < m; ++i) {
      for (int j = 1; i + j < m; ++j) {
        if (!thin.offer((i * a + j * b + (m - i - j) * c) / m)) return false;
      }
    }
  }
  return true;
}

}  // namespace

std::vector<Vector3> surface_samples(const Collider& shape, double spacing, int budget,
                                     const std::string& path) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw ModelError(path + ".sample_spacing", "must be a positive number of metres");
  }
  validate_body_shape(shape, path + ".shape");
  // Counts first, in doubles (a tiny spacing must fail here, not in an allocation).
  const auto too_many = [&](double count) {
    return ModelError(path + ".sample_spacing",
                      "would give about " + std::to_string(static_cast<long long>(count)) +
                          " samples, more than the scene's budget of " + std::to_string(budget));
  };
  const auto check = [&](double count) {
    if (count > budget) throw too_many(count);
  };
  const double pi = std::numbers::pi;
  std::vector<Vector3> points;
  std::visit(
      [&](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, SphereShape>) {
          const double count = std::ceil(4.0 * pi * s.radius * s.radius / (spacing * spacing));
          check(count);
          fibonacci(static_cast<int>(count), -1.0, Vector3::Zero(), s.radius, points);
        }
        if constexpr (std::is_same_v<S, BoxShape>) {
          const Vector3 n = 2.0 * s.half_extents / spacing;
          check(2.0 * ((n.x() + 2) * (n.y() + 2) + (n.y() + 2) * (n.z() + 2) +
                       (n.x() + 2) * (n.z() + 2)));
          // A grid on each face: n_i + 1 coordinates along axis i, the points with at least one
          // coordinate on a face (each once).
          const Vector3& h = s.half_extents;
          const int nx = divisions(2 * h.x(), spacing), ny = divisions(2 * h.y(), spacing),
                    nz = divisions(2 * h.z(), spacing);
          for (int i = 0; i <= nx; ++i) {
            for (int j = 0; j <= ny; ++j) {
              for (int k = 0; k <= nz; ++k) {
                if (i != 0 && i != nx && j != 0 && j != ny && k != 0 && k != nz) continue;
                points.emplace_back(-h.x() + 2 * h.x() * i / nx, -h.y() + 2 * h.y() * j / ny,
                                    -h.z() + 2 * h.z() * k / nz);
              }
            }
          }
        }
        if constexpr (std::is_same_v<S, CapsuleShape>) {
          check(4.0 * pi * s.radius * s.radius / (spacing * spacing) +
                (2.0 * s.half_length / spacing + 2) * (2.0 * pi * s.radius / spacing + 1));
          // Rings along the side (both ends included), then the two caps beyond them.
          const int rings = divisions(2 * s.half_length, spacing);
          const int around = std::max(3, static_cast<int>(std::ceil(2 * pi * s.radius / spacing)));
          for (int i = 0; i <= rings && s.half_length > 0.0; ++i) {
            const double z = -s.half_length + 2 * s.half_length * i / rings;
            for (int j = 0; j < around; ++j) {
              const double a = 2 * pi * j / around;
              points.emplace_back(s.radius * std::cos(a), s.radius * std::sin(a), z);
            }
          }
          // A hemisphere's worth of points per cap; a capsule of zero length is one whole sphere.
          const double cap_area = (s.half_length > 0.0 ? 2.0 : 4.0) * pi * s.radius * s.radius;
          const int cap = std::max(1, static_cast<int>(std::ceil(cap_area / (spacing * spacing))));
          const std::size_t first = points.size();
          fibonacci(cap, s.half_length > 0.0 ? 0.0 : -1.0, Vector3(0, 0, s.half_length), s.radius,
                    points);
          if (s.half_length > 0.0) {
            for (std::size_t i = first, n = points.size(); i < n; ++i) {
              const Vector3 p = points[i];
              points.emplace_back(p.x(), -p.y(), -p.z());  // the other cap, turned by π about x
            }
          }
        }
        if constexpr (std::is_same_v<S, TorusShape>) {
          check(link_count(0.0, s.major_radius, s.minor_radius, spacing));
          link_samples(0.0, s.major_radius, s.minor_radius, spacing, points);
        }
        if constexpr (std::is_same_v<S, LinkShape>) {
          check(link_count(s.half_length, s.major_radius, s.minor_radius, spacing));
          link_samples(s.half_length, s.major_radius, s.minor_radius, spacing, points);
        }
        if constexpr (std::is_same_v<S, CylinderShape>) {
          check(cylinder_count(s.radius, s.half_length, spacing));
          cylinder_samples(s.radius, s.half_length, spacing, points);
        }
        if constexpr (std::is_same_v<S, MeshShape>) {
          // About one sample per (gap × spacing)² of area; the thinning stops past the budget.
          check(mesh_area(*s.mesh) / std::pow(kMeshSampleGap * spacing, 2));
          if (!mesh_samples(*s.mesh, spacing, budget, points))
            throw too_many(static_cast<double>(points.size()));
        }
        // Plane and tube: not body shapes, refused by validate_body_shape above.
      },
      shape.shape);
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

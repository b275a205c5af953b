#include "sdf.hpp"

#include <Eigen/Geometry>  // cross
#include <Eigen/LU>        // determinant
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "mesh_sdf.hpp"
#include "model.hpp"

namespace liedyn {
namespace {

// All shapes fill an SdfValue in the collider frame; Collider::evaluate maps it to the world.

// ∇²φ of a point core, (I − u uᵀ)/d.
Matrix3 sphere_hessian(const Vector3& u, double d) {
  return (Matrix3::Identity() - u * u.transpose()) / d;
}

// ∇²φ of a line core with unit direction e, (I − e eᵀ − u uᵀ)/d (u ⟂ e).
Matrix3 cylinder_hessian(const Vector3& e, const Vector3& u, double d) {
  return (Matrix3::Identity() - e * e.transpose() - u * u.transpose()) / d;
}

// The unit vector of the coordinate axis least aligned with the unit vector e (lowest index
// on ties), made perpendicular to e: the documented gradient on a segment (d = 0).
Vector3 perpendicular_to(const Vector3& e) {
  Eigen::Index k = 0;
  e.cwiseAbs().minCoeff(&k);  // Eigen returns the first minimum
  Vector3 a = Vector3::Unit(k);
  a -= a.dot(e) * e;  // |e_k| ≤ 1/√3, so ‖a‖ ≥ √(2/3)
  return a.normalized();
}

// φ = z, ∇φ = e_z, ∇²φ = 0.
void plane_sdf(const Vector3& x, SdfValue& out) {
  out.distance = x.z();
  out.gradient = Vector3::UnitZ();
}

// φ = ‖x‖ − ρ, ∇φ = u = x/‖x‖, ∇²φ = (I − u uᵀ)/‖x‖; at the centre ∇φ = e_z, ∇²φ = 0.
void sphere_sdf(const SphereShape& s, const Vector3& x, bool with_hessian, SdfValue& out) {
  const double d = x.norm();
  out.distance = d - s.radius;
  if (d <= kCoreDistance) {  // the centre: conical kink (header, "Non-smooth points")
    out.gradient = Vector3::UnitZ();
    return;
  }
  out.gradient = x / d;
  if (with_hessian) out.hessian = sphere_hessian(out.gradient, d);
}

// Rounded box (header): b = half_extents − rounding, q = |x| − b.
void box_sdf(const BoxShape& s, const Vector3& x, bool with_hessian, SdfValue& out) {
  const Vector3 b = s.half_extents - Vector3::Constant(s.rounding);
  const Vector3 q = x.cwiseAbs() - b;
  // w = x − clamp(x, −b, b): sign(x_i) q_i on the active set {q_i > 0} (where |x_i| > b_i > 0,
  // so the sign is defined), 0 elsewhere. A tie q_i = 0 is inactive (face rather than edge).
  Vector3 w = Vector3::Zero();
  Matrix3 active = Matrix3::Zero();  // P_A
  for (int i = 0; i < 3; ++i) {
    if (q(i) > 0.0) {
      w(i) = std::copysign(q(i), x(i));
      active(i, i) = 1.0;
    }
  }
  const double d = w.norm();
  if (d > kCoreDistance) {  // outside the inner box: distance to it, minus the rounding
    out.distance = d - s.rounding;
    out.gradient = w / d;  // on a face exactly ±e_i (d = |w_i|), so ∇²φ = 0 exactly there
    if (with_hessian) out.hessian = (active - out.gradient * out.gradient.transpose()) / d;
    return;
  }
  // Inside the inner box (or within kCoreDistance of it): φ = max_i q_i − rounding, exact for
  // a convex core. maxCoeff picks the lowest index on ties; sign(0) = +1.
  Eigen::Index k = 0;
  const double q_max = q.maxCoeff(&k);
  out.distance = q_max - s.rounding;
  out.gradient = Vector3::Zero();
  out.gradient(k) = std::signbit(x(k)) ? -1.0 : 1.0;
}

// Capsule: c = (0, 0, clamp(z, −L, L)), w = x − c (header).
void capsule_sdf(const CapsuleShape& s, const Vector3& x, bool with_hessian, SdfValue& out) {
  const double L = s.half_length;
  const bool side = -L < x.z() && x.z() < L;  // |z| = L counts as a cap (sphere)
  const Vector3 w(x.x(), x.y(), x.z() - std::clamp(x.z(), -L, L));  // w_z = 0 on the side
  const double d = w.norm();
  out.distance = d - s.radius;
  if (d <= kCoreDistance) {  // on the segment: perpendicular_to(e_z) = e_x
    out.gradient = Vector3::UnitX();
    return;
  }
  out.gradient = w / d;
  if (with_hessian) {
    out.hessian = side ? cylinder_hessian(Vector3::UnitZ(), out.gradient, d)
                       : sphere_hessian(out.gradient, d);
  }
}

// Tube: brute force over the segments for the nearest point (first segment on ties).
void tube_sdf(const TubeShape& s, const Vector3& x, bool with_hessian, SdfValue& out) {
  const std::vector<Vector3>& v = s.polyline;
  double best_d2 = std::numeric_limits<double>::infinity();
  std::size_t best = 0;
  Vector3 best_c = v.front();
  bool best_interior = false;
  for (std::size_t j = 0; j + 1 < v.size(); ++j) {
    const Vector3 ab = v[j + 1] - v[j];
    const double t = (x - v[j]).dot(ab);  // projection parameter × ‖ab‖²
    const double l2 = ab.squaredNorm();   // > 0 (validate)
    // Clamped ends are the vertices themselves (not v_j + 1·ab, which may round elsewhere):
    // both segments at a joint then give the same point, distance and derivatives.
    const bool interior = t > 0.0 && t < l2;
    const Vector3 c = t <= 0.0 ? v[j] : (t >= l2 ? v[j + 1] : Vector3(v[j] + (t / l2) * ab));
    const double d2 = (x - c).squaredNorm();
    if (d2 < best_d2) {  // strict: ties keep the first segment
      best_d2 = d2;
      best = j;
      best_c = c;
      best_interior = interior;
    }
  }
  const Vector3 w = x - best_c;
  const double d = w.norm();
  out.distance = d - s.radius;
  if (d <= kCoreDistance) {  // on the polyline
    out.gradient = perpendicular_to((v[best + 1] - v[best]).normalized());
    return;
  }
  out.gradient = w / d;
  if (with_hessian) {
    out.hessian = best_interior
                      ? cylinder_hessian((v[best + 1] - v[best]).normalized(), out.gradient, d)
                      : sphere_hessian(out.gradient, d);
  }
}

// The planar offset of x from the segment S = [−L, L] × {0} × {0} (header, "Link"):
// s = ‖w‖, w = (x − clamp(x, −L, L), y, 0), its unit gradient n = w/s (e_y for s ≤
// kCoreDistance, header "Non-smooth points"), and whether S's nearest point is an end
// (|x| ≥ L, where ∇²s = τ τᵀ/s; beside the interior ∇²s = 0). L = 0: the distance from the z
// axis.
struct PlanarOffset {
  double s = 0.0;
  Vector3 n = Vector3::UnitY();
  bool arc = true;
};

PlanarOffset planar_offset(double L, const Vector3& x) {
  PlanarOffset o;
  const Vector3 w(x.x() - std::clamp(x.x(), -L, L), x.y(), 0.0);
  o.s = w.norm();
  if (o.s > kCoreDistance) o.n = w / o.s;
  o.arc = !(-L < x.x() && x.x() < L);  // |x| = L counts as an arc (header)
  return o;
}

// The distance D from x to the stadium curve at distance R from S (L = 0: the circle of
// radius R about the z axis), its gradient and Hessian (header, "Link").
void stadium_distance(double L, double R, const Vector3& x, bool with_hessian, SdfValue& out) {
  const PlanarOffset o = planar_offset(L, x);
  const double a = o.s - R;
  const double D = Eigen::Vector2d(a, x.z()).norm();
  out.distance = D;
  if (D <= kCoreDistance) {  // on the curve: conical kink, the outward planar normal
    out.gradient = o.n;
    return;
  }
  out.gradient = (a * o.n + x.z() * Vector3::UnitZ()) / D;
  if (with_hessian) {
    const Vector3 tau = Vector3::UnitZ().cross(o.n);
    out.hessian = cylinder_hessian(tau, out.gradient, D);
    // About an end of S (and not on the torus's axis, where the term is dropped): a ∇²s / D.
    if (o.arc && o.s > kCoreDistance) out.hessian += (a / (o.s * D)) * tau * tau.transpose();
  }
}

// Link (torus: L = 0): φ = D − r.
void link_sdf(double L, double R, double r, const Vector3& x, bool with_hessian, SdfValue& out) {
  stadium_distance(L, R, x, with_hessian, out);
  out.distance -= r;
}

// Cylinder: the rectangle q = (s − ρ, |z| − h) of the (s, z) half-plane (header).
void cylinder_sdf(const CylinderShape& c, const Vector3& x, bool with_hessian, SdfValue& out) {
  const PlanarOffset o = planar_offset(0.0, x);
  const double q1 = o.s - c.radius, q2 = std::abs(x.z()) - c.half_length;
  const double sign_z = std::signbit(x.z()) ? -1.0 : 1.0;
  if (q1 > 0.0 && q2 > 0.0) {  // beyond the rim: the torus of minor radius 0 at the rim
    stadium_distance(0.0, c.radius, x - sign_z * c.half_length * Vector3::UnitZ(), with_hessian,
                     out);
    return;
  }
  if (q1 >= q2) {  // the side (ties inside: the side)
    out.distance = q1;
    out.gradient = o.n;
    if (with_hessian && o.s > kCoreDistance) {
      out.hessian = cylinder_hessian(Vector3::UnitZ(), o.n, o.s);
    }
    return;
  }
  out.distance = q2;  // a cap
  out.gradient = sign_z * Vector3::UnitZ();
}

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

void require_positive(double v, const std::string& field) {
  if (!std::isfinite(v) || !(v > 0.0)) {
    throw ModelError(field, "must be a finite positive number of metres (found " + number(v) + ")");
  }
}

void require_non_negative(double v, const std::string& field) {
  if (!std::isfinite(v) || !(v >= 0.0)) {
    throw ModelError(field, "must be finite and ≥ 0 (found " + number(v) + ")");
  }
}

// A torus or link: 0 < minor < major (the tube may not reach the axis or the segment: the
// SDF would no longer be a distance inside, header).
void require_radii(double major, double minor, const std::string& path) {
  require_positive(major, path + ".major_radius");
  require_positive(minor, path + ".minor_radius");
  if (!(minor < major)) {
    throw ModelError(path + ".minor_radius", "must be below major_radius " + number(major) +
                                                 " (found " + number(minor) + ")");
  }
}

}  // namespace

SdfValue Collider::evaluate(const Vector3& p, bool with_hessian) const {
  const Vector3 x = orientation.transpose() * (p - position);  // x = Rᵀ(p − o)
  SdfValue local;
  std::visit(
      [&](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, PlaneShape>) plane_sdf(x, local);
        if constexpr (std::is_same_v<S, SphereShape>) sphere_sdf(s, x, with_hessian, local);
        if constexpr (std::is_same_v<S, BoxShape>) box_sdf(s, x, with_hessian, local);
        if constexpr (std::is_same_v<S, CapsuleShape>) capsule_sdf(s, x, with_hessian, local);
        if constexpr (std::is_same_v<S, TubeShape>) tube_sdf(s, x, with_hessian, local);
        if constexpr (std::is_same_v<S, TorusShape>) {
          link_sdf(0.0, s.major_radius, s.minor_radius, x, with_hessian, local);
        }
        if constexpr (std::is_same_v<S, CylinderShape>) cylinder_sdf(s, x, with_hessian, local);
        if constexpr (std::is_same_v<S, LinkShape>) {
          link_sdf(s.half_length, s.major_radius, s.minor_radius, x, with_hessian, local);
        }
        if constexpr (std::is_same_v<S, MeshShape>) local = s.grid->evaluate(x, with_hessian);
      },
      shape);
  const double sign = inside ? -1.0 : 1.0;  // inside: φ → −φ (and so its derivatives)
  SdfValue out;
  out.distance = sign * local.distance;
  out.gradient = sign * (orientation * local.gradient);  // ∇φ = R ∇φ_loc
  if (with_hessian) {
    // ∇²φ = R ∇²φ_loc Rᵀ, symmetrised: the product is symmetric only up to round-off.
    const Matrix3 H = orientation * local.hessian * orientation.transpose();
    out.hessian = (0.5 * sign) * (H + H.transpose());
  }
  return out;
}

void Collider::validate(const std::string& path) const {
  const auto field = [&path](const std::string& member) { return path + "." + member; };
  require_finite(position, field("position"));
  require_finite(orientation, field("orientation"));
  const double drift = (orientation.transpose() * orientation - Matrix3::Identity()).norm();
  if (drift > 1e-9 || orientation.determinant() <= 0.0) {
    throw ModelError(field("orientation"),
                     "must be a rotation matrix (‖RᵀR − I‖ = " + number(drift) +
                         ", det R = " + number(orientation.determinant()) + ")");
  }
  std::visit(
      [&](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, SphereShape>) require_positive(s.radius, field("radius"));
        if constexpr (std::is_same_v<S, BoxShape>) {
          require_finite(s.half_extents, field("half_extents"));
          if (!(s.half_extents.minCoeff() > 0.0)) {
            throw ModelError(field("half_extents"), "must all be positive");
          }
          const double limit = s.half_extents.minCoeff();
          if (!std::isfinite(s.rounding) || !(s.rounding >= 0.0) || !(s.rounding < limit)) {
            throw ModelError(field("rounding"),
                             "must be finite, ≥ 0 and below the smallest half "
                             "extent " +
                                 number(limit) + " (found " + number(s.rounding) + ")");
          }
        }
        if constexpr (std::is_same_v<S, CapsuleShape>) {
          require_non_negative(s.half_length, field("half_length"));
          require_positive(s.radius, field("radius"));
        }
        if constexpr (std::is_same_v<S, TorusShape>)
          require_radii(s.major_radius, s.minor_radius, path);
        if constexpr (std::is_same_v<S, CylinderShape>) {
          require_positive(s.radius, field("radius"));
          require_positive(s.half_length, field("half_length"));
        }
        if constexpr (std::is_same_v<S, LinkShape>) {
          require_non_negative(s.half_length, field("half_length"));
          require_radii(s.major_radius, s.minor_radius, path);
        }
        if constexpr (std::is_same_v<S, TubeShape>) {
          if (s.polyline.size() < 2) {
            throw ModelError(field("polyline"), "must have at least 2 points (found " +
                                                    std::to_string(s.polyline.size()) + ")");
          }
          for (std::size_t j = 0; j < s.polyline.size(); ++j) {
            const std::string point = field("polyline[" + std::to_string(j) + "]");
            require_finite(s.polyline[j], point);
            if (j == 0) continue;
            // The nearest-point search divides by the squared segment length.
            const double l2 = (s.polyline[j] - s.polyline[j - 1]).squaredNorm();
            if (!(l2 > 0.0)) {
              throw ModelError(point,
                               "repeats the previous point: segments must have a "
                               "positive length");
            }
            if (!std::isfinite(l2)) {
              throw ModelError(point,
                               "is too far from the previous point (the squared segment "
                               "length overflows)");
            }
          }
          require_positive(s.radius, field("radius"));
        }
        if constexpr (std::is_same_v<S, MeshShape>) {
          if (s.grid == nullptr) throw ModelError(field("file"), "no grid was built from the mesh");
        }
      },
      shape);
}

void validate_body_shape(const Collider& shape, const std::string& path) {
  const bool body = std::visit(
      [](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, MeshShape>) return s.mesh != nullptr;
        return !std::is_same_v<S, PlaneShape> && !std::is_same_v<S, TubeShape>;
      },
      shape.shape);
  // Where an unbounded or unsampled solid belongs instead: a moving collider.
  const std::string moving = " (a moving plane, tube or inside-out shape is a collider with a \"kinematic\" block)";
  if (!body) {
    throw ModelError(path + ".type",
                     "a body's shape must be a sphere, box, capsule, torus, cylinder, link or mesh" + moving);
  }
  if (shape.inside) throw ModelError(path + ".inside", "a body's shape is a solid, not its complement" + moving);
}

std::vector<Vector3> catmull_rom_polyline(const std::vector<Vector3>& control_points,
                                          int samples_per_segment) {
  const std::size_t n = control_points.size();
  if (n < 2) {
    throw std::invalid_argument("catmull_rom_polyline: needs at least 2 control points (found " +
                                std::to_string(n) + ")");
  }
  if (samples_per_segment < 1) {
    throw std::invalid_argument("catmull_rom_polyline: samples_per_segment must be ≥ 1 (found " +
                                std::to_string(samples_per_segment) + ")");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!control_points[i].allFinite()) {
      throw std::invalid_argument("catmull_rom_polyline: control_points[" + std::to_string(i) +
                                  "] is not finite");
    }
    if (i > 0 && control_points[i] == control_points[i - 1]) {
      throw std::invalid_argument("catmull_rom_polyline: control_points[" + std::to_string(i) +
                                  "] repeats the previous point");
    }
  }
  // Control point i, with the reflected phantoms P_{−1} = 2P_0 − P_1, P_n = 2P_{n−1} − P_{n−2}.
  const auto point = [&](std::ptrdiff_t i) -> Vector3 {
    const auto m = static_cast<std::ptrdiff_t>(n);
    if (i < 0) return 2.0 * control_points[0] - control_points[1];
    if (i >= m) return 2.0 * control_points[n - 1] - control_points[n - 2];
    return control_points[static_cast<std::size_t>(i)];
  };
  std::vector<Vector3> out;
  out.reserve((n - 1) * static_cast<std::size_t>(samples_per_segment) + 1);
  for (std::size_t span = 0; span + 1 < n; ++span) {
    const auto i = static_cast<std::ptrdiff_t>(span);
    const Vector3 P0 = point(i - 1), P1 = point(i), P2 = point(i + 1), P3 = point(i + 2);
    // Centripetal knots: t_{k+1} = t_k + ‖P_{k+1} − P_k‖^½ (all spacings > 0: distinct points).
    const double t0 = 0.0;
    const double t1 = t0 + std::sqrt((P1 - P0).norm());
    const double t2 = t1 + std::sqrt((P2 - P1).norm());
    const double t3 = t2 + std::sqrt((P3 - P2).norm());
    out.push_back(P1);  // exact, not the (rounded) value of the formula at t = t1
    for (int k = 1; k < samples_per_segment; ++k) {
      const double t = t1 + (t2 - t1) * k / samples_per_segment;
      // Barry–Goldman pyramid of linear interpolations.
      const Vector3 A1 = ((t1 - t) * P0 + (t - t0) * P1) / (t1 - t0);
      const Vector3 A2 = ((t2 - t) * P1 + (t - t1) * P2) / (t2 - t1);
      const Vector3 A3 = ((t3 - t) * P2 + (t - t2) * P3) / (t3 - t2);
      const Vector3 B1 = ((t2 - t) * A1 + (t - t0) * A2) / (t2 - t0);
      const Vector3 B2 = ((t3 - t) * A2 + (t - t1) * A3) / (t3 - t1);
      out.push_back(((t2 - t) * B1 + (t - t1) * B2) / (t2 - t1));
    }
  }
  out.push_back(control_points.back());
  return out;
}

}  // namespace liedyn

#pragma once
// Signed distance fields φ of static colliders, with world-frame gradient and Hessian, for
// penalty contact V = ½ k max(0, ρ − φ(p))² (lib/contact.hpp).
//
// φ(p) is the signed Euclidean distance from p to the collider's surface, > 0 outside the
// solid, < 0 inside. Wherever φ is differentiable |∇φ| = 1, and ∇²φ = ∂²φ/∂p² is symmetric
// with ∇²φ ∇φ = 0. Every shape below is the exact SDF (not a bound), written in the collider
// frame ("local", x = p_local); Collider::evaluate maps it to the world:
//   x = Rᵀ(p − o),   φ(p) = φ_loc(x),   ∇φ = R ∇φ_loc,   ∇²φ = R ∇²φ_loc Rᵀ,
// (R = orientation, collider → world; o = position). R is used as given: validate() accepts
// ‖RᵀR − I‖ ≤ 1e-9, and |∇φ| = 1 holds to that accuracy.
// `inside` negates φ, ∇φ and ∇²φ: the solid becomes the complement of the shape (a bowl from
// a sphere, the lumen of a tube).
//
// Shapes (local frame; u = unit vector from the nearest point of a core set to x):
//   Plane    φ = z,  ∇φ = e_z,  ∇²φ = 0             (world: φ = n·(p − o), n = R e_z).
//   Sphere   φ = ‖x‖ − ρ,  ∇φ = u = x/‖x‖,  ∇²φ = (I − u uᵀ)/‖x‖.
//   Box      b = half_extents − rounding (the inner box; the solid is it inflated by
//            `rounding`, so the outer size stays half_extents), q = |x| − b (componentwise):
//              φ = ‖max(q, 0)‖ + min(max_i q_i, 0) − rounding           (Inigo Quilez).
//            Outside the inner box (some q_i > 0), with the active set A = {i : q_i > 0},
//            w = x − clamp(x, −b, b) (w_i = sign(x_i) q_i on A, 0 elsewhere), d = ‖w‖:
//              φ = d − rounding,  ∇φ = u = w/d,  ∇²φ = (P_A − u uᵀ)/d,  P_A = Σ_{i∈A} e_i e_iᵀ,
//            i.e. |A| = 1 (near a face): ∇²φ = 0 exactly; |A| = 2 (near an edge): a cylinder
//            about the edge; |A| = 3 (near a corner): a sphere about the corner.
//            Inside the inner box (all q_i ≤ 0), k = argmax_i q_i:
//              φ = q_k − rounding,  ∇φ = sign(x_k) e_k,  ∇²φ = 0.
//   Capsule  segment from −L e_z to +L e_z (L = half_length), c = (0, 0, clamp(z, −L, L)),
//            w = x − c, d = ‖w‖, u = w/d:  φ = d − ρ,  ∇φ = u,
//              ∇²φ = (I − e_z e_zᵀ − u uᵀ)/d  along the side (|z| < L, a cylinder),
//              ∇²φ = (I − u uᵀ)/d             at the caps (|z| ≥ L, a sphere).
//   Tube     the union of capsules around the segments [v_j, v_{j+1}] of the polyline:
//            φ = min_j d_j − ρ, d_j = distance from x to segment j; for the nearest segment,
//            e = its unit direction, c = the nearest point on it, u = (x − c)/d:
//              ∇²φ = (I − e eᵀ − u uᵀ)/d  where c is inside the segment (a cylinder),
//              ∇²φ = (I − u uᵀ)/d         where c is a vertex (a sphere: the joints and the
//                                         two closed, hemispherical ends).
//            Cost: a brute-force loop over all segments, O(segments) per evaluation (no
//            spatial index: tubes are a few hundred segments at most). With inside = true the
//            solid is everything outside the tube, i.e. the lumen of a pipe closed at both
//            ends: extend the polyline past where the rod can reach.
//
// Non-smooth points: the value returned there, and why.
//   * Core sets, where d = 0 (sphere centre, capsule segment, tube polyline): φ has a
//     conical kink. We return φ = −ρ (exact), ∇²φ = 0 (the true ∇²φ grows as 1/d) and a
//     fixed unit ∇φ (a one-sided derivative, so still |∇φ| = 1): sphere e_z; capsule e_x;
//     tube: the coordinate axis least aligned with the segment (lowest index on ties), made
//     perpendicular to it. d ≤ kCoreDistance (1e-150 m) counts as d = 0: below ~1e-154 the
//     squared norm underflows and w/d is no longer a unit vector. With inside = true these
//     are the deepest points of the lumen, where contact needs a sample larger than the tube.
//   * Box, inside the inner box: on the medial sets where two q_i tie, k is the lowest such
//     index; on the plane x_k = 0 (medial between opposite faces, e.g. the box centre)
//     sign(0) = +1. At the centre, k is the axis of the smallest b_i (lowest index on ties).
//   * Tube: where two segments are equally near at different points (the medial surface on
//     the inside of a bend) the FIRST segment in polyline order is used. At a vertex both
//     adjacent segments give the vertex itself: same point, same (sphere) derivatives.
//   * C¹ but not C² (φ, ∇φ continuous, ∇²φ jumps): box planes q_i = 0, capsule planes
//     z = ±L, tube planes through the vertices normal to a segment. On them we use the
//     lower-dimensional side: q_i = 0 is not active (face rather than edge); |z| = L is a cap
//     (sphere); a clamped projection is a vertex (sphere).
// Accuracy: φ to a few ulps of max(‖x‖, size of the shape) — also 1e-9 from the surface and
// 1e6 away — for points up to ~1e150 m (beyond, squared norms overflow).

#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "state.hpp"

namespace liedyn {

// φ and its derivatives at a world point. hessian is only written when requested.
struct SdfValue {
  double distance = 0.0;               // φ(p), m; < 0 inside the solid
  Vector3 gradient = Vector3::Zero();  // ∇φ (unit length wherever φ is a true distance)
  Matrix3 hessian = Matrix3::Zero();   // ∇²φ (symmetric), 1/m
};

// The half-space z ≤ 0 of the collider frame is solid: φ = z.
struct PlaneShape {};
// Solid ball of radius `radius` (m, > 0) about the frame origin.
struct SphereShape {
  double radius = 1.0;
};
// Box about the origin, edges rounded by `rounding` (the solid is the box of
// half_extents − rounding, inflated by rounding: the outer size stays half_extents).
// half_extents > 0 (m); 0 ≤ rounding < min half extent.
struct BoxShape {
  Vector3 half_extents = Vector3::Ones();
  double rounding = 0.0;
};
// Segment from −half_length e_z to +half_length e_z (half_length ≥ 0; 0 is a sphere),
// inflated by radius (> 0).
struct CapsuleShape {
  double half_length = 1.0;
  double radius = 0.1;
};
// Solid tube of radius `radius` (> 0) around a polyline (≥ 2 points, collider frame,
// consecutive points distinct), closed by hemispheres at both ends.
struct TubeShape {
  std::vector<Vector3> polyline;
  double radius = 0.1;
};
class GridSdf;  // lib/mesh_sdf.hpp
// A closed triangle mesh, as the trilinear interpolant of its signed distance sampled on a
// grid (lib/mesh_sdf.hpp; mesh coordinates = the collider frame). Shared between copies of
// the collider: a grid can hold millions of values.
struct MeshShape {
  std::shared_ptr<const GridSdf> grid;
};
using Shape = std::variant<PlaneShape, SphereShape, BoxShape, CapsuleShape, TubeShape, MeshShape>;

// Distances to a core set (sphere centre, segment, polyline) at or below this count as zero
// (see "Non-smooth points" above).
inline constexpr double kCoreDistance = 1e-150;

struct Collider {
  std::string name;
  Shape shape;
  Vector3 position = Vector3::Zero();         // collider frame origin, world
  Matrix3 orientation = Matrix3::Identity();  // collider frame → world
  bool inside = false;  // φ → −φ: the solid is everything OUTSIDE the shape (a bowl from a
                        // sphere, the lumen of a tube)

  // φ(p), ∇φ(p), and ∇²φ(p) if with_hessian (otherwise `hessian` stays zero), world frame,
  // as described at the top. Allocation-free; cost O(1), or O(segments) for a tube.
  SdfValue evaluate(const Vector3& p, bool with_hessian = true) const;

  // Throws liedyn::ModelError (lib/model.hpp) naming the first offending field as
  // path + ".radius", ".half_extents", ".rounding", ".half_length", ".polyline",
  // ".polyline[j]", ".position", ".orientation": every number finite; radius > 0;
  // half_extents > 0; 0 ≤ rounding < min half extent; half_length ≥ 0; a polyline of ≥ 2
  // points with no zero-length (or overflowing) segment; orientation a rotation
  // (‖RᵀR − I‖_F ≤ 1e-9 and det R > 0, as Model::validate).
  void validate(const std::string& path) const;
};

// Centripetal Catmull–Rom spline (α = ½: knot spacing ‖P_{i+1} − P_i‖^½; no cusps or
// self-intersections within a span, unlike the uniform variant) through `control_points`,
// sampled as a polyline for TubeShape. The ends use phantom points reflected through the end
// points, P_{−1} = 2P_0 − P_1 and P_n = 2P_{n−1} − P_{n−2}. Each of the n − 1 spans gives
// `samples_per_segment` points at equal parameter steps, starting at its first control
// point, and the last control point closes the list: (n − 1)·samples_per_segment + 1
// points, with control point i exactly at index i·samples_per_segment.
// Throws std::invalid_argument for fewer than 2 points, samples_per_segment < 1, a
// non-finite point or two consecutive equal points.
std::vector<Vector3> catmull_rom_polyline(const std::vector<Vector3>& control_points,
                                          int samples_per_segment);

}  // namespace liedyn

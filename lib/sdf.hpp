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
//   Link     (a chain link; the torus is L = 0) the solid tube of radius r about the stadium
//            curve C of the xy plane at distance R from the segment S = [−L, L] × {0} × {0}
//            (0 ≤ L, 0 < r < R). With the planar offset from S
//              w = (x − clamp(x, −L, L), y, 0),  s = ‖w‖,  n = w/s  (unit, ⟂ e_z),
//            a = s − R, D = ‖(a, z)‖ (the distance to C), u = (a n + z e_z)/D, τ = e_z × n:
//              φ = D − r,  ∇φ = u,
//              ∇²φ = (I − τ τᵀ − u uᵀ)/D                   beside the straight sides (|x| < L),
//              ∇²φ = (I − τ τᵀ − u uᵀ)/D + a/(s D) τ τᵀ    about the arcs (|x| ≥ L; a torus).
//            Why: for c ∈ C, ‖x − c‖² = z² + ‖(x, y) − c‖², and the planar distance from (x, y)
//            to the level set C = {s = R} is |s − R| (s is the distance to a convex set, and
//            every point of the ray from its nearest point of S through (x, y) has that same
//            nearest point), so D is the exact distance to C; the solid is the union of the
//            balls of radius r about C, exact also inside since r < R (no point of the solid
//            is nearer S than R − r > 0). Derivatives through s: ∇D = u with ∇s = n, and
//            ∇²D = (n nᵀ + e_z e_zᵀ + a ∇²s − u uᵀ)/D, where n nᵀ + e_z e_zᵀ = I − τ τᵀ and
//            ∇²s = 0 beside S's interior (s = |y|), ∇²s = (I − e_z e_zᵀ − n nᵀ)/s = τ τᵀ/s
//            about its ends. The torus's τ τᵀ curvature a/(s D) is cos v/(R + r cos v) on its
//            surface (v = the angle about the tube), the textbook one.
//   Cylinder radius ρ, half length h along z, flat caps. With s, n = the planar offset from
//            the z axis (the link's with L = 0) and q = (s − ρ, |z| − h) (the rectangle's
//            SDF in the (s, z) half-plane):
//              rim  (q_1 > 0 and q_2 > 0): the distance to the rim circle at z = sign(z) h,
//                   i.e. the torus (link with L = 0) of major radius ρ and minor radius 0 at
//                   x − sign(z) h e_z: φ = ‖q‖;
//              side (otherwise, q_1 ≥ q_2): φ = s − ρ, ∇φ = n, ∇²φ = (I − e_z e_zᵀ − n nᵀ)/s
//                   (outside beside the side, or inside nearer the side than a cap);
//              cap  (otherwise, q_2 > q_1): φ = |z| − h, ∇φ = sign(z) e_z, ∇²φ = 0.
//
// Non-smooth points: the value returned there, and why.
//   * Core sets, where d = 0 (sphere centre, capsule segment, tube polyline, link and torus
//     core curve C, where D = 0): φ has a conical kink. We return φ = −ρ (exact; −r for a
//     link), ∇²φ = 0 (the true ∇²φ grows as 1/d) and a fixed unit ∇φ (a one-sided derivative,
//     so still |∇φ| = 1): sphere e_z; capsule e_x; tube: the coordinate axis least aligned
//     with the segment (lowest index on ties), made perpendicular to it; link: n (in the
//     plane, away from S). d ≤ kCoreDistance (1e-150 m) counts as d = 0: below ~1e-154 the
//     squared norm underflows and w/d is no longer a unit vector. With inside = true these
//     are the deepest points of the lumen, where contact needs a sample larger than the tube.
//   * Link and torus, on the set s = 0 (≤ kCoreDistance): the strip {y = 0, |x| ≤ L} across
//     the link's hole, where both straight sides are equally near (of a torus: its z axis,
//     equidistant from the whole circle C). φ = ‖(R, z)‖ − r is exact; we take n = e_y and
//     ∇²s = 0: ∇φ = (−R e_y + z e_z)/D, ∇²φ = (I − e_x e_xᵀ − u uᵀ)/D. For a link these are
//     the one-sided derivatives from y > 0; for a torus the true a/(s D) τ τᵀ term grows
//     without bound towards the axis, and is dropped there.
//   * Cylinder: on its axis where the side is nearest (s = 0, inside, |z| ≤ h − ρ) ∇φ = e_y
//     (n as for the torus), ∇²φ = 0 (the true one grows as 1/s); inside, on the cone q_1 = q_2
//     from the rim (equally near side and cap) the side is used; on the disc z = 0 between
//     the caps (where they are nearer than the side) sign(+0) = +1. The rim circle itself
//     (q = 0) is the side.
//   * Box, inside the inner box: on the medial sets where two q_i tie, k is the lowest such
//     index; on the plane x_k = 0 (medial between opposite faces, e.g. the box centre)
//     sign(0) = +1. At the centre, k is the axis of the smallest b_i (lowest index on ties).
//   * Tube: where two segments are equally near at different points (the medial surface on
//     the inside of a bend) the FIRST segment in polyline order is used. At a vertex both
//     adjacent segments give the vertex itself: same point, same (sphere) derivatives.
//   * C¹ but not C² (φ, ∇φ continuous, ∇²φ jumps): box planes q_i = 0, capsule planes
//     z = ±L, tube planes through the vertices normal to a segment, link planes x = ±L,
//     cylinder planes |z| = h (outside the side) and cylinder s = ρ (outside a cap). On them
//     we use the lower-dimensional side: q_i = 0 is not active (face rather than edge);
//     |z| = L is a cap (sphere); a clamped projection is a vertex (sphere); |x| = L is an arc
//     (torus); a cylinder's q_i = 0 is not positive (side or cap rather than rim).
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
// Solid torus about the z axis: the ball of radius minor_radius swept around the circle of
// radius major_radius in the xy plane (m; 0 < minor_radius < major_radius). A link with
// half_length 0.
struct TorusShape {
  double major_radius = 1.0;
  double minor_radius = 0.25;
};
// Solid cylinder along z with flat caps at z = ±half_length (m, > 0), of radius `radius`
// (m, > 0).
struct CylinderShape {
  double radius = 0.5;
  double half_length = 1.0;
};
// A chain link: the ball of radius minor_radius swept along the stadium curve of the xy plane
// at distance major_radius from the segment [−half_length, half_length] × {0} × {0}: two
// straight sides parallel to x at y = ±major_radius joined by half circles about
// (±half_length, 0, 0). 0 ≤ half_length (0: a torus), 0 < minor_radius < major_radius (m).
struct LinkShape {
  double half_length = 0.5;
  double major_radius = 0.5;
  double minor_radius = 0.1;
};
class GridSdf;        // lib/mesh_sdf.hpp
struct TriangleMesh;  // lib/mesh_sdf.hpp
// A closed triangle mesh, as the trilinear interpolant of its signed distance sampled on a
// grid (lib/mesh_sdf.hpp; mesh coordinates = the collider frame). Shared between copies of
// the collider: a grid can hold millions of values. `mesh` is the mesh the grid was built
// from (checked closed and consistently oriented by the grid): a body with this shape takes
// its samples, bounding radius and mass properties from it.
struct MeshShape {
  std::shared_ptr<const GridSdf> grid;
  std::shared_ptr<const TriangleMesh> mesh;
};
using Shape = std::variant<PlaneShape, SphereShape, BoxShape, CapsuleShape, TubeShape, TorusShape,
                           CylinderShape, LinkShape, MeshShape>;

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
  // ".polyline[j]", ".major_radius", ".minor_radius", ".file", ".position", ".orientation":
  // every number finite; radius > 0; half_extents > 0; 0 ≤ rounding < min half extent;
  // half_length ≥ 0 (a cylinder's > 0); a polyline of ≥ 2 points with no zero-length (or
  // overflowing) segment; major_radius > 0; 0 < minor_radius < major_radius; a mesh has its
  // grid; orientation a rotation (‖RᵀR − I‖_F ≤ 1e-9 and det R > 0, as Model::validate).
  void validate(const std::string& path) const;
};

// The one place that decides which shapes a dynamic body, or any body of the scene's
// "bodies", may have (Model::validate, the scene's bodies, surface_samples, mass_properties):
// a bounded solid whose surface samples (lib/body_contact.hpp) and mass properties
// (lib/mass_properties.hpp) are known — a sphere, box, capsule, torus, cylinder, link or mesh
// (with its triangles), not `inside`. A kinematic body's shape is only touched, never sampled
// or weighed, so it may be any collider (a moving collider: a plane, a tube, a bowl; its
// bounding radius may be +∞, lib/body_contact.cpp). Throws ModelError(path + ".type") for
// another shape or a mesh without its triangles, and (path + ".inside") for a complement.
void validate_body_shape(const Collider& shape, const std::string& path);

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

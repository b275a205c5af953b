#pragma once
// The mass and rotational inertia of a solid of uniform density, from its shape (a body's
// "density" instead of "mass" and "inertia").
//
// With V the volume and S = ∫ p pᵀ dV the second moments about the shape's centre (diagonal
// in the shape's own axes for the symmetric solids, full for a mesh), a density ρ gives
//   m = ρ V,   I = ρ (tr(S) 1 − S)   (inertia about the centre, I_xx = ρ ∫ (y² + z²) dV),
// turned into the body's axes by the shape's orientation Q: Q I Qᵀ. The shape's centre must
// be the body's origin, which is its centre of mass.
//
// Sphere (radius r): V = 4πr³/3, S_ii = 4πr⁵/15.
// Capsule (half length h along z, radius r): a cylinder (V = 2πr²h, S_xx = πr⁴h/2,
//   S_zz = 2πr²h³/3) and two hemispheres whose flat faces sit at z = ±h (each: V = 2πr³/3,
//   S_xx = 2πr⁵/15, and with z = h + w, ∫ z² = h²V + 2h ∫w + ∫w², ∫w = πr⁴/4, ∫w² = 2πr⁵/15).
// Rounded box (outer half extents e, rounding r; inner box a = e − r): the inner box
//   inflated by r, cut into the inner box, six face slabs, twelve quarter cylinders along the
//   edges and eight sphere octants at the corners. With u ≥ 0 the distance beyond the inner
//   box along an axis, a quarter disc of radius r has area πr²/4, ∫u = r³/3, ∫u² = πr⁴/16, and
//   a sphere octant V = πr³/6, ∫u = πr⁴/16, ∫u² = πr⁵/30; ∫x² over a part lying beyond the
//   inner box along x is ∫(a_x + u)² = a_x² V + 2 a_x ∫u + ∫u². A sharp box is r = 0.
// Cylinder (half length h along z, radius r): the capsule's cylinder.
// Torus (major radius R, minor r, about z), by Pappus: in the disc of the tube's cross-section
//   (ρ = R + u, z; u² + z² ≤ r², dV = ρ dA dθ), V = 2π²Rr², ∫z² = 2πR ∫z² dA = π²Rr⁴/2,
//   ∫(x² + y²) = 2π ∫(R + u)³ dA = 2π²R³r² + (3/2)π²Rr⁴, so ∫x² = ∫y² = π²R³r² + (3/4)π²Rr⁴:
//   I_zz = m(R² + ¾r²), I_xx = I_yy = m(½R² + ⅝r²).
// Link (half length L, radii R, r): two cylinders of radius r and half length L along x at
//   y = ±R (∫y² gains R² V each), and the two halves of the torus about (±L, 0, 0): with x' =
//   x ∓ L, ∫x² = ∫x'² ± 2L ∫x' + L² V/2 per half, where over the half x' ≥ 0
//   ∫x' = ∫cos θ dθ ∫(R + u)² dA = 2(πr²R² + πr⁴/4) (the other half's is its negative), so
//   the halves add the torus's moments, 4L ∫x' and L² V_torus to ∫x².
// Closed triangle mesh (its triangles, the grid's; checked closed and consistently oriented),
//   by the divergence theorem: the signed tetrahedra (0, a, b, c) of its triangles, x = Jξ
//   with J = [a b c] over the unit simplex (∫ξ_i ξ_j = (1 + δ_ij)/120), give
//     V_t = a·(b × c)/6,  ∫x = V_t (a + b + c)/4,  ∫x xᵀ = V_t/20 (a aᵀ + b bᵀ + c cᵀ + s sᵀ),
//   s = a + b + c, summed (all signs flipped if the total V < 0: normals pointing inward). The
//   mesh's origin must be its centroid c = ∫x / V, to kMeshCentroidTolerance × its size (half
//   its bounding box's diagonal: an OBJ written to 6 digits is centred to about that); S is
//   then taken about c, S − V c cᵀ.

#include <string>

#include "sdf.hpp"
#include "state.hpp"

namespace liedyn {

struct MassProperties {
  double mass = 0.0;
  Matrix3 inertia = Matrix3::Zero();  // about the centre of mass, body axes
};

// How far a mesh's centroid may be from its origin, relative to its size (header).
inline constexpr double kMeshCentroidTolerance = 1e-6;

// Throws ModelError(path + ".density") unless density is finite and > 0, and
// (path + ".contact.shape…") for a shape that is not a body's (validate_body_shape), one not
// centred on the body's origin (".position") or a mesh whose centroid is not its origin
// (".file", saying by how much).
MassProperties mass_properties(const Collider& shape, double density, const std::string& path);

}  // namespace liedyn

#pragma once
// The mass and rotational inertia of a solid of uniform density, from its shape (a body's
// "density" instead of "mass" and "inertia").
//
// With V the volume and S = ∫ p pᵀ dV the second moments about the shape's centre (diagonal
// in the shape's own axes for these symmetric solids), a density ρ gives
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

#include <string>

#include "sdf.hpp"
#include "state.hpp"

namespace liedyn {

struct MassProperties {
  double mass = 0.0;
  Matrix3 inertia = Matrix3::Zero();  // about the centre of mass, body axes
};

// Throws ModelError(path + ".density") unless density is finite and > 0, and
// (path + ".contact.shape…") for a shape it cannot integrate (a sphere, box or capsule) or one
// not centred on the body's origin.
MassProperties mass_properties(const Collider& shape, double density, const std::string& path);

}  // namespace liedyn

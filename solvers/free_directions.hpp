#pragma once
// Free directions: tangent directions of one point or one rotation of a component along which
// the potential Ψ has no curvature at a state, so nothing holds the model there.
//
// Why: in static mode there is no inertia, and a model can be anchored (every body tied to
// the world by springs) and still leave a motion free: a body hung by springs attached on one
// line through it spins about that line at no cost. Ψ is then flat along the spin, its
// Hessian H singular, and Newton's step (H + μI)⁻¹ g has an arbitrary component along the
// spin that never falls below the tolerance: the steps do not converge although the
// equilibrium they reach is exact (only not unique). Naming the free motion tells the user
// what to add (a spring off that line, a clamp) instead of leaving "did not converge".
//
// The test is per block: with H_bb the 3×3 diagonal block of point or rotation b (Lie
// derivatives: world-frame rotation axes), an eigenvector a of H_bb with eigenvalue
//   λ ≤ kFreeCurvature · max_ii |H_ii|
// is a free direction e_b ⊗ a. For a positive semi-definite H (a minimum), vᵀHv = 0 implies
// Hv = 0: the direction is free in the whole component, not only in its own block. Motions
// that are free only jointly (two bodies turning together) are not found by this test.

#include <string>
#include <vector>

#include "../lib/incremental_potential.hpp"

namespace liedyn {

struct FreeDirection {
  std::string object;  // "bodies[2]", "rods[0].nodes[3]", "rods[0].edges[3]"
  bool rotation = true;  // rotation about `axis`, or translation along it
  Vector3 axis = Vector3::UnitZ();  // unit, world frame

  // "free rotation of bodies[2] about (0, 0, 1): no stiffness holds it"
  std::string describe() const;
};

// Relative curvature below which a direction counts as free (see the header comment): far
// below any stiffness a scene would hold a body with, far above the round-off of H.
inline constexpr double kFreeCurvature = 1e-10;

// The free directions of component `c` of `model` at q (its potential set up for the step,
// IncrementalPotential::begin_step). Assembles Ψ once.
std::vector<FreeDirection> free_directions(const Model& model, const Component& c,
                                           const State& q);

}  // namespace liedyn

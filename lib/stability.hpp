#pragma once
// The stable step of a conditionally stable integrator (Model::Integrator, fox_goodwin).
//
// The Newmark family with γ = ½ (lib/history.hpp) on a linear oscillation M ẍ = −K x multiplies
// each mode's amplitude per step by the roots of r² − (2 − (1 − 2β) s) r + 1 = 0 over
// (1 + β s), s = (ωh)²: both on the unit circle (no growth, no decay) while s (1 − 4β) < 4, and
// one real and below −1 beyond. β = ¼ (trapezoidal) is stable at every h; β = 1/12
// (fox_goodwin) while ωh < √6. A step is stable where the largest s over the modes is, that is
// the largest eigenvalue of the generalised problem K v = s (M/h²) v — with K the Lie Hessian of
// the terms of the state at q (those β weights; not inertia, friction, motors or exact joints)
// and M/h² the inertia terms' m/h² and R (tr(Ĵ) 1 − Ĵ) Rᵀ = I_w/h² (lib/inertia.hpp).
//
// Estimated by Lanczos's method on L⁻¹ K L⁻ᵀ (M/h² = L Lᵀ, 3×3 blocks) with full
// reorthogonalisation: its largest Ritz value converges to the largest eigenvalue from below,
// within round-off of it after as many iterations as there are DOFs and, for a rod's dense top of
// the spectrum, to within the cluster's width after the iterations taken here (kLanczosSteps).

#include <Eigen/Core>

#include "incremental_potential.hpp"
#include "state.hpp"

namespace liedyn {

// The largest (ωh)² of the component's modes at q (0 when no term of the state is stiff there;
// negative eigenvalues, a buckling direction, do not count; +∞ where the stiffness is not
// finite). The component must have positive definite inertia on every DOF block (a dynamic
// step; std::logic_error otherwise).
double largest_mode_step_squared(const Component& component, const State& q);

// Throws ModelError on "time_step" when integrator β < ¼ (newmark_beta) and some component's
// largest (ωh)² at q (the state of `frame`) reaches the bound 4/(1 − 4β), naming ω, the bound
// on h and the unconditionally stable integrators. Nothing for the other integrators and in
// static mode.
void check_stable_step(const Model& model, const std::vector<Component>& components, const State& q,
                       int frame);
// The same for a validated model's first step (its components at q_0), as the Simulator's
// constructor will check it: for a scene's loader, which names the file.
void check_stable_start(const Model& model);

}  // namespace liedyn

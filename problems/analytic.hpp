#pragma once
// Closed-form solutions that a scene can declare ("analytic": NAME, docs/scene-format.md), the
// exact reference `liedyn sweep` measures its errors against. Each one states what it assumes;
// a scene that declares a solution but breaks an assumption is rejected at load (SceneError,
// field "analytic"), so a sweep never compares against a formula that does not apply.
//
// free_body — one rigid body, no springs, forces, torques or rods, dynamic mode, with an
//   axisymmetric inertia (two equal principal moments I⊥, symmetry axis a with moment I_a, in
//   the body frame). The angular momentum L = R₀ I_b R₀ᵀ ω₀ (world) is constant and
//     R(t) = exp(t L̂ / I⊥) R₀ exp(t λ â),   λ = (1/I_a − 1/I⊥) aᵀR₀ᵀL,
//   since then Rᵀ Ṙ = (RᵀL/I⊥ + λ a)^ = (I_b⁻¹ RᵀL)^ (aᵀRᵀL is constant: R(t)ᵀL is R₀ᵀL turned
//   about a). The centre of mass falls freely: x(t) = x₀ + v₀ t + ½ g t².
//   Frame k is compared at t = k h; backward Euler is first order and dissipates, so the
//   error grows with h and with time.
//
// cantilever — static mode; one straight rod, node 0 and edge 0 clamped (and nothing else),
//   no gravity, one constant force F on the last node, perpendicular to the rod, isotropic
//   bending (K_b₁ = K_b₂ = EI). Euler–Bernoulli (small deflection) with s the distance of a
//   node from node 0 and L that of the last node:
//     w(s) = λ F s² (3L − s) / (6 EI),   slope w′(s) = λ F s (2L − s) / (2 EI),
//   at load step λ = k/frames; each edge turns by w′ at its midpoint about d × F̂ (d: the
//   rod's direction), but the clamped edge 0, which holds the tangent at the clamp, not at all.
//   The linear theory is itself off by O((F L²/EI)²) relative, and the discrete rod by
//   O((l/L)²) (tests/test_analytic.cpp, tests/test_rod_validation.cpp).
//
// axial_stretch — static mode; one straight rod with node 0 fixed (other nodes free; edges
//   may be clamped), no gravity, one constant force F on the last node along the rod. Every
//   edge carries the tension F, Ψ_s = ½ k_s l (1 − ‖e‖/l)² gives ‖e‖ = l (1 + F/k_s), so each
//   node moves by u(s) = λ F s / k_s along the rod and no edge turns. Exact for the discrete
//   rod too (the sweep's error is then solver error only).

#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "scene.hpp"

namespace liedyn {

std::optional<AnalyticSolution> parse_analytic(std::string_view name);  // "none", "free_body", …
const char* to_string(AnalyticSolution solution);

// What a solution predicts at one frame: the points and rotations it describes, by their
// index in State::points / State::rotations (the others are absent).
struct ExactFrame {
  std::vector<std::pair<int, Vector3>> points;
  std::vector<std::pair<int, Matrix3>> rotations;
};

// Throws SceneError (field "analytic", naming the broken assumption) if the scene declares a
// solution whose assumptions it does not meet; does nothing for kNone.
void check_analytic(const Scene& scene);

// Frames 0 … scene.frames of the declared solution (check_analytic first). Empty for kNone.
std::vector<ExactFrame> exact_trajectory(const Scene& scene);

}  // namespace liedyn

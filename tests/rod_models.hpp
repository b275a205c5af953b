#pragma once
// Rod models and continuum references shared by the rod tests (test_rod_validation.cpp,
// test_rod_convergence.cpp).

#include <Eigen/Core>
#include <cmath>

#include "lib/rod.hpp"
#include "solvers/newton.hpp"

namespace liedyn::test_models {

// A straight, uniform rod along x: `edges` edges of length `length`/`edges`, total mass
// `mass` [kg], radius `radius` [m], stretch and shear stiffnesses ks, kx [N], and the same
// stiffness EI [N m²] in bending and twist. Nothing clamped, no loads.
inline RodSpec uniform_rod(int edges, double length, double mass, double radius, double ks,
                           double kx, double EI) {
  RodSpec rod;
  rod.name = "rod";
  for (int i = 0; i <= edges; ++i) rod.nodes.push_back(Vector3(length * i / edges, 0.0, 0.0));
  rod.mass = mass;
  rod.radius = radius;
  rod.stretch_stiffness = ks;
  rod.shear_stiffness = kx;
  rod.bending_stiffness = Vector3(EI, EI, EI);
  return rod;
}

inline SolverOptions newton(double tolerance, int max_iterations = 50) {
  SolverOptions options;
  options.tolerance = tolerance;  // on the Newton step, metres and radians
  options.max_iterations = max_iterations;
  return options;
}

struct Tip {
  double x = 0.0;  // along the undeformed rod
  double y = 0.0;  // deflection, along the load
};

// Elastica: an inextensible, unshearable rod of length L clamped horizontally at s = 0 under
// a dead tip load F perpendicular to the undeformed rod. θ(s) is the tangent angle towards
// the load; the bending moment at s is F (x(L) − x(s)), so EI θ' = F (x(L) − x(s)) and
//   θ'' = −p cos θ,  p = F/EI,   θ(0) = 0,  θ'(L) = 0,   x' = cos θ,  y' = sin θ.
// Shooting on κ₀ = θ'(0) = p x(L) ∈ [0, pL]: θ'(L) = κ₀ − p ∫cos θ is < 0 at κ₀ = 0 and ≥ 0 at
// κ₀ = pL, so bisection brackets the root. RK4 with 4000 steps: global error O((L/4000)⁴),
// at rounding level (for p L = 2 the tip changes by < 3e-14 from 1000 to 4000 steps).
inline Tip elastica_tip(double p, double L) {
  const int steps = 4000;
  const double ds = L / steps;
  auto integrate = [&](double kappa0, Tip* tip) {
    Eigen::Vector4d u(0.0, kappa0, 0.0, 0.0);  // θ, θ', x, y
    auto f = [&](const Eigen::Vector4d& v) {
      return Eigen::Vector4d(v[1], -p * std::cos(v[0]), std::cos(v[0]), std::sin(v[0]));
    };
    for (int k = 0; k < steps; ++k) {
      const Eigen::Vector4d k1 = f(u);
      const Eigen::Vector4d k2 = f(u + 0.5 * ds * k1);
      const Eigen::Vector4d k3 = f(u + 0.5 * ds * k2);
      const Eigen::Vector4d k4 = f(u + ds * k3);
      u += ds / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    if (tip) *tip = Tip{u[2], u[3]};
    return u[1];  // θ'(L)
  };
  double lo = 0.0, hi = p * L;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * p * L; ++it) {
    const double mid = 0.5 * (lo + hi);
    (integrate(mid, nullptr) < 0.0 ? lo : hi) = mid;
  }
  Tip tip;
  integrate(0.5 * (lo + hi), &tip);
  return tip;
}

// The discrete rod's tip deflection under a small tip force, over Euler–Bernoulli's
// F L³/(3 EI), for a uniform rod of n edges clamped at node 0 and edge 0 (bending only, no
// shear compliance): hinges at nodes i = 1…n−1 of stiffness EI/w_i carrying F (L − i l), with
// w_i = l and w_1 = 3l/2 next to the clamp (lib/rod.hpp), give
//   Σ_i F (L − i l)² w_i/EI = F l³/EI (Σ_{j=1}^{n−1} j² + ½ (n − 1)²),
// which is 1 − 5/(2n²) + 3/(2n³) of F L³/(3 EI): second order in 1/n.
inline double clamped_rod_tip_fraction(double n) { return 1.0 - 2.5 / (n * n) + 1.5 / (n * n * n); }

// A uniform cantilever of `edges` edges along x (length 1 m, 0.1 kg, radius 1 cm, k_s = k_x =
// 1e4 N, stiffness EI in bending and twist), nodes 0 and 1 and edge 0 clamped, straight at
// rest and started bent in the x–y plane to the uniform `curvature`: each hinge turns by the
// curvature times its cell, 3l/2 at node 1 next to the clamped edge 0 and l elsewhere
// (lib/rod.hpp), so that the bending moment is the same along the rod. Edge lengths stay the
// rest lengths, so that only bending is excited (a bent start that also stretched the rod
// would ring its stiff stretch modes, which the trapezoidal rule keeps undamped: ω h ≫ 1).
inline RodSpec bent_cantilever(int edges, double EI, double curvature) {
  RodSpec rod = uniform_rod(edges, 1.0, 0.1, 0.01, 1e4, 1e4, EI);
  rod.fixed_nodes = {0, 1};
  rod.fixed_edges = {0};
  rod.rest_nodes = rod.nodes;
  const double l = 1.0 / edges;
  double angle = 0.0;
  for (std::size_t i = 1; i + 1 < rod.nodes.size(); ++i) {
    angle += curvature * (i == 1 ? 1.5 * l : l);
    rod.nodes[i + 1] = rod.nodes[i] + l * Vector3(std::cos(angle), std::sin(angle), 0.0);
  }
  return rod;
}

// Smallest root of cos β cosh β = −1 (clamped–free beam): β₁ = 1.8751040687…; the first
// bending mode of a cantilever of mass m, length L, stiffness EI has ω₁ = β₁² √(EI/(m L³)).
inline double cantilever_beta1() {
  double beta = 1.875;
  for (int it = 0; it < 20; ++it) {  // Newton on f(β) = cos β cosh β + 1
    const double f = std::cos(beta) * std::cosh(beta) + 1.0;
    const double df = -std::sin(beta) * std::cosh(beta) + std::cos(beta) * std::sinh(beta);
    beta -= f / df;
  }
  return beta;
}

}  // namespace liedyn::test_models

#pragma once
// Analyses of the parameterisations themselves (no scene): data for paper Fig. 3.

#include <string>

namespace liedyn {

// Singular values σ1 ≥ σ2 ≥ σ3 of ∂vec(exp(r))/∂r (eq. 5) for ‖r‖ = 2π k/(samples − 1),
// k = 0 … samples − 1 (the values do not depend on the axis), as CSV:
//   angle,sigma1,sigma2,sigma3
std::string exp_jacobian_singular_values_csv(int samples);

}  // namespace liedyn

#pragma once
// The backward-Euler step as an NLP for Ipopt 3.11 (docs/design.md §9.4): minimise the
// component's incremental potential Ψ (paper §4.2) over n = component.dofs variables, with no
// bounds, subject to its exact joints (below) as equality constraints. Ipopt has no manifolds, so each rotation is
// written in a chart around a reference R₀ (manifolds/rotation_chart.hpp):
//   positions   x            (the variables themselves),
//   rotations   R = exp(θ) R₀,   θ ∈ R³ the variables.
// SolverOptions::rotation chooses the chart:
//   * lie (default): R₀ = R at the start of the solve and θ = 0 — tangent increments;
//   * rotvec: R₀ = I and θ = log R (‖θ‖ ≤ π at the start) — global rotation vectors, the
//     unknowns of Newton's rotation-vector parameterisation (solvers/newton.hpp);
//   * quat: no chart: 4 variables q per rotation, R = A.21(q)/qᵀq, with qᵀq − 1 = 0 as one
//     more equality row per rotation after the joints' (manifolds/quaternion_chart.hpp has
//     the derivatives; docs/design.md §10.3). Its rows' Jacobians and Hessian blocks take
//     E(q) = 4 Q(q)ᵀ/qᵀq where the charts take J_l(θ); q starts at the unit quaternion of
//     R (s ≥ 0) at every solve.
//
// Exact joints (term.hpp, Constraint; joint_terms.hpp) are Ipopt's own equalities, not the
// augmented Lagrangian the other back-ends run: f is Ψ without them (each held at λ = 0,
// ρ = 0 while Ipopt evaluates), and each exact joint part gives r = kConstraintRank rows
// Pᵀc(q) = 0, P the r leading eigenvectors of J Jᵀ at the start of the solve (J = ∂c, the
// part's Lie Jacobian; 3 rows for a point or a weld, 2 for a hinge's alignment and a slider's
// line, whose third direction, along the axis, is second order in c and would make the
// Jacobian rank-deficient). Their Jacobian is Pᵀ J with J_l(θ) in rotation columns; the
// Lagrangian's Hessian obj_factor ∇²f + Σ λ̃ᵀ∇²(Pᵀc) comes from a second assembly with each
// part at λ = P λ̃ (its Lagrangian form λᵀc, whose ∇²(λᵀc) is exact for every part), less
// the first. When Ipopt
// stops, each part is left in its Lagrangian form with Ipopt's λ = P λ̃ and its own ρ:
// λᵀc + ½ρ‖c‖², whose Newton step is the shared test below, and whose λ is the joint's force
// (IncrementalPotential::exact_forces, read by the adjoint). A λ along a dropped axis does no
// work (Jᵀ of it is second order), so P λ̃ and the augmented Lagrangian's ρ(c + s) differ
// there and only there. Joint limits (inequalities) stay in f as their augmented-Lagrangian
// penalties, updated by StepSolver::solve (an interior-point barrier would have to be driven
// to μ → 0 within every step to hold a stop to the tolerance).
//
// Derivatives (manifolds/rotation_vector.hpp), exact, from the Lie gradient g and Lie
// Hessian H that the terms provide (docs/design.md §1.4):
//   ∂Ψ/∂θ   = J_l(θ)ᵀ g,
//   ∂²Ψ/∂θ² = J_l(θ)ᵀ H_θθ J_l(θ) + C(θ, g),   ∂²Ψ/∂x∂θ = H_xθ J_l(θ),
// because exp(θ + ε) R₀ = exp(J_l(θ) ε + O(ε²)) exp(θ) R₀: a change ε of the variable is a
// left perturbation J_l(θ) ε of R. The J_l factor is what makes the gradient the gradient of
// the function Ipopt evaluates; the Lie gradient g alone is that only at θ = 0, and its
// finite differences along θ give H − ½ hat(g), not a symmetric Hessian. Ipopt's line search
// compares Ψ with the slope ∇fᵀd and its derivative checker differences Ψ and ∇f, so both
// must be exact. At θ = 0, J_l = I and C = 0: the chart derivatives are the Lie ones.
// eval_h hands Ipopt the lower triangle, times obj_factor, in a sparse pattern recorded once
// from the 3×3 block order of one assembly (IncrementalPotential::assemble_into calls its sink
// in the same order every time); later assemblies scatter by call order without allocating.
// One assembly per new point serves eval_grad_f and eval_h (and eval_f there); a trial point
// of the line search that only needs Ψ costs one IncrementalPotential::value.
//
// What stops Ipopt: Ipopt's own optimality test is effectively switched off (tol at 1e-300,
// acceptable_iter 0) and intermediate_callback stops it once ‖d‖∞ ≤ SolverOptions::tolerance,
// where d is the primal search direction of the iteration just made, the solution of
// (W + δ_w I) d = −∇f (W the chart Hessian, δ_w Ipopt's inertia correction, 0 when W is
// positive definite). With δ_w = 0 and θ small that is the Newton step of the shared test
// at the previous iterate, so the new iterate is within O(‖d‖²) (quadratic convergence)
// of the minimiser. Iteration 0 (d = 0 by convention) never stops it. Ipopt also stops at its
// iteration limit (SolverOptions::max_iterations, summed over the solves of a step).
//
// Then the shared convergence test (step_solver.hpp) decides: a Newton StepSolver on the Lie
// parameterisation, which owns the component, evaluates the exact Lie Newton step at the
// final state — one assembly, one Cholesky factorisation and two triangular solves, about one
// Newton iteration without its line search. "Converged" therefore means exactly what it means
// for Newton, whatever Ipopt believed.
//
// Why re-centre: when the test fails (Ipopt's step was regularised or shortened, or the
// chart's metric J_l(θ) had drifted from the Lie one as θ grew), another Ipopt solve starts
// at the current state — lie: R₀ ← R, θ = 0, so the chart is again the Lie one at the
// current point; rotvec: θ = log R re-wrapped into ‖θ‖ ≤ π — with fresh Ipopt state (barrier
// and filter, L-BFGS memory). At most IpoptOptions::max_recentrings of them per step; after
// that the step is kMaxIterations, with the state updated (as Newton does).
//
// Failures: an Ipopt error status (Invalid_Number_Detected, Restoration_Failed,
// Error_In_Step_Computation, Diverging_Iterates, …) gives kSolverFailed, with StepReport::
// message naming it, and q restored to its value on entry. A Ψ, g or H that is not finite at
// the start of a solve gives kNonFinite without calling Ipopt; at a trial point Ipopt is told
// that the evaluation failed (it then shortens the step).
//
// Options passed to Ipopt (IpoptOptions, SolverOptions): print_level (0: silent, banner
// suppressed too), output_file at file_print_level max(print_level, 5), derivative_test,
// hessian_approximation ("limited-memory": Ipopt's L-BFGS, eval_h unused), max_iter; fixed:
// linear_solver mumps (the only one in Debian's Ipopt), nlp_scaling_method none (scaling Ψ
// by a constant does not change a Newton direction; with Ipopt's default gradient-based
// scaling the free body and rods of tests/test_ipopt.cpp took exactly as many iterations per
// step, at no gain in time), tol 1e-300 and acceptable_iter 0 (above), point_perturbation_radius
// 0.1 (the derivative checker tests at the starting point moved at random by up to that much per
// variable; Ipopt's default, 10, takes rotation vectors past 2π, where the chart is singular).
// One IpoptApplication per back-end object, initialised once with Initialize("") (plain
// Initialize() would read a stray ipopt.opt from the working directory). Its first solve is
// OptimizeTNLP, later ones ReOptimizeTNLP (same TNLP and pattern: Ipopt keeps its algorithm
// objects, but re-initialises them and takes our starting point; the derivative checker, when
// asked, still runs at the start of every solve).
//
// Cost: Ipopt 3.11 with MUMPS spends about a millisecond per solve and per iteration on its
// own bookkeeping (MUMPS instance set-up, timing via getrusage, option look-ups), whatever the
// size of the step: orders of magnitude above our assembly for a rigid body, still most of
// the time for a rod of a few hundred DOFs. And it makes one iteration more than Newton: its
// last, tiny step (‖d‖∞ ≤ tolerance) is the one Newton's test computes and does not take.
// This back-end is for comparison, not speed.
//
// Report: iterations = Ipopt iterations summed over the solves of the step; assemblies =
// charted assemblies (gradient and Hessian; not the Ψ-only trial evaluations) + the final
// tests'; factorizations = the tests' Cholesky factorisations (MUMPS's inside Ipopt are not
// counted); gradient_norm (Lie) and step_norm from the last test; with
// SolverOptions::measure_time, assembly_seconds = time in our evaluation callbacks (Ψ and
// assemblies) + the tests' assemblies, solve_seconds = the rest of Ipopt's wall time (its
// linear algebra and bookkeeping) + the tests' factorisations and solves.
// first_gradient_norm and second_gradient_norm are the gradient norms in the NLP's variables
// of its first two assemblies (Lie gradients when θ = 0; under quat a rotation's entries are
// E(q)ᵀ g, of twice the Lie norm at unit q). measure_condition is ignored.

#include <memory>

#include "step_solver.hpp"

namespace liedyn {

// The Ipopt back-end for `component` (options validated by the caller; backend is not read,
// any rotation parameterisation). Throws ModelError("solver.ipopt.output_file", …) if
// IpoptOptions::output_file cannot be opened for writing.
std::unique_ptr<StepSolver> make_ipopt_step_solver(Component component,
                                                   const SolverOptions& options);

}  // namespace liedyn

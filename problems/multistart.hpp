#pragma once
// `liedyn optimize --starts K`: the same optimisation from K points, for losses that are not
// convex (a letter's rod settles in a local basin, a die lands on another face), the best
// kept.
//
// Starts. Start 0 is the scene's γ₀, so a multi-start run never ends worse than the single
// run. Start k ≥ 1 draws every parameter: uniformly within its bounds where it has both,
// else γ₀ᵢ + σ·N(0,1), mirrored back across a one-sided bound it crosses. The draws come from
// one 64-bit Mersenne Twister seeded with `seed`, start after start, and the uniform and
// normal variates are made here (<random>'s distributions leave their algorithms to the
// library), so a seed gives the same starts on every machine.
//
// Runs. Each start is `liedyn optimize`'s minimisation (its optimiser settings and its loss
// scale — the scene's, or the loss at γ₀ — shared by every start) from its point, on `jobs`
// threads (problems/parallel.hpp), or spread over the ranks of an MPI job (start k on rank
// k mod P; rank 0 collects and writes; problems/process_group.hpp).
//
// Outputs (one folder, locked for the run). After every finished start one unit replaces
//   out/starts.csv       start,evaluations,iterations,best_loss,best_normalized_loss,status,
//                        reached_target,seconds,message — the finished starts, by start
//   out/checkpoint.json  the problem (problem_identity with starts, seed and spread), the loss
//                        scale and every finished start's result with its best γ
//   out/starts.png       (the last unit only) each start's best loss (problems/run_plots.hpp)
// and at the end one unit replaces parameters.csv, trajectory.csv and frames.csv of the best
// start's best γ. With resume the checkpoint's finished starts are kept (each one's best loss
// re-evaluated at its best γ: an edited or stale checkpoint is refused, SceneError) and the
// others run from their drawn points (not from where they were interrupted).

#include <cstdint>
#include <iosfwd>
#include <vector>

#include <Eigen/Core>

#include "optimization.hpp"

namespace liedyn {

// The `count` starting points (see above); lower/upper: ±∞ where unbounded.
std::vector<Eigen::VectorXd> draw_starts(const Eigen::VectorXd& gamma0, const Eigen::VectorXd& lower,
                                         const Eigen::VectorXd& upper, int count, std::uint64_t seed,
                                         double spread);

// Returns 0 when the best start reached the target, 3 when it did not, 4 when every start
// failed. Throws SceneError for bad options (--starts, --spread, -j) and checkpoints.
int run_multistart(const Scene& scene, const OptimizeOptions& options, std::ostream& out);

}  // namespace liedyn

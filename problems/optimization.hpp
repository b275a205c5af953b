#pragma once
// Trajectory optimisation from a scene file (paper §5, §7.3–7.4): the scene's "optimization"
// block (docs/scene-format.md), and the `liedyn gradcheck` and `liedyn optimize` commands.

#include <filesystem>
#include <iosfwd>
#include <nlohmann/json_fwd.hpp>
#include <cstdint>
#include <optional>
#include <string>

#include "../solvers/adjoint.hpp"
#include "../solvers/gradient_check.hpp"
#include "../solvers/optimizer.hpp"
#include "scene.hpp"

namespace liedyn {

// Parses the "optimization" block of a scene whose model is already validated. Throws
// SceneError (schema) or ModelError (indices, with the field's path).
OptimizationSpec parse_optimization(const nlohmann::json& value, const Scene& scene);

// The differentiable simulation a scene with an "optimization" block describes (SceneError
// if it has none).
DifferentiableSimulation make_differentiable_simulation(const Scene& scene);

// The loss and gradient `liedyn optimize` minimises, over `sim` (kept by reference): a
// parameter vector whose simulation is not defined (a forward step that does not converge, an
// angular velocity beyond π per step) is an infeasible trial point, at which Ceres and Ipopt
// shorten their step (solvers/optimizer.hpp).
ObjectiveFunction objective_of(const DifferentiableSimulation& sim);

// The parameters' bounds for `optimizer` (none if no block has any). Bounds under ceres-lbfgs,
// which cannot respect them, are bad input: SceneError naming `field`.
Bounds optimizer_bounds(const Scene& scene, const DifferentiableSimulation& sim,
                        Optimizer optimizer, const std::string& field);

// `liedyn gradcheck`: checks the gradient at γ₀, or at the γ of `parameters_file` when it is
// not empty (a parameters.csv of `liedyn optimize`, e.g. the point where an optimisation
// stalled); prints one row per checked parameter (with --verbose) and then the last line
// exactly
//   gradcheck: max_rel_error=<float> params=<int> tolerance=<float>
// Returns 0 when within tolerance, 1 otherwise. A parameters file that cannot be read, or
// whose rows are not this scene's parameters in order, is a SceneError naming the line.
int run_gradcheck(const Scene& scene, const GradientCheckOptions& options, bool verbose,
                  std::ostream& out, const std::filesystem::path& parameters_file = {});

class ProcessGroup;
class OutputFolder;

struct OptimizeOptions {
  std::filesystem::path out;              // output directory (created)
  std::optional<Optimizer> optimizer;     // overrides the scene's
  std::optional<int> max_iterations;      // overrides the scene's
  bool resume = false;                    // continue from out/checkpoint.json
  std::ostream* progress = nullptr;       // evaluation, loss, best, elapsed (a terminal)
  // Multi-start (problems/multistart.hpp): starts > 1 optimisations from drawn points.
  int starts = 1;
  std::uint64_t seed = 1;                 // of the drawn starts
  double spread = 0.1;                    // σ of the starts of unbounded parameters
  int jobs = 1;                           // starts at once (threads)
  ProcessGroup* group = nullptr;          // MPI ranks sharing the starts (null: alone)
};

// The identity of an optimisation problem, which checkpoints name: the scene's content
// (Scene::identity) and the optimiser settings that shape its path. max_iterations is left
// out: continuing a run for longer is the same problem.
nlohmann::json problem_identity(const Scene& scene, const OptimizerOptions& optimizer);
// SceneError naming `source` and the first field of `expected` that `stored` lacks or differs in.
void check_problem_identity(const nlohmann::json& stored, const nlohmann::json& expected,
                            const std::string& source);
// The scene's optimiser settings with the command line's overrides, validated.
OptimizerOptions resolve_optimizer(const Scene& scene, const OptimizeOptions& options);
// Adds parameters.csv (name,value of `best`) with trajectory.csv and frames.csv of its forward
// simulation to `folder`'s current unit (with what the caller added: run_optimize's loss.png)
// and commits it.
void write_best_run(OutputFolder& folder, const Scene& scene, const DifferentiableSimulation& sim,
                    const Eigen::VectorXd& best);

// `liedyn optimize`: minimises the scene's objective. The output folder is locked for the
// run (output_folder.hpp); after every evaluation one unit replaces
//   out/history.csv       iteration,loss,normalized_loss,gradient_norm,seconds (one row per
//                         evaluation of loss and gradient)
//   out/checkpoint.json   the problem it belongs to (the scene's content hash and the
//                         optimiser settings), the best parameters so far and the history
// and at the end one unit replaces out/parameters.csv (name,value of the best γ) with
// out/trajectory.csv and out/frames.csv (its forward simulation, the format of `liedyn
// simulate`) and out/loss.png (the loss at each evaluation, problems/run_plots.hpp). With
// resume, a checkpoint of another problem, or whose best loss is not the loss re-evaluated
// at its best point, is refused (SceneError: exit 2); otherwise the
// optimisation restarts from the checkpoint's best parameters (the L-BFGS memory is not
// kept) and appends to its history. Returns 0 when the target was reached, 3 when it stopped
// otherwise (iterations, round-off, back-end convergence), 4 on failure. With starts > 1 (or
// under mpirun): run_multistart (problems/multistart.hpp).
int run_optimize(const Scene& scene, const OptimizeOptions& options, std::ostream& out);

}  // namespace liedyn

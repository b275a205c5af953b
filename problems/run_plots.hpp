#pragma once
// `liedyn plot DIR [--out OUT]`: PNG plots of what an output folder holds, to see at a glance
// whether a run behaved (energy drift, solver effort, contacts) and how an optimisation went.
//
// A run's frames.csv (`liedyn simulate`, or the best run `liedyn optimize` leaves), against
// time:
//   energy.png         kinetic, potential and total energy: drift or jumps in the total show
//                      the integrator or a contact adding or losing energy
//   iterations.png     Newton iterations of each step: where the solver works hard
//   gradient_norm.png  the gradient norm each step's solve ended at, log y: how far within
//                      (or beyond) the tolerance each step converged
//   penetration.png    max_penetration and, where rods can touch, min_rod_separation
//   momentum.png       angular momentum about the origin, x, y and z: conserved without
//                      external torques, so its drift is the integrator's
// Frame 0 is the initial state, not a step (its status is "initial"): it is in the state plots
// (energy, penetration, momentum) but not in the per-step ones (iterations, gradient_norm).
// A plot whose columns are absent, or empty in every row it would use, is skipped and said so.
//
// An optimisation's history.csv (`liedyn optimize`), against the iteration column (one per
// evaluation of loss and gradient, continued by --resume):
//   loss.png                the loss at each evaluation and the best so far (line searches
//                           try points worse than the best), log y; the normalised loss on a
//                           right-hand axis. It is the loss divided by one constant, the loss
//                           scale, so a second series would be the same curve shifted on the
//                           log axis and would halve the room each has; a second axis gives
//                           both readings of one curve. The scale is history.csv's
//                           loss / normalized_loss, which must agree on every row.
//   loss_gradient_norm.png  ‖∇ loss‖ at each evaluation, log y (not gradient_norm.png: the
//                           best run's Newton gradient norms take that name in the same folder)
// A multi-start's starts.csv (`liedyn optimize --starts K`, problems/multistart.hpp):
//   starts.png              each start's best loss (normalised on the right), marked by how it
//                           ended: reached the target, stopped short, failed
//
// The PNGs are written into OUT (DIR by default) as one unit (problems/output_folder.hpp), and
// each written file is printed. Bad input — a missing folder, one with none of these files, a
// malformed CSV, a field that is not a number — is a SceneError naming the file, the line and
// the column; nothing is written then.

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <vector>

#include "plot.hpp"
#include "recorded_run.hpp"

namespace liedyn {

// loss.png's plot: `loss` against `iteration` with its running minimum, titled with the
// output folder's name; the normalised loss (loss / loss_scale) on the right when the scale
// is known. `liedyn optimize` writes it with its final unit.
LinePlot loss_plot(const std::vector<double>& iteration, const std::vector<double>& loss,
                   std::optional<double> loss_scale, const std::filesystem::path& folder);

// starts.png's plot of a multi-start's starts.csv (`starts`), titled with the output folder's
// name. `liedyn optimize --starts` writes it with its last starts.csv.
ScatterPlot starts_plot(const CsvTable& starts, const std::filesystem::path& folder);

// Writes the plots of `dir`'s files into `out` (see above); prints one line per file written
// or plot skipped to `report`.
void write_plots(const std::filesystem::path& dir, const std::filesystem::path& out,
                 std::ostream& report);

}  // namespace liedyn

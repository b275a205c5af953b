#include "sweep.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "../lib/so3.hpp"
#include "../solvers/gradient_check.hpp"
#include "analytic.hpp"
#include "bench.hpp"
#include "json_reader.hpp"
#include "optimization.hpp"
#include "parallel.hpp"
#include "output.hpp"
#include "plot.hpp"
#include "scene_settings.hpp"

namespace liedyn {
namespace {

using nlohmann::json;

// What an axis is to the reference (sweep.hpp): a fidelity setting with a finest value, a
// solver setting the reference keeps at the scene's value, or part of the model (a group).
enum class AxisKind {
  kTimeStep,
  kTolerance,
  kMaxIterations,
  kBackend,
  kRotation,
  kIntegrator,
  kLoadSteps,
  kSolverSetting,
  kModel
};

AxisKind classify(const std::string& path, bool static_scene) {
  if (path == "time_step") return AxisKind::kTimeStep;
  if (path == "solver.tolerance") return AxisKind::kTolerance;
  if (path == "solver.max_iterations") return AxisKind::kMaxIterations;
  if (path == "solver.backend") return AxisKind::kBackend;
  if (path == "solver.rotation") return AxisKind::kRotation;
  if (path == "integrator") return AxisKind::kIntegrator;
  if (path == "frames" && static_scene) return AxisKind::kLoadSteps;
  if (path.rfind("solver.", 0) == 0) return AxisKind::kSolverSetting;
  return AxisKind::kModel;
}

// Commas inside brackets or braces belong to a JSON value, not to the list.
std::vector<std::string> split_values(const std::string& text) {
  std::vector<std::string> values(1);
  int depth = 0;
  for (const char ch : text) {
    if (ch == '[' || ch == '{') ++depth;
    if (ch == ']' || ch == '}') --depth;
    if (ch == ',' && depth == 0) {
      values.emplace_back();
    } else {
      values.back() += ch;
    }
  }
  return values;
}

std::string describe(const std::vector<std::string>& names,
                     const std::vector<std::string>& values) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    text += (i > 0 ? " " : "") + names[i] + "=" + values[i];
  }
  return text;
}

// One scene of the grid (or a reference) with the overrides that made it.
struct GridScene {
  std::vector<std::string> settings;
  std::string label;  // "path=value …"
  Scene scene;
};

GridScene make_scene(const json& base, const std::string& source,
                     const std::vector<std::string>& paths,
                     const std::vector<std::string>& values) {
  json root = base;
  for (std::size_t i = 0; i < paths.size(); ++i) {
    set_scene_path(root, paths[i], parse_setting_value(values[i]), source);
  }
  GridScene g;
  g.settings = values;
  g.label = describe(paths, values);
  g.scene = parse_scene(root.dump(), source + " [" + g.label + "]", std::filesystem::path(source).parent_path());
  return g;
}

// Where a frame sits on the common axis of comparisons: time (dynamic) or load fraction.
double frame_position(const Scene& scene, int k) {
  return scene.model.static_equilibrium ? double(k) / std::max(scene.frames, 1)
                                        : k * scene.model.time_step;
}

// The recorded run: states, energy and momentum per completed frame (0 included).
struct Recording {
  TimedRun run;
  std::vector<State> states;
  std::vector<double> energy;
  std::vector<Vector3> momentum;
};

Recording record(const Scene& scene, int repeats) {
  Recording r;
  auto observe = [&](const Simulator& sim) {
    r.states.push_back(sim.state());
    r.energy.push_back(sim.kinetic_energy() + sim.potential_energy());
    r.momentum.push_back(sim.angular_momentum());
  };
  try {
    observe(Simulator(scene.model, scene.solver));
    r.run = time_scene(scene, scene.solver, observe);
    std::vector<double> seconds{r.run.total_seconds};
    for (int i = 1; i < repeats && !r.run.failed; ++i) {
      seconds.push_back(time_scene(scene, scene.solver).total_seconds);
    }
    r.run.total_seconds = median(seconds);
  } catch (const std::exception& e) {  // ModelError: options the Simulator refuses
    r.run.failed = true;
    r.run.failure = e.what();
  }
  return r;
}

void fill_cost(const Scene& scene, const Recording& r, SweepRun& run) {
  run.frames = scene.frames;
  run.frames_completed = r.run.frames;
  run.wall_seconds = r.run.total_seconds;
  run.newton_iterations = r.run.sum.iterations;
  run.factorizations = r.run.sum.factorizations;
  run.unconverged_steps = r.run.unconverged_steps;
  run.failed = r.run.failed;
  run.failure = r.run.failure;
  if (scene.model.static_equilibrium || r.run.frames == 0) return;
  run.energy_drift = run.momentum_drift = 0.0;
  for (std::size_t k = 0; k < r.energy.size(); ++k) {
    run.energy_drift = std::max(run.energy_drift, std::abs(r.energy[k] - r.energy[0]));
    run.momentum_drift = std::max(run.momentum_drift, (r.momentum[k] - r.momentum[0]).norm());
  }
}

// Largest errors over the frames; each starts at NaN and becomes a max once compared.
struct ErrorMax {
  double position = SweepRun::kNaN, orientation = SweepRun::kNaN;
  void point(const Vector3& x, const Vector3& exact) {
    position = std::fmax(position, (x - exact).cwiseAbs().maxCoeff());
  }
  void rotation(const Matrix3& R, const Matrix3& exact) {
    orientation = std::fmax(orientation, so3::distance(R, exact));
  }
};

void against_analytic(const Scene& scene, const Recording& r, SweepRun& run) {
  const std::vector<ExactFrame> exact = exact_trajectory(scene);
  ErrorMax e;
  for (std::size_t k = 0; k < r.states.size() && k < exact.size(); ++k) {
    for (const auto& [i, x] : exact[k].points) e.point(r.states[k].points[i], x);
    for (const auto& [i, R] : exact[k].rotations) e.rotation(r.states[k].rotations[i], R);
  }
  run.position_error = e.position;
  run.orientation_error = e.orientation;
}

// Compares at the run's frames, interpolating the reference between its two nearest frames.
void against_reference(const Scene& scene, const Recording& r, const Scene& reference_scene,
                       const Recording& reference, SweepRun& run) {
  if (reference.states.empty()) return;
  const double unit = frame_position(reference_scene, 1);  // one reference frame
  ErrorMax e;
  for (std::size_t k = 0; k < r.states.size(); ++k) {
    const double j = frame_position(scene, static_cast<int>(k)) / unit;
    std::size_t j0 = static_cast<std::size_t>(std::floor(j + 1e-9));
    double f = j - double(j0);
    if (f < 1e-9) f = 0.0;
    if (j0 >= reference.states.size() || (f > 0.0 && j0 + 1 >= reference.states.size())) break;
    const State& a = reference.states[j0];
    const State& b = reference.states[f > 0.0 ? j0 + 1 : j0];
    const State& q = r.states[k];
    if (q.points.size() != a.points.size() || q.rotations.size() != a.rotations.size()) return;
    for (std::size_t i = 0; i < q.points.size(); ++i) {
      e.point(q.points[i], (1.0 - f) * a.points[i] + f * b.points[i]);
    }
    for (std::size_t i = 0; i < q.rotations.size(); ++i) {
      const Matrix3& Ra = a.rotations[i];
      e.rotation(q.rotations[i], so3::exp(f * so3::log(b.rotations[i] * Ra.transpose())) * Ra);
    }
  }
  run.position_error = e.position;
  run.orientation_error = e.orientation;
}

// A reference gradient: central differences of the reference run's loss.
struct ReferenceGradient {
  Eigen::VectorXd gamma;
  std::vector<int> indices;
  std::vector<double> differences;
  std::string failure;
};

ReferenceGradient reference_gradient(const Scene& scene, int sample) {
  ReferenceGradient g;
  try {
    const DifferentiableSimulation sim = make_differentiable_simulation(scene);
    g.gamma = sim.initial_parameters();
    g.indices = sample_indices(static_cast<int>(g.gamma.size()), sample, 1);
    const GradientCheckOptions defaults;
    g.differences = central_differences(sim, g.gamma, g.indices, defaults.step);
  } catch (const std::exception& e) {
    g.failure = e.what();
  }
  return g;
}

void gradient_error(const Scene& scene, const ReferenceGradient& reference, SweepRun& run) {
  if (!reference.failure.empty() || reference.differences.empty()) return;
  try {
    const DifferentiableSimulation sim = make_differentiable_simulation(scene);
    const Eigen::VectorXd gamma = sim.initial_parameters();
    if (gamma.size() != reference.gamma.size()) return;  // e.g. per-frame controls, other h
    Eigen::VectorXd adjoint;
    const DifferentiableSimulation::Result pass = sim.evaluate(gamma, &adjoint);
    run.gradient_seconds = pass.forward_seconds + pass.backward_seconds;
    double largest = 0.0;
    for (const double d : reference.differences) largest = std::max(largest, std::abs(d));
    const double scale = GradientCheckOptions{}.floor * largest;
    run.gradient_error = 0.0;
    for (std::size_t i = 0; i < reference.indices.size(); ++i) {
      run.gradient_error =
          std::max(run.gradient_error,
                   relative_error(adjoint(reference.indices[i]), reference.differences[i], scale));
    }
  } catch (const std::exception& e) {  // SimulationFailed: an unconverged step, say
    run.failed = true;
    run.failure += std::string(run.failure.empty() ? "" : "; ") + "gradient: " + e.what();
  }
}

// A progress bar on a terminal, else one line per finished task; callable from any thread.
class Progress {
 public:
  Progress(std::ostream* out, bool bar, int total) : out_(out), bar_(bar), total_(total) {}
  void start(const std::string& what) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (out_ == nullptr || !bar_) return;
    const int width = 30;
    const int filled = total_ > 0 ? width * done_ / total_ : width;
    *out_ << "\r[" << std::string(filled, '#') << std::string(width - filled, '.') << "] " << done_
          << "/" << total_ << " " << what << "\033[K" << std::flush;
  }
  void finish(const std::string& what, double seconds) {
    const std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    if (out_ == nullptr) return;
    if (bar_) {
      if (done_ == total_) *out_ << "\r\033[K" << std::flush;
      return;
    }
    *out_ << "sweep " << done_ << "/" << total_ << ": " << what << " (" << std::setprecision(3)
          << seconds << " s)\n";
  }

 private:
  std::mutex mutex_;
  std::ostream* out_;
  bool bar_;
  int total_, done_ = 0;
};

// Overrides of the reference of a group of runs (see sweep.hpp).
std::vector<std::pair<std::string, std::string>> reference_overrides(
    const std::vector<SweepAxis>& axes, const std::vector<AxisKind>& kinds,
    const std::vector<const GridScene*>& group, int refinement) {
  std::vector<std::pair<std::string, std::string>> overrides;
  auto number = [](double x) {
    std::ostringstream os;
    os << std::setprecision(15) << x;  // 15: h/4 and tolerance/100 without binary noise
    return os.str();
  };
  const Scene& first = group.front()->scene;
  double h = first.model.time_step, duration = 0.0, tolerance = first.solver.tolerance;
  int iterations = first.solver.max_iterations, load_steps = first.frames;
  for (const GridScene* g : group) {
    h = std::min(h, g->scene.model.time_step);
    duration = std::max(duration, g->scene.frames * g->scene.model.time_step);
    tolerance = std::min(tolerance, g->scene.solver.tolerance);
    iterations = std::max(iterations, g->scene.solver.max_iterations);
    load_steps = std::max(load_steps, g->scene.frames);
  }
  for (std::size_t a = 0; a < axes.size(); ++a) {
    switch (kinds[a]) {
      case AxisKind::kTimeStep: {
        const double h_ref = h / refinement;
        overrides.emplace_back("time_step", number(h_ref));
        if (!first.model.static_equilibrium) {
          // As a number, not cast to int first: a grid whose reference would take more
          // steps than a scene may is refused by the scene's own check, naming it.
          overrides.emplace_back("frames", number(std::ceil(duration / h_ref - 1e-9)));
        }
        break;
      }
      case AxisKind::kTolerance:
        overrides.emplace_back("solver.tolerance", number(tolerance / 100));
        break;
      case AxisKind::kMaxIterations:
        overrides.emplace_back("solver.max_iterations", std::to_string(iterations));
        break;
      case AxisKind::kBackend:  // Newton with lie below, whatever the axis says
      case AxisKind::kRotation:
        break;
      case AxisKind::kIntegrator:
        // One reference for every integrator on the axis, the most accurate one's: a backward
        // Euler reference at h/4 is itself first-order wrong, and each integrator measured
        // against its own would hide that (docs/design.md §14); fox_goodwin's, where the axis
        // has it (fourth order in the phase of points, §14.2), errs less than the trapezoidal
        // rule's at the same h.
        overrides.emplace_back("integrator",
                               std::any_of(group.begin(), group.end(),
                                           [](const GridScene* g) {
                                             return g->scene.model.integrator == Integrator::kFoxGoodwin;
                                           })
                                   ? "fox_goodwin"
                                   : "trapezoidal");
        break;
      case AxisKind::kLoadSteps:
        overrides.emplace_back("frames", std::to_string(load_steps));
        break;
      case AxisKind::kModel:
        // With h on the grid, the reference's frames cover the group's longest run instead.
        if (axes[a].path == "frames" &&
            std::count(kinds.begin(), kinds.end(), AxisKind::kTimeStep) > 0)
          break;
        overrides.emplace_back(axes[a].path, group.front()->settings[a]);
        break;
      case AxisKind::kSolverSetting:
        break;  // the scene's own value
    }
  }
  // Our Newton solver on the exact Lie Hessian: the one that reaches tight tolerances on
  // every scene (Ceres stalls near round-off, README "Back-ends").
  overrides.emplace_back("solver.backend", "newton");
  overrides.emplace_back("solver.rotation", "lie");
  return overrides;
}

}  // namespace

SweepAxis parse_sweep_axis(const std::string& text) {
  const auto split = split_setting(text);
  if (!split) throw std::invalid_argument("--set " + text + ": expected PATH=VALUE[,VALUE…]");
  SweepAxis axis{split->first, split_values(split->second)};
  for (const std::string& v : axis.values) {
    if (v.empty()) throw std::invalid_argument("--set " + text + ": empty value");
  }
  return axis;
}

SweepResult run_sweep(const std::string& scene_text, const std::string& source,
                      const SweepOptions& options) {
  if (options.reference_refinement < 1 || options.gradient_sample < 0 || options.repeats < 1 ||
      options.jobs < 1 || options.share.count < 1 || options.share.index < 0 ||
      options.share.index >= options.share.count || options.other_processes < 0) {
    throw std::invalid_argument(
        "sweep: reference_refinement ≥ 1, gradient_sample ≥ 0, repeats ≥ 1, jobs ≥ 1, "
        "0 ≤ share index < share count, other_processes ≥ 0");
  }
  const Scene base_scene = parse_scene(scene_text, source);  // its errors name the file itself
  const json base = json::parse(scene_text);
  const bool static_scene = base_scene.model.static_equilibrium;
  SweepResult result;
  result.scene = source;
  std::vector<AxisKind> kinds;
  bool frames_axis = false, time_step_axis = false;
  std::size_t time_step_index = 0;
  for (const SweepAxis& axis : options.axes) {
    if (std::find(result.axis_names.begin(), result.axis_names.end(), axis.path) !=
        result.axis_names.end()) {
      throw SceneError(source, "--set " + axis.path, "is given twice");
    }
    result.axis_names.push_back(axis.path);
    kinds.push_back(classify(axis.path, static_scene));
    frames_axis |= axis.path == "frames";
    if (axis.path == "time_step") {
      time_step_axis = true;
      time_step_index = result.axis_names.size() - 1;
    }
  }
  // With h on the grid, frames follow it so that every run covers the scene's duration.
  std::vector<std::string> paths = result.axis_names;
  const bool rescale = time_step_axis && !frames_axis && !static_scene;
  if (rescale) {
    paths.push_back("frames");
    result.notes.push_back("frames = round(T/h) for the scene's duration T = " +
                           format_number(base_scene.frames * base_scene.model.time_step, 6) + " s");
  }

  // Every grid point, parsed before anything runs.
  std::vector<GridScene> grid;
  std::vector<std::size_t> at(options.axes.size(), 0);
  std::size_t count = 1;
  for (const SweepAxis& axis : options.axes) count *= axis.values.size();
  for (std::size_t n = 0; n < count; ++n) {
    std::vector<std::string> values;
    for (std::size_t a = 0; a < options.axes.size(); ++a)
      values.push_back(options.axes[a].values[at[a]]);
    if (rescale) {
      const json h = parse_setting_value(values[time_step_index]);
      const double frames =
          h.is_number() && h.get<double>() > 0.0
              ? std::round(base_scene.frames * base_scene.model.time_step / h.get<double>())
              : 1.0;  // a bad h: parse_scene names it
      values.push_back(std::to_string(static_cast<long long>(std::max(frames, 1.0))));
    }
    GridScene g = make_scene(base, source, paths, values);
    g.settings.resize(options.axes.size());
    grid.push_back(std::move(g));
    // The first axis outermost: count up from the last.
    for (std::size_t a = options.axes.size(); a-- > 0;) {
      if (++at[a] < options.axes[a].values.size()) break;
      at[a] = 0;
    }
  }

  // Groups of runs that share a reference: the same values on every model axis.
  // In grid order of their first run.
  std::vector<std::pair<std::string, std::vector<std::size_t>>> groups;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    std::string key;
    for (std::size_t a = 0; a < kinds.size(); ++a) {
      if (kinds[a] == AxisKind::kModel) key += grid[i].settings[a] + "\n";
    }
    auto group = std::find_if(groups.begin(), groups.end(),
                              [&](const auto& g) { return g.first == key; });
    if (group == groups.end()) group = groups.insert(groups.end(), {key, {}});
    group->second.push_back(i);
  }
  const bool analytic = base_scene.analytic != AnalyticSolution::kNone;
  const bool optimization = base_scene.optimization.has_value();
  struct Reference {
    GridScene scene;
    Recording recording;
    ReferenceGradient gradient;
  };
  std::vector<Reference> references;
  std::vector<std::size_t> reference_of(grid.size());
  for (const auto& [key, members] : groups) {
    std::vector<const GridScene*> group;
    for (const std::size_t i : members) group.push_back(&grid[i]);
    std::vector<std::string> ref_paths, ref_values;
    for (const auto& [path, value] :
         reference_overrides(options.axes, kinds, group, options.reference_refinement)) {
      ref_paths.push_back(path);
      ref_values.push_back(value);
    }
    for (const std::size_t i : members) reference_of[i] = references.size();
    references.push_back({make_scene(base, source + " reference", ref_paths, ref_values), {}, {}});
  }
  // Every scene parses, references included: only now may the driver create its folder.
  if (options.before_runs) options.before_runs();
  if (analytic) {
    result.notes.push_back(std::string("errors against the scene's analytic solution \"") +
                           to_string(base_scene.analytic) + "\" (problems/analytic.hpp)");
  } else {
    result.notes.push_back(
        "errors against reference runs at the grid's finest settings (below: a swept time step / " +
        std::to_string(options.reference_refinement) +
        ", a swept tolerance / 100, Newton with lie); the finest runs' errors read low");
  }

  result.grid_size = static_cast<int>(grid.size());
  result.share = options.share;
  nlohmann::ordered_json identity = {{"scene", base_scene.identity},
                                     {"axes", nlohmann::ordered_json::array()},
                                     {"reference_refinement", options.reference_refinement},
                                     {"gradient_sample", options.gradient_sample},
                                     {"repeats", options.repeats}};
  for (const SweepAxis& axis : options.axes) {
    identity["axes"].push_back({{"path", axis.path}, {"values", axis.values}});
  }
  result.identity = identity.dump();

  // What a checkpoint holds is kept (sweep.hpp).
  std::map<int, SweepRun> kept_runs, kept_references;
  if (options.resume != nullptr) {
    const SweepResult& done = *options.resume;
    if (done.identity != result.identity) {
      throw SceneError(options.resume_source, "identity",
                       "belongs to another sweep (scene content, axes or options differ): "
                       "start without --resume, or with the sweep's own command");
    }
    for (const SweepRun& r : done.runs) kept_runs[r.index] = r;
    for (const SweepRun& r : done.references) kept_references[r.index] = r;
  }

  // This process's grid points, the ones left to run, and the references they need.
  const bool simulate_references = !analytic;
  const bool compute_references = simulate_references || optimization;
  std::vector<int> mine, runs_left, references_left;
  std::vector<bool> group_in_share(references.size(), false), group_needed(references.size(), false);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (static_cast<int>(i) % options.share.count != options.share.index) continue;
    mine.push_back(static_cast<int>(i));
    group_in_share[reference_of[i]] = true;
    if (kept_runs.count(static_cast<int>(i)) == 0) {
      runs_left.push_back(static_cast<int>(i));
      group_needed[reference_of[i]] = true;
    }
  }
  for (std::size_t r = 0; r < references.size() && compute_references; ++r) {
    if (group_in_share[r] && (group_needed[r] || kept_references.count(static_cast<int>(r)) == 0)) {
      references_left.push_back(static_cast<int>(r));
    }
  }

  // Finished rows by index; the result so far is built from them in index order.
  std::map<int, SweepRun> finished_runs = kept_runs, finished_references;
  for (std::size_t r = 0; r < references.size(); ++r) {
    const auto kept = kept_references.find(static_cast<int>(r));
    if (group_in_share[r] && kept != kept_references.end() &&
        std::find(references_left.begin(), references_left.end(), int(r)) == references_left.end()) {
      finished_references.insert(*kept);
    }
  }
  std::mutex finished_mutex;
  const auto so_far = [&] {
    SweepResult partial = result;
    for (const auto& [index, run] : finished_references) partial.references.push_back(run);
    for (const auto& [index, run] : finished_runs) {
      if (std::binary_search(mine.begin(), mine.end(), index)) partial.runs.push_back(run);
    }
    return partial;
  };
  const auto finished = [&](std::map<int, SweepRun>& rows, SweepRun row) {
    const std::lock_guard<std::mutex> lock(finished_mutex);
    rows[row.index] = std::move(row);
    if (options.on_finished) options.on_finished(so_far());
  };

  Progress progress(options.progress, options.progress_bar,
                    static_cast<int>(references_left.size() + runs_left.size()));
  using Clock = std::chrono::steady_clock;
  const auto sharing = [&](std::size_t tasks) {
    return std::min(options.jobs, static_cast<int>(tasks)) + options.other_processes;
  };
  parallel_for(static_cast<int>(references_left.size()), options.jobs, [&](int t) {
    const int r = references_left[t];
    Reference& ref = references[r];
    const auto start = Clock::now();
    const std::string what = "reference " + ref.scene.label;
    progress.start(what);
    if (simulate_references) ref.recording = record(ref.scene.scene, 1);
    if (optimization) ref.gradient = reference_gradient(ref.scene.scene, options.gradient_sample);
    progress.finish(what, std::chrono::duration<double>(Clock::now() - start).count());
    SweepRun summary;
    summary.index = r;
    summary.settings = {ref.scene.label};
    summary.reference = "(reference)";
    summary.parallel_runs = sharing(references_left.size());
    fill_cost(ref.scene.scene, ref.recording, summary);
    if (!ref.gradient.failure.empty()) {
      summary.failed = true;
      summary.failure += std::string(summary.failure.empty() ? "" : "; ") +
                         "reference gradient: " + ref.gradient.failure;
    }
    finished(finished_references, std::move(summary));
  });

  parallel_for(static_cast<int>(runs_left.size()), options.jobs, [&](int t) {
    const int i = runs_left[t];
    const GridScene& g = grid[i];
    const Reference& ref = references[reference_of[i]];
    const auto start = Clock::now();
    const std::string what = describe(result.axis_names, g.settings);
    progress.start(what);
    SweepRun run;
    run.index = i;
    run.settings = g.settings;
    run.parallel_runs = sharing(runs_left.size());
    const Recording r = record(g.scene, options.repeats);
    fill_cost(g.scene, r, run);
    // Errors over the frames the run completed: none (NaN) when its first step failed.
    if (analytic) {
      run.reference = std::string("analytic ") + to_string(base_scene.analytic);
      if (r.run.frames > 0) against_analytic(g.scene, r, run);
    } else {
      run.reference = ref.scene.label.empty() ? "the scene's settings" : ref.scene.label;
      if (r.run.frames > 0) against_reference(g.scene, r, ref.scene.scene, ref.recording, run);
    }
    if (optimization) gradient_error(g.scene, ref.gradient, run);
    progress.finish(what, std::chrono::duration<double>(Clock::now() - start).count());
    finished(finished_runs, std::move(run));
  });
  return so_far();
}

namespace {

// The metrics plotted against wall time, and the CSV's accuracy columns.
struct Metric {
  const char* key;
  const char* label;
  double SweepRun::*value;
};
constexpr Metric kMetrics[] = {
    {"position_error", "position error [m]", &SweepRun::position_error},
    {"orientation_error", "orientation error [rad]", &SweepRun::orientation_error},
    {"energy_drift", "energy drift [J]", &SweepRun::energy_drift},
    {"momentum_drift", "angular momentum drift [kg m²/s]", &SweepRun::momentum_drift},
    {"gradient_error", "gradient relative error", &SweepRun::gradient_error},
};

// The error the `front` marks refer to (sweep.hpp): position, else orientation, else gradient.
const Metric& primary_metric(const SweepResult& result) {
  for (const Metric& m : {kMetrics[0], kMetrics[1], kMetrics[4]}) {
    if (std::any_of(result.runs.begin(), result.runs.end(),
                    [&](const SweepRun& r) { return r.*m.value > 0.0; })) {
      for (const Metric& k : kMetrics) {
        if (k.value == m.value) return k;
      }
    }
  }
  return kMetrics[0];
}

// Runs on the (wall time, metric) Pareto front; failed runs never are.
std::vector<bool> on_front(const SweepResult& result, double SweepRun::*metric) {
  std::vector<PlotPoint> points;
  for (const SweepRun& r : result.runs) {
    points.push_back({r.failed ? SweepRun::kNaN : r.wall_seconds, r.*metric, "", 0});
  }
  std::vector<bool> front(result.runs.size(), false);
  for (const std::size_t i : pareto_front(points)) front[i] = true;
  return front;
}

}  // namespace

namespace {

using ordered_json = nlohmann::ordered_json;

// JSON has no NaN or infinity: NaN (a metric not defined) as null, ±∞ (a run that blew up)
// as the strings "inf" and "-inf".
ordered_json number_or_null(double x) {
  if (std::isnan(x)) return nullptr;
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  return x;
}

ordered_json run_to_json(const SweepRun& r) {
  return {{"index", r.index},
          {"settings", r.settings},
          {"frames", r.frames},
          {"frames_completed", r.frames_completed},
          {"wall_seconds", number_or_null(r.wall_seconds)},
          {"parallel_runs", r.parallel_runs},
          {"newton_iterations", r.newton_iterations},
          {"factorizations", r.factorizations},
          {"unconverged_steps", r.unconverged_steps},
          {"position_error", number_or_null(r.position_error)},
          {"orientation_error", number_or_null(r.orientation_error)},
          {"energy_drift", number_or_null(r.energy_drift)},
          {"momentum_drift", number_or_null(r.momentum_drift)},
          {"gradient_error", number_or_null(r.gradient_error)},
          {"gradient_seconds", number_or_null(r.gradient_seconds)},
          {"reference", r.reference},
          {"failed", r.failed},
          {"failure", r.failure}};
}

using scene_json::ObjectReader;

// A metric as number_or_null writes it.
double metric(ObjectReader& r, const std::string& key) {
  const scene_json::json& v = r.get(key);
  if (v.is_null()) return SweepRun::kNaN;
  if (v == "inf") return std::numeric_limits<double>::infinity();
  if (v == "-inf") return -std::numeric_limits<double>::infinity();
  return r.to_number(v, r.field(key));
}

std::vector<std::string> strings(ObjectReader& r, const std::string& key) {
  std::vector<std::string> out;
  const scene_json::json& values = r.array(key);
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i].is_string()) r.fail(r.field(key) + "[" + std::to_string(i) + "]", "must be a string");
    out.push_back(values[i].get<std::string>());
  }
  return out;
}

bool flag(ObjectReader& r, const std::string& key) {
  if (!r.has(key)) r.fail(r.field(key), "is required but missing");
  return r.boolean(key, false);
}

SweepRun run_from_json(const scene_json::json& value, const std::string& source, const std::string& path) {
  ObjectReader f(value, path, source,
                 {"index", "settings", "frames", "frames_completed", "wall_seconds", "parallel_runs",
                  "newton_iterations", "factorizations", "unconverged_steps", "position_error",
                  "orientation_error", "energy_drift", "momentum_drift", "gradient_error",
                  "gradient_seconds", "reference", "failed", "failure"});
  SweepRun r;
  r.index = f.integer("index", 0);
  r.settings = strings(f, "settings");
  r.frames = f.integer("frames", 0);
  r.frames_completed = f.integer("frames_completed", 0);
  r.wall_seconds = metric(f, "wall_seconds");
  r.parallel_runs = f.integer("parallel_runs", 1);
  r.newton_iterations = f.integer("newton_iterations", 0);
  r.factorizations = f.integer("factorizations", 0);
  r.unconverged_steps = f.integer("unconverged_steps", 0);
  r.position_error = metric(f, "position_error");
  r.orientation_error = metric(f, "orientation_error");
  r.energy_drift = metric(f, "energy_drift");
  r.momentum_drift = metric(f, "momentum_drift");
  r.gradient_error = metric(f, "gradient_error");
  r.gradient_seconds = metric(f, "gradient_seconds");
  r.reference = f.string("reference");
  r.failed = flag(f, "failed");
  r.failure = f.string("failure");
  f.finish();
  return r;
}

constexpr const char* kSweepFormat = "liedyn sweep 1";

}  // namespace

ordered_json sweep_to_json(const SweepResult& result) {
  ordered_json j = {{"format", kSweepFormat},
                    {"scene", result.scene},
                    {"identity", ordered_json::parse(result.identity)},
                    {"grid_size", result.grid_size},
                    {"share", {{"index", result.share.index}, {"count", result.share.count}}},
                    {"axis_names", result.axis_names},
                    {"notes", result.notes},
                    {"references", ordered_json::array()},
                    {"runs", ordered_json::array()}};
  for (const SweepRun& r : result.references) j["references"].push_back(run_to_json(r));
  for (const SweepRun& r : result.runs) j["runs"].push_back(run_to_json(r));
  return j;
}

SweepResult sweep_from_json(const ordered_json& value, const std::string& source) {
  const scene_json::json plain = value;  // the scene files' reader, with its field paths
  ObjectReader f(plain, "", source,
                 {"format", "scene", "identity", "grid_size", "share", "axis_names", "notes", "references", "runs"});
  if (f.string("format") != kSweepFormat) {
    f.fail("format", std::string("is not \"") + kSweepFormat + "\"");
  }
  SweepResult result;
  result.scene = f.string("scene");
  f.get("identity");
  result.identity = value.at("identity").dump();  // in the order written (the reader's json sorts keys)
  result.grid_size = f.integer("grid_size", 0);
  ObjectReader share(f.get("share"), "share", source, {"index", "count"});
  result.share = {share.integer("index", 0), share.integer("count", 1)};
  if (result.share.index >= result.share.count) f.fail("share", "must have 0 ≤ index < count");
  result.axis_names = strings(f, "axis_names");
  result.notes = strings(f, "notes");
  for (const char* key : {"references", "runs"}) {
    const bool run = std::string(key) == "runs";
    const scene_json::json& rows = f.array(key);
    std::vector<SweepRun>& out = run ? result.runs : result.references;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::string path = std::string(key) + "[" + std::to_string(i) + "]";
      out.push_back(run_from_json(rows[i], source, path));
      if (run ? out.back().index >= result.grid_size || out.back().settings.size() != result.axis_names.size()
              : out.back().settings.size() != 1) {
        f.fail(path, run ? "is not a grid point of this sweep (index or settings)"
                         : "is not a reference (its settings are one label)");
      }
    }
  }
  f.finish();
  return result;
}

SweepResult merge_sweeps(const std::vector<SweepResult>& parts, const std::vector<std::string>& sources,
                         bool complete) {
  if (parts.empty()) throw std::invalid_argument("merge_sweeps: no parts");
  const SweepResult& first = parts.front();
  std::set<int> shares;
  SweepResult merged = first;
  merged.share = {};
  merged.runs.clear();
  merged.references.clear();
  std::map<int, SweepRun> runs, references;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const SweepResult& part = parts[p];
    const std::string& source = sources.at(p);
    if (part.identity != first.identity || part.grid_size != first.grid_size) {
      throw SceneError(source, "identity", "is another sweep's than " + sources.front() + "'s");
    }
    if (part.share.count != first.share.count) {
      throw SceneError(source, "share", "has count " + std::to_string(part.share.count) + ", " +
                                            sources.front() + " " + std::to_string(first.share.count));
    }
    if (!shares.insert(part.share.index).second) {
      throw SceneError(source, "share", "index " + std::to_string(part.share.index) + " is given twice");
    }
    for (const SweepRun& r : part.runs) {
      if (r.index % part.share.count != part.share.index || !runs.emplace(r.index, r).second) {
        throw SceneError(source, "runs", "grid point " + std::to_string(r.index) + " is not this share's");
      }
    }
    for (const SweepRun& r : part.references) references.emplace(r.index, r);
  }
  if (complete) {
    int missing = 0;  // the first share absent (the set is ordered)
    for (const int s : shares) missing += s == missing ? 1 : 0;
    if (missing < first.share.count) {
      throw SceneError(sources.front(), "share",
                       "share " + std::to_string(missing) + " of " + std::to_string(first.share.count) + " is missing");
    }
    for (int i = 0; i < first.grid_size; ++i) {
      if (runs.count(i) == 0) {
        throw SceneError(sources[static_cast<std::size_t>(std::find_if(parts.begin(), parts.end(), [&](const SweepResult& part) {
                                                            return i % part.share.count == part.share.index;
                                                          }) - parts.begin())],
                         "runs", "grid point " + std::to_string(i) + " is missing (an unfinished shard?)");
      }
    }
  }
  for (const auto& [index, run] : references) merged.references.push_back(run);
  for (const auto& [index, run] : runs) merged.runs.push_back(run);
  return merged;
}

std::string sweep_csv(const SweepResult& result) {
  std::ostringstream os;
  for (const std::string& name : result.axis_names) os << csv_field(name) << ",";
  os << "frames_requested,frames_completed,wall_seconds,parallel_runs,newton_iterations,"
        "factorizations,unconverged_steps";
  for (const Metric& m : kMetrics) os << "," << m.key;
  os << ",gradient_seconds,pareto,failed,reference,failure\n";
  const std::vector<bool> front = on_front(result, primary_metric(result).value);
  for (std::size_t i = 0; i < result.runs.size(); ++i) {
    const SweepRun& r = result.runs[i];
    for (const std::string& v : r.settings) os << csv_field(v) << ",";
    os << r.frames << "," << r.frames_completed << "," << format_number(r.wall_seconds, 9) << ","
       << r.parallel_runs << "," << r.newton_iterations << "," << r.factorizations << "," << r.unconverged_steps;
    for (const Metric& m : kMetrics) os << "," << format_number(r.*m.value, 9);
    os << "," << format_number(r.gradient_seconds, 9) << "," << (front[i] ? 1 : 0) << ","
       << (r.failed ? 1 : 0) << "," << csv_field(r.reference) << "," << csv_field(r.failure)
       << "\n";
  }
  return os.str();
}

std::string format_sweep(const SweepResult& result) {
  std::ostringstream os;
  os << "sweep of " << result.scene << ": " << result.runs.size() << " runs\n";
  for (const std::string& note : result.notes) os << "  " << note << "\n";
  for (const SweepRun& ref : result.references) {
    os << "  reference " << ref.settings.front() << ": " << format_number(ref.wall_seconds, 4)
       << " s, " << ref.frames_completed << "/" << ref.frames << " frames"
       << (ref.unconverged_steps > 0
               ? ", " + std::to_string(ref.unconverged_steps) + " unconverged steps"
               : std::string())
       << (ref.failed ? ", FAILED: " + ref.failure : std::string()) << "\n";
  }
  const std::vector<bool> front = on_front(result, primary_metric(result).value);
  std::vector<std::string> headings = result.axis_names;
  for (const char* h : {"seconds", "iter", "unconv", "Δx max [m]", "ΔR max [rad]",
                        "energy drift [J]", "grad err", "front"}) {
    headings.emplace_back(h);
  }
  std::vector<std::vector<std::string>> lines{headings};
  for (std::size_t i = 0; i < result.runs.size(); ++i) {
    const SweepRun& r = result.runs[i];
    std::vector<std::string> line = r.settings;
    line.push_back(format_number(r.wall_seconds, 4));
    line.push_back(std::to_string(r.newton_iterations));
    line.push_back(std::to_string(r.unconverged_steps));
    for (const double v :
         {r.position_error, r.orientation_error, r.energy_drift, r.gradient_error}) {
      line.push_back(std::isnan(v) ? "-" : format_number(v, 3));
    }
    line.push_back(r.failed ? "FAILED" : front[i] ? "*" : "");
    lines.push_back(line);
  }
  std::vector<std::size_t> widths(headings.size(), 0);
  auto width = [](const std::string& s) {  // code points, for Δ
    return static_cast<std::size_t>(std::count_if(s.begin(), s.end(), [](char ch) {
      return (static_cast<unsigned char>(ch) & 0xC0) != 0x80;
    }));
  };
  for (const auto& line : lines) {
    for (std::size_t c = 0; c < line.size(); ++c) widths[c] = std::max(widths[c], width(line[c]));
  }
  for (const auto& line : lines) {
    for (std::size_t c = 0; c < line.size(); ++c) {
      os << (c > 0 ? "  " : "") << std::string(widths[c] - width(line[c]), ' ') << line[c];
    }
    os << "\n";
  }
  os << "front: on the Pareto front of wall time against " << primary_metric(result).key << "\n";
  for (const SweepRun& r : result.runs) {
    if (r.failed)
      os << "failed: " << describe(result.axis_names, r.settings) << ": " << r.failure << "\n";
  }
  return os.str();
}

void write_sweep(const SweepResult& result, OutputFolder& out) {
  out.add("sweep.csv") << sweep_csv(result);
  out.add("sweep.json") << sweep_to_json(result).dump(1) << "\n";
  for (const Metric& m : kMetrics) {
    if (std::none_of(result.runs.begin(), result.runs.end(),
                     [&](const SweepRun& r) { return std::isfinite(r.*m.value) && r.*m.value > 0.0; })) {
      continue;
    }
    ScatterPlot plot;
    plot.title = std::string(m.label) +
                 " against cost: " + std::filesystem::path(result.scene).filename().string();
    if (result.axis_names.size() > 1) {
      plot.title += " (labels: ";
      for (std::size_t a = 1; a < result.axis_names.size(); ++a) {
        plot.title += (a > 1 ? ", " : "") + result.axis_names[a];
      }
      plot.title += ")";
    }
    plot.x_label = "wall time of the time steps [s]";
    plot.y_label = m.label;
    // One series per value of the first axis; the other axes' values label the points.
    std::vector<std::string> series;
    for (const SweepRun& r : result.runs) {
      const std::string name =
          result.axis_names.empty() ? "runs" : result.axis_names[0] + "=" + r.settings[0];
      auto it = std::find(series.begin(), series.end(), name);
      if (it == series.end()) it = series.insert(series.end(), name);
      std::string label;
      for (std::size_t a = 1; a < r.settings.size(); ++a)
        label += (a > 1 ? " " : "") + r.settings[a];
      plot.points.push_back({r.failed ? SweepRun::kNaN : r.wall_seconds, r.*m.value, label,
                             static_cast<int>(it - series.begin())});
    }
    plot.series_names = series;
    const std::string name = std::string(m.key) + "_vs_time.png";
    write_png(plot, out.add(name), (out.path() / name).string());
  }
  out.commit();
}

}  // namespace liedyn

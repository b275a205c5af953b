// liedyn — command-line driver.
//   liedyn simulate SCENE.json --out DIR [--allow-unconverged] [--quiet] [--ipopt-log FILE]
//                  [--every N]   (trajectory.csv every N-th frame and the last)
//   liedyn bench SCENE.json [--repeat N] [--json]     (cost per Newton iteration; no files)
//   liedyn compare SCENE.json [--backends newton,ceres,ipopt] [--rotations lie,rotvec,quat]
//                  [--csv | --json] [--repeat N] [--frames-csv FILE] [--condition-every N]
//                  (one row per backend × rotation, backends outer; the first row is the
//                  reference for deviations; without --backends the scene's back-end, without
//                  --rotations the scene's parameterisation if --backends is given, else all
//                  three; a row whose step fails is marked failed, the others still run)
//   liedyn exp-jacobian --out FILE [--samples N]   (paper Fig. 3 data: σ of ∂vec(exp r)/∂r)
//   liedyn gradcheck SCENE.json [--sample N] [--seed S] [--tolerance T] [--step E] [--verbose]
//                  [--parameters DIR/parameters.csv]
//                  (adjoint gradient against central differences; last line
//                  "gradcheck: max_rel_error=<float> params=<int> tolerance=<float>"; exit 0
//                  within tolerance, 1 otherwise)
//   liedyn sweep SCENE.json --set PATH=V1,V2,… [--set …] [--rotations …] [--backends …]
//                  --out DIR [--refine N] [--gradient-sample N] [--repeat N] [--quiet]
//                  [-j N] [--shard I/N] [--resume]
//                  (every combination of the settings, each measured for cost and accuracy
//                  against the scene's analytic solution or a finer reference run; writes
//                  DIR/sweep.csv, sweep.json and DIR/*_vs_time.png; exit 4 if a run failed;
//                  problems/sweep_command.hpp)
//   liedyn sweep-merge SHARD_DIR… --out DIR   (the shards of --shard joined)
//   liedyn view RUN_DIR   (RUN_DIR/view.html: the run animated in one offline page;
//                  problems/view.hpp)
//   liedyn plot DIR [--out OUT]   (PNGs of a run's frames.csv, an optimisation's history.csv
//                  and starts.csv, written into OUT, default DIR; problems/run_plots.hpp)
//   liedyn export RUN_DIR --format gltf|obj|vtk [--every N] [--out DIR]
//                  (the run as run.glb, frame_NNNNNN.obj, or frame_NNNNNN.vtp + run.pvd, in
//                  DIR or RUN_DIR/export-FORMAT; problems/export.hpp)
//   liedyn optimize SCENE.json --out DIR [--optimizer nlopt-lbfgs|ceres-lbfgs|ipopt-lbfgs]
//                  [--max-iterations N] [--resume] [--starts K [--seed S] [--spread σ] [-j N]]
//                  (exit 0 target reached, 3 stopped short of it, 4 failed;
//                  multi-start: problems/multistart.hpp)
// Under mpirun (liedyn built with MPI), sweep and optimize --starts share their runs among
// the ranks; rank 0 writes the outputs (problems/process_group.hpp).
// simulate, bench, compare, gradcheck and optimize take [--set PATH=VALUE …]: values over the
// scene file's (problems/scene_settings.hpp), e.g. --set integrator=trapezoidal.
// Exit status: 0 success; 2 bad input (scene or options), nothing written; 3 some steps ended
// at max_iterations (outputs written; --allow-unconverged makes this 0); 4 a step failed
// (outputs written up to it; compare: a row failed, all rows printed); 1
// other errors (I/O).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <memory>
#include <optional>
#include <string_view>

#include "analysis.hpp"
#include "bench.hpp"
#include "compare.hpp"
#include "export.hpp"
#include "optimization.hpp"
#include "output.hpp"
#include "parallel.hpp"
#include "process_group.hpp"
#include "memory_budget.hpp"
#include "scene_settings.hpp"
#include "run.hpp"
#include "scene_checks.hpp"
#include "sweep_command.hpp"
#include "run_plots.hpp"
#include "view.hpp"

#include <unistd.h>

namespace {

// The values of a list option (--backends, --rotations) through `parse` (parse_backend,
// parse_rotation) into `out`; false, after a message naming the option and the value, for an
// unknown name.
template <class T>
bool parse_names(const std::vector<std::string>& names,
                 std::optional<T> (*parse)(std::string_view), const char* option,
                 const char* what, const char* expected, std::vector<T>& out) {
  for (const std::string& name : names) {
    const std::optional<T> value = parse(name);
    if (!value) {
      std::cerr << "liedyn: " << option << ": unknown " << what << " \"" << name
                << "\" (expected " << expected << ")\n";
      return false;
    }
    out.push_back(*value);
  }
  return true;
}

void print_warnings(const liedyn::Scene& scene) {
  for (const std::string& w : liedyn::scene_warnings(scene)) {
    std::cerr << "liedyn: warning: " << scene.source << ": " << w << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"liedyn: rigid-body dynamics with Lie derivatives"};
  app.require_subcommand(1);

  std::string scene_file, out_dir;
  bool allow_unconverged = false, quiet = false;
  CLI::App* simulate = app.add_subcommand("simulate", "Simulate a scene file");
  simulate->add_option("scene", scene_file, "Scene file (JSON)")->required();
  simulate->add_option("--out", out_dir, "Output directory")->required();
  simulate->add_flag("--allow-unconverged", allow_unconverged,
                     "Exit 0 even if steps end at max_iterations");
  simulate->add_flag("--quiet", quiet, "No progress on stderr");
  std::string ipopt_log;
  simulate->add_option("--ipopt-log", ipopt_log, "Ipopt's log file (the ipopt back-end only)");
  int every = 1;
  simulate->add_option("--every", every,
                       "Write every N-th frame (and the last) to trajectory.csv; frames.csv keeps every frame")
      ->check(CLI::Range(1, 1000000000));

  int repeats = 5;
  bool json = false;
  CLI::App* bench = app.add_subcommand("bench", "Time a scene's Newton iterations (no outputs)");
  bench->add_option("scene", scene_file, "Scene file (JSON)")->required();
  bench->add_option("--repeat", repeats, "Runs to take the median of")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  bench->add_flag("--json", json, "Print one JSON object instead of text");

  std::vector<std::string> backend_names, rotation_names;
  bool csv = false;
  std::string frames_csv;
  int condition_every = 0;
  CLI::App* compare = app.add_subcommand(
      "compare",
      "Run a scene under several back-ends and rotation parameterisations: one row per "
      "backend × rotation (backends outer); deviations are from the first row");
  compare->add_option("scene", scene_file, "Scene file (JSON)")->required();
  compare
      ->add_option("--backends", backend_names,
                   "Back-ends: newton, ceres, ipopt (default: the scene's)")
      ->delimiter(',');
  compare
      ->add_option("--rotations", rotation_names,
                   "Parameterisations: lie, rotvec, quat (default: the scene's with --backends, "
                   "else lie,rotvec,quat); a pair the back-end does not support is a failed row")
      ->delimiter(',');
  int compare_repeats = 3;
  compare->add_option("--repeat", compare_repeats, "Timed runs per row (medians)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  auto* compare_csv_flag = compare->add_flag("--csv", csv, "Print CSV instead of a table");
  compare->add_flag("--json", json, "Print one JSON object instead of a table")
      ->excludes(compare_csv_flag);
  compare->add_option("--frames-csv", frames_csv,
                      "Also write per-frame iterations, gradient norms and condition numbers "
                      "(condition numbers: Newton only)");
  compare->add_option("--condition-every", condition_every,
                      "Newton's condition number every N frames (0: every frame up to 300 DOFs, "
                      "else ~20 frames)")
      ->check(CLI::NonNegativeNumber);
  compare->add_option("--ipopt-log", ipopt_log, "Ipopt's log file (rows of the ipopt back-end)");

  std::string out_file;
  int samples = 361;
  CLI::App* exp_jacobian = app.add_subcommand(
      "exp-jacobian", "Singular values of d vec(exp(r))/dr for |r| in [0, 2 pi] (paper Fig. 3)");
  exp_jacobian->add_option("--out", out_file, "CSV file to write")->required();
  exp_jacobian->add_option("--samples", samples, "Angles, evenly spaced")
      ->check(CLI::Range(2, 1000000))
      ->capture_default_str();

  liedyn::GradientCheckOptions check;
  bool verbose = false;
  CLI::App* gradcheck = app.add_subcommand(
      "gradcheck", "Adjoint gradient of a scene's optimisation against central differences");
  gradcheck->add_option("scene", scene_file, "Scene file (JSON) with an optimization block")
      ->required();
  gradcheck->add_option("--sample", check.sample, "Check this many random parameters (0: all)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  gradcheck->add_option("--seed", check.seed, "Seed of the sample")->capture_default_str();
  gradcheck->add_option("--tolerance", check.tolerance, "Largest relative error accepted")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  gradcheck->add_option("--step", check.step, "Relative finite-difference step")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  gradcheck->add_flag("--verbose", verbose, "One CSV row per checked parameter");
  std::string gradcheck_parameters;
  gradcheck->add_option("--parameters", gradcheck_parameters,
                        "Check at the γ of this parameters.csv (of liedyn optimize), not at γ₀");

  liedyn::OptimizeOptions optimize_options;
  std::string optimizer_name;
  int optimize_iterations = 0;
  CLI::App* optimize = app.add_subcommand(
      "optimize", "Minimise a scene's objective over its parameters (adjoint gradients, L-BFGS)");
  optimize->add_option("scene", scene_file, "Scene file (JSON) with an optimization block")
      ->required();
  optimize->add_option("--out", out_dir, "Output directory")->required();
  optimize->add_option("--optimizer", optimizer_name,
                       "nlopt-lbfgs, ceres-lbfgs or ipopt-lbfgs (default: the scene's)");
  optimize->add_option("--max-iterations", optimize_iterations, "Overrides the scene's")
      ->check(CLI::PositiveNumber);
  optimize->add_flag("--resume", optimize_options.resume,
                     "Continue from DIR/checkpoint.json (multi-start: keep its finished starts)");
  optimize_options.jobs = liedyn::default_jobs();
  optimize->add_option("--starts", optimize_options.starts,
                       "Optimise from K points: the scene's, then K−1 drawn (uniform within "
                       "bounds, else the scene's value + spread·N(0,1)); keeps the best")
      ->check(CLI::Range(1, 1000000));
  optimize->add_option("--seed", optimize_options.seed, "Seed of the drawn starts")
      ->capture_default_str();
  optimize->add_option("--spread", optimize_options.spread,
                       "σ of the drawn starts of unbounded parameters")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  optimize->add_option("-j,--jobs", optimize_options.jobs,
                       "Starts at once (threads; default: the machine's cores)")
      ->check(CLI::Range(1, 1024));

  std::vector<std::string> set_texts;
  liedyn::SweepCommand sweep_command;
  liedyn::SweepOptions& sweep_options = sweep_command.options;
  sweep_options.jobs = liedyn::default_jobs();
  CLI::App* sweep = app.add_subcommand(
      "sweep",
      "Run a scene over a grid of settings, each run measured for cost and for accuracy "
      "(against the scene's analytic solution or a finer reference run)");
  sweep->add_option("scene", scene_file, "Scene file (JSON)")->required();
  sweep->add_option("--set", set_texts,
                    "An axis of the grid: PATH=V1,V2,… (dotted path into the scene, e.g. "
                    "time_step=0.02,0.01 or solver.tolerance=1e-4,1e-8); repeatable");
  sweep
      ->add_option("--rotations", rotation_names,
                   "Parameterisations as an axis (solver.rotation): lie, rotvec, quat")
      ->delimiter(',');
  sweep->add_option("--backends", backend_names,
                    "Back-ends as an axis (solver.backend): newton, ceres, ipopt")
      ->delimiter(',');
  sweep->add_option("--out", out_dir, "Output directory")->required();
  sweep->add_option("--refine", sweep_options.reference_refinement,
                    "Reference time step = smallest on the grid / N")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  sweep->add_option("--gradient-sample", sweep_options.gradient_sample,
                    "Optimisation scenes: parameters checked for the gradient error (0: all)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sweep->add_option("--repeat", sweep_options.repeats, "Timed runs per grid point (median)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  sweep->add_flag("--quiet", quiet, "No progress on stderr");
  sweep->add_option("-j,--jobs", sweep_options.jobs,
                    "Runs at once (threads; default: the machine's cores). Timings meant for "
                    "comparison: -j 1 (the CSV's parallel_runs says how many ran at once)")
      ->check(CLI::Range(1, 1024));
  sweep->add_option("--shard", sweep_command.shard,
                    "I/N: run every N-th grid point from I into OUT/shard-I-of-N (N alone: I "
                    "from $SLURM_ARRAY_TASK_ID); join the shards with sweep-merge");
  sweep->add_flag("--resume", sweep_command.resume,
                  "Keep the runs of OUT/checkpoint.json and run the rest");

  std::string view_dir;
  CLI::App* view = app.add_subcommand(
      "view", "Write RUN_DIR/view.html: one offline page that animates a run (three.js)");
  view->add_option("run_dir", view_dir, "A run's output folder (liedyn simulate --out)")->required();

  std::string plot_dir, plot_out;
  CLI::App* plot = app.add_subcommand(
      "plot",
      "PNG plots of an output folder: a run's energy, iterations, gradient norms, "
      "penetration and momentum; an optimisation's loss");
  plot->add_option("dir", plot_dir, "An output folder (liedyn simulate or optimize --out)")
      ->required();
  plot->add_option("--out", plot_out, "Where to write the PNGs (default: the folder itself)");
  std::string export_dir, export_format, export_out;
  int export_every = 1;
  CLI::App* export_command = app.add_subcommand(
      "export", "Write a run as glTF (run.glb), an OBJ sequence, or VTK PolyData for ParaView");
  export_command->add_option("run_dir", export_dir, "A run's output folder (liedyn simulate --out)")->required();
  export_command->add_option("--format", export_format, "gltf, obj or vtk")
      ->required()
      ->check(CLI::IsMember({"gltf", "obj", "vtk"}));
  export_command->add_option("--every", export_every, "Every N-th written frame (and the last)")
      ->check(CLI::Range(1, 1 << 30))
      ->capture_default_str();
  export_command->add_option("--out", export_out, "Output directory (default: RUN_DIR/export-FORMAT)");

  std::vector<std::string> merge_dirs;
  CLI::App* sweep_merge = app.add_subcommand(
      "sweep-merge", "Join the shards of a sweep (--shard) into the outputs of one sweep");
  sweep_merge->add_option("shards", merge_dirs, "Shard folders (each with its sweep.json)")
      ->required();
  sweep_merge->add_option("--out", out_dir, "Output directory")->required();

  std::vector<std::string> settings;
  for (CLI::App* command : {simulate, bench, compare, gradcheck, optimize}) {
    command->add_option("--set", settings,
                        "PATH=VALUE: a value over the scene file's (dotted path into its JSON, "
                        "e.g. integrator=trapezoidal or solver.tolerance=1e-12); repeatable");
  }
  std::string memory_limit_text;
  for (CLI::App* command : {simulate, bench, compare, gradcheck, optimize, sweep}) {
    command->add_option("--memory-limit", memory_limit_text,
                        "Refuse runs estimated to need more memory than this (e.g. 4G; "
                        "default: the machine's available memory)");
  }

  liedyn::install_output_signal_handlers();
  // The ranks of an MPI job (mpirun -np P liedyn sweep|optimize …), else this process alone.
  std::unique_ptr<liedyn::ProcessGroup> mpi;
  try {
    mpi = liedyn::start_process_group(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "liedyn: " << e.what() << "\n";
    return 2;
  }
  liedyn::ProcessGroup& group = mpi ? *mpi : liedyn::single_process();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    if (exp_jacobian->parsed()) {
      liedyn::AtomicFile file(out_file);
      file.stream() << liedyn::exp_jacobian_singular_values_csv(samples);
      file.commit();
      return 0;
    }
    liedyn::CompareOptions options;
    if (compare->parsed() &&
        !(parse_names(backend_names, liedyn::parse_backend, "--backends", "back-end",
                      "newton, ceres or ipopt", options.backends) &&
          parse_names(rotation_names, liedyn::parse_rotation, "--rotations", "parameterisation",
                      "lie, rotvec or quat", options.rotations))) {
      return 2;
    }
    if (optimize->parsed() && !optimizer_name.empty()) {
      optimize_options.optimizer = liedyn::parse_optimizer(optimizer_name);
      if (!optimize_options.optimizer) {
        std::cerr << "liedyn: --optimizer: unknown optimizer \"" << optimizer_name
                  << "\" (expected nlopt-lbfgs, ceres-lbfgs or ipopt-lbfgs)\n";
        return 2;
      }
    }
    std::optional<std::uint64_t> memory_limit;
    if (!memory_limit_text.empty()) {
      try {
        memory_limit = liedyn::parse_byte_size(memory_limit_text);
      } catch (const std::invalid_argument& e) {
        std::cerr << "liedyn: " << e.what() << "\n";
        return 2;
      }
    }
    if (view->parsed()) {
      const liedyn::ViewSummary v = liedyn::write_view(view_dir);
      std::cout << "view: " << v.frames << " frames, " << v.objects << " objects, "
                << v.bytes / 1024 << " KiB\n"
                << "open " << std::filesystem::absolute(view_dir / std::filesystem::path("view.html")).string()
                << " in a browser (offline: everything is in the file)\n";
      return 0;
    }
    if (plot->parsed()) {
      liedyn::write_plots(plot_dir, plot_out.empty() ? plot_dir : plot_out, std::cout);
      return 0;
    }
    if (export_command->parsed()) {
      liedyn::ExportOptions options;
      options.format = *liedyn::parse_export_format(export_format);  // CLI11 checked the name
      options.every = export_every;
      options.out = export_out;
      const liedyn::ExportSummary e = liedyn::write_export(export_dir, options);
      std::cout << "export: " << e.files << " files, " << e.frames << " frames, " << e.objects << " objects, "
                << e.bytes / 1024 << " KiB (" << e.bytes << " bytes) in " << e.dir.string() << "\n";
      return 0;
    }
    if (sweep_merge->parsed()) {
      std::vector<std::filesystem::path> dirs(merge_dirs.begin(), merge_dirs.end());
      return liedyn::run_sweep_merge(dirs, out_dir, std::cout);
    }
    if (sweep->parsed()) {
      std::vector<liedyn::Backend> backends;
      std::vector<liedyn::RotationParameterization> rotations;
      if (!parse_names(backend_names, liedyn::parse_backend, "--backends", "back-end",
                       "newton, ceres or ipopt", backends) ||
          !parse_names(rotation_names, liedyn::parse_rotation, "--rotations", "parameterisation",
                       "lie, rotvec or quat", rotations)) {
        return 2;
      }
      try {
        for (const std::string& text : set_texts) sweep_options.axes.push_back(liedyn::parse_sweep_axis(text));
      } catch (const std::invalid_argument& e) {
        if (group.rank() == 0) std::cerr << "liedyn: " << e.what() << "\n";
        return 2;
      }
      if (!backend_names.empty()) sweep_options.axes.push_back({"solver.backend", backend_names});
      if (!rotation_names.empty()) sweep_options.axes.push_back({"solver.rotation", rotation_names});
      const liedyn::Scene base = liedyn::load_scene(scene_file);
      if (group.rank() == 0) print_warnings(base);
      liedyn::admit_memory(base, base.optimization ? 1 : 0, memory_limit);
      sweep_command.scene_file = scene_file;
      sweep_command.out = out_dir;
      sweep_command.quiet = quiet;
      return liedyn::run_sweep_command(sweep_command, group, std::cout);
    }
    liedyn::Scene scene = liedyn::load_scene(scene_file, settings);
    scene.solver.ipopt.output_file = ipopt_log;
    print_warnings(scene);
    // Trajectories kept whole: the adjoint's (gradcheck, optimize), compare's two.
    const int trajectories = gradcheck->parsed() || optimize->parsed() ? 1 : compare->parsed() ? 2 : 0;
    liedyn::admit_memory(scene, trajectories, memory_limit);
    if ((gradcheck->parsed() || optimize->parsed()) && !scene.optimization) {
      std::cerr << "liedyn: " << scene_file
                << ": optimization: is required but missing (nothing to differentiate)\n";
      return 2;
    }
    if (gradcheck->parsed()) {
      return liedyn::run_gradcheck(scene, check, verbose, std::cout, gradcheck_parameters);
    }
    if (optimize->parsed()) {
      optimize_options.out = out_dir;
      optimize_options.group = &group;
      if (::isatty(STDERR_FILENO) != 0) optimize_options.progress = &std::cerr;
      if (optimize_iterations > 0) optimize_options.max_iterations = optimize_iterations;
      return liedyn::run_optimize(scene, optimize_options, std::cout);
    }
    if (compare->parsed()) {
      options.condition_every = condition_every;
      options.repeats = compare_repeats;
      if (::isatty(STDERR_FILENO) != 0) options.progress = &std::cerr;
      const std::vector<liedyn::CompareRow> rows = liedyn::compare_solvers(scene, options);
      if (!frames_csv.empty()) {
        liedyn::AtomicFile file(frames_csv);
        file.stream() << liedyn::compare_frames_csv(rows);
        file.commit();
      }
      std::cout << (json  ? liedyn::compare_json(scene, rows)
                    : csv ? liedyn::compare_csv(rows)
                          : liedyn::format_compare(scene, rows));
      int status = 0;
      for (const liedyn::CompareRow& row : rows) {
        if (row.failed) {
          std::cerr << "liedyn: " << row.label() << ": " << row.failure << "\n";
          status = 4;
        }
      }
      return status;
    }
    if (bench->parsed()) {
      const liedyn::BenchResult result = liedyn::bench_scene(scene, repeats);
      std::cout << (json ? liedyn::bench_json(result) : liedyn::format_bench(result));
      if (result.failed) {
        std::cerr << "liedyn: " << result.failure << "\n";
        return 4;
      }
      return 0;
    }
    const liedyn::SimulationSummary summary =
        liedyn::simulate_scene(scene, out_dir, quiet ? nullptr : &std::cerr, every);
    std::cout << liedyn::format_summary(scene, summary);
    std::cout << "outputs      " << out_dir << "/trajectory.csv, " << out_dir << "/frames.csv\n";
    if (summary.failed) {
      std::cerr << "liedyn: " << summary.failure << "\n";
      return 4;
    }
    if (summary.unconverged_steps > 0 && !allow_unconverged) {
      std::cerr << "liedyn: " << summary.unconverged_steps
                << " steps did not meet the tolerance (see frames.csv, columns converged and status)";
      if (!summary.free_directions.empty()) {
        std::cerr << "; the equilibrium is not unique: " << summary.free_directions.front();
        if (summary.free_directions.size() > 1) {
          std::cerr << " (and " << summary.free_directions.size() - 1 << " more, listed above)";
        }
      }
      std::cerr << "\n";
      return 3;
    }
    return 0;
  } catch (const liedyn::RootFailed&) {
    return 1;  // rank 0 says why
  } catch (const liedyn::SceneError& e) {
    // Bad input: every rank read the same and fails alike; rank 0 says it.
    if (group.rank() == 0) std::cerr << "liedyn: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "liedyn: " << (group.size() > 1 ? "rank " + std::to_string(group.rank()) + ": " : "")
              << e.what() << "\n";
    group.abort(1);  // the other ranks may be waiting for this one
    return 1;
  }
}

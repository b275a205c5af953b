// liedyn — command-line driver.
//   liedyn simulate SCENE.json --out DIR [--allow-unconverged] [--quiet]
//   liedyn bench SCENE.json [--repeat N] [--json]     (cost per Newton iteration; no files)
// Exit status: 0 success; 2 bad input (scene or options), nothing written; 3 some steps ended
// at max_iterations (outputs written; --allow-unconverged makes this 0); 4 a step failed
// (outputs written up to it); 1 other errors (I/O).

#include <CLI/CLI.hpp>
#include <iostream>

#include "bench.hpp"
#include "run.hpp"

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

  int repeats = 5;
  bool json = false;
  CLI::App* bench = app.add_subcommand("bench", "Time a scene's Newton iterations (no outputs)");
  bench->add_option("scene", scene_file, "Scene file (JSON)")->required();
  bench->add_option("--repeat", repeats, "Runs to take the median of")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  bench->add_flag("--json", json, "Print one JSON object instead of text");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    const liedyn::Scene scene = liedyn::load_scene(scene_file);
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
        liedyn::simulate_scene(scene, out_dir, quiet ? nullptr : &std::cerr);
    std::cout << liedyn::format_summary(scene, summary);
    std::cout << "outputs      " << out_dir << "/trajectory.csv, " << out_dir << "/frames.csv\n";
    if (summary.failed) {
      std::cerr << "liedyn: " << summary.failure << "\n";
      return 4;
    }
    if (summary.unconverged_steps > 0 && !allow_unconverged) {
      std::cerr << "liedyn: " << summary.unconverged_steps
                << " steps did not meet the tolerance (see frames.csv, column converged)\n";
      return 3;
    }
    return 0;
  } catch (const liedyn::SceneError& e) {
    std::cerr << "liedyn: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "liedyn: " << e.what() << "\n";
    return 1;
  }
}

// liedyn — command-line driver.
//   liedyn simulate SCENE.json --out DIR [--allow-unconverged] [--quiet]
// Exit status: 0 success; 2 bad input (scene or options), nothing written; 3 some steps ended
// at max_iterations (outputs written; --allow-unconverged makes this 0); 4 a step failed
// (outputs written up to it); 1 other errors (I/O).

#include <CLI/CLI.hpp>
#include <iostream>

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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    const liedyn::Scene scene = liedyn::load_scene(scene_file);
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

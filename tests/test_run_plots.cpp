// `liedyn plot` (problems/run_plots.hpp) and the loss.png of `liedyn optimize`: the PNGs a
// simulate or optimize folder gets, the plots skipped for missing columns (and said so),
// frame 0 kept out of the per-step plots, and bad input refused naming file, line and column
// (exit 2, nothing written).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "png_image.hpp"
#include "problems/recorded_run.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;

const fs::path kSourceDir = LIEDYN_SOURCE_DIR;

class PlotCli : public test::CliFixture {
 protected:
  PlotCli() : CliFixture("liedyn_plot_test_") {}

  static std::string scene(const std::string& name) {
    return (kSourceDir / "problems/scenes" / name).string();
  }

  // A PNG of the default size, 900 × 600, that is not blank.
  static void expect_plot(const fs::path& file) {
    SCOPED_TRACE(file.string());
    ASSERT_TRUE(fs::exists(file));
    const test::Image image(file);
    ASSERT_EQ(image.status(), CAIRO_STATUS_SUCCESS);
    EXPECT_EQ(image.width(), 900);
    EXPECT_EQ(image.height(), 600);
    EXPECT_GT(image.count(0.1, 0.95, 0.1, 0.9,
                          [](int r, int g, int b) { return r < 200 || g < 200 || b < 200; }),
              1000);
  }

  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
};

// A run without contact: its penetration is 0 throughout, and not plotted.
const std::vector<std::string> kRunPlots = {"energy.png", "iterations.png", "gradient_norm.png",
                                            "momentum.png"};

TEST_F(PlotCli, ASimulatedRunGetsItsPlots) {
  const Result sim =
      run({"simulate", scene("pendulum.json"), "--set", "frames=100", "--out", "out", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const Result r = run({"plot", "out"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const std::string& png : kRunPlots) {
    expect_plot(dir_ / "out" / png);
    EXPECT_NE(r.out.find("wrote out/" + png + "\n"), std::string::npos) << r.out;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out" / "penetration.png"));
  EXPECT_NE(r.out.find("skipped penetration.png: out/frames.csv has no values in max_penetration, "
                       "min_rod_separation (or only zeros: nothing touched)"),
            std::string::npos)
      << r.out;
  // One unit of the folder: run.json names the plots as the plot run's, the run's files as
  // the simulation's.
  const nlohmann::json manifest = nlohmann::json::parse(test::read_file(dir_ / "out" / "run.json"));
  const std::string plot_run = manifest["files"]["energy.png"]["run"];
  EXPECT_EQ(manifest["files"]["momentum.png"]["run"], plot_run);
  EXPECT_NE(manifest["files"]["frames.csv"]["run"], plot_run);

  // --out: elsewhere, the run's folder untouched.
  for (const std::string& png : kRunPlots) fs::remove(dir_ / "out" / png);
  const Result elsewhere = run({"plot", "out", "--out", "plots"});
  ASSERT_EQ(elsewhere.exit_code, 0) << elsewhere.err;
  for (const std::string& png : kRunPlots) {
    expect_plot(dir_ / "plots" / png);
    EXPECT_FALSE(fs::exists(dir_ / "out" / png));
  }
}

TEST_F(PlotCli, PlotsWithoutTheirColumnsAreSkippedAndSaid) {
  // No momentum columns, no potential energy, min_rod_separation empty throughout.
  fs::create_directory(dir_ / "run");
  write("run/frames.csv",
        "frame,time,newton_iterations,gradient_norm,status,kinetic_energy,max_penetration,"
        "min_rod_separation\n"
        "0,0,0,0,initial,1,0,\n"
        "1,0.1,3,1e-10,converged,0.9,0.001,\n"
        "2,0.2,4,2e-11,converged,0.8,0.002,\n");
  Result r = run({"plot", "run"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* png : {"energy.png", "iterations.png", "gradient_norm.png", "penetration.png"}) {
    expect_plot(dir_ / "run" / png);
  }
  EXPECT_FALSE(fs::exists(dir_ / "run" / "momentum.png"));
  EXPECT_NE(r.out.find("skipped momentum.png: run/frames.csv has no values in angular_momentum_x, "
                       "angular_momentum_y, angular_momentum_z"),
            std::string::npos)
      << r.out;

  // Only the initial state: nothing per step to plot (frame 0 is not a step).
  write("run/frames.csv",
        "frame,time,newton_iterations,gradient_norm,status,kinetic_energy\n"
        "0,0,0,0,initial,1\n");
  r = run({"plot", "run"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote run/energy.png"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("skipped iterations.png: run/frames.csv holds no step"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("skipped gradient_norm.png: run/frames.csv holds no step"),
            std::string::npos)
      << r.out;
}

TEST_F(PlotCli, BadInputIsRefusedNamingFileLineAndColumn) {
  ASSERT_EQ(
      run({"simulate", scene("pendulum.json"), "--set", "frames=10", "--out", "out", "--quiet"})
          .exit_code,
      0);
  const std::string good = test::read_file(dir_ / "out" / "frames.csv");
  const auto refused = [&](const std::string& frames, const std::string& message) {
    SCOPED_TRACE(message);
    write("out/frames.csv", frames);
    const Result r = run({"plot", "out"});
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out" / "energy.png"));
  };
  // Line 5 (frame 3): its kinetic energy (the sixth field) is not a number.
  std::string bad;
  std::istringstream in(good);
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    if (++number == 5) {
      std::vector<std::string> fields = csv_fields(line);
      fields[5] = "x" + fields[5];
      line.clear();
      for (std::size_t i = 0; i < fields.size(); ++i) line += (i > 0 ? "," : "") + fields[i];
    }
    bad += line + "\n";
  }
  refused(bad, "out/frames.csv: line 5: kinetic_energy \"x");
  refused(good + "11,0.2\n", "out/frames.csv: line 13: has 2 fields, the header 22");
  refused("time,frame\n0,0\n", "out/frames.csv: line 1: is not frames.csv's header");
  refused("frame,kinetic_energy\n0,1\n", "out/frames.csv: time: is not a column of this file");
  // No folder, a folder with nothing to plot.
  Result r = run({"plot", "nowhere"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nowhere: is not a folder"), std::string::npos) << r.err;
  fs::create_directory(dir_ / "empty");
  r = run({"plot", "empty"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("empty: holds no frames.csv, history.csv or starts.csv"), std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::is_empty(dir_ / "empty"));
  // history.csv: a field that is not a number; a normalised loss on another scale.
  fs::create_directory(dir_ / "opt");
  write("opt/history.csv",
        "iteration,loss,normalized_loss,gradient_norm,seconds\n0,2,1,1,0\n1,one,0.5,1,0\n");
  r = run({"plot", "opt"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("opt/history.csv: line 3: loss \"one\" is not a number"), std::string::npos)
      << r.err;
  write("opt/history.csv",
        "iteration,loss,normalized_loss,gradient_norm,seconds\n0,2,1,1,0\n1,1,0.25,1,0\n");
  r = run({"plot", "opt"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("opt/history.csv: line 3: normalized_loss is loss / 4"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "opt" / "loss.png"));
}

TEST_F(PlotCli, AnOptimizationWritesItsLossPlotAndGetsItsOwnPlots) {
  const std::string die = scene("optimization/die_throw.json");
  const Result o = run({"optimize", die, "--out", "opt", "--max-iterations", "3"});
  ASSERT_EQ(o.exit_code, 3) << o.out << o.err;
  // optimize's loss.png, in the unit of parameters.csv.
  expect_plot(dir_ / "opt" / "loss.png");
  const nlohmann::json manifest = nlohmann::json::parse(test::read_file(dir_ / "opt" / "run.json"));
  EXPECT_EQ(manifest["files"]["loss.png"]["run"], manifest["files"]["parameters.csv"]["run"]);

  fs::remove(dir_ / "opt" / "loss.png");
  const Result r = run({"plot", "opt"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const std::string png : {"loss.png", "loss_gradient_norm.png"}) {
    expect_plot(dir_ / "opt" / png);
    EXPECT_NE(r.out.find("wrote opt/" + png + "\n"), std::string::npos) << r.out;
  }
  for (const std::string& png : kRunPlots) expect_plot(dir_ / "opt" / png);  // the best run's

  // Multi-start: each start's best loss.
  const Result m = run(
      {"optimize", die, "--out", "starts", "--max-iterations", "2", "--starts", "2", "-j", "1"});
  ASSERT_LE(m.exit_code, 3) << m.out << m.err;
  // optimize --starts draws it itself, with its last starts.csv (one unit: the same run).
  expect_plot(dir_ / "starts" / "starts.png");
  const nlohmann::json starts_manifest = nlohmann::json::parse(test::read_file(dir_ / "starts" / "run.json"));
  EXPECT_EQ(starts_manifest["files"]["starts.png"]["run"], starts_manifest["files"]["starts.csv"]["run"]);
  fs::remove(dir_ / "starts" / "starts.png");
  const Result s = run({"plot", "starts"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  expect_plot(dir_ / "starts" / "starts.png");
  EXPECT_NE(s.out.find("wrote starts/starts.png"), std::string::npos) << s.out;
}

}  // namespace
}  // namespace liedyn

// The `liedyn simulate SCENE --out DIR` command line (problems/main.cpp), run as a real
// process: outputs, exit codes (0 ok, 2 bad input, 3 unconverged steps, 4 failed step) and
// the promise that bad input writes nothing and leaves existing outputs alone.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const char* const kTrajectoryHeader = "frame,time,object,kind,index,x,y,z,qw,qx,qy,qz";
const char* const kFramesHeaderStart =
    "frame,time,newton_iterations,gradient_norm,converged,kinetic_energy,potential_energy,"
    "angular_momentum_x,angular_momentum_y,angular_momentum_z";

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << p;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, sep)) out.push_back(item);
  if (!s.empty() && s.back() == sep) out.emplace_back();
  return out;
}

// A CSV file: header and rows (split on commas).
struct Csv {
  std::string header;
  std::vector<std::vector<std::string>> rows;
  std::size_t column(const std::string& name) const {
    const auto names = split(header, ',');
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == name) return i;
    }
    ADD_FAILURE() << "no column " << name << " in " << header;
    return 0;
  }
};

Csv read_csv(const fs::path& p) {
  Csv csv;
  std::istringstream in(read_file(p));
  std::string line;
  if (!std::getline(in, csv.header)) ADD_FAILURE() << p << " is empty";
  while (std::getline(in, line)) csv.rows.push_back(split(line, ','));
  return csv;
}

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

std::string butterfly_bolt() {
  return read_file(fs::path(LIEDYN_SOURCE_DIR) / "problems/scenes/butterfly_bolt.json");
}

// Replaces exactly one occurrence of `from` (the test scene is derived from the example).
std::string replace_once(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "\"" << from << "\" not in the scene";
  if (at == std::string::npos) return text;
  EXPECT_EQ(text.find(from, at + 1), std::string::npos) << "\"" << from << "\" twice";
  return text.replace(at, from.size(), to);
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("liedyn_cli_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);  // kept for inspection on failure
  }

  struct Result {
    int exit_code = -1;
    std::string out, err;
  };

  // Runs `liedyn <args>` (arguments single-quoted) from the test directory.
  Result run(const std::vector<std::string>& args) {
    std::string command = "cd '" + dir_.string() + "' && '" + std::string(LIEDYN_CLI) + "'";
    for (const std::string& a : args) command += " '" + a + "'";
    command +=
        " > '" + (dir_ / "stdout.txt").string() + "' 2> '" + (dir_ / "stderr.txt").string() + "'";
    Result r;
    const int status = std::system(command.c_str());
    if (status != -1 && WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    r.out = read_file(dir_ / "stdout.txt");
    r.err = read_file(dir_ / "stderr.txt");
    fs::remove(dir_ / "stdout.txt");
    fs::remove(dir_ / "stderr.txt");
    return r;
  }

  Result simulate(const std::string& scene_text, const std::string& out,
                  std::vector<std::string> extra = {}) {
    write_file(dir_ / "scene.json", scene_text);
    std::vector<std::string> args = {"simulate", "scene.json", "--out", out, "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run(args);
  }

  fs::path dir_;
};

TEST_F(Cli, ButterflyBoltWritesTrajectoryAndFrames) {
  const std::string scene = replace_once(butterfly_bolt(), "\"frames\": 1000", "\"frames\": 20");
  // A nested output directory is created.
  const Result r = simulate(scene, "results/bolt");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("20 of 20"), std::string::npos) << r.out;

  const fs::path out = dir_ / "results/bolt";
  // Only the two outputs: no temporary file is left behind.
  EXPECT_EQ(listing(out), (std::set<std::string>{"frames.csv", "trajectory.csv"}));

  const Csv trajectory = read_csv(out / "trajectory.csv");
  EXPECT_EQ(trajectory.header, kTrajectoryHeader);
  ASSERT_EQ(trajectory.rows.size(), 21u);  // frames 0..20, one body
  for (std::size_t k = 0; k < trajectory.rows.size(); ++k) {
    const auto& row = trajectory.rows[k];
    ASSERT_EQ(row.size(), 12u) << "row " << k;
    EXPECT_EQ(std::stoi(row[0]), static_cast<int>(k));
    EXPECT_NEAR(std::stod(row[1]), 0.01 * static_cast<double>(k), 1e-12);
    EXPECT_EQ(row[2], "bolt");
    EXPECT_EQ(row[3], "body");
    EXPECT_EQ(row[4], "0");
    // No gravity, no initial velocity: the centre of mass stays at the origin.
    for (int c = 5; c < 8; ++c) EXPECT_NEAR(std::stod(row[c]), 0.0, 1e-12) << "row " << k;
    const double qw = std::stod(row[8]), qx = std::stod(row[9]), qy = std::stod(row[10]),
                 qz = std::stod(row[11]);
    EXPECT_NEAR(qw * qw + qx * qx + qy * qy + qz * qz, 1.0, 1e-12) << "row " << k;
  }
  // Frame 0 is the initial state (identity orientation); the bolt then turns about y.
  EXPECT_EQ(std::stod(trajectory.rows[0][8]), 1.0);
  EXPECT_GT(std::abs(std::stod(trajectory.rows[20][10])),
            0.1);  // ≈ sin(0.2) after 0.2 s at 2 rad/s

  const Csv frames = read_csv(out / "frames.csv");
  EXPECT_EQ(frames.header.rfind(kFramesHeaderStart, 0), 0u) << frames.header;
  ASSERT_EQ(frames.rows.size(), 21u);
  const std::size_t converged = frames.column("converged");
  const std::size_t status = frames.column("status");
  const std::size_t ke = frames.column("kinetic_energy");
  const std::size_t columns = split(frames.header, ',').size();
  for (std::size_t k = 0; k < frames.rows.size(); ++k) {
    ASSERT_EQ(frames.rows[k].size(), columns) << "row " << k;
    EXPECT_EQ(std::stoi(frames.rows[k][0]), static_cast<int>(k));
    EXPECT_EQ(frames.rows[k][converged], "1") << "row " << k;
    EXPECT_EQ(frames.rows[k][status], k == 0 ? "initial" : "converged") << "row " << k;
    // ½ ωᵀIω = ½·2·2² + ½·2.8·0.01² at the start; backward Euler only dissipates.
    const double energy = std::stod(frames.rows[k][ke]);
    EXPECT_GT(energy, 3.0) << "row " << k;
    EXPECT_LE(energy, 4.00014 + 1e-9) << "row " << k;
  }
  EXPECT_NEAR(std::stod(frames.rows[0][ke]), 4.00014, 1e-9);
}

TEST_F(Cli, SuccessfulRunReplacesEarlierOutputs) {
  fs::create_directories(dir_ / "out");
  write_file(dir_ / "out/trajectory.csv", "old\n");
  write_file(dir_ / "out/frames.csv", "old\n");
  write_file(dir_ / "out/notes.txt", "mine\n");
  const Result r =
      simulate(replace_once(butterfly_bolt(), "\"frames\": 1000", "\"frames\": 3"), "out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_csv(dir_ / "out/trajectory.csv").rows.size(), 4u);
  EXPECT_EQ(read_csv(dir_ / "out/frames.csv").rows.size(), 4u);
  EXPECT_EQ(read_file(dir_ / "out/notes.txt"), "mine\n");
  EXPECT_EQ(listing(dir_ / "out"),
            (std::set<std::string>{"frames.csv", "notes.txt", "trajectory.csv"}));
}

TEST_F(Cli, BadSceneExits2AndWritesNothing) {
  const std::string bad = replace_once(butterfly_bolt(), "\"mass\": 1.0", "\"mass\": -1.0");
  const Result r = simulate(bad, "fresh_out");
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("scene.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bodies[0].mass"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "fresh_out"));
}

TEST_F(Cli, BadSceneLeavesExistingOutputsUntouched) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  std::string sentinel = "frame,time,sentinel\n";
  for (int i = 0; i < 256; ++i) sentinel += static_cast<char>(i);  // every byte value
  write_file(out / "trajectory.csv", sentinel);
  const auto before = fs::last_write_time(out / "trajectory.csv");

  const std::string bad = replace_once(butterfly_bolt(), "\"tolerance\": 1e-9", "\"tolerance\": 0");
  const Result r = simulate(bad, "out");
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("scene.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("solver.tolerance"), std::string::npos) << r.err;
  EXPECT_EQ(read_file(out / "trajectory.csv"), sentinel);
  EXPECT_EQ(fs::last_write_time(out / "trajectory.csv"), before);
  EXPECT_EQ(listing(out), std::set<std::string>{"trajectory.csv"});
}

TEST_F(Cli, OtherBadInputExits2) {
  // Unknown key inside a body.
  Result r = simulate(replace_once(butterfly_bolt(), "\"name\": \"bolt\"",
                                   "\"name\": \"bolt\", \"colour\": \"red\""),
                      "out");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("bodies[0].colour"), std::string::npos) << r.err;
  // Invalid JSON.
  r = simulate(replace_once(butterfly_bolt(), "0.01] }", "0.01], }"), "out");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("scene.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("invalid JSON"), std::string::npos) << r.err;
  // A number that overflows a double.
  r = simulate(replace_once(butterfly_bolt(), "\"time_step\": 0.01", "\"time_step\": 1e999"),
               "out");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("scene.json: time_step"), std::string::npos) << r.err;
  // A scene file that does not exist.
  r = run({"simulate", "missing_scene.json", "--out", "out"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("missing_scene.json"), std::string::npos) << r.err;
  // Command-line mistakes: no --out, unknown option, no subcommand.
  write_file(dir_ / "scene.json", butterfly_bolt());
  EXPECT_EQ(run({"simulate", "scene.json"}).exit_code, 2);
  EXPECT_EQ(run({"simulate", "scene.json", "--out", "out", "--bogus"}).exit_code, 2);
  EXPECT_EQ(run({}).exit_code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  // --help is not an error.
  EXPECT_EQ(run({"simulate", "--help"}).exit_code, 0);
}

std::string cantilever() {
  return read_file(fs::path(LIEDYN_SOURCE_DIR) / "problems/scenes/cantilever.json");
}

// Rows of one frame of a rod, by kind ("node" / "edge") and index.
struct RodFrame {
  std::vector<std::vector<double>> node, edge;  // columns x, y, z (and qw, qx, qy, qz)
};

TEST_F(Cli, RodWritesNodeAndEdgeRows) {
  // The bundled cantilever, shortened: 4 edges (5 nodes), 10 frames.
  std::string scene = replace_once(cantilever(), "\"frames\": 300", "\"frames\": 10");
  scene = replace_once(scene, "\"edges\": 20", "\"edges\": 4");
  scene = replace_once(scene, "\"node\": 20", "\"node\": 4");
  const Result r = simulate(scene, "out");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("rods 1 (5 nodes)"), std::string::npos) << r.out;

  const Csv trajectory = read_csv(dir_ / "out/trajectory.csv");
  EXPECT_EQ(trajectory.header, kTrajectoryHeader);
  constexpr int kNodes = 5, kEdges = 4, kFrames = 10;
  ASSERT_EQ(trajectory.rows.size(), static_cast<std::size_t>((kFrames + 1) * (kNodes + kEdges)));
  std::vector<RodFrame> frames(kFrames + 1);
  for (std::size_t n = 0; n < trajectory.rows.size(); ++n) {
    const auto& row = trajectory.rows[n];
    ASSERT_EQ(row.size(), 12u) << "row " << n;
    // Within a frame: nodes 0…4, then edges 0…3.
    const int frame = static_cast<int>(n) / (kNodes + kEdges);
    const int slot = static_cast<int>(n) % (kNodes + kEdges);
    const bool is_node = slot < kNodes;
    EXPECT_EQ(std::stoi(row[0]), frame) << "row " << n;
    EXPECT_NEAR(std::stod(row[1]), 0.01 * frame, 1e-12) << "row " << n;
    EXPECT_EQ(row[2], "beam") << "row " << n;
    EXPECT_EQ(row[3], is_node ? "node" : "edge") << "row " << n;
    EXPECT_EQ(std::stoi(row[4]), is_node ? slot : slot - kNodes) << "row " << n;
    if (is_node) {
      for (int c = 8; c < 12; ++c) EXPECT_EQ(row[c], "") << "row " << n << " column " << c;
      frames[frame].node.push_back({std::stod(row[5]), std::stod(row[6]), std::stod(row[7])});
    } else {
      std::vector<double> values;
      for (int c = 5; c < 12; ++c) values.push_back(std::stod(row[c]));
      const double norm2 = values[3] * values[3] + values[4] * values[4] +
                           values[5] * values[5] + values[6] * values[6];
      EXPECT_NEAR(norm2, 1.0, 1e-12) << "row " << n;
      EXPECT_GE(values[3], 0.0) << "row " << n;
      frames[frame].edge.push_back(values);
    }
  }
  for (int k = 0; k <= kFrames; ++k) {
    const RodFrame& f = frames[k];
    ASSERT_EQ(f.node.size(), static_cast<std::size_t>(kNodes));
    ASSERT_EQ(f.edge.size(), static_cast<std::size_t>(kEdges));
    // Edge rows sit at the midpoints of their nodes.
    for (int j = 0; j < kEdges; ++j) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(f.edge[j][c], 0.5 * (f.node[j][c] + f.node[j + 1][c]), 1e-15)
            << "frame " << k << " edge " << j;
      }
    }
    // Node 0 and edge 0 are clamped: the edge frame takes e_z to the x axis (90° about y).
    for (int c = 0; c < 3; ++c) EXPECT_EQ(f.node[0][c], 0.0) << "frame " << k;
    EXPECT_NEAR(f.edge[0][3], std::sqrt(0.5), 1e-15) << "frame " << k;
    EXPECT_NEAR(f.edge[0][5], std::sqrt(0.5), 1e-15) << "frame " << k;
  }
  // Frame 0 is the rest shape along x; the tip load then bends the rod down (−z), in plane.
  for (int i = 0; i < kNodes; ++i) {
    EXPECT_NEAR(frames[0].node[i][0], 0.25 * i, 1e-15);
    EXPECT_EQ(frames[0].node[i][2], 0.0);
  }
  EXPECT_LT(frames[kFrames].node[4][2], -1e-4);
  EXPECT_LT(frames[kFrames].node[4][2], frames[kFrames].node[2][2]);
  EXPECT_NEAR(frames[kFrames].node[4][1], 0.0, 1e-12);

  const Csv frames_csv = read_csv(dir_ / "out/frames.csv");
  ASSERT_EQ(frames_csv.rows.size(), static_cast<std::size_t>(kFrames + 1));
  const std::size_t converged = frames_csv.column("converged");
  for (const auto& row : frames_csv.rows) EXPECT_EQ(row[converged], "1");
}

TEST_F(Cli, CantileverExampleConvergesAndSwingsAboutTheStaticDeflection) {
  const Result r = simulate(cantilever(), "out");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("300 of 300"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("unconverged  0 steps"), std::string::npos) << r.out;

  const Csv frames = read_csv(dir_ / "out/frames.csv");
  ASSERT_EQ(frames.rows.size(), 301u);
  const std::size_t converged = frames.column("converged");
  for (std::size_t k = 0; k < frames.rows.size(); ++k) {
    EXPECT_EQ(frames.rows[k][converged], "1") << "row " << k;
  }
  const Csv trajectory = read_csv(dir_ / "out/trajectory.csv");
  ASSERT_EQ(trajectory.rows.size(), 301u * (21 + 20));
  // Tip (node 20) released from rest under a step load P: it overshoots to about twice the
  // static deflection P L³/(3 EI) = 0.01/(3·0.08) m, less what backward Euler dissipates.
  double lowest = 0.0;
  for (const auto& row : trajectory.rows) {
    if (row[3] == "node" && row[4] == "20") lowest = std::min(lowest, std::stod(row[7]));
  }
  const double static_deflection = 0.01 / (3 * 0.08);
  EXPECT_GT(-lowest, 1.4 * static_deflection);
  EXPECT_LT(-lowest, 2.05 * static_deflection);
}

TEST_F(Cli, BadRodExits2) {
  const Result r = simulate(replace_once(cantilever(), "\"fixed_nodes\": [0]",
                                         "\"fixed_nodes\": [21]"),
                            "out");
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("scene.json: rods[0].fixed_nodes[0]: "), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(Cli, BenchReportsIterationCostsWithoutWritingFiles) {
  write_file(dir_ / "scene.json", cantilever());
  const Result r = run({"bench", "scene.json", "--repeat", "2", "--json"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  // One JSON object with the documented keys; the rod of 20 edges clamped at node 0 and
  // edge 0 has 20 free nodes and 19 free edges: 117 DOFs.
  for (const char* key : {"\"dofs\": 117", "\"frames\": 300", "\"repeats\": 2",
                          "\"assembly_us\": ", "\"solve_us\": ", "\"iteration_us\": ",
                          "\"total_seconds\": ",
                          "\"iterations_per_frame\": ", "\"failed\": false"}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << key << " missing from " << r.out;
  }
  EXPECT_EQ(listing(dir_), std::set<std::string>{"scene.json"});  // no outputs written
  const Result bad = run({"bench", "missing.json"});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("missing.json"), std::string::npos) << bad.err;
}

TEST_F(Cli, CompareRunsEachParameterisationAndWritesPerFrameSeries) {
  write_file(dir_ / "scene.json", replace_once(butterfly_bolt(), "\"frames\": 1000",
                                               "\"frames\": 50"));
  const Result r = run({"compare", "scene.json", "--rotations", "lie,rotvec,quat", "--csv",
                        "--repeat", "1", "--frames-csv", "frames.csv"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  write_file(dir_ / "compare.csv", r.out);
  const Csv table = read_csv(dir_ / "compare.csv");
  ASSERT_EQ(table.rows.size(), 3u);
  const std::size_t rotation = table.column("rotation"), frames = table.column("frames");
  const std::size_t deviation = table.column("max_rotation_deviation");
  const std::size_t condition = table.column("condition_mean");
  const char* names[] = {"lie", "rotvec", "quat"};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(table.rows[i][rotation], names[i]);
    EXPECT_EQ(table.rows[i][frames], "50");
    // Every frame of a 6-DOF body is sampled; the Hessian is positive definite.
    EXPECT_GE(std::stod(table.rows[i][condition]), 1.0);
    // Converged steps agree with the reference (tolerance 1e-9 rad per step).
    EXPECT_LT(std::stod(table.rows[i][deviation]), 1e-6) << names[i];
  }
  EXPECT_EQ(table.rows[0][deviation], "0");  // the reference itself
  const Csv series = read_csv(dir_ / "frames.csv");
  EXPECT_EQ(series.header,
            "rotation,frame,iterations,first_gradient_norm,second_gradient_norm,"
            "residual_reduction,condition");
  EXPECT_EQ(series.rows.size(), 150u);

  const Result json = run({"compare", "scene.json", "--rotations", "quat,lie", "--json",
                           "--repeat", "1"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_NE(json.out.find("\"reference\": \"quat\""), std::string::npos) << json.out;
  const Result unknown = run({"compare", "scene.json", "--rotations", "lie,euler"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("euler"), std::string::npos) << unknown.err;
}

// One Newton update per step against a tolerance one update cannot meet: with h = 0.1 s the
// first update leaves a Newton step of ~1e-7 rad (with h = 0.01 s it is already ~1e-16).
std::string unconverged_scene() {
  std::string s = replace_once(butterfly_bolt(), "\"frames\": 1000", "\"frames\": 20");
  s = replace_once(s, "\"time_step\": 0.01", "\"time_step\": 0.1");
  s = replace_once(s, "\"tolerance\": 1e-9", "\"tolerance\": 1e-12");
  return replace_once(s, "\"max_iterations\": 50", "\"max_iterations\": 1");
}

void expect_flagged_unconverged(const fs::path& frames_csv) {
  const Csv frames = read_csv(frames_csv);
  ASSERT_EQ(frames.rows.size(), 21u);
  const std::size_t converged = frames.column("converged");
  const std::size_t iterations = frames.column("newton_iterations");
  const std::size_t status = frames.column("status");
  int zeros = 0;
  for (std::size_t k = 1; k < frames.rows.size(); ++k) {
    EXPECT_LE(std::stoi(frames.rows[k][iterations]), 1) << "row " << k;
    if (frames.rows[k][converged] == "0") {
      ++zeros;
      EXPECT_EQ(frames.rows[k][status], "max_iterations") << "row " << k;
    } else {
      EXPECT_EQ(frames.rows[k][converged], "1");
    }
  }
  EXPECT_GT(zeros, 10);
}

TEST_F(Cli, UnconvergedStepsExit3) {
  const Result r = simulate(unconverged_scene(), "out");
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("converged"), std::string::npos) << r.err;
  // The outputs are written all the same, and complete.
  EXPECT_EQ(read_csv(dir_ / "out/trajectory.csv").rows.size(), 21u);
  expect_flagged_unconverged(dir_ / "out/frames.csv");
  EXPECT_EQ(listing(dir_ / "out"), (std::set<std::string>{"frames.csv", "trajectory.csv"}));
}

TEST_F(Cli, AllowUnconvergedExits0) {
  const Result r = simulate(unconverged_scene(), "out", {"--allow-unconverged"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(read_csv(dir_ / "out/trajectory.csv").rows.size(), 21u);
  expect_flagged_unconverged(dir_ / "out/frames.csv");
}

// Gravity of 1e153 m/s² with h = 1 s: a valid scene whose potential m g·x overflows once
// the body has fallen ~1e155 m, after a number of completed steps.
const char* const kRunawayScene = R"({
  "description": "a body falling until the incremental potential overflows",
  "time_step": 1.0,
  "frames": 100,
  "gravity": [0, 0, -1e153],
  "bodies": [ { "name": "rock", "mass": 1, "inertia": [1, 1, 1] } ]
})";

TEST_F(Cli, FailedStepExits4AndKeepsEarlierFrames) {
  const Result r = simulate(kRunawayScene, "out");
  ASSERT_EQ(r.exit_code, 4) << r.out << r.err;
  EXPECT_EQ(listing(dir_ / "out"), (std::set<std::string>{"frames.csv", "trajectory.csv"}));

  const Csv trajectory = read_csv(dir_ / "out/trajectory.csv");
  const Csv frames = read_csv(dir_ / "out/frames.csv");
  EXPECT_EQ(trajectory.header, kTrajectoryHeader);
  // Some steps completed before the failure, and not all of them.
  ASSERT_GT(trajectory.rows.size(), 2u);
  ASSERT_LT(trajectory.rows.size(), 101u);
  ASSERT_EQ(frames.rows.size(), trajectory.rows.size());
  for (std::size_t k = 0; k < frames.rows.size(); ++k) {
    EXPECT_EQ(std::stoi(trajectory.rows[k][0]), static_cast<int>(k));
    EXPECT_EQ(std::stoi(frames.rows[k][0]), static_cast<int>(k));
    // Kept rows hold a state: finite positions.
    EXPECT_TRUE(std::isfinite(std::stod(trajectory.rows[k][7]))) << "row " << k;
  }
  // The failed step is the one after the last kept frame, and stderr says how it failed.
  const std::string failed_step = "step " + std::to_string(frames.rows.size()) + " ";
  EXPECT_NE(r.err.find(failed_step), std::string::npos) << r.err;
  EXPECT_TRUE(r.err.find("non_finite") != std::string::npos ||
              r.err.find("line_search_failed") != std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("FAILED"), std::string::npos) << r.out;
  const std::size_t status = frames.column("status");
  for (std::size_t k = 1; k < frames.rows.size(); ++k) {
    EXPECT_TRUE(frames.rows[k][status] == "converged" || frames.rows[k][status] == "max_iterations")
        << frames.rows[k][status];
  }
}

}  // namespace

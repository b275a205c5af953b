// Output safety (problems/output.hpp, problems/output_folder.hpp): files written exclusively
// under unpredictable names and renamed into place, output folders replaced as a unit and
// locked, leftovers of interrupted runs settled, signals cleaned up after, and the command
// line's guarantees (nothing a scene says chooses where liedyn writes; names quoted in CSV).

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "../problems/output.hpp"
#include "../problems/output_folder.hpp"
#include "../problems/scene.hpp"
#include "cli_fixture.hpp"

extern char** environ;

namespace liedyn {
namespace {

namespace fs = std::filesystem;
using test::read_file;

// Every entry of `dir`, by name.
std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

bool has_staging(const fs::path& dir) {
  for (const std::string& name : listing(dir)) {
    if (name.rfind(".liedyn-staging-", 0) == 0) return true;
  }
  return false;
}

void write(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

class OutputTest : public test::CliFixture {
 protected:
  OutputTest() : CliFixture("liedyn_output_test_") {}

  // The folder `name` with a committed unit {a.csv: "old a", b.csv: "old b"}.
  fs::path folder_with_old_unit(const std::string& name) {
    const fs::path out = dir_ / name;
    OutputFolder folder(out, "first", nullptr);
    folder.add("a.csv") << "old a";
    folder.add("b.csv") << "old b";
    folder.commit();
    return out;
  }
};

// ---------------------------------------------------------------------------------------
// OutputFolder
// ---------------------------------------------------------------------------------------

TEST_F(OutputTest, CommitReplacesTheUnitAndTheManifestNamesItsRun) {
  const fs::path out = folder_with_old_unit("out");
  EXPECT_EQ(listing(out), (std::set<std::string>{"a.csv", "b.csv", "run.json"}));
  EXPECT_EQ(read_file(out / "a.csv"), "old a");
  {
    OutputFolder folder(out, "second", nullptr);
    folder.add("a.csv") << "new a";
    EXPECT_EQ(read_file(out / "a.csv"), "old a") << "nothing is replaced before commit";
    EXPECT_TRUE(has_staging(out));
    folder.commit();
    EXPECT_FALSE(has_staging(out));
    const nlohmann::json manifest = nlohmann::json::parse(read_file(out / "run.json"));
    const std::string run = manifest.at("files").at("a.csv").at("run");
    EXPECT_EQ(run, folder.run_id());
    EXPECT_EQ(manifest.at("files").at("a.csv").at("bytes"), 5);
    // b.csv was not replaced: still named as the first run's.
    const std::string first = manifest.at("files").at("b.csv").at("run");
    EXPECT_NE(first, run);
    EXPECT_EQ(manifest.at("runs").at(first).at("command"), "first");
    EXPECT_EQ(manifest.at("runs").at(run).at("command"), "second");
  }
  EXPECT_EQ(read_file(out / "a.csv"), "new a");
  EXPECT_EQ(read_file(out / "b.csv"), "old b");
}

TEST_F(OutputTest, AnUncommittedUnitLeavesNothing) {
  const fs::path out = folder_with_old_unit("out");
  {
    OutputFolder folder(out, "second", nullptr);
    folder.add("a.csv") << "new a";
    folder.add("c.csv") << "new c";
  }  // e.g. an exception before commit
  EXPECT_EQ(listing(out), (std::set<std::string>{"a.csv", "b.csv", "run.json"}));
  EXPECT_EQ(read_file(out / "a.csv"), "old a");
}

TEST_F(OutputTest, AFolderInTheWayReplacesNothing) {
  // frames.csv being a directory used to leave a new trajectory.csv beside the old frames.csv.
  const fs::path out = folder_with_old_unit("out");
  fs::remove(out / "b.csv");
  fs::create_directory(out / "b.csv");
  {
    OutputFolder folder(out, "second", nullptr);
    folder.add("a.csv") << "new a";
    folder.add("b.csv") << "new b";
    try {
      folder.commit();
      ADD_FAILURE() << "commit over a folder must throw";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("b.csv: is a folder"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("nothing in"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(read_file(out / "a.csv"), "old a");
  EXPECT_FALSE(has_staging(out));
}

TEST_F(OutputTest, ASymlinkAtATargetIsReplacedNotWrittenThrough) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  write(dir_ / "victim.txt", "precious");
  fs::create_symlink(dir_ / "victim.txt", out / "a.csv");
  {
    OutputFolder folder(out, "run", nullptr);
    folder.add("a.csv") << "new a";
    folder.commit();
  }
  EXPECT_EQ(read_file(dir_ / "victim.txt"), "precious");
  EXPECT_FALSE(fs::is_symlink(out / "a.csv"));
  EXPECT_EQ(read_file(out / "a.csv"), "new a");
}

TEST_F(OutputTest, ASecondWriterIsRefusedAtOnce) {
  const fs::path out = dir_ / "out";
  OutputFolder first(out, "first", nullptr);
  EXPECT_THROW(OutputFolder(out, "second", nullptr), OutputFolderBusy);
}

TEST_F(OutputTest, AnInterruptedStagingFolderIsRemoved) {
  const fs::path out = folder_with_old_unit("out");
  fs::create_directory(out / ".liedyn-staging-AbC123");
  write(out / ".liedyn-staging-AbC123/a.csv", "half a run");
  std::ostringstream notes;
  { OutputFolder folder(out, "next", &notes); }
  EXPECT_EQ(listing(out), (std::set<std::string>{"a.csv", "b.csv", "run.json"}));
  EXPECT_EQ(read_file(out / "a.csv"), "old a");
  EXPECT_NE(notes.str().find("removed the staging folder of an interrupted run"), std::string::npos)
      << notes.str();
}

TEST_F(OutputTest, ACommitPastItsPointOfNoReturnIsFinished) {
  // A crash after the commit record was written and a.csv was renamed, before b.csv and the
  // manifest: the next run into the folder finishes the commit.
  const fs::path out = folder_with_old_unit("out");
  const fs::path staging = out / ".liedyn-staging-XyZ789";
  fs::create_directory(staging);
  write(out / "a.csv", "new a");  // already renamed
  write(staging / "b.csv", "new b");
  write(staging / "run.json", R"({"format": "liedyn run manifest 1", "runs": {}, "files": {}})");
  write(staging / "COMMIT", "a.csv\nb.csv\nrun.json\n");
  fs::remove(out / "run.json");
  std::ostringstream notes;
  { OutputFolder folder(out, "next", &notes); }
  EXPECT_EQ(listing(out), (std::set<std::string>{"a.csv", "b.csv", "run.json"}));
  EXPECT_EQ(read_file(out / "b.csv"), "new b");
  EXPECT_NE(notes.str().find("finished the commit of an interrupted run (2 files)"),
            std::string::npos)
      << notes.str();
}

TEST_F(OutputTest, TemporariesOfEndedOlderRunsAreRemoved) {
  // Earlier versions wrote "<file>.tmp-<pid>" and left them behind when killed.
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string stale = "frames.csv.tmp-" + std::to_string(dead);
  const std::string live = "frames.csv.tmp-" + std::to_string(::getpid());
  write(out / stale, "left by a killed run");
  write(out / live, "a live writer's");
  { OutputFolder folder(out, "next", nullptr); }
  EXPECT_FALSE(fs::exists(out / stale));
  EXPECT_TRUE(fs::exists(out / live)) << "a live process's temporary is not touched";
}

TEST_F(OutputTest, NamesThatOnlyLookLikeTemporariesAreLeftAlone) {
  // A user's files whose "pid" is not one (too many digits for any pid, beyond pid_max, or not
  // digits) are not ours: they stay, and opening the folder does not fail on them.
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  const std::vector<std::string> names = {"data.tmp-99999999999999999999", "data.tmp-4194305", "data.tmp-12a",
                                          ".tmp-1", "data.tmp-"};
  for (const std::string& name : names) write(out / name, "the user's");
  EXPECT_NO_THROW({ OutputFolder folder(out, "next", nullptr); });
  for (const std::string& name : names) EXPECT_TRUE(fs::exists(out / name)) << name;
}

TEST_F(OutputTest, AWriteFailureLeavesTheEarlierUnit) {
  // A file size limit makes writes fail with EFBIG, as a full disk fails them with ENOSPC:
  // the commit must throw before anything in the folder is replaced.
  const fs::path out = folder_with_old_unit("out");
  const pid_t child = ::fork();
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try {
      OutputFolder folder(out, "big", nullptr);
      folder.add("a.csv") << std::string(100, 'a');
      folder.add("b.csv") << std::string(1 << 20, 'b');
      folder.commit();
    } catch (const std::runtime_error& e) {
      ::_exit(std::string(e.what()).find("b.csv: write failed") != std::string::npos ? 7 : 8);
    }
    ::_exit(9);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 7) << "7: the commit threw naming b.csv";
  EXPECT_EQ(read_file(out / "a.csv"), "old a");
  EXPECT_EQ(read_file(out / "b.csv"), "old b");
  EXPECT_FALSE(has_staging(out));
}

// ---------------------------------------------------------------------------------------
// AtomicFile
// ---------------------------------------------------------------------------------------

TEST_F(OutputTest, AtomicFileTemporariesAreUniqueAndPlantedNamesAreHarmless) {
  write(dir_ / "victim.txt", "precious");
  // The name earlier versions used: a planted symlink of it used to redirect the write.
  fs::create_symlink(dir_ / "victim.txt", dir_ / ("out.csv.tmp-" + std::to_string(::getpid())));
  {
    AtomicFile first(dir_ / "out.csv");
    AtomicFile second(dir_ / "out.csv");
    std::set<std::string> temporaries;
    for (const std::string& name : listing(dir_)) {
      if (name.rfind(".out.csv.liedyn-", 0) == 0) temporaries.insert(name);
    }
    EXPECT_EQ(temporaries.size(), 2u);
    first.stream() << "one";
    first.commit();
  }
  EXPECT_EQ(read_file(dir_ / "victim.txt"), "precious");
  EXPECT_EQ(read_file(dir_ / "out.csv"), "one");
  for (const std::string& name : listing(dir_)) {
    EXPECT_EQ(name.find(".liedyn-"), std::string::npos) << name << " left behind";
  }
}

// ---------------------------------------------------------------------------------------
// The command line
// ---------------------------------------------------------------------------------------

constexpr const char* kSpinner = R"({
  "time_step": 0.001, "frames": 20,
  "bodies": [{ "name": "box", "mass": 1, "inertia": [1, 2, 3],
               "angular_velocity": [0.1, 3, 0.1] }]
})";

TEST_F(OutputTest, SimulateIntoALockedFolderFailsAtOnce) {
  write(dir_ / "scene.json", kSpinner);
  OutputFolder held(dir_ / "out", "another run", nullptr);
  const auto start = std::chrono::steady_clock::now();
  const Result r = run({"simulate", "scene.json", "--out", "out", "--quiet"});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20)) << "it waited";
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("another liedyn run is writing into this folder"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out/trajectory.csv"));
}

TEST_F(OutputTest, SimulateWritesTrajectoryAndFramesAsOneUnit) {
  write(dir_ / "scene.json", kSpinner);
  ASSERT_EQ(run({"simulate", "scene.json", "--out", "out", "--quiet"}).exit_code, 0);
  const nlohmann::json manifest = nlohmann::json::parse(read_file(dir_ / "out/run.json"));
  EXPECT_EQ(manifest.at("files").at("trajectory.csv").at("run"),
            manifest.at("files").at("frames.csv").at("run"));
  EXPECT_EQ(manifest.at("files").at("trajectory.csv").at("bytes"),
            static_cast<long long>(fs::file_size(dir_ / "out/trajectory.csv")));
}

TEST_F(OutputTest, SimulateUnderAFileSizeLimitKeepsThePreviousPair) {
  write(dir_ / "scene.json", kSpinner);
  ASSERT_EQ(run({"simulate", "scene.json", "--out", "out", "--quiet"}).exit_code, 0);
  const std::string trajectory = read_file(dir_ / "out/trajectory.csv");
  const std::string frames = read_file(dir_ / "out/frames.csv");
  nlohmann::json longer = nlohmann::json::parse(kSpinner);
  longer["frames"] = 2000;  // ~300 kB of trajectory, over the 64 kB limit below
  write(dir_ / "longer.json", longer.dump());
  const std::string command = "cd '" + dir_.string() + "' && ulimit -f 64 && '" + LIEDYN_CLI +
                              "' simulate longer.json --out out --quiet > /dev/null 2> err.txt";
  const int status = std::system(("bash -c \"" + command + "\"").c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1) << read_file(dir_ / "err.txt");
  EXPECT_NE(read_file(dir_ / "err.txt").find("write failed"), std::string::npos)
      << read_file(dir_ / "err.txt");
  EXPECT_EQ(read_file(dir_ / "out/trajectory.csv"), trajectory);
  EXPECT_EQ(read_file(dir_ / "out/frames.csv"), frames);
  EXPECT_FALSE(has_staging(dir_ / "out"));
}

TEST_F(OutputTest, ATerminatingSignalRemovesTheStagedFilesAndExits128PlusSignal) {
  nlohmann::json scene = nlohmann::json::parse(kSpinner);
  scene["frames"] = 100000000;  // runs until killed
  write(dir_ / "scene.json", scene.dump());
  write(dir_ / "short.json", kSpinner);
  ASSERT_EQ(run({"simulate", "short.json", "--out", "out", "--quiet"}).exit_code, 0);
  const std::string before = read_file(dir_ / "out/trajectory.csv");
  for (const int signal : {SIGTERM, SIGINT, SIGHUP}) {
    const std::string cli = LIEDYN_CLI, scene_file = (dir_ / "scene.json").string(),
                      out = (dir_ / "out").string();
    const char* argv[] = {cli.c_str(), "simulate", scene_file.c_str(), "--out", out.c_str(),
                          "--quiet", nullptr};
    pid_t pid = 0;
    ASSERT_EQ(::posix_spawn(&pid, cli.c_str(), nullptr, nullptr, const_cast<char**>(argv), environ), 0);
    for (int i = 0; i < 400 && !has_staging(dir_ / "out"); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    ASSERT_TRUE(has_staging(dir_ / "out")) << "the run never started";
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    ::kill(pid, signal);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << "signal " << signal;
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal);
    EXPECT_EQ(listing(dir_ / "out"),
              (std::set<std::string>{"frames.csv", "run.json", "shapes.json", "trajectory.csv"}))
        << "signal " << signal;
    EXPECT_EQ(read_file(dir_ / "out/trajectory.csv"), before);
  }
}

TEST_F(OutputTest, ASceneCannotChooseWhereIpoptWrites) {
  nlohmann::json scene = nlohmann::json::parse(kSpinner);
  scene["solver"] = {{"ipopt", {{"output_file", "../clobbered.txt"}}}};
  write(dir_ / "scene.json", scene.dump());
  const Result r = run({"compare", "scene.json", "--backends", "ipopt"});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("solver.ipopt.output_file: is not read from scene files"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_.parent_path() / "clobbered.txt"));
  // The log file comes from the command line.
  write(dir_ / "scene.json", kSpinner);
  const Result logged = run({"compare", "scene.json", "--backends", "ipopt", "--ipopt-log", "ipopt.txt"});
  EXPECT_EQ(logged.exit_code, 0) << logged.out << logged.err;
  EXPECT_NE(read_file(dir_ / "ipopt.txt").find("Ipopt"), std::string::npos);
}

TEST_F(OutputTest, NamesAreQuotedInCsvAndControlCharactersRefused) {
  nlohmann::json scene = nlohmann::json::parse(kSpinner);
  scene["bodies"][0]["name"] = "a,b \"c\"";
  write(dir_ / "scene.json", scene.dump());
  ASSERT_EQ(run({"simulate", "scene.json", "--out", "out", "--quiet"}).exit_code, 0);
  // Every row parses to the header's 12 columns, and the name comes back whole.
  const std::string check =
      "/usr/bin/python3 -c \"import csv,sys; rows=list(csv.reader(open(sys.argv[1], newline=''))); "
      "assert all(len(r)==12 for r in rows), set(map(len,rows)); "
      "assert rows[1][2]=='a,b \\\"c\\\"', rows[1][2]\" '" +
      (dir_ / "out/trajectory.csv").string() + "'";
  EXPECT_EQ(std::system(check.c_str()), 0) << check;
  for (const std::string& bad : {std::string("a\nb"), std::string("a\rb"), std::string("a\x1b[2Jb"),
                                std::string("a\0b", 3)}) {
    scene["bodies"][0]["name"] = bad;
    write(dir_ / "bad.json", scene.dump());
    const Result r = run({"simulate", "bad.json", "--out", "bad", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("bodies[0].name: must not contain control characters"), std::string::npos)
        << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

TEST_F(OutputTest, SceneFilesAreRegularBoundedAndWithoutNul) {
  ASSERT_EQ(::mkfifo((dir_ / "fifo.json").c_str(), 0600), 0);
  Result r = run({"simulate", "fifo.json", "--out", "out"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("fifo.json: is not a regular file"), std::string::npos) << r.err;
  r = run({"simulate", "/dev/zero", "--out", "out"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/dev/zero: is not a regular file"), std::string::npos) << r.err;
  write(dir_ / "nul.json", std::string(kSpinner) + std::string("\0{\"junk\": 1}", 12));
  r = run({"simulate", "nul.json", "--out", "out"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("contains a NUL byte at offset"), std::string::npos) << r.err;
  {
    std::ofstream big(dir_ / "big.json");
    big << std::string(kMaxSceneFileBytes + 1, ' ');
  }
  r = run({"simulate", "big.json", "--out", "out"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("more than a scene file may be"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(OutputTest, FramesBeyondTheCapAreRefused) {
  nlohmann::json scene = nlohmann::json::parse(kSpinner);
  scene["frames"] = 2147483647;
  write(dir_ / "scene.json", scene.dump());
  const Result r = run({"simulate", "scene.json", "--out", "out"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("frames: must be an integer in [0, 1000000000]"), std::string::npos) << r.err;
}

TEST_F(OutputTest, SimulateReportsSolveAndOutputTimesApart) {
  write(dir_ / "scene.json", kSpinner);
  const Result r = run({"simulate", "scene.json", "--out", "out", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("solved in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("outputs written in"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace liedyn

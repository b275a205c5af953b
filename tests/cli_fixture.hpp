#pragma once
// A test fixture that runs the `liedyn` binary (LIEDYN_CLI) as a process in a fresh temporary
// directory per test (kept on failure, for inspection). Shared by test_cli.cpp and
// test_optimization.cpp.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace liedyn::test {

// The whole file (empty if it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The smallest normalised loss in an optimisation's history.csv
// (iteration,loss,normalized_loss,…); +∞ without rows.
inline double best_normalized_loss(const std::filesystem::path& history_csv) {
  std::ifstream history(history_csv);
  std::string line;
  std::getline(history, line);  // header
  double best = INFINITY;
  while (std::getline(history, line)) {
    std::stringstream fields(line);
    std::string field;
    for (int i = 0; i < 3; ++i) std::getline(fields, field, ',');
    best = std::min(best, std::stod(field));
  }
  return best;
}

class CliFixture : public ::testing::Test {
 protected:
  // `prefix` names the temporary directory: <tmp>/<prefix><pid>_<test name>.
  explicit CliFixture(std::string prefix) : prefix_(std::move(prefix)) {}

  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           (prefix_ + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) std::filesystem::remove_all(dir_);  // kept for inspection on failure
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
    std::filesystem::remove(dir_ / "stdout.txt");
    std::filesystem::remove(dir_ / "stderr.txt");
    return r;
  }

  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

}  // namespace liedyn::test

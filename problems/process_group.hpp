#pragma once
// The processes that share one sweep or one multi-start optimisation: the ranks of an MPI job
// (`mpirun -np P liedyn …`, problems/mpi_group.cpp, in the liedyn executable when it is built
// with MPI), or this process alone (the base class).
//
// Rank 0 writes every output. The others send it their results as they finish (the latest
// text replaces the earlier ones of that rank) and a final message at their end; rank 0
// collects them between its own runs (checkpoints) and waits for every final message before
// it writes the outputs.

#include <exception>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "output_folder.hpp"

namespace liedyn {

class ProcessGroup {
 public:
  virtual ~ProcessGroup() = default;

  virtual int rank() const { return 0; }
  virtual int size() const { return 1; }
  // Whether every rank says true (a collective: every rank must call it).
  virtual bool all_true(bool mine) { return mine; }
  // Rank 0's text on every rank (a collective).
  virtual std::string broadcast(const std::string& from_root) { return from_root; }

  // Ranks > 0: results so far (`final`: the last message of this rank).
  virtual void send(const std::string& /*text*/, bool /*final*/) {}
  // Rank 0: the messages that have arrived; with `wait`, blocks until every other rank's
  // final message has arrived.
  struct Message {
    int rank;
    std::string text;
    bool final;
  };
  virtual std::vector<Message> receive(bool /*wait*/) { return {}; }

  // Ends every rank's process at once with `code` (an error on one rank that the others,
  // waiting for it, would never see); returns where there is only this process.
  virtual void abort(int /*code*/) {}
};

// This process alone.
ProcessGroup& single_process();

// Thrown on ranks > 0 when rank 0 could not start a shared run (rank 0 reports why).
struct RootFailed : std::runtime_error {
  RootFailed() : std::runtime_error("rank 0 could not start") {}
};

// The start of a shared run (a collective): rank 0 locks the output folder `dir` into
// `folder` (output_folder.hpp) and, when `checkpoint` is not empty, reads it (SceneError
// naming it when it is missing or unreadable); every rank gets the checkpoint's text (empty
// without one). When rank 0 cannot start, it throws its error and the others RootFailed.
std::string open_output_on_root(ProcessGroup& group, std::optional<OutputFolder>& folder,
                                const std::filesystem::path& dir, const std::string& command,
                                const std::filesystem::path& checkpoint);

// The MPI ranks of this process when mpirun (or srun) started it and liedyn was built with
// MPI (problems/mpi_group.cpp, part of the liedyn executable only); null when it runs alone.
// Throws std::runtime_error when it was started as one of several ranks by a liedyn built
// without MPI (each rank would run the whole grid and write the same folder).
std::unique_ptr<ProcessGroup> start_process_group(int& argc, char**& argv);

}  // namespace liedyn

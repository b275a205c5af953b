#pragma once
// `liedyn sweep` and `liedyn sweep-merge`: the grid of problems/sweep.hpp run by one process
// with threads (-j), by the ranks of an MPI job, or by Slurm array tasks (--shard), with
// checkpoints and --resume; and the shards joined into the outputs of one run.
//
// Output folders (problems/output_folder.hpp, each locked by the process that writes it):
//   OUT/                     sweep.csv, sweep.json, *_vs_time.png, checkpoint.json
//   OUT/shard-I-of-N/        the same for the grid points of shard I (--shard I/N)
// checkpoint.json is sweep.json of the runs finished so far, replaced as runs finish (a unit
// of its own, at most once a second) and written whole with the outputs; --resume keeps its
// runs and runs the rest. Under MPI rank 0 writes
// everything; the other ranks' runs reach its checkpoint as rank 0 finishes its own runs.

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "process_group.hpp"
#include "sweep.hpp"

namespace liedyn {

struct SweepCommand {
  std::string scene_file;
  std::filesystem::path out;
  bool quiet = false;
  bool resume = false;
  // "I/N", or "N" with I from $SLURM_ARRAY_TASK_ID; empty: the whole grid.
  std::string shard;
  SweepOptions options;  // the axes, refinement, gradient sample, repeats, jobs
};

// Parses `--shard` ("I/N" or "N"): SceneError naming --shard (or SLURM_ARRAY_TASK_ID) when
// malformed or out of range.
SweepShare parse_shard(const std::string& text, const char* slurm_array_task_id);

// Runs the command; exit status as the other commands: 0, 2 bad input (SceneError thrown),
// 4 a run failed. Rank 0 prints the table to `out`.
int run_sweep_command(const SweepCommand& command, ProcessGroup& group, std::ostream& out);

// `liedyn sweep-merge DIR… --out OUT`: the sweep.json of every shard folder joined and
// written to OUT as one run writes them (SceneError for parts that are not one sweep's).
int run_sweep_merge(const std::vector<std::filesystem::path>& dirs,
                    const std::filesystem::path& out_dir, std::ostream& out);

}  // namespace liedyn

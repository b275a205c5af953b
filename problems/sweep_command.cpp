#include "sweep_command.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "output_folder.hpp"
#include "scene.hpp"

#include <unistd.h>

namespace liedyn {
namespace {

using ordered_json = nlohmann::ordered_json;

// A sweep.json or checkpoint.json's text (untrusted: SceneError naming `source`).
SweepResult read_sweep_json(const std::string& text, const std::string& source) {
  ordered_json value;
  try {
    value = ordered_json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw SceneError(source, "", std::string("is not JSON (") + e.what() + ")");
  }
  return sweep_from_json(value, source);
}

SweepResult read_sweep_file(const std::filesystem::path& file) {
  return read_sweep_json(read_named_input(file, std::uintmax_t(1) << 30, "sweep result"), file.string());
}

int exit_status(const SweepResult& result) {
  const auto failed = [](const SweepRun& r) { return r.failed; };
  return std::any_of(result.runs.begin(), result.runs.end(), failed) ||
                 std::any_of(result.references.begin(), result.references.end(), failed)
             ? 4
             : 0;
}

}  // namespace

SweepShare parse_shard(const std::string& text, const char* slurm_array_task_id) {
  const auto integer = [](const std::string& s, const std::string& field) {
    std::size_t used = 0;
    int value = -1;
    try {
      value = std::stoi(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (s.empty() || used != s.size() || value < 0) {
      throw SceneError("--shard", field, "\"" + s + "\" is not an integer ≥ 0");
    }
    return value;
  };
  SweepShare share;
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos) {
    share.count = integer(text, "count");
    if (slurm_array_task_id == nullptr) {
      throw SceneError("--shard", "index",
                       "is not given (\"I/N\") and SLURM_ARRAY_TASK_ID is not set");
    }
    share.index = integer(slurm_array_task_id, "SLURM_ARRAY_TASK_ID");
  } else {
    share.index = integer(text.substr(0, slash), "index");
    share.count = integer(text.substr(slash + 1), "count");
  }
  if (share.count < 1) throw SceneError("--shard", "count", "must be ≥ 1");
  if (share.index >= share.count) {
    throw SceneError("--shard", "index",
                     std::to_string(share.index) + " is not below the count " +
                         std::to_string(share.count) + " (Slurm: --array=0-" +
                         std::to_string(share.count - 1) + ")");
  }
  return share;
}

int run_sweep_command(const SweepCommand& command, ProcessGroup& group, std::ostream& out) {
  SweepOptions options = command.options;
  const bool root = group.rank() == 0;
  std::filesystem::path dir = command.out;
  if (!command.shard.empty()) {
    if (group.size() > 1) {
      throw SceneError("--shard", "", "and mpirun both split the grid: use one of them");
    }
    options.share = parse_shard(command.shard, std::getenv("SLURM_ARRAY_TASK_ID"));
    dir /= "shard-" + std::to_string(options.share.index) + "-of-" +
           std::to_string(options.share.count);
  } else if (group.size() > 1) {
    options.share = {group.rank(), group.size()};
    options.other_processes = group.size() - 1;
  }
  options.progress = command.quiet || !root ? nullptr : &std::cerr;
  options.progress_bar = options.progress != nullptr && ::isatty(2) != 0;

  // Rank 0 locks the folder and reads the checkpoint once every grid point has parsed (bad
  // input writes nothing); every rank then resumes from the same checkpoint text.
  std::optional<OutputFolder> folder;
  SweepResult checkpoint;
  const std::filesystem::path checkpoint_file = dir / "checkpoint.json";
  if (command.resume) {
    options.resume = &checkpoint;
    options.resume_source = checkpoint_file.string();
  }
  // Every rank's latest result; rank 0 checkpoints the union of them.
  std::vector<std::optional<SweepResult>> latest(group.size());
  const auto share_of_rank = [&](int r) { return group.size() > 1 ? SweepShare{r, group.size()} : options.share; };
  const auto in_share = [](const SweepRun& run, const SweepShare& share) { return run.index % share.count == share.index; };
  options.before_runs = [&] {
    const std::string text = open_output_on_root(group, folder, dir, "sweep " + command.scene_file,
                                                 command.resume ? checkpoint_file : std::filesystem::path());
    if (!command.resume) return;
    checkpoint = read_sweep_json(text, checkpoint_file.string());
    // What the checkpoint holds of a rank's share stands until that rank reports.
    for (int r = 0; r < group.size(); ++r) {
      SweepResult part = checkpoint;
      part.share = share_of_rank(r);
      part.runs.clear();
      for (const SweepRun& run : checkpoint.runs) {
        if (in_share(run, part.share)) part.runs.push_back(run);
      }
      latest[r] = std::move(part);
    }
  };
  const auto take_messages = [&](bool wait) {
    for (ProcessGroup::Message& m : group.receive(wait)) {
      try {
        latest.at(m.rank) = sweep_from_json(ordered_json::parse(m.text), "rank " + std::to_string(m.rank));
      } catch (const std::exception& e) {  // not bad input: a fault between ranks (abort them all)
        throw std::runtime_error("rank " + std::to_string(m.rank) + " sent a result rank 0 cannot read: " + e.what());
      }
    }
  };
  const auto union_of_ranks = [&](bool complete) {  // complete: every rank's final result
    std::vector<SweepResult> parts;
    std::vector<std::string> sources;
    for (int r = 0; r < group.size(); ++r) {
      if (!latest[r]) continue;
      parts.push_back(*latest[r]);
      sources.push_back("rank " + std::to_string(r));
    }
    SweepResult merged = merge_sweeps(parts, sources, complete);
    if (group.size() == 1) merged.share = parts.front().share;  // a shard stays one
    return merged;
  };
  auto last_checkpoint = std::chrono::steady_clock::time_point{};
  options.on_finished = [&](const SweepResult& so_far) {
    if (!root) {
      group.send(sweep_to_json(so_far).dump(), false);
      return;
    }
    latest[0] = so_far;
    take_messages(false);
    // A checkpoint is a commit (an fsync per file): at most one a second, however short the
    // runs; the last one goes with the outputs.
    const auto now = std::chrono::steady_clock::now();
    if (now - last_checkpoint < std::chrono::seconds(1)) return;
    last_checkpoint = now;
    folder->add("checkpoint.json") << sweep_to_json(union_of_ranks(false)).dump(1) << "\n";
    folder->commit();
  };

  SweepResult result = run_sweep(read_scene_file(command.scene_file), command.scene_file, options);
  if (!root) {
    group.send(sweep_to_json(result).dump(), true);
    return exit_status(result);
  }
  latest[0] = result;
  take_messages(true);
  result = union_of_ranks(group.size() > 1);
  if (command.resume) {
    const auto kept = std::count_if(checkpoint.runs.begin(), checkpoint.runs.end(), [&](const SweepRun& run) {
      return group.size() > 1 || in_share(run, options.share);
    });
    out << "resumed from " << checkpoint_file.string() << ": kept " << kept << " of " << result.runs.size()
        << " runs\n";
  }
  // The checkpoint, finished, goes with the outputs (one unit).
  folder->add("checkpoint.json") << sweep_to_json(result).dump(1) << "\n";
  write_sweep(result, *folder);
  out << format_sweep(result);
  out << "outputs: " << dir.string() << "/sweep.csv, sweep.json and the *_vs_time.png plots\n";
  if (options.share.count > 1 && group.size() == 1) {
    out << "shard " << options.share.index << " of " << options.share.count
        << ": join the shards with liedyn sweep-merge " << command.out.string()
        << "/shard-*-of-" << options.share.count << " --out DIR\n";
  }
  return exit_status(result);
}

int run_sweep_merge(const std::vector<std::filesystem::path>& dirs,
                    const std::filesystem::path& out_dir, std::ostream& out) {
  std::vector<SweepResult> parts;
  std::vector<std::string> sources;
  for (const std::filesystem::path& dir : dirs) {
    sources.push_back((dir / "sweep.json").string());
    parts.push_back(read_sweep_file(dir / "sweep.json"));
  }
  if (parts.empty()) throw SceneError("sweep-merge", "", "no shard folders given");
  const SweepResult merged = merge_sweeps(parts, sources);
  OutputFolder folder(out_dir, "sweep-merge", &std::cerr);
  write_sweep(merged, folder);
  out << format_sweep(merged);
  out << "outputs: " << out_dir.string() << "/sweep.csv, sweep.json and the *_vs_time.png plots\n";
  return exit_status(merged);
}

}  // namespace liedyn

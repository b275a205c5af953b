#pragma once
// An output folder (`--out DIR`) whose files are replaced as a unit.
//
// The files of a run belong together (trajectory.csv with its frames.csv; parameters.csv with
// the trajectory it produced), so a run never replaces them one by one as it goes:
//  1. The folder is locked (flock on the folder itself) for the life of the OutputFolder: a
//     second run into it fails at once (OutputFolderBusy) instead of mixing its files in.
//  2. Every file of a unit is written into a fresh staging folder ".liedyn-staging-XXXXXX"
//     inside DIR (files created exclusively, see output.hpp), then fsynced: a full disk or
//     a write error shows here, while DIR still holds the previous unit untouched.
//  3. commit() checks that each target can be replaced (not a folder), writes the list of
//     the unit's files to "COMMIT" in the staging folder — the point of no return — removes
//     the old manifest, renames every file into DIR, and the new manifest run.json last.
//     Signals are held during the renames.
//  4. Opening the folder settles what an interrupted run left: a staging folder with COMMIT
//     (a commit cut by a crash or kill -9) is rolled forward; one without is removed, as are
//     the "<file>.tmp-<pid>" temporaries of older liedyn versions whose process is gone.
// So DIR holds either the previous unit or the new one; while a commit is under way, or after
// a crash in it until the next liedyn run into DIR, run.json is absent. run.json names, for
// every file liedyn wrote into DIR, the run that wrote it (an id, the command, the time) and
// its size, so files of different runs are never mistaken for one run's.
// Not covered: power loss or an OS crash (folders are not fsynced), and writers other than
// liedyn.

#include <filesystem>
#include <functional>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "output.hpp"

namespace liedyn {

// Another run holds the folder (exit 1 in the driver).
struct OutputFolderBusy : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class OutputFolder {
 public:
  // Creates `dir` if missing, locks it, settles an interrupted run's leftovers (one line per
  // repair to `notes`, if non-null). `command` describes the run in run.json.
  OutputFolder(std::filesystem::path dir, std::string command, std::ostream* notes);
  ~OutputFolder();  // discards an uncommitted unit
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  // A new file of the current unit, written to the staging folder; `name` is a plain file
  // name. Throws std::runtime_error if it cannot be created.
  std::ostream& add(const std::string& name);
  // Writes out, fsyncs and closes the unit's file `name` now rather than at commit(): a unit
  // of thousands of files (an export's frames) must not hold a descriptor, a buffer and one
  // of the 256 slots of files removed on SIGINT/SIGTERM (output.hpp) for each until then. A
  // signal after this leaves the file in the staging folder, for the next run into the
  // folder to remove (step 4 above). Its stream must not be written again. Throws
  // std::runtime_error if a write failed, std::logic_error if `name` is not a file of the unit.
  void finish(const std::string& name);
  // Which files of earlier units this unit replaces even where it has no file of that name
  // (an export of every 10th frame replaces an export of every frame): of the files the
  // folder's run.json lists, those `replaces` accepts are removed after the unit's files are
  // in place (only what liedyn wrote: run.json names it). Empty: none.
  using Replaces = std::function<bool(const std::string& name)>;
  // Replaces the unit's files in the folder together (see above), then removes the earlier
  // files that `replaces` accepts; throws std::runtime_error, with the folder's previous unit
  // in place, if the unit cannot be written. The next add() starts a new unit. (A crash
  // between the renames and the removals leaves those earlier files, no longer in run.json.)
  void commit(const Replaces& replaces = {});

  const std::filesystem::path& path() const { return dir_; }
  const std::string& run_id() const { return run_id_; }

 private:
  struct Staged {
    std::string name;
    std::unique_ptr<FileStream> file;
    int cleanup_slot = -1;
  };
  FileStream& stage(const std::string& name);  // a file in the staging folder
  void settle_leftovers(std::ostream* notes);
  // Ends the current unit: releases its files and its staging folder, removing what is not
  // left (kNothing: discard the unit; kFiles: the files were renamed away; kEverything: a
  // commit cut half-way, for the next run to finish).
  enum class Leave { kNothing, kFiles, kEverything };
  void close_unit(Leave leave);
  // run.json after this unit; `superseded` gets the earlier files `replaces` accepts.
  std::string manifest_text(const Replaces& replaces, std::vector<std::string>& superseded) const;

  std::filesystem::path dir_;
  std::string command_, run_id_, started_;
  int dirfd_ = -1;
  int staging_fd_ = -1;
  std::string staging_name_;
  int staging_slot_ = -1;
  std::vector<Staged> staged_;
};

}  // namespace liedyn

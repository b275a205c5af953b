#include "output_folder.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <ctime>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "output_internal.hpp"

namespace liedyn {
namespace {

using internal::error_text;
using json = nlohmann::json;

constexpr const char* kManifest = "run.json";
constexpr const char* kCommitRecord = "COMMIT";
constexpr const char* kStagingPrefix = ".liedyn-staging-";

std::string utc_now() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

std::string new_run_id() {
  std::random_device device;
  std::ostringstream os;
  os << std::hex << device() << device() << '-' << ::getpid();
  return os.str();
}

bool is_folder_at(int dirfd, const std::string& name) {
  struct stat st {};
  return ::fstatat(dirfd, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISDIR(st.st_mode);
}

// The names of a commit record, one per line.
std::vector<std::string> read_lines(int dirfd, const char* name) {
  std::vector<std::string> lines;
  const int fd = ::openat(dirfd, name, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return lines;
  std::string text;
  char chunk[4096];
  for (ssize_t n; (n = ::read(fd, chunk, sizeof chunk)) > 0;) text.append(chunk, static_cast<std::size_t>(n));
  ::close(fd);
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.find('/') == std::string::npos) lines.push_back(line);
  }
  return lines;
}

// Removes the regular files of a staging folder and the folder; false if something else is
// in it (left alone).
bool remove_staging(int dirfd, const std::filesystem::path& staging) {
  bool clean = true;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(staging, error)) {
    if (entry.is_symlink() || entry.is_regular_file()) {
      std::filesystem::remove(entry.path(), error);
    } else {
      clean = false;
    }
  }
  return clean && ::unlinkat(dirfd, staging.filename().c_str(), AT_REMOVEDIR) == 0;
}

// The process id of a temporary file "<name>.tmp-<pid>" that a writer left (atomic writes
// stage into such files), or 0 when `name` is not one. A pid is at most 2²² on Linux
// (pid_max), so more than 7 digits are not one either.
long temporary_pid(const std::string& name) {
  const std::size_t at = name.rfind(".tmp-");
  if (at == std::string::npos || at == 0) return 0;
  const std::string digits = name.substr(at + 5);
  if (digits.empty() || digits.size() > 7 ||
      !std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return c >= '0' && c <= '9'; })) {
    return 0;
  }
  const long pid = std::stol(digits);
  return pid <= (1L << 22) ? pid : 0;
}

}  // namespace

OutputFolder::OutputFolder(std::filesystem::path dir, std::string command, std::ostream* notes)
    : dir_(std::move(dir)), command_(std::move(command)), run_id_(new_run_id()), started_(utc_now()) {
  std::error_code error;
  std::filesystem::create_directories(dir_, error);
  dirfd_ = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dirfd_ < 0) {
    throw std::runtime_error(dir_.string() + ": cannot open the output folder: " +
                             (error ? error.message() : error_text(errno)));
  }
  if (::flock(dirfd_, LOCK_EX | LOCK_NB) != 0) {
    const int reason = errno;
    ::close(dirfd_);
    if (reason == EWOULDBLOCK) {
      throw OutputFolderBusy(dir_.string() +
                             ": another liedyn run is writing into this folder (it is locked); "
                             "wait for it to end or choose another --out");
    }
    throw std::runtime_error(dir_.string() + ": cannot lock the output folder: " + error_text(reason));
  }
  settle_leftovers(notes);
}

OutputFolder::~OutputFolder() {
  close_unit(Leave::kNothing);  // an uncommitted unit is discarded
  ::close(dirfd_);  // releases the lock
}

void OutputFolder::settle_leftovers(std::ostream* notes) {
  // Safe under the lock: every liedyn writer into this folder holds it for its whole life, so
  // nothing found here belongs to a live run (except .tmp-<pid> files of versions that did
  // not lock, hence the pid check).
  std::vector<std::filesystem::path> stagings, temporaries;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir_, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kStagingPrefix, 0) == 0 && entry.is_directory() && !entry.is_symlink()) {
      stagings.push_back(entry.path());
    } else if (const long pid = temporary_pid(name); pid > 0 && entry.is_regular_file() && !entry.is_symlink()) {
      if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
        temporaries.push_back(entry.path());
      }
    }
  }
  for (const std::filesystem::path& staging : stagings) {
    const int fd = ::open(staging.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) continue;
    const std::vector<std::string> names = read_lines(fd, kCommitRecord);
    int moved = 0;
    if (!names.empty()) {  // a commit past its point of no return: finish it
      ::unlinkat(dirfd_, kManifest, 0);
      for (const std::string& name : names) {
        if (!is_folder_at(dirfd_, name) &&
            ::renameat(fd, name.c_str(), dirfd_, name.c_str()) == 0) {
          ++moved;
        }
      }
    }
    ::close(fd);
    const bool removed = remove_staging(dirfd_, staging);
    if (notes != nullptr) {
      *notes << "liedyn: " << dir_.string() << ": "
             << (names.empty() ? "removed the staging folder of an interrupted run"
                               : "finished the commit of an interrupted run (" +
                                     std::to_string(moved) + " files)")
             << (removed ? "" : "; " + staging.filename().string() + " holds other files, left alone")
             << '\n';
    }
  }
  for (const std::filesystem::path& file : temporaries) {
    std::filesystem::remove(file, error);
    if (notes != nullptr) {
      *notes << "liedyn: " << dir_.string() << ": removed " << file.filename().string()
             << ", a temporary of a run that ended\n";
    }
  }
}

std::ostream& OutputFolder::add(const std::string& name) {
  if (name.empty() || name.find('/') != std::string::npos || name[0] == '.' || name == kManifest ||
      name == kCommitRecord) {
    throw std::logic_error("OutputFolder::add: not a plain output name: " + name);
  }
  if (staging_fd_ < 0) {
    staging_fd_ = internal::create_unique_folder(dirfd_, kStagingPrefix, dir_.string(), staging_name_);
    staging_slot_ = internal::register_removal(dirfd_, staging_name_, true);
  }
  return stage(name).stream();
}

FileStream& OutputFolder::stage(const std::string& name) {
  const int fd = ::openat(staging_fd_, name.c_str(),
                          O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) {
    throw std::runtime_error((dir_ / name).string() + ": cannot create: " + error_text(errno));
  }
  staged_.push_back({name, std::make_unique<FileStream>(fd),
                     internal::register_removal(staging_fd_, name, false)});
  return *staged_.back().file;
}

void OutputFolder::finish(const std::string& name) {
  for (Staged& s : staged_) {
    if (s.name == name && s.file) {
      s.file->finish((dir_ / s.name).string());
      s.file.reset();  // its buffer
      // And its slot among the files a signal removes (there are 256): a signal now leaves
      // it in the staging folder, which the next run into the folder removes (a staging
      // folder without COMMIT, settle_leftovers).
      internal::release_removal(s.cleanup_slot);
      s.cleanup_slot = -1;
      return;
    }
  }
  throw std::logic_error("OutputFolder::finish: " + name + " is not an open file of the unit");
}

std::string OutputFolder::manifest_text(const Replaces& replaces, std::vector<std::string>& superseded) const {
  // Entries of the previous manifest for files this unit does not replace are kept while the
  // file is still there: run.json describes the folder, not only this unit.
  json files = json::object(), runs = json::object();
  std::ifstream previous(dir_ / kManifest);
  json old;
  if (previous && !is_folder_at(dirfd_, kManifest)) {
    try {
      old = json::parse(previous);
    } catch (const json::exception&) {
      old = json();
    }
  }
  if (old.is_object() && old.contains("files") && old["files"].is_object() && old.contains("runs") &&
      old["runs"].is_object()) {
    for (const auto& item : old["files"].items()) {
      const std::string& name = item.key();  // not a structured binding: the lambda captures it
      const json& entry = item.value();
      struct stat st {};
      const bool replaced = std::any_of(staged_.begin(), staged_.end(),
                                        [&](const Staged& s) { return s.name == name; });
      if (replaced || name.find('/') != std::string::npos ||
          ::fstatat(dirfd_, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) != 0 || !entry.is_object() ||
          !entry.contains("run") || !entry["run"].is_string()) {
        continue;
      }
      if (replaces && !S_ISDIR(st.st_mode) && name != kManifest && name != kCommitRecord && name[0] != '.' &&
          replaces(name)) {
        superseded.push_back(name);
        continue;
      }
      const std::string run = entry["run"].get<std::string>();
      files[name] = entry;
      if (old["runs"].contains(run)) runs[run] = old["runs"][run];
    }
  }
  runs[run_id_] = {{"command", command_}, {"started", started_}, {"committed", utc_now()}};
  for (const Staged& s : staged_) {
    struct stat st {};
    ::fstatat(staging_fd_, s.name.c_str(), &st, AT_SYMLINK_NOFOLLOW);
    files[s.name] = {{"run", run_id_}, {"bytes", static_cast<long long>(st.st_size)}};
  }
  json manifest = {{"format", "liedyn run manifest 1"}, {"runs", runs}, {"files", files}};
  return manifest.dump(2) + "\n";
}

void OutputFolder::commit(const Replaces& replaces) {
  if (staged_.empty()) return;
  for (Staged& s : staged_) {
    if (s.file) s.file->finish((dir_ / s.name).string());
  }
  std::vector<std::string> names;
  for (const Staged& s : staged_) names.push_back(s.name);
  names.push_back(kManifest);
  for (const std::string& name : names) {
    if (is_folder_at(dirfd_, name)) {
      throw std::runtime_error((dir_ / name).string() +
                               ": is a folder and cannot be replaced by the run's file; nothing "
                               "in " + dir_.string() + " was replaced");
    }
  }
  // The manifest and the commit record are staged like the unit's files.
  std::vector<std::string> superseded;
  for (const auto& [name, text] : {std::pair<std::string, std::string>{kManifest, manifest_text(replaces, superseded)},
                                   {kCommitRecord, ""}}) {
    std::string body = text;
    if (name == kCommitRecord) {
      for (const std::string& n : names) body += n + "\n";
    }
    FileStream& file = stage(name);
    file.stream() << body;
    file.finish((dir_ / name).string());
  }
  // Past this point the unit is complete on disk; a crash leaves it to be rolled forward.
  const internal::SignalBlock hold;
  ::unlinkat(dirfd_, kManifest, 0);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (::renameat(staging_fd_, names[i].c_str(), dirfd_, names[i].c_str()) != 0) {
      const int reason = errno;
      close_unit(Leave::kEverything);  // the next run into the folder finishes the commit
      throw std::runtime_error(
          (dir_ / names[i]).string() + ": cannot rename into place (" + error_text(reason) +
          ") after " + std::to_string(i) + " of " + std::to_string(names.size()) +
          " files; the whole run is in " + (dir_ / staging_name_).string() +
          " and the next liedyn run into " + dir_.string() + " finishes the commit");
    }
  }
  ::unlinkat(staging_fd_, kCommitRecord, 0);
  close_unit(Leave::kFiles);  // renamed away: only the empty staging folder is removed
  for (const std::string& name : superseded) ::unlinkat(dirfd_, name.c_str(), 0);
}

void OutputFolder::close_unit(Leave leave) {
  if (staging_fd_ < 0) return;
  for (Staged& s : staged_) {
    s.file.reset();
    if (leave == Leave::kNothing) ::unlinkat(staging_fd_, s.name.c_str(), 0);
    internal::release_removal(s.cleanup_slot);
  }
  staged_.clear();
  ::close(staging_fd_);
  staging_fd_ = -1;
  if (leave != Leave::kEverything) ::unlinkat(dirfd_, staging_name_.c_str(), AT_REMOVEDIR);
  internal::release_removal(staging_slot_);
  staging_slot_ = -1;
}

}  // namespace liedyn

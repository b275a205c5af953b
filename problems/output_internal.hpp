#pragma once
// Internal to problems/output*.cpp: unique names created exclusively inside a folder, the
// list of paths a terminating signal removes, and blocking those signals while a commit
// renames files (so that a commit is never cut half-way by Ctrl-C).

#include <string>

namespace liedyn::internal {

// Creates "<prefix><random>" inside the folder `dirfd` with O_CREAT | O_EXCL | O_NOFOLLOW
// (a file) or mkdirat (a folder, mode 0700), retrying on a name clash; returns the open file
// descriptor (for a folder: opened O_DIRECTORY) and sets `name`. Throws std::runtime_error
// naming `where` on failure.
int create_unique_file(int dirfd, const std::string& prefix, const std::string& where,
                       std::string& name);
int create_unique_folder(int dirfd, const std::string& prefix, const std::string& where,
                         std::string& name);

// Registers `name` in the folder `dirfd` (which must stay open while registered) for removal
// when SIGINT, SIGTERM or SIGHUP ends the process; a folder is removed after the files, so
// register the files staged in it too. Returns the slot to release once the path is renamed
// or removed.
int register_removal(int dirfd, const std::string& name, bool is_folder);
void release_removal(int slot);

// Holds SIGINT, SIGTERM and SIGHUP pending while alive (the handler runs when it ends).
class SignalBlock {
 public:
  SignalBlock();
  ~SignalBlock();
  SignalBlock(const SignalBlock&) = delete;
  SignalBlock& operator=(const SignalBlock&) = delete;

 private:
  unsigned long long saved_[16];  // a sigset_t, kept opaque here (checked by a static_assert)
};

// errno's text.
std::string error_text(int error);

}  // namespace liedyn::internal

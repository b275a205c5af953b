#include "process_group.hpp"

#include <iostream>

#include "scene.hpp"

namespace liedyn {

ProcessGroup& single_process() {
  static ProcessGroup alone;
  return alone;
}

std::string open_output_on_root(ProcessGroup& group, std::optional<OutputFolder>& folder,
                                const std::filesystem::path& dir, const std::string& command,
                                const std::filesystem::path& checkpoint) {
  std::exception_ptr error;
  std::string text;
  if (group.rank() == 0) {
    try {
      // Checked first: a missing checkpoint creates no folder.
      if (!checkpoint.empty() && !std::filesystem::is_regular_file(checkpoint)) {
        throw SceneError(checkpoint.string(), "", "cannot resume: no checkpoint (not a regular file)");
      }
      folder.emplace(dir, command, &std::cerr);
      if (!checkpoint.empty()) text = read_named_input(checkpoint, std::uintmax_t(1) << 30, "checkpoint");
    } catch (...) {
      error = std::current_exception();
    }
  }
  if (!group.all_true(error == nullptr)) {
    if (error) std::rethrow_exception(error);
    throw RootFailed();
  }
  return checkpoint.empty() ? text : group.broadcast(text);
}

}  // namespace liedyn

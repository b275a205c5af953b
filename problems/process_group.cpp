#include "process_group.hpp"

namespace liedyn {

ProcessGroup& single_process() {
  static ProcessGroup alone;
  return alone;
}

void share_root_outcome(ProcessGroup& group, const std::exception_ptr& root_error) {
  if (group.all_true(root_error == nullptr)) return;
  if (root_error) std::rethrow_exception(root_error);
  throw RootFailed();
}

}  // namespace liedyn

#include "parallel.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace liedyn {

int default_jobs() { return std::max(1, static_cast<int>(std::thread::hardware_concurrency())); }

void parallel_for(int count, int jobs, const std::function<void(int)>& task) {
  std::atomic<int> next{0};
  std::atomic<bool> stop{false};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  const auto work = [&] {
    for (int i = next++; i < count && !stop; i = next++) {
      try {
        task(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        stop = true;
      }
    }
  };
  std::vector<std::thread> helpers;
  try {
    for (int t = 1; t < std::min(jobs, count); ++t) helpers.emplace_back(work);
  } catch (...) {  // no thread to be had (std::system_error): stop the started ones first
    stop = true;
    for (std::thread& t : helpers) t.join();
    throw;
  }
  work();
  for (std::thread& t : helpers) t.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace liedyn

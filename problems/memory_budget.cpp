#include "memory_budget.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "output.hpp"

namespace liedyn {
namespace {

constexpr double kBaseBytes = 16e6;
constexpr double kBytesPerDof = 480.0;

std::string gigabytes(double bytes) { return format_number(bytes / 1e9, 3) + " GB"; }

}  // namespace

MemoryEstimate estimate_memory(const Scene& scene, int trajectories) {
  double points = 0, rotations = 0;
  for (std::size_t b = 0; b < scene.model.bodies.size(); ++b) {
    points += 1;
    rotations += 1;
  }
  for (const RodSpec& rod : scene.model.rods) {
    points += rod.node_count();
    rotations += rod.node_count() - 1;
  }
  const double dofs = 3 * (points + rotations);
  const double per_frame = 24 * points + 72 * rotations + 48;
  MemoryEstimate e;
  e.working_set = static_cast<std::uint64_t>(kBaseBytes + kBytesPerDof * dofs);
  e.trajectory =
      static_cast<std::uint64_t>(trajectories * per_frame * (static_cast<double>(scene.frames) + 1));
  return e;
}

std::optional<std::uint64_t> available_memory() {
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string key;
    std::uint64_t kilobytes = 0;
    if (fields >> key >> kilobytes && key == "MemAvailable:") return kilobytes * 1024;
  }
  return std::nullopt;
}

std::uint64_t parse_byte_size(const std::string& text) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const std::string unit = text.substr(used);
  double scale = 1;
  if (unit == "K" || unit == "k") scale = 1024.0;
  else if (unit == "M") scale = 1024.0 * 1024;
  else if (unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "T") scale = 1024.0 * 1024 * 1024 * 1024;
  else if (!unit.empty()) used = 0;
  if (used == 0 || !std::isfinite(value) || value <= 0 || value * scale > 1.8e19) {
    throw std::invalid_argument("--memory-limit: \"" + text +
                                "\" is not a size (expected e.g. 512M, 4G or a number of bytes)");
  }
  return static_cast<std::uint64_t>(value * scale);
}

void admit_memory(const Scene& scene, int trajectories, std::optional<std::uint64_t> limit) {
  const bool from_machine = !limit;
  if (!limit) limit = available_memory();
  if (!limit) return;
  const MemoryEstimate e = estimate_memory(scene, trajectories);
  if (e.total() <= *limit) return;
  std::ostringstream reason;
  reason << "the run needs about " << gigabytes(static_cast<double>(e.total())) << " ("
         << gigabytes(static_cast<double>(e.working_set)) << " for a step";
  if (e.trajectory > 0) {
    reason << ", " << gigabytes(static_cast<double>(e.trajectory)) << " for the "
           << (trajectories > 1 ? "trajectories kept" : "trajectory kept for the adjoint") << ": "
           << scene.frames << " frames";
  }
  reason << "), more than the memory limit of " << gigabytes(static_cast<double>(*limit))
         << (from_machine ? " (the machine's available memory)" : "")
         << "; fewer frames or nodes fit, or --memory-limit SIZE raises the limit";
  throw SceneError(scene.source, "--memory-limit", reason.str());
}

}  // namespace liedyn

#pragma once
// Memory admitted before a run starts: a run that cannot fit is refused with its estimate
// (exit 2) rather than dying of std::bad_alloc after minutes of work.
//
// The estimate has two parts:
//  - the working set of one step, from the degrees of freedom: ~480 bytes per DOF (Hessian
//    pattern, factorisation, gradients, terms) above a ~16 MB base, as measured (docs/design.md
//    §12, "Memory");
//  - the trajectory a command keeps: the adjoint (optimize, gradcheck) records every frame's
//    state, 24 bytes per point and 72 per rotation; compare keeps two (reference and row).
// Mesh grid SDFs are bounded by their own cell cap when the scene loads.

#include <cstdint>
#include <optional>
#include <string>

#include "scene.hpp"

namespace liedyn {

struct MemoryEstimate {
  std::uint64_t working_set = 0;  // bytes
  std::uint64_t trajectory = 0;   // bytes
  std::uint64_t total() const { return working_set + trajectory; }
};

// `trajectories`: how many whole trajectories the command keeps (0, 1 or 2).
MemoryEstimate estimate_memory(const Scene& scene, int trajectories);

// MemAvailable of /proc/meminfo, in bytes; nullopt if unknown.
std::optional<std::uint64_t> available_memory();

// "4G", "512M", "1.5G", "800000K", "1000000" (bytes; K, M, G, T are powers of 1024); throws
// std::invalid_argument naming the text.
std::uint64_t parse_byte_size(const std::string& text);

// Throws SceneError(scene file, "--memory-limit", …) naming the estimate and the limit when
// the estimate exceeds `limit` (default: available_memory(); no check if that is unknown).
void admit_memory(const Scene& scene, int trajectories, std::optional<std::uint64_t> limit);

}  // namespace liedyn

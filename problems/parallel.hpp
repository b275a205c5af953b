#pragma once
// Many independent runs on the cores of one machine (`liedyn sweep -j`, `liedyn optimize
// --starts K -j`).
//
// Runs are independent scenes: each builds its own Simulator or DifferentiableSimulation
// and shares only read-only input, so threads suffice (no process per run). The one library
// that is not re-entrant, Ipopt with MUMPS, serialises itself (solvers/ipopt_lock.hpp).
// Results do not depend on the number of threads: every task writes its own slot, and the
// callers order their outputs by task index, never by finishing order.

#include <functional>

namespace liedyn {

// The machine's cores (std::thread::hardware_concurrency, at least 1): the default of -j.
int default_jobs();

// Calls task(i) for every i in [0, count) on min(jobs, count) threads (the calling thread is
// one of them), each thread taking the next index as it finishes one. If a task throws, no
// further task starts, the threads are joined and the first exception is rethrown.
void parallel_for(int count, int jobs, const std::function<void(int)>& task);

}  // namespace liedyn

#pragma once
// One Ipopt solve at a time in a process. Internal to solvers/.
//
// Debian 12's Ipopt (3.11) factorises its KKT systems with MUMPS's sequential build, whose
// dummy MPI layer and instance table are process-wide state: two threads inside Ipopt at
// once can corrupt each other (reported against Ipopt 3.14 as well). liedyn runs scenes on
// several threads (sweeps and multi-start optimisation with -j, Python thread pools), so
// every Ipopt solve — and every destruction of an IpoptApplication, which terminates its
// MUMPS instance — holds this lock: Ipopt runs are serialised, everything else stays
// parallel. Recursive: an L-BFGS objective evaluated inside Ipopt may itself take time steps
// with the Ipopt back-end, on the same thread.

#include <mutex>

namespace liedyn {

inline std::recursive_mutex& ipopt_mutex() {
  static std::recursive_mutex mutex;
  return mutex;
}

}  // namespace liedyn

// The MPI side of process_group.hpp. Compiled into the liedyn executable only (never into
// the libraries or the Python module), with LIEDYN_HAVE_MPI when CMake found MPI.
//
// Debian's sequential MUMPS (under Ipopt) exports a fake MPI of its own, including the C
// functions MPI_Init, MPI_Comm_rank (always 0), MPI_Finalize (does nothing) and MPI_Wtime.
// Whichever library the dynamic linker meets first serves those names to the whole process,
// and MUMPS must keep its fakes (it passes them its own communicator values). So liedyn links
// MPI after Ipopt (CMakeLists.txt) and calls those four through the profiling names PMPI_*,
// which only the real MPI exports; the others (MPI_Init_thread, MPI_Isend, …) have no fake.
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "process_group.hpp"

#ifdef LIEDYN_HAVE_MPI
#include <mpi.h>

#include <list>
#endif

namespace liedyn {
namespace {

// Set by mpirun (Open MPI) or by a PMI/PMIx launcher (srun): how many ranks were started.
int launched_ranks() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"}) {
    if (const char* value = std::getenv(name)) return std::atoi(value);
  }
  return 0;
}

#ifdef LIEDYN_HAVE_MPI

constexpr int kUpdate = 1, kFinal = 2;

class MpiGroup final : public ProcessGroup {
 public:
  MpiGroup(int& argc, char**& argv) {
    // Serialised: the sweep's threads call send/receive, one at a time (under its lock).
    int provided = 0;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
    if (provided < MPI_THREAD_SERIALIZED) {
      PMPI_Finalize();
      throw std::runtime_error("MPI: this MPI library cannot be called from several threads "
                               "one at a time (MPI_THREAD_SERIALIZED)");
    }
    PMPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    PMPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiGroup() override {
    wait_for_sends();
    PMPI_Finalize();
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }

  bool all_true(bool mine) override {
    int in = mine ? 1 : 0, out = 0;
    MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
    return out != 0;
  }

  std::string broadcast(const std::string& from_root) override {
    unsigned long long length = from_root.size();
    MPI_Bcast(&length, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
    std::string text = rank_ == 0 ? from_root : std::string(length, '\0');
    MPI_Bcast(text.data(), static_cast<int>(length), MPI_CHAR, 0, MPI_COMM_WORLD);
    return text;
  }

  void send(const std::string& text, bool final) override {
    // Non-blocking: a rank goes on with its runs while rank 0 is busy with one of its own.
    sends_.push_back({text, MPI_REQUEST_NULL});
    Pending& p = sends_.back();
    MPI_Isend(p.text.data(), static_cast<int>(p.text.size()), MPI_CHAR, 0, final ? kFinal : kUpdate,
              MPI_COMM_WORLD, &p.request);
    if (final) wait_for_sends();
    // Free what has been delivered.
    for (auto it = sends_.begin(); it != sends_.end();) {
      int done = 0;
      MPI_Test(&it->request, &done, MPI_STATUS_IGNORE);
      it = done ? sends_.erase(it) : std::next(it);
    }
  }

  std::vector<Message> receive(bool wait) override {
    std::vector<Message> messages;
    for (;;) {
      MPI_Status status;
      int ready = 0;
      if (wait && finals_ < size_ - 1) {
        MPI_Probe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &status);
        ready = 1;
      } else {
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &ready, &status);
      }
      if (!ready) break;
      int length = 0;
      MPI_Get_count(&status, MPI_CHAR, &length);
      std::string text(length, '\0');
      MPI_Recv(text.data(), length, MPI_CHAR, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
      const bool final = status.MPI_TAG == kFinal;
      finals_ += final ? 1 : 0;
      messages.push_back({status.MPI_SOURCE, std::move(text), final});
    }
    return messages;
  }

  void abort(int code) override { MPI_Abort(MPI_COMM_WORLD, code); }

 private:
  void wait_for_sends() {
    for (Pending& p : sends_) MPI_Wait(&p.request, MPI_STATUS_IGNORE);
    sends_.clear();
  }

  struct Pending {
    std::string text;  // kept until delivered
    MPI_Request request;
  };
  int rank_ = 0, size_ = 1, finals_ = 0;
  std::list<Pending> sends_;  // a list: the buffers must not move
};

#endif

}  // namespace

std::unique_ptr<ProcessGroup> start_process_group(int& argc, char**& argv) {
#ifdef LIEDYN_HAVE_MPI
  if (launched_ranks() > 0) return std::make_unique<MpiGroup>(argc, argv);
  return nullptr;
#else
  (void)argc;
  (void)argv;
  if (launched_ranks() > 1) {
    throw std::runtime_error(
        "started by mpirun as one of " + std::to_string(launched_ranks()) +
        " ranks, but this liedyn was built without MPI (install libopenmpi-dev and rebuild: "
        "scripts/install-deps.sh does)");
  }
  return nullptr;
#endif
}

}  // namespace liedyn

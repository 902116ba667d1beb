#include "mpi_world.hpp"

#include <chrono>
#include <cstdlib>
#include <mutex>
#include <thread>

#ifdef PMFRAG_HAVE_MPI
#include <mpi.h>
#endif

namespace pmfrag::app {

namespace {
int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoi(v) : fallback;
}
#ifdef PMFRAG_HAVE_MPI
// Open MPI's blocking calls spin a core at 100 %; a rank waiting for others would take a core from the
// simulations that share its node. Poll gently instead (case runs last seconds to minutes).
void wait_idle(MPI_Request& req, MPI_Status* st) {
  for (int done = 0;;) {
    MPI_Test(&req, &done, st);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}
#endif

}  // namespace

MpiWorld::MpiWorld() {
#ifdef PMFRAG_HAVE_MPI
  // Started by mpirun? (Open MPI sets these; a plain start must not initialise MPI at all.)
  if (env_int("OMPI_COMM_WORLD_SIZE", 0) > 0 || env_int("PMI_SIZE", 0) > 0) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    local_size_ = env_int("OMPI_COMM_WORLD_LOCAL_SIZE", size_);
    active_ = true;
  }
#endif
}

MpiWorld::~MpiWorld() {
#ifdef PMFRAG_HAVE_MPI
  if (active_) MPI_Finalize();
#endif
}

void MpiWorld::distribute(int count, const std::function<void(int)>& work) {
  if (!active_ || size_ == 1) {
    for (int c = 0; c < count; ++c) work(c);
    return;
  }
#ifdef PMFRAG_HAVE_MPI
  constexpr int ask = 1, give = 2;
  if (rank_ == 0) {
    // Rank 0's own cases run on a thread; only this (main) thread calls MPI.
    std::mutex m;
    int next = 0;
    auto take = [&] {
      std::lock_guard<std::mutex> lock(m);
      return next < count ? next++ : -1;
    };
    std::thread own([&] {
      for (int c; (c = take()) >= 0;) work(c);
    });
    for (int stopped = 0; stopped < size_ - 1;) {
      int dummy = 0;
      MPI_Status st;
      MPI_Request req;
      MPI_Irecv(&dummy, 1, MPI_INT, MPI_ANY_SOURCE, ask, MPI_COMM_WORLD, &req);
      wait_idle(req, &st);
      const int c = take();
      MPI_Send(&c, 1, MPI_INT, st.MPI_SOURCE, give, MPI_COMM_WORLD);
      if (c < 0) ++stopped;
    }
    own.join();
  } else {
    for (;;) {
      int dummy = 0, c = -1;
      MPI_Send(&dummy, 1, MPI_INT, 0, ask, MPI_COMM_WORLD);
      MPI_Recv(&c, 1, MPI_INT, 0, give, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      if (c < 0) break;
      work(c);
    }
  }
  barrier();
#endif
}

void MpiWorld::barrier() {
#ifdef PMFRAG_HAVE_MPI
  if (!active_) return;
  MPI_Request req;
  MPI_Ibarrier(MPI_COMM_WORLD, &req);
  wait_idle(req, MPI_STATUS_IGNORE);
#endif
}

}  // namespace pmfrag::app

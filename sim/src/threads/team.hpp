// The threads that run the per-step kernels. A step of the paper's plate is ~20 us of work; libgomp's
// barrier costs ~1.7 us on this VM (it always makes a futex syscall), and a step had six of them, so two
// OpenMP threads ran slower than one. The team keeps its workers spinning between kernels (then sleeping,
// if idle for long) and synchronizes with atomics (~0.2 us). Kernels split their loops with `share`, the
// same static, contiguous partition every time, and each particle's sum has a fixed order: results are
// bitwise the same for any number of threads.
#pragma once

#include "pmfrag/threads/threads.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

namespace pmfrag::detail {

class Team {
 public:
  /// `min_particles_per_thread`: the rule threads_for applies to work items (8,192 by default).
  explicit Team(int threads, std::size_t min_particles_per_thread = default_min_particles_per_thread);
  ~Team();
  /// Below this many particles a thread's share of a step is a few microseconds, and whether a second
  /// thread pays depends on the machine at the moment (on the project's 2-core VM the (7,14) plate ran 1.5x
  /// faster on two threads while both virtual cores were free, 0.8x while the host kept one busy:
  /// docs/history.md, 2026-12-01), so the static rule keeps small systems on one thread and the tuner measures.
  static constexpr std::size_t default_min_particles_per_thread = 8192;
  Team(const Team&) = delete;
  Team& operator=(const Team&) = delete;

  int size() const { return size_; }
  /// How many of the team's threads `items` work items are worth (at least one per
  /// min_particles_per_thread): work below it is summed on the calling thread without waking the team.
  int threads_for(std::size_t items) const {
    return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(size_), std::max<std::size_t>(1, items / min_particles_)));
  }

  /// The team's partition of n particles: thread t takes [b[t], b[t + 1]), contiguous shares in multiples
  /// of share_grain, equal unless set_weights or set_balance says otherwise. Call outside `run`. Every
  /// per-particle kernel of a step uses it, so each thread finds the positions, velocities and forces it
  /// touches in its own core's cache.
  const std::vector<long>& bounds(long n);

  /// Runs body(tid) on every thread (the caller is tid 0); returns when all have finished. A deferred
  /// prologue, if any, runs first in the same hand-out, with a barrier between the two.
  template <class Body>
  void run(Body&& body) {
    if (size_ == 1) {
      body(0);
      return;
    }
    using B = std::remove_reference_t<Body>;
    dispatch([](void* ctx, int tid) { (*static_cast<B*>(ctx))(tid); }, &body);
  }

  /// Hands prologue(tid) to the team's next `run` (or `flush`): a step's move and its bond forces then
  /// cost one hand-out and a barrier instead of two hand-outs (a hand-out and the wait for the workers
  /// cost 0.7-1.2 us between this VM's virtual cores in slow minutes, a barrier 0.1-0.5 us; the plate's
  /// step on two threads is ~5 us of work). The prologue must live until then. On one thread it runs now.
  template <class Prologue>
  void defer(Prologue& prologue) {
    if (size_ == 1) {
      prologue(0);
      return;
    }
    pre_fn_ = [](void* ctx, int tid) { (*static_cast<Prologue*>(ctx))(tid); };
    pre_ctx_ = &prologue;
  }
  /// Runs a deferred prologue that no `run` took up.
  void flush() {
    if (pre_fn_ != nullptr) dispatch(nullptr, nullptr);
  }
  /// Forgets a deferred prologue (the caller is unwinding past it).
  void discard() { pre_fn_ = nullptr; }

  /// All threads of the team wait here until every one has arrived (call only inside `run`, with the
  /// thread's tid).
  void barrier(int tid);
  /// The same, publishing up to `max_published` numbers of this thread with its arrival; after it,
  /// published(t, tid) gives thread t's. They travel in the cache line the waiting threads read anyway: a
  /// line of its own cost each reader another transfer between cores (~0.2 us on this VM) every step.
  static constexpr std::size_t max_published = 3;
  void barrier(int tid, const double* data, std::size_t count);
  /// Thread t's numbers from the barrier that thread tid passed last (until tid arrives at the next one).
  const double* published(int t, int tid) const {
    const std::uint64_t pass = passed_[static_cast<std::size_t>(tid)].value.load(std::memory_order_relaxed);
    return passed_[static_cast<std::size_t>(t)].data[pass & 1];
  }

  /// Each thread's share of particles, in proportion (ignored unless it has one weight per thread; empty:
  /// none). Results do not depend on it (every particle's forces are summed in a fixed order whoever
  /// computes them): tests use it to check that (ThreadOptions::weights).
  void set_fixed_weights(std::vector<double> weights);
  /// True if fixed weights were given for this team: bounds() follows them and the balancer leaves them.
  bool weights_fixed() const { return fixed_.size() == static_cast<std::size_t>(size_); }
  /// This team's shares in proportion to `weights` as measured (LoadBalancer), unless weights_fixed.
  void set_balance(std::vector<double> weights);
  /// The partition of n particles into `threads` shares in proportion to `weights` (empty: equal), as
  /// bounds() makes it.
  static std::vector<long> partition(long n, int threads, const std::vector<double>& weights);

 private:
  using Fn = void (*)(void*, int);
  void dispatch(Fn fn, void* ctx);
  void work(int tid);

  // Every cache line is written by one thread only, and a worker learns of a job from one line: between
  // two virtual cores a line costs 150-600 ns to move on this VM (a worker started 300-1,200 cycles after
  // the job was handed out, measured 2026-12-01), and the first version moved four or five per job.
  struct alignas(64) Job {
    std::atomic<std::uint32_t> generation{0};  ///< bumped to hand out a job (or to stop)
    bool stop = false;
    Fn pre = nullptr;  ///< a deferred prologue, or none
    void* pre_ctx = nullptr;
    Fn fn = nullptr;  ///< the body, or none (a flushed prologue alone)
    void* ctx = nullptr;
  };
  static_assert(sizeof(Job) == 64);
  /// Runs the job as thread tid: the prologue, then (after a barrier) the body. A prologue alone needs no
  /// barrier: the caller's wait for the workers to finish is one.
  void perform(const Job& job, int tid) {
    if (job.pre != nullptr) job.pre(job.pre_ctx, tid);
    if (job.fn == nullptr) return;
    if (job.pre != nullptr) barrier(tid);
    job.fn(job.ctx, tid);
  }
  struct alignas(64) Counter {
    std::atomic<std::uint64_t> value{0};
    /// barrier k's published numbers at [k & 1]: a thread may arrive at the next barrier (and write the
    /// other half) before the others have read these, but not at the one after
    double data[2][max_published] = {};
  };
  static_assert(sizeof(Counter) == 64);
  int size_ = 1;
  Job job_;                          ///< written by the caller
  Fn pre_fn_ = nullptr;              ///< the deferred prologue (caller only)
  void* pre_ctx_ = nullptr;
  std::unique_ptr<Counter[]> done_;  ///< per worker: the generation it last finished (written by it)
  std::unique_ptr<Counter[]> passed_;  ///< per thread: barriers it has reached (written by it)
  std::vector<std::thread> workers_;
  std::size_t min_particles_ = default_min_particles_per_thread;
  std::vector<double> fixed_;    ///< given weights (set_fixed_weights)
  std::vector<double> balance_;  ///< measured weights (set_balance); empty: equal
  long bounds_n_ = -1;  ///< the particle count bounds_ was made for (-1: stale)
  std::vector<long> bounds_;
};

/// The teams of one integrator, one per size used, and its rule for how many threads a system uses. Owned
/// by the Leapfrog, built from its ThreadOptions.
class Threads {
 public:
  explicit Threads(ThreadOptions options);
  /// The team of `count` threads (1 ... max()), started on first use and kept: switching between counts
  /// starts no threads.
  Team& team(int count);
  int max() const { return max_; }
  /// The static rule (ThreadOptions::threads_for).
  int threads_for(std::size_t particles) const { return options_.threads_for(particles); }
  /// The most threads worth trying: max(), at most one per block of `particle_grain`.
  int most_threads_for(std::size_t particles) const;
  /// True if the options fix the count (min_particles_per_thread given): it is then not measured.
  bool rule_fixed() const { return options_.min_particles_per_thread > 0; }
  /// Fixed shares for teams of weights.size() threads (ThreadOptions::weights); empty: measured again.
  void set_weights(std::vector<double> weights);

 private:
  ThreadOptions options_;
  int max_ = 1;
  std::vector<std::unique_ptr<Team>> teams_;  ///< by size
};

/// A clock for comparing the threads' busy times: the time-stamp counter where there is one (~20 cycles a
/// read; invariant and common to all cores on the CPUs this runs on), else steady_clock's nanoseconds.
inline std::uint64_t busy_clock() {
#if defined(__x86_64__) || defined(__i386__)
  return __builtin_ia32_rdtsc();
#else
  return static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
#endif
}

/// Thread tid's share [begin, end) of n items, in multiples of `grain` (except the last).
inline std::pair<long, long> share(long n, int tid, int threads, long grain = 1) {
  const long units = (n + grain - 1) / grain;
  const long per = units / threads, extra = units % threads;
  const long b = tid * per + std::min<long>(tid, extra);
  const long e = b + per + (tid < extra ? 1 : 0);
  return {std::min(n, b * grain), std::min(n, e * grain)};
}

/// The assembly block of the bond stencil (a multiple of every vector width); a thread gets at least one.
inline constexpr long particle_grain = 256;
/// Particle shares (Team::bounds) start on multiples of 64 particles (whole cache lines, whole vectors): in
/// blocks of 256 the (7,14) plate's 2698 particles split 1536 / 1162, and the first thread's bond pass took
/// 11,800 cycles a step against the second's 8,600 (measured 2026-12-01).
inline constexpr long share_grain = 64;

/// body(first, last, tid) on every thread of the team for n particles, each with its share (Team::bounds).
template <class Body>
inline void for_particles(Team& team, std::size_t n, Body&& body) {
  const std::vector<long>& b = team.bounds(static_cast<long>(n));
  team.run([&](int tid) { body(b[static_cast<std::size_t>(tid)], b[static_cast<std::size_t>(tid) + 1], tid); });
}

}  // namespace pmfrag::detail

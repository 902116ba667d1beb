// How a simulation's steps use threads. Handed to the integrator (Leapfrog, RunOptions::threads) and kept
// there: no thread count, rule or share lives in process-wide or thread-local state.
#pragma once

#include <cstddef>
#include <vector>

namespace pmfrag {

struct ThreadOptions {
  /// The most threads a step may use (`--threads`); 0: the processors this process may run on.
  int max = 0;
  /// 0 (default): the run measures how many threads its steps run fastest on (1, 2, 4, ... up to `max`,
  /// each with at least 256 particles) and re-measures every so often. Otherwise the count is fixed: all
  /// `max` threads, but at most one per this many particles (1 splits any system; the 1-vs-2-thread tests use
  /// it). The trajectory is bitwise the same for any count.
  std::size_t min_particles_per_thread = 0;
  /// Each thread's share of the particles in proportion (e.g. {1, 3}) for teams of weights.size() threads;
  /// empty: shares follow the threads' measured speeds (equal to start with). Results do not depend on it.
  std::vector<double> weights;

  /// `max` resolved: the given count, or the processors available to this process.
  int resolved_max() const;
  /// The count a system of this many particles uses when the count is not measured (the static rule: `max`
  /// threads, at most one per min_particles_per_thread, 8,192 if not given).
  int threads_for(std::size_t particles) const;
};

/// ThreadOptions with `max` threads and the environment's PMFRAG_MIN_PARTICLES_PER_THREAD and
/// PMFRAG_THREAD_WEIGHTS ("1,3"), which benchmarks and scripts use to fix the count and the shares.
ThreadOptions thread_options_from_environment(int max);

}  // namespace pmfrag

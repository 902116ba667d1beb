// How many threads a step runs on, chosen by measuring. Whether a second thread pays for a small body
// depends on the machine at the moment, not only on the body: on the project's 2-core VM the (7,14) plate
// (2698 particles, ~10 us a step) ran 1.5x faster on two threads while both virtual cores were free and
// 0.8x as fast while the host kept one of them busy (docs/history.md, 2026-12-01). Every particle's force
// is summed in a fixed order, so the trajectory is bitwise the same whatever count is chosen: the choice may
// follow the clock without costing reproducibility.
//
// Every so often the tuner runs a short window of steps on each candidate count (1, 2, 4, ... up to the
// most the body can use), takes the mean time of a step in each with the slowest 1/16 of steps (under
// Leapfrog::advance, of blocks of up to 8 steps) left out (a neighbour-list rebuild or a frame written
// between steps does not sway it), and holds the fastest until
// the next probe. Not the median: on this VM a two-thread step of the plate had a median of 17,700 cycles
// and a mean of 22,400 (the worker now and then starts or finishes thousands of cycles late, in one step
// of ten or more; rdtsc, 2026-12-02), so the median chose two threads where one ran as fast. Only probe
// windows read the clock.
#pragma once

#include "threads/team.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <limits>
#include <vector>

namespace pmfrag::detail {

class ThreadTuner {
 public:
  ThreadTuner(const Threads& threads, std::size_t particles)
      : fixed_(threads.threads_for(particles)), count_now_(fixed_) {
    if (threads.rule_fixed()) return;
    for (int t = 1; t <= threads.most_threads_for(particles); t *= 2) candidates_.push_back(t);
    if (candidates_.size() < 2) candidates_.clear();
    per_step_.assign(candidates_.size(), 0.0);
  }
  ThreadTuner(const ThreadTuner&) = delete;
  ThreadTuner& operator=(const ThreadTuner&) = delete;

  bool active() const { return !candidates_.empty(); }

  /// The thread count for the next step or block (set by before_steps; the static rule when not measuring).
  int count() const { return count_now_; }

  /// Before a step: chooses the thread count for it (count()), and starts the clock in a probe window.
  void before_step() { before_steps(); }
  /// After the step.
  void after_step(int threads_used) { after_steps(threads_used, 1); }

  /// Before a block of steps (Leapfrog::advance): as before_step; returns how many steps the block may
  /// take on this count (to the end of the hold, or a few at a time in a probe window, each timed).
  long before_steps() {
    count_now_ = !active() ? fixed_ : holding_ > 0 ? best_ : candidates_[probe_];
    if (!active()) return std::numeric_limits<long>::max();
    if (holding_ > 0) return holding_;
    if (count_ < warm_steps) return warm_steps - count_;
    start_ = clock::now();
    return std::min(timed_block, window_ - count_);
  }
  /// After a block of k steps (at most what before_steps allowed).
  void after_steps(int threads_used, long k) {
    const std::size_t t = static_cast<std::size_t>(threads_used);
    if (steps_with_.size() <= t) steps_with_.resize(t + 1, 0);
    steps_with_[t] += k;
    if (!active() || k <= 0) return;
    if (holding_ > 0) {
      holding_ -= std::min(k, holding_);
      return;
    }
    if (count_ >= warm_steps)  // the block's mean step
      times_.push_back(std::chrono::duration<double>(clock::now() - start_).count() / static_cast<double>(k));
    count_ += k;
    if (count_ < window_) return;
    // the window on candidate probe_ is over: its mean step, the slowest 1/16 left out
    const std::size_t kept = times_.size() - times_.size() / 16;
    std::nth_element(times_.begin(), times_.begin() + static_cast<std::ptrdiff_t>(kept), times_.end());
    double sum = 0.0;
    for (std::size_t j = 0; j < kept; ++j) sum += times_[j];
    per_step_[probe_] = sum / static_cast<double>(kept);
    times_.clear();
    count_ = 0;
    if (++probe_ < candidates_.size()) return;
    probe_ = 0;
    const std::size_t b = static_cast<std::size_t>(std::min_element(per_step_.begin(), per_step_.end()) - per_step_.begin());
    best_ = candidates_[b];
    // Windows of ~2 ms of steps (at least 32), and ~64 windows between probes: the probe of a count slower by
    // half costs under 1 % of the run.
    const double step = std::max(per_step_[b], 1e-9);
    window_ = warm_steps + std::clamp(static_cast<long>(2e-3 / step), 32L, 2048L);
    holding_ = 64 * window_;
  }

  /// Steps run with each thread count (index: threads).
  const std::vector<long>& steps_with() const { return steps_with_; }

 private:
  using clock = std::chrono::steady_clock;
  // steps at the start of a window left out of the timing: a team that has slept, its first plan, caches
  static constexpr long warm_steps = 8;
  // steps timed together in a probe window of blocks: short enough that the trimmed mean still leaves out
  // a step with a list rebuild or a frame, long enough that a block's barriers are those of a long run
  static constexpr long timed_block = 8;
  int fixed_ = 1;      ///< the static rule's count (when not measuring)
  int count_now_ = 1;  ///< the count chosen for the next step or block
  std::vector<int> candidates_;
  std::vector<double> per_step_;  ///< s: each candidate's (trimmed) mean step in the last probe
  std::vector<double> times_;     ///< s: the steps timed in this window
  std::vector<long> steps_with_;
  std::size_t probe_ = 0;  ///< the candidate being probed
  long count_ = 0;         ///< steps into this window
  long window_ = warm_steps + 64;
  long holding_ = 0;  ///< steps left on best_ before the next probe
  int best_ = 1;
  clock::time_point start_;
};

}  // namespace pmfrag::detail

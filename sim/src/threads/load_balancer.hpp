// Each thread's share of the particles in proportion to its measured speed. On the project's 2-core VM the
// two virtual cores are at times not equally fast: in slow minutes one core's half of the plate's force pass
// took 16,300 cycles and the other's 10,200 for equal shares, and the other way round in the next run
// (rdtsc, 2026-12-02). Every step waits for the slower thread (resident steps have one barrier a step). So
// each thread's busy time in resident steps (its move and forces, not its wait) is summed over a window of
// steps, and the shares are then set in proportion to the particles each thread handled per unit of time,
// if that shortens the slowest thread's predicted time by more than 3 % (the shares move in whole grains of
// 64 particles). The partition changes no result: every particle's forces are summed in a fixed order
// whoever computes them.
#pragma once

#include "threads/team.hpp"

#include <algorithm>
#include <cstddef>
#include <vector>

namespace pmfrag::detail {

class LoadBalancer {
 public:
  /// Steps measured before each decision: ~3-10 ms of the plate, so a change of the VM's speeds is
  /// followed within a few hundredths of a second, and a new partition (a new plan for the bond stencil,
  /// ~0.1 ms) is made at most a few times a second.
  static constexpr long window = 1024;

  /// Steps until the next decision (a block of resident steps should end there).
  long room() const { return window - steps_; }

  /// After a block of `steps` resident steps on the partition `bounds`: busy[t * stride] is thread t's busy
  /// time in it. Decides, once a window is full, whether to move the team's shares (Team::set_balance).
  void add(Team& team, const std::vector<long>& bounds, const double* busy, std::size_t stride, long steps) {
    const std::size_t threads = bounds.size() - 1;
    if (steps <= 0 || threads < 2 || team.weights_fixed()) return;
    if (bounds != bounds_) {  // a new partition (or team): measure it afresh
      bounds_ = bounds;
      busy_.assign(threads, 0.0);
      steps_ = 0;
    }
    for (std::size_t t = 0; t < threads; ++t) busy_[t] += busy[t * stride];
    steps_ += steps;
    if (steps_ < window) return;
    std::vector<double> speed(threads);  // particles per unit of busy time
    double slowest = 0.0;
    for (std::size_t t = 0; t < threads; ++t) {
      if (!(busy_[t] > 0.0)) return;
      speed[t] = static_cast<double>(bounds[t + 1] - bounds[t]) / busy_[t];
      slowest = std::max(slowest, busy_[t]);
    }
    steps_ = 0;
    std::fill(busy_.begin(), busy_.end(), 0.0);
    const long n = bounds.back();
    const std::vector<long> next = Team::partition(n, static_cast<int>(threads), speed);
    double predicted = 0.0;
    for (std::size_t t = 0; t < threads; ++t)
      predicted = std::max(predicted, static_cast<double>(next[t + 1] - next[t]) / speed[t]);
    if (next != bounds && predicted < 0.97 * slowest) team.set_balance(std::move(speed));
  }

 private:
  std::vector<long> bounds_;  ///< the partition being measured
  std::vector<double> busy_;  ///< per thread, summed over the window
  long steps_ = 0;            ///< steps measured in the window
};

}  // namespace pmfrag::detail

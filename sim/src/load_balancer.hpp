// Each thread's share of the particles in proportion to its measured speed. On the project's 2-core VM the
// two virtual cores are at times not equally fast: in slow minutes one core's half of the plate's force pass
// took 16,300 cycles and the other's 10,200 for equal shares, and the other way round in the next run
// (rdtsc, session 13). Every step waits for the slower thread. So each thread's busy time in resident steps
// (its move, forces and gather, not its waits) is summed over a window of steps, and the shares are then
// set in proportion to the particles each thread handled per unit of time, if that shortens the predicted
// step by more than 3 % (the shares move in whole grains of 64 particles). The partition
// changes no result: every particle's forces are summed in a fixed order whoever computes them.
#pragma once

#include "team.hpp"

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

  /// Busy times are kept per phase of a step: the threads wait for each other after each (a barrier), so
  /// a step lasts the sum over phases of the slowest thread's time in it, and the phases need not be slow on
  /// the same core (the move reads memory, the forces compute: a core shared with another guest loses more
  /// of the first; measured 2,500 against 3,800 cycles in the move, 12,900 against 11,300 in the forces).
  static constexpr std::size_t phases = 2;

  /// After a block of `steps` resident steps on the partition `bounds`: busy[t * stride + p] is thread t's
  /// busy time in phase p. Decides, once a window is full, whether to move the team's shares
  /// (Team::set_balance): to the shares in proportion to the speeds in the whole step or in one phase,
  /// whichever gives the shortest predicted step, if that is > 3 % shorter than the present one's.
  void add(Team& team, const std::vector<long>& bounds, const double* busy, std::size_t stride, long steps) {
    const std::size_t threads = bounds.size() - 1;
    if (steps <= 0 || threads < 2 || Team::weights_fixed(static_cast<int>(threads))) return;
    if (bounds != bounds_) {  // a new partition (or team): measure it afresh
      bounds_ = bounds;
      busy_.assign(threads * phases, 0.0);
      steps_ = 0;
    }
    for (std::size_t t = 0; t < threads; ++t)
      for (std::size_t p = 0; p < phases; ++p) busy_[t * phases + p] += busy[t * stride + p];
    steps_ += steps;
    if (steps_ < window) return;
    steps_ = 0;
    std::vector<double> cost(threads * phases);  // busy time per particle
    for (std::size_t t = 0; t < threads; ++t)
      for (std::size_t p = 0; p < phases; ++p) {
        if (!(busy_[t * phases + p] > 0.0)) return;
        cost[t * phases + p] = busy_[t * phases + p] / static_cast<double>(bounds[t + 1] - bounds[t]);
      }
    std::fill(busy_.begin(), busy_.end(), 0.0);
    // the step on partition b: sum over phases of the slowest thread's (particles x cost)
    const auto step_time = [&](const std::vector<long>& b) {
      double sum = 0.0;
      for (std::size_t p = 0; p < phases; ++p) {
        double slowest = 0.0;
        for (std::size_t t = 0; t < threads; ++t)
          slowest = std::max(slowest, static_cast<double>(b[t + 1] - b[t]) * cost[t * phases + p]);
        sum += slowest;
      }
      return sum;
    };
    const double now = step_time(bounds);
    double best = now;
    std::vector<double> chosen;
    for (std::size_t basis = 0; basis <= phases; ++basis) {  // the whole step, then each phase
      std::vector<double> speed(threads);
      for (std::size_t t = 0; t < threads; ++t) {
        double c = 0.0;
        for (std::size_t p = 0; p < phases; ++p)
          if (basis == phases || basis == p) c += cost[t * phases + p];
        speed[t] = 1.0 / c;
      }
      const double predicted = step_time(Team::partition(bounds.back(), static_cast<int>(threads), speed));
      if (predicted < best) best = predicted, chosen = std::move(speed);
    }
    if (!chosen.empty() && best < 0.97 * now) team.set_balance(std::move(chosen));
  }

 private:
  std::vector<long> bounds_;  ///< the partition being measured
  std::vector<double> busy_;  ///< per thread and phase, summed over the window
  long steps_ = 0;            ///< steps measured in the window
};

}  // namespace pmfrag::detail

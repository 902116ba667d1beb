// dt = "adaptive": the step is a power-of-two fraction of a base step, dt = base / 2^level.
//
// Why levels and not the limit itself: a step that follows the closest approach continuously is modulated at
// the frequency of the very contact it resolves, and a leapfrog with a periodically modulated step can be
// parametrically unstable. Measured on the 200 cm/s impact: a continuously varying step let the energy
// balance grow exponentially (26 % of the impact energy), while the same cap as a fixed step held it to
// 5e-4. With levels the step is constant for long stretches; it halves at once when the limit demands and
// doubles only after `calm_steps` steps in a row that would allow it.
#pragma once

#include <cmath>
#include <stdexcept>

namespace pmfrag {

class StepLevels {
 public:
  static constexpr int calm_steps = 64;
  /// The smallest step is base / 2^19, 1.9e-6 of the cap: a configuration that needs less (particles pressed
  /// to the stiffest part of the law, an impact too fast for the clamp) stops the run rather than crawl.
  static constexpr int max_level = 19;

  /// `dt_max` [s] is the cap; the base is the largest step <= dt_max that divides `every` [s], so that
  /// output times are reached without a sliver step.
  StepLevels(double dt_max, double every) : base_(every / std::ceil(every / dt_max * (1.0 - 1e-12))) {}

  /// The step to take now, given the largest step the configuration allows [s].
  double next(double allowed) {
    int need = 0;
    if (allowed < base_) need = static_cast<int>(std::ceil(std::log2(base_ / allowed) - 1e-12));
    if (!(need <= max_level))  // also NaN
      throw std::runtime_error("the stable step fell below 1e-6 of the cap");
    if (need > level_) {
      level_ = need, calm_ = 0;
    } else if (need < level_) {
      if (++calm_ >= calm_steps) --level_, calm_ = 0;
    } else {
      calm_ = 0;
    }
    return std::ldexp(base_, -level_);
  }

  double base() const { return base_; }
  int level() const { return level_; }
  /// For checkpoints: the level and the calm count are history.
  int calm() const { return calm_; }
  void restore(int level, int calm) { level_ = level, calm_ = calm; }

 private:
  double base_;
  int level_ = 0, calm_ = 0;
};

}  // namespace pmfrag

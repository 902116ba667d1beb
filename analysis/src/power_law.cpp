#include "pmfrag/analysis/power_law.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

namespace pmfrag::analysis {

const char* power_law_rule() {
  return "discrete maximum likelihood over fragments of at least s_min particles, the largest fragment left out "
         "(the remnant); s_min >= 2 minimises the Kolmogorov-Smirnov distance among choices leaving >= 10 "
         "fragments (Clauset, Shalizi & Newman 2009); 95 % likelihood-ratio interval";
}

double hurwitz_zeta(double s, double a) {
  constexpr int direct = 20;
  double sum = 0.0;
  for (int k = 0; k < direct; ++k) sum += std::pow(a + k, -s);
  // Euler-Maclaurin for the rest, from x = a + 20: the integral, half the first term, three Bernoulli terms.
  const double x = a + direct;
  const double xs = std::pow(x, -s);
  sum += x * xs / (s - 1.0) + 0.5 * xs;
  sum += s / 12.0 * xs / x;
  sum -= s * (s + 1) * (s + 2) / 720.0 * xs / (x * x * x);
  sum += s * (s + 1) * (s + 2) * (s + 3) * (s + 4) / 30240.0 * xs / std::pow(x, 5);
  return sum;
}

namespace {

// Golden-section search for the maximum of a function concave on [lo, hi].
double argmax(const std::function<double(double)>& f, double lo, double hi) {
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = lo, b = hi, c = b - g * (b - a), d = a + g * (b - a);
  double fc = f(c), fd = f(d);
  for (int k = 0; k < 200 && b - a > 1e-12; ++k) {
    if (fc > fd)
      b = d, d = c, fd = fc, c = b - g * (b - a), fc = f(c);
    else
      a = c, c = d, fc = fd, d = a + g * (b - a), fd = f(d);
  }
  return 0.5 * (a + b);
}

// Where f, monotone between `inside` and `outside`, crosses `level` (bisection).
double crossing(const std::function<double(double)>& f, double inside, double outside, double level) {
  if (f(outside) >= level) return outside;  // the interval reaches the search bound
  for (int k = 0; k < 200 && std::fabs(outside - inside) > 1e-12; ++k) {
    const double mid = 0.5 * (inside + outside);
    (f(mid) >= level ? inside : outside) = mid;
  }
  return 0.5 * (inside + outside);
}

constexpr double tau_lo = 1.0001, tau_hi = 20.0;

}  // namespace

std::optional<PowerLawFit> fit_discrete_power_law(const std::vector<long>& all_sizes, std::string& why, long min_fitted) {
  std::vector<long> sizes;
  for (long s : all_sizes)
    if (s >= 2) sizes.push_back(s);
  std::sort(sizes.begin(), sizes.end());
  if (static_cast<long>(sizes.size()) < min_fitted) {
    why = std::to_string(sizes.size()) + " fragments of >= 2 particles (besides the largest): a fit needs at least " +
          std::to_string(min_fitted);
    return std::nullopt;
  }
  std::optional<PowerLawFit> best;
  std::vector<long> candidates(sizes.begin(), sizes.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  for (long s_min : candidates) {
    const auto first = std::lower_bound(sizes.begin(), sizes.end(), s_min);
    const long n = static_cast<long>(sizes.end() - first);
    if (n < min_fitted) break;
    double sum_log = 0.0;
    for (auto it = first; it != sizes.end(); ++it) sum_log += std::log(static_cast<double>(*it));
    const double a = static_cast<double>(s_min);
    const auto log_l = [&](double tau) { return -static_cast<double>(n) * std::log(hurwitz_zeta(tau, a)) - tau * sum_log; };
    PowerLawFit fit;
    fit.exponent = argmax(log_l, tau_lo, tau_hi);
    const double level = log_l(fit.exponent) - 0.5 * 3.841458820694124;  // chi-squared, one degree, 95 %
    fit.ci_low = crossing(log_l, fit.exponent, tau_lo, level);
    fit.ci_high = crossing(log_l, fit.exponent, tau_hi, level);
    fit.s_min = s_min;
    fit.fitted = n;
    // KS distance at every distinct size: the empirical CDF after its step against the law's.
    const double z = hurwitz_zeta(fit.exponent, a);
    double ks = 0.0;
    for (auto it = first; it != sizes.end();) {
      const auto next = std::upper_bound(it, sizes.end(), *it);
      const double empirical = static_cast<double>(next - first) / static_cast<double>(n);
      const double model = 1.0 - hurwitz_zeta(fit.exponent, static_cast<double>(*it) + 1.0) / z;
      ks = std::max(ks, std::fabs(empirical - model));
      it = next;
    }
    fit.ks_distance = ks;
    if (!best || ks < best->ks_distance) best = fit;
  }
  return best;
}

}  // namespace pmfrag::analysis

// The fragment mass distribution's power law n(m) ~ m^-tau, fitted by maximum likelihood (Clauset, Shalizi &
// Newman, SIAM Review 51, 2009): not least squares on a histogram, whose slope is biased by the binning.
// Fragments of one mass unit (one particle) are counted apart and never fitted.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace pmfrag::analysis {

struct PowerLawFit {
  double exponent = 0.0;             ///< tau
  double ci_low = 0.0, ci_high = 0.0;  ///< 95 % likelihood-ratio interval of tau (s_min held fixed)
  long s_min = 0;                    ///< the smallest size fitted [mass units]
  long fitted = 0;                   ///< sizes at or above s_min that entered the fit
  double ks_distance = 0.0;          ///< Kolmogorov-Smirnov distance between those sizes and the fitted law
};

/// The rule, in words, for docs and summary.json.
const char* power_law_rule();

/// Fits P(s) = s^-tau / zeta(tau, s_min), s = s_min, s_min + 1, ... to whole sizes (fragment masses in units of
/// the particle mass), with s_min chosen by the Clauset-Shalizi-Newman rule: the candidate >= 2 that minimises
/// the Kolmogorov-Smirnov distance, among candidates leaving at least `min_fitted` sizes. Returns nothing, and
/// says why in `why`, when fewer than `min_fitted` sizes of at least 2 exist.
std::optional<PowerLawFit> fit_discrete_power_law(const std::vector<long>& sizes, std::string& why, long min_fitted = 10);

/// Hurwitz zeta(s, a) = sum_{k >= 0} (a + k)^-s for s > 1, a >= 1 (Euler-Maclaurin after 20 terms).
double hurwitz_zeta(double s, double a);

}  // namespace pmfrag::analysis

// The particle-model pair law of Eq. (22): F(r) = -G/r^p + H/r^q (positive = repulsive, along the pair axis).
// Header-only and inlined: this is the evaluator the pair loop is templated on (cf. HOOMD's EvaluatorPairMie).
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

namespace pmfrag {

/// x^n for a small non-negative integer n by repeated squaring: the pair loop must not call pow().
inline double ipow(double x, int n) noexcept {
  double result = 1.0;
  while (n > 0) {
    if (n & 1) result *= x;
    x *= x;
    n >>= 1;
  }
  return result;
}

/// The largest exponent a law may have: the engine's kernels and the (p,q) sweeps stop there.
inline constexpr int max_exponent = 64;

/// Throws std::invalid_argument unless 1 <= p < q <= max_exponent: the one check of a law's exponents that
/// scenes, the material model and the command line share.
inline void validate_exponents(int p, int q) {
  if (p < 1) throw std::invalid_argument("p must be >= 1 (got " + std::to_string(p) + ")");
  if (q <= p) throw std::invalid_argument("q must be greater than p (got p = " + std::to_string(p) + ", q = " + std::to_string(q) + ")");
  if (q > max_exponent)
    throw std::invalid_argument("q must be at most " + std::to_string(max_exponent) + " (got " + std::to_string(q) + ")");
}

struct PairLaw {
  int p = 7;        ///< attractive exponent, p >= 1
  int q = 14;       ///< repulsive exponent, q > p
  double G = 0.0;   ///< attraction coefficient [dyne cm^p]
  double H = 0.0;   ///< repulsion coefficient [dyne cm^q]

  /// Throws std::invalid_argument unless 1 <= p < q <= max_exponent and G, H > 0 and finite.
  void validate() const {
    validate_exponents(p, q);
    if (!(G > 0.0) || !std::isfinite(G)) throw std::invalid_argument("pair law: G must be positive and finite");
    if (!(H > 0.0) || !std::isfinite(H)) throw std::invalid_argument("pair law: H must be positive and finite");
  }

  /// Eq. (22): force [dyne] at separation r [cm], positive = repulsive.
  double force(double r) const noexcept {
    const double inv = 1.0 / r;
    return -G * ipow(inv, p) + H * ipow(inv, q);
  }

  /// Force divided by r, from 1/r: the pair loop multiplies this by the separation vector.
  double force_over_r_from_inv(double inv) const noexcept {
    const double ip = ipow(inv, p);
    const double iq = ipow(inv, q);
    return (-G * ip + H * iq) * inv;
  }

  /// Eqs. (23)-(24) with the sign of the H term corrected (physics.md): potential [erg], phi' = -F.
  double potential(double r) const noexcept {
    const double rep = -H * std::pow(r, 1.0 - q) / (1.0 - q);
    if (p == 1) return G * std::log(r) + rep;
    return G * std::pow(r, 1.0 - p) / (1.0 - p) + rep;
  }

  /// Stiffness -dF/dr [dyne/cm] (Eq. 25); positive inside r_d, zero at the damage spacing.
  double stiffness(double r) const noexcept {
    return -p * G * ipow(1.0 / r, p + 1) + q * H * ipow(1.0 / r, q + 1);
  }

  /// Equilibrium spacing, F = 0: r0 = (H/G)^(1/(q-p)).
  double equilibrium_spacing() const noexcept { return std::pow(H / G, 1.0 / (q - p)); }

  /// Damage spacing r_d (dF/dr = 0, the peak attraction): r_d = r0 (q/p)^(1/(q-p)).
  double damage_spacing() const noexcept {
    return equilibrium_spacing() * std::pow(static_cast<double>(q) / p, 1.0 / (q - p));
  }

  /// The peak attractive force |F(r_d)| [dyne]: the most a bond can hold.
  double peak_force() const noexcept { return std::fabs(force(damage_spacing())); }
};

}  // namespace pmfrag

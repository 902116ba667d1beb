// The molecular-dynamics copper model the particle model is mapped from (Sec. 2.1, Eqs. 1-7).
#pragma once

#include "pmfrag/model/pair_law.hpp"

namespace pmfrag::copper {

// Eq. (1): phi_a(r) = -A6/r^6 + B12/r^12 erg with r in angstrom.
inline constexpr double A6 = 1.398068e-10;   // erg A^6
inline constexpr double B12 = 1.55104e-8;    // erg A^12
inline constexpr double atom_mass_g = 1.0542e-22;  // m_a (Sec. 3.2)
inline constexpr double r_a_paper_A = 2.46;  // the paper's rounded minimum (Eq. 3)
inline constexpr double angstrom_cm = 1e-8;

/// Eq. (2) as a pair law with r in angstrom and F in dyne: F = -dphi/dr * 1e8 (erg/A -> dyne).
inline PairLaw force_law_angstrom() { return PairLaw{7, 13, 6.0 * A6 * 1e8, 12.0 * B12 * 1e8}; }

/// Eq. (1): potential [erg], r in angstrom.
inline double potential(double r_A) { return -A6 / ipow(r_A, 6) + B12 / ipow(r_A, 12); }

/// Exact minimum of Eq. (1): 2.460485 A (the paper rounds to 2.46).
double equilibrium_spacing_A();

/// Ashby-Jones modulus E_a = S0/r (Eqs. 4-5) evaluated at r [A], in GPa (152.94 at 2.46 A).
double youngs_modulus_GPa(double r_A);

/// Damage spacing r_d [A], where dF/dr = 0 (2.7279 A).
double damage_spacing_A();

/// Eq. (7) as the paper evaluates it (N = 1/r_d^2 and a factor-10 unit slip): 462.84 MN/m^2.
double tensile_strength_paper_MNm2();
/// The physically consistent value, |F(r_d)|/r_d^2 in MN/m^2 (10x the paper's).
double tensile_strength_MNm2();

}  // namespace pmfrag::copper

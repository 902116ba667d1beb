// MD -> PM passage by equivalence of mass and energy (Sec. 5.1, Eqs. 21-34), with the counting convention
// and misprint corrections of physics.md. Everything in CGS unless a name says otherwise.
#pragma once

#include "pmfrag/model/pair_law.hpp"

#include <array>
#include <vector>

namespace pmfrag {

/// A block A x B x C [cm] of the material the particle model stands for (the paper's: 8 x 11.43 x 3.1).
struct Block {
  double A = 8.0;
  double B = 11.43;
  double C = 3.1;
};

/// Everything the material model derives for one (p, q), spacing r0 and block.
struct Material {
  int p = 0, q = 0;
  double r0_cm = 0.0;
  Block block;
  int imax = 0, jmax = 0, kmax = 0;  ///< nodes per direction (Sec. 3.2 mesh)
  double N = 0.0;                    ///< quasi-particles, Eq. (27)
  double Nstar = 0.0;                ///< atoms in the lattice extents, Eq. (21)
  double mass_g = 0.0;               ///< quasi-particle mass, Eq. (28)
  double phi0_erg = 0.0;             ///< pair energy at r0, Eq. (29)
  PairLaw law;                       ///< G, H from Eqs. (29)-(33)
  double S0_dyne_per_cm = 0.0;       ///< stiffness at r0, Eq. (25)
  double E_GPa = 0.0;                ///< Eq. (26)
  double r_d_cm = 0.0;               ///< damage spacing
  double peak_force_dyne = 0.0;      ///< |F(r_d)|
  double sigma_TS_paper_MNm2 = 0.0;  ///< Table 1 convention: |F(r_d)|/r_d^2 x 1e-8
  double sigma_TS_MNm2 = 0.0;        ///< consistent units: |F(r_d)|/r_d^2 x 1e-7
  double dt_max_stretch_s = 0.0;     ///< Eq. (15) with dF/dr at r0
};

/// Derive the particle-model material. Throws std::invalid_argument for q <= p, p < 1, r0 <= 0 or a
/// block smaller than one spacing.
Material derive_material(int p, int q, double r0_cm, const Block& block = {});

/// Eq. (15): the largest stable leapfrog step 2/Omega, Omega = sqrt(|dF/dr| / m), with dF/dr at r [cm].
double dt_limit(const PairLaw& law, double mass_g, double r_cm);

/// Eq. (15) for impact: the force is held constant inside r_min, so the stiffest pair sits at r_min.
inline double dt_limit_impact(const PairLaw& law, double mass_g, double r_min_cm) {
  return dt_limit(law, mass_g, r_min_cm);
}

/// The (p, q) grid of Fig. 3: p = 1..14, q = 2..15, q > p (105 pairs).
std::vector<std::array<int, 2>> fig3_grid();

}  // namespace pmfrag

#include "pmfrag/model/copper_md.hpp"

#include <cmath>

namespace pmfrag::copper {

double equilibrium_spacing_A() { return force_law_angstrom().equilibrium_spacing(); }

double youngs_modulus_GPa(double r_A) {
  // S [dyne/A] -> dyne/cm is x1e8; divided by r [cm] = r_A x1e-8; dyne/cm^2 -> GPa is x1e-10.
  return force_law_angstrom().stiffness(r_A) / r_A * 1e6;
}

double damage_spacing_A() { return force_law_angstrom().damage_spacing(); }

namespace {
// |F(r_d)| / r_d^2 in dyne/cm^2, with r_d converted to cm.
double strength_cgs() {
  const PairLaw law = force_law_angstrom();
  const double rd_cm = law.damage_spacing() * angstrom_cm;
  return law.peak_force() / (rd_cm * rd_cm);
}
}  // namespace

double tensile_strength_paper_MNm2() { return strength_cgs() * 1e-8; }
double tensile_strength_MNm2() { return strength_cgs() * 1e-7; }

}  // namespace pmfrag::copper

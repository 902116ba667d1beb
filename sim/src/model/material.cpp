#include "pmfrag/model/material.hpp"

#include "pmfrag/model/copper_md.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace pmfrag {

namespace {
const double sin60 = std::sqrt(3.0) / 2.0;
const double layer = std::sqrt(6.0) / 3.0;  // fcc section spacing / r0

// Eq. (21) for extents a, b, c [cm] with the paper's rounded r_a = 2.46 A.
double atom_count(double a, double b, double c) {
  const double ra = copper::r_a_paper_A;
  return (a * 1e8 / ra + 1.0) * (b * 1e8 / (ra * sin60) + 1.0) * (c * 1e8 / (ra * layer) + 1.0);
}
}  // namespace

Material derive_material(int p, int q, double r0, const Block& block) {
  validate_exponents(p, q);
  if (!(r0 > 0.0) || !std::isfinite(r0)) throw std::invalid_argument("r0 must be a positive length in cm");
  if (!(block.A >= r0) || !(block.B >= r0) || !(block.C >= r0) || !std::isfinite(block.A + block.B + block.C))
    throw std::invalid_argument("block must be at least one spacing r0 in every direction");

  Material m;
  m.p = p;
  m.q = q;
  m.r0_cm = r0;
  m.block = block;
  // Convention T (physics.md): nodes = round(extent / spacing) + 1 per direction.
  m.imax = static_cast<int>(std::lround(block.A / r0)) + 1;
  m.jmax = static_cast<int>(std::lround(block.B / (r0 * sin60))) + 1;
  m.kmax = static_cast<int>(std::lround(block.C / (r0 * layer))) + 1;
  m.N = static_cast<double>(m.imax) * m.jmax * m.kmax;  // Eq. (27)
  // N* counts atoms in the extents the lattice actually spans, (n - 1) spacings per direction.
  m.Nstar = atom_count((m.imax - 1) * r0, (m.jmax - 1) * r0 * sin60, (m.kmax - 1) * r0 * layer);
  m.mass_g = m.Nstar * copper::atom_mass_g / m.N;  // Eq. (28)

  const double phi_a = copper::potential(copper::r_a_paper_A);  // Eq. (3): -3.15045e-13 erg
  m.phi0_erg = m.Nstar * phi_a / m.N;                           // Eq. (29)

  double H = 0.0;
  if (p == 1) {  // Eq. (31) with the sign of physics.md
    const double r1q = std::pow(r0, 1.0 - q);
    H = m.phi0_erg * (1.0 - q) / ((1.0 - q) * r1q * std::log(r0) - r1q);
  } else {  // Eq. (33)
    H = m.phi0_erg * (1.0 - p) * (1.0 - q) * std::pow(r0, q - 1.0) / (p - q);
  }
  const double G = H * std::pow(r0, static_cast<double>(p - q));  // F(r0) = 0 (Eq. 30); Eq. 33 misprints r0^(1-q)
  m.law = PairLaw{p, q, G, H};
  try {  // r0^(q - 1) and r0^(p - q) leave double's range for large exponents at small r0 (or large at large)
    m.law.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("the material model gives no usable law for (p,q) = (" + std::to_string(p) + "," +
                                std::to_string(q) + ") at r0 = " + std::to_string(r0) + " cm (G = " +
                                std::to_string(G) + ", H = " + std::to_string(H) + "): " + e.what());
  }

  m.S0_dyne_per_cm = m.law.stiffness(r0);
  m.E_GPa = m.S0_dyne_per_cm / r0 * 1e-10;  // Eq. (26), dyne/cm^2 -> GPa
  m.r_d_cm = m.law.damage_spacing();
  m.peak_force_dyne = m.law.peak_force();
  const double sigma_cgs = m.peak_force_dyne / (m.r_d_cm * m.r_d_cm);
  m.sigma_TS_paper_MNm2 = sigma_cgs * 1e-8;  // Table 1's convention (a factor-10 slip, physics.md)
  m.sigma_TS_MNm2 = sigma_cgs * 1e-7;
  m.dt_max_stretch_s = dt_limit(m.law, m.mass_g, r0);
  return m;
}

double dt_limit(const PairLaw& law, double mass_g, double r_cm) {
  const double omega = std::sqrt(std::fabs(law.stiffness(r_cm)) / mass_g);  // Eq. (15)
  return 2.0 / omega;
}

std::vector<std::array<int, 2>> fig3_grid() {
  std::vector<std::array<int, 2>> grid;
  for (int p = 1; p <= 14; ++p)
    for (int q = p + 1; q <= 15; ++q) grid.push_back({p, q});
  return grid;
}

}  // namespace pmfrag

// Studies: scenes run and reduced to numbers, as plain structs (the command line prints and charts them).
#pragma once

#include <cstddef>
#include <filesystem>

namespace pmfrag::studies {

/// A virtual tensile test of one material, `pmfrag study modulus` (docs/accuracy.md, "Virtual tensile test").
struct TensileResult {
  int dim = 2, p = 0, q = 0;
  std::size_t particles = 0;
  double E_eq26 = 0;   ///< GPa: Eq. (26), E = S0 / r0
  double E_fit = 0;    ///< GPa: from the elastic energy U - U0 = E V eps^2 / 2 (2-D: a thickness of r0)
  double poisson = 0;  ///< lateral contraction of the middle slab over the axial strain
  double strain = 0;   ///< the largest axial strain reached
  double fit_rms = 0;  ///< rms residual of the energy fit, relative to the energy
};

/// Stretches a defect-free block of (p, q) slowly (its top and bottom rows pulled apart at 20 cm/s, ~20 wave
/// transits to a strain of 2e-3) and fits E and the Poisson ratio. 2-D: a 6 x 12 cm triangular plate; 3-D:
/// 16 x 30 x 12 fcc sites; both `scale` times larger in every direction. The run goes to a folder under `dir`
/// (throws std::runtime_error if it stops early).
TensileResult tensile_test(const std::filesystem::path& dir, int dim, int p, int q, int scale = 1);

}  // namespace pmfrag::studies

// Lattice sites of the paper's meshes (Sec. 3): Greenspan's 2-D plate in its 1-D storage order, the
// triangular lattice it is a piece of, and the close-packed 3-D block (stacked "hcp" as printed, or "fcc"
// as named; see docs/physics.md).
#pragma once

#include "pmfrag/body/geometry.hpp"

#include <vector>

namespace pmfrag {

struct Sites {
  int dim = 2;
  std::vector<Vec3> position;  ///< cm
  std::vector<int> index;      ///< the site's number in its lattice's own storage order (1-based)
};

/// Greenspan's 8 x 11.43 cm plate, r0 = 0.2 cm: 2713 sites numbered as in Sec. 3.1 (rows of 40 and 41).
Sites greenspan_plate();

/// Triangular lattice (2-D): rows j = 0..ny-1 at y0 + j r0 sin60, x = x0 + i r0 (odd rows shifted by -r0/2),
/// i = 0..nx-1. This is the paper's x-y section of the 3-D block.
Sites triangular_lattice(double r0, const Vec3& origin, int nx, int ny);

enum class Stacking { hcp, fcc };

/// Close-packed block (Sec. 3.2): sections k = 0..nz-1 of the triangular lattice at z0 + k r0 sqrt(6)/3.
/// hcp: sections alternate shifts B = (-r0/2, +r0 sin60/3) and A = (0, 0), as printed; fcc: B, A, C with
/// C = (-r0/2, -r0 sin60/3). Sites are numbered section by section but stored row j by row, each row
/// through all sections (see lattice.cpp: it keeps bonded particles close in memory).
Sites close_packed_lattice(double r0, const Vec3& origin, int nx, int ny, int nz, Stacking stacking);

/// The lattice-site counts that cover a bounding box [min, max] starting at min (one extra column so the
/// shifted rows reach the right edge).
void lattice_counts_for(const Vec3& min, const Vec3& max, double r0, int dim, int& nx, int& ny, int& nz);

}  // namespace pmfrag

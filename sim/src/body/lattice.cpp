#include "pmfrag/body/lattice.hpp"

#include <cmath>

namespace pmfrag {

namespace {
const double sin60 = std::sqrt(3.0) / 2.0;
}

Sites greenspan_plate() {
  // Sec. 3.1, literally: x(1) = -3.9, y(1) = -5.71576764; x(41) = -4.0, y(41) = -5.54256256; rows of 40 and 41;
  // site i repeats site i-81 two rows (2 r0 sin60) higher, up to i = 2713.
  constexpr int n = 2713;
  constexpr double r0 = 0.2;
  std::vector<double> x(n + 1), y(n + 1);
  x[1] = -3.9;
  y[1] = -5.71576764;
  for (int i = 1; i <= 39; ++i) x[i + 1] = x[i] + r0, y[i + 1] = y[1];
  x[41] = -4.0;
  y[41] = -5.54256256;
  for (int i = 41; i <= 80; ++i) x[i + 1] = x[i] + r0, y[i + 1] = y[41];
  for (int i = 82; i <= n; ++i) x[i] = x[i - 81], y[i] = y[i - 81] + 2.0 * r0 * sin60;
  Sites s;
  s.dim = 2;
  for (int i = 1; i <= n; ++i) {
    s.position.emplace_back(x[i], y[i], 0.0);
    s.index.push_back(i);
  }
  return s;
}

Sites triangular_lattice(double r0, const Vec3& origin, int nx, int ny) {
  Sites s;
  s.dim = 2;
  s.position.reserve(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  s.index.reserve(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  int k = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = origin.x() + r0 * i - ((j % 2) ? 0.5 * r0 : 0.0);
      s.position.emplace_back(x, origin.y() + r0 * sin60 * j, origin.z());
      s.index.push_back(++k);
    }
  return s;
}

Sites close_packed_lattice(double r0, const Vec3& origin, int nx, int ny, int nz, Stacking stacking) {
  const double dx = 0.5 * r0, dy = r0 * sin60, dz = r0 * std::sqrt(6.0) / 3.0;
  const Vec3 shiftA(0, 0, 0), shiftB(-dx, dy / 3.0, 0), shiftC(-dx, -dy / 3.0, 0);
  Sites s;
  s.dim = 3;
  const std::size_t sites = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz);
  s.position.reserve(sites), s.index.reserve(sites);  // grown by doubling, they would hold up to twice that
  // Stored row by row through the thickness (i fastest, then the section k, then the row j), numbered
  // section by section (index = 1 + i + nx (j + ny k)): a particle's bonds then reach at most one row of
  // every section ahead (nx nz + nx + 1 places, 862 in the paper's block) instead of a whole section
  // (nx ny + nx + 1, 2789), so the bond stencil's buffers stay in L2.
  for (int j = 0; j < ny; ++j)
    for (int k = 0; k < nz; ++k) {
      Vec3 shift;
      if (stacking == Stacking::hcp)
        shift = (k % 2 == 0) ? shiftB : shiftA;  // the paper's odd (1-based) sections shifted: ABAB
      else
        shift = (k % 3 == 0) ? shiftB : (k % 3 == 1) ? shiftA : shiftC;
      for (int i = 0; i < nx; ++i) {
        const double x = origin.x() + r0 * i - ((j % 2) ? dx : 0.0);
        s.position.emplace_back(x + shift.x(), origin.y() + dy * j + shift.y(), origin.z() + dz * k);
        s.index.push_back(1 + i + nx * (j + ny * k));
      }
    }
  return s;
}

void lattice_counts_for(const Vec3& min, const Vec3& max, double r0, int dim, int& nx, int& ny, int& nz) {
  const double eps = 1e-9;
  nx = static_cast<int>(std::floor((max.x() - min.x()) / r0 + eps)) + 2;
  ny = static_cast<int>(std::floor((max.y() - min.y()) / (r0 * sin60) + eps)) + 1;
  nz = dim == 3 ? static_cast<int>(std::floor((max.z() - min.z()) / (r0 * std::sqrt(6.0) / 3.0) + eps)) + 1 : 1;
}

}  // namespace pmfrag

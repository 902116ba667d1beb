// Cell list for finding pairs closer than a cutoff, in O(N log N) for any spread of particles: cells are
// keyed by their integer coordinates and sorted, so pieces that fly far apart cost no empty cells.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pmfrag {

template <int D>
class CellList {
 public:
  using V = Eigen::Matrix<double, D, 1>;

  /// Calls f(i, j, r2) once for every pair i < j with |x_i - x_j|^2 < cutoff^2, in a fixed order that
  /// depends only on the positions (so lists built from equal positions are equal).
  /// x: a vector of V, whatever its allocator.
  template <class Positions, class F>
  void for_each_pair(const Positions& x, double cutoff, F&& f) {
    const std::size_t n = x.size();
    checks_ = 0;
    if (n < 2) return;
    V lo = x[0];
    for (const auto& p : x) lo = lo.cwiseMin(p);
    const double inv_cell = 1.0 / cutoff;
    // Built per call, not kept: at millions of particles they were 32 (2-D) to 40 (3-D) bytes a particle for
    // the whole run, and a rebuild's sort costs far more than their allocation.
    std::vector<Entry> entries(n);
    for (std::size_t i = 0; i < n; ++i) {
      std::array<std::int64_t, 3> c{0, 0, 0};
      for (int d = 0; d < D; ++d) c[d] = clamp_cell(std::floor((x[i][d] - lo[d]) * inv_cell));
      entries[i] = {pack(c), static_cast<std::uint32_t>(i)};
    }
    std::sort(entries.begin(), entries.end());
    // positions in cell order (sorted): the inner loop reads a contiguous run instead of jumping through x
    std::vector<V> sorted(n);
    for (std::size_t a = 0; a < n; ++a) sorted[a] = x[entries[a].index];
    const double cut2 = cutoff * cutoff;
    // One cursor per row of neighbour cells (dz, dy): cells are visited in key order, so the first key a row
    // needs only grows, and each cursor moves forward through the sorted entries (a binary search per
    // neighbour cell was most of a contact-list rebuild in 3-D).
    std::array<std::size_t, 9> cursor{};
    std::size_t begin = 0;
    while (begin < n) {
      std::size_t end = begin;
      const std::uint64_t key = entries[begin].key;
      while (end < n && entries[end].key == key) ++end;
      const auto c = unpack(key);
      // Neighbour cells with key >= this one cover each pair of cells once (same cell: i < j).
      int row = 0;
      for (int dz = (D == 3 ? -1 : 0); dz <= (D == 3 ? 1 : 0); ++dz)
        for (int dy = -1; dy <= 1; ++dy, ++row) {
          const std::int64_t ny = c[1] + dy, nz = c[2] + dz;
          if (ny < 0 || nz < 0 || ny > max_cell || nz > max_cell) continue;
          if (pack({c[0] + 1 > max_cell ? max_cell : c[0] + 1, ny, nz}) < key) continue;  // the whole row lies below
          // The row's first key for this cell; the next cell (one to the right) needs the cell after it.
          std::size_t& first = cursor[static_cast<std::size_t>(row)];
          const std::uint64_t row_key = pack({c[0] > 0 ? c[0] - 1 : 0, ny, nz});
          while (first < n && entries[first].key < row_key) ++first;
          std::size_t at = first;
          for (int dx = -1; dx <= 1; ++dx) {
            const std::int64_t nx = c[0] + dx;
            if (nx < 0 || nx > max_cell) continue;
            const std::uint64_t nkey = pack({nx, ny, nz});
            if (nkey < key) continue;
            while (at < n && entries[at].key < nkey) ++at;
            const std::size_t nb = at;
            std::size_t ne = nb;
            while (ne < n && entries[ne].key == nkey) ++ne;
            at = ne;
            checks_ += (end - begin) * (ne - nb);
            for (std::size_t a = begin; a < end; ++a) {
              const std::uint32_t i = entries[a].index;
              const V xi = sorted[a];
              for (std::size_t b = nkey == key ? a + 1 : nb; b < ne; ++b) {  // same cell: sorted by index
                const double r2 = (xi - sorted[b]).squaredNorm();
                if (r2 < cut2) {
                  const std::uint32_t j = entries[b].index;
                  f(std::min(i, j), std::max(i, j), r2);
                }
              }
            }
          }
        }
      begin = end;
    }
  }

  /// Candidate pairs the last call examined (work, for tests: it must not grow with how far pieces fly).
  std::size_t checks() const { return checks_; }
  /// Cells span up to 2^21 cutoffs per axis (8e5 cm at D = 0.34 cm); pieces beyond share edge cells.
  static constexpr std::int64_t max_cell = (1 << 21) - 1;

 private:
  struct Entry {
    std::uint64_t key;
    std::uint32_t index;
    bool operator<(const Entry& o) const { return key < o.key || (key == o.key && index < o.index); }
  };
  static std::int64_t clamp_cell(double c) {
    // Particles absurdly far away share edge cells: still correct (distances are checked), just slower.
    if (!(c >= 0.0)) return 0;
    return c > static_cast<double>(max_cell) ? max_cell : static_cast<std::int64_t>(c);
  }
  static std::uint64_t pack(const std::array<std::int64_t, 3>& c) {
    return (static_cast<std::uint64_t>(c[2]) << 42) | (static_cast<std::uint64_t>(c[1]) << 21) |
           static_cast<std::uint64_t>(c[0]);
  }
  static std::array<std::int64_t, 3> unpack(std::uint64_t k) {
    return {static_cast<std::int64_t>(k & max_cell), static_cast<std::int64_t>((k >> 21) & max_cell),
            static_cast<std::int64_t>(k >> 42)};
  }
  std::size_t checks_ = 0;
};

}  // namespace pmfrag

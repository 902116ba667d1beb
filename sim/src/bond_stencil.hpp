// Bond forces on a lattice, evaluated as stencil sweeps. Particles of a lattice body are numbered row by
// row, so most bonds (i, j) share one of a few index offsets o = j - i (Greenspan's plate: 1, 40, 41). For
// each common offset, one contiguous, vectorized sweep over i evaluates every bond (i, i + o) once and
// stores its force at F[o + i] in an array padded with o zeros at each end; particle i then receives
// F[o + i] - F[i] from that offset: no gathers, no scatters, each bond evaluated once. Bonds off the
// common offsets (around holes and slits, between bodies) go through a pair table and a gather.
// Every particle's sum has a fixed order, so forces are bitwise the same for any thread count.
#pragma once

#include "bond_sweep_avx512.hpp"
#include "pair_kernels.hpp"
#include "team.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>

namespace pmfrag::detail {

/// F(r)/r of one bond (> 0 repulsive), 0 if the bond is gone or longer than sqrt(cut2); counts in `broke` a
/// live bond found too long (broken for good the first time it exceeds D: the caller retires it).
/// Branch-free, so the loops calling it vectorize. Real = float evaluates r², 1/r and the law in single
/// precision (the breaking test stays in double, so a bond breaks at the same length either way).
template <class Real, class Law>
inline double bond_force_over_r(const Law& law, std::size_t k, double r2, bool live, double cut2, double inv_rmin,
                                long& broke) {
  const bool within = r2 <= cut2;
  broke += live & !within;
  const Real inv = Real(1) / std::sqrt(Real(live ? r2 : cut2));  // no bond here: keep the arithmetic finite
  const Real ie = std::min(inv, Real(inv_rmin));                 // force held constant inside r_min (Sec. 4.2)
  // Computed for every slot and masked by a multiplication: with a select, GCC 12 leaves the float variant
  // unvectorized ("control flow in loop").
  const double fr = static_cast<double>(law.template magnitude<Real>(k, ie) * inv);
  return fr * static_cast<double>(live & within);
}

template <int D>
class BondStencil {
 public:
  BondStencil() = default;
  /// bonds (i < j) with their law index; n particles.
  BondStencil(std::size_t n, const std::vector<int>& bi, const std::vector<int>& bj, const std::vector<int>& blaw,
              bool single_precision = false) {
    n_ = n;
    single_ = single_precision;
    std::map<int, std::size_t> count;
    for (std::size_t b = 0; b < bi.size(); ++b) ++count[bj[b] - bi[b]];
    std::map<int, int> group_of;
    for (auto [o, c] : count) {
      // A sweep costs n - o evaluations: worth it when at least 40 % of them are bonds.
      if (static_cast<std::size_t>(o) < n && c >= 8 && static_cast<double>(c) >= 0.4 * static_cast<double>(n - o)) {
        group_of[o] = static_cast<int>(groups_.size());
        Group g;
        g.offset = o;
        g.alive.assign(n - o, 0);
        g.law.assign(n - o, 0);
        for (auto& f : g.F) f.assign(n + o, 0.0);
        groups_.push_back(std::move(g));
      }
    }
    loc_.resize(bi.size());
    for (std::size_t b = 0; b < bi.size(); ++b) {
      const int o = bj[b] - bi[b];
      auto it = group_of.find(o);
      if (it != group_of.end()) {
        Group& g = groups_[static_cast<std::size_t>(it->second)];
        g.alive[static_cast<std::size_t>(bi[b])] = 1;
        g.law[static_cast<std::size_t>(bi[b])] = blaw[b];
        loc_[b] = {it->second, bi[b]};
      } else {
        loc_[b] = {-1, static_cast<int>(sparse_.size())};
        sparse_.add(bi[b], bj[b], blaw[b]);
        sparse_alive_.push_back(1);
      }
    }
    sparse_.index(n);
    for (auto& c : xs_) c.assign(n, 0.0);
  }

  void set_alive(std::size_t bond, bool alive) {
    const auto [g, k] = loc_[bond];
    if (g >= 0)
      groups_[static_cast<std::size_t>(g)].alive[static_cast<std::size_t>(k)] = alive;
    else
      sparse_alive_[static_cast<std::size_t>(k)] = alive;
  }

  std::size_t sweeps() const { return groups_.size(); }
  std::size_t sparse_bonds() const { return sparse_.size(); }

  /// Adds bond forces to f (N x D, interleaved). Returns the number of intact bonds found longer than
  /// sqrt(cut2): the caller retires them.
  template <class Law>
  long add_forces(const double* x, double* f, const Law& law, double cut2, double inv_rmin) {
    const long n = static_cast<long>(n_);
    std::atomic<long> broke{0};
    Team& team = Team::get(n_);
    team.run([&](int tid) {
      const int nt = team.size();
      const auto [b, e] = particle_share(n, tid, nt);
      for (long p = b; p < e; ++p)
        for (int c = 0; c < D; ++c) xs_[c][static_cast<std::size_t>(p)] = x[static_cast<std::size_t>(p) * D + c];
      team.barrier();  // the sweeps read neighbours' positions
      long mine = 0;
      for (auto& g : groups_) {
        if (single_)
          sweep<float>(g, law.with_ids(g.law.data()), cut2, inv_rmin, mine, tid, nt);
        else
          sweep<double>(g, law.with_ids(g.law.data()), cut2, inv_rmin, mine, tid, nt);
      }
      if (sparse_.size() > 0) {
        if (single_)
          sparse_pass<float>(law.with_ids(sparse_.law.data()), cut2, inv_rmin, mine, tid, nt);
        else
          sparse_pass<double>(law.with_ids(sparse_.law.data()), cut2, inv_rmin, mine, tid, nt);
      }
      if (mine > 0) broke.fetch_add(mine, std::memory_order_relaxed);
      team.barrier();  // assembly reads every thread's bond forces
      assemble(f, tid, nt);
    });
    return broke.load();
  }

 private:
  struct Group {
    int offset = 0;
    std::vector<std::uint8_t> alive;  ///< bond (i, i + offset) exists and is intact
    std::vector<int> law;
    std::vector<double> F[D];  ///< force on i of bond (i, i + offset) at F[offset + i]; zeros at both ends
  };

  // Evaluate one offset's bonds (inside a parallel region).
  template <class Real, class Law>
  void sweep(Group& g, const Law law, double cut2, double inv_rmin, long& broke, int tid, int nt) {
    const long m = static_cast<long>(n_) - g.offset;
    const std::size_t o = static_cast<std::size_t>(g.offset);
    const double* __restrict x0 = xs_[0].data();
    const double* __restrict x1 = xs_[1].data();
    const double* __restrict x2 = xs_[D - 1].data();
    const std::uint8_t* __restrict alive = g.alive.data();
    double* __restrict F0 = g.F[0].data() + o;
    double* __restrict F1 = g.F[1].data() + o;
    double* __restrict F2 = g.F[D - 1].data() + o;
    // Bonds by their first particle, in this thread's particles: the assembly reads them from this core.
    const auto [pb, pe] = particle_share(static_cast<long>(n_), tid, nt);
    const long b = std::min(pb, m), e = std::min(pe, m);
#ifdef PMFRAG_HAVE_AVX512_SWEEP
    if constexpr (std::is_same_v<Real, double> && is_fixed_law<Law>::value) {
      broke += sweep_fixed_avx512<D, Law::p, Law::q>(x0, x1, x2, o, alive, F0, F1, F2, static_cast<std::size_t>(b),
                                                     static_cast<std::size_t>(e), law.G, law.H, cut2, inv_rmin);
      return;
    }
#endif
#pragma omp simd reduction(+ : broke)
    for (long p = b; p < e; ++p) {
      const std::size_t i = static_cast<std::size_t>(p);
      const double d0 = x0[i] - x0[i + o], d1 = x1[i] - x1[i + o];
      const double d2 = D == 3 ? x2[i] - x2[i + o] : 0.0;
      const double fr = bond_force_over_r<Real>(law, i, d0 * d0 + d1 * d1 + d2 * d2, alive[i] != 0, cut2, inv_rmin, broke);
      F0[i] = fr * d0;
      F1[i] = fr * d1;
      if constexpr (D == 3) F2[i] = fr * d2;
    }
  }

  template <class Real, class Law>
  void sparse_pass(const Law law, double cut2, double inv_rmin, long& broke, int tid, int nt) {
    const long m = static_cast<long>(sparse_.size());
    const int* __restrict pi = sparse_.i.data();
    const int* __restrict pj = sparse_.j.data();
    const std::uint8_t* __restrict alive = sparse_alive_.data();
    const double* __restrict x0 = xs_[0].data();
    const double* __restrict x1 = xs_[1].data();
    const double* __restrict x2 = xs_[D - 1].data();
    double* __restrict F0 = sparse_.force[0].data();
    double* __restrict F1 = sparse_.force[1].data();
    double* __restrict F2 = sparse_.force[D - 1].data();
    const auto [first, last] = share(m, tid, nt);
#pragma omp simd reduction(+ : broke)
    for (long p = first; p < last; ++p) {
      const std::size_t u = static_cast<std::size_t>(p);
      const std::size_t a = static_cast<std::size_t>(pi[u]), b = static_cast<std::size_t>(pj[u]);
      const double d0 = x0[a] - x0[b], d1 = x1[a] - x1[b];
      const double d2 = D == 3 ? x2[a] - x2[b] : 0.0;
      const double fr = bond_force_over_r<Real>(law, u, d0 * d0 + d1 * d1 + d2 * d2, alive[u] != 0, cut2, inv_rmin, broke);
      F0[u] = fr * d0;
      F1[u] = fr * d1;
      if constexpr (D == 3) F2[u] = fr * d2;
    }
  }

  // f_i += sum over offsets of F[o + i] - F[i], then the sparse bonds of i, each particle in a fixed order
  // (bitwise the same for any partition into threads). One pass over f in blocks: the offsets' terms are
  // summed in a small buffer first, so f is read and written once however many offsets there are.
  void assemble(double* f, int tid, int nt) const {
    constexpr long block = particle_grain;
    const long n = static_cast<long>(n_);
    const int* __restrict off = sparse_.offset.data();
    const bool any_sparse = sparse_.size() > 0;
    const auto [pb, pe] = particle_share(n, tid, nt);  // whole blocks
    for (long blk = pb / block; blk * block < pe; ++blk) {
      const std::size_t b0 = static_cast<std::size_t>(blk * block);
      const std::size_t len = static_cast<std::size_t>(std::min(block, n - blk * block));
      alignas(64) double acc[D][block];
      for (int c = 0; c < D; ++c)
        for (std::size_t k = 0; k < len; ++k) acc[c][k] = 0.0;
      for (const Group& g : groups_) {
        const std::size_t o = static_cast<std::size_t>(g.offset);
        for (int c = 0; c < D; ++c) {
          const double* __restrict F = g.F[c].data() + b0;
          double* __restrict a = acc[c];
#pragma omp simd
          for (std::size_t k = 0; k < len; ++k) a[k] += F[o + k] - F[k];
        }
      }
      if (any_sparse) {
        for (std::size_t k = 0; k < len; ++k) {
          if (off[b0 + k] == off[b0 + k + 1]) continue;
          double sum[D];
          sparse_.sum_of(b0 + k, sum);
          for (int c = 0; c < D; ++c) acc[c][k] += sum[c];
        }
      }
      double* __restrict fb = f + b0 * D;
      for (std::size_t k = 0; k < len; ++k)
        for (int c = 0; c < D; ++c) fb[k * D + static_cast<std::size_t>(c)] += acc[c][k];
    }
  }

  std::size_t n_ = 0;
  bool single_ = false;
  std::vector<Group> groups_;
  PairTable<D> sparse_;
  std::vector<std::uint8_t> sparse_alive_;
  std::vector<std::pair<int, int>> loc_;  ///< bond -> (group or -1 for sparse, index)
  std::vector<double> xs_[D];             ///< positions by component (contiguous sweeps)
};

}  // namespace pmfrag::detail

// Bond forces on a lattice, evaluated as stencil sweeps. Particles of a lattice body are numbered row by
// row, so most bonds (i, j) share one of a few index offsets o = j - i (Greenspan's plate: 1, 40, 41). For
// each common offset, one contiguous, vectorized sweep over i evaluates every bond (i, i + o) and stores its
// force on i at F[i]; particle i then receives F[i] - F[i - o] from that offset: no gathers, no scatters.
// Bonds off the common offsets (around holes and slits, between bodies) go through a pair table and a gather.
// In a large body, offsets whose bonds share no particle share one F (a group: the 3-D block's 819 and 821,
// one lattice direction on rows of either parity); particle i then receives -F[i - o] at the offset o whose
// bond reaches it.
//
// Sweep and assembly run together, one block of 256 particles at a time: a block's bond forces are summed
// into f while they are still in L1. The assembly reads F[i - o] at most one block plus the largest offset
// back, so each offset's F is a ring of R slots (R a power of two, at least that far): the buffers stay in
// L2 however large the body (the 3-D block's full-length rows, 17 MB, streamed through memory). Each thread
// keeps the bond forces of its own particles, and evaluates the few bonds (i - o, i) reaching back into the
// previous thread's particles itself (the same arithmetic, so the same bits), so no thread waits for another
// between the sweep and the assembly. Every particle's sum has a fixed order: forces are bitwise the same
// for any thread count.
#pragma once

#include "pmfrag/kernels/aligned.hpp"
#include "kernels/bond_sweep_avx512.hpp"
#include "pmfrag/run/build_info.hpp"
#include "kernels/pair_kernels.hpp"
#include "threads/team.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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
  /// bonds (i < j), sorted by (i, j), with their law index; n particles. merge_offsets = false: one group per
  /// offset always (the tests compare the two layouts). per_bond_laws = false: the caller only ever passes a
  /// single-law evaluator (FixedLaw, OneLaw), so no per-particle law index is stored (4 B per particle and
  /// group: 12 B a particle on the plate, 32 on the 3-D block).
  BondStencil(std::size_t n, const std::vector<int>& bi, const std::vector<int>& bj, const std::vector<int>& blaw,
              bool single_precision = false, bool merge_offsets = true, bool per_bond_laws = true) {
    n_ = n;
    single_ = single_precision;
    for (std::size_t b = 1; b < bi.size(); ++b)  // set_alive bisects the off-stencil bonds in this order
      if (bi[b - 1] > bi[b] || (bi[b - 1] == bi[b] && bj[b - 1] >= bj[b]))
        throw std::logic_error("BondStencil: the bonds are not sorted by (i, j)");
    // per offset o = j - i (0 < o < n): flat arrays, not maps (the cutoff model builds a stencil per list)
    std::vector<std::uint32_t> count(n, 0);
    for (std::size_t b = 0; b < bi.size(); ++b) ++count[static_cast<std::size_t>(bj[b] - bi[b])];
    // A sweep evaluates only the runs of consecutive i that have a bond, but the assembly visits every
    // particle once per group. Measured (1 thread): an offset is worth a sweep when at least 5 % of its slots
    // are bonds (the plate's 39: 22 %, 10 % faster as a sweep; the 3-D block's inter-plane offsets at 15-36 %:
    // the bond pass 1.36 -> 0.94 ms once they were swept from rings that stay in L2).
    std::vector<int> swept;
    for (std::size_t uo = 1; uo < n && swept.size() < max_stencil_offsets; ++uo) {
      const std::size_t c = count[uo];
      if (c >= 8 && static_cast<double>(c) >= 0.05 * static_cast<double>(n - uo)) swept.push_back(static_cast<int>(uo));
    }
    // Offsets whose bonds share no first and no second particle may share one buffer (a group): a lattice
    // direction whose offset changes with the row's parity or the section's stacking is then swept into one
    // ring, and the assembly reads it back at each offset only where a bond lands (the 3-D block: 13 offsets
    // in 8 groups, the fewest its conflicts allow). Merged only where the rings stream through L2 (the test
    // for a whole-body ring below): there it saves stores and zero fills (3-D block: one thread 1.24x / 1.11x
    // on the two cores, two threads 1.02-1.05x). A body whose rings fit ran 0.90x / 0.91x merged (the plate,
    // one / two threads: its 39 and 41 alternate every 40-41 particles). The most populous offsets go first.
    const long largest = swept.empty() ? 0 : swept.back();
    const bool merge = merge_offsets && !fits_whole(n, swept.size(), aligned_reach(largest));
    if (merge)
      std::stable_sort(swept.begin(), swept.end(), [&](int a, int b) {
        return count[static_cast<std::size_t>(a)] > count[static_cast<std::size_t>(b)];
      });
    std::vector<std::vector<int>> starts(swept.size());  // merging: the first particles of each offset's bonds
    if (merge) {
      std::vector<int> term_of(n, -1);
      for (std::size_t k = 0; k < swept.size(); ++k) term_of[static_cast<std::size_t>(swept[k])] = static_cast<int>(k);
      for (std::size_t b = 0; b < bi.size(); ++b) {
        const int k = term_of[static_cast<std::size_t>(bj[b] - bi[b])];
        if (k >= 0) starts[static_cast<std::size_t>(k)].push_back(bi[b]);
      }
    }
    std::vector<std::vector<std::uint8_t>> first_taken, second_taken;  // per group and particle
    std::vector<int> group_of(n, -1);                                  // per offset
    for (std::size_t k = 0; k < swept.size(); ++k) {
      const int o = swept[k];
      std::size_t gi = merge ? 0 : groups_.size();
      for (; gi < groups_.size(); ++gi)
        if (std::none_of(starts[k].begin(), starts[k].end(), [&](int i) {
              return first_taken[gi][static_cast<std::size_t>(i)] || second_taken[gi][static_cast<std::size_t>(i + o)];
            }))
          break;
      if (gi == groups_.size()) {
        groups_.emplace_back();
        groups_.back().alive.assign(n, 0);
        if (per_bond_laws) groups_.back().law.assign(n, 0);
        if (merge) first_taken.emplace_back(n, 0), second_taken.emplace_back(n, 0);
      }
      if (merge)
        for (const int i : starts[k])
          first_taken[gi][static_cast<std::size_t>(i)] = second_taken[gi][static_cast<std::size_t>(i + o)] = 1;
      groups_[gi].offsets.push_back(o);
      groups_[gi].max_offset = std::max(groups_[gi].max_offset, static_cast<long>(o));
      group_of[static_cast<std::size_t>(o)] = static_cast<int>(gi);
      group_at_offset_.push_back({o, static_cast<int>(gi)});
      reach_ = std::max(reach_, static_cast<long>(o));
    }
    std::sort(group_at_offset_.begin(), group_at_offset_.end());
    std::vector<std::vector<int>> offset_at(groups_.size(), std::vector<int>(n, 0));  // per group: each bond's offset
    std::vector<int> si, sj, sl;
    for (std::size_t b = 0; b < bi.size(); ++b) {
      const int gi = group_of[static_cast<std::size_t>(bj[b] - bi[b])];
      if (gi >= 0) {
        Group& g = groups_[static_cast<std::size_t>(gi)];
        const std::size_t i = static_cast<std::size_t>(bi[b]);
        g.alive[i] = 1;
        if (per_bond_laws) g.law[i] = blaw[b];
        offset_at[static_cast<std::size_t>(gi)][i] = bj[b] - bi[b];
      } else {
        si.push_back(bi[b]), sj.push_back(bj[b]), sl.push_back(blaw[b]);
        sparse_alive_.push_back(1);
      }
    }
    sparse_i_ = std::move(si), sparse_j_ = std::move(sj), sparse_law_ = std::move(sl);
    for (std::size_t gi = 0; gi < groups_.size(); ++gi) {
      Group& g = groups_[gi];
      const std::vector<int>& at = offset_at[gi];
      // Runs [begin, end) of i with a bond at one offset; gaps shorter than a vector are swept through (no
      // bond there: the force is zero).
      const long m = static_cast<long>(n);
      for (long i = 0; i < m; ++i) {
        const std::size_t u = static_cast<std::size_t>(i);
        if (!g.alive[u]) continue;
        if (!g.runs.empty() && g.runs.back().offset == at[u] && i - g.runs.back().end < 8)
          g.runs.back().end = i + 1;
        else
          g.runs.push_back({i, i + 1, at[u]});
      }
      if (g.offsets.size() > 1) {
        // per offset, the particles i (eight to a byte) that a bond (i - o, i) of the group reaches
        for (const int o : g.offsets) {
          std::vector<std::uint8_t> lanes((n + 7) / 8, 0);
          for (std::size_t i = 0; i + static_cast<std::size_t>(o) < n; ++i)
            if (g.alive[i] && at[i] == o) {
              const std::size_t j = i + static_cast<std::size_t>(o);
              lanes[j / 8] = static_cast<std::uint8_t>(lanes[j / 8] | (1u << (j % 8)));
            }
          g.lanes.push_back(std::move(lanes));
        }
        // per eight particles: the one offset that reaches them (its index, and its lanes), or 0xff if several
        g.codes.assign((n + 7) / 8, 0);
        for (std::size_t v = 0; v < g.codes.size(); ++v) {
          int term = -1;
          for (std::size_t t = 0; t < g.lanes.size(); ++t)
            if (g.lanes[t][v] != 0) term = term < 0 ? static_cast<int>(t) : 0xff;
          if (term < 0) term = 0;
          const unsigned mask = term == 0xff ? 0u : g.lanes[static_cast<std::size_t>(term)][v];
          g.codes[v] = static_cast<std::uint16_t>((static_cast<unsigned>(term) << 8) | mask);
        }
      }
    }
    for (const Group& g : groups_) {
      for (std::size_t k = 0; k < g.offsets.size(); ++k)
        terms_.push_back({static_cast<std::size_t>(g.offsets[k]), g.lanes.empty() ? nullptr : g.lanes[k].data()});
      group_terms_.push_back(g.offsets.size());
      group_codes_.push_back(g.codes.empty() ? nullptr : g.codes.data());
      offsets_.push_back(static_cast<std::size_t>(g.offsets.front()));
      merged_ = merged_ || g.offsets.size() > 1;
    }
    four_ = D == 2 && !merged_ && groups_.size() == 4;
    reach_ = aligned_reach(reach_);
    // a block's assembly reads back to F[b0 - reach]; the block being swept must not overwrite it
    ring_ = ring_of(static_cast<std::size_t>(reach_) + particle_grain);
    // small bodies: one slot per particle if that fits in L2 (the plate: 1.5 us a step slower on a ring of
    // two blocks, as the gaps between runs must then be zeroed)
    if (fits_whole(n_, groups_.size(), reach_)) ring_ = whole_ring(n_, reach_);
    // if no slot is ever reused, the slots no bond maps to keep their initial zeros
    wraps_ = ring_ < n_ + static_cast<std::size_t>(reach_);
  }

  /// Whether add_forces sets f (f = 0 + the bond forces, for every particle) instead of adding to it: the
  /// move then need not zero f, nor the assembly read it (two of the plate's seven streams through L2).
  void assign_forces(bool assign) { assign_ = assign; }

  /// Buffers the sweeps fill: one per offset, fewer where offsets were merged.
  std::size_t groups() const { return groups_.size(); }

  /// Marks the bond (i, j) of the constructor's list intact or not. Found from its offset (a group's bonds
  /// are indexed by i) or, off the stencil, by bisection of the few off-stencil bonds, which keep the list's
  /// (i, j) order: no per-bond index is kept (8 B a bond).
  void set_alive(int i, int j, bool alive) {
    const auto at = std::lower_bound(group_at_offset_.begin(), group_at_offset_.end(), std::pair<int, int>{j - i, -1});
    if (at != group_at_offset_.end() && at->first == j - i) {
      groups_[static_cast<std::size_t>(at->second)].alive[static_cast<std::size_t>(i)] = alive;
      return;
    }
    std::size_t lo = 0, hi = sparse_i_.size();  // the first off-stencil bond not before (i, j)
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      if (sparse_i_[mid] < i || (sparse_i_[mid] == i && sparse_j_[mid] < j))
        lo = mid + 1;
      else
        hi = mid;
    }
    if (lo == sparse_i_.size() || sparse_i_[lo] != i || sparse_j_[lo] != j)
      throw std::logic_error("BondStencil::set_alive: (" + std::to_string(i) + ", " + std::to_string(j) + ") is not a bond");
    sparse_alive_[lo] = alive;
  }

  /// Adds bond forces to f (N x D, interleaved), split among `team`'s threads. Returns a positive number if some intact bond was found
  /// longer than sqrt(cut2) (a bond near a thread boundary may be counted twice): the caller retires them.
  template <class Law>
  long add_forces(Team& team, const double* x, double* f, const Law& law, double cut2, double inv_rmin) {
    std::atomic<long> broke{0};
    prepare(team.bounds(static_cast<long>(n_)));
    team.run([&](int tid) {
      const long mine = add_forces_of(tid, x, f, law, cut2, inv_rmin);
      if (mine > 0) broke.fetch_add(mine, std::memory_order_relaxed);
    });
    return broke.load();
  }

  /// Readies the work of the partition `bounds` (Team::bounds; planned on first use, the last few kept):
  /// call before add_forces_of, outside the team.
  void prepare(const std::vector<long>& bounds) {
    for (std::size_t k = 0; k < plans_.size(); ++k)
      if (plans_[k].first == bounds) {
        current_ = k;
        return;
      }
    // A partition per thread count the tuner tries (and per weights a test sets): a few plans cover them.
    constexpr std::size_t kept = 6;
    if (plans_.size() == kept) plans_.erase(plans_.begin());
    plans_.emplace_back(bounds, plan(bounds));
    current_ = plans_.size() - 1;
  }

  /// Thread tid's part of add_forces (the forces on its share of the prepared partition), inside a team
  /// pass. Returns this thread's count of bonds found too long.
  template <class Law>
  long add_forces_of(int tid, const double* x, double* f, const Law& law, double cut2, double inv_rmin) {
    Work& w = plans_[current_].second[static_cast<std::size_t>(tid)];
    return single_ ? forces_of<float>(w, x, law, cut2, inv_rmin, f) : forces_of<double>(w, x, law, cut2, inv_rmin, f);
  }

 private:
  /// The reach rounded up to whole cache lines: keeps each thread's buffers 64-byte aligned like its particles.
  static long aligned_reach(long reach) { return (reach + 7) / 8 * 8; }
  /// The smallest ring (a block times a power of two) of at least `least` slots.
  static std::size_t ring_of(std::size_t least) {
    std::size_t r = particle_grain;
    while (r < least) r *= 2;
    return r;
  }
  /// A ring in which no slot holds two particles: n + reach slots, at least a block plus the reach.
  static std::size_t whole_ring(std::size_t n, long reach) {
    return ring_of(std::max(n, static_cast<std::size_t>(particle_grain)) + static_cast<std::size_t>(reach));
  }
  /// Whether a thread's rings of `groups` groups may hold every particle once and still leave most of the
  /// core's L2 (read at run time) to the particles' positions and forces: a quarter of it (256 KiB on the
  /// 1 MiB L2 of the machine this was first measured on; 256 KiB where the size cannot be read).
  static bool fits_whole(std::size_t n, std::size_t groups, long reach) {
    const std::size_t l2 = l2_cache_bytes();
    const std::size_t budget = l2 > 0 ? l2 / 4 : (256u << 10);
    return whole_ring(n, reach) * groups * D * sizeof(double) <= budget;
  }

  struct Run {
    long begin, end;  ///< [begin, end) of i
    int offset;       ///< the bonds (i, i + offset)
  };
  struct Group {
    std::vector<int> offsets;  ///< in the order the assembly subtracts them
    long max_offset = 0;
    std::vector<std::uint8_t> alive;  ///< per particle i: its bond in the group exists and is intact
    std::vector<int> law;
    std::vector<Run> runs;       ///< ascending
    std::vector<std::vector<std::uint8_t>> lanes;  ///< per offset, if several (StencilTerm::lanes)
    std::vector<std::uint16_t> codes;  ///< per eight particles, if several offsets: term << 8 | lanes, term 0xff: mixed
  };
  /// One thread's particles [pb, pe) and what it needs to sum their bond forces by itself.
  struct Work {
    long pb = 0, pe = 0;
    /// per group and component (stride `stride`): force on i of bond (i, i + offset) at slot i mod R; slots
    /// [R, R + 256) repeat the first block, so a block's F[i - o] read from anywhere in the ring never wraps
    std::vector<double, AlignedAllocator<double>> F;
    std::size_t stride = 0;
    double* F_of(std::size_t g, int c) { return F.data() + (g * D + static_cast<std::size_t>(c)) * stride; }
    const double* F_of(std::size_t g, int c) const {
      return F.data() + (g * D + static_cast<std::size_t>(c)) * stride;
    }
    PairTable<D> sparse;                 ///< off-stencil bonds touching [pb, pe), in ascending global order
    std::vector<int> sparse_id;          ///< their index among all off-stencil bonds (for `alive`)
    std::vector<std::uint8_t, AlignedAllocator<std::uint8_t>> sparse_alive;
    long xlo = 0, xhi = 0;  ///< the particles whose positions its sweeps read (its own and `reach` either side)
    std::vector<double, AlignedAllocator<double>> xs[D];  ///< their positions by component, from xlo
    /// per group: the first run the thread sweeps; the first not yet swept this step (written by the
    /// thread, in lines of its own)
    std::vector<std::size_t> first_run;
    std::vector<std::size_t, AlignedAllocator<std::size_t>> next_run;
  };

  // Positions of particles [from, to) into the thread's copy, by component.
  static void copy_positions(Work& w, const double* x, long from, long to) {
    for (long p = from; p < to; ++p)
      for (int c = 0; c < D; ++c)
        w.xs[c][static_cast<std::size_t>(p - w.xlo)] = x[static_cast<std::size_t>(p) * D + static_cast<std::size_t>(c)];
  }

  // Each thread's share of particles, its sweep buffers (zeros where no bond is ever evaluated: before
  // particle 0 and past n - offset) and its off-stencil bonds.
  std::vector<Work> plan(const std::vector<long>& bounds) const {
    const std::size_t threads = bounds.size() - 1;
    std::vector<Work> work(threads);
    const long n = static_cast<long>(n_);
    for (std::size_t t = 0; t < threads; ++t) {
      Work& w = work[t];
      w.pb = bounds[t], w.pe = bounds[t + 1];
      // the ring, its repeated first block, and one cache line more: R and 256 are even numbers of cache
      // lines, so the stride is odd and the 64-byte aligned rows do not all fall into the same L1 sets
      w.stride = ring_ + particle_grain + 8;
      w.F.assign(groups_.size() * D * w.stride, 0.0);
      for (std::size_t b = 0; b < sparse_i_.size(); ++b) {
        const auto in = [&](int p) { return p >= w.pb && p < w.pe; };
        if (in(sparse_i_[b]) || in(sparse_j_[b])) {
          w.sparse.add(sparse_i_[b], sparse_j_[b], sparse_law_[b]);
          w.sparse_id.push_back(static_cast<int>(b));
        }
      }
      w.sparse.index(n_);
      w.xlo = std::max(0L, w.pb - reach_);
      w.xhi = std::min(n, w.pe + reach_);
      if (w.pb >= w.pe) w.xlo = w.xhi = w.pb;
      // 8 more: the sweep reads whole aligned eights, up to 7 positions past a run's last partner
      for (auto& c : w.xs) c.assign(static_cast<std::size_t>(w.xhi - w.xlo) + 8, 0.0);
      w.sparse_alive.resize(w.sparse_id.size());
      for (const Group& g : groups_) {
        const long from = std::max(0L, w.pb - g.max_offset);
        w.first_run.push_back(static_cast<std::size_t>(
            std::lower_bound(g.runs.begin(), g.runs.end(), from, [](const Run& run, long i) { return run.end <= i; }) -
            g.runs.begin()));
      }
      w.next_run.assign(w.first_run.begin(), w.first_run.end());
    }
    return work;
  }

  // This thread's bond forces at positions x (N x D): off-stencil bonds first, then block by block every
  // offset's sweep and the assembly into f. The thread copies the positions the sweeps read (its particles
  // and their partners) by component, no other thread waiting for it. A body whose bond forces fit the
  // ring whole (the plate) is copied in one pass; a larger one block by block just ahead of the sweeps (the
  // 3-D block's 1.3 MB of positions were copied whole and read back from beyond L2: one thread 1.02-1.04x;
  // the plate copied so ran 0.96-0.97x on two threads).
  template <class Real, class Law>
  long forces_of(Work& w, const double* x, const Law& law, double cut2, double inv_rmin, double* f) {
    long broke = 0;
    long copied = w.xlo;  // the positions copied so far: [xlo, copied)
    const auto copy_to = [&](long end) {
      end = std::min(end, w.xhi);
      if (copied < end) copy_positions(w, x, copied, end), copied = end;
    };
    if (!wraps_) copy_to(w.xhi);
    for (std::size_t u = 0; u < w.sparse_id.size(); ++u)
      w.sparse_alive[u] = sparse_alive_[static_cast<std::size_t>(w.sparse_id[u])];
    if (w.sparse.size() > 0) sparse_pass<Real>(w, x, law.with_ids(w.sparse.law.data()), cut2, inv_rmin, broke);
    std::copy(w.first_run.begin(), w.first_run.end(), w.next_run.begin());
    // The bonds (i, i + o) with i < pb whose second particle is ours (none before particle 0: zeros).
    copy_to(w.pb + reach_);
    for (std::size_t g = 0; g < groups_.size(); ++g) {
      zero(w, g, w.pb - groups_[g].max_offset, std::min(0L, w.pb));
      sweep_runs<Real>(w, g, law.with_ids(groups_[g].law.data()), cut2, inv_rmin, broke,
                       std::max(0L, w.pb - groups_[g].max_offset), w.pb);
    }
    std::size_t next_touched = 0;
    for (long b0 = w.pb; b0 < w.pe; b0 += particle_grain) {
      const long b1 = std::min(w.pe, b0 + particle_grain);
      copy_to(b1 + reach_);  // a bond (i, i + o) of the block reaches at most `reach` past it
      for (std::size_t g = 0; g < groups_.size(); ++g)
        sweep_runs<Real>(w, g, law.with_ids(groups_[g].law.data()), cut2, inv_rmin, broke, b0, b1);
      assemble(w, b0, b1, next_touched, f);
    }
    return broke;
  }

  // Evaluate one group's bonds (i, i + o(i)), i in [b, e), where its runs are; zeros between them (the ring's
  // slots hold other particles' forces from before). One block at a time: a block's slots do not wrap.
  template <class Real, class Law>
  void sweep_runs(Work& w, std::size_t gi, const Law& law, double cut2, double inv_rmin, long& broke, long b, long e) {
    // the thread sweeps each offset's bonds in ascending i: the runs before b are behind its cursor
    const auto& runs = groups_[gi].runs;
    auto r = runs.begin() + static_cast<std::ptrdiff_t>(w.next_run[gi]);
    while (r != runs.end() && r->end <= b) ++r;
    for (long c0 = b; c0 < e;) {
      const long c1 = std::min(e, (c0 / particle_grain + 1) * particle_grain);
      long at = c0;
      for (; r != runs.end() && r->begin < c1; ++r) {
        const long rb = std::max(at, r->begin), re = std::min(c1, r->end);
        zero(w, gi, at, rb);
        sweep<Real>(w, gi, law, cut2, inv_rmin, broke, rb, re, r->offset);
        at = re;
        if (r->end > c1) break;  // the run goes on in the next block
      }
      zero(w, gi, at, c1);
      w.next_run[gi] = static_cast<std::size_t>(r - runs.begin());
      if (slot(c0) < particle_grain)  // this block wrote the ring's first block: repeat it past the end
        for (int c = 0; c < D; ++c) std::copy_n(w.F_of(gi, c) + slot(c0), c1 - c0, w.F_of(gi, c) + ring_ + slot(c0));
      c0 = c1;
    }
  }

  std::size_t slot(long i) const { return static_cast<std::size_t>(i) & (ring_ - 1); }

  void zero(Work& w, std::size_t gi, long b, long e) const {
    if (wraps_ && b < e)
      for (int c = 0; c < D; ++c) std::fill_n(w.F_of(gi, c) + slot(b), e - b, 0.0);
  }

  // Evaluate the bonds (i, i + o), i in [b, e), of one group into this thread's buffer.
  template <class Real, class Law>
  void sweep(Work& w, std::size_t gi, const Law law, double cut2, double inv_rmin, long& broke, long b, long e,
             int offset) {
    if (b >= e) return;
    const Group& g = groups_[gi];
    const std::size_t o = static_cast<std::size_t>(offset);
    const std::size_t ub = static_cast<std::size_t>(b), m = static_cast<std::size_t>(e - b);
    // positions of particle b + k at x[k] (the thread's copy starts at xlo <= b)
    const double* __restrict x0 = w.xs[0].data() + (ub - static_cast<std::size_t>(w.xlo));
    const double* __restrict x1 = w.xs[1].data() + (ub - static_cast<std::size_t>(w.xlo));
    const double* __restrict x2 = w.xs[D - 1].data() + (ub - static_cast<std::size_t>(w.xlo));
    const std::uint8_t* __restrict alive = g.alive.data() + ub;
    // F[i] lives at slot i mod R ([b, e) lies in one block: no wrap)
    const std::size_t shift = slot(b);
    double* __restrict F0 = w.F_of(gi, 0) + shift;
    double* __restrict F1 = w.F_of(gi, 1) + shift;
    double* __restrict F2 = w.F_of(gi, D - 1) + shift;
#ifdef PMFRAG_HAVE_AVX512_SWEEP
    if constexpr (std::is_same_v<Real, double> && is_fixed_law<Law>::value) {
      if (fixed_law_scales_ok<Law::p, Law::q>(law.G, law.H)) {
        broke += sweep_fixed_avx512<D, Law::p, Law::q>(x0, x1, x2, o, alive, F0, F1, F2, m, ub & 7, law.G,
                                                       law.H, cut2, inv_rmin);
        return;
      }
    }
    if constexpr (std::is_same_v<Real, double> && is_one_law<Law>::value) {
      if (const auto fixed = law.scales_ok ? fixed_sweep<D>(law.law.p, law.law.q) : nullptr) {
        broke += fixed(x0, x1, x2, o, alive, F0, F1, F2, m, ub & 7, law.law.G, law.law.H, cut2, inv_rmin);
        return;
      }
      if (law.law.q > law.law.p && law.law.p >= 1) {  // the factored form's q - p > 0
        broke += sweep_one_law_avx512<D, Law::bits>(x0, x1, x2, o, alive, F0, F1, F2, m, ub & 7, law.law.p,
                                                    law.law.q, law.law.G, law.law.H, cut2, inv_rmin);
        return;
      }
    }
    if constexpr (std::is_same_v<Real, double> && std::is_same_v<Law, ManyLaws>) {
      if (law.table->usable) {
        broke += sweep_laws_avx512<D>(x0, x1, x2, o, alive, law.id + ub, F0, F1, F2, m, ub & 7, *law.table, cut2,
                                      inv_rmin);
        return;
      }
    }
#endif
#pragma omp simd reduction(+ : broke)
    for (std::size_t k = 0; k < m; ++k) {
      const double d0 = x0[k] - x0[k + o], d1 = x1[k] - x1[k + o];
      const double d2 = D == 3 ? x2[k] - x2[k + o] : 0.0;
      const double fr = bond_force_over_r<Real>(law, ub + k, d0 * d0 + d1 * d1 + d2 * d2, alive[k] != 0, cut2,
                                                inv_rmin, broke);
      F0[k] = fr * d0;
      F1[k] = fr * d1;
      if constexpr (D == 3) F2[k] = fr * d2;
    }
  }

  template <class Real, class Law>
  void sparse_pass(Work& w, const double* x, const Law law, double cut2, double inv_rmin, long& broke) {
    const long m = static_cast<long>(w.sparse.size());
    const int* __restrict pi = w.sparse.i.data();
    const int* __restrict pj = w.sparse.j.data();
    const std::uint8_t* __restrict alive = w.sparse_alive.data();
    const double* __restrict xa = x;  // N x D: the bonds' ends are anywhere in the thread's reach
    double* __restrict F0 = w.sparse.force[0].data();
    double* __restrict F1 = w.sparse.force[1].data();
    double* __restrict F2 = w.sparse.force[D - 1].data();
#pragma omp simd reduction(+ : broke)
    for (long p = 0; p < m; ++p) {
      const std::size_t u = static_cast<std::size_t>(p);
      const std::size_t a = static_cast<std::size_t>(pi[u]) * D, b = static_cast<std::size_t>(pj[u]) * D;
      const double d0 = xa[a] - xa[b], d1 = xa[a + 1] - xa[b + 1];
      const double d2 = D == 3 ? xa[a + D - 1] - xa[b + D - 1] : 0.0;
      const double fr = bond_force_over_r<Real>(law, u, d0 * d0 + d1 * d1 + d2 * d2, alive[u] != 0, cut2, inv_rmin, broke);
      F0[u] = fr * d0;
      F1[u] = fr * d1;
      if constexpr (D == 3) F2[u] = fr * d2;
    }
  }

  // f_i += sum over offsets of F[i] - F[i - o], then the off-stencil bonds of i, each particle in a fixed
  // order (bitwise the same for any partition into threads; adding a zero where a particle has no
  // off-stencil bond changes nothing but the sign of a zero).
  void assemble(const Work& w, long b0, long b1, std::size_t& next_touched, double* f) const {
    constexpr long block = particle_grain;
    const std::size_t len = static_cast<std::size_t>(b1 - b0);
    const std::size_t at = slot(b0);
    alignas(64) double extra[D][block];  // off-stencil sums of this block's particles
    bool any_extra = false;
    const std::vector<int>& touched = w.sparse.touched;
    for (; next_touched < touched.size() && touched[next_touched] < b1; ++next_touched) {
      const std::size_t p = static_cast<std::size_t>(touched[next_touched]);
      if (static_cast<long>(p) < b0) continue;  // a partner outside this thread's particles
      if (!any_extra)
        for (int c = 0; c < D; ++c) std::fill_n(extra[c], len, 0.0);
      any_extra = true;
      double sum[D];
      w.sparse.sum_of(p, sum);
      for (int c = 0; c < D; ++c) extra[c][p - static_cast<std::size_t>(b0)] = sum[c];
    }
    double* __restrict fb = f + static_cast<std::size_t>(b0) * D;
#ifdef PMFRAG_HAVE_AVX512_SWEEP
    const std::size_t lane0 = static_cast<std::size_t>(b0) / 8;  // b0 is a multiple of 8
    static_assert(block == 256, "the AVX-512 assemblies take blocks of at most 256");
    const double(*ex)[256] = any_extra ? extra : nullptr;
    if (merged_) {  // a branch per group and eight particles: the plate ran 0.84x when it went this way too
      if (assign_)
        assemble_block_grouped_avx512<D, true>(w.F.data(), at, ring_ - 1, w.stride, terms_.data(), group_terms_.data(),
                                               group_codes_.data(), group_terms_.size(), lane0, ex, fb, len);
      else
        assemble_block_grouped_avx512<D, false>(w.F.data(), at, ring_ - 1, w.stride, terms_.data(), group_terms_.data(),
                                                group_codes_.data(), group_terms_.size(), lane0, ex, fb, len);
    } else if (four_ && assign_) {
      assemble_block_four_avx512<true>(w.F.data(), at, ring_ - 1, w.stride, offsets_.data(), ex, fb, len);
    } else if (four_) {
      assemble_block_four_avx512<false>(w.F.data(), at, ring_ - 1, w.stride, offsets_.data(), ex, fb, len);
    } else if (assign_) {
      assemble_block_avx512<D, true>(w.F.data(), at, ring_ - 1, w.stride, offsets_.data(), groups_.size(), ex, fb, len);
    } else {
      assemble_block_avx512<D, false>(w.F.data(), at, ring_ - 1, w.stride, offsets_.data(), groups_.size(), ex, fb, len);
    }
#else
    alignas(64) double acc[D][block];
    for (int c = 0; c < D; ++c)
      for (std::size_t k = 0; k < len; ++k) acc[c][k] = 0.0;
    const StencilTerm* term = terms_.data();
    for (std::size_t g = 0; g < group_terms_.size(); term += group_terms_[g], ++g)
      for (int c = 0; c < D; ++c)
        for (std::size_t k = 0; k < len; ++k) {
          // the same order as the vector assembly: F[i], less F[i - o] at each offset that reaches i
          double s = w.F_of(g, c)[at + k];
          for (std::size_t t = 0; t < group_terms_[g]; ++t) {
            const std::size_t i = static_cast<std::size_t>(b0) + k;
            if (term[t].lanes == nullptr || ((term[t].lanes[i / 8] >> (i % 8)) & 1u))
              s -= w.F_of(g, c)[slot(static_cast<long>(i) - static_cast<long>(term[t].offset))];
          }
          acc[c][k] += s;
        }
    if (any_extra)
      for (int c = 0; c < D; ++c)
        for (std::size_t k = 0; k < len; ++k) acc[c][k] += extra[c][k];
    for (std::size_t k = 0; k < len; ++k)
      for (int c = 0; c < D; ++c) {
        double& out = fb[k * D + static_cast<std::size_t>(c)];
        out = (assign_ ? 0.0 : out) + acc[c][k];
      }
#endif
  }

  std::size_t n_ = 0;
  bool single_ = false;
  bool assign_ = false;  ///< add_forces sets f rather than adding to it
  long reach_ = 0;  ///< the largest offset, rounded up to 8
  std::size_t ring_ = particle_grain;  ///< R: slots per offset and component of a thread's F
  bool wraps_ = true;                  ///< some slot of a ring holds more than one particle
  std::vector<Group> groups_;
  std::vector<StencilTerm> terms_;          ///< every group's offsets in turn, for the assembly
  std::vector<std::size_t> group_terms_;    ///< how many of terms_ each group has
  std::vector<const std::uint16_t*> group_codes_;  ///< Group::codes, or nullptr
  std::vector<std::size_t> offsets_;  ///< each group's first offset (its only one unless merged_)
  bool merged_ = false;               ///< some group has several offsets
  bool four_ = false;                 ///< 2-D, four groups of one offset each (the plate): assemble_block_four_avx512
  std::vector<int> sparse_i_, sparse_j_, sparse_law_;  ///< off-stencil bonds
  std::vector<std::uint8_t> sparse_alive_;
  std::vector<std::pair<int, int>> group_at_offset_;  ///< (offset, its group), by offset
  std::vector<std::pair<std::vector<long>, std::vector<Work>>> plans_;  ///< by partition: per thread
  std::size_t current_ = 0;  ///< the prepared plan
};

}  // namespace pmfrag::detail

// The pair effect: the (p,q) law of Eq. (22) between particles, under one of two readings (physics.md):
//  bonded - the original nearest-neighbour bonds interact until they first exceed D, then are gone for good;
//           particles not bonded repel by the law's repulsive branch (r < r0) so fragments collide.
//  cutoff - Greenspan's reading: every pair closer than D interacts; pairs form and break freely.
// Pair forces are computed once per pair into an array and gathered per particle in a fixed order, so the
// result is bitwise the same for any number of threads.
#include "pmfrag/effects.hpp"
#include "pmfrag/neighbors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pmfrag {

namespace {

/// A list of pairs (i < j) with per-pair law and force, and per-particle incidence for the gather.
template <int D>
struct PairTable {
  using V = Eigen::Matrix<double, D, 1>;
  std::vector<int> i, j, law;
  std::vector<double> force[D];  ///< components of the force on i (j gets the opposite), one array each
  std::vector<int> offset, entry;  ///< CSR: entry = pair << 1 | (particle is j)

  std::size_t size() const { return i.size(); }
  void clear() { i.clear(), j.clear(), law.clear(); }
  void add(int a, int b, int l) { i.push_back(a), j.push_back(b), law.push_back(l); }
  void index(std::size_t n) {
    for (auto& c : force) c.assign(size(), 0.0);
    offset.assign(n + 1, 0);
    for (std::size_t p = 0; p < size(); ++p) ++offset[static_cast<std::size_t>(i[p]) + 1], ++offset[static_cast<std::size_t>(j[p]) + 1];
    for (std::size_t k = 0; k < n; ++k) offset[k + 1] += offset[k];
    entry.resize(static_cast<std::size_t>(offset[n]));
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (std::size_t p = 0; p < size(); ++p) {  // ascending p: a fixed order per particle
      entry[static_cast<std::size_t>(fill[static_cast<std::size_t>(i[p])]++)] = static_cast<int>(p << 1);
      entry[static_cast<std::size_t>(fill[static_cast<std::size_t>(j[p])]++)] = static_cast<int>(p << 1 | 1);
    }
  }
  void gather(std::vector<V>& f) const {
    const long n = static_cast<long>(f.size());
#pragma omp parallel for schedule(static)
    for (long k = 0; k < n; ++k) {
      V s = V::Zero();
      for (int e = offset[static_cast<std::size_t>(k)]; e < offset[static_cast<std::size_t>(k) + 1]; ++e) {
        const int en = entry[static_cast<std::size_t>(e)];
        const double sign = 1.0 - 2.0 * (en & 1);  // j gets -F
        const std::size_t p = static_cast<std::size_t>(en >> 1);
        for (int c = 0; c < D; ++c) s[c] += sign * force[c][p];
      }
      f[static_cast<std::size_t>(k)] += s;
    }
  }
};

enum class Mode { bond, cutoff, contact };

// Potential with the r_min clamp continued linearly (phi' = -F, F constant inside r_min).
inline double law_potential(const PairLaw& law, double r, double r_min) {
  if (r >= r_min) return law.potential(r);
  return law.potential(r_min) + law.force(r_min) * (r_min - r);
}

template <int D>
class PairEffect final : public Effect<D> {
 public:
  using V = Eigen::Matrix<double, D, 1>;

  PairEffect(const System& sys, const PairSpec& spec) : spec_(spec) {
    laws_ = sys.laws;
    phase_ = sys.phase;
    nphase_ = sys.phase_names.size();
    pair_law_ = sys.phase_pair_law;
    cutoff_ = sys.cutoff;
    inv_rmin_ = sys.r_min > 0.0 ? 1.0 / sys.r_min : std::numeric_limits<double>::infinity();
    r_min_ = sys.r_min;
    for (const auto& b : sys.bonds) bonds_.add(b[0], b[1], law_of(b[0], b[1]));
    bonds_.index(sys.size());
    alive_.assign(bonds_.size(), 1);
    phi_break_.assign(bonds_.size(), 0.0);
    build_slots(sys.size());
    contact_reach_.resize(laws_.size());
    for (std::size_t l = 0; l < laws_.size(); ++l) contact_reach_[l] = laws_[l].equilibrium_spacing();
    max_reach_ = spec_.model == PairModel::cutoff ? cutoff_ : *std::max_element(contact_reach_.begin(), contact_reach_.end());
    skin_ = 0.3 * sys.r0;
    uses_list_ = spec_.model == PairModel::cutoff || spec_.contact;
  }

  std::string name() const override { return spec_.model == PairModel::bonded ? "pair (bonded)" : "pair (cutoff)"; }
  unsigned stages() const override {
    return stage::setup | stage::force | stage::observe | (uses_list_ ? stage::after_move : 0u);
  }

  void setup(State<D>& s) override {
    if (uses_list_) rebuild(s);
  }
  void canonicalize(const State<D>& s) override {
    if (uses_list_) rebuild(s);
  }

  void add_forces(State<D>& s) override {
    if (spec_.model == PairModel::bonded) {
      const long broke = bond_forces(s);
      if (broke > 0) {
        retire_broken(s);
        if (first_break_step_ < 0) first_break_step_ = s.step;
      }
    }
    if (uses_list_ && list_.size() > 0) {
      if (spec_.model == PairModel::cutoff)
        compute<Mode::cutoff>(s, list_);
      else
        compute<Mode::contact>(s, list_);
      list_.gather(s.f);
    }
  }

  void save(std::vector<double>& out) const override {
    out.push_back(static_cast<double>(first_break_step_));
    for (std::size_t b = 0; b < alive_.size(); ++b) out.push_back(alive_[b]), out.push_back(phi_break_[b]);
  }
  void load(const double*& in) override {
    first_break_step_ = static_cast<long>(*in++);
    for (std::size_t b = 0; b < alive_.size(); ++b) alive_[b] = static_cast<std::uint8_t>(*in++), phi_break_[b] = *in++;
    for (std::size_t b = 0; b < alive_.size(); ++b)
      slot_alive_[static_cast<std::size_t>(bond_slot_[2 * b])] = slot_alive_[static_cast<std::size_t>(bond_slot_[2 * b + 1])] = alive_[b];
  }

  void after_move(State<D>& s, double max_step) override {
    // Verlet criterion with a bound instead of a pass over the particles: no particle has moved more than
    // the sum of the largest single-step moves since the build. Rebuild before two could have closed the skin.
    moved_bound_ += max_step;
    if (!(2.0 * moved_bound_ < skin_)) rebuild(s);
  }

  void observe(const State<D>& s, Observables& o) const override {
    double pe = 0.0;
    long beyond = 0;
    for (std::size_t b = 0; b < bonds_.size(); ++b) {
      const double r = (s.x[static_cast<std::size_t>(bonds_.i[b])] - s.x[static_cast<std::size_t>(bonds_.j[b])]).norm();
      if (spec_.model == PairModel::bonded) {
        if (alive_[b])
          pe += law_potential(laws_[static_cast<std::size_t>(bonds_.law[b])], r, r_min_);
        else
          ++beyond, o.bond_break_energy += phi_break_[b];
      } else if (r > cutoff_) {
        ++beyond;
      }
    }
    for (std::size_t p = 0; p < list_.size(); ++p) {
      const double r = (s.x[static_cast<std::size_t>(list_.i[p])] - s.x[static_cast<std::size_t>(list_.j[p])]).norm();
      const PairLaw& law = laws_[static_cast<std::size_t>(list_.law[p])];
      if (spec_.model == PairModel::cutoff) {
        if (r <= cutoff_) pe += law_potential(law, r, r_min_);
      } else {
        const double reach = contact_reach_[static_cast<std::size_t>(list_.law[p])];
        if (r < reach) pe += law_potential(law, r, r_min_) - law.potential(reach);
      }
    }
    o.potential += pe;
    o.pairs_beyond_cutoff += beyond;
  }

  const std::vector<std::uint8_t>& alive() const { return alive_; }
  long first_break_step() const { return first_break_step_; }

 private:
  int law_of(int a, int b) const {
    return pair_law_[static_cast<std::size_t>(phase_[static_cast<std::size_t>(a)]) * nphase_ +
                     static_cast<std::size_t>(phase_[static_cast<std::size_t>(b)])];
  }

  // Returns the number of bonds broken in this evaluation (bond mode). The kernel is branch-free (a select,
  // not a branch, decides whether a pair acts), so it vectorizes; the rare step where bonds break is
  // finished by a serial pass that retires them.
  template <Mode mode>
  long compute(State<D>& s, PairTable<D>& t) {
    if (nphase_ == 1) {
      const PairLaw& l = laws_.front();
      const double reach2 = contact_reach_.front() * contact_reach_.front();
      // The paper's three laws get compile-time exponents (straight multiplications); others a runtime power.
      if (l.p == 7 && l.q == 14) return kernel<mode>(s, t, FixedLaw<7, 14>{l.G, l.H, reach2});
      if (l.p == 5 && l.q == 10) return kernel<mode>(s, t, FixedLaw<5, 10>{l.G, l.H, reach2});
      if (l.p == 3 && l.q == 5) return kernel<mode>(s, t, FixedLaw<3, 5>{l.G, l.H, reach2});
      return kernel<mode>(s, t, OneLaw{l, reach2});
    }
    return kernel<mode>(s, t, ManyLaws{laws_.data(), t.law.data(), contact_reach_.data()});
  }

  template <int N>
  static double pw(double x) {
    if constexpr (N == 0) return 1.0;
    else if constexpr (N == 1) return x;
    else if constexpr (N % 2 == 0) { const double h = pw<N / 2>(x); return h * h; }
    else return x * pw<N - 1>(x);
  }
  template <int P, int Q>
  struct FixedLaw {
    double G, H, reach2;
    double magnitude(std::size_t, double ie) const { return -G * pw<P>(ie) + H * pw<Q>(ie); }
    double contact2(std::size_t) const { return reach2; }
  };
  struct OneLaw {
    PairLaw law;
    double reach2;
    double magnitude(std::size_t, double ie) const { return -law.G * ipow(ie, law.p) + law.H * ipow(ie, law.q); }
    double contact2(std::size_t) const { return reach2; }
  };
  struct ManyLaws {
    const PairLaw* laws;
    const int* id;
    const double* reach;
    double magnitude(std::size_t u, double ie) const {
      const PairLaw& l = laws[id[u]];
      return -l.G * ipow(ie, l.p) + l.H * ipow(ie, l.q);
    }
    double contact2(std::size_t u) const { return reach[id[u]] * reach[id[u]]; }
  };

  template <Mode mode, class Law>
  long kernel(State<D>& s, PairTable<D>& t, const Law law) {
    const double cut2 = cutoff_ * cutoff_;
    const long m = static_cast<long>(t.size());
    const double inv_rmin = inv_rmin_;
    const std::uint8_t* __restrict alive = alive_.data();
    const int* __restrict pi = t.i.data();
    const int* __restrict pj = t.j.data();
    const double* __restrict x = s.x.front().data();
    double* __restrict f0 = t.force[0].data();
    double* __restrict f1 = t.force[1].data();
    double* __restrict f2 = t.force[D - 1].data();
    long broke = 0;
#pragma omp parallel for simd schedule(static) reduction(+ : broke)
    for (long p = 0; p < m; ++p) {
      const std::size_t u = static_cast<std::size_t>(p);
      const std::size_t a = static_cast<std::size_t>(pi[u]) * D, b = static_cast<std::size_t>(pj[u]) * D;
      // Written out per dimension (no inner loops) so the compiler vectorizes across pairs.
      const double d0 = x[a] - x[b], d1 = x[a + 1] - x[b + 1];
      const double d2 = D == 3 ? x[a + D - 1] - x[b + D - 1] : 0.0;
      const double r2 = d0 * d0 + d1 * d1 + d2 * d2;
      bool act;
      if constexpr (mode == Mode::bond) {
        const bool live = alive[u] != 0, within = r2 <= cut2;
        act = live & within;  // a bond is broken for good the first time it exceeds D
        broke += live & !within;
      } else if constexpr (mode == Mode::cutoff) {
        act = r2 <= cut2;
      } else {
        act = r2 < law.contact2(u);  // contact: the repulsive branch, r < r0
      }
      const double inv = 1.0 / std::sqrt(r2);
      const double ie = std::min(inv, inv_rmin);  // force held constant inside r_min (Sec. 4.2)
      const double mag = law.magnitude(u, ie) * inv;  // > 0 repulsive
      const double fr = act ? mag : 0.0;
      f0[u] = fr * d0;
      f1[u] = fr * d1;
      if constexpr (D == 3) f2[u] = fr * d2;
    }
    return broke;
  }

  // Bonds as slots: particle i's bonds sit in slots k = s * n + i (s < nslot), slot-major so a vector of
  // consecutive particles reads consecutive slots. Each bond is evaluated from both ends: twice the force
  // evaluations, but no per-bond force array and no scatter, and each particle's sum has a fixed order.
  // Both ends see the same r^2 (the squares of d and -d are equal), so they agree on when it breaks.
  void build_slots(std::size_t n) {
    std::vector<int> degree(n, 0);
    for (std::size_t b = 0; b < bonds_.size(); ++b) ++degree[static_cast<std::size_t>(bonds_.i[b])], ++degree[static_cast<std::size_t>(bonds_.j[b])];
    nslot_ = degree.empty() ? 0 : *std::max_element(degree.begin(), degree.end());
    // Pad to the lattice's coordination (6 in 2-D, 12 close-packed) so the kernel's slot loop has a
    // compile-time length and unrolls; padding slots point at the particle itself and are never alive.
    if (nslot_ <= 6)
      nslot_ = 6;
    else if (nslot_ <= 12)
      nslot_ = 12;
    n_ = n;
    slot_nbr_.resize(static_cast<std::size_t>(nslot_) * n);
    for (std::size_t k = 0; k < slot_nbr_.size(); ++k) slot_nbr_[k] = static_cast<int>(k % n);  // padding: self
    slot_alive_.assign(slot_nbr_.size(), 0);
    for (auto& a : acc_) a.assign(n, 0.0);
    slot_law_.assign(slot_nbr_.size(), 0);
    bond_slot_.resize(2 * bonds_.size());
    std::fill(degree.begin(), degree.end(), 0);
    for (std::size_t b = 0; b < bonds_.size(); ++b) {  // bonds are sorted, so each particle's slots are too
      const int ends[2] = {bonds_.i[b], bonds_.j[b]};
      for (int e = 0; e < 2; ++e) {
        const std::size_t a = static_cast<std::size_t>(ends[e]);
        const std::size_t k = static_cast<std::size_t>(degree[a]++) * n + a;
        slot_nbr_[k] = ends[1 - e];
        slot_alive_[k] = 1;
        slot_law_[k] = bonds_.law[b];
        bond_slot_[2 * b + static_cast<std::size_t>(e)] = static_cast<long>(k);
      }
    }
  }

  long bond_forces(State<D>& s) {
    if (nslot_ == 6) return bond_forces<6>(s);
    if (nslot_ == 12) return bond_forces<12>(s);
    return bond_forces<0>(s);
  }
  template <int NSLOT>
  long bond_forces(State<D>& s) {
    if (nphase_ == 1) {
      const PairLaw& l = laws_.front();
      if (l.p == 7 && l.q == 14) return slot_kernel<NSLOT>(s, FixedLaw<7, 14>{l.G, l.H, 0.0});
      if (l.p == 5 && l.q == 10) return slot_kernel<NSLOT>(s, FixedLaw<5, 10>{l.G, l.H, 0.0});
      if (l.p == 3 && l.q == 5) return slot_kernel<NSLOT>(s, FixedLaw<3, 5>{l.G, l.H, 0.0});
      return slot_kernel<NSLOT>(s, OneLaw{l, 0.0});
    }
    return slot_kernel<NSLOT>(s, ManyLaws{laws_.data(), slot_law_.data(), contact_reach_.data()});
  }

  // One vectorizable pass per slot over all particles, accumulating into per-particle sums (slot order is
  // fixed, so each particle's sum is the same for any thread count). Every pass uses the same static
  // partition, so a thread only ever touches its own particles and needs no barrier between passes.
  template <int NSLOT, class Law>
  long slot_kernel(State<D>& s, const Law law) {
    const long n = static_cast<long>(n_);
    const int nslot = NSLOT > 0 ? NSLOT : nslot_;
    const double cut2 = cutoff_ * cutoff_;
    const double inv_rmin = inv_rmin_;
    const double* __restrict x = s.x.front().data();
    double* __restrict f = s.f.front().data();
    double* __restrict ax = acc_[0].data();
    double* __restrict ay = acc_[1].data();
    double* __restrict az = acc_[D - 1].data();
    long broke = 0;
#pragma omp parallel reduction(+ : broke)
    {
      for (int sl = 0; sl < nslot; ++sl) {
        const int* __restrict nbr = slot_nbr_.data() + static_cast<std::size_t>(sl) * n_;
        const std::uint8_t* __restrict alive = slot_alive_.data() + static_cast<std::size_t>(sl) * n_;
        const std::size_t base = static_cast<std::size_t>(sl) * n_;
        const bool first = sl == 0;
#pragma omp for simd schedule(static) nowait
        for (long p = 0; p < n; ++p) {
          const std::size_t i = static_cast<std::size_t>(p);
          const std::size_t j = static_cast<std::size_t>(nbr[i]);
          const double d0 = x[i * D] - x[j * D], d1 = x[i * D + 1] - x[j * D + 1];
          const double d2 = D == 3 ? x[i * D + D - 1] - x[j * D + D - 1] : 0.0;
          const double r2 = d0 * d0 + d1 * d1 + d2 * d2;
          const bool live = alive[i] != 0, within = r2 <= cut2;
          broke += live & !within;  // a bond is broken for good the first time it exceeds D
          const double inv = 1.0 / std::sqrt(live ? r2 : cut2);  // padding slots (r = 0) stay finite
          const double ie = std::min(inv, inv_rmin);  // force held constant inside r_min (Sec. 4.2)
          const double mag = law.magnitude(base + i, ie) * inv;  // > 0 repulsive
          const double fr = (live & within) ? mag : 0.0;
          ax[i] = (first ? 0.0 : ax[i]) + fr * d0;
          ay[i] = (first ? 0.0 : ay[i]) + fr * d1;
          if constexpr (D == 3) az[i] = (first ? 0.0 : az[i]) + fr * d2;
        }
      }
#pragma omp for simd schedule(static)
      for (long p = 0; p < n; ++p) {
        const std::size_t i = static_cast<std::size_t>(p);
        f[i * D] += ax[i];
        f[i * D + 1] += ay[i];
        if constexpr (D == 3) f[i * D + D - 1] += az[i];
      }
    }
    return broke;
  }

  void retire_broken(const State<D>& s) {
    const double cut2 = cutoff_ * cutoff_;
    const double* x = s.x.front().data();
    for (std::size_t b = 0; b < bonds_.size(); ++b) {
      if (!alive_[b]) continue;
      const std::size_t i = static_cast<std::size_t>(bonds_.i[b]), j = static_cast<std::size_t>(bonds_.j[b]);
      const double d0 = x[i * D] - x[j * D], d1 = x[i * D + 1] - x[j * D + 1];
      const double d2 = D == 3 ? x[i * D + D - 1] - x[j * D + D - 1] : 0.0;
      const double r2 = d0 * d0 + d1 * d1 + d2 * d2;  // exactly as the kernel computes it
      if (!(r2 <= cut2)) {
        alive_[b] = 0;
        slot_alive_[static_cast<std::size_t>(bond_slot_[2 * b])] = slot_alive_[static_cast<std::size_t>(bond_slot_[2 * b + 1])] = 0;
        phi_break_[b] = law_potential(laws_[static_cast<std::size_t>(bonds_.law[b])], std::sqrt(r2), r_min_);
      }
    }
  }

  // Verlet list of pairs within reach + skin. Bonded: excludes intact bonds (they act through the bond list).
  void rebuild(const State<D>& s) {
    list_.clear();
    const std::size_t n = s.size();
    std::vector<int> bond_off, bond_other;
    if (spec_.model == PairModel::bonded) {
      // intact-bond lookup per particle
      bond_off.assign(n + 1, 0);
      for (std::size_t b = 0; b < bonds_.size(); ++b)
        if (alive_[b]) ++bond_off[static_cast<std::size_t>(bonds_.i[b]) + 1];
      for (std::size_t k = 0; k < n; ++k) bond_off[k + 1] += bond_off[k];
      bond_other.resize(static_cast<std::size_t>(bond_off[n]));
      std::vector<int> fill(bond_off.begin(), bond_off.end() - 1);
      for (std::size_t b = 0; b < bonds_.size(); ++b)
        if (alive_[b]) bond_other[static_cast<std::size_t>(fill[static_cast<std::size_t>(bonds_.i[b])]++)] = bonds_.j[b];
    }
    cells_.for_each_pair(s.x, max_reach_ + skin_, [&](std::uint32_t a, std::uint32_t b, double) {
      if (spec_.model == PairModel::bonded) {
        for (int e = bond_off[a]; e < bond_off[a + 1]; ++e)
          if (bond_other[static_cast<std::size_t>(e)] == static_cast<int>(b)) return;
      }
      list_.add(static_cast<int>(a), static_cast<int>(b), law_of(static_cast<int>(a), static_cast<int>(b)));
    });
    list_.index(n);
    moved_bound_ = 0.0;
    ++rebuilds_;
  }

  PairSpec spec_;
  std::vector<PairLaw> laws_;
  std::vector<int> phase_, pair_law_;
  std::size_t nphase_ = 1;
  double cutoff_ = 0.0, inv_rmin_ = 0.0, r_min_ = 0.0, skin_ = 0.0, max_reach_ = 0.0;
  std::vector<double> contact_reach_;
  bool uses_list_ = false;
  PairTable<D> bonds_, list_;
  std::vector<std::uint8_t> alive_;
  std::vector<double> phi_break_;
  std::size_t n_ = 0;
  int nslot_ = 0;
  std::vector<int> slot_nbr_, slot_law_;
  std::vector<std::uint8_t> slot_alive_;
  std::vector<long> bond_slot_;
  std::vector<double> acc_[D];  ///< per-particle bond force sums, one array per component
  long first_break_step_ = -1;
  double moved_bound_ = 0.0;  ///< cm: bound on any particle's displacement since the last list build
  CellList<D> cells_;
  long rebuilds_ = 0;
};

}  // namespace

template <int D>
std::unique_ptr<Effect<D>> make_pair_effect(const System& sys, const PairSpec& spec) {
  return std::make_unique<PairEffect<D>>(sys, spec);
}

template <int D>
BondView<D> bond_view(const Effect<D>& e) {
  BondView<D> v;
  if (auto* p = dynamic_cast<const PairEffect<D>*>(&e)) {
    v.alive = &p->alive();
    v.first_break_step = p->first_break_step();
  }
  return v;
}

template std::unique_ptr<Effect<2>> make_pair_effect<2>(const System&, const PairSpec&);
template std::unique_ptr<Effect<3>> make_pair_effect<3>(const System&, const PairSpec&);
template BondView<2> bond_view<2>(const Effect<2>&);
template BondView<3> bond_view<3>(const Effect<3>&);

}  // namespace pmfrag

// The pair effect: the (p,q) law of Eq. (22) between particles, under one of two readings (physics.md):
//  bonded - the original nearest-neighbour bonds interact until they first exceed D, then are gone for good;
//           particles not bonded repel by the law's repulsive branch (r < r0) so fragments collide.
//  cutoff - Greenspan's reading: every pair closer than D interacts; pairs form and break freely.
// Bonds go through stencil sweeps (bond_stencil.hpp); neighbour-list pairs (contacts, cutoff model) through
// a pair table and a gather. Both sum each particle's forces in a fixed order: bitwise the same results for
// any number of threads.
#include "kernels/bond_stencil.hpp"
#include "kernels/pair_kernels.hpp"
#include "pmfrag/step/effects.hpp"
#include "pmfrag/model/material.hpp"
#include "pmfrag/step/neighbors.hpp"

#include <Eigen/LU>  // 2x2 and 3x3 inverse and determinant (affine_residual)

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

namespace pmfrag {

namespace {

using detail::law_potential;
using detail::PairTable;

template <int D>
class PairEffect final : public Effect<D> {
 public:
  using V = Eigen::Matrix<double, D, 1>;

  PairEffect(const System& sys, const PairSpec& spec) : spec_(spec) {
    laws_ = sys.laws;
    law_table_ = detail::LawTable(laws_);
    phase_ = sys.phase;
    nphase_ = sys.phase_names.size();
    pair_law_ = sys.phase_pair_law;
    cutoff_ = sys.cutoff;
    inv_rmin_ = sys.r_min > 0.0 ? 1.0 / sys.r_min : std::numeric_limits<double>::infinity();
    r_min_ = sys.r_min;
    n_ = sys.size();
    for (const auto& b : sys.bonds) bi_.push_back(b[0]), bj_.push_back(b[1]), blaw_.push_back(law_of(b[0], b[1]));
    alive_.assign(bi_.size(), 1);
    phi_break_.assign(bi_.size(), 0.0);
    if (spec_.model == PairModel::bonded) {
      stencil_ = detail::BondStencil<D>(n_, bi_, bj_, blaw_, spec_.single_precision);
      stencil_.assign_forces(true);  // stage::assigns_forces: the bonds' sum is every particle's first term
    }
    contact_reach_.resize(laws_.size());
    for (std::size_t l = 0; l < laws_.size(); ++l) contact_reach_[l] = laws_[l].equilibrium_spacing();
    max_reach_ = spec_.model == PairModel::cutoff ? cutoff_ : *std::max_element(contact_reach_.begin(), contact_reach_.end());
    r0_ = sys.r0;
    law_mass_.assign(laws_.size(), std::numeric_limits<double>::infinity());
    for (std::size_t a = 0; a < nphase_; ++a)
      for (std::size_t b = 0; b < nphase_; ++b) {
        double& m = law_mass_[static_cast<std::size_t>(pair_law_[a * nphase_ + b])];
        m = std::min({m, sys.phase_mass[a], sys.phase_mass[b]});
      }
    uses_list_ = spec_.model == PairModel::cutoff || spec_.contact;
    window_ = 0.05 * r0_;
  }

  std::string name() const override { return spec_.model == PairModel::bonded ? "pair (bonded)" : "pair (cutoff)"; }
  unsigned stages() const override {
    return stage::setup | stage::force | stage::observe | stage::step_limit | (uses_list_ ? stage::after_move : 0u) |
           (spec_.model == PairModel::bonded ? stage::fused_force : 0u) | stage::assigns_forces | stage::resident;
  }

  void setup(State<D>& s) override {
    if (!uses_list_) return;
    if (spec_.model == PairModel::bonded) {
      // Bonded: the contact list's skin stays at 0.3 r0. Its reach is the bonds' own spacing, where there is
      // no gap to fit a skin into (measured from it: 0.01 r0, a rebuild every ~400 steps, 12 % of the quiet
      // plate); and wider, every intact piece's second neighbours (sqrt(3) r0) join the contact list
      // (adapted up to 0.8 r0: the whole (7,14) plate 3.2 -> 5.0 s).
      skin_ = skin_min_ = skin_max_ = 0.3 * r0_;
    } else {
      skin_ = skin_min_ = skin_in_gap(s);
      skin_max_ = 0.8 * r0_;
    }
    rebuild(s);
  }
  void canonicalize(const State<D>& s) override {
    if (uses_list_) rebuild(s);
    far_margin_ = -1.0;  // the next crossing test is a full pass, in a resumed run as in this one
  }

  // The bonds read positions and which bonds are intact, nothing the neighbour list keeps: they are summed
  // in the pass that moves the particles (Leapfrog::step). Bonds found too long are retired in add_forces,
  // after the guard has accepted the step.
  void add_fused_forces(State<D>& s) override {
    const double cut2 = cutoff_ * cutoff_;
    broke_ = detail::with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) {
      return stencil_.add_forces(*s.team, s.x.front().data(), s.f.front().data(), law, cut2, inv_rmin_);
    });
  }

  void add_forces(State<D>& s) override {
    const double cut2 = cutoff_ * cutoff_;
    settle_breaks(s, std::exchange(broke_, 0));
    if (spec_.model == PairModel::cutoff) record_crossings(s);
    // cutoff: these forces come first and set f (stage::assigns_forces), so with no pair f is zero
    if (spec_.model == PairModel::cutoff && list_.size() == 0) std::fill(s.f.begin(), s.f.end(), V::Zero());
    if (uses_list_ && list_.size() > 0) {
      detail::with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) {
        if (spec_.model == PairModel::cutoff)  // the Verlet list of a lattice is a stencil too
          return list_stencil_.add_forces(*s.team, s.x.front().data(), s.f.front().data(), law, cut2, inv_rmin_);
        contact_kernel(s, law.with_ids(list_.law.data()));
        return 0L;
      });
    }
  }

  // Resident steps (effects.hpp), each thread on its particles. Bonded: the bonds and contacts. A thread
  // evaluates every contact its particles are in (a pair across two threads' shares twice, with the same
  // arithmetic, so the same bits) into its own copy of the pair forces, and sums its particles' from it.
  // Cutoff: the Verlet list's stencil, as add_forces evaluates it; a due list ends the block, and the plain
  // step that follows decides whether to rebuild (after_move).
  bool resident_begin(State<D>&, const std::vector<long>& bounds) override {
    const std::size_t threads = bounds.size() - 1;
    moved_of_.assign(threads * 8, moved_bound_);  // a cache line per thread: [0] moved_bound_, [1] drift_,
    for (std::size_t t = 0; t < threads; ++t) moved_of_[t * 8 + 2] = since_break_;  // [2] since_break_
    if (spec_.model == PairModel::cutoff) {
      if (list_.size() == 0 || far_margin_ < 0.0) return false;  // (the plain step zeroes f / makes a full pass)
      list_stencil_.prepare(bounds);
      for (std::size_t t = 0; t < threads; ++t) moved_of_[t * 8 + 1] = drift_;
      near_of_.resize(threads);
      for (auto& v : near_of_) v.clear();
      for (const int b : near_) {  // each near bond is tested by the thread owning its first particle
        const long i = bi_[static_cast<std::size_t>(b)];
        const std::size_t t = static_cast<std::size_t>(std::upper_bound(bounds.begin(), bounds.end(), i) - bounds.begin()) - 1;
        near_of_[std::min(t, threads - 1)].push_back(b);
      }
      return true;
    }
    stencil_.prepare(bounds);
    const std::vector<int>& touched = list_.touched;
    touched_from_.clear();
    for (long b : bounds)
      touched_from_.push_back(std::lower_bound(touched.begin(), touched.end(), b) - touched.begin());
    contacts_of_.resize(threads);
    for (std::size_t t = 0; t < threads; ++t) {
      ThreadContacts& c = contacts_of_[t];
      c.pairs.clear();
      const auto mine = [&](int p) { return p >= bounds[t] && p < bounds[t + 1]; };
      for (std::size_t p = 0; p < list_.size(); ++p)
        if (mine(list_.i[p]) || mine(list_.j[p])) c.pairs.push_back(static_cast<int>(p));
      for (auto& F : c.force) F.resize(list_.size());
    }
    return true;
  }
  bool resident_due(const State<D>&, double max_step, int tid) const override {
    const double* mine = &moved_of_[static_cast<std::size_t>(tid) * 8];
    return (uses_list_ && !list_holds(mine[0] + max_step, mine[2] + max_step)) ||
           (spec_.model == PairModel::cutoff && crossing_pass_due(mine[1] + max_step));
  }
  void resident_moved(double max_step, int tid) override {
    double* mine = &moved_of_[static_cast<std::size_t>(tid) * 8];
    if (uses_list_) mine[0] += max_step, mine[2] += max_step;
    if (spec_.model == PairModel::cutoff) mine[1] += max_step;
  }
  long resident_forces(State<D>& s, const double* x, int tid) override {
    const double cut2 = cutoff_ * cutoff_;
    return detail::with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) {
      if (spec_.model == PairModel::cutoff) {  // the events: near bonds that crossed D (settled by record_crossings)
        list_stencil_.add_forces_of(tid, x, s.f.front().data(), law, cut2, inv_rmin_);
        long crossed = 0;
        for (const int b : near_of_[static_cast<std::size_t>(tid)])
          crossed += (bond_r2(x, static_cast<std::size_t>(b)) <= cut2) != static_cast<bool>(alive_[static_cast<std::size_t>(b)]);
        return crossed;
      }
      const long mine = stencil_.add_forces_of(tid, x, s.f.front().data(), law, cut2, inv_rmin_);
      if (mine > 0) broke_of_team_.fetch_add(mine, std::memory_order_relaxed);
      ThreadContacts& c = contacts_of_[static_cast<std::size_t>(tid)];
      if (uses_list_ && !c.pairs.empty()) {
        const auto contact_law = law.with_ids(list_.law.data());
        typename detail::PairTable<D>::Forces F;
        for (int k = 0; k < D; ++k) F[static_cast<std::size_t>(k)] = c.force[k].data();
        for (const int p : c.pairs) {
          double out[D];
          contact_pair_force(x, contact_law, static_cast<std::size_t>(p), out);
          for (int k = 0; k < D; ++k) c.force[k][static_cast<std::size_t>(p)] = out[k];
        }
        list_.gather_touched(s.f.front().data(), touched_from_[static_cast<std::size_t>(tid)],
                             touched_from_[static_cast<std::size_t>(tid) + 1], F);
      }
      return mine;
    });
  }
  void resident_end(State<D>&) override {
    if (uses_list_) moved_bound_ = moved_of_[0], since_break_ = moved_of_[2];
    if (spec_.model == PairModel::cutoff) drift_ = moved_of_[1];
  }
  void resident_settle(State<D>& s) override {
    settle_breaks(s, broke_of_team_.exchange(0));
    if (spec_.model == PairModel::cutoff) record_crossings(s);
  }

  void save(std::vector<double>& out) const override {
    out.push_back(static_cast<double>(first_break_step_));
    out.push_back(first_break_time_);
    for (std::size_t b = 0; b < alive_.size(); ++b) out.push_back(alive_[b]), out.push_back(phi_break_[b]);
    out.push_back(skin_);  // the adapted skin decides when the list is next rebuilt: part of the state
    out.push_back(static_cast<double>(broke_count_));
    out.push_back(static_cast<double>(re_formed_count_));
  }
  void load(const double*& in) override {
    first_break_step_ = static_cast<long>(*in++);
    first_break_time_ = *in++;
    for (std::size_t b = 0; b < alive_.size(); ++b) {
      alive_[b] = static_cast<std::uint8_t>(*in++);
      phi_break_[b] = *in++;
      if (spec_.model == PairModel::bonded) stencil_.set_alive(b, alive_[b]);
    }
    skin_ = *in++;
    broke_count_ = static_cast<long>(*in++);
    re_formed_count_ = static_cast<long>(*in++);
  }

  void after_move(State<D>& s, double max_step) override {
    if (spec_.model == PairModel::cutoff) drift_ += max_step;
    // Verlet criterion with a bound instead of a pass over the particles: no particle has moved more than
    // the sum of the largest single-step moves since the build. Rebuild before two could have closed the skin.
    moved_bound_ += max_step;
    since_break_ += max_step;
    if (list_holds(moved_bound_, since_break_)) return;
    // The bound is loose once particles vibrate: each step's largest move is added though they move back.
    // The displacements themselves decide (one pass over the particles, cheaper than a rebuild: the broken
    // cutoff plate rebuilt every 24 steps on the bound, at ~2 ms each). Well before the skin is used up
    // the list is rebuilt anyway, so this pass does not run every step.
    if (2.0 * since_break_ < break_room_) {  // (else a pair whose bond broke may be near: rebuild now)
      const double moved = std::sqrt(max_displacement2(s));
      if (2.0 * moved < 0.75 * skin_) {
        moved_bound_ = moved;  // still a bound on every particle's displacement since the build
        room_ = skin_;
        return;
      }
      // Less a common affine map (three passes: only when the displacements alone would rebuild, ~35 us on
      // the plate; run at every pass they cost the broken cutoff plate 6 % of its run).
      const auto [residual, room] = affine_residual(s);
      if (2.0 * residual < 0.75 * room) {
        moved_bound_ = residual;  // from here on, a bound on every particle's residual under this map
        room_ = room;
        return;
      }
      adapt_skin(s.step - built_step_);
    }
    rebuild(s);
  }

  // The cutoff model's potential is shifted to zero at D (phi(r) - phi(D) for each pair within D): the force is
  // unchanged, and the energy no longer jumps by phi(D) each time a pair crosses D, so kinetic + potential
  // - boundary work stays a conservation check (unshifted, the 3-D block's balance was off by up to 20 times
  // its kinetic energy within 1e-4 s: docs/physics.md, "Two readings").
  // pairs_beyond_cutoff is counted from the distances here, apart from the record of crossings.
  void observe(const State<D>& s, Observables& o) const override {
    double pe = 0.0;
    long beyond = 0;
    const double cut2 = cutoff_ * cutoff_;
    for (std::size_t b = 0; b < bi_.size(); ++b) {
      if (spec_.model == PairModel::bonded) {
        const double r = (s.x[static_cast<std::size_t>(bi_[b])] - s.x[static_cast<std::size_t>(bj_[b])]).norm();
        if (alive_[b])
          pe += law_potential(laws_[static_cast<std::size_t>(blaw_[b])], r, r_min_);
        else
          ++beyond, o.bond_break_energy += phi_break_[b];
      } else if (!(bond_r2(s.x.front().data(), b) <= cut2)) {
        ++beyond;
      }
    }
    for (std::size_t p = 0; p < list_.size(); ++p) {
      const double r = (s.x[static_cast<std::size_t>(list_.i[p])] - s.x[static_cast<std::size_t>(list_.j[p])]).norm();
      const PairLaw& law = laws_[static_cast<std::size_t>(list_.law[p])];
      if (spec_.model == PairModel::cutoff) {
        if (r <= cutoff_) pe += law_potential(law, r, r_min_) - law_potential(law, cutoff_, r_min_);
      } else {
        const double reach = contact_reach_[static_cast<std::size_t>(list_.law[p])];
        if (r < reach) pe += law_potential(law, r, r_min_) - law.potential(reach);
      }
    }
    o.potential += pe;
    o.pairs_beyond_cutoff += beyond;
  }

  // Eq. (15) at the closest approach of the pairs that act now, per law: the stiffness -dF/dr grows as a
  // pair is pressed below r0 and is constant (zero) inside r_min, and for stretched pairs it is largest at
  // r0, so each law's closest distance is clamped to [r_min, r_eq]. One extra pass over the pairs per step.
  double step_limit(const State<D>& s) const override {
    std::vector<double> close2(laws_.size(), std::numeric_limits<double>::infinity());
    double* c2 = close2.data();
    const double* x = s.x.front().data();
    const double cut2 = cutoff_ * cutoff_;
    auto r2_of = [x](int i, int j) {
      const std::size_t a = static_cast<std::size_t>(i) * D, b = static_cast<std::size_t>(j) * D;
      double r2 = 0.0;
      for (int d = 0; d < D; ++d) r2 += (x[a + d] - x[b + d]) * (x[a + d] - x[b + d]);
      return r2;
    };
    if (spec_.model == PairModel::bonded) {
      const long nb = static_cast<long>(bi_.size());
      for (long b = 0; b < nb; ++b) {
        const std::size_t u = static_cast<std::size_t>(b);
        if (alive_[u]) c2[blaw_[u]] = std::min(c2[blaw_[u]], r2_of(bi_[u], bj_[u]));
      }
    }
    const long np = static_cast<long>(list_.size());
    for (long p = 0; p < np; ++p) {
      const std::size_t u = static_cast<std::size_t>(p);
      const int l = list_.law[u];
      const double r2 = r2_of(list_.i[u], list_.j[u]);
      const double reach = spec_.model == PairModel::cutoff ? cut2 : contact_reach_[static_cast<std::size_t>(l)] *
                                                                         contact_reach_[static_cast<std::size_t>(l)];
      if (r2 < reach) c2[l] = std::min(c2[l], r2);
    }
    double limit = std::numeric_limits<double>::infinity();
    for (std::size_t l = 0; l < laws_.size(); ++l) {
      if (!std::isfinite(close2[l])) continue;
      const double r = std::clamp(std::sqrt(close2[l]), r_min_, laws_[l].equilibrium_spacing());
      limit = std::min(limit, dt_limit(laws_[l], law_mass_[l], r));
    }
    return limit;
  }

  const std::vector<std::uint8_t>& alive() const { return alive_; }
  bool cutoff_model() const { return spec_.model == PairModel::cutoff; }
  long broke_count() const { return broke_count_; }
  long re_formed_count() const { return re_formed_count_; }
  void take_events(std::vector<BondEvent>& out) {
    out.insert(out.end(), events_.begin(), events_.end());
    events_.clear();
  }
  long first_break_step() const { return first_break_step_; }
  double first_break_time() const { return first_break_time_; }
  long list_builds() const { return list_builds_; }
  double skin() const { return skin_; }

 private:
  int law_of(int a, int b) const {
    return pair_law_[static_cast<std::size_t>(phase_[static_cast<std::size_t>(a)]) * nphase_ +
                     static_cast<std::size_t>(phase_[static_cast<std::size_t>(b)])];
  }

  // The Verlet criterion, one test for plain and resident steps: while no particle's residual (its
  // displacement since the build less the common map of affine_residual; at the build, none) exceeds
  // `bound` [cm], no pair outside the list can have come within reach; nor a pair whose bond broke since
  // the build, while no particle has moved `since_break` [cm] since the first such break (break_room_).
  bool list_holds(double bound, double since_break) const {
    return 2.0 * bound < room_ && 2.0 * since_break < break_room_;
  }

  // Bonds found too long in the last force evaluation are gone for good (bonded model).
  void settle_breaks(const State<D>& s, long broke) {
    if (spec_.model != PairModel::bonded || broke == 0) return;
    const double closest = retire_broken(s);
    // A pair whose bond just broke must repel as a contact once it comes back within reach, and the list
    // left it out while bonded. It is D or more apart now and closes by at most twice the moves since, so the
    // list holds until those add up to half its distance to reach (D - r_eq ~ 0.7 r0: far more than the skin
    // allows). Rebuilding at every break instead was most of a 3-D impact's run (a rebuild nearly every step).
    if (!uses_list_) return;
    if (!std::isfinite(break_room_)) since_break_ = 0.0;
    break_room_ = std::min(break_room_, closest - max_reach_);
  }

  void record(const State<D>& s, std::size_t b, bool re_formed) {
    events_.push_back({s.step, s.time(), static_cast<long>(b), re_formed});
    if (re_formed) {
      ++re_formed_count_;
    } else {
      ++broke_count_;
      if (first_break_step_ < 0) first_break_step_ = s.step, first_break_time_ = s.time();
    }
  }

  // Squared length of original bond b at positions x (N x D), with the arithmetic of the sweeps.
  double bond_r2(const double* x, std::size_t b) const {
    const std::size_t i = static_cast<std::size_t>(bi_[b]), j = static_cast<std::size_t>(bj_[b]);
    const double d0 = x[i * D] - x[j * D], d1 = x[i * D + 1] - x[j * D + 1];
    const double d2 = D == 3 ? x[i * D + D - 1] - x[j * D + D - 1] : 0.0;
    return d0 * d0 + d1 * d1 + d2 * d2;
  }

  // Cutoff model: every crossing of D by an original bond is recorded at the step it happens (alive_: within
  // D). A bond's length changes by at most twice the largest move of a particle, so a bond whose length was
  // |r - D| = m from D at the last full pass cannot cross before the moves since (drift_) add up to m / 2.
  // Each step tests only the bonds that were near D (near_); all of them again once the drift could have
  // carried any other across (far_margin_: the smallest m among them). Which bonds a step tests changes
  // nothing recorded, only what it costs: the record is the same for any schedule of passes.
  bool crossing_pass_due(double drift) const { return !(2.0 * drift + 1e-9 * r0_ < far_margin_); }
  void record_crossings(const State<D>& s) {
    const double cut2 = cutoff_ * cutoff_;
    const double* x = s.x.front().data();
    const auto test = [&](std::size_t b) {
      const double r2 = bond_r2(x, b);
      const bool within = r2 <= cut2;
      if (within != static_cast<bool>(alive_[b])) alive_[b] = within, record(s, b, within);
      return r2;
    };
    if (!crossing_pass_due(drift_)) {
      for (const int b : near_) test(static_cast<std::size_t>(b));
      return;
    }
    // The window of near bonds follows how long the last full pass lasted (fragments flying apart move
    // far each step; an intact lattice hardly at all), as the Verlet skin does.
    const long lasted = s.step - full_pass_step_;
    if (far_margin_ >= 0.0 && lasted < 20) window_ = std::min(2.0 * window_, 0.5 * r0_);
    if (lasted > 2000) window_ = std::max(0.5 * window_, 0.02 * r0_);
    near_.clear();
    far_margin_ = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < bi_.size(); ++b) {
      const double margin = std::abs(std::sqrt(test(b)) - cutoff_);
      if (margin < window_)
        near_.push_back(static_cast<int>(b));
      else
        far_margin_ = std::min(far_margin_, margin);
    }
    drift_ = 0.0;
    full_pass_step_ = s.step;
  }

  // The bonded model's contacts: unbonded pairs closer than r0 feel the law's repulsive branch. A select,
  // not a branch, decides whether a pair acts, so the loop below vectorizes. Pair u's force on i: out.
  template <class Law>
  void contact_pair_force(const double* x, const Law& law, std::size_t u, double (&out)[D]) const {
    const std::size_t a = static_cast<std::size_t>(list_.i[u]) * D, b = static_cast<std::size_t>(list_.j[u]) * D;
    const double d0 = x[a] - x[b], d1 = x[a + 1] - x[b + 1];
    const double d2 = D == 3 ? x[a + D - 1] - x[b + D - 1] : 0.0;
    const double r2 = d0 * d0 + d1 * d1 + d2 * d2;
    const double rc = contact_reach_[static_cast<std::size_t>(list_.law[u])];
    const bool act = r2 < rc * rc;
    const double inv = 1.0 / std::sqrt(r2);
    const double ie = std::min(inv, inv_rmin_);  // force held constant inside r_min (Sec. 4.2)
    const double mag = law.magnitude(u, ie) * inv;  // > 0 repulsive
    const double fr = act ? mag : 0.0;
    out[0] = fr * d0;
    out[1] = fr * d1;
    if constexpr (D == 3) out[D - 1] = fr * d2;
  }
  // Pairs [first, last) into list_.force.
  template <class Law>
  void contact_pair_forces(const State<D>& s, const Law law, long first, long last) {
    const double* x = s.x.front().data();
    double* __restrict f0 = list_.force[0].data();
    double* __restrict f1 = list_.force[1].data();
    double* __restrict f2 = list_.force[D - 1].data();
#pragma omp simd
    for (long p = first; p < last; ++p) {
      const std::size_t u = static_cast<std::size_t>(p);
      double out[D];
      contact_pair_force(x, law, u, out);
      f0[u] = out[0];
      f1[u] = out[1];
      if constexpr (D == 3) f2[u] = out[D - 1];
    }
  }

  template <class Law>
  void contact_kernel(State<D>& s, const Law law) {
    const long m = static_cast<long>(list_.size());
    double* f = s.f.front().data();
    // The team's rule for particles holds for pairs too: too few contacts for a second thread (before
    // fracture, the pairs across a slit) are summed here without waking the team. The sums are the same
    // either way (each particle's order is fixed).
    detail::Team& team = *s.team;
    auto body = [&](int tid, int nt) {
      const auto [first, last] = detail::share(m, tid, nt);
      contact_pair_forces(s, law, first, last);
      if (nt > 1) team.barrier(tid);  // the gather reads every thread's pair forces
      list_.gather(f, tid, nt);
    };
    if (team.threads_for(static_cast<std::size_t>(m)) == 1)
      body(0, 1);
    else
      team.run([&](int tid) { body(tid, team.size()); });
  }

  /// Retires the bonds longer than D at s.x; returns the shortest of them [cm].
  double retire_broken(const State<D>& s) {
    const double cut2 = cutoff_ * cutoff_;
    const double* x = s.x.front().data();
    double shortest2 = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < bi_.size(); ++b) {
      if (!alive_[b]) continue;
      const double r2 = bond_r2(x, b);
      if (!(r2 <= cut2)) {
        alive_[b] = 0;
        stencil_.set_alive(b, false);
        phi_break_[b] = law_potential(laws_[static_cast<std::size_t>(blaw_[b])], std::sqrt(r2), r_min_);
        record(s, b, false);
        shortest2 = std::min(shortest2, r2);
      }
    }
    return std::sqrt(shortest2);
  }

  // The skin trades pairs evaluated every step against rebuilds (~1.5 ms for the plate, ~60 steps' work).
  // An intact lattice wants a skin inside the gap between D and the next lattice shell (the (7,14) cutoff
  // plate: D = 1.7 r0, next shell sqrt(3) r0; a skin of 0.3 r0 doubled the pairs and cost 40 % of the quiet
  // phase); a broken one, with pieces flying at ~1e4 cm/s, wants a wide one (fixed skins over the whole
  // cutoff (7,14) run: 0.025 r0 56,205 rebuilds 45 s, 0.3 r0 2,016 8.1 s, 0.6 r0 259 6.8 s, 1.0 r0 58 10.9 s).
  // So the cutoff model's skin follows the rebuild interval: doubled when the list lasted under 200 steps,
  // halved (not below the start) when it lasted over 2,000. Decided from step counts only: reproducible.
  void adapt_skin(long steps_lasted) {
    if (steps_lasted < 200)
      skin_ = std::min(2.0 * skin_, skin_max_);
    else if (steps_lasted > 2000)
      skin_ = std::max(0.5 * skin_, skin_min_);
  }

  // 3/4 of the gap between D and the closest pair beyond it at the start (a lattice's next shell), kept
  // within [0.01, 0.3] r0.
  double skin_in_gap(const State<D>& s) {
    double closest2 = std::numeric_limits<double>::infinity();
    const double reach2 = max_reach_ * max_reach_;
    cells_.for_each_pair(s.x, max_reach_ + 0.3 * r0_, [&](std::uint32_t, std::uint32_t, double r2) {
      if (r2 > reach2) closest2 = std::min(closest2, r2);
    });
    const double gap = std::sqrt(closest2) - max_reach_;  // infinite: nothing beyond reach within 0.3 r0
    return std::clamp(0.75 * gap, 0.01 * r0_, 0.3 * r0_);
  }

  // Verlet list of pairs within reach + skin. Bonded: excludes intact bonds (they act through the stencil).
  void rebuild(const State<D>& s) {
    ++list_builds_;
    list_.clear();
    ByFirst bonded;  // intact bonds by first particle
    if (spec_.model == PairModel::bonded) {
      std::vector<std::pair<int, int>> intact;
      for (std::size_t b = 0; b < bi_.size(); ++b)
        if (alive_[b]) intact.push_back({bi_[b], bj_[b]});
      bonded = by_first(intact);
    }
    std::vector<std::pair<int, int>> found;
    cells_.for_each_pair(s.x, max_reach_ + skin_, [&](std::uint32_t a, std::uint32_t b, double) {
      if (spec_.model == PairModel::bonded) {
        for (int e = bonded.start[a]; e < bonded.start[a + 1]; ++e)
          if (bonded.other[static_cast<std::size_t>(e)] == static_cast<int>(b)) return;
      }
      found.push_back({static_cast<int>(a), static_cast<int>(b)});
    });
    // Sorted, so the order in which each particle sums its active pairs does not depend on when the list was
    // built (pairs beyond reach add exactly zero): contact forces are then independent of rebuild timing.
    // By first particle with a counting sort, then each particle's few partners (a std::sort of the whole
    // list was 15 % of the broken cutoff plate's run).
    ByFirst pairs = by_first(found);
    for (std::size_t a = 0; a < n_; ++a) {
      const auto b0 = pairs.other.begin() + pairs.start[a], b1 = pairs.other.begin() + pairs.start[a + 1];
      std::sort(b0, b1);
      for (auto it = b0; it != b1; ++it) list_.add(static_cast<int>(a), *it, law_of(static_cast<int>(a), *it));
    }
    list_.index(n_);
    if (spec_.model == PairModel::cutoff) {
      list_stencil_ = detail::BondStencil<D>(n_, list_.i, list_.j, list_.law, spec_.single_precision);
      list_stencil_.assign_forces(true);  // stage::assigns_forces: the pairs' sum is every particle's first term
    }
    moved_bound_ = 0.0;
    room_ = skin_;
    since_break_ = 0.0;
    break_room_ = std::numeric_limits<double>::infinity();
    built_step_ = s.step;
    x_build_.assign(s.x.front().data(), s.x.front().data() + s.size() * D);
  }

  /// Pairs (a, b) grouped by a (a counting sort): a's partners are other[start[a], start[a + 1]), in the
  /// order given.
  struct ByFirst {
    std::vector<int> start, other;
  };
  ByFirst by_first(const std::vector<std::pair<int, int>>& pairs) const {
    ByFirst g;
    g.start.assign(n_ + 1, 0);
    for (const auto& pr : pairs) ++g.start[static_cast<std::size_t>(pr.first) + 1];
    for (std::size_t k = 0; k < n_; ++k) g.start[k + 1] += g.start[k];
    g.other.resize(pairs.size());
    std::vector<int> fill(g.start.begin(), g.start.end() - 1);
    for (const auto& [a, b] : pairs) g.other[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = b;
    return g;
  }

  double max_displacement2(const State<D>& s) const {
    const double* __restrict x = s.x.front().data();
    const double* __restrict x0 = x_build_.data();
    const long m = static_cast<long>(s.size());
    double max2 = 0.0;
#pragma omp simd reduction(max : max2)
    for (long k = 0; k < m; ++k) {
      double d2 = 0.0;
      for (int c = 0; c < D; ++c) d2 += (x[k * D + c] - x0[k * D + c]) * (x[k * D + c] - x0[k * D + c]);
      max2 = std::max(max2, d2);
    }
    return max2;
  }

  // The displacements since the build, d_i, less the affine map u(x) = A x + c fitted to them by least
  // squares over x_i at the build: returns the largest residual |d_i - u(x_i)| and the room it may use.
  // A pair outside the list was at least R = reach + skin apart at the build; now its separation is
  // (I + A) r + e_i - e_j, at least (1 - |A|_F) R - 2 max|e|. So it cannot have come within reach while
  // 2 max|e| < room = (1 - |A|_F) R - reach (with A = 0: the skin, the usual Verlet test). A plate pulled
  // at its edges is stretched nearly affinely: its pulled rows move far, its pairs little (the cutoff
  // (7,14) plate rebuilt its list every ~900 steps on the raw displacements, 0.8 ms each).
  std::pair<double, double> affine_residual(const State<D>& s) const {
    using M = Eigen::Matrix<double, D, D>;
    const std::size_t n = s.size();
    const auto at = [&](std::size_t i) { return Eigen::Map<const V>(x_build_.data() + i * D); };
    V x_mean = V::Zero(), d_mean = V::Zero();
    for (std::size_t i = 0; i < n; ++i) x_mean += at(i), d_mean += s.x[i] - at(i);
    x_mean /= static_cast<double>(n);
    d_mean /= static_cast<double>(n);
    M xx = M::Zero(), dx = M::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      const V X = at(i) - x_mean;
      xx += X * X.transpose();
      dx += (s.x[i] - at(i) - d_mean) * X.transpose();
    }
    M A = M::Zero();
    const double scale = xx.trace() / D;  // a body flat in some direction has no fit there: translation only
    if (scale > 0.0 && std::abs(xx.determinant()) > 1e-12 * std::pow(scale, D)) A = dx * xx.inverse();
    double worst2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const V X = at(i) - x_mean;
      worst2 = std::max(worst2, (s.x[i] - at(i) - d_mean - A * X).squaredNorm());
    }
    const double reach = max_reach_ + skin_;
    return {std::sqrt(worst2), (1.0 - A.norm()) * reach - max_reach_};
  }

  PairSpec spec_;
  std::vector<PairLaw> laws_;
  detail::LawTable law_table_;  ///< laws_ for the vector sweep of several laws
  std::vector<int> phase_, pair_law_;
  std::size_t nphase_ = 1, n_ = 0;
  double cutoff_ = 0.0, inv_rmin_ = 0.0, r_min_ = 0.0, max_reach_ = 0.0, r0_ = 0.0;
  double skin_ = 0.0, skin_min_ = 0.0;  ///< cm: Verlet skin now, and its floor (the starting skin)
  double skin_max_ = 0.0;  ///< cm: the skin's ceiling
  long built_step_ = 0;  ///< step of the last list build
  long list_builds_ = 0;
  std::vector<double> contact_reach_;
  bool uses_list_ = false;
  std::vector<int> bi_, bj_, blaw_;  ///< original bonds (i < j) and their law
  std::vector<std::uint8_t> alive_;
  std::vector<double> phi_break_;
  long broke_ = 0;  ///< bonds the last add_fused_forces found too long (retired by add_forces)
  std::vector<BondEvent> events_;  ///< recorded since the last take_events
  long broke_count_ = 0;           ///< bonds broken (cutoff model: pairs leaving D), over the whole run
  long re_formed_count_ = 0;       ///< cutoff model: pairs coming back within D
  // cutoff model's crossing record (record_crossings)
  std::vector<int> near_;               ///< bonds within window_ of D at the last full pass, ascending
  std::vector<std::vector<int>> near_of_;  ///< resident steps: near_ by the thread owning a bond's first particle
  double far_margin_ = -1.0;            ///< cm: smallest |r - D| of the other bonds then (< 0: pass due)
  double drift_ = 0.0;                  ///< cm: the largest moves summed since the last full pass
  double window_ = 0.0;                 ///< cm: how near D a bond is tested every step
  long full_pass_step_ = 0;
  std::atomic<long> broke_of_team_{0};  ///< the same, summed by the threads of resident_forces
  struct alignas(64) ThreadContacts {  ///< resident steps: a thread's contacts (a cache line of its own)
    std::vector<int> pairs;            ///< the contacts its particles are in, ascending
    std::vector<double> force[D];      ///< its copy of those pairs' forces (by pair index)
  };
  std::vector<ThreadContacts> contacts_of_;
  std::vector<double> moved_of_;        ///< resident steps: each thread's copy of moved_bound_ (cm)
  std::vector<long> touched_from_;      ///< resident steps: thread t gathers list_.touched[from[t], from[t+1])
  long first_break_step_ = -1;
  double first_break_time_ = -1.0;
  std::vector<double> law_mass_;  ///< g: the lightest particle a law acts on (Eq. 15 takes the smallest m)
  detail::BondStencil<D> stencil_;       ///< bonded model: the bonds
  detail::BondStencil<D> list_stencil_;  ///< cutoff model: the Verlet list
  PairTable<D> list_;
  double moved_bound_ = 0.0;  ///< cm: bound on any particle's residual (list_holds) since the last list build
  double since_break_ = 0.0;  ///< cm: bound on any particle's move since the first bond broke after the build
  double break_room_ = std::numeric_limits<double>::infinity();  ///< cm: shortest such pair at its break, less reach
  double room_ = 0.0;  ///< cm: twice the largest residual the list allows (the skin at the build; affine_residual)
  std::vector<double> x_build_;  ///< cm: positions (N x D) at the last list build
  CellList<D> cells_;
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
    v.cutoff_model = p->cutoff_model();
    v.broke = p->broke_count();
    v.re_formed = p->re_formed_count();
    v.first_break_step = p->first_break_step();
    v.first_break_time = p->first_break_time();
    v.list_builds = p->list_builds();
    v.skin = p->skin();
  }
  return v;
}

template <int D>
void take_bond_events(Effect<D>& e, std::vector<BondEvent>& out) {
  if (auto* p = dynamic_cast<PairEffect<D>*>(&e)) p->take_events(out);
}

template std::unique_ptr<Effect<2>> make_pair_effect<2>(const System&, const PairSpec&);
template std::unique_ptr<Effect<3>> make_pair_effect<3>(const System&, const PairSpec&);
template BondView<2> bond_view<2>(const Effect<2>&);
template BondView<3> bond_view<3>(const Effect<3>&);
template void take_bond_events<2>(Effect<2>&, std::vector<BondEvent>&);
template void take_bond_events<3>(Effect<3>&, std::vector<BondEvent>&);

}  // namespace pmfrag

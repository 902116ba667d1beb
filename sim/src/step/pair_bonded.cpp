// The bonded reading of the pair law (physics.md, "Two readings"): the original nearest-neighbour bonds
// interact until they first exceed D, then are gone for good; particles not bonded repel by the law's
// repulsive branch (r < r_eq) so fragments collide. Bonds go through stencil sweeps (bond_stencil.hpp),
// contacts through the Verlet list's pair table and a gather. Both sum each particle's forces in a fixed
// order: bitwise the same results for any number of threads.
#include "kernels/bond_stencil.hpp"
#include "step/pair_base.hpp"

#include <atomic>

namespace pmfrag::detail {

namespace {

template <int D>
class BondedPair final : public PairBase<D> {
  using Base = PairBase<D>;
  using Base::alive_, Base::bi_, Base::bj_, Base::laws_, Base::law_table_, Base::nphase_, Base::n_,
      Base::cutoff_, Base::inv_rmin_, Base::r_min_, Base::max_reach_, Base::r0_, Base::contact_reach_,
      Base::phi_break_, Base::list_, Base::skin_, Base::skin_min_, Base::skin_max_, Base::since_break_,
      Base::break_room_, Base::uses_list_, Base::spec_;

 public:
  using V = Eigen::Matrix<double, D, 1>;

  BondedPair(const System& sys, const PairSpec& spec) : Base(sys, spec, spec.contact) {
    std::vector<int> blaw(bi_.size());
    for (std::size_t b = 0; b < blaw.size(); ++b) blaw[b] = this->bond_law(b);
    // one phase: with_law always passes a single-law evaluator, so the stencil keeps no law per bond
    stencil_ = BondStencil<D>(n_, bi_, bj_, blaw, spec_.single_precision, true, this->nphase_ != 1);
    stencil_.assign_forces(true);  // stage::assigns_forces: the bonds' sum is every particle's first term
    // Original bonds come sorted (build_system; the stencil above checks): bonds [bond_from_[a], bond_from_[a + 1]).
    bond_from_.assign(n_ + 1, 0);
    for (const int i : bi_) ++bond_from_[static_cast<std::size_t>(i) + 1];
    for (std::size_t a = 0; a < n_; ++a) bond_from_[a + 1] += bond_from_[a];
    max_reach_ = *std::max_element(contact_reach_.begin(), contact_reach_.end());
  }

  std::string name() const override { return "pair (bonded)"; }
  unsigned stages() const override { return Base::stages() | stage::fused_force; }

  void setup(State<D>& s) override {
    if (!uses_list_) return;
    // The contact list's skin stays at 0.3 r0. Its reach is the bonds' own spacing, where there is no gap
    // to fit a skin into (measured from it: 0.01 r0, a rebuild every ~400 steps, 12 % of the quiet plate);
    // and wider, every intact piece's second neighbours (sqrt(3) r0) join the contact list (adapted up to
    // 0.8 r0: the whole (7,14) plate 3.2 -> 5.0 s).
    skin_ = skin_min_ = skin_max_ = 0.3 * r0_;
    this->rebuild(s);
  }
  void canonicalize(const State<D>& s) override {
    if (uses_list_) this->renew_list(s);
  }
  void load(const double*& in, const double* end) override {
    Base::load(in, end);
    for (std::size_t b = 0; b < alive_.size(); ++b) stencil_.set_alive(bi_[b], bj_[b], alive_[b]);
  }

  // The bonds read positions and which bonds are intact, nothing the neighbour list keeps: they are summed
  // in the pass that moves the particles (Leapfrog::step). Bonds found too long are retired in add_forces,
  // after the guard has accepted the step.
  void add_fused_forces(State<D>& s) override {
    const double cut2 = cutoff_ * cutoff_;
    broke_ = with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) {
      return stencil_.add_forces(*s.team, s.x.front().data(), s.f.front().data(), law, cut2, inv_rmin_);
    });
  }

  void add_forces(State<D>& s) override {
    settle_breaks(s, std::exchange(broke_, 0));
    if (uses_list_ && list_.size() > 0)
      with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) { contact_kernel(s, law.with_ids(list_.law.data())); });
  }

  // Resident steps (effects.hpp), each thread on its particles: the bonds and contacts. A thread evaluates
  // every contact its particles are in (a pair across two threads' shares twice, with the same arithmetic,
  // so the same bits) into its own copy of the pair forces, and sums its particles' from it.
  bool resident_begin(State<D>&, const std::vector<long>& bounds) override {
    const std::size_t threads = bounds.size() - 1;
    this->list_resident_begin(threads);
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
    return this->list_resident_due(max_step, tid);
  }
  void resident_moved(double max_step, int tid) override { this->list_resident_moved(max_step, tid); }
  long resident_forces(State<D>& s, const double* x, int tid) override {
    const double cut2 = cutoff_ * cutoff_;
    return with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) {
      const long mine = stencil_.add_forces_of(tid, x, s.f.front().data(), law, cut2, inv_rmin_);
      if (mine > 0) broke_of_team_.fetch_add(mine, std::memory_order_relaxed);
      ThreadContacts& c = contacts_of_[static_cast<std::size_t>(tid)];
      if (uses_list_ && !c.pairs.empty()) {
        const auto contact_law = law.with_ids(list_.law.data());
        typename PairTable<D>::Forces F;
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
  void resident_end(State<D>&) override { this->list_resident_end(); }
  void resident_settle(State<D>& s) override { settle_breaks(s, broke_of_team_.exchange(0)); }

  void after_move(State<D>& s, double max_step) override { this->check_list(s, max_step); }

  // Intact bonds at phi(r), broken ones at phi at their break (bond_break_energy), contacts within reach at
  // phi(r) - phi(r_eq).
  void observe(const State<D>& s, Observables& o) const override {
    double pe = 0.0;
    long beyond = 0;
    for (std::size_t b = 0; b < bi_.size(); ++b) {
      const double r = (s.x[static_cast<std::size_t>(bi_[b])] - s.x[static_cast<std::size_t>(bj_[b])]).norm();
      if (alive_[b])
        pe += law_potential(laws_[static_cast<std::size_t>(this->bond_law(b))], r, r_min_);
      else
        ++beyond, o.bond_break_energy += this->phi_at_break(b);
    }
    for (std::size_t p = 0; p < list_.size(); ++p) {
      const double r = (s.x[static_cast<std::size_t>(list_.i[p])] - s.x[static_cast<std::size_t>(list_.j[p])]).norm();
      const PairLaw& law = laws_[static_cast<std::size_t>(list_.law[p])];
      const double reach = contact_reach_[static_cast<std::size_t>(list_.law[p])];
      if (r < reach) pe += law_potential(law, r, r_min_) - law.potential(reach);
    }
    o.potential += pe;
    o.pairs_beyond_cutoff += beyond;
  }

 private:
  void closest_bonds(const double* x, double* c2) const override {
    const long nb = static_cast<long>(bi_.size());
    for (long b = 0; b < nb; ++b) {
      const std::size_t u = static_cast<std::size_t>(b);
      if (alive_[u]) {
        double& c = c2[this->bond_law(u)];
        c = std::min(c, Base::r2_of(x, bi_[u], bj_[u]));
      }
    }
  }
  double list_reach2(int law) const override {
    return contact_reach_[static_cast<std::size_t>(law)] * contact_reach_[static_cast<std::size_t>(law)];
  }
  // The list holds contacts: intact bonds act through the stencil. They are read in place, by first particle
  // (a list of the intact ones, made at each rebuild, was 40 bytes a particle at the setup's peak memory).
  typename Base::Exclusions excluded_from_list() const override {
    return {bond_from_.data(), bj_.data(), alive_.data()};
  }

  // Bonds found too long in the last force evaluation are gone for good.
  void settle_breaks(const State<D>& s, long broke) {
    if (broke == 0) return;
    const double closest = retire_broken(s);
    // A pair whose bond just broke must repel as a contact once it comes back within reach, and the list
    // left it out while bonded. It is D or more apart now and closes by at most twice the moves since, so the
    // list holds until those add up to half its distance to reach (D - r_eq ~ 0.7 r0: far more than the skin
    // allows). Rebuilding at every break instead was most of a 3-D impact's run (a rebuild nearly every step).
    if (!uses_list_) return;
    if (!std::isfinite(break_room_)) since_break_ = 0.0;
    break_room_ = std::min(break_room_, closest - max_reach_);
  }

  /// Retires the bonds longer than D at s.x; returns the shortest of them [cm].
  double retire_broken(const State<D>& s) {
    const double cut2 = cutoff_ * cutoff_;
    const double* x = s.x.front().data();
    double shortest2 = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < bi_.size(); ++b) {
      if (!alive_[b]) continue;
      const double r2 = this->bond_r2(x, b);
      if (!(r2 <= cut2)) {
        alive_[b] = 0;
        stencil_.set_alive(bi_[b], bj_[b], false);
        phi_break_[b] = law_potential(laws_[static_cast<std::size_t>(this->bond_law(b))], std::sqrt(r2), r_min_);
        this->record(s, b, false);
        shortest2 = std::min(shortest2, r2);
      }
    }
    return std::sqrt(shortest2);
  }

  // Unbonded pairs closer than r_eq feel the law's repulsive branch. A select, not a branch, decides whether
  // a pair acts, so the loop below vectorizes. Pair u's force on i: out.
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
    Team& team = *s.team;
    auto body = [&](int tid, int nt) {
      const auto [first, last] = share(m, tid, nt);
      contact_pair_forces(s, law, first, last);
      if (nt > 1) team.barrier(tid);  // the gather reads every thread's pair forces
      list_.gather(f, tid, nt);
    };
    if (team.threads_for(static_cast<std::size_t>(m)) == 1)
      body(0, 1);
    else
      team.run([&](int tid) { body(tid, team.size()); });
  }

  BondStencil<D> stencil_;  ///< the bonds
  std::vector<int> bond_from_;  ///< bonds by first particle: a's are [bond_from_[a], bond_from_[a + 1])
  long broke_ = 0;          ///< bonds the last add_fused_forces found too long (retired by add_forces)
  std::atomic<long> broke_of_team_{0};  ///< the same, summed by the threads of resident_forces
  struct alignas(64) ThreadContacts {  ///< resident steps: a thread's contacts (a cache line of its own)
    std::vector<int> pairs;            ///< the contacts its particles are in, ascending
    std::vector<double> force[D];      ///< its copy of those pairs' forces (by pair index)
  };
  std::vector<ThreadContacts> contacts_of_;
  std::vector<long> touched_from_;  ///< resident steps: thread t gathers list_.touched[from[t], from[t+1])
};

}  // namespace

template <int D>
std::unique_ptr<Effect<D>> make_bonded_pair(const System& sys, const PairSpec& spec) {
  return std::make_unique<BondedPair<D>>(sys, spec);
}
template std::unique_ptr<Effect<2>> make_bonded_pair<2>(const System&, const PairSpec&);
template std::unique_ptr<Effect<3>> make_bonded_pair<3>(const System&, const PairSpec&);

}  // namespace pmfrag::detail

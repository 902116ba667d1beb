// The cutoff reading of the pair law, Greenspan's (physics.md, "Two readings"): every pair closer than D
// interacts; pairs form and break freely. The Verlet list of a lattice is a stencil too, so its pairs go
// through the same sweeps as the bonded model's bonds (bond_stencil.hpp), each particle's forces summed in
// a fixed order: bitwise the same results for any number of threads. The original bonds are not forces
// here, only a record: each time one leaves D or comes back within it.
#include "kernels/bond_stencil.hpp"
#include "step/pair_base.hpp"

namespace pmfrag::detail {

namespace {

template <int D>
class CutoffPair final : public PairBase<D> {
  using Base = PairBase<D>;
  using Base::alive_, Base::bi_, Base::laws_, Base::law_table_, Base::nphase_, Base::n_, Base::cutoff_,
      Base::inv_rmin_, Base::r_min_, Base::max_reach_, Base::r0_, Base::list_, Base::skin_, Base::skin_min_,
      Base::skin_max_, Base::moved_of_, Base::spec_;

 public:
  using V = Eigen::Matrix<double, D, 1>;

  CutoffPair(const System& sys, const PairSpec& spec) : Base(sys, spec, true) {
    max_reach_ = cutoff_;
    window_ = 0.05 * r0_;
  }

  std::string name() const override { return "pair (cutoff)"; }

  void setup(State<D>& s) override {
    skin_ = skin_min_ = this->skin_in_gap(s);
    skin_max_ = 0.8 * r0_;
    this->rebuild(s);
  }
  void canonicalize(const State<D>& s) override {
    this->renew_list(s);
    far_margin_ = -1.0;  // the next crossing test is a full pass, in a resumed run as in this one
  }

  void add_forces(State<D>& s) override {
    const double cut2 = cutoff_ * cutoff_;
    record_crossings(s);
    // these forces come first and set f (stage::assigns_forces), so with no pair f is zero
    if (list_.size() == 0) {
      std::fill(s.f.begin(), s.f.end(), V::Zero());
      return;
    }
    with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) {
      return list_stencil_.add_forces(*s.team, s.x.front().data(), s.f.front().data(), law, cut2, inv_rmin_);
    });
  }

  // Resident steps (effects.hpp), each thread on its particles: the Verlet list's stencil, as add_forces
  // evaluates it, and the near bonds' test against D. A due list ends the block, and the plain step that
  // follows decides whether to rebuild (after_move).
  bool resident_begin(State<D>&, const std::vector<long>& bounds) override {
    const std::size_t threads = bounds.size() - 1;
    this->list_resident_begin(threads);
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
  bool resident_due(const State<D>&, double max_step, int tid) const override {
    const double* mine = &moved_of_[static_cast<std::size_t>(tid) * 8];
    return this->list_resident_due(max_step, tid) || crossing_pass_due(mine[1] + max_step);
  }
  void resident_moved(double max_step, int tid) override {
    this->list_resident_moved(max_step, tid);
    moved_of_[static_cast<std::size_t>(tid) * 8 + 1] += max_step;
  }
  long resident_forces(State<D>& s, const double* x, int tid) override {
    const double cut2 = cutoff_ * cutoff_;
    return with_law(laws_, law_table_, nphase_ == 1, [&](const auto& law) {
      // the events: near bonds that crossed D (settled by record_crossings)
      list_stencil_.add_forces_of(tid, x, s.f.front().data(), law, cut2, inv_rmin_);
      long crossed = 0;
      for (const int b : near_of_[static_cast<std::size_t>(tid)])
        crossed += (this->bond_r2(x, static_cast<std::size_t>(b)) <= cut2) != static_cast<bool>(alive_[static_cast<std::size_t>(b)]);
      return crossed;
    });
  }
  void resident_end(State<D>&) override {
    this->list_resident_end();
    drift_ = moved_of_[1];
  }
  void resident_settle(State<D>& s) override { record_crossings(s); }

  void after_move(State<D>& s, double max_step) override {
    drift_ += max_step;
    this->check_list(s, max_step);
  }

  // The potential is shifted to zero at D (phi(r) - phi(D) for each pair within D): the force is unchanged,
  // and the energy no longer jumps by phi(D) each time a pair crosses D, so kinetic + potential - boundary
  // work stays a conservation check (unshifted, the 3-D block's balance was off by up to 20 times its
  // kinetic energy within 1e-4 s: docs/physics.md, "Two readings"). pairs_beyond_cutoff is counted from the
  // distances here, apart from the record of crossings.
  void observe(const State<D>& s, Observables& o) const override {
    double pe = 0.0;
    long beyond = 0;
    const double cut2 = cutoff_ * cutoff_;
    for (std::size_t b = 0; b < bi_.size(); ++b)
      if (!(this->bond_r2(s.x.front().data(), b) <= cut2)) ++beyond;
    for (std::size_t p = 0; p < list_.size(); ++p) {
      const double r = (s.x[static_cast<std::size_t>(list_.i[p])] - s.x[static_cast<std::size_t>(list_.j[p])]).norm();
      const PairLaw& law = laws_[static_cast<std::size_t>(list_.law[p])];
      if (r <= cutoff_) pe += law_potential(law, r, r_min_) - law_potential(law, cutoff_, r_min_);
    }
    o.potential += pe;
    o.pairs_beyond_cutoff += beyond;
  }

 private:
  double list_reach2(int) const override { return cutoff_ * cutoff_; }
  void list_built() override {
    list_stencil_ = BondStencil<D>(n_, list_.i, list_.j, list_.law, spec_.single_precision);
    list_stencil_.assign_forces(true);  // stage::assigns_forces: the pairs' sum is every particle's first term
  }

  // Every crossing of D by an original bond is recorded at the step it happens (alive_: within D). A bond's
  // length changes by at most twice the largest move of a particle, so a bond whose length was |r - D| = m
  // from D at the last full pass cannot cross before the moves since (drift_) add up to m / 2. Each step
  // tests only the bonds that were near D (near_); all of them again once the drift could have carried any
  // other across (far_margin_: the smallest m among them). Which bonds a step tests changes nothing
  // recorded, only what it costs: the record is the same for any schedule of passes.
  bool crossing_pass_due(double drift) const { return !(2.0 * drift + 1e-9 * r0_ < far_margin_); }
  void record_crossings(const State<D>& s) {
    const double cut2 = cutoff_ * cutoff_;
    const double* x = s.x.front().data();
    const auto test = [&](std::size_t b) {
      const double r2 = this->bond_r2(x, b);
      const bool within = r2 <= cut2;
      if (within != static_cast<bool>(alive_[b])) alive_[b] = within, this->record(s, b, within);
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

  BondStencil<D> list_stencil_;  ///< the Verlet list as a stencil
  std::vector<int> near_;        ///< bonds within window_ of D at the last full pass, ascending
  std::vector<std::vector<int>> near_of_;  ///< resident steps: near_ by the thread owning a bond's first particle
  double far_margin_ = -1.0;  ///< cm: smallest |r - D| of the other bonds then (< 0: pass due)
  double drift_ = 0.0;        ///< cm: the largest moves summed since the last full pass
  double window_ = 0.0;       ///< cm: how near D a bond is tested every step
  long full_pass_step_ = 0;
};

}  // namespace

template <int D>
std::unique_ptr<Effect<D>> make_cutoff_pair(const System& sys, const PairSpec& spec) {
  return std::make_unique<CutoffPair<D>>(sys, spec);
}
template std::unique_ptr<Effect<2>> make_cutoff_pair<2>(const System&, const PairSpec&);
template std::unique_ptr<Effect<3>> make_cutoff_pair<3>(const System&, const PairSpec&);

}  // namespace pmfrag::detail

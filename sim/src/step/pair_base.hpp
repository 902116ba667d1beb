// What the two pair effects share (physics.md, "Two readings"): the laws between phases, the original bonds
// and the record of their changes, and one Verlet list of pairs within reach + skin, with its criterion
// (a bound on the moves, the displacements, the displacements less an affine map), its skin and its rebuild.
// BondedPair (pair_bonded.cpp) and CutoffPair (pair_cutoff.cpp) add their forces, their events and their
// part of the resident steps.
#pragma once

#include "kernels/pair_kernels.hpp"
#include "pmfrag/model/material.hpp"
#include "pmfrag/step/effects.hpp"
#include "pmfrag/step/neighbors.hpp"

#include <Eigen/LU>  // 2x2 and 3x3 inverse and determinant (affine_residual)

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace pmfrag::detail {

template <int D>
class PairBase : public Effect<D> {
 public:
  using V = Eigen::Matrix<double, D, 1>;

  PairBase(const System& sys, const PairSpec& spec, bool uses_list) : spec_(spec), uses_list_(uses_list) {
    laws_ = sys.laws;
    law_table_ = LawTable(laws_);
    phase_ = sys.phase;
    nphase_ = sys.phase_names.size();
    pair_law_ = sys.phase_pair_law;
    cutoff_ = sys.cutoff;
    inv_rmin_ = sys.r_min > 0.0 ? 1.0 / sys.r_min : std::numeric_limits<double>::infinity();
    r_min_ = sys.r_min;
    n_ = sys.size();
    bi_.reserve(sys.bonds.size()), bj_.reserve(sys.bonds.size());  // no slack
    for (const auto& b : sys.bonds) bi_.push_back(b[0]), bj_.push_back(b[1]);
    alive_.assign(bi_.size(), 1);
    contact_reach_.resize(laws_.size());
    for (std::size_t l = 0; l < laws_.size(); ++l) contact_reach_[l] = laws_[l].equilibrium_spacing();
    r0_ = sys.r0;
    law_mass_.assign(laws_.size(), std::numeric_limits<double>::infinity());
    for (std::size_t a = 0; a < nphase_; ++a)
      for (std::size_t b = 0; b < nphase_; ++b) {
        double& m = law_mass_[static_cast<std::size_t>(pair_law_[a * nphase_ + b])];
        m = std::min({m, sys.phase_mass[a], sys.phase_mass[b]});
      }
  }

  unsigned stages() const override {
    return stage::setup | stage::force | stage::observe | stage::step_limit | (uses_list_ ? stage::after_move : 0u) |
           stage::assigns_forces | stage::resident;
  }

  // History for a checkpoint; the layout is the same for both readings. Only the bonds not intact (the
  // cutoff model: not within D) are listed, ascending, each with phi at its break: a closing checkpoint of
  // the whole bond state, two doubles a bond, was the peak of a run's memory at millions of bonds.
  void save(const State<D>& s, std::vector<double>& out) const override {
    out.push_back(static_cast<double>(first_break_step_));
    out.push_back(first_break_time_);
    out.push_back(static_cast<double>(bonds_not_intact()));
    for (std::size_t b = 0; b < alive_.size(); ++b)
      if (!alive_[b]) out.push_back(static_cast<double>(b)), out.push_back(phi_at_break(b));
    out.push_back(skin_);  // the adapted skin decides when the list is next rebuilt: part of the state
    out.push_back(static_cast<double>(broke_count_));
    out.push_back(static_cast<double>(re_formed_count_));
    if (uses_list_) save_list(s, out);
  }
  std::size_t saved_size(const State<D>& s) const override {
    return 2 * bonds_not_intact() + 6 + (uses_list_ ? list_saved_size(s) : 0);
  }
  void load(const double*& in, const double* end) override {
    const auto bad = [] { return std::runtime_error("checkpoint does not match the scene (bond record)"); };
    if (end - in < 3) throw bad();
    first_break_step_ = static_cast<long>(*in++);
    first_break_time_ = *in++;
    const double listed = *in++;
    if (!(listed >= 0.0 && listed <= static_cast<double>(alive_.size())) || end - in < 2 * static_cast<long>(listed) + 3)
      throw bad();
    std::fill(alive_.begin(), alive_.end(), std::uint8_t{1});
    phi_break_.clear();
    double last = -1.0;
    for (long k = 0; k < static_cast<long>(listed); ++k) {
      const double b = *in++, phi = *in++;
      if (!(b > last && b < static_cast<double>(alive_.size()))) throw bad();  // ascending bond numbers
      last = b;
      alive_[static_cast<std::size_t>(b)] = 0;
      if (phi != 0.0) phi_break_[static_cast<std::size_t>(b)] = phi;
    }
    skin_ = *in++;
    broke_count_ = static_cast<long>(*in++);
    re_formed_count_ = static_cast<long>(*in++);
    if (uses_list_) load_list(in, end);
  }

  // Eq. (15) at the closest approach of the pairs that act now, per law: the stiffness -dF/dr grows as a
  // pair is pressed below r0 and is constant (zero) inside r_min, and for stretched pairs it is largest at
  // r0, so each law's closest distance is clamped to [r_min, r_eq]. One extra pass over the pairs per step.
  double step_limit(const State<D>& s) const override {
    std::vector<double> close2(laws_.size(), std::numeric_limits<double>::infinity());
    double* c2 = close2.data();
    const double* x = s.x.front().data();
    closest_bonds(x, c2);
    const long np = static_cast<long>(list_.size());
    for (long p = 0; p < np; ++p) {
      const std::size_t u = static_cast<std::size_t>(p);
      const int l = list_.law[u];
      const double r2 = r2_of(x, list_.i[u], list_.j[u]);
      if (r2 < list_reach2(l)) c2[l] = std::min(c2[l], r2);
    }
    double limit = std::numeric_limits<double>::infinity();
    for (std::size_t l = 0; l < laws_.size(); ++l) {
      if (!std::isfinite(close2[l])) continue;
      const double r = std::clamp(std::sqrt(close2[l]), r_min_, laws_[l].equilibrium_spacing());
      limit = std::min(limit, dt_limit(laws_[l], law_mass_[l], r));
    }
    return limit;
  }

  BondView<D> bond_view() const override {
    BondView<D> v;
    v.alive = &alive_;
    v.cutoff_model = spec_.model == PairModel::cutoff;
    v.broke = broke_count_;
    v.re_formed = re_formed_count_;
    v.first_break_step = first_break_step_;
    v.first_break_time = first_break_time_;
    v.list_builds = list_builds_;
    v.skin = skin_;
    return v;
  }
  void take_bond_events(std::vector<BondEvent>& out) override {
    out.insert(out.end(), events_.begin(), events_.end());
    events_.clear();
  }

 protected:
  /// Squared distance of particles i and j at positions x (N x D).
  static double r2_of(const double* x, int i, int j) {
    const std::size_t a = static_cast<std::size_t>(i) * D, b = static_cast<std::size_t>(j) * D;
    double r2 = 0.0;
    for (int d = 0; d < D; ++d) r2 += (x[a + d] - x[b + d]) * (x[a + d] - x[b + d]);
    return r2;
  }
  /// step_limit: lowers c2[law] to the squared length of the closest pairs acting outside the list.
  virtual void closest_bonds(const double* /*x*/, double* /*c2*/) const {}
  /// step_limit: the squared distance within which a list pair of this law acts.
  virtual double list_reach2(int law) const = 0;
  /// Pairs (a, b) grouped by a: a's partners are other[start[a], start[a + 1]), in the order given.
  struct ByFirst {
    std::vector<int> start, other;
  };
  /// rebuild: pairs (i < j) the list leaves out, read in place: particle a's are other[e] for e in
  /// [start[a], start[a + 1]) with keep[e] set (keep null: all). None by default.
  struct Exclusions {
    const int* start = nullptr;
    const int* other = nullptr;
    const std::uint8_t* keep = nullptr;
  };
  virtual Exclusions excluded_from_list() const { return {}; }
  /// rebuild: after the list is built and indexed.
  virtual void list_built() {}

  /// The law of original bond b (one phase: the only law).
  int bond_law(std::size_t b) const { return nphase_ == 1 ? 0 : law_of(bi_[b], bj_[b]); }
  std::size_t bonds_not_intact() const {
    return static_cast<std::size_t>(std::count(alive_.begin(), alive_.end(), std::uint8_t{0}));
  }
  /// erg: phi of bond b at its break (0 for an intact bond, and in the cutoff model).
  double phi_at_break(std::size_t b) const {
    const auto it = phi_break_.find(b);
    return it == phi_break_.end() ? 0.0 : it->second;
  }

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

  // The list part of after_move.
  void check_list(State<D>& s, double max_step) {
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

  // Resident steps: each thread's copies of the list's bounds, a cache line per thread ([0] moved_bound_,
  // [2] since_break_; [1] is CutoffPair's drift).
  void list_resident_begin(std::size_t threads) {
    moved_of_.assign(threads * 8, moved_bound_);
    for (std::size_t t = 0; t < threads; ++t) moved_of_[t * 8 + 2] = since_break_;
  }
  bool list_resident_due(double max_step, int tid) const {
    const double* mine = &moved_of_[static_cast<std::size_t>(tid) * 8];
    return uses_list_ && !list_holds(mine[0] + max_step, mine[2] + max_step);
  }
  void list_resident_moved(double max_step, int tid) {
    double* mine = &moved_of_[static_cast<std::size_t>(tid) * 8];
    if (uses_list_) mine[0] += max_step, mine[2] += max_step;
  }
  void list_resident_end() {
    if (uses_list_) moved_bound_ = moved_of_[0], since_break_ = moved_of_[2];
  }

  void record(const State<D>& s, std::size_t b, bool re_formed) {
    events_.push_back({s.step, s.time(), static_cast<long>(b), re_formed});
    if (uses_list_) changed_since_build_.push_back(static_cast<int>(b));
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

  // The skin trades pairs evaluated every step against rebuilds (~1.5 ms for the plate, ~60 steps' work).
  // An intact lattice wants a skin inside the gap between D and the next lattice shell (the (7,14) cutoff
  // plate: D = 1.7 r0, next shell sqrt(3) r0; a skin of 0.3 r0 doubled the pairs and cost 40 % of the quiet
  // phase); a broken one, with pieces flying at ~1e4 cm/s, wants a wide one (fixed skins over the whole
  // cutoff (7,14) run: 0.025 r0 56,205 rebuilds 45 s, 0.3 r0 2,016 8.1 s, 0.6 r0 259 6.8 s, 1.0 r0 58 10.9 s).
  // So the skin follows the rebuild interval: doubled when the list lasted under 200 steps, halved (not
  // below the start) when it lasted over 2,000. Decided from step counts only: reproducible. (The bonded
  // model's floor and ceiling are equal: its skin stays.)
  void adapt_skin(long steps_lasted) {
    if (steps_lasted < 200)
      skin_ = std::min(2.0 * skin_, skin_max_);
    else if (steps_lasted > 2000)
      skin_ = std::max(0.5 * skin_, skin_min_);
  }

  // 3/4 of the gap between reach and the closest pair beyond it at the start (a lattice's next shell), kept
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

  // Verlet list of pairs within reach + skin, less the pairs excluded_from_list.
  void rebuild(const State<D>& s) { build_list(s.x, s.step); }

  // canonicalize's list: the one this run had, if a checkpoint taken between two builds was just loaded
  // (built again from the positions and the bonds of its build, with the bounds it had reached); else a new
  // one. The sweeps' layout follows the list (which offsets are dense enough to sweep: pairs present but
  // beyond reach then change the order of a particle's sum), so a list built at another step would change
  // the trajectory's last bits.
  void renew_list(const State<D>& s) {
    if (!loaded_list_) {
      rebuild(s);
      return;
    }
    const LoadedList p = std::move(*loaded_list_);
    loaded_list_.reset();
    if (p.x.empty()) {  // the checkpoint's step had just built its list
      rebuild(s);
    } else {
      for (auto b = p.changed.rbegin(); b != p.changed.rend(); ++b) alive_[static_cast<std::size_t>(*b)] ^= 1u;
      build_list(p.x, p.built_step);
      for (const int b : p.changed) alive_[static_cast<std::size_t>(b)] ^= 1u;
      changed_since_build_ = p.changed;
      moved_bound_ = p.moved_bound, since_break_ = p.since_break, break_room_ = p.break_room, room_ = p.room;
    }
    list_builds_ = p.builds;
  }

  template <class Positions>
  void build_list(const Positions& xs, long step) {
    ++list_builds_;
    list_.clear();
    changed_since_build_.clear();
    const Exclusions excluded = excluded_from_list();
    std::vector<std::pair<int, int>> found;
    cells_.for_each_pair(xs, max_reach_ + skin_, [&](std::uint32_t a, std::uint32_t b, double) {
      if (excluded.start) {
        for (int e = excluded.start[a]; e < excluded.start[a + 1]; ++e)
          if (excluded.other[e] == static_cast<int>(b) && (!excluded.keep || excluded.keep[e])) return;
      }
      found.push_back({static_cast<int>(a), static_cast<int>(b)});
    });
    // Sorted, so the list does not depend on the order of the cells' pairs (the sweeps' layout still depends
    // on which pairs the list holds: see renew_list). By first particle with a counting sort, then each
    // particle's few partners (a std::sort of the whole list was 15 % of the broken cutoff plate's run).
    ByFirst pairs = by_first(found);
    for (std::size_t a = 0; a < n_; ++a) {
      const auto b0 = pairs.other.begin() + pairs.start[a], b1 = pairs.other.begin() + pairs.start[a + 1];
      std::sort(b0, b1);
      for (auto it = b0; it != b1; ++it) list_.add(static_cast<int>(a), *it, law_of(static_cast<int>(a), *it));
    }
    list_.index(n_);
    list_built();
    moved_bound_ = 0.0;
    room_ = skin_;
    since_break_ = 0.0;
    break_room_ = std::numeric_limits<double>::infinity();
    built_step_ = step;
    x_build_.assign(xs.front().data(), xs.front().data() + n_ * D);
  }

  // The list's part of a checkpoint: its build count, and whether it was built at this step (a checkpoint
  // step rebuilds it: canonicalize). If not, what renew_list needs to build it again as it was: the build's
  // step and positions (N x D), the bounds since, and the bonds whose state changed since (they were
  // left out of the list, or not, as they were then).
  bool list_built_now(const State<D>& s) const { return built_step_ == s.step; }
  std::size_t list_saved_size(const State<D>& s) const {
    return 2 + (list_built_now(s) ? 0 : 6 + changed_since_build_.size() + x_build_.size());
  }
  void save_list(const State<D>& s, std::vector<double>& out) const {
    out.push_back(static_cast<double>(list_builds_));
    out.push_back(list_built_now(s) ? 1.0 : 0.0);
    if (list_built_now(s)) return;
    out.insert(out.end(), {static_cast<double>(built_step_), moved_bound_, since_break_, break_room_, room_,
                           static_cast<double>(changed_since_build_.size())});
    for (const int b : changed_since_build_) out.push_back(static_cast<double>(b));
    out.insert(out.end(), x_build_.begin(), x_build_.end());
  }
  void load_list(const double*& in, const double* end) {
    const auto bad = [] { return std::runtime_error("checkpoint does not match the scene (neighbour list)"); };
    if (end - in < 2) throw bad();
    LoadedList p;
    p.builds = static_cast<long>(*in++);
    if (*in++ == 0.0) {  // built before the checkpoint's step: how it was built
      if (end - in < 6) throw bad();
      p.built_step = static_cast<long>(*in++);
      p.moved_bound = *in++, p.since_break = *in++, p.break_room = *in++, p.room = *in++;
      const double changed = *in++;
      if (!(changed >= 0.0) || end - in < static_cast<long>(changed) + static_cast<long>(n_ * D)) throw bad();
      for (long k = 0; k < static_cast<long>(changed); ++k) {
        const double b = *in++;
        if (!(b >= 0.0 && b < static_cast<double>(alive_.size()))) throw bad();
        p.changed.push_back(static_cast<int>(b));
      }
      p.x.resize(n_);
      for (std::size_t i = 0; i < n_; ++i)
        for (int c = 0; c < D; ++c) p.x[i][c] = *in++;
    }
    loaded_list_ = std::move(p);
  }

  /// Pairs grouped by first particle (a counting sort).
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
  LawTable law_table_;  ///< laws_ for the vector sweep of several laws
  std::vector<int> phase_, pair_law_;
  std::size_t nphase_ = 1, n_ = 0;
  double cutoff_ = 0.0, inv_rmin_ = 0.0, r_min_ = 0.0, max_reach_ = 0.0, r0_ = 0.0;
  std::vector<double> contact_reach_;  ///< cm, per law: its equilibrium spacing (where contacts stop acting)
  std::vector<double> law_mass_;  ///< g: the lightest particle a law acts on (Eq. 15 takes the smallest m)
  bool uses_list_ = false;
  // the original bonds and their record
  std::vector<int> bi_, bj_;         ///< original bonds (i < j); their law: bond_law
  std::vector<std::uint8_t> alive_;  ///< bonded: intact; cutoff: within D
  std::unordered_map<std::size_t, double> phi_break_;  ///< erg: phi at the break, of the broken bonds (bonded)
  std::vector<BondEvent> events_;  ///< recorded since the last take_bond_events
  long broke_count_ = 0;           ///< bonds broken (cutoff model: pairs leaving D), over the whole run
  long re_formed_count_ = 0;       ///< cutoff model: pairs coming back within D
  long first_break_step_ = -1;
  double first_break_time_ = -1.0;
  // the Verlet list
  PairTable<D> list_;
  CellList<D> cells_;
  double skin_ = 0.0, skin_min_ = 0.0;  ///< cm: Verlet skin now, and its floor (the starting skin)
  double skin_max_ = 0.0;               ///< cm: the skin's ceiling
  long built_step_ = 0;                 ///< step of the last list build
  long list_builds_ = 0;
  double moved_bound_ = 0.0;  ///< cm: bound on any particle's residual (list_holds) since the last list build
  double since_break_ = 0.0;  ///< cm: bound on any particle's move since the first bond broke after the build
  double break_room_ = std::numeric_limits<double>::infinity();  ///< cm: shortest such pair at its break, less reach
  double room_ = 0.0;  ///< cm: twice the largest residual the list allows (the skin at the build; affine_residual)
  std::vector<double> x_build_;   ///< cm: positions (N x D) at the last list build
  std::vector<int> changed_since_build_;  ///< bonds whose state changed since the last list build, in order
  struct LoadedList {  ///< a loaded checkpoint's list, until renew_list (see list_saved_size)
    long builds = 0;
    long built_step = 0;  ///< the rest only if built before the checkpoint's step (x not empty)
    double moved_bound = 0.0, since_break = 0.0, break_room = 0.0, room = 0.0;
    std::vector<int> changed;
    AlignedVector<V> x;
  };
  std::optional<LoadedList> loaded_list_;
  std::vector<double> moved_of_;  ///< resident steps: each thread's copies of the list's bounds (a line each)
};

/// The two readings of the pair law (physics.md): each its own effect.
template <int D>
std::unique_ptr<Effect<D>> make_bonded_pair(const System& sys, const PairSpec& spec);
template <int D>
std::unique_ptr<Effect<D>> make_cutoff_pair(const System& sys, const PairSpec& spec);

}  // namespace pmfrag::detail

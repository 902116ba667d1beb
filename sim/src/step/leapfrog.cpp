#include "pmfrag/step/leapfrog.hpp"

#include "threads/load_balancer.hpp"
#include "threads/team.hpp"
#include "threads/thread_tuner.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace pmfrag {

namespace {

constexpr std::size_t line_doubles = 8;  // doubles in a cache line

struct Kick {
  long bad;     ///< components that moved more than the component limit (or are not finite)
  double max2;  ///< cm^2: the largest squared component move
};

// Eqs. (12)-(14) on the flat components [b, e) of the N x D arrays. A function of its own, not the body of
// the lambda handed to the thread team: inlined into the team's dispatch thunk, GCC 12 kept the reduction
// variables in memory, and the two-thread plate's pass took 15,000 cycles instead of 3,000 (measured); kept
// out of line so every caller runs the same, vectorized code.
// ZeroF: f is used up here (the next evaluation adds into zeros); otherwise the first fused force sets it.
// The positions are read from xin and written to xout (the same array, or the other of resident steps' two).
// Uniform: every component in [b, e) has the inverse mass uniform_inv_mass (the same arithmetic as reading it
// from inv_mass, one stream through the cache fewer).
template <bool ZeroF, bool Uniform>
[[gnu::noinline]] Kick kick_drift(const double* xin, double* xout, double* __restrict v, double* __restrict f,
                                  const double* __restrict inv_mass, double uniform_inv_mass, long b, long e, double h,
                                  double dt, double component_limit2) {
  long bad = 0;
  double max2 = 0.0;
#pragma omp simd reduction(+ : bad) reduction(max : max2)
  for (long j = b; j < e; ++j) {
    const double vj = v[j] + (h * (Uniform ? uniform_inv_mass : inv_mass[j])) * f[j];
    const double dx = dt * vj;
    v[j] = vj;
    xout[j] = xin[j] + dx;
    if constexpr (ZeroF) f[j] = 0.0;
    const double d2 = dx * dx;
    bad += !(d2 <= component_limit2);
    max2 = std::max(max2, d2);
  }
  return {bad, max2};
}

}  // namespace

template <int D>
State<D> initial_state(const System& sys) {
  const std::size_t n = sys.size();
  State<D> s;
  s.r0 = sys.r0;
  s.x.resize(n);
  s.v.resize(n);
  s.masses = ParticleMasses(sys.phase_mass, sys.phase);
  for (std::size_t i = 0; i < n; ++i) {
    s.x[i] = sys.position[i].head<D>();
    s.v[i] = sys.velocity[i].head<D>();
  }
  return s;
}

template <int D>
Leapfrog<D>::Leapfrog(const System& sys, std::vector<std::unique_ptr<Effect<D>>> effects, double dt, bool adaptive,
                      ThreadOptions threads)
    : Leapfrog(initial_state<D>(sys), std::move(effects), dt, adaptive, std::move(threads)) {}

template <int D>
Leapfrog<D>::Leapfrog(State<D> initial, std::vector<std::unique_ptr<Effect<D>>> effects, double dt, bool adaptive,
                      ThreadOptions threads)
    : s_(std::move(initial)), effects_(std::move(effects)), uniform_(!adaptive),
      threads_(std::make_unique<detail::Threads>(std::move(threads))),
      tuner_(std::make_unique<detail::ThreadTuner>(*threads_, s_.size())),
      balancer_(std::make_unique<detail::LoadBalancer>()) {
  const std::size_t n = s_.size();
  s_.dt = dt;
  s_.f.assign(n, V::Zero());
  for (auto& e : effects_) {
    const unsigned st = e->stages();
    if (st & stage::assigns_forces) {  // fused forces are computed before the others (plain_step)
      const bool first = fused_force_.empty() && ((st & stage::fused_force) || force_.empty());
      if (!first) throw std::logic_error(e->name() + ": only the effect whose forces come first can assign them");
      assigned_ = true;
    } else if ((st & stage::fused_force) && assigned_ && fused_force_.empty()) {
      throw std::logic_error(e->name() + ": its fused forces would come before those assigning the forces");
    }
    if (st & stage::fused_force) fused_force_.push_back(e.get());
    const bool local = (st & stage::local_force) != 0;
    if (st & (stage::force | stage::local_force)) force_.push_back({e.get(), local});
    if (st & (stage::resident | stage::local_force)) thread_forces_.push_back({e.get(), local});
    if (st & stage::after_move) after_move_.push_back(e.get());
    if (st & stage::observe) observe_.push_back(e.get());
    if (st & stage::step_limit) step_limit_.push_back(e.get());
    if (st & stage::resident) resident_.push_back(e.get());
    // steps run resident only if every effect that acts in a step can
    constexpr unsigned acts = stage::force | stage::after_move | stage::fused_force;
    if ((st & acts) && !(st & stage::resident)) resident_ok_ = false;
  }
  use_team();
  for (auto& e : effects_)
    if (e->stages() & stage::setup) e->setup(s_);
  // After setup: kinematic boundaries zero their particles' inverse mass. A body of one mass has two inverse
  // masses (its own and the boundaries' zero), in a few runs: the move then reads no array of them. Only if
  // the runs are short against a vector does it read one inverse mass per component.
  for (std::size_t i = 0; i < n; ++i) {
    const long b = static_cast<long>(i) * D;
    const double m = s_.masses.inv_mass(i);
    const bool same = !mass_runs_.empty() && mass_runs_.back().inv_mass == m &&
                      std::signbit(mass_runs_.back().inv_mass) == std::signbit(m);  // the same bits
    if (!same)
      mass_runs_.push_back({b, b + D, m});
    else
      mass_runs_.back().end = b + D;
  }
  if (mass_runs_.size() > 8 + n * D / 256) {
    mass_runs_.clear();
    inv_mass_dof_.resize(n * D);
    for (std::size_t j = 0; j < n * D; ++j) inv_mass_dof_[j] = s_.masses.inv_mass(j / D);
  }
  compute_forces();
}

template <int D>
Leapfrog<D>::Leapfrog(Leapfrog&&) noexcept = default;
template <int D>
Leapfrog<D>::~Leapfrog() = default;

template <int D>
const std::vector<long>& Leapfrog<D>::thread_steps() const {
  return tuner_->steps_with();
}

template <int D>
void Leapfrog<D>::set_thread_weights(std::vector<double> weights) {
  threads_->set_weights(std::move(weights));
}

// The team of the count the tuner chose, handed to the effects with the state.
template <int D>
detail::Team& Leapfrog<D>::use_team() {
  s_.team = &threads_->team(tuner_->count());
  return *s_.team;
}

template <int D>
void Leapfrog<D>::compute_forces() {
  std::fill(s_.f.begin(), s_.f.end(), V::Zero());
  for (auto* e : fused_force_) e->add_fused_forces(s_);
  add_forces();
}

// The force stage in attachment order. Consecutive local forces run in one pass of the team, each thread on
// its share, so they cost a hand-out together, not one each.
template <int D>
void Leapfrog<D>::add_forces() {
  for (std::size_t k = 0; k < force_.size();) {
    if (!force_[k].local) {
      force_[k++].effect->add_forces(s_);
      continue;
    }
    std::size_t end = k;
    while (end < force_.size() && force_[end].local) ++end;
    detail::Team& team = *s_.team;
    const std::vector<long>& b = team.bounds(static_cast<long>(s_.size()));
    const double* x = s_.x.front().data();
    team.run([&](int tid) {
      for (std::size_t j = k; j < end; ++j)
        force_[j].effect->local_forces(s_, x, b[static_cast<std::size_t>(tid)], b[static_cast<std::size_t>(tid) + 1]);
    });
    k = end;
  }
}

template <int D>
double Leapfrog<D>::step_limit() const {
  double limit = std::numeric_limits<double>::infinity();
  for (auto* e : step_limit_) limit = std::min(limit, e->step_limit(s_));
  return limit;
}

template <int D>
void Leapfrog<D>::step(double dt) {
  tuner_->before_step();
  const int threads = plain_step(dt);
  tuner_->after_step(threads);
}

// Eq. (12): V_1/2 = V_0 + (dt/2) a_0;  Eq. (13): V_k+1/2 = V_k-1/2 + dt a_k;  Eq. (14): r_k+1 = r_k + dt V_k+1/2.
// One pass over thread tid's share of the flat N x D arrays, so it vectorizes without gathers. The guard is
// checked per component first: no component moving more than r0 / (2 sqrt(D)) means no particle moves
// more than r0/2 (NaN fails the test too); only if some component does, the exact per-particle check of
// finish_step decides. The largest component move gives sqrt(D) x it as the bound the neighbour lists use.
// Each thread writes its count and largest move to a cache line of its own in moves_.
template <int D>
void Leapfrog<D>::move(int tid, const std::vector<long>& share, double h, double dt, const double* xin, double* xout) {
  const double component_limit2 = 0.25 * s_.r0 * s_.r0 / D;
  const long first = share[static_cast<std::size_t>(tid)], last = share[static_cast<std::size_t>(tid) + 1];
  double* v = s_.v.front().data();
  double* f = s_.f.front().data();
  const long b = first * D, e = last * D;
  Kick k{0, 0.0};
  if (mass_runs_.empty()) {
    k = (assigned_ ? kick_drift<false, false> : kick_drift<true, false>)(xin, xout, v, f, inv_mass_dof_.data(), 0.0, b,
                                                                          e, h, dt, component_limit2);
  } else {
    const auto kick = assigned_ ? kick_drift<false, true> : kick_drift<true, true>;
    auto run = std::upper_bound(mass_runs_.begin(), mass_runs_.end(), b,
                                [](long j, const MassRun& r) { return j < r.end; });  // the run holding b
    for (; run != mass_runs_.end() && run->begin < e; ++run) {
      const Kick part = kick(xin, xout, v, f, nullptr, run->inv_mass, std::max(b, run->begin), std::min(e, run->end),
                             h, dt, component_limit2);
      k.bad += part.bad;
      k.max2 = std::max(k.max2, part.max2);  // the largest of the parts' largest: the same number
    }
  }
  double* slot = moves_.data() + static_cast<std::size_t>(tid) * line_doubles;
  slot[0] = k.max2;
  slot[1] = static_cast<double>(k.bad);
}

// The last move over all threads: components that failed the guard's test, the largest squared move.
template <int D>
std::pair<long, double> Leapfrog<D>::moved(int threads) const {
  long bad = 0;
  double max2 = 0.0;
  for (int t = 0; t < threads; ++t) {
    const double* slot = moves_.data() + static_cast<std::size_t>(t) * line_doubles;
    max2 = std::max(max2, slot[0]);
    bad += static_cast<long>(slot[1]);
  }
  return {bad, max2};
}

template <int D>
int Leapfrog<D>::plain_step(double dt) {
  const long n = static_cast<long>(s_.size());
  if (dt != s_.dt) uniform_ = false;
  const double h = s_.step == 0 ? 0.5 * dt : 0.5 * (s_.dt + dt);  // == dt exactly for equal steps
  detail::Team& team = use_team();
  const int threads = team.size();
  moves_.resize(static_cast<std::size_t>(threads) * line_doubles, 0.0);
  const std::vector<long>& share = team.bounds(n);
  // The move is handed to the team's next pass: the fused forces' (the bonds') if any, so the two cost one
  // hand-out (team.hpp). Each thread moves its own share, the particles whose forces it assembles.
  double* x = s_.x.front().data();
  auto kick = [&](int tid) { move(tid, share, h, dt, x, x); };
  team.defer(kick);
  try {
    for (auto* e : fused_force_) e->add_fused_forces(s_);
  } catch (...) {
    team.discard();  // the kick lives in this frame
    throw;
  }
  team.flush();
  finish_step(dt, threads);
  return threads;
}

// The rest of a step once the particles have moved and the fused forces are in: the guard, the clock,
// after_move, the other forces.
template <int D>
void Leapfrog<D>::finish_step(double dt, int threads) {
  const auto [bad, max2] = moved(threads);
  if (bad > 0) {
    for (std::size_t i = 0; i < s_.size(); ++i) {
      const double move = dt * s_.v[i].norm();
      if (!(move <= 0.5 * s_.r0)) {
        std::ostringstream msg;
        msg << "unstable: particle " << i << " at step " << s_.step << " (t = " << s_.time() << " s) ";
        if (!std::isfinite(move))
          msg << "has a non-finite velocity";
        else
          msg << "would move " << move << " cm in one step (more than r0/2 = " << 0.5 * s_.r0 << " cm)";
        msg << "; reduce dt (now " << dt << " s) or check the scene";
        throw GuardError(msg.str(), s_.step, s_.time(), static_cast<long>(i));
      }
    }
  }
  ++s_.step;
  s_.dt = dt;
  s_.t = uniform_ ? static_cast<double>(s_.step) * dt : s_.t + dt;
  const double max_step = std::sqrt(D * max2);
  for (auto* e : after_move_) e->after_move(s_, max_step);
  add_forces();  // f holds the fused forces (added to the zeros the move left, or set by them)
}

template <int D>
long Leapfrog<D>::advance(long steps) {
  long k = 0;
  while (k < steps) {
    long room = std::min(tuner_->before_steps(), steps - k);
    detail::Team& team = use_team();
    long took = 0;
    if (team.size() > 1 && resident_ok_ && uniform_ && s_.step > 0) {
      room = std::min(room, std::max(1L, balancer_->room()));
      took = resident_steps(team, room);
    } else {
      for (; took < room; ++took) plain_step(s_.dt);
    }
    tuner_->after_steps(team.size(), took);
    k += took;
  }
  return k;
}

// Up to `steps` steps in one pass of the team (effects.hpp, "Resident steps"): a hand-out and the wait for
// the workers cost 0.7-1.2 us between this VM's virtual cores and a step of the plate on two threads is
// ~5 us of work; and nothing runs on one thread alone between steps, so no core reads the others' particles
// but at the edges of its share. One barrier a step, after the move. Before it, a thread has computed its
// particles' complete forces (the effects' resident_forces need no other thread) and moved them; after it,
// every thread knows every move and the events of the forces before it, and reads the others' new
// positions. Positions alternate between s.x and a second buffer (a step reads one and writes the other),
// so a thread may move on while another still reads the last positions. The move's guard or a due list
// (after a barrier) or a broken bond (known at the next barrier, after the next move, which is the same
// whatever the bond: it was already too long to pull) ends the block; the step is finished on the plain
// path. Each thread's busy time goes to the load balancer. Returns the steps taken (at least one).
template <int D>
long Leapfrog<D>::resident_steps(detail::Team& team, long steps) {
  const long n = static_cast<long>(s_.size());
  const int threads = team.size();
  const double dt = s_.dt;
  const std::vector<long>& share = team.bounds(n);
  for (auto* e : resident_)
    if (!e->resident_begin(s_, share)) {
      plain_step(dt);
      return 1;
    }
  moves_.resize(static_cast<std::size_t>(threads) * line_doubles, 0.0);
  busy_.assign(static_cast<std::size_t>(threads) * line_doubles, 0.0);
  x_alt_.resize(s_.size());
  double* const x[2] = {s_.x.front().data(), x_alt_.front().data()};  // step j reads x[j & 1]
  long done = 0;  // steps whose forces are complete (written by thread 0)
  enum class End { all, due, events } end = End::all;  // written by thread 0
  const auto steps_of = [&](int tid) -> std::uint64_t {  // returns the thread's busy time (not its waits)
    std::uint64_t busy = 0;
    double found = 0.0;  // bonds the thread's last forces found too long
    for (long j = 0;; ++j) {
      double* slot = moves_.data() + static_cast<std::size_t>(tid) * line_doubles;
      if (j < steps) {
        const std::uint64_t t0 = detail::busy_clock();
        move(tid, share, dt, dt, x[j & 1], x[(j + 1) & 1]);
        busy += detail::busy_clock() - t0;
      } else {
        slot[0] = slot[1] = 0.0;  // no move: only the last forces' events are exchanged
      }
      slot[2] = found;
      team.barrier(tid, slot, 3);  // the move's largest squared component, bad count and events go with it
      // every thread reads the same numbers and so decides alike
      long bad = 0;
      double max2 = 0.0, events = 0.0;
      for (int t = 0; t < threads; ++t) {
        const double* in = team.published(t, tid);
        max2 = std::max(max2, in[0]);
        bad += static_cast<long>(in[1]);
        events += in[2];
      }
      if (events > 0.0) {  // the forces at x[j & 1] broke bonds: settle them there, then finish step j
        if (tid == 0) end = End::events;
        return busy;
      }
      if (j == steps) return busy;
      const double max_step = std::sqrt(D * max2);
      bool due = bad > 0;
      for (auto* e : resident_) due = due || e->resident_due(s_, max_step, tid);
      if (due) {
        if (tid == 0) end = End::due;
        return busy;
      }
      const std::uint64_t t0 = detail::busy_clock();
      long mine = 0;
      for (auto* e : resident_) e->resident_moved(max_step, tid);
      const long first = share[static_cast<std::size_t>(tid)], last = share[static_cast<std::size_t>(tid) + 1];
      for (const ForceEffect& e : thread_forces_) {  // in attachment order, as add_forces
        if (e.local)
          e.effect->local_forces(s_, x[(j + 1) & 1], first, last);
        else
          mine += e.effect->resident_forces(s_, x[(j + 1) & 1], tid);
      }
      for (auto* e : resident_) e->resident_gather(s_, tid);
      busy += detail::busy_clock() - t0;
      found = static_cast<double>(mine);
      if (tid == 0) done = j + 1;  // the clock is advanced after the block: its line is read by every move
    }
  };
  team.run([&](int tid) { busy_[static_cast<std::size_t>(tid) * line_doubles] = static_cast<double>(steps_of(tid)); });
  // s.x holds the positions of the last step whose forces are complete
  if (done & 1) std::swap(s_.x, x_alt_);
  s_.step += done;
  resident_taken_ += done;
  s_.t = static_cast<double>(s_.step) * dt;
  balancer_->add(team, share, busy_.data(), line_doubles, done);
  for (auto* e : resident_) e->resident_end(s_);
  if (end == End::events) {
    for (auto* e : resident_) e->resident_settle(s_);  // the bonds to retire, at the positions that broke them
    if (done == steps) return done;                    // (found after the last step: no move followed)
  }
  if (end != End::all) {  // step done + 1 moved, nothing else: the plain path's forces, guard and after_move
    std::swap(s_.x, x_alt_);
    for (auto* e : fused_force_) e->add_fused_forces(s_);
    finish_step(dt, threads);
    return done + 1;
  }
  return done;
}

template <int D>
void Leapfrog<D>::whole_step_velocity(std::vector<V>& out) const {
  out.resize(s_.size());
  whole_step_velocity(0, s_.size(), out.data()->data());
}

template <int D>
void Leapfrog<D>::whole_step_velocity(std::size_t first, std::size_t count, double* out) const {
  const double h = s_.step == 0 ? 0.0 : 0.5 * s_.dt;
  for (std::size_t i = first; i < first + count; ++i)
    Eigen::Map<V>(out + (i - first) * D) = s_.v[i] + (h * s_.masses.inv_mass(i)) * s_.f[i];
}

template <int D>
Observables Leapfrog<D>::observe() const {
  Observables o;
  // The whole-step velocities of whole_step_velocity, one at a time (no N-long array for a sum).
  const double h = s_.step == 0 ? 0.0 : 0.5 * s_.dt;
  double ke = 0.0;
  for (std::size_t i = 0; i < s_.size(); ++i) {
    const V v = s_.v[i] + (h * s_.masses.inv_mass(i)) * s_.f[i];
    ke += 0.5 * s_.masses.mass(i) * v.squaredNorm();
  }
  o.kinetic = ke;
  for (auto* e : observe_) e->observe(s_, o);
  return o;
}

template <int D>
void Leapfrog<D>::canonicalize() {
  use_team();
  for (auto& e : effects_) e->canonicalize(s_);
  compute_forces();
}

template <int D>
std::vector<double> Leapfrog<D>::effect_state() const {
  std::vector<double> out;
  std::size_t size = 0;  // one allocation: at millions of bonds, growth by doubling held up to 3x the state
  for (const auto& e : effects_) size += e->saved_size(s_);
  out.reserve(size);
  for (const auto& e : effects_) e->save(s_, out);
  assert(out.size() == size && "an effect's saved_size() disagrees with its save()");
  return out;
}

template <int D>
void Leapfrog<D>::restore(long step, double time, double dt, const std::vector<double>& x, const std::vector<double>& v,
                          const std::vector<double>& effects) {
  if (x.size() != s_.size() * D || v.size() != x.size())
    throw std::runtime_error("checkpoint does not match the scene (particle count or dimension)");
  s_.step = step;
  s_.t = time;  // for uniform steps the checkpoint holds exactly step x dt
  s_.dt = dt;
  for (std::size_t i = 0; i < s_.size(); ++i)
    for (int d = 0; d < D; ++d) s_.x[i][d] = x[i * D + d], s_.v[i][d] = v[i * D + d];
  const double* in = effects.data();
  const double* end = in + effects.size();
  for (auto& e : effects_) e->load(in, end);
  if (in != end) throw std::runtime_error("checkpoint does not match the scene (effects)");
  canonicalize();
}

template class Leapfrog<2>;
template class Leapfrog<3>;
template State<2> initial_state<2>(const System&);
template State<3> initial_state<3>(const System&);

}  // namespace pmfrag

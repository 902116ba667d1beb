// Effects: the pieces of physics a scene attaches. Each declares the stages of a step it takes part in and
// the integrator calls only those (cf. LAMMPS fixes' setmask); an effect the scene does not declare is never
// built, so it costs nothing.
#pragma once

#include "pmfrag/kernels/aligned.hpp"
#include "pmfrag/body/system.hpp"
#include "pmfrag/threads/threads.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace pmfrag {

namespace detail {
class Team;
}

/// The particles' masses as a few kinds, a byte a particle instead of two doubles (16 B at millions of
/// particles): a kind per phase, and one per phase for particles whose motion is prescribed (inverse mass 0).
class ParticleMasses {
 public:
  ParticleMasses() = default;
  /// particle i has the mass of phase phase_of[i] [g]
  ParticleMasses(const std::vector<double>& phase_mass, const std::vector<int>& phase_of) {
    if (phase_mass.size() > 128) throw std::invalid_argument("more than 128 phases");
    for (const double m : phase_mass) mass_.push_back(m), inv_.push_back(1.0 / m);
    kind_.reserve(phase_of.size());
    for (const int p : phase_of) kind_.push_back(static_cast<std::uint8_t>(p));
  }
  double mass(std::size_t i) const { return mass_[kind_[i]]; }        ///< g
  double inv_mass(std::size_t i) const { return inv_[kind_[i]]; }     ///< 1/g; 0 if prescribed
  /// Particle i's motion is prescribed (a kinematic boundary): its inverse mass becomes 0, its mass stays.
  void prescribe(std::size_t i) {
    const double m = mass(i);
    std::size_t k = 0;
    while (k < mass_.size() && !(inv_[k] == 0.0 && mass_[k] == m)) ++k;
    if (k == mass_.size()) mass_.push_back(m), inv_.push_back(0.0);
    kind_[i] = static_cast<std::uint8_t>(k);
  }
  std::size_t size() const { return kind_.size(); }

 private:
  std::vector<std::uint8_t> kind_;
  std::vector<double> mass_, inv_;  ///< per kind
};

template <int D>
struct State {
  using V = Eigen::Matrix<double, D, 1>;
  // On whole cache lines: the threads' shares of a step start on multiples of 64 particles, so with the
  // arrays aligned no line holds two threads' particles (with std::allocator's 16 bytes, each share's
  // boundary line of x, v and f went back and forth between the cores every step).
  AlignedVector<V> x;  ///< positions r_k [cm]
  AlignedVector<V> v;  ///< velocities: v_0 before the first step, then the half-step v_{k-1/2} [cm/s]
  AlignedVector<V> f;  ///< forces at r_k [dyne]
  ParticleMasses masses;  ///< g; inverse 0 for particles whose motion is prescribed (kinematic)
  long step = 0;
  double dt = 0.0;  ///< s: the step that led to r_k (fixed steps: every step)
  double t = 0.0;   ///< s: the time of r_k
  double r0 = 0.2;  ///< cm
  /// The thread team of this step, set by the integrator before it calls the effects (its count is the
  /// integrator's ThreadOptions and tuner, not process-wide state); effects split their work on it.
  detail::Team* team = nullptr;
  double time() const { return t; }
  std::size_t size() const { return x.size(); }
};

/// Tallied only on output steps (energies) or accumulated by the effects that own them.
struct Observables {
  double kinetic = 0.0;            ///< erg
  double potential = 0.0;          ///< erg (pair law summed over interacting pairs and contacts)
  double boundary_work = 0.0;      ///< erg done on the body by kinematic boundaries
  double bond_break_energy = 0.0;  ///< erg: sum of phi(r) of bonds at the step they broke
  long pairs_beyond_cutoff = 0;    ///< original bonds now longer than D (bonded: the broken ones)
  /// Conserved without damping or gravity: kinetic + potential + bond_break_energy - boundary_work.
  double balance() const { return kinetic + potential + bond_break_energy - boundary_work; }
};

namespace stage {
inline constexpr unsigned setup = 1u << 0;       ///< once, before the first force evaluation
inline constexpr unsigned force = 1u << 1;       ///< add forces at r_k (in attachment order; pair first)
inline constexpr unsigned after_move = 1u << 2;  ///< after r_{k+1} is known (neighbour lists)
inline constexpr unsigned observe = 1u << 3;     ///< contribute to Observables on output steps
inline constexpr unsigned step_limit = 1u << 4;  ///< bound the next step (called only for dt = "adaptive")
/// forces at r_k that read only positions and the effect's own state, not what after_move maintains (the
/// bonds of the bonded model): evaluated before the other stages, in the same thread-team pass as the move
inline constexpr unsigned fused_force = 1u << 5;
/// the effect's work in quiet steps can also run inside one thread-team pass over many steps
/// (Leapfrog::advance), through the resident_* calls; an attached effect without it keeps every step on the
/// plain path (one team pass per step, the serial stages between)
inline constexpr unsigned resident = 1u << 6;
/// for the effect whose forces come first in a step (the first fused-force effect, or the first force effect
/// if no effect has fused forces): its forces set every particle's force (f = 0 + its forces) instead of
/// adding to it, so the move need not zero f first (one stream through memory fewer)
inline constexpr unsigned assigns_forces = 1u << 7;
/// forces on each particle from that particle alone (its mass, position, velocity and the forces added
/// before it): written once, as local_forces over a range of particles, and run by every thread on its own
/// share in plain and resident steps alike, in attachment order among the other forces. Needs no other stage.
inline constexpr unsigned local_force = 1u << 8;
}  // namespace stage

/// A change in the state of an original bond (a row of System::bonds), recorded by the pair effect at the
/// step it happens and written to the trajectory (/connectivity/broken_bonds).
/// Bonded model: the bond broke (longer than D) and is gone for good. Cutoff model: the pair left D (it no
/// longer interacts), or came back within D (re_formed: it interacts again).
struct BondEvent {
  long step = 0;       ///< the first step whose positions show the change
  double time = 0.0;   ///< s, of that step
  long bond = 0;       ///< row of /connectivity/bonds
  bool re_formed = false;
  bool operator==(const BondEvent&) const = default;
};

/// What a pair effect reports of the original bonds and its neighbour list (for run.json and tests).
template <int D>
struct BondView {
  /// per original bond: intact (bonded model) or within D (cutoff model)
  const std::vector<std::uint8_t>* alive = nullptr;
  bool cutoff_model = false;
  long first_break_step = -1;      ///< the first bond broken / pair leaving D
  double first_break_time = -1.0;  ///< s
  long broke = 0;                  ///< bonds broken (cutoff model: times a pair left D)
  long re_formed = 0;              ///< cutoff model: times a pair came back within D
  long list_builds = 0;  ///< neighbour-list builds since the run (or its resume) started; 0 if it keeps no list
  double skin = 0.0;     ///< cm: the Verlet skin now (it adapts; see step/pair_base.hpp)
};
template <int D>
class Effect {
 public:
  using V = Eigen::Matrix<double, D, 1>;
  virtual ~Effect() = default;
  virtual std::string name() const = 0;
  virtual unsigned stages() const = 0;
  virtual void setup(State<D>&) {}
  virtual void add_forces(State<D>&) {}
  /// stage::local_force: the forces on particles [first, last) at the positions x (N x D; s.x's outside
  /// resident steps), added to (or applied to) s.f. Called by one thread per range; touches nothing else.
  virtual void local_forces(State<D>&, const double* /*x*/, long /*first*/, long /*last*/) {}
  /// stage::fused_force: adds forces at r_k (already moved to, but s.step, s.t not yet advanced; may run
  /// on positions the guard then rejects, so it changes nothing but s.f and buffers of its own: what
  /// follows from those forces, e.g. retiring broken bonds, waits for add_forces).
  virtual void add_fused_forces(State<D>&) {}

  // Resident steps (stage::resident). The team's threads run the steps of a block together, thread t on its
  // particles [bounds[t], bounds[t + 1]); per step: the move, a barrier, resident_due, resident_moved,
  // resident_forces and resident_gather. One barrier a step: the positions are kept in two buffers (a step
  // reads one and writes the other), so no thread overwrites positions another may still read, and each
  // thread completes its own particles' forces without waiting for the others. A step in which something
  // happens (a bond breaks, a list may be due) leaves the block and is finished on the plain path, so the
  // trajectory is bitwise the one step() gives. s.step and s.t stay at the block's start until it ends.
  /// Before a block, outside the team: ready the threads' work; false if the next step must be plain.
  virtual bool resident_begin(State<D>&, const std::vector<long>& /*bounds*/) { return false; }
  /// Every thread alike, after the move (max_step as for after_move): true if this step needs the plain
  /// after_move (a list may be due). Changes nothing.
  virtual bool resident_due(const State<D>&, double /*max_step*/, int /*tid*/) const { return false; }
  /// Every thread, if no effect was due: record what after_move would have (in the thread's own copy).
  virtual void resident_moved(double /*max_step*/, int /*tid*/) {}
  /// Thread tid: the complete forces on its particles at the positions x (N x D; not s.x's during a block),
  /// with no other thread's help; returns the events (bonds found too long) the plain add_forces must
  /// settle. Thread tid's part of add_forces otherwise.
  virtual long resident_forces(State<D>&, const double* /*x*/, int /*tid*/) { return 0; }
  /// Thread tid, after every effect's resident_forces on its particles: what reads their complete forces.
  virtual void resident_gather(State<D>&, int /*tid*/) {}
  /// After the block, outside the team (s.step advanced past its steps): keep what the threads recorded
  /// (e.g. the moved bound), tally its steps in order (e.g. the boundary's work).
  virtual void resident_end(State<D>&) {}
  /// For a step that ended the block with events: settle them as add_forces would.
  virtual void resident_settle(State<D>&) {}

  /// `max_step` bounds how far any particle moved in this step [cm] (a cheap bound for Verlet lists).
  virtual void after_move(State<D>&, double /*max_step*/) {}
  virtual void observe(const State<D>&, Observables&) const {}
  /// The Eq. (15) limit [s] for the configuration at r_k (adaptive steps only).
  virtual double step_limit(const State<D>&) const { return std::numeric_limits<double>::infinity(); }
  /// Make the next force evaluation independent of history (e.g. rebuild neighbour lists now), so a run
  /// resumed from this step is bitwise identical to one that never stopped.
  virtual void canonicalize(const State<D>&) {}
  /// History an effect carries between steps (broken bonds, tallied work), appended as doubles for a
  /// checkpoint of the state s, and read back in the same order.
  virtual void save(const State<D>& /*s*/, std::vector<double>&) const {}
  /// How many values save(s, ...) appends (a hint for one allocation).
  virtual std::size_t saved_size(const State<D>& /*s*/) const { return 0; }
  /// Reads what save() appended from [in, end), advancing in; throws std::runtime_error if it does not fit.
  virtual void load(const double*& /*in*/, const double* /*end*/) {}

  /// Reports: what the effect knows of the original bonds (the pair effects; others report nothing), and
  /// the bond events recorded since the last call, moved to the end of `out` in step order.
  virtual BondView<D> bond_view() const { return {}; }
  virtual void take_bond_events(std::vector<BondEvent>&) {}
};

/// The pair effect's report, if `e` is one (else an empty view).
template <int D>
BondView<D> bond_view(const Effect<D>& e) {
  return e.bond_view();
}
/// Moves the bond events `e` recorded since the last call to the end of `out`, in step order.
template <int D>
void take_bond_events(Effect<D>& e, std::vector<BondEvent>& out) {
  e.take_bond_events(out);
}

/// The effects a scene declares, in the order the integrator calls them: pair, greenspan_alpha, gravity,
/// damping, kinematic. (The impactor sets initial velocities when the System is built.)
template <int D>
std::vector<std::unique_ptr<Effect<D>>> make_effects(const System& sys, const Scene& scene);

}  // namespace pmfrag

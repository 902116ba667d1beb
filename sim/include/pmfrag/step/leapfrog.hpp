// Leapfrog integration exactly as Eqs. (12)-(14), with a stability guard: a non-finite value or a particle
// moving more than r0/2 in one step stops the run with an error naming particle, step and time.
#pragma once

#include "pmfrag/step/effects.hpp"

#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

namespace pmfrag {

namespace detail {
class Threads;
class ThreadTuner;
class LoadBalancer;
class Team;
}

struct GuardError : std::runtime_error {
  GuardError(const std::string& what, long step_, double time_, long particle_)
      : std::runtime_error(what), step(step_), time(time_), particle(particle_) {}
  long step;
  double time;
  long particle;
};

/// The System's particles at t = 0 (positions, velocities, masses) as an integrator's state.
template <int D>
State<D> initial_state(const System& sys);

template <int D>
class Leapfrog {
 public:
  using V = Eigen::Matrix<double, D, 1>;

  /// Takes the System's particles at t = 0, runs the effects' setup, and evaluates forces at r_0.
  /// `adaptive`: steps will vary (dt = "adaptive"), so time is summed rather than step x dt.
  /// `threads`: how the steps use threads (the count, whether it is measured, the shares).
  Leapfrog(const System& sys, std::vector<std::unique_ptr<Effect<D>>> effects, double dt, bool adaptive = false,
           ThreadOptions threads = {});
  /// The same from the System's particles already taken (initial_state), so the System can go first.
  Leapfrog(State<D> initial, std::vector<std::unique_ptr<Effect<D>>> effects, double dt, bool adaptive = false,
           ThreadOptions threads = {});
  Leapfrog(Leapfrog&&) noexcept;
  ~Leapfrog();

  /// One step k -> k+1: Eq. (12) at k = 0 (starter half step), Eq. (13) after, and Eq. (14) in one pass;
  /// then forces at r_{k+1}, so forces are always those of the current positions between steps.
  void step() { step(s_.dt); }
  /// The same with a step of its own (dt = "adaptive"): the kick spans half of the previous step and half
  /// of this one, v_k+1/2 = v_k-1/2 + (dt_k-1 + dt_k)/2 a_k, which is Eq. (13) when the two are equal.
  void step(double dt);
  /// `steps` steps of the fixed dt, the same as calling step() that often: quiet steps of scenes whose
  /// effects all allow it run many to one pass of the thread team (Effect's resident steps). Returns steps.
  long advance(long steps);
  /// The smallest Eq. (15) limit the attached effects report for the present configuration [s].
  double step_limit() const;

  /// Whole-step velocities v_k = v_{k-1/2} + (dt/2) a_k (v_0 at k = 0), as written to frames.
  void whole_step_velocity(std::vector<V>& out) const;
  /// The same for particles [first, first + count), into out (count x D).
  void whole_step_velocity(std::size_t first, std::size_t count, double* out) const;
  /// Energies and tallies at the current step (serial sums: the same for any thread count).
  Observables observe() const;

  /// Make the next step independent of list history (see Effect::canonicalize); used at checkpoints.
  void canonicalize();

  /// Every effect's history, for a checkpoint.
  std::vector<double> effect_state() const;
  /// Continue from a checkpoint: step, positions r_k, half-step velocities v_k-1/2 and effect history; lists
  /// are rebuilt and forces evaluated exactly as canonicalize() did when the checkpoint was taken.
  void restore(long step, double time, double dt, const std::vector<double>& x, const std::vector<double>& v,
               const std::vector<double>& effects);

  State<D>& state() { return s_; }
  const State<D>& state() const { return s_; }
  const std::vector<std::unique_ptr<Effect<D>>>& effects() const { return effects_; }
  /// Steps taken on each thread count (index: threads); the count is measured, not fixed (thread_tuner.hpp).
  const std::vector<long>& thread_steps() const;
  /// Fixed shares of the particles for teams of weights.size() threads from the next step on (tests move
  /// them between blocks of steps; results do not depend on them); empty: measured shares.
  void set_thread_weights(std::vector<double> weights);
  /// Steps that ran inside resident blocks (many steps to one pass of the team), not on the plain path.
  long resident_steps_taken() const { return resident_taken_; }

 private:
  detail::Team& use_team();  ///< the team for the next step (the tuner's count), set in s_.team
  void compute_forces();  ///< all forces at r_k, from zero
  void add_forces();      ///< the force stage (stage::force and stage::local_force effects, in order)
  /// Thread tid's share of the move, positions read from xin and written to xout (may be the same).
  void move(int tid, const std::vector<long>& share, double h, double dt, const double* xin, double* xout);
  int plain_step(double dt);  ///< one step, one team pass (returns the threads used)
  std::pair<long, double> moved(int threads) const;
  void finish_step(double dt, int threads);
  long resident_steps(detail::Team& team, long steps);
  State<D> s_;
  std::vector<std::unique_ptr<Effect<D>>> effects_;
  std::vector<Effect<D>*> fused_force_, after_move_, observe_, step_limit_;
  /// 1/g per degree of freedom (N x D), for the flat update pass; only if mass_runs_ is empty
  std::vector<double> inv_mass_dof_;
  /// Runs of degrees of freedom [begin, end) sharing one 1/g (g^-1), ascending; empty if there are too many
  /// (then the move reads inv_mass_dof_)
  struct MassRun {
    long begin, end;
    double inv_mass;
  };
  std::vector<MassRun> mass_runs_;
  AlignedVector<double> moves_;  ///< per thread, a cache line: the last move's largest squared component, bad
                               ///< count (and, in resident steps, the events its last forces found)
  std::vector<Effect<D>*> resident_;
  struct ForceEffect {
    Effect<D>* effect;
    bool local;  ///< stage::local_force
  };
  /// the force stage (stage::force or stage::local_force), in attachment order
  std::vector<ForceEffect> force_;
  /// resident steps: the effects whose forces a thread computes on its share (resident or local), in order
  std::vector<ForceEffect> thread_forces_;
  bool resident_ok_ = true;     ///< every effect acting in a step has resident steps
  bool assigned_ = false;       ///< the step's first forces set f (stage::assigns_forces): the move keeps it
  long resident_taken_ = 0;  ///< steps completed inside resident blocks
  bool uniform_ = true;  ///< every step so far had the same dt: time = step x dt exactly
  std::unique_ptr<detail::Threads> threads_;     ///< this integrator's thread teams
  std::unique_ptr<detail::ThreadTuner> tuner_;  ///< how many threads each step runs on
  std::unique_ptr<detail::LoadBalancer> balancer_;  ///< each thread's share of the particles
  AlignedVector<double> busy_;  ///< per thread, a cache line: its busy time in the last resident steps
  AlignedVector<V> x_alt_;    ///< resident steps: the positions' second buffer
};

}  // namespace pmfrag

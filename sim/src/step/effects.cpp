// The effects besides the pair law. Each is attached only when the scene declares it.
#include "pmfrag/step/effects.hpp"

#include "step/pair_base.hpp"
#include "threads/team.hpp"

#include <algorithm>
#include <stdexcept>
#include <cmath>
#include <functional>

namespace pmfrag {

namespace {

template <int D>
Eigen::Matrix<double, D, 1> head(const Vec3& v) {
  return v.head<D>();
}

/// Kinematic boundary (Sec. 4.2): selected particles move at a prescribed velocity whatever the forces.
/// They get velocity u and zero inverse mass, so leapfrog keeps them at u (like LAMMPS' velocity set + fix
/// setforce). The work the boundary does: its force on particle i is -f_i, so dW/dt = g = -sum f_i . u; the
/// sum over steps uses the trapezoid rule, which is what leapfrog's second-order energy balance needs.
/// Runs last among the force effects, so f_i is the complete force.
template <int D>
class Kinematic final : public Effect<D> {
 public:
  using V = Eigen::Matrix<double, D, 1>;
  Kinematic(const System& sys, const KinematicSpec& spec, std::size_t index)
      : u_(head<D>(spec.velocity)),
        index_(select_particles(sys, spec.select, "kinematic[" + std::to_string(index) + "].select")) {
    // g is summed by blocks of share_grain particles, each block in index order, then the blocks in order:
    // the thread owning a block can sum it in a resident step (the team's shares are whole blocks), and g
    // has the same bits whoever summed which block.
    std::sort(index_.begin(), index_.end());
    for (std::size_t k = 0; k < index_.size(); ++k) {
      const long block = index_[k] / detail::share_grain;
      if (block_.empty() || block_.back() != block) block_.push_back(block), block_from_.push_back(k);
    }
    block_from_.push_back(index_.size());
    partial_.assign(block_.size() * 8, 0.0);  // a cache line per block: written by its thread
  }
  std::string name() const override { return "kinematic"; }
  unsigned stages() const override { return stage::setup | stage::force | stage::observe | stage::resident; }
  void setup(State<D>& s) override {
    for (int i : index_) s.v[static_cast<std::size_t>(i)] = u_, s.masses.prescribe(static_cast<std::size_t>(i));
  }
  // A plain step is a resident block of one step on one thread: the tally is written once.
  void add_forces(State<D>& s) override {
    whole_[1] = static_cast<long>(s.size());
    resident_begin(s, whole_);
    resident_gather(s, 0);
    resident_end(s);
  }
  // Resident steps: each thread keeps its blocks' g of every step, and the steps are tallied in order once the
  // block of steps is over (resident_end). Read by one thread every step, the other threads' sums cost it a
  // transfer between cores each (~0.2 us on this VM) before it could go on.
  bool resident_begin(State<D>&, const std::vector<long>& bounds) override {
    bounds_ = bounds;  // (assigned into its capacity: no allocation after the first block)
    if (history_.size() != block_.size()) {
      history_.resize(block_.size());
      for (auto& h : history_) h.g.reserve(1024);
    }
    for (auto& h : history_) h.g.clear();
    return true;
  }
  void resident_gather(State<D>& s, int tid) override {
    const long lo = bounds_[static_cast<std::size_t>(tid)], hi = bounds_[static_cast<std::size_t>(tid) + 1];
    for (std::size_t b = 0; b < block_.size(); ++b)
      if (block_[b] * detail::share_grain >= lo && block_[b] * detail::share_grain < hi)
        history_[b].g.push_back(block_power(s, b));
  }
  void resident_end(State<D>& s) override {
    // the steps whose forces every thread gathered: s.step - k + 1 ... s.step. A step already tallied (forces
    // evaluated again at the same step, at a checkpoint) counts once.
    const std::size_t k = history_.empty() ? 0 : history_.front().g.size();
    for (std::size_t j = 0; j < k; ++j) {
      const long step = s.step - static_cast<long>(k - 1 - j);
      for (std::size_t b = 0; b < block_.size(); ++b) partial_[b * 8] = history_[b].g[j];
      if (step != tallied_step_) tally(step, s.dt);
    }
    for (auto& h : history_) h.g.clear();
  }
  void observe(const State<D>& s, Observables& o) const override {
    o.boundary_work += left_sum_ + 0.5 * s.dt * (g_ - g0_);
  }
  void save(const State<D>&, std::vector<double>& out) const override {
    out.insert(out.end(), {left_sum_, g0_, g_, static_cast<double>(tallied_step_)});
  }
  std::size_t saved_size(const State<D>&) const override { return 4; }
  void load(const double*& in, const double* end) override {
    if (end - in < 4) throw std::runtime_error("checkpoint does not match the scene (boundary work)");
    left_sum_ = *in++, g0_ = *in++, g_ = *in++;
    tallied_step_ = static_cast<long>(*in++);
  }

 private:
  double block_power(const State<D>& s, std::size_t b) const {
    double g = 0.0;
    for (std::size_t k = block_from_[b]; k < block_from_[b + 1]; ++k)
      g -= s.f[static_cast<std::size_t>(index_[k])].dot(u_);
    return g;
  }
  // the step's g from the blocks' sums, into the trapezoid tally
  void tally(long step, double dt) {
    double g = 0.0;
    for (std::size_t b = 0; b < block_.size(); ++b) g += partial_[b * 8];
    if (tallied_step_ < 0)
      g0_ = g;
    else
      left_sum_ += g_ * dt;
    g_ = g;
    tallied_step_ = step;
  }
  V u_;
  std::vector<int> index_;
  std::vector<long> block_;               ///< the share_grain blocks holding selected particles, ascending
  std::vector<std::size_t> block_from_;   ///< block b's particles: index_[block_from_[b], block_from_[b + 1])
  std::vector<double> partial_;           ///< g of block b at [8 b] (erg/s)
  std::vector<long> bounds_;              ///< resident steps: the team's partition
  std::vector<long> whole_{0, 0};         ///< a plain step's partition: every particle on one thread
  struct alignas(64) History {             ///< a cache line per block: each is written by its thread
    std::vector<double> g;                 ///< the block's g in each step of the resident block (erg/s)
  };
  std::vector<History> history_;
  double left_sum_ = 0.0, g0_ = 0.0, g_ = 0.0;
  long tallied_step_ = -1;
};

// The local forces below work on the flat N x D arrays with one coefficient per degree of freedom, so each
// is one vectorized stream (as Eigen's per-particle 2-vectors, each took longer than the whole move: perf on
// the plate, 2026-12-03). Each coefficient is the product the per-particle form computed, so the bits are the
// same.
template <int D>
AlignedVector<double> per_dof(const System& sys, const std::function<double(std::size_t i, int d)>& c) {
  AlignedVector<double> out(sys.size() * D);
  for (std::size_t i = 0; i < sys.size(); ++i)
    for (int d = 0; d < D; ++d) out[i * D + static_cast<std::size_t>(d)] = c(i, d);
  return out;
}
inline double particle_mass(const System& sys, std::size_t i) {
  return sys.phase_mass[static_cast<std::size_t>(sys.phase[i])];
}

/// Gravity m g: a constant force per degree of freedom.
template <int D>
class Gravity final : public Effect<D> {
 public:
  using V = Eigen::Matrix<double, D, 1>;
  Gravity(const System& sys, const Vec3& g)
      : g_(head<D>(g)), mg_(per_dof<D>(sys, [&](std::size_t i, int d) { return particle_mass(sys, i) * g[d]; })) {}
  std::string name() const override { return "gravity"; }
  unsigned stages() const override { return stage::local_force | stage::observe; }
  void local_forces(State<D>& s, const double*, long first, long last) override {
    double* __restrict f = s.f.front().data();
    const double* __restrict mg = mg_.data();
#pragma omp simd
    for (long j = first * D; j < last * D; ++j) f[j] += mg[j];
  }
  void observe(const State<D>& s, Observables& o) const override {
    double pe = 0.0;  // -m g . x
    for (std::size_t k = 0; k < s.size(); ++k) pe -= s.masses.mass(k) * g_.dot(s.x[k]);
    o.potential += pe;
  }

 private:
  V g_;
  AlignedVector<double> mg_;  ///< dyne: m g per degree of freedom
};

/// Viscous damping -gamma m v, with v the latest half-step velocity.
template <int D>
class Damping final : public Effect<D> {
 public:
  Damping(const System& sys, double gamma)
      : gamma_m_(per_dof<D>(sys, [&](std::size_t i, int) { return gamma * particle_mass(sys, i); })) {}
  std::string name() const override { return "damping"; }
  unsigned stages() const override { return stage::local_force; }
  void local_forces(State<D>& s, const double*, long first, long last) override {
    double* __restrict f = s.f.front().data();
    const double* __restrict v = s.v.front().data();
    const double* __restrict gm = gamma_m_.data();
#pragma omp simd
    for (long j = first * D; j < last * D; ++j) f[j] -= gm[j] * v[j];
  }

 private:
  AlignedVector<double> gamma_m_;  ///< g/s: gamma m per degree of freedom
};

/// Greenspan's Eq. (10): the interaction is scaled by a = 0.001 x 980 m / |F(D)| per particle, making it
/// "small relative to gravity". The paper sets a = 1 and shows this gives a pseudo-dynamic solution; it is
/// here to show that difference. Must follow the pair effect and precede other forces.
template <int D>
class GreenspanAlpha final : public Effect<D> {
 public:
  explicit GreenspanAlpha(const System& sys)
      : alpha_(per_dof<D>(sys, [&](std::size_t i, int) {
          const int ph = sys.phase[i];
          return 0.98 * particle_mass(sys, i) / std::fabs(sys.law(ph, ph).force(sys.cutoff));
        })) {}
  std::string name() const override { return "greenspan_alpha"; }
  unsigned stages() const override { return stage::local_force; }
  void local_forces(State<D>& s, const double*, long first, long last) override {
    double* __restrict f = s.f.front().data();
    const double* __restrict a = alpha_.data();
#pragma omp simd
    for (long j = first * D; j < last * D; ++j) f[j] *= a[j];
  }

 private:
  AlignedVector<double> alpha_;  ///< per degree of freedom
};

}  // namespace

template <int D>
std::vector<std::unique_ptr<Effect<D>>> make_effects(const System& sys, const Scene& scene) {
  std::vector<std::unique_ptr<Effect<D>>> out;
  if (scene.pair)
    out.push_back(scene.pair->model == PairModel::bonded ? detail::make_bonded_pair<D>(sys, *scene.pair)
                                                         : detail::make_cutoff_pair<D>(sys, *scene.pair));
  if (scene.greenspan_alpha) {
    if (!scene.pair) throw SceneError(scene.file + ": greenspan_alpha scales the pair force, but no [pair] is declared");
    out.push_back(std::make_unique<GreenspanAlpha<D>>(sys));
  }
  if (scene.gravity) out.push_back(std::make_unique<Gravity<D>>(sys, *scene.gravity));
  if (scene.damping) out.push_back(std::make_unique<Damping<D>>(sys, scene.damping->gamma));
  for (std::size_t k = 0; k < scene.kinematic.size(); ++k)
    out.push_back(std::make_unique<Kinematic<D>>(sys, scene.kinematic[k], k));
  return out;
}

template std::vector<std::unique_ptr<Effect<2>>> make_effects<2>(const System&, const Scene&);
template std::vector<std::unique_ptr<Effect<3>>> make_effects<3>(const System&, const Scene&);

}  // namespace pmfrag

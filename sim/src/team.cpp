#include "team.hpp"

#include "pmfrag/run.hpp"

#include <omp.h>

#include <cstdlib>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define PMFRAG_PAUSE() _mm_pause()
#else
#define PMFRAG_PAUSE() ((void)0)
#endif

namespace pmfrag::detail {

namespace {
// Spin this many rounds before yielding the core: long enough to cover the serial work between two kernels
// of a step, short enough that an oversubscribed machine (sweeps, CI) still makes progress.
constexpr int spin_rounds = 20000;

template <class Done>
void spin_until(Done&& done) {
  for (int k = 0; !done(); ++k) {
    if (k < spin_rounds)
      PMFRAG_PAUSE();
    else
      std::this_thread::yield();
  }
}

constexpr std::size_t default_min_particles = 8192;
long env_min_particles() {
  const char* env = std::getenv("PMFRAG_MIN_PARTICLES_PER_THREAD");
  return env ? std::atol(env) : 0;
}
std::atomic<std::size_t>& min_particles_setting() {
  static std::atomic<std::size_t> m{env_min_particles() > 0 ? static_cast<std::size_t>(env_min_particles())
                                                             : default_min_particles};
  return m;
}
std::atomic<bool>& rule_fixed() {
  static std::atomic<bool> fixed{env_min_particles() > 0};
  return fixed;
}
thread_local int tuned = 0;

int max_threads() { return std::max(1, omp_get_max_threads()); }
}  // namespace

std::size_t Team::min_particles_per_thread() { return min_particles_setting().load(std::memory_order_relaxed); }
bool Team::thread_rule_fixed() { return rule_fixed().load(std::memory_order_relaxed); }

int Team::threads_for(std::size_t particles) {
  const std::size_t fit = std::max<std::size_t>(1, particles / min_particles_per_thread());
  return static_cast<int>(std::min<std::size_t>(fit, static_cast<std::size_t>(max_threads())));
}

int Team::most_threads_for(std::size_t particles) {
  const std::size_t fit = std::max<std::size_t>(1, particles / static_cast<std::size_t>(particle_grain));
  return static_cast<int>(std::min<std::size_t>(fit, static_cast<std::size_t>(max_threads())));
}

void Team::set_tuned_threads(int threads) { tuned = std::max(0, threads); }

Team& Team::get(std::size_t particles) {
  thread_local std::vector<std::unique_ptr<Team>> teams;  // by size
  const int want = tuned > 0 ? std::min(tuned, most_threads_for(particles)) : threads_for(particles);
  const std::size_t k = static_cast<std::size_t>(want);
  if (teams.size() <= k) teams.resize(k + 1);
  if (!teams[k]) teams[k] = std::make_unique<Team>(want);
  return *teams[k];
}

Team::Team(int threads) : size_(std::max(1, threads)) {
  for (int t = 1; t < size_; ++t) workers_.emplace_back([this, t] { work(t); });
}

Team::~Team() {
  stop_ = true;
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (auto& w : workers_) w.join();
}

void Team::dispatch(Fn fn, void* ctx) {
  fn_ = fn, ctx_ = ctx;
  finished_.store(0, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);  // publishes fn_, ctx_
  generation_.notify_all();                               // wakes only workers that went to sleep
  fn(ctx, 0);
  spin_until([&] { return finished_.load(std::memory_order_acquire) == size_ - 1; });
}

void Team::work(int tid) {
  std::uint32_t seen = 0;
  for (;;) {
    // Spin for the next job, then sleep on the generation counter (a futex) until one is handed out.
    int k = 0;
    std::uint32_t g;
    while ((g = generation_.load(std::memory_order_acquire)) == seen) {
      if (++k < spin_rounds)
        PMFRAG_PAUSE();
      else
        generation_.wait(seen, std::memory_order_acquire);
    }
    seen = g;
    if (stop_) return;
    fn_(ctx_, tid);
    finished_.fetch_add(1, std::memory_order_acq_rel);
  }
}

void Team::barrier() {
  const std::uint32_t pass = passed_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) == size_ - 1) {
    arrived_.store(0, std::memory_order_relaxed);
    passed_.fetch_add(1, std::memory_order_release);
  } else {
    spin_until([&] { return passed_.load(std::memory_order_acquire) != pass; });
  }
}

}  // namespace pmfrag::detail

namespace pmfrag {
void set_min_particles_per_thread(std::size_t n) {
  detail::min_particles_setting().store(n > 0 ? n : detail::default_min_particles);
  detail::rule_fixed().store(n > 0);
}
int step_threads(std::size_t particles) { return detail::Team::threads_for(particles); }
}  // namespace pmfrag

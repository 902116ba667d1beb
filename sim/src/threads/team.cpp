#include "threads/team.hpp"

#include "pmfrag/run/run.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
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

}  // namespace

Team::Team(int threads, std::size_t min_particles_per_thread)
    : size_(std::max(1, threads)), done_(new Counter[static_cast<std::size_t>(size_)]),
      passed_(new Counter[static_cast<std::size_t>(size_)]),
      min_particles_(std::max<std::size_t>(1, min_particles_per_thread)) {
  for (int t = 1; t < size_; ++t) workers_.emplace_back([this, t] { work(t); });
}

void Team::set_fixed_weights(std::vector<double> w) {
  fixed_ = std::move(w);
  bounds_n_ = -1;
}

std::vector<long> Team::partition(long n, int threads, const std::vector<double>& weights) {
  std::vector<double> w(static_cast<std::size_t>(threads), 1.0);
  if (weights.size() == w.size()) w = weights;
  double total = 0.0;
  for (double v : w) total += v;
  // cumulative weight -> whole grains; every thread keeps at least one grain if there are enough
  const long units = (n + share_grain - 1) / share_grain;
  const long least = units >= threads ? 1 : 0;
  std::vector<long> b(static_cast<std::size_t>(threads) + 1, 0);
  double cum = 0.0;
  long prev = 0;
  for (int t = 1; t < threads; ++t) {
    cum += w[static_cast<std::size_t>(t) - 1] / total;
    // the nearest whole grain to the weighted share of the n particles (not of the grains: the last one
    // may be nearly empty, and the plate's 2698 then split 1408 / 1290 instead of 1344 / 1354)
    const double ideal = cum * static_cast<double>(n) / static_cast<double>(share_grain);
    const long u = std::clamp(std::lround(ideal), prev + least, units - (threads - t) * least);
    b[static_cast<std::size_t>(t)] = std::min(n, u * share_grain);
    prev = u;
  }
  b[static_cast<std::size_t>(threads)] = n;
  return b;
}

const std::vector<long>& Team::bounds(long n) {
  if (n == bounds_n_) return bounds_;
  bounds_ = partition(n, size_, weights_fixed() ? fixed_ : balance_);
  bounds_n_ = n;
  return bounds_;
}

void Team::set_balance(std::vector<double> w) {
  balance_ = std::move(w);
  bounds_n_ = -1;
}

Team::~Team() {
  job_.stop = true;
  job_.generation.fetch_add(1, std::memory_order_release);
  job_.generation.notify_all();
  for (auto& w : workers_) w.join();
}

void Team::dispatch(Fn fn, void* ctx) {
  job_.pre = pre_fn_, job_.pre_ctx = pre_ctx_;
  pre_fn_ = nullptr;
  job_.fn = fn, job_.ctx = ctx;
  const std::uint32_t g = job_.generation.load(std::memory_order_relaxed) + 1;
  job_.generation.store(g, std::memory_order_release);  // publishes the job
  job_.generation.notify_all();                         // wakes only workers that went to sleep
  perform(job_, 0);
  for (int t = 1; t < size_; ++t)
    spin_until([&] { return done_[static_cast<std::size_t>(t)].value.load(std::memory_order_acquire) == g; });
}

void Team::work(int tid) {
  std::uint32_t seen = 0;
  for (;;) {
    // Spin for the next job, then sleep on the generation counter (a futex) until one is handed out.
    int k = 0;
    std::uint32_t g;
    while ((g = job_.generation.load(std::memory_order_acquire)) == seen) {
      if (++k < spin_rounds)
        PMFRAG_PAUSE();
      else
        job_.generation.wait(seen, std::memory_order_acquire);
    }
    seen = g;
    if (job_.stop) return;
    perform(job_, tid);
    done_[static_cast<std::size_t>(tid)].value.store(g, std::memory_order_release);
  }
}

void Team::barrier(int tid) { barrier(tid, nullptr, 0); }

void Team::barrier(int tid, const double* data, std::size_t count) {
  Counter& mine = passed_[static_cast<std::size_t>(tid)];
  const std::uint64_t pass = mine.value.load(std::memory_order_relaxed) + 1;
  std::copy_n(data, std::min(count, max_published), mine.data[pass & 1]);
  mine.value.store(pass, std::memory_order_release);
  for (int t = 0; t < size_; ++t)
    if (t != tid)
      spin_until([&] { return passed_[static_cast<std::size_t>(t)].value.load(std::memory_order_acquire) >= pass; });
}

Threads::Threads(ThreadOptions options) : options_(std::move(options)), max_(options_.resolved_max()) {}

Team& Threads::team(int count) {
  const std::size_t k = static_cast<std::size_t>(std::clamp(count, 1, max_));
  if (teams_.size() <= k) teams_.resize(k + 1);
  if (!teams_[k]) {
    const std::size_t rule = rule_fixed() ? options_.min_particles_per_thread : Team::default_min_particles_per_thread;
    teams_[k] = std::make_unique<Team>(static_cast<int>(k), rule);
    teams_[k]->set_fixed_weights(options_.weights);
  }
  return *teams_[k];
}

int Threads::most_threads_for(std::size_t particles) const {
  const std::size_t fit = std::max<std::size_t>(1, particles / static_cast<std::size_t>(particle_grain));
  return static_cast<int>(std::min<std::size_t>(fit, static_cast<std::size_t>(max_)));
}

void Threads::set_weights(std::vector<double> weights) {
  options_.weights = std::move(weights);
  for (auto& t : teams_)
    if (t) t->set_fixed_weights(options_.weights);
}

}  // namespace pmfrag::detail

namespace pmfrag {

int ThreadOptions::resolved_max() const { return max > 0 ? max : std::max(1, omp_get_max_threads()); }

int ThreadOptions::threads_for(std::size_t particles) const {
  const std::size_t per = min_particles_per_thread > 0 ? min_particles_per_thread
                                                      : detail::Team::default_min_particles_per_thread;
  const std::size_t fit = std::max<std::size_t>(1, particles / per);
  return static_cast<int>(std::min<std::size_t>(fit, static_cast<std::size_t>(resolved_max())));
}

ThreadOptions thread_options_from_environment(int max) {
  ThreadOptions o;
  o.max = max;
  if (const char* env = std::getenv("PMFRAG_MIN_PARTICLES_PER_THREAD")) {
    const long v = std::atol(env);
    if (v > 0) o.min_particles_per_thread = static_cast<std::size_t>(v);
  }
  // "1,3": the second thread takes three times the first one's particles; anything else: equal shares
  const char* env = std::getenv("PMFRAG_THREAD_WEIGHTS");
  for (const char* p = env; p != nullptr && *p != '\0';) {
    char* end = nullptr;
    const double v = std::strtod(p, &end);
    if (end == p || !(v > 0.0)) {
      o.weights.clear();
      break;
    }
    o.weights.push_back(v);
    p = *end == ',' ? end + 1 : end;
  }
  return o;
}

}  // namespace pmfrag

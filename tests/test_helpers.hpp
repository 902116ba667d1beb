// Shared helpers for engine tests: scenes from the shipped cases, stepping to a time, simple systems.
#pragma once

#include "pmfrag/step/leapfrog.hpp"
#include "pmfrag/body/scene.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace pmfrag::test {

/// PMFRAG_TEST_SCALE (default 1) shortens the hard cases' runs; the sanitized CI build sets 0.1 so that the
/// same tests walk the same code under ASan/UBSan in minutes. The physics thresholds hold at either length.
inline double test_scale() {
  const char* s = std::getenv("PMFRAG_TEST_SCALE");
  const double v = s ? std::atof(s) : 1.0;
  return v > 0.0 && v <= 1.0 ? v : 1.0;
}
inline long scaled(long n) { return std::max(1L, static_cast<long>(static_cast<double>(n) * test_scale())); }

inline std::string case_path(const std::string& name) { return std::string(PMFRAG_SOURCE_DIR) + "/cases/" + name; }

/// A whole text file (empty if it cannot be read: the caller's assertions then fail on it).
inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::filesystem::path temp_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() / ("pmfrag_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

template <int D>
Leapfrog<D> make_leapfrog(const System& sys, const Scene& sc, double dt, ThreadOptions threads = {}) {
  return Leapfrog<D>(sys, make_effects<D>(sys, sc), dt, false, std::move(threads));
}

/// Exactly `threads` threads, whatever the body's size (the 1-vs-2-thread comparisons split small scenes).
inline ThreadOptions split_among(int threads, std::vector<double> weights = {}) {
  ThreadOptions o;
  o.max = threads;
  o.min_particles_per_thread = 1;
  o.weights = std::move(weights);
  return o;
}

}  // namespace pmfrag::test

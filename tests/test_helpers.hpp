// Shared helpers for engine tests: scenes from the shipped cases, stepping to a time, simple systems.
#pragma once

#include "pmfrag/leapfrog.hpp"
#include "pmfrag/scene.hpp"

#include <unistd.h>

#include <filesystem>
#include <string>

namespace pmfrag::test {

inline std::string case_path(const std::string& name) { return std::string(PMFRAG_SOURCE_DIR) + "/cases/" + name; }

inline std::filesystem::path temp_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() / ("pmfrag_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

template <int D>
Leapfrog<D> make_leapfrog(const System& sys, const Scene& sc, double dt) {
  return Leapfrog<D>(sys, make_effects<D>(sys, sc), dt);
}

}  // namespace pmfrag::test

// A sweep: one base scene run over (p,q) pairs and any other keys, one case per combination. The spec is a
// TOML file; this part only reads it and lists the cases (the command line runs them).
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace pmfrag {

struct SweepCase {
  std::string name;                    ///< folder name, e.g. "p7_q14" or "p7_q14_time.dt=5e-08"
  int p = 0, q = 0;
  std::vector<std::string> overrides;  ///< --set items for this case (phase laws first)
};

struct SweepSpec {
  std::string file;                      ///< the spec, for messages
  std::string base;                      ///< the base scene, resolved against the spec's folder
  std::vector<std::array<int, 2>> pairs;  ///< (p,q); "all" = the 105 pairs of Fig. 3
  std::vector<std::string> set;          ///< applied to every case
  std::vector<std::pair<std::string, std::vector<std::string>>> vary;  ///< key -> values (a product)
};

/// Reads a spec. Errors (SceneError) name file, line and key.
SweepSpec read_sweep_spec(const std::string& path);

/// The cases of a spec: pairs x the product of `vary`, in a fixed order. Every phase of the base scene gets
/// the case's (p,q).
std::vector<SweepCase> sweep_cases(const SweepSpec& spec, std::size_t phases);

}  // namespace pmfrag

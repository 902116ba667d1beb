#include "pmfrag/run/build_info.hpp"

#include <fstream>

#include "kernels/bond_sweep_avx512.hpp"  // defines PMFRAG_HAVE_AVX512_SWEEP where the AVX-512 sweeps are compiled

namespace pmfrag {

const char* kernel_path() {
#ifdef PMFRAG_HAVE_AVX512_SWEEP
  return "avx512";
#else
  return "portable";
#endif
}

std::string processor_name() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) break;
    const auto start = line.find_first_not_of(" \t", colon + 1);
    return start == std::string::npos ? "unknown processor" : line.substr(start);
  }
  return "unknown processor";
}

}  // namespace pmfrag

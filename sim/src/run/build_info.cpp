#include "pmfrag/run/build_info.hpp"

#include <unistd.h>

#include <cctype>
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

namespace {
std::size_t read_l2_cache_bytes() {
#ifdef _SC_LEVEL2_CACHE_SIZE
  const long v = sysconf(_SC_LEVEL2_CACHE_SIZE);
  if (v > 0) return static_cast<std::size_t>(v);
#endif
  std::ifstream in("/sys/devices/system/cpu/cpu0/cache/index2/size");  // e.g. "512K"
  std::size_t n = 0;
  char unit = 0;
  if (!(in >> n)) return 0;
  in >> unit;
  switch (std::toupper(static_cast<unsigned char>(unit))) {
    case 'K': return n << 10;
    case 'M': return n << 20;
    default: return n;
  }
}
}  // namespace

std::size_t l2_cache_bytes() {
  static const std::size_t bytes = read_l2_cache_bytes();
  return bytes;
}

}  // namespace pmfrag

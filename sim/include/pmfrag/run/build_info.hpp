// What this build of pmfrag runs on: its bond kernels and the processor, named beside every speed figure.
#pragma once

#include <cstddef>
#include <string>

namespace pmfrag {

/// The bond kernels compiled in: "avx512" (the AVX-512 sweeps) or "portable" (plain loops the compiler
/// vectorizes as it can). CMake's PMFRAG_KERNELS chooses; `auto` follows the compiler's target.
const char* kernel_path();

/// The processor's model name as the operating system reports it (Linux: /proc/cpuinfo), read at run time;
/// "unknown processor" where it cannot be read.
std::string processor_name();

/// The level-2 cache of one core in bytes, read at run time (sysconf, else
/// /sys/devices/system/cpu/cpu0/cache/index2/size), once; 0 where neither tells.
std::size_t l2_cache_bytes();

}  // namespace pmfrag

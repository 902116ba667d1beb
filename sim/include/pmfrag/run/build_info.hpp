// What this build of pmfrag runs on: its bond kernels and the processor, named beside every speed figure.
#pragma once

#include <string>

namespace pmfrag {

/// The bond kernels compiled in: "avx512" (the AVX-512 sweeps) or "portable" (plain loops the compiler
/// vectorizes as it can). CMake's PMFRAG_KERNELS chooses; `auto` follows the compiler's target.
const char* kernel_path();

/// The processor's model name as the operating system reports it (Linux: /proc/cpuinfo), read at run time;
/// "unknown processor" where it cannot be read.
std::string processor_name();

}  // namespace pmfrag

// libFuzzer target for the scene parser: any text must give a valid Scene or a SceneError that names the
// file and a line ("fuzz.toml:<line>: ..."). Any other exception, a crash, a hang or a sanitizer report is a
// finding. Built by tests/fuzz/CMakeLists.txt with clang; run by scripts/fuzz (and CI).
#include "pmfrag/body/scene.hpp"

#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const pmfrag::Scene sc = pmfrag::parse_scene(text, "fuzz.toml");
    // A scene that parsed must be one the engine can take: positive step, end and spacing.
    if (!(sc.time.end > 0.0) || (!sc.time.auto_dt && !sc.time.adaptive && !(sc.time.dt > 0.0)) || sc.bodies.empty()) {
      std::fprintf(stderr, "accepted an unusable scene\n");
      std::abort();
    }
    for (const auto& b : sc.bodies)
      if (!(b.r0 > 0.0)) {
        std::fprintf(stderr, "accepted r0 = %g\n", b.r0);
        std::abort();
      }
  } catch (const pmfrag::SceneError& e) {
    const std::string m = e.what();
    const std::string prefix = "fuzz.toml:";
    if (m.rfind(prefix, 0) != 0 || m.size() <= prefix.size() ||
        !std::isdigit(static_cast<unsigned char>(m[prefix.size()]))) {
      std::fprintf(stderr, "error without file and line: %s\n", m.c_str());
      std::abort();
    }
  }
  return 0;
}

// Runs a scene with the installed pmfrag library: what `pmfrag run SCENE --out DIR --set ...` does, without
// its options. Usage: run_scene SCENE OUT_DIR [KEY=VALUE ...]
#include <pmfrag/run/run.hpp>
#include <pmfrag/body/scene.hpp>

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: run_scene SCENE OUT_DIR [KEY=VALUE ...]\n");
    return 2;
  }
  try {
    const std::vector<std::string> overrides(argv + 3, argv + argc);
    pmfrag::RunOptions options;
    options.out_dir = argv[2];
    options.force = true;
    const pmfrag::RunResult r = pmfrag::run_scene(pmfrag::read_scene(argv[1], overrides), options);
    std::printf("%s: %ld steps, %ld frames, %zu particles; %ld bonds broken\n", r.completed ? "finished" : "stopped",
                r.steps, r.frames, r.particles, r.bonds_broken);
    return r.completed ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "run_scene: %s\n", e.what());
    return 1;
  }
}

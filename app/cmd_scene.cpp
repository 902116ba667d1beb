#include "cmd_scene.hpp"

#include "pmfrag/step/effects.hpp"
#include "pmfrag/body/system.hpp"

#include <cmath>
#include <cstdio>
#include <memory>

namespace pmfrag::app {

namespace {

struct SceneCli {
  std::string scene;
  std::vector<std::string> set;
};

void run(const SceneCli& o) {
  const Scene sc = read_scene(o.scene, o.set);
  const System sys = build_system(sc);
  std::printf("%s: %s\n", sc.file.c_str(), sc.title.c_str());
  std::printf("dimension %d, r0 = %g cm, D = %g cm, %zu particles, %zu bonds\n", sys.dim, sys.r0, sys.cutoff, sys.size(),
              sys.bonds.size());
  for (std::size_t k = 0; k < sys.phase_names.size(); ++k) {
    const PairLaw& l = sys.law(static_cast<int>(k), static_cast<int>(k));
    std::printf("phase %-10s (p,q) = (%d,%d)  G = %.6e  H = %.6e  mass = %.6g g\n", sys.phase_names[k].c_str(), l.p, l.q,
                l.G, l.H, sys.phase_mass[k]);
  }
  const StepChoice step = choose_step(sc, sys);
  std::printf("stability limit: %.4e s = Eq. 15 %.4e s%s x lattice factor %.4f (bulk lattices: triangular 1/sqrt(6) = 0.408, fcc 1/sqrt(8) = 0.354)\n",
              step.limit, step.pair_limit, sys.r_min > 0 ? " at r_min" : "", step.lattice_factor);
  if (step.adaptive)
    std::printf("dt: adaptive, at most %.4e s\n", step.dt);
  else
    std::printf("dt: %.4e s (%.3f x the limit)\n", step.dt, step.dt / step.limit);
  std::string effects;
  if (sys.dim == 2)
    for (const auto& e : make_effects<2>(sys, sc)) effects += (effects.empty() ? "" : ", ") + e->name();
  else
    for (const auto& e : make_effects<3>(sys, sc)) effects += (effects.empty() ? "" : ", ") + e->name();
  std::printf("effects: %s\n", effects.empty() ? "none" : effects.c_str());
}

}  // namespace

void add_scene_command(CLI::App& app) {
  auto o = std::make_shared<SceneCli>();
  auto* cmd = app.add_subcommand("scene", "Check a scene and describe what it builds (particles, bonds, laws, effects)");
  cmd->add_option("scene", o->scene, "Scene file (TOML)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--set", o->set, "Override a scene key (repeatable)")->type_name("KEY=VALUE");
  cmd->callback([o] { run(*o); });
}

}  // namespace pmfrag::app

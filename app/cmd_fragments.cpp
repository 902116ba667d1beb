#include "cmd_fragments.hpp"

#include "parse.hpp"
#include "pmfrag/io/folder_lock.hpp"
#include "pmfrag/analysis/fragments.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace pmfrag::app {

namespace {

struct FragmentsCli {
  std::string dir;
  std::string criterion;  ///< "": the engine's record
};

void run(const FragmentsCli& o) {
  std::optional<analysis::BreakCriterion> c;
  try {
    c = analysis::BreakCriterion::parse_option(o.criterion);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const std::string traj = (std::filesystem::path(o.dir) / "trajectory.h5").string();
  if (!std::filesystem::exists(traj)) throw UsageError(o.dir + ": no trajectory.h5 (run `pmfrag run SCENE --out DIR` first)");
  const FolderLock lock(o.dir);  // one writer per run folder: a second is refused at once
  const auto rep = analysis::analyse_fragments(traj, c);
  analysis::write_fragment_report(rep, o.dir);
  const auto& end = rep.timeline.back();
  long singles = 0;
  for (const auto& g : rep.final_fragments) singles += g.particles == 1;
  std::printf("fragments of %s: (p,q) = (%d,%d), broken bonds: %s; %ld frames%s\n", o.dir.c_str(), rep.p, rep.q,
              rep.criterion.c_str(), rep.frames_read, rep.partial ? " (PARTIAL)" : "");
  if (rep.target_particles > 0)
    std::printf("  %ld particles of bodies held in place (targets) are left out of the counts below\n", rep.target_particles);
  if (rep.onset_time >= 0)
    std::printf("  onset (first broken bond, frame resolution): %.4e s\n", rep.onset_time);
  else
    std::printf("  no bond broke\n");
  if (rep.separation_time >= 0)
    std::printf("  separation (>= 2 fragments of >= 5 %% mass): %.4e s\n", rep.separation_time);
  else
    std::printf("  no separation into pieces of >= 5 %% of the mass\n");
  if (end.broken_engine >= 0 && end.broken_engine != end.broken)
    std::printf("  note: the engine counted %ld bonds broken or beyond D at t = %.4e s, this reading %ld\n",
                end.broken_engine, end.time, end.broken);
  std::printf("  at t = %.4e s: %ld broken bonds, %ld fragments (%ld of >= 2 particles, %ld single particles, %ld of >= 1 %% "
              "mass), largest %.1f %% of the mass\n",
              end.time, end.broken, end.fragments, end.fragments - singles, singles, end.fragments_1pct,
              100.0 * end.largest_fraction);
  if (const auto& d = rep.distribution)
    std::printf("  mass distribution: n(m) ~ m^-tau, tau = %.3f (95 %% interval %.3f-%.3f) over %ld fragments of >= %ld "
                "particles (KS distance %.3f); second largest %.1f %% of the mass\n",
                d->exponent, d->ci_low, d->ci_high, d->fitted, d->s_min, d->ks_distance, 100.0 * rep.second_largest_fraction);
  else
    std::printf("  mass distribution: no power-law fit (%s)\n", rep.distribution_note.c_str());
  if (rep.partial) std::printf("  note: %s\n", rep.note.c_str());
  std::printf("  wrote fragments_timeline.csv, fragments_final.csv, fragment_sizes.csv, fragment_mass_ccdf.csv, "
              "summary.json in %s\n", o.dir.c_str());
}

}  // namespace

void add_fragments_command(CLI::App& app) {
  auto o = std::make_shared<FragmentsCli>();
  auto* cmd = app.add_subcommand("fragments", "Cluster broken bonds into fragments (timeline, final fragments, sizes)");
  cmd->add_option("run_dir", o->dir, "Run folder (holds trajectory.h5)")->required();
  cmd->add_option("--break", o->criterion,
                  "Read broken bonds from their lengths at the frames instead of the engine's record (the default): "
                  "D (longer than the interaction distance), rd (the damage spacing) or a factor of r0, e.g. 1.5")
      ->type_name("D|rd|FACTOR");
  cmd->callback([o] { run(*o); });
}

}  // namespace pmfrag::app

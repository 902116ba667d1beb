#include "cmd_run.hpp"

#include "parse.hpp"
#include "pmfrag/run/build_info.hpp"
#include "pmfrag/run/run.hpp"

#include <unistd.h>

#include <csignal>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

namespace pmfrag::app {

namespace {

struct RunCli {
  std::string scene, out, resume;
  std::vector<std::string> set;
  bool allow_unstable = false, force = false, quiet = false;
  int threads = 0;
};

std::string clock_text(double s) {
  char b[32];
  if (s < 60)
    std::snprintf(b, sizeof b, "%.0fs", s);
  else
    std::snprintf(b, sizeof b, "%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
  return b;
}

extern "C" void on_stop_signal(int) { request_stop(); }

/// Exit code for a run stopped by SIGINT/SIGTERM: the shell convention for SIGINT.
constexpr int exit_interrupted = 130;

void run(const RunCli& o) {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  if (o.resume.empty() && (o.scene.empty() || o.out.empty()))
    throw UsageError("run: give SCENE and --out DIR, or --resume DIR");
  if (!o.resume.empty() && !o.scene.empty()) throw UsageError("--resume: takes the run folder only, not a scene");
  RunOptions ro;
  ro.out_dir = o.resume.empty() ? o.out : o.resume;
  ro.allow_unstable = o.allow_unstable;
  ro.force = o.force;
  ro.threads = thread_options_from_environment(o.threads);
  ro.warn = [](const std::string& line) { std::fprintf(stderr, "pmfrag: %s\n", line.c_str()); };
  if (!o.quiet) ro.log = ro.warn;
  const bool tty = isatty(fileno(stderr));
  double last_plain = -1e9;
  if (!o.quiet)
    ro.progress = [&, tty](const Progress& p) {
      if (tty) {
        const int width = 30;
        const int filled = static_cast<int>(width * p.time / p.end);
        std::string bar(static_cast<std::size_t>(filled), '#');
        bar.resize(width, '.');
        std::fprintf(stderr, "\r[%s] t = %.4e / %.4e s  %.3g steps/s  ETA %s   ", bar.c_str(), p.time, p.end,
                     p.steps_per_s, clock_text(p.eta_s).c_str());
      } else if (p.wall_s - last_plain >= 5.0) {
        last_plain = p.wall_s;
        std::fprintf(stderr, "pmfrag: t = %.4e / %.4e s (%.0f%%), %.3g steps/s, ETA %s\n", p.time, p.end,
                     100.0 * p.time / p.end, p.steps_per_s, clock_text(p.eta_s).c_str());
      }
    };
  const RunResult r = o.resume.empty() ? run_scene(read_scene(o.scene, o.set), ro) : resume_run(ro);
  if (!o.quiet && tty) std::fprintf(stderr, "\n");
  if (r.completed && r.steps == 0 && !r.message.empty()) {
    std::printf("%s\n", r.message.c_str());
    return;
  }
  std::printf("%s: %ld steps, %ld frames, %zu particles in %.3g s (%.3g particle-steps/s, %d threads, %s kernels, %s; "
              "%.3g s of setup before)\n",
              r.completed ? "finished" : "STOPPED", r.steps, r.frames, r.particles, r.wall_s, r.particle_steps_per_s(),
              r.threads(), kernel_path(), processor_name().c_str(), r.setup_s);
  // What happened to the bonds, in the words of the model that ran.
  if (r.pair_model == "cutoff") {
    if (r.bonds_broken > 0)
      std::printf("cutoff model: pairs of the lattice left D %ld times (the first at t = %.6e s) and came back within D "
                  "%ld times; %ld are beyond D at the end\n",
                  r.bonds_broken, r.first_break_time, r.bonds_re_formed, r.bonds_beyond_now);
    else
      std::printf("cutoff model: no pair of the lattice left D\n");
  } else if (r.pair_model == "bonded") {
    if (r.bonds_broken > 0)
      std::printf("first broken bond at t = %.6e s; %ld bonds broken\n", r.first_break_time, r.bonds_broken);
    else
      std::printf("no bond broke\n");
  }
  std::printf("trajectory: %s/trajectory.h5\n", ro.out_dir.c_str());
  if (r.interrupted) {
    std::fprintf(stderr, "pmfrag: %s\n", r.message.c_str());
    std::fflush(nullptr);
    std::_Exit(exit_interrupted);
  }
  if (!r.completed) throw std::runtime_error(r.message + " (frames written so far are kept)");
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto o = std::make_shared<RunCli>();
  auto* cmd = app.add_subcommand("run", "Simulate a scene (cases/*.toml) and write OUT/trajectory.h5 (H5MD)");
  cmd->add_option("scene", o->scene, "Scene file (TOML)")->check(CLI::ExistingFile);
  cmd->add_option("--out,-o", o->out, "Output folder (trajectory.h5, checkpoint.h5, run.json)");
  cmd->add_option("--resume", o->resume,
                  "Continue the run in this folder from its last checkpoint (bitwise as if never stopped)")
      ->type_name("DIR");
  cmd->add_option("--set", o->set, "Override a scene key, e.g. --set time.end=2e-3 (repeatable)")->type_name("KEY=VALUE");
  cmd->add_flag("--allow-unstable", o->allow_unstable, "Run even if dt exceeds the Eq. 15 stability limit");
  cmd->add_flag("--force", o->force, "Overwrite an existing trajectory in the output folder");
  cmd->add_option("--threads", o->threads, "At most this many threads (default: all cores); the run measures which count is fastest. Results are identical for any count")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--quiet,-q", o->quiet, "No progress or log lines");
  cmd->callback([o] { run(*o); });
}

}  // namespace pmfrag::app

// Running a scene end to end: build the System and its effects, choose and check the step (Eq. 15), advance
// with leapfrog and write the H5MD trajectory.
#pragma once

#include "pmfrag/body/scene.hpp"
#include "pmfrag/threads/threads.hpp"

#include <functional>
#include <filesystem>
#include <string>
#include <vector>

namespace pmfrag {

struct Progress {
  double time = 0.0, end = 0.0;  ///< simulated s
  long step = 0, steps = 0;
  double steps_per_s = 0.0, eta_s = 0.0, wall_s = 0.0;
};

struct RunOptions {
  std::string out_dir;
  bool allow_unstable = false;  ///< run even if dt exceeds the Eq. 15 limit
  bool force = false;           ///< overwrite an existing trajectory
  ThreadOptions threads;        ///< how the steps use threads (threads.hpp)
  std::function<void(const std::string&)> log;         ///< one line of information
  std::function<void(const std::string&)> warn;        ///< one line the user must see, even when quiet
  std::function<void(const Progress&)> progress;       ///< called every ~0.2 s of wall time
};

struct RunResult {
  long steps = 0, frames = 0;
  std::size_t particles = 0;
  double dt = 0.0, dt_limit = 0.0, wall_s = 0.0;  ///< wall_s: the steps, from the first frame on
  double setup_s = 0.0;  ///< s of wall time before the first frame: system, step limit, effects, lists, files
  double output_s = 0.0;  ///< s of wall_s spent writing frames and checkpoints (wall_s - output_s: the steps alone)
  std::string pair_model = "none";  ///< "bonded", "cutoff" or "none"
  double first_break_time = -1.0;  ///< s; -1 if no bond broke (cutoff model: no pair of the lattice left D)
  long bonds_broken = 0;      ///< bonded: bonds broken; cutoff: times a pair of the lattice left D (whole run)
  long bonds_re_formed = 0;   ///< cutoff: times such a pair came back within D
  long bonds_beyond_now = 0;  ///< bonds broken / beyond D at the last step
  long list_builds = 0;            ///< neighbour-list builds (since a resume, if resumed)
  double skin = 0.0;               ///< cm: the Verlet skin at the end (0: no list)
  bool adaptive = false;           ///< dt = "adaptive": dt is the cap, dt_min the smallest step taken
  double dt_min = 0.0;             ///< s
  bool completed = false;          ///< false: stopped by the guard or interrupted (message says why)
  bool interrupted = false;        ///< stopped by request_stop(): a checkpoint was written at that step
  std::string message;
  std::vector<long> thread_steps;  ///< steps taken on each thread count (index: threads), as measured best
  /// The thread count most steps ran on.
  int threads() const {
    std::size_t best = 1;
    for (std::size_t t = 1; t < thread_steps.size(); ++t)
      if (thread_steps[t] > thread_steps[best]) best = t;
    return static_cast<int>(best);
  }
  double particle_steps_per_s() const { return wall_s > 0 ? static_cast<double>(particles) * steps / wall_s : 0.0; }
};

/// Thrown when dt exceeds the Eq. 15 limit and allow_unstable is not set.
struct UnstableStepError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

RunResult run_scene(const Scene& scene, const RunOptions& options);

/// What a run folder's run.json records, read back (a sweep or study gathering its runs). Fields the file does
/// not hold keep their defaults; a file that cannot be read or is not JSON throws std::runtime_error naming it.
RunResult read_run_record(const std::string& path);

/// Asks a running simulation to stop at the end of its current step, write a checkpoint and return
/// (RunResult::interrupted). Async-signal-safe: call it from a SIGINT/SIGTERM handler.
void request_stop() noexcept;

/// Continues the run in options.out_dir from its last checkpoint (the scene and its overrides are read from
/// the trajectory). Killed before the first checkpoint: starts over. Already finished: says so in
/// RunResult::message and does nothing.
RunResult resume_run(const RunOptions& options);

/// A new run's folder: refuses to overwrite a trajectory without `force`, clears the old run's record and
/// checkpoint, and keeps the scene as read and its overrides beside the trajectory (scene.toml, overrides.txt).
void start_run_folder(const std::filesystem::path& dir, const Scene& scene, bool force);
/// The scene a run folder (or a LAMMPS deck) keeps: scene.toml with the overrides of overrides.txt.
Scene read_folder_scene(const std::filesystem::path& dir);

}  // namespace pmfrag

#include "pmfrag/run/run.hpp"

#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/folder_lock.hpp"
#include "pmfrag/run/build_info.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/step/leapfrog.hpp"
#include "pmfrag/step/step_levels.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>

namespace pmfrag {

namespace {

volatile std::sig_atomic_t stop_requested = 0;

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// When frames, checkpoints and the end fall. Fixed steps count steps; adaptive steps count time and land
// exactly on every output time.
struct Schedule {
  long steps = 0, every = 0, checkpoint_every = 0;  ///< fixed steps: steps to the end, between frames, checkpoints
  long checkpoint_frames = 0;                       ///< adaptive steps: frames between checkpoints
  double every_s = 0.0, end = 0.0, tol = 0.0;       ///< s
};
Schedule schedule_of(const Scene& scene, double dt) {
  Schedule c;
  c.steps = std::max(1L, std::lround(scene.time.end / dt));
  c.every = std::max(1L, std::lround(scene.output.every / dt));
  c.checkpoint_every =
      scene.output.checkpoint_every > 0 ? std::max(1L, std::lround(scene.output.checkpoint_every / dt)) : 10 * c.every;
  c.every_s = scene.output.every, c.end = scene.time.end, c.tol = 1e-6 * std::min(c.every_s, dt);
  c.checkpoint_frames =
      scene.output.checkpoint_every > 0 ? std::max(1L, std::lround(scene.output.checkpoint_every / c.every_s)) : 10;
  return c;
}


// What a run writes as it goes: frames, the bond events before each, and checkpoints.
template <int D>
class RunOutput {
 public:
  RunOutput(H5mdWriter& writer, Leapfrog<D>& lf, std::string checkpoint_path)
      : writer_(writer), lf_(lf), checkpoint_path_(std::move(checkpoint_path)) {}

  // The bond events recorded since the last frame or checkpoint go to the trajectory before either.
  void record_events() {
    events_.clear();
    for (const auto& e : lf_.effects()) take_bond_events<D>(*e, events_);
    writer_.append_bond_events(events_);
  }
  // Positions and velocities go to the file from the integrator's arrays: D packed doubles a particle are the
  // N x D layout of a frame, so no flat copy is made (32 B a particle in 2-D, 48 in 3-D).
  static_assert(sizeof(Eigen::Matrix<double, D, 1>) == D * sizeof(double));
  void frame() {
    failing_write_says_what_is_kept([&] {
      record_events();
      const auto& s = lf_.state();
      // velocities a chunk of the file at a time: no N x D array of them
      const H5mdWriter::FrameRows velocity = [&](std::size_t first, std::size_t count, double* out) {
        lf_.whole_step_velocity(first, count, out);
      };
      writer_.write_frame(s.step, s.time(), s.x.data()->data(), velocity, lf_.observe());
      last_frame_time_ = s.time();
    });
  }
  void checkpoint(const StepLevels& levels) {
    failing_write_says_what_is_kept([&] { write_checkpoint_now(levels); });
    checkpoint_frames_ = writer_.frames(), checkpoint_time_ = lf_.state().time();
  }
  void resumed_from(const Checkpoint& c) {
    checkpoint_frames_ = c.frames, checkpoint_time_ = c.time;
    last_frame_time_ = -1.0;  // not read back: the first frame written after the resume sets it
  }

 private:
  // A write that fails (a full disk) ends the run with one line: the file and the cause, then what is kept.
  template <class F>
  void failing_write_says_what_is_kept(F&& write) {
    try {
      write();
    } catch (const std::runtime_error& e) {
      // The time is known for a frame this process wrote; a resumed run's earlier frames are named by number.
      const std::string until = last_frame_time_ >= 0.0 ? ", to t = " + fmt("%.6g", last_frame_time_) + " s," : "";
      std::string kept = writer_.frames() > 0
                             ? "frames 0.." + std::to_string(writer_.frames() - 1) + until + " are whole"
                             : "no frame was written";
      kept += checkpoint_frames_ > 0 ? "; the checkpoint at frame " + std::to_string(checkpoint_frames_ - 1) +
                                           ", t = " + fmt("%.6g", checkpoint_time_) + " s, is intact"
                                     : "; there is no checkpoint yet";
      throw std::runtime_error(std::string(e.what()) + " (" + kept + ")");
    }
  }
  void write_checkpoint_now(const StepLevels& levels) {
    record_events();
    writer_.flush();  // the rows the checkpoint counts are on disk before it
    const auto& s = lf_.state();
    Checkpoint c;
    c.bond_events = writer_.bond_event_rows();
    c.step = s.step;
    c.time = s.t;
    c.dt = s.dt;
    c.level = levels.level(), c.calm = levels.calm();
    c.frames = writer_.frames();
    c.effects = lf_.effect_state();
    write_checkpoint(checkpoint_path_, c, s.x.data()->data(), s.v.data()->data(), s.size() * D);
  }

  double last_frame_time_ = 0.0, checkpoint_time_ = 0.0;
  long checkpoint_frames_ = 0;
  H5mdWriter& writer_;
  Leapfrog<D>& lf_;
  std::string checkpoint_path_;
  std::vector<BondEvent> events_;
};

template <int D>
void log_start(const RunOptions& opt, std::size_t particles, std::size_t bonds, const Leapfrog<D>& lf,
               const Schedule& at, double dt, bool adaptive) {
  if (!opt.log) return;
  std::string names;
  for (const auto& e : lf.effects()) names += (names.empty() ? "" : ", ") + e->name();
  opt.log("effects: " + (names.empty() ? std::string("none") : names));
  if (adaptive)
    opt.log(std::to_string(particles) + " particles, " + std::to_string(bonds) + " bonds, adaptive steps up to " + fmt("%.4g", dt) + " s, a frame every " + fmt("%.4g", at.every_s) + " s");
  else
    opt.log(std::to_string(particles) + " particles, " + std::to_string(bonds) + " bonds, " +
            std::to_string(at.steps) + " steps, a frame every " + std::to_string(at.every) + " steps");
}

// The pair effect's report on the bonds, into the result.
template <int D>
void take_bond_results(const Leapfrog<D>& lf, RunResult& res) {
  for (const auto& e : lf.effects()) {
    const auto bv = bond_view<D>(*e);
    if (!bv.alive) continue;
    res.pair_model = bv.cutoff_model ? "cutoff" : "bonded";
    if (bv.first_break_step >= 0) res.first_break_time = bv.first_break_time;
    res.bonds_broken = bv.broke;
    res.bonds_re_formed = bv.re_formed;
    res.bonds_beyond_now = 0;
    for (const auto a : *bv.alive) res.bonds_beyond_now += !a;
    res.list_builds = bv.list_builds, res.skin = bv.skin;
  }
}

// run.json: what ran and how fast (for sweeps and benchmarks; read back by read_run_record).
void write_run_record(const std::filesystem::path& dir, const RunResult& res, long event_rows, double r0) {
  nlohmann::ordered_json by_threads = nlohmann::ordered_json::object();
  for (std::size_t t = 1; t < res.thread_steps.size(); ++t)
    if (res.thread_steps[t] > 0) by_threads[std::to_string(t)] = res.thread_steps[t];
  const nlohmann::ordered_json record = {
      {"completed", res.completed},
      {"interrupted", res.interrupted},
      {"message", res.message},
      {"particles", res.particles},
      {"steps", res.steps},
      {"frames", res.frames},
      {"dt_s", res.dt},
      {"dt_adaptive", res.adaptive},
      {"dt_min_s", res.dt_min},
      {"dt_limit_s", res.dt_limit},
      {"setup_s", res.setup_s},
      {"wall_s", res.wall_s},
      {"output_s", res.output_s},
      {"particle_steps_per_s", res.particle_steps_per_s()},
      {"threads", res.threads()},
      {"kernels", kernel_path()},
      {"processor", processor_name()},
      {"l2_cache_bytes", l2_cache_bytes()},
      {"steps_by_threads", by_threads},
      {"pair_model", res.pair_model},
      {"first_break_time_s", res.first_break_time},
      {"bond_events",
       {{"broken", res.bonds_broken},
        {"re_formed", res.bonds_re_formed},
        {"beyond_cutoff_at_end", res.bonds_beyond_now},
        {"rows", event_rows}}},
      {"neighbour_list_builds", res.list_builds},
      {"verlet_skin_r0", res.skin / r0}};
  write_file_atomically(dir / "run.json", [&](std::ostream& js) {
    js << record.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << "\n";
  });
}

// A progress line every ~0.2 s of wall time (checked every 256 steps).
class ProgressReport {
 public:
  using clock = std::chrono::steady_clock;
  explicit ProgressReport(const RunOptions& opt) : opt_(opt), t0_(clock::now()), last_(t0_) {}
  double wall_s() const { return std::chrono::duration<double>(clock::now() - t0_).count(); }
  void maybe(long k, double time, const Schedule& at, bool adaptive) {
    if (!opt_.progress || (k & 255) != 0) return;
    const auto now = clock::now();
    if (std::chrono::duration<double>(now - last_).count() <= 0.2) return;
    last_ = now;
    Progress p;
    p.wall_s = std::chrono::duration<double>(now - t0_).count();
    p.step = k, p.time = time, p.end = at.end;
    p.steps = adaptive ? std::max(k, std::lround(k * at.end / std::max(p.time, at.tol))) : at.steps;
    p.steps_per_s = k / p.wall_s;
    p.eta_s = (p.steps - k) / p.steps_per_s;
    opt_.progress(p);
  }

 private:
  const RunOptions& opt_;
  clock::time_point t0_, last_;
};

template <int D>
RunResult run_dim(const Scene& scene, System&& sys, const RunOptions& opt, const StepChoice& choice,
                  const Checkpoint* from, std::chrono::steady_clock::time_point started) {
  const double dt = choice.dt, limit = choice.limit;  // adaptive: dt is the cap
  const bool adaptive = choice.adaptive;
  RunResult res;
  res.particles = sys.size();
  res.dt = dt;
  res.dt_limit = limit;
  res.adaptive = adaptive;
  const Schedule at = schedule_of(scene, dt);
  const RunParameters rp{dt, limit, at.end, adaptive ? 0 : at.every, adaptive};

  const std::filesystem::path dir(opt.out_dir);
  make_folder(dir);
  if (!from) start_run_folder(dir, scene, opt.force);
  const std::string traj = (dir / "trajectory.h5").string();
  if (from && !trajectory_opens_for_append(traj)) {
    // A full disk cut the trajectory's end, or its writer died before closing it: the frames the checkpoint
    // counts are copied into a new one.
    rebuild_trajectory(traj, sys, scene, rp, from->frames, from->bond_events);
    if (opt.log)
      opt.log("rebuilt " + traj + " from its first " + std::to_string(from->frames) +
              " frames (its end was cut, or its writer did not close it)");
  }
  std::unique_ptr<H5mdWriter> writer_ptr = from ? std::make_unique<H5mdWriter>(traj, from->frames, from->bond_events)
                                                : std::make_unique<H5mdWriter>(traj, sys, scene, rp);
  H5mdWriter& writer = *writer_ptr;

  // The effects and the integrator's state hold all the run needs: the System's particles and bonds (a
  // quarter of the peak memory at millions of particles) go before the effects' setup builds its lists.
  auto effects = make_effects<D>(sys, scene);
  State<D> initial = initial_state<D>(sys);
  const std::size_t particles = sys.size(), bonds = sys.bonds.size();
  const double r0 = sys.r0;
  { const System gone = std::move(sys); }
  Leapfrog<D> lf(std::move(initial), std::move(effects), dt, adaptive, opt.threads);
  if (from) {
    lf.restore(from->step, from->time, from->dt, from->position, from->velocity, from->effects);
    if (opt.log) opt.log("resumed at step " + std::to_string(from->step) + " (t = " + fmt("%.6g", lf.state().time()) + " s)");
  }
  log_start(opt, particles, bonds, lf, at, dt, adaptive);

  RunOutput<D> out(writer, lf, (dir / "checkpoint.h5").string());
  if (from) out.resumed_from(*from);
  StepLevels levels(dt, at.every_s);
  if (from) levels.restore(from->level, from->calm);
  ProgressReport progress(opt);
  res.setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  auto done = [&] { return adaptive ? !(lf.state().t < at.end - at.tol) : lf.state().step >= at.steps; };
  double dt_min_taken = dt;
  try {
    // Frames and checkpoints timed apart, so that the steps' own cost can be read from run.json at any size
    const auto timed = [&res](auto&& write) {
      const auto t0 = std::chrono::steady_clock::now();
      write();
      res.output_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    if (!from) timed([&] { out.frame(); });
    // For tests: an interruption at the first step past this one, as a SIGINT there would (tests/resume_test.sh)
    const char* stop_env = std::getenv("PMFRAG_TEST_STOP_AT_STEP");
    const long stop_at_step = stop_env ? std::atol(stop_env) : -1;
    while (!done()) {
      bool frame_due = false, take_checkpoint = false;
      if (adaptive) {
        // The stability limit at the closest approach present, as a power-of-two level of the cap (see
        // step_levels.hpp), cut short only to land on an output time.
        const double allowed = scene.time.safety * choice.lattice_factor * lf.step_limit();
        double h = 0.0;
        try {
          h = levels.next(allowed);
        } catch (const std::runtime_error&) {
          // The state is whole (this step is not taken): keep it in a checkpoint, as an interrupted run does.
          lf.canonicalize();
          out.checkpoint(levels);
          throw GuardError("adaptive step collapsed: the limit at the closest approach is " + fmt("%.3g", allowed) +
                               " s, below 1e-6 of the cap " + fmt("%.3g", dt) + " s, at t = " + fmt("%.6g", lf.state().t) +
                               " s (particles pressed to the stiffest part of the law: a lower speed, or a larger "
                               "pair.r_min); a checkpoint is kept at this step",
                           lf.state().step, lf.state().t, -1);
        }
        const double to_out = std::min(static_cast<double>(writer.frames()) * at.every_s, at.end) - lf.state().t;
        if (h >= to_out - at.tol) h = to_out;
        dt_min_taken = std::min(dt_min_taken, h);
        lf.step(h);
        frame_due = !(lf.state().t < static_cast<double>(writer.frames()) * at.every_s - at.tol) || done();
        take_checkpoint = frame_due && (done() || writer.frames() % at.checkpoint_frames == 0);
      } else {
        // Steps to the next frame, checkpoint or progress line in one call: quiet steps then run many to a
        // pass of the thread team.
        const long k0 = lf.state().step;
        lf.advance(std::min({at.every - k0 % at.every, at.checkpoint_every - k0 % at.checkpoint_every,
                             256 - (k0 & 255), at.steps - k0}));
        const long k = lf.state().step;
        frame_due = k % at.every == 0 || k == at.steps;
        take_checkpoint = k % at.checkpoint_every == 0 || k == at.steps;  // and at the last step
      }
      const long k = lf.state().step;
      // At a checkpoint step the lists are rebuilt first, in an uninterrupted run as in a resumed one, so
      // both continue bitwise alike.
      if (take_checkpoint) lf.canonicalize();
      if (frame_due) timed([&] { out.frame(); });
      if (take_checkpoint) timed([&] { out.checkpoint(levels); });
      if (stop_at_step >= 0 && k >= stop_at_step) stop_requested = 1;
      if (stop_requested && !done()) {
        // Interrupted: keep the frames written and checkpoint this step so --resume continues from here.
        timed([&] { out.checkpoint(levels); });
        res.interrupted = true;
        res.message = "interrupted at step " + std::to_string(k) + " (t = " + fmt("%.6g", lf.state().time()) +
                      " s); continue with: pmfrag run --resume " + opt.out_dir;
        break;
      }
      progress.maybe(k, lf.state().time(), at, adaptive);
    }
    res.completed = !res.interrupted;
  } catch (const GuardError& e) {
    res.completed = false;
    res.message = e.what();
  }
  // What reads the trajectory says it is partial until a resume completes it.
  if (!res.completed) writer.mark_incomplete(res.interrupted ? res.message : "stopped: " + res.message);
  res.wall_s = progress.wall_s();
  res.steps = lf.state().step;
  res.dt_min = dt_min_taken;
  res.thread_steps = lf.thread_steps();
  res.frames = writer.frames();
  out.record_events();  // a run stopped between frames: its last events too (after the last frame's rows)
  writer.close();
  take_bond_results(lf, res);
  write_run_record(dir, res, writer.bond_event_rows(), r0);
  return res;
}

}  // namespace

void request_stop() noexcept { stop_requested = 1; }

RunResult read_run_record(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the run record");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not a run record (" + e.what() + ")");
  }
  if (!j.is_object()) throw std::runtime_error(path + ": not a run record (not a JSON object)");
  // A number written as null (not finite) or absent keeps the default.
  const auto number = [&](const nlohmann::json& at, const char* key, double fallback) {
    return at.contains(key) && at[key].is_number() ? at[key].get<double>() : fallback;
  };
  const auto flag = [&](const char* key) { return j.contains(key) && j[key].is_boolean() && j[key].get<bool>(); };
  RunResult r;
  r.completed = flag("completed");
  r.interrupted = flag("interrupted");
  r.adaptive = flag("dt_adaptive");
  if (j.contains("message") && j["message"].is_string()) r.message = j["message"].get<std::string>();
  if (j.contains("pair_model") && j["pair_model"].is_string()) r.pair_model = j["pair_model"].get<std::string>();
  r.particles = static_cast<std::size_t>(number(j, "particles", 0.0));
  r.steps = static_cast<long>(number(j, "steps", 0.0));
  r.frames = static_cast<long>(number(j, "frames", 0.0));
  r.dt = number(j, "dt_s", 0.0);
  r.dt_min = number(j, "dt_min_s", 0.0);
  r.dt_limit = number(j, "dt_limit_s", 0.0);
  r.wall_s = number(j, "wall_s", 0.0);
  r.setup_s = number(j, "setup_s", 0.0);
  r.output_s = number(j, "output_s", 0.0);
  r.first_break_time = number(j, "first_break_time_s", -1.0);
  r.list_builds = static_cast<long>(number(j, "neighbour_list_builds", 0.0));
  if (j.contains("bond_events") && j["bond_events"].is_object()) {
    const nlohmann::json& e = j["bond_events"];
    r.bonds_broken = static_cast<long>(number(e, "broken", 0.0));
    r.bonds_re_formed = static_cast<long>(number(e, "re_formed", 0.0));
    r.bonds_beyond_now = static_cast<long>(number(e, "beyond_cutoff_at_end", 0.0));
  }
  if (j.contains("steps_by_threads") && j["steps_by_threads"].is_object())
    for (const auto& [threads, steps] : j["steps_by_threads"].items()) {
      char* end = nullptr;
      const std::size_t t = std::strtoul(threads.c_str(), &end, 10);
      if (*end || t == 0 || t > 4096 || !steps.is_number()) continue;
      if (r.thread_steps.size() <= t) r.thread_steps.resize(t + 1, 0);
      r.thread_steps[t] = steps.get<long>();
    }
  return r;
}

namespace {
// A new run, its step checked; `take_lock`: false if the caller already holds the folder's lock.
RunResult start_run(const Scene& scene, const RunOptions& opt, bool take_lock,
                    std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now()) {
  System sys = build_system(scene);
  const StepChoice choice = choose_step(scene, sys);
  const double limit = choice.limit, dt = choice.dt;
  if (opt.log) {
    const std::string where =
        sys.r_min > 0 ? " (at r_min = " + fmt("%.3g", sys.r_min) + " cm)" : std::string(" (stretch, at r0)");
    const std::string limits = "stability limit " + fmt("%.4g", limit) + " s = Eq. 15 " + fmt("%.4g", choice.pair_limit) +
                               " s" + where + " x lattice factor " + fmt("%.3f", choice.lattice_factor);
    if (choice.adaptive)
      opt.log("dt adaptive: " + fmt("%.3g", scene.time.safety) + " x the limit at the closest approach, at most " +
              fmt("%.4g", dt) + " s (" + limits + ")");
    else
      opt.log("dt = " + fmt("%.4g", dt) + " s, " + limits + ", dt/limit = " + fmt("%.3f", dt / limit));
  }
  if (!choice.adaptive && dt > limit && !opt.allow_unstable)
    throw UnstableStepError(scene.file + ": time.dt = " + fmt("%.4g", dt) + " s exceeds the stability limit " +
                            fmt("%.4g", limit) + " s (Eq. 15 x lattice factor " + fmt("%.3f", choice.lattice_factor) +
                            "; ratio " + fmt("%.3f", dt / limit) +
                            "); lower it, use dt = \"auto\", or pass --allow-unstable");
  if (scene.time.end < dt) throw SceneError(scene.file + ": time.end is shorter than one step");
  std::optional<FolderLock> lock;
  if (take_lock) lock.emplace(opt.out_dir);  // one writer per run folder (folder_lock.hpp)
  if (scene.dim == 2) return run_dim<2>(scene, std::move(sys), opt, choice, nullptr, started);
  return run_dim<3>(scene, std::move(sys), opt, choice, nullptr, started);
}
}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& opt) { return start_run(scene, opt, true); }

RunResult resume_run(const RunOptions& opt) {
  const auto started = std::chrono::steady_clock::now();
  namespace fs = std::filesystem;
  const fs::path dir(opt.out_dir);
  const fs::path traj = dir / "trajectory.h5", ckpt = dir / "checkpoint.h5", info = dir / "run.json";
  if (!fs::exists(traj)) throw std::runtime_error(traj.string() + " does not exist: nothing to resume");
  const FolderLock lock(dir);  // one writer per run folder (folder_lock.hpp)
  if (fs::exists(info) && read_run_record(info.string()).completed) {
    RunResult r;
    r.completed = true;
    r.message = "already finished: " + traj.string() + " is complete";
    return r;
  }
  const Scene scene = read_folder_scene(dir);
  RunOptions o = opt;
  if (!fs::exists(ckpt)) {
    if (o.log) o.log("no checkpoint in " + dir.string() + ": starting over");
    o.force = true;
    return start_run(scene, o, false, started);
  }
  const Checkpoint c = read_checkpoint(ckpt.string());
  System sys = build_system(scene);
  const StepChoice choice = choose_step(scene, sys);
  try {
    if (scene.dim == 2) return run_dim<2>(scene, std::move(sys), o, choice, &c, started);
    return run_dim<3>(scene, std::move(sys), o, choice, &c, started);
  } catch (const TrajectoryShortOfCheckpoint& e) {
    // The frames the checkpoint counts are not all on disk whole: a run from step 0 writes them again, bitwise
    // the same (runs are deterministic on any thread count), rather than a trajectory with a hole.
    if (o.warn) o.warn(std::string(e.what()) + ": starting the run over");
    o.force = true;
    return start_run(scene, o, false, started);
  }
}

// A new run's folder: refuses to overwrite a trajectory without --force, clears the old run's record and
// checkpoint, and keeps the scene as read and its overrides beside the trajectory (--resume needs nothing else).
void start_run_folder(const std::filesystem::path& dir, const Scene& scene, bool force) {
  namespace fs = std::filesystem;
  const fs::path traj = dir / "trajectory.h5";
  if (fs::exists(traj) && !force)
    throw std::runtime_error(traj.string() + " exists; use --force to overwrite it or --resume to continue it");
  fs::remove(dir / "run.json");
  fs::remove(dir / "checkpoint.h5");
  write_file_atomically(dir / "scene.toml", [&](std::ostream& s) { s << scene.source; });
  write_file_atomically(dir / "overrides.txt", [&](std::ostream& ov) {
    ov << "# source: " << scene.file << "\n";
    for (const auto& o : scene.overrides) ov << o << "\n";
  });
}

Scene read_folder_scene(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  if (!fs::exists(dir / "scene.toml") || !fs::exists(dir / "overrides.txt"))
    throw std::runtime_error(dir.string() + " has no scene.toml/overrides.txt: not a pmfrag run folder");
  std::string file;
  std::vector<std::string> overrides;
  {
    std::ifstream ov(dir / "overrides.txt");
    for (std::string line; std::getline(ov, line);) {
      if (line.rfind("# source: ", 0) == 0)
        file = line.substr(10);
      else if (!line.empty())
        overrides.push_back(line);
    }
  }
  std::ifstream in(dir / "scene.toml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_scene(text, file, overrides);
}

}  // namespace pmfrag
